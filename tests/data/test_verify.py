"""rmb-data verify: clean episodes and datasets pass, each kind of damage is one named finding."""

import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pyarrow.parquet as pq
import pytest

from rmb_lerobot.cli.data import main
from rmb_lerobot.data.verify import format_table, verify_paths


def main_file(path: Path) -> Path:
    return path / "main.rmb.hdf5" if path.suffix == ".rmb" else path


def flip_data_byte(h5_path: Path, key: str) -> None:
    with h5py.File(h5_path, "r") as h5:
        offset = h5[key].id.get_chunk_info(0).byte_offset
    data = bytearray(h5_path.read_bytes())
    data[offset + 5] ^= 0x10
    h5_path.write_bytes(bytes(data))


def one(path: Path, **kwargs):
    (report,) = verify_paths([path], progress=False, **kwargs)
    return report


def checks(report) -> list[str]:
    return [f.check for f in report.findings]


@pytest.fixture(scope="module")
def converted(tmp_path_factory) -> Path:
    """A tiny converted dataset (2 cameras, RGB + depth, 12 frames), made once."""
    from rmb_lerobot import EpisodeWriter
    from rmb_lerobot.converters import ConvertOptions, to_lerobot
    from rmb_lerobot.kinematics import UR5E
    from rmb_lerobot.synthetic import ur5e_attrs, ur5e_steps

    root = tmp_path_factory.mktemp("verify")
    with EpisodeWriter(root / "demo.rmb", ur5e_attrs(("front", "hand")), fk=UR5E) as writer:
        for step in ur5e_steps(12, ("front", "hand"), (64, 48), seed=1):
            writer.append(step)
    options = ConvertOptions(depth=True)
    to_lerobot(
        [root / "demo.rmb"], output=root / "ds", options=options, video_codec="h264", progress=False
    )
    return root / "ds"


@pytest.fixture
def dataset(converted, tmp_path) -> Path:
    return Path(shutil.copytree(converted, tmp_path / "ds"))


@pytest.mark.parametrize("variant", ["rmb", "hdf5"])
def test_a_clean_episode_passes_and_everything_is_read(tmp_path, record, variant):
    report = one(record(tmp_path / f"demo.{variant}"))
    assert report.ok, format_table([report])
    assert report.counts["datasets"] == report.counts["checksummed"] > 10
    assert report.counts["frames"] == 4 * 12  # 2 cameras x (RGB + depth) x 12 steps
    assert report.counts["digests"] == (4 if variant == "rmb" else 0)


def test_an_episode_of_the_original_rmb_passes_without_checksums(
    tmp_path, steps, attrs, write_like_original
):
    report = one(write_like_original(tmp_path / "orig.rmb", steps, attrs))
    assert report.ok, format_table([report])
    assert report.counts["checksummed"] == 0 and report.counts["digests"] == 0


@pytest.mark.parametrize(
    ("variant", "key"), [("rmb", "command_eef_pose"), ("hdf5", "hand_rgb_image")]
)
def test_a_flipped_hdf5_byte_is_found(tmp_path, record, variant, key):
    path = record(tmp_path / f"demo.{variant}")
    flip_data_byte(main_file(path), key)
    report = one(path)
    assert checks(report) == ["hdf5"], format_table([report])
    assert f"'{key}'" in report.findings[0].message and "checksum" in report.findings[0].message


def test_a_changed_video_is_found_by_its_digest(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    video = path / "front_rgb_image.rmb.mp4"
    data = bytearray(video.read_bytes())
    data[-40] ^= 0x01  # near the end: may decode fine, but the digest differs
    video.write_bytes(bytes(data))
    report = one(path)
    assert "digest" in checks(report)
    assert str(video) in next(f.message for f in report.findings if f.check == "digest")


def test_a_truncated_video_is_found(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    video = path / "hand_depth_image.rmb.mp4"
    video.write_bytes(video.read_bytes()[: video.stat().st_size // 2])
    report = one(path)
    assert {"video", "digest"} <= set(checks(report)), format_table([report])


def test_non_finite_values_are_found_in_every_float_key(tmp_path, record):
    path = record(tmp_path / "demo.hdf5")
    with h5py.File(path, "a") as h5:
        for key, step in (("measured_eef_wrench", 4), ("front_depth_image", 2)):
            data = h5[key][()]
            data[step].flat[:3] = np.nan
            del h5[key]
            h5.create_dataset(key, data=data)
    report = one(path)
    messages = [f.message for f in report.findings if f.check == "values"]
    assert len(messages) == 2, format_table([report])
    assert any("3 non-finite pixels" in m and "step 2" in m for m in messages)
    assert any("3 non-finite values" in m and "step 4" in m for m in messages)
    assert one(path, allow_non_finite=True).ok


def test_a_missing_depth_video_is_found(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    (path / "hand_depth_image.rmb.mp4").unlink()
    report = one(path)
    assert sorted(checks(report)) == ["cameras", "digest"], format_table([report])
    assert all("hand_depth_image.rmb.mp4" in f.message for f in report.findings)


def test_frame_counts_are_checked_against_time(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    with h5py.File(main_file(path), "a") as h5:
        time = h5["time"][()]
        del h5["time"]
        h5.create_dataset("time", data=time[:-1])
    report = one(path)
    assert "length" in checks(report)
    assert any("'time' has 11 steps" in f.message for f in report.findings)


def test_a_clean_dataset_passes(converted):
    report = one(converted)
    assert report.ok, format_table([report])
    assert report.kind == "lerobot" and report.counts["frames"] == 4 * 12


def test_dataset_timestamps_and_stats_are_checked(dataset):
    data = next(dataset.glob("data/*/*.parquet"))
    table = pq.read_table(data)
    timestamps = table["timestamp"].to_numpy().copy()
    timestamps[5] += 0.5
    index = table.column_names.index("timestamp")
    pq.write_table(table.set_column(index, "timestamp", [timestamps.astype(np.float32)]), data)
    stats = json.loads((dataset / "meta/stats.json").read_text())
    stats["action"]["mean"][0] = float("nan")
    (dataset / "meta/stats.json").write_text(json.dumps(stats))
    report = one(dataset)
    assert sorted(checks(report)) == ["stats", "time"], format_table([report])
    assert "frame 5" in report.findings[checks(report).index("time")].message


def test_a_broken_dataset_video_is_found(dataset):
    video = next(dataset.glob("videos/observation.images.front/*/*.mp4"))
    video.write_bytes(video.read_bytes()[: video.stat().st_size // 2])
    report = one(dataset)
    assert checks(report) and set(checks(report)) <= {"video"}, format_table([report])
    assert str(video) in report.findings[0].message


def test_cli_table_and_exit_codes(tmp_path, record, capsys):
    good = record(tmp_path / "good.rmb")
    assert main(["verify", "--no-progress", str(good)]) == 0
    assert "all ok" in capsys.readouterr().out
    bad = record(tmp_path / "bad.hdf5")
    flip_data_byte(bad, "time")
    assert main(["verify", "--no-progress", "--json", str(good), str(bad)]) == 1
    out = json.loads(capsys.readouterr().out)
    assert [r["ok"] for r in out] == [True, False]
    assert main(["verify", str(tmp_path / "nothing")]) == 2
