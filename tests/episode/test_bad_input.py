"""open_episode on damaged or wrong data: every case is an RmbFormatError naming file and key.

Each test writes a valid episode (the ``record`` fixture or the original RMB's recipe), breaks
one thing the way a fuzzer, a buggy writer or a bad disk would, and checks the error.
"""

from pathlib import Path

import h5py
import numpy as np
import pytest

from rmb_lerobot import MissingKeyError, RmbFormatError, open_episode


def main_file(path: Path) -> Path:
    return path / "main.rmb.hdf5" if path.suffix == ".rmb" else path


def replace_dataset(path: Path, key: str, data) -> None:
    with h5py.File(main_file(path), "a") as h5:
        if key in h5:
            del h5[key]
        h5.create_dataset(key, data=data)


def set_attr(path: Path, name: str, value) -> None:
    with h5py.File(main_file(path), "a") as h5:
        h5.attrs[name] = value


def stored(path: Path, key: str) -> np.ndarray:
    with h5py.File(main_file(path), "r") as h5:
        return h5[key][()]


# ---------------------------------------------------------------- non-finite values
@pytest.fixture
def nan_episode(tmp_path, record) -> Path:
    path = record(tmp_path / "demo.rmb")
    joints = stored(path, "measured_joint_pos")
    joints[7, 2] = np.nan
    joints[9, 0] = np.inf
    replace_dataset(path, "measured_joint_pos", joints)
    return path


def test_nan_in_a_low_dim_key_is_refused_naming_the_first_bad_step(nan_episode):
    with open_episode(nan_episode) as ep:
        series = ep["measured_joint_pos"]  # lazy: nothing read yet
        assert series[0:5].shape == (5, 7)  # finite steps read fine
        with pytest.raises(RmbFormatError, match=r"holds nan at step 7 \(and 1 more") as info:
            series[:]
        assert info.value.key == "measured_joint_pos"
        assert "main.rmb.hdf5" in str(info.value) and "allow_non_finite=True" in str(info.value)
        with pytest.raises(RmbFormatError, match=r"holds inf at step 9"):
            series[[9, 1]]
        with pytest.raises(RmbFormatError, match="step 7"):
            ep.validate()


def test_nan_is_kept_when_allowed(nan_episode):
    with open_episode(nan_episode, allow_non_finite=True) as ep:
        joints = ep["measured_joint_pos"][:]
        assert np.isnan(joints[7, 2]) and np.isinf(joints[9, 0])
        ep.validate()


def test_cached_episodes_check_too(nan_episode):
    with open_episode(nan_episode, cache=True) as ep, pytest.raises(RmbFormatError, match="nan"):
        ep["measured_joint_pos"]


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_depth_is_refused_with_frame_and_pixel_count(tmp_path, record, bad):
    """RMB depth is finite metres (0 = no data): NaN/inf in HDF5 depth is a broken writer."""
    path = record(tmp_path / "demo.hdf5")
    depth = stored(path, "front_depth_image")
    depth[3, 0, :2] = bad
    depth[7, 1, 1] = bad
    replace_dataset(path, "front_depth_image", depth)
    with open_episode(path) as ep:
        assert ep["front_depth_image"][2:3].shape[0] == 1  # finite frames read fine
        with pytest.raises(
            RmbFormatError, match=r"depth frame 3 holds 2 non-finite pixels"
        ) as info:
            ep["front_depth_image"][:]
        assert "2 of the frames read" in str(info.value)
        assert info.value.key == "front_depth_image" and info.value.path == path
        with pytest.raises(RmbFormatError, match=r"depth frame 7 holds 1 non-finite pixels"):
            ep["front_depth_image"][7]
    with open_episode(path, allow_non_finite=True) as ep:
        assert not np.isfinite(ep["front_depth_image"][3][0, 0])


def test_negative_depth_still_means_no_data(tmp_path, record):
    path = record(tmp_path / "demo.hdf5")
    depth = stored(path, "front_depth_image")
    depth[3, 0, 0] = -1.0
    replace_dataset(path, "front_depth_image", depth)
    with open_episode(path) as ep:
        assert ep["front_depth_image"][3][0, 0] == -1.0


# ---------------------------------------------------------------- cameras without images
def test_a_listed_camera_without_rgb_video_is_refused_at_open(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    (path / "hand_rgb_image.rmb.mp4").unlink()
    with pytest.raises(
        MissingKeyError, match=r"camera 'hand' is listed in the 'camera_names'"
    ) as info:
        open_episode(path)
    assert info.value.path == path / "hand_rgb_image.rmb.mp4"
    assert info.value.key == "hand_rgb_image"


def test_a_listed_camera_without_rgb_dataset_is_refused_at_open(tmp_path, record):
    path = record(tmp_path / "demo.hdf5")
    with h5py.File(path, "a") as h5:
        del h5["front_rgb_image"]
    with pytest.raises(MissingKeyError, match=r"expected a dataset 'front_rgb_image'"):
        open_episode(path)


@pytest.mark.parametrize("writer", ["ours", "original"])
def test_a_lost_depth_video_is_refused(tmp_path, record, steps, attrs, write_like_original, writer):
    """Ours: the file is in the recorded digests; the original's: other cameras have depth."""
    if writer == "ours":
        path = record(tmp_path / "demo.rmb")
    else:
        path = write_like_original(tmp_path / "demo.rmb", steps, attrs)
    (path / "hand_depth_image.rmb.mp4").unlink()
    with pytest.raises(MissingKeyError, match=r"camera 'hand' .* no depth images") as info:
        open_episode(path)
    assert "allow_missing_depth=True" in str(info.value)
    assert info.value.key == "hand_depth_image"
    assert info.value.path == path / "hand_depth_image.rmb.mp4"
    with open_episode(path, allow_missing_depth=True) as ep:
        assert ep.camera_names == ["front", "hand"]
        assert "hand_depth_image" not in ep and "front_depth_image" in ep


def test_depth_of_some_cameras_only_is_fine_when_so_recorded(tmp_path, steps, attrs):
    """Episodes converted from LeRobot datasets may have depth for some cameras only."""
    from rmb_lerobot import EpisodeWriter

    for variant in ("rmb", "hdf5"):
        path = tmp_path / f"partial.{variant}"
        with EpisodeWriter(path, attrs) as writer:
            for step in steps:
                writer.append({k: v for k, v in step.items() if k != "hand_depth_image"})
        with open_episode(path) as ep:
            assert "hand_depth_image" not in ep and "front_depth_image" in ep


def test_depth_may_be_absent_for_every_camera(tmp_path, steps, attrs, write_like_original):
    """The original RMB records depth for every listed camera or for none."""
    no_depth = [{k: v for k, v in s.items() if not k.endswith("_depth_image")} for s in steps]
    path = write_like_original(tmp_path / "demo.rmb", no_depth, attrs)
    with open_episode(path) as ep:
        assert not any(k.endswith("_depth_image") for k in ep)


def test_point_cloud_cameras_need_depth(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    (path / "hand_depth_image.rmb.mp4").unlink()
    set_attr(path, "pointcloud_camera_names", np.array(["hand"], dtype=h5py.string_dtype()))
    with pytest.raises(MissingKeyError, match=r"'pointcloud_camera_names'.*no depth") as info:
        open_episode(path)
    assert info.value.path == path / "hand_depth_image.rmb.mp4"


# ---------------------------------------------------------------- frame rate
def test_fps_refuses_a_gap_in_time(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    time = stored(path, "time")
    time[6:] += 0.3
    replace_dataset(path, "time", time)
    with open_episode(path) as ep:
        with pytest.raises(RmbFormatError, match=r"jumps by 0\.332 s at step 6") as info:
            _ = ep.fps
        assert info.value.key == "time"
        with pytest.raises(RmbFormatError, match="jumps"):
            ep.validate()


def test_fps_refuses_time_in_milliseconds(tmp_path, record):
    path = record(tmp_path / "demo.hdf5")
    replace_dataset(path, "time", stored(path, "time") * 1000)
    with open_episode(path) as ep, pytest.raises(RmbFormatError, match="milliseconds"):
        _ = ep.fps


# ---------------------------------------------------------------- damaged HDF5 structure
def test_a_scalar_dataset_is_refused_at_open(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    replace_dataset(path, "reward", 1.0)
    with pytest.raises(
        RmbFormatError, match=r"a single value \(\); expected one row per step"
    ) as info:
        open_episode(path)
    assert info.value.key == "reward"


def test_a_group_where_a_dataset_belongs_is_refused_at_open(tmp_path, record):
    path = record(tmp_path / "demo.hdf5")
    with h5py.File(path, "a") as h5:
        del h5["reward"]
        h5.create_group("reward").create_dataset("value", data=np.zeros(12))
    with pytest.raises(RmbFormatError, match="found a group where a dataset was expected") as info:
        open_episode(path)
    assert info.value.key == "reward"


def test_a_dataset_name_that_is_not_utf8_is_refused(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    with h5py.File(main_file(path), "a") as h5:
        h5.create_dataset(b"measured_\xffjoint_pos", data=np.zeros((12, 7)))
    with pytest.raises(RmbFormatError, match="dataset name is not UTF-8") as info:
        open_episode(path)
    assert "\\xff" in info.value.key


def test_a_dangling_link_is_refused(tmp_path, record):
    path = record(tmp_path / "demo.hdf5")
    with h5py.File(path, "a") as h5:
        h5["extra"] = h5py.SoftLink("/nowhere")
    with pytest.raises(RmbFormatError, match="dangling link") as info:
        open_episode(path)
    assert info.value.key == "extra"


def test_byte_flips_in_the_hdf5_header_raise_only_our_errors(tmp_path, record):
    """A seeded fuzzer over a compact episode's HDF5 file (header and low-dimensional data).

    Before these checks, about 1 flip in 11 escaped as h5py's KeyError/RuntimeError/OSError.
    Flips inside data values stay undetectable (HDF5 stores no checksums by default).
    """
    path = record(tmp_path / "demo.rmb")
    main = path / "main.rmb.hdf5"
    clean = main.read_bytes()
    rng = np.random.default_rng(7)
    refused = 0
    for _ in range(100):
        data = bytearray(clean)
        data[int(rng.integers(len(data)))] ^= 1 << int(rng.integers(8))
        main.write_bytes(bytes(data))
        try:
            with open_episode(path) as ep:
                ep.validate()
                for key in ep:
                    if not key.endswith("_image"):
                        ep[key][:]
        except RmbFormatError:
            refused += 1
    assert refused > 0


# ---------------------------------------------------------------- attributes
def test_task_desc_of_opaque_bytes_is_refused(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    set_attr(path, "task_desc", np.void(b"pick the cube"))
    with pytest.raises(RmbFormatError, match=r"expected one text string") as info:
        open_episode(path)
    assert info.value.key == "task_desc"


def test_task_desc_that_is_not_utf8_is_refused(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    with h5py.File(main_file(path), "a") as h5:
        h5.attrs.create("task_desc", data=b"pick \xff cube", dtype=h5py.string_dtype("utf-8"))
    with pytest.raises(RmbFormatError, match=r"not UTF-8 text") as info:
        open_episode(path)
    assert info.value.key == "task_desc" and "\\udcff" in str(info.value)


def test_fixed_length_byte_string_attributes_are_read_as_text(tmp_path, record):
    """h5py stores Python bytes as fixed-length strings, as older RMB versions did."""
    path = record(tmp_path / "demo.rmb")
    set_attr(path, "task_desc", np.bytes_("pick the cube"))
    with open_episode(path) as ep:
        assert ep.attrs["task_desc"] == "pick the cube"


def test_camera_names_must_be_a_list(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    set_attr(path, "camera_names", "front")
    with pytest.raises(RmbFormatError, match="expected a list of names") as info:
        open_episode(path)
    assert info.value.key == "camera_names"


def test_a_bad_fovy_or_world_index_is_found_by_validate(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    set_attr(path, "front_depth_image_fovy", "wide")
    with open_episode(path) as ep:
        with pytest.raises(RmbFormatError, match="field of view") as info:
            ep.fovy("front")
        assert info.value.key == "front_depth_image_fovy"
        with pytest.raises(RmbFormatError, match="field of view"):
            ep.validate()
    set_attr(path, "front_depth_image_fovy", 45.0)
    set_attr(path, "world_idx", 1.5)
    with open_episode(path) as ep, pytest.raises(RmbFormatError, match="integer world index"):
        ep.validate()


# ---------------------------------------------------------------- dtypes and shapes
@pytest.mark.parametrize("dtype", [np.int64, np.bool_])
def test_joint_positions_must_be_floats(tmp_path, record, dtype):
    path = record(tmp_path / "demo.rmb")
    replace_dataset(path, "measured_joint_pos", stored(path, "measured_joint_pos").astype(dtype))
    with pytest.raises(
        RmbFormatError, match=rf"holds {np.dtype(dtype)} values; expected floats"
    ) as info:
        open_episode(path)
    assert info.value.key == "measured_joint_pos"


def test_an_extra_joint_column_on_a_ur5e_is_refused(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    joints = stored(path, "measured_joint_pos")
    replace_dataset(path, "measured_joint_pos", np.concatenate([joints, joints[:, :1]], axis=1))
    with pytest.raises(
        RmbFormatError, match=r"8 values per step; expected \(T, 7\), env 'MujocoUR5eCableEnv'"
    ) as info:
        open_episode(path)
    assert info.value.key == "measured_joint_pos"


def test_unknown_robots_need_consistent_keys(tmp_path, record):
    """No layout to check against: measured/command and position/velocity must agree."""
    path = record(tmp_path / "demo.rmb")
    set_attr(path, "env", "MyLabArmEnv")
    with open_episode(path):
        pass  # consistent 7-joint keys: fine
    joints = stored(path, "command_joint_vel")
    replace_dataset(path, "command_joint_vel", joints[:, :6])
    with pytest.raises(
        RmbFormatError,
        match=r"6 values per step; expected \(T, 7\), as 'measured_joint_pos' implies",
    ) as info:
        open_episode(path)
    assert info.value.key == "command_joint_vel"


def test_env_names_match_exactly(tmp_path, record):
    """A two-arm env whose name contains a UR5e env's is not taken for a UR5e: a UR5e-sized
    episode labelled with it is refused, one with both arms' numbers opens."""
    path = record(tmp_path / "demo.hdf5")
    set_attr(path, "env", "MujocoUR5eDualCableEnv")
    with pytest.raises(RmbFormatError, match=r"expected \(T, 14\).*MujocoUR5eDualCableEnv"):
        open_episode(path)
    with h5py.File(path, "a") as h5:
        for key in list(h5):
            if isinstance(h5[key], h5py.Dataset) and h5[key].ndim == 2:  # per-step vectors
                both = np.concatenate([h5[key][()], h5[key][()]], axis=1)
                del h5[key]
                h5.create_dataset(key, data=both)
    with open_episode(path) as ep:
        assert ep["measured_joint_pos"].shape == (12, 14)
        assert ep["command_eef_pose"].shape == (12, 14)


def test_millimetre_depth_in_a_single_file_is_refused(tmp_path, record):
    path = record(tmp_path / "demo.hdf5")
    depth_mm = (stored(path, "hand_depth_image") * 1000).astype(np.uint16)
    replace_dataset(path, "hand_depth_image", depth_mm)
    with pytest.raises(
        RmbFormatError, match=r"uint16 .*millimetres\?.*expected float metres"
    ) as info:
        open_episode(path)
    assert info.value.key == "hand_depth_image"


def test_float_rgb_in_a_single_file_is_refused(tmp_path, record):
    path = record(tmp_path / "demo.hdf5")
    replace_dataset(path, "front_rgb_image", stored(path, "front_rgb_image") / 255.0)
    with pytest.raises(RmbFormatError, match=r"expected uint8 \(T, H, W, 3\)"):
        open_episode(path)


def test_a_depth_video_in_the_rgb_files_place_is_refused(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    rgb = path / "front_rgb_image.rmb.mp4"
    rgb.write_bytes((path / "front_depth_image.rmb.mp4").read_bytes())
    with open_episode(path) as ep:
        with pytest.raises(RmbFormatError, match="depth video in this RGB file's place") as info:
            ep["front_rgb_image"]
        assert info.value.path == rgb
        with pytest.raises(RmbFormatError, match="yuv444p"):
            ep.validate()


def test_original_rmb_episodes_still_pass_validation(tmp_path, steps, attrs, write_like_original):
    meta = {**attrs, "version": "1.0.0", "rgb_tactile_names": [], "pointcloud_camera_names": []}
    for name in ("original.rmb", "original.hdf5"):
        with open_episode(write_like_original(tmp_path / name, steps, meta)) as ep:
            ep.validate(frames=True)
            assert ep.fps == pytest.approx(31.25)
