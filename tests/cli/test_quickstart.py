"""The README's main job, at a small size."""

from rmb_lerobot.cli.quickstart import main


def test_quickstart_collects_checks_and_summarises(tmp_path, capsys):
    out = tmp_path / "qs"
    args = ["--out", str(out), "--episodes", "1", "--workers", "1", "--image-size", "32", "32"]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "collected 1 episodes of MujocoUR5eInsert, 1 successful" in printed
    assert "low-dimensional keys and attributes: identical" in printed
    assert "front_depth_image" in printed and "PSNR" in printed
    assert [p.name for p in (out / "rmb").iterdir()] == ["MujocoUR5eInsert_world0_000.rmb"]
