"""EpisodeWriter: RMB's on-disk layout, derived keys, streaming, atomicity, bad input."""

import logging
import os
import stat
import time

import h5py
import numpy as np
import pytest

from rmb_lerobot import EpisodeWriter, RmbFormatError, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot.episode.writer import remove_legacy_temporaries
from rmb_lerobot.kinematics import UR5E
from rmb_lerobot.pose import relative_pose
from rmb_lerobot.staging import remove_stale


def test_compact_episode_has_rmbs_file_layout(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    assert sorted(p.name for p in path.iterdir()) == [
        "front_depth_image.rmb.mp4",
        "front_rgb_image.rmb.mp4",
        "hand_depth_image.rmb.mp4",
        "hand_rgb_image.rmb.mp4",
        "main.rmb.hdf5",
    ]
    with h5py.File(path / "main.rmb.hdf5") as h5:
        assert all(isinstance(h5[k], h5py.Dataset) for k in h5)  # flat: no groups
        assert not any(K.is_image_key(k) for k in h5)
        assert h5.attrs["format"] == "RmbData-Compact"
        assert h5.attrs["version"] == K.RMB_FORMAT_VERSION
        assert list(h5.attrs["camera_names"]) == ["front", "hand"]
        assert h5.attrs["world_idx"] == 0
        assert h5.attrs["front_depth_image_fovy"] == 45.0
        assert h5.attrs["env"] == "MujocoUR5eCableEnv"
        assert h5["measured_joint_pos"].shape == (12, 7)
        assert h5["measured_joint_pos"].compression is None


def test_single_hdf5_stores_images_as_datasets(tmp_path, record, steps):
    path = record(tmp_path / "demo.hdf5")
    with h5py.File(path) as h5:
        assert h5.attrs["format"] == "RmbData-SingleHDF5"
        assert h5["front_rgb_image"].dtype == np.uint8 and h5["front_rgb_image"].shape == (
            12,
            48,
            64,
            3,
        )
        assert h5["front_depth_image"].dtype == np.float32
        np.testing.assert_array_equal(h5["front_rgb_image"][3], steps[3]["front_rgb_image"])
        np.testing.assert_array_equal(h5["hand_depth_image"][5], steps[5]["hand_depth_image"])


def test_eef_poses_come_from_forward_kinematics_and_rel_keys_are_derived(tmp_path, record, steps):
    with open_episode(record(tmp_path / "demo.hdf5")) as ep:
        joints = np.stack([s["measured_joint_pos"] for s in steps])
        poses = ep["measured_eef_pose"][:]
        np.testing.assert_allclose(poses[4], UR5E(joints[4]))
        np.testing.assert_allclose(ep["command_eef_pose"][2], UR5E(steps[2]["command_joint_pos"]))
        rel = ep["measured_eef_pose_rel"][:]
        np.testing.assert_allclose(rel[0], np.zeros(6))  # RMB records zero at the first step
        np.testing.assert_allclose(rel[5], relative_pose(poses[4], poses[5]), atol=1e-12)
        np.testing.assert_allclose(ep["measured_joint_pos_rel"][5], joints[5] - joints[4])
        assert ep["command_gripper_joint_pos_rel"].shape == (12, 1)
        assert "measured_joint_vel_rel" not in ep  # only RMB's relative quantities


def test_given_derived_keys_are_kept_as_recorded(tmp_path, steps, attrs):
    mine = np.arange(7, dtype=np.float64)
    with EpisodeWriter(tmp_path / "demo.hdf5", attrs, fk=UR5E) as writer:
        for step in steps:
            writer.append({**step, "measured_eef_pose": mine, "measured_joint_pos_rel": mine})
    with open_episode(tmp_path / "demo.hdf5") as ep:
        np.testing.assert_array_equal(ep["measured_eef_pose"][3], mine)
        np.testing.assert_array_equal(ep["measured_joint_pos_rel"][3], mine)


def test_images_are_streamed_to_disk_while_recording(tmp_path, steps, attrs):
    writer = EpisodeWriter(tmp_path / "demo.hdf5", attrs)
    for step in steps[:5]:
        writer.append(step)
    # Images went to the (hidden, temporary) file as they arrived; only low-dim data is buffered.
    assert writer._h5["front_rgb_image"].shape[0] == 5
    assert not any(K.is_image_key(key) for key in writer._lowdim)
    assert not (tmp_path / "demo.hdf5").exists()
    writer.close()
    assert (tmp_path / "demo.hdf5").exists()


@pytest.mark.parametrize("name", ["demo.rmb", "demo.hdf5"])
@pytest.mark.parametrize("interrupt", [RuntimeError("robot fault"), KeyboardInterrupt()])
def test_an_interrupted_recording_leaves_nothing(tmp_path, steps, attrs, name, interrupt):
    with pytest.raises(type(interrupt)), EpisodeWriter(tmp_path / name, attrs) as writer:
        for i, step in enumerate(steps):
            if i == 6:
                raise interrupt
            writer.append(step)
    assert list(tmp_path.iterdir()) == []


def test_existing_destination_needs_overwrite(tmp_path, record, steps, attrs):
    path = record(tmp_path / "demo.rmb")
    with pytest.raises(RmbFormatError, match="destination exists"):
        EpisodeWriter(path, attrs)
    with EpisodeWriter(path, {**attrs, "world_idx": 3}, overwrite=True) as writer:
        for step in steps[:4]:
            writer.append(step)
    with open_episode(path) as ep:
        assert len(ep) == 4 and ep.attrs["world_idx"] == 3
    assert [p.name for p in tmp_path.iterdir()] == ["demo.rmb"]


@pytest.mark.parametrize("name", ["demo.rmb", "demo.hdf5"])
def test_an_interrupted_overwrite_keeps_the_previous_episode(tmp_path, record, steps, attrs, name):
    path = record(tmp_path / name)
    with pytest.raises(KeyboardInterrupt), EpisodeWriter(path, attrs, overwrite=True) as writer:
        writer.append(steps[0])
        raise KeyboardInterrupt
    with open_episode(path) as ep:
        assert len(ep) == len(steps)
    assert [p.name for p in tmp_path.iterdir()] == [name]


@pytest.mark.parametrize("name", ["demo.rmb", "demo.hdf5"])
def test_the_temporary_is_locked_while_recording(tmp_path, steps, attrs, name):
    # HDF5 locks the temporary file it writes; the staging lock is a separate file, so a
    # clean-up (here in the same process; flock conflicts between open files all the same)
    # sees a live writer and leaves its temporary alone.
    writer = EpisodeWriter(tmp_path / name, attrs)
    for step in steps[:3]:
        writer.append(step)
    hidden = sorted(p.name for p in tmp_path.iterdir())
    assert len(hidden) == 2 and hidden[0].startswith(f".{name}.tmp-")
    assert hidden[1] == hidden[0] + ".lock"
    assert remove_stale(tmp_path) == []
    writer.append(steps[3])
    writer.close()
    assert [p.name for p in tmp_path.iterdir()] == [name]


def test_an_unclosed_writer_that_is_dropped_leaves_nothing(tmp_path, steps, attrs):
    writer = EpisodeWriter(tmp_path / "demo.rmb", attrs)
    writer.append(steps[0])
    del writer
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", ["demo.rmb", "demo.hdf5"])
@pytest.mark.parametrize("umask", [0o022, 0o002])
def test_written_files_follow_the_umask(tmp_path, record, name, umask):
    previous = os.umask(umask)
    try:
        path = record(tmp_path / name)
    finally:
        os.umask(previous)
    entries = [path, *path.iterdir()] if path.is_dir() else [path]
    assert any(e.suffix == ".mp4" for e in entries) or name.endswith(".hdf5")
    for entry in entries:
        expected = (0o777 if entry.is_dir() else 0o666) & ~umask
        assert stat.S_IMODE(entry.stat().st_mode) == expected, entry.name


def _age(path, hours):
    old = time.time() - hours * 3600
    for entry in [path, *path.rglob("*")]:
        os.utime(entry, (old, old), follow_symlinks=False)


def test_temporaries_of_older_versions_are_removed_after_a_day(tmp_path, record, caplog):
    record(tmp_path / "kept.rmb")
    dead = tmp_path / ".a.rmb.tmp-0123abcd"  # older versions: 8 hex digits, no lock
    dead.mkdir()
    (dead / "front_rgb_image.rmb.mp4").write_bytes(b"x")
    _age(dead, 25)
    young = tmp_path / ".b.hdf5.tmp-89abcdef"  # perhaps an older version still recording
    young.write_bytes(b"x")
    _age(young, 2)
    trash = tmp_path / ".kept.rmb.old-00ff00ff"  # an overwritten episode, its successor in place
    trash.mkdir()
    _age(trash, 30)
    orphan = tmp_path / ".c.rmb.old-11ff11ff"  # the only copy of c.rmb: never removed
    orphan.mkdir()
    _age(orphan, 30)
    other = tmp_path / ".notes.txt.tmp-0123abcd"  # not an episode temporary
    other.write_text("x")
    _age(other, 30)

    with caplog.at_level(logging.WARNING):
        removed, kept = remove_legacy_temporaries(tmp_path)
    assert removed == [dead, trash]
    assert kept == [young, orphan]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [young.name, orphan.name, other.name, "kept.rmb"]
    )
    assert f"delete now with: rm -rf -- {young}" in caplog.text
    assert f"restore it with: mv -n -- {orphan} {tmp_path / 'c.rmb'}" in caplog.text


def test_legacy_clean_up_leaves_current_temporaries_to_their_locks(tmp_path, steps, attrs):
    writer = EpisodeWriter(tmp_path / "demo.rmb", attrs)
    writer.append(steps[0])
    _age(writer._tmp, 48)
    assert remove_legacy_temporaries(tmp_path) == ([], [])
    writer.append(steps[1])
    writer.close()
    with open_episode(tmp_path / "demo.rmb") as ep:
        assert len(ep) == 2


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ({"front_rgb_image": np.zeros((48, 64, 3), np.float32)}, "RGB image must be uint8"),
        ({"front_rgb_image": np.zeros((48, 64), np.uint8)}, "RGB image must be uint8"),
        ({"front_depth_image": np.zeros((48, 64, 1), np.float32)}, "depth image must be"),
        ({"front_depth_image": np.zeros((48, 64), np.int32)}, "depth image must be"),
        ({"measured_joint_pos": np.zeros(6)}, "has shape"),
        ({"measured_joint_pos": np.array(["a"] * 7)}, "expected numbers"),
        ({"time": np.zeros(2)}, "expected a scalar"),
    ],
)
def test_bad_values_are_rejected_naming_file_and_key(tmp_path, steps, attrs, bad, message):
    path = tmp_path / "demo.rmb"
    writer = EpisodeWriter(path, attrs)
    writer.append(steps[0])
    with pytest.raises(RmbFormatError, match=message) as info:
        writer.append({**steps[1], **bad})
    assert info.value.key == next(iter(bad)) and info.value.path == path
    assert len(writer) == 1  # the bad step was not half-recorded
    writer.abort()
    assert list(tmp_path.iterdir()) == []


def test_steps_must_keep_the_same_keys(tmp_path, steps, attrs):
    writer = EpisodeWriter(tmp_path / "demo.hdf5", attrs)
    writer.append(steps[0])
    step = dict(steps[1])
    del step["reward"]
    with pytest.raises(RmbFormatError, match=r"missing \['reward'\]"):
        writer.append(step)
    with pytest.raises(RmbFormatError, match=r"unexpected \['extra'\]"):
        writer.append({**steps[1], "extra": 1.0})
    writer.abort()


def test_time_is_required(tmp_path, steps, attrs):
    step = {k: v for k, v in steps[0].items() if k != "time"}
    with pytest.raises(RmbFormatError, match="every step needs 'time'"):
        EpisodeWriter(tmp_path / "demo.rmb", attrs).append(step)


def test_empty_episode_is_not_written(tmp_path, attrs):
    writer = EpisodeWriter(tmp_path / "demo.rmb", attrs)
    with pytest.raises(RmbFormatError, match="no steps were appended"):
        writer.close()
    assert list(tmp_path.iterdir()) == []


def test_extension_and_format_must_agree(tmp_path):
    with pytest.raises(RmbFormatError, match=r"invalid episode extension '\.h5'"):
        EpisodeWriter(tmp_path / "demo.h5")
    with pytest.raises(RmbFormatError, match="does not match the extension"):
        EpisodeWriter(tmp_path / "demo.rmb", fmt="hdf5")
    assert list(tmp_path.iterdir()) == []


def test_depth_beyond_the_uint16_range_is_stored_as_no_data(tmp_path, steps, attrs):
    depth = steps[0]["front_depth_image"].copy()
    depth[0, :4] = [np.nan, -1.0, 70.0, np.inf]
    with EpisodeWriter(tmp_path / "demo.rmb", attrs) as writer:
        writer.append({**steps[0], "front_depth_image": depth})
        writer.append(steps[1])
    with open_episode(tmp_path / "demo.rmb") as ep:
        stored = ep["front_depth_image"][0]
        np.testing.assert_array_equal(stored[0, :4], 0)
        np.testing.assert_allclose(stored[1:], depth[1:], atol=0.0005 + 1e-6)  # rounded to mm


def test_smaller_depth_codec_is_opt_in_and_keeps_millimetres_within_1mm(tmp_path, record, steps):
    path = record(tmp_path / "demo.rmb", depth_codec="rmbz")
    assert (path / "front_depth_image.rmbz").exists()
    assert not (path / "front_depth_image.rmb.mp4").exists()
    with open_episode(path) as ep:
        truth_mm = np.rint(np.stack([s["front_depth_image"] for s in steps]) * 1000)
        # rmbz keeps every millimetre value within 1 mm (float metres were rounded to mm first).
        assert np.abs(ep["front_depth_image"][:] * 1000 - truth_mm).max() <= 1 + 1e-3
