"""Seeded fuzz test: every corrupted episode ends in our error types or a documented handling.

Each case corrupts a copy of a small valid episode in one of the ways an outside fuzz test
found (classes below), then runs what a user runs on it: ``open_episode`` + read every key +
``fps`` + ``validate()``, then ``to_lerobot`` into a fresh destination. The run happens in a
child process (forked by ``bad_input_server.py``, which imported LeRobot once, so a case costs
milliseconds to start), so a segfault or a hang fails the case instead of the suite.

Allowed outcomes per case:
- ``rejected``: an :class:`~rmb_lerobot.errors.RmbFormatError` naming the episode's file, and
  nothing at (or hidden beside) the conversion's destination;
- ``accepted``: only for the classes whose handling is documented in the README ("Bad input"):
  negative depth stored as "no data", and MP4 damage that decodes to valid frames (lossy video
  cannot tell a flipped coefficient from content; ``verify=True`` / ``rmb-data verify`` find it
  through the recorded digests, which this user path does not check);
- ``harmless``: accepted, and every low-dimensional key reads exactly as before the damage
  (the flipped bytes were unused ones, e.g. free space in an HDF5 header).
Anything else (another exception type, a crash, a hang) fails.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np
import pytest

from rmb_lerobot import EpisodeWriter, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot.kinematics import UR5E
from rmb_lerobot.synthetic import ur5e_attrs, ur5e_steps

SEED = 20261124
STEPS = 12
CAMERAS = ("front",)
SIZE = (48, 32)
CASE_TIMEOUT_S = 60


# ------------------------------------------------------------------ corruptions
def _main(episode: Path) -> Path:
    return episode / K.COMPACT_MAIN_FILE if episode.suffix == ".rmb" else episode


def _rewrite(episode: Path, key: str, value: np.ndarray) -> None:
    with h5py.File(_main(episode), "r+") as h5:
        del h5[key]
        h5.create_dataset(key, data=value)


def _float_keys(episode: Path) -> list[str]:
    with h5py.File(_main(episode), "r") as h5:
        return sorted(
            k
            for k in h5
            if isinstance(h5[k], h5py.Dataset)
            and h5[k].dtype.kind == "f"
            and h5[k].ndim >= 1
            and not K.is_image_key(k)
        )


def nonfinite_lowdim(episode: Path, rng: np.random.Generator) -> None:
    key = rng.choice(_float_keys(episode))
    with h5py.File(_main(episode), "r+") as h5:
        data = h5[key][()]
        flat = data.reshape(-1)
        flat[rng.integers(flat.size)] = rng.choice([np.nan, np.inf, -np.inf])
        h5[key][...] = data


def beyond_float32(episode: Path, rng: np.random.Generator) -> None:
    key = str(rng.choice([K.MEASURED_JOINT_POS, K.COMMAND_JOINT_POS]))
    with h5py.File(_main(episode), "r") as h5:
        data = h5[key][()].astype(np.float64)
    data[rng.integers(len(data)), rng.integers(data.shape[1])] = rng.choice([1e39, -3e40])
    _rewrite(episode, key, data)


def missing_camera_video(episode: Path, rng: np.random.Generator) -> None:
    (episode / f"{K.rgb_image_key('front')}.rmb.mp4").unlink()


def time_gap(episode: Path, rng: np.random.Generator) -> None:
    with h5py.File(_main(episode), "r") as h5:
        t = h5[K.TIME][()]
    t[rng.integers(2, len(t)) :] += 0.3
    _rewrite(episode, K.TIME, t)


def time_in_ms(episode: Path, rng: np.random.Generator) -> None:
    with h5py.File(_main(episode), "r") as h5:
        t = h5[K.TIME][()]
    _rewrite(episode, K.TIME, t * 1000.0)


def flip_video_bytes(episode: Path, rng: np.random.Generator) -> None:
    video = rng.choice(sorted(episode.glob("*.mp4")))
    data = bytearray(video.read_bytes())
    for _ in range(int(rng.integers(1, 8))):
        i = int(rng.integers(len(data)))
        data[i] ^= 1 << int(rng.integers(8))
    video.write_bytes(bytes(data))


def truncate_video(episode: Path, rng: np.random.Generator) -> None:
    video = rng.choice(sorted(episode.glob("*.mp4")))
    data = video.read_bytes()
    video.write_bytes(data[: int(rng.integers(16, len(data) - 1))])


def corrupt_hdf5_header(episode: Path, rng: np.random.Generator) -> None:
    path = _main(episode)
    data = bytearray(path.read_bytes())
    for _ in range(int(rng.integers(1, 6))):
        data[int(rng.integers(0, 2048))] = int(rng.integers(256))
    path.write_bytes(bytes(data))


def truncate_hdf5(episode: Path, rng: np.random.Generator) -> None:
    path = _main(episode)
    data = path.read_bytes()
    path.write_bytes(data[: int(rng.integers(8, len(data) - 1))])


def scalar_dataset(episode: Path, rng: np.random.Generator) -> None:
    _rewrite(episode, str(rng.choice([K.TIME, K.MEASURED_JOINT_POS, K.REWARD])), np.float64(1.0))


def group_for_dataset(episode: Path, rng: np.random.Generator) -> None:
    key = str(rng.choice([K.MEASURED_JOINT_POS, K.COMMAND_JOINT_POS]))
    with h5py.File(_main(episode), "r+") as h5:
        del h5[key]
        h5.create_group(key)


def non_utf8_dataset_name(episode: Path, rng: np.random.Generator) -> None:
    with h5py.File(_main(episode), "r+") as h5:
        h5.create_dataset(b"bad\xff\xfename", data=np.zeros(STEPS))


def task_desc_invalid_utf8(episode: Path, rng: np.random.Generator) -> None:
    with h5py.File(_main(episode), "r+") as h5:
        h5.attrs[K.ATTR_TASK_DESC] = np.bytes_(b"pick \xff\xfe up")


def task_desc_not_text(episode: Path, rng: np.random.Generator) -> None:
    with h5py.File(_main(episode), "r+") as h5:
        h5.attrs[K.ATTR_TASK_DESC] = [42, np.array([1.0, 2.0])][int(rng.integers(2))]


def integer_joint_positions(episode: Path, rng: np.random.Generator) -> None:
    with h5py.File(_main(episode), "r") as h5:
        data = h5[K.MEASURED_JOINT_POS][()]
    _rewrite(episode, K.MEASURED_JOINT_POS, np.round(data).astype(np.int64))


def bool_joint_positions(episode: Path, rng: np.random.Generator) -> None:
    with h5py.File(_main(episode), "r") as h5:
        data = h5[K.COMMAND_JOINT_POS][()]
    _rewrite(episode, K.COMMAND_JOINT_POS, data > 0)


def extra_joint_column(episode: Path, rng: np.random.Generator) -> None:
    key = str(rng.choice([K.MEASURED_JOINT_POS, K.COMMAND_JOINT_POS]))
    with h5py.File(_main(episode), "r") as h5:
        data = h5[key][()]
    _rewrite(episode, key, np.concatenate([data, data[:, :1]], axis=1))


def depth_in_millimetres(episode: Path, rng: np.random.Generator) -> None:
    key = K.depth_image_key("front")
    with h5py.File(_main(episode), "r") as h5:
        depth = h5[key][()]
    _rewrite(episode, key, np.round(depth * 1000).astype(np.uint16))


def depth_video_as_rgb(episode: Path, rng: np.random.Generator) -> None:
    rgb = episode / f"{K.rgb_image_key('front')}.rmb.mp4"
    depth = next(episode.glob(f"{K.depth_image_key('front')}*.mp4"))
    shutil.copyfile(depth, rgb)


def bad_fovy(episode: Path, rng: np.random.Generator) -> None:
    value = [np.bytes_(b"wide"), np.nan, -10.0, 400.0][int(rng.integers(4))]
    with h5py.File(_main(episode), "r+") as h5:
        h5.attrs[K.fovy_attr("front")] = value


def _set_depth_pixel(episode: Path, rng: np.random.Generator, values: list[float]) -> None:
    key = K.depth_image_key("front")
    with h5py.File(_main(episode), "r+") as h5:
        depth = h5[key][()]
        depth[rng.integers(STEPS), rng.integers(SIZE[1]), rng.integers(SIZE[0])] = rng.choice(
            values
        )
        h5[key][...] = depth


def depth_nonfinite(episode: Path, rng: np.random.Generator) -> None:
    _set_depth_pixel(episode, rng, [np.nan, np.inf, -np.inf])


def depth_negative(episode: Path, rng: np.random.Generator) -> None:
    _set_depth_pixel(episode, rng, [-1.0])


def flip_hdf5_data(episode: Path, rng: np.random.Generator) -> None:
    """Flip bits in the stored data of a dataset (our files carry Fletcher-32 checksums)."""
    path = _main(episode)
    with h5py.File(path, "r") as h5:
        key = str(rng.choice(sorted(h5)))
        info = h5[key].id.get_chunk_info(int(rng.integers(h5[key].id.get_num_chunks())))
    data = bytearray(path.read_bytes())
    for _ in range(int(rng.integers(1, 4))):
        data[info.byte_offset + int(rng.integers(info.size))] ^= 1 << int(rng.integers(8))
    path.write_bytes(bytes(data))


Corruption = Callable[[Path, np.random.Generator], None]

# (name, corruption, episode variant, outcomes allowed); "accepted" only where documented.
CLASSES: list[tuple[str, Corruption, str, frozenset[str], int]] = [
    ("nonfinite_lowdim", nonfinite_lowdim, "rmb", frozenset({"rejected"}), 4),
    ("beyond_float32", beyond_float32, "hdf5", frozenset({"rejected"}), 2),
    ("missing_camera_video", missing_camera_video, "rmb", frozenset({"rejected"}), 1),
    ("time_gap", time_gap, "rmb", frozenset({"rejected"}), 2),
    ("time_in_ms", time_in_ms, "hdf5", frozenset({"rejected"}), 1),
    ("flip_video_bytes", flip_video_bytes, "rmb", frozenset({"rejected", "accepted"}), 8),
    ("truncate_video", truncate_video, "rmb", frozenset({"rejected"}), 3),
    ("corrupt_hdf5_header", corrupt_hdf5_header, "rmb", frozenset({"rejected", "harmless"}), 3),
    ("truncate_hdf5", truncate_hdf5, "hdf5", frozenset({"rejected"}), 2),
    ("scalar_dataset", scalar_dataset, "rmb", frozenset({"rejected"}), 2),
    ("group_for_dataset", group_for_dataset, "rmb", frozenset({"rejected"}), 1),
    ("non_utf8_dataset_name", non_utf8_dataset_name, "hdf5", frozenset({"rejected"}), 1),
    ("task_desc_invalid_utf8", task_desc_invalid_utf8, "rmb", frozenset({"rejected"}), 1),
    ("task_desc_not_text", task_desc_not_text, "hdf5", frozenset({"rejected"}), 2),
    ("integer_joint_positions", integer_joint_positions, "rmb", frozenset({"rejected"}), 1),
    ("bool_joint_positions", bool_joint_positions, "hdf5", frozenset({"rejected"}), 1),
    ("extra_joint_column", extra_joint_column, "hdf5", frozenset({"rejected"}), 2),
    ("depth_in_millimetres", depth_in_millimetres, "hdf5", frozenset({"rejected"}), 1),
    ("depth_video_as_rgb", depth_video_as_rgb, "rmb", frozenset({"rejected"}), 1),
    ("bad_fovy", bad_fovy, "rmb", frozenset({"rejected"}), 3),
    ("depth_nonfinite", depth_nonfinite, "hdf5", frozenset({"rejected"}), 2),
    ("depth_negative", depth_negative, "hdf5", frozenset({"accepted"}), 1),
    ("flip_hdf5_data_compact", flip_hdf5_data, "rmb", frozenset({"rejected"}), 4),
    ("flip_hdf5_data_single", flip_hdf5_data, "hdf5", frozenset({"rejected"}), 4),
]
CASES = [
    pytest.param(name, corrupt, variant, allowed, index, id=f"{name}-{index}")
    for name, corrupt, variant, allowed, count in CLASSES
    for index in range(count)
]


# ------------------------------------------------------------------ the child processes
@pytest.fixture(scope="module")
def run_case():
    """``run_case(episode, dest) -> {"outcome", "message"}`` through the fork server."""
    server = subprocess.Popen(
        [sys.executable, str(Path(__file__).with_name("bad_input_server.py")), str(CASE_TIMEOUT_S)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env={**os.environ, "OMP_NUM_THREADS": "1", "HF_HUB_OFFLINE": "1"},
    )

    def _run(episode: Path, dest: Path) -> dict:
        server.stdin.write(json.dumps({"episode": str(episode), "dest": str(dest)}) + "\n")
        server.stdin.flush()
        line = server.stdout.readline()
        assert line, f"the fork server died (exit code {server.poll()})"
        return json.loads(line)

    yield _run
    server.stdin.close()
    server.wait(timeout=30)


@pytest.fixture(scope="module")
def valid_episodes(tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("valid")
    steps = list(ur5e_steps(STEPS, CAMERAS, SIZE, seed=3))
    episodes = {}
    for variant in ("rmb", "hdf5"):
        path = root / f"episode.{variant}"
        with EpisodeWriter(path, ur5e_attrs(CAMERAS), fk=UR5E) as writer:
            for step in steps:
                writer.append(step)
        episodes[variant] = path
    return episodes


def _copy(source: Path, target: Path) -> Path:
    if source.is_dir():
        shutil.copytree(source, target)
    else:
        shutil.copyfile(source, target)
    return target


def test_the_valid_episodes_convert(run_case, valid_episodes, tmp_path):
    for variant, episode in valid_episodes.items():
        result = run_case(episode, tmp_path / f"ds-{variant}")
        assert result["outcome"] == "accepted", result["message"]


@pytest.mark.parametrize(("name", "corrupt", "variant", "allowed", "index"), CASES)
def test_bad_input_ends_in_our_error_or_a_documented_handling(
    run_case, valid_episodes, tmp_path, name, corrupt, variant, allowed, index
):
    rng = np.random.default_rng([SEED, index, sum(map(ord, name))])
    work = tmp_path / "in"
    work.mkdir()
    episode = _copy(valid_episodes[variant], work / valid_episodes[variant].name)
    corrupt(episode, rng)
    dest = tmp_path / "out" / "ds"
    result = run_case(episode, dest)
    if result["outcome"] == "accepted" and "harmless" in allowed:
        result["outcome"] = (
            "harmless"
            if _same_lowdim(episode, valid_episodes[variant])
            else ("accepted with changed data")
        )

    assert result["outcome"] in allowed, f"{name}: {result['outcome']}\n{result['message']}"
    if result["outcome"] == "rejected":
        assert episode.name in result["message"], result["message"]  # names the file
        assert not dest.exists()
        assert not dest.parent.exists() or not any(dest.parent.iterdir())


def _same_lowdim(damaged: Path, original: Path) -> bool:
    """Whether every low-dim key and attribute of ``damaged`` equals the original's."""
    with open_episode(damaged) as a, open_episode(original) as b:
        keys = [k for k in b if not K.is_image_key(k)]
        return (
            set(a) == set(b)
            and dict(a.attrs).keys() == dict(b.attrs).keys()
            and all(np.array_equal(a[k][:], b[k][:]) for k in keys)
        )
