"""The README's main job, at a small size."""

from rmb_lerobot.cli.quickstart import main


def test_quickstart_records_checks_and_summarises(tmp_path, capsys):
    out = tmp_path / "qs"
    assert main(["--out", str(out), "--steps", "20", "--image-size", "64", "48"]) == 0
    printed = capsys.readouterr().out
    assert "low-dimensional keys and attributes: identical" in printed
    assert "front_depth_image" in printed and "PSNR" in printed
    assert sorted(p.name for p in out.iterdir()) == [
        "switched_from_rmb.hdf5",
        "synthetic_ur5e.hdf5",
        "synthetic_ur5e.rmb",
    ]
