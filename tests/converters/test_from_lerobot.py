"""rmb-convert from-lerobot: the exact round trip, and datasets from other sources."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from lerobot.configs import DepthEncoderConfig, RGBEncoderConfig
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import RmbFormatError, find_episodes, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot.converters import MappingOverrides, from_lerobot

# Bounds measured on the 32x32 demos (AV1 CRF 30 in LeRobot, then H.264 CRF 23 in the .rmb):
# about 32 dB; depth goes through LeRobot's 12-bit log quantisation (<= 1.65 mm at 3.5 m).
MIN_PSNR_DB = 28.0
MAX_DEPTH_ERROR_MM = 1.65


@pytest.fixture(scope="module")
def round_trip(converted_depth, tmp_path_factory):
    out = tmp_path_factory.mktemp("back") / "episodes"
    written = from_lerobot(root=converted_depth, output=out, progress=False)
    return written


def test_round_trip_restores_every_key_and_attribute(demos, round_trip, psnr):
    sources = find_episodes(demos)
    assert [p.name for p in round_trip] == [p.name for p in sources]
    for src, back in zip(sources, round_trip, strict=True):
        with open_episode(src) as a, open_episode(back) as b:
            assert sorted(a.keys()) == sorted(b.keys())
            assert a.attrs.keys() == b.attrs.keys()
            for name, value in a.attrs.items():
                if name == "video_sha256":  # the digests of each episode's own video files
                    continue
                assert np.array_equal(np.asarray(value), np.asarray(b.attrs[name])), name
            for key in a:
                x, y = np.asarray(a[key][:]), np.asarray(b[key][:])
                if K.is_rgb_image_key(key):
                    assert psnr(x, y) >= MIN_PSNR_DB, key
                elif K.is_depth_image_key(key):
                    assert np.abs(x.astype(np.float64) - y).max() * 1000 <= MAX_DEPTH_ERROR_MM
                else:
                    assert y.dtype == np.float64 and y.shape == x.shape, key
                    np.testing.assert_array_equal(x.astype(np.float32), y.astype(np.float32), key)


def test_single_file_format_and_episode_selection(converted_depth, tmp_path):
    written = from_lerobot(
        root=converted_depth, output=tmp_path / "out", fmt="hdf5", episodes=[1], progress=False
    )
    assert [p.name for p in written] == ["MujocoUR5eInsert_world1_001.hdf5"]
    with open_episode(written[0]) as ep:
        assert ep.format.short_name == "hdf5" and ep.attrs["world_idx"] == 1
        assert ep["front_depth_image"].dtype == np.float32


def test_bad_requests(converted_depth, tmp_path):
    with pytest.raises(RmbFormatError, match=r"episodes \[5\] not in the dataset"):
        from_lerobot(root=converted_depth, output=tmp_path / "a", episodes=[5], progress=False)
    with pytest.raises(RmbFormatError, match="no LeRobotDataset here"):
        from_lerobot(root=tmp_path, output=tmp_path / "b", progress=False)
    (tmp_path / "c").mkdir()
    with pytest.raises(FileExistsError):
        from_lerobot(root=converted_depth, output=tmp_path / "c", progress=False)
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A dataset shaped like lerobot-record's (an SO-100 with an RGB-D camera), no rmb.json."""
    root = tmp_path_factory.mktemp("record") / "so100"
    joints = ["shoulder_pan.pos", "shoulder_lift.pos", "elbow.pos", "wrist.pos", "gripper.pos"]
    image = {"dtype": "video", "names": ["height", "width", "channels"]}
    features = {
        "observation.state": {"dtype": "float32", "shape": (5,), "names": joints},
        "action": {"dtype": "float32", "shape": (5,), "names": joints},
        "observation.images.laptop": {**image, "shape": (24, 32, 3)},
        "observation.images.laptop_depth": {
            **image,
            "shape": (24, 32, 1),
            "info": {"is_depth_map": True},
        },
        "observation.images.wrist": {"dtype": "image", "shape": (24, 32, 3), "names": None},
        "observation.effort": {"dtype": "float32", "shape": (5,), "names": joints},
        "next.reward": {"dtype": "float32", "shape": (1,), "names": None},
    }
    dataset = LeRobotDataset.create(
        "user/so100_test",
        fps=30,
        features=features,
        root=root,
        robot_type="so100_follower",
        rgb_encoder=RGBEncoderConfig(vcodec="h264"),
        depth_encoder=DepthEncoderConfig(extra_options={"x265-params": "lossless=1:log-level=0"}),
    )
    rng = np.random.default_rng(0)
    for episode in range(2):
        for i in range(10):
            dataset.add_frame(
                {
                    "observation.state": rng.normal(size=5).astype(np.float32),
                    "action": rng.normal(size=5).astype(np.float32),
                    "observation.images.laptop": np.full((24, 32, 3), 20 * i, np.uint8),
                    "observation.images.laptop_depth": np.full((24, 32, 1), 500 + i, np.uint16),
                    "observation.images.wrist": np.full((24, 32, 3), 10 * i, np.uint8),
                    "observation.effort": rng.normal(size=5).astype(np.float32),
                    "next.reward": np.array([float(i == 9)], np.float32),
                    "task": f"pick cube {episode}",
                }
            )
        dataset.save_episode(parallel_encoding=False)  # no forked encoder processes in tests
    dataset.finalize()
    return root


def test_a_lerobot_record_dataset_maps_by_the_documented_defaults(recorded, tmp_path):
    written = from_lerobot(root=recorded, output=tmp_path / "out", progress=False)
    assert [p.name for p in written] == ["episode_000000.rmb", "episode_000001.rmb"]
    source = LeRobotDataset("user/so100_test", root=recorded, video_backend="pyav")
    rows = source.hf_dataset.with_format("numpy")[10:20]
    with open_episode(written[1]) as ep:
        assert ep.attrs["env"] == "so100_follower" and ep.attrs["task_desc"] == "pick cube 1"
        assert ep.attrs["camera_names"] == ["laptop", "wrist"] and len(ep) == 10
        assert ep.fps == pytest.approx(30)
        np.testing.assert_array_equal(ep[K.MEASURED_JOINT_POS][:], rows["observation.state"])
        np.testing.assert_array_equal(ep[K.COMMAND_JOINT_POS][:], rows["action"])
        np.testing.assert_array_equal(ep["reward"][:], rows["next.reward"])
        assert K.MEASURED_JOINT_POS_REL in ep  # derived, as the original recorder does
        assert "measured_joint_torque" not in ep  # observation.effort has no default RMB key
        assert ep["laptop_rgb_image"][3].shape == (24, 32, 3)
        assert abs(int(ep["laptop_rgb_image"][3].mean()) - 60) <= 3
        assert abs(int(ep["wrist_rgb_image"][7].mean()) - 70) <= 3  # stored as PNG images
        depth = ep["laptop_depth_image"][:]
        np.testing.assert_allclose(depth[:, 0, 0], (500 + np.arange(10)) / 1000, atol=2e-3)


def test_overrides_split_the_state_and_rename_features(recorded, tmp_path):
    renamed = MappingOverrides(
        cameras={"observation.images.laptop": "front", "observation.images.laptop_depth": "front"},
        keys={"observation.effort": "measured_joint_torque"},
    )
    (written,) = from_lerobot(
        root=recorded, output=tmp_path / "out", episodes=[0], overrides=renamed, progress=False
    )
    with open_episode(written) as ep:
        assert ep["measured_joint_torque"].shape == (10, 5)
        assert ep.camera_names == ["front", "wrist"] and "front_depth_image" in ep
    split = MappingOverrides(
        state_keys=("measured_joint_pos:4", "measured_gripper_joint_pos"),
        action_keys=("command_joint_pos:4", "command_gripper_joint_pos"),  # measured = command
    )
    (written,) = from_lerobot(
        root=recorded, output=tmp_path / "split", episodes=[0], overrides=split, progress=False
    )
    with open_episode(written) as ep:
        assert ep[K.MEASURED_JOINT_POS].shape == ep[K.COMMAND_JOINT_POS].shape == (10, 4)
        assert ep[K.MEASURED_GRIPPER_JOINT_POS].shape == (10, 1)
    bad = MappingOverrides(state_keys=("measured_joint_pos:3", "measured_gripper_joint_pos:1"))
    with pytest.raises(RmbFormatError, match="has 5 numbers but the mapping"):
        from_lerobot(root=recorded, output=tmp_path / "bad", overrides=bad, progress=False)
    assert not (tmp_path / "bad").exists()


@pytest.fixture
def dataset_with_nan(tmp_path):
    """A small dataset without videos whose ``observation.state`` holds NaN at frame 3 of
    episode 1 (written into the parquet: LeRobot's writer cannot compute stats over NaN)."""
    root = tmp_path / "nan_ds"
    vector = {"dtype": "float32", "shape": (3,), "names": ["a", "b", "c"]}
    features = {"observation.state": vector, "action": vector}
    dataset = LeRobotDataset.create("user/nan", fps=10, features=features, root=root)
    for episode in range(2):
        for i in range(6):
            value = np.full(3, episode * 10 + i, np.float32)
            dataset.add_frame({"observation.state": value, "action": value, "task": "t"})
        dataset.save_episode()
    dataset.finalize()
    (data,) = (root / "data").rglob("*.parquet")
    table = pq.read_table(data)
    states = np.stack(table.column("observation.state").to_numpy(zero_copy_only=False))
    states[6 + 3, 1] = np.nan
    column = pa.array(list(states), type=table.schema.field("observation.state").type)
    index = table.schema.get_field_index("observation.state")
    pq.write_table(table.set_column(index, "observation.state", column), data)
    return root


def test_nan_in_the_dataset_is_refused_unless_allowed(dataset_with_nan, tmp_path):
    out = tmp_path / "out"
    with pytest.raises(RmbFormatError) as err:
        from_lerobot(root=dataset_with_nan, output=out, progress=False)
    message = str(err.value)
    assert "nan in episode 1, frame 3, component 1" in message and "'observation.state'" in message
    assert str(dataset_with_nan) in message and "--allow-non-finite" in message
    assert not out.exists() and [p.name for p in tmp_path.iterdir()] == ["nan_ds"]

    written = from_lerobot(root=dataset_with_nan, output=out, allow_non_finite=True, progress=False)
    with open_episode(written[1], allow_non_finite=True) as ep:
        state = ep[K.MEASURED_JOINT_POS][:]
    assert np.isnan(state[3, 1]) and state[4, 1] == 14


def test_stale_temporaries_of_a_killed_run_are_removed(converted_depth, tmp_path, caplog):
    stale = tmp_path / ".out.tmp-0123456789ab"  # what a killed run leaves: unlocked lock
    (stale / "episode.rmb").mkdir(parents=True)
    (tmp_path / ".out.tmp-0123456789ab.tmp").mkdir()
    (tmp_path / ".out.tmp-0123456789ab.lock").write_text("pid 1\n")
    from_lerobot(root=converted_depth, output=tmp_path / "out", episodes=[0], progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    assert any("stale" in r.getMessage() for r in caplog.records)


def _action_features(names: list[str]) -> dict:
    return {
        "observation.state": {
            "dtype": "float32",
            "shape": [7],
            "names": [f"j{i}.pos" for i in range(7)],
        },
        "action": {"dtype": "float32", "shape": [len(names)], "names": names},
    }


def test_an_end_effector_velocity_action_is_not_taken_for_joint_positions():
    from rmb_lerobot import lerobot_names as N
    from rmb_lerobot.converters.lerobot_mapping import resolve_mapping

    # What an rmb_ur5e robot with action_space=ee_velocity records under lerobot-record.
    twist = [*N.EE_VELOCITY_NAMES, N.GRIPPER_POS_NAME]
    mapping = resolve_mapping(_action_features(twist), depth_keys=[], rmb_meta=None)
    assert mapping.action == (("command_eef_vel", 6), ("command_gripper_joint_pos", 1))
    assert mapping.state == (("measured_joint_pos", None),)

    # Other velocity actions (a mobile base, a dual arm's interleaved twists) must be named.
    with pytest.raises(ValueError, match=r"'\.vel'.*--action-keys"):
        resolve_mapping(_action_features(["x.vel", "theta.vel"]), depth_keys=[], rmb_meta=None)
    # Joint positions keep the documented default.
    joints = resolve_mapping(_action_features(["a.pos", "b.pos"]), depth_keys=[], rmb_meta=None)
    assert joints.action == (("command_joint_pos", None),)
