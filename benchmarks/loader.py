"""Training-style random access: a converted LeRobotDataset against the RMB episodes it came from.

Usage::

    .venv/bin/python benchmarks/loader.py [--episodes 3] [--steps 100] [--size 640 480]
        [--samples 300] [--workdir DIR] [--video-backends pyav [torchcodec]]

Data: synthetic UR5e episodes (:mod:`rmb_lerobot.synthetic`) written as compact ``.rmb``
(H.264 RGB with our writer's GOP 10, lossless ``rmb-videoio`` depth with GOP 30), converted with
``rmb-convert to-lerobot --depth``, once with LeRobot's default RGB codec (AV1, GOP 2) and once
with ``--video-codec copy``; depth is LeRobot's 12-bit HEVC (GOP 2) in both.

One sample, as a policy with two observation steps and an action chunk asks for it (the
``delta_timestamps`` of diffusion-like policies): ``observation.state`` at t-1 and t, the
``front`` and ``hand`` RGB images at t-1 and t, the ``hand`` depth image at t, and the actions
t .. t+15 (indices clamped at episode ends, as LeRobot pads). Samples are drawn uniformly at
random (fixed seed) in one process, as ``DataLoader(num_workers=0)`` would; rates scale with
workers on both sides.

- ``LeRobotDataset``: ``LeRobotDataset(..., delta_timestamps=..., video_backend=...)[i]``, for the
  default conversion (AV1 RGB, GOP 2) and for ``--video-codec copy`` (the episodes' H.264, GOP 10);
  depth is LeRobot's HEVC in both. ``pyav`` (our environment's decoder) reopens and seeks each
  video per sample; ``torchcodec`` keeps one decoder per file open, but loads only where FFmpeg
  4-8 shared libraries are on the loader path (not from our PyPI-only install, see RESULTS.md).
- ``open_episode``: one open :class:`~rmb_lerobot.episode.Episode` per file, its series kept
  (readers stay open between samples); frames read by index lists, low-dimensional keys read
  from HDF5 per sample.
- ``open_episode, cache``: ``open_episode(cache=True)``: every key of every episode decoded into
  RAM once (the setup time is reported), then numpy indexing.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import EpisodeWriter, find_episodes, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters import ConvertOptions, to_lerobot
from rmb_lerobot.converters.copy import COPY
from rmb_lerobot.kinematics import UR5E
from rmb_lerobot.synthetic import UR5E_CONTROL_HZ, ur5e_attrs, ur5e_steps

CAMERAS = ("front", "hand")
DEPTH_CAMERA = "hand"
OBS_STEPS = (-1, 0)
ACTION_STEPS = tuple(range(16))


def make_data(work: Path, episodes: int, steps: int, size: tuple[int, int]) -> dict[str, Path]:
    """The RMB episodes and their conversions with LeRobot's default RGB codec and ``copy``."""
    paths = {"episodes": work / "episodes", None: work / "dataset", COPY: work / "dataset_copy"}
    if not paths["episodes"].exists():
        for index in range(episodes):
            path = paths["episodes"] / f"synthetic_{index:03d}.rmb"
            with EpisodeWriter(path, ur5e_attrs(CAMERAS), fk=UR5E) as writer:
                for step in ur5e_steps(steps, CAMERAS, size, seed=index):
                    writer.append(step)
    for codec in (None, COPY):
        if not paths[codec].exists():
            options = ConvertOptions(depth=True)
            to_lerobot([paths["episodes"]], output=paths[codec], options=options, video_codec=codec)
    return paths


def lerobot_loader(root: Path, video_backend: str):
    fps = UR5E_CONTROL_HZ
    obs = [i / fps for i in OBS_STEPS]
    delta = {key: obs for key in (N.STATE, N.image_key("front"), N.image_key("hand"))}
    delta[N.ACTION_KEY] = [i / fps for i in ACTION_STEPS]
    dataset = LeRobotDataset(
        f"local/{root.name}", root=root, delta_timestamps=delta, video_backend=video_backend
    )
    depth = N.depth_image_key(DEPTH_CAMERA)
    keys = [N.STATE, N.ACTION_KEY, N.image_key("front"), N.image_key("hand"), depth]

    def sample(index: int) -> dict:
        item = dataset[index]
        return {key: item[key] for key in keys}

    return sample, len(dataset)


class EpisodeLoader:
    """A map-style sampler over RMB episodes through ``open_episode``."""

    def __init__(self, paths: list[Path], cache: bool):
        self.episodes = [open_episode(path, cache=cache) for path in paths]
        self.image_keys = [K.rgb_image_key(c) for c in CAMERAS]
        self.depth_key = K.depth_image_key(DEPTH_CAMERA)
        self.lowdim = (K.MEASURED_JOINT_POS, K.COMMAND_JOINT_POS)
        keys = (*self.image_keys, self.depth_key, *self.lowdim)
        # Series objects hold the open video readers; with cache=True this decodes everything.
        self.series = [{key: ep[key] for key in keys} for ep in self.episodes]
        self.starts = np.cumsum([0] + [len(ep) for ep in self.episodes])

    def __len__(self) -> int:
        return int(self.starts[-1])

    def __call__(self, index: int) -> dict:
        episode = int(np.searchsorted(self.starts, index, side="right") - 1)
        t, length, series = (
            index - self.starts[episode],
            len(self.episodes[episode]),
            self.series[episode],
        )
        obs = [min(max(t + d, 0), length - 1) for d in OBS_STEPS]
        act = [min(max(t + d, 0), length - 1) for d in ACTION_STEPS]
        item = {key: series[key][obs] for key in self.image_keys}
        item[self.depth_key] = series[self.depth_key][[obs[-1]]]
        item[K.MEASURED_JOINT_POS] = series[K.MEASURED_JOINT_POS][obs]
        item[K.COMMAND_JOINT_POS] = series[K.COMMAND_JOINT_POS][act]
        return item

    def close(self) -> None:
        for episode in self.episodes:
            episode.close()


def run(sample, count: int, samples: int, seed: int = 0) -> tuple[float, float]:
    """(samples per second, CPU ms per sample) over ``samples`` random indices."""
    indices = np.random.default_rng(seed).integers(0, count, samples)
    sample(int(indices[0]))  # warm up (opens files)
    wall, cpu = time.perf_counter(), time.process_time()
    for index in indices:
        sample(int(index))
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    return samples / wall, 1000 * cpu / samples


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=3)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--size", type=int, nargs=2, default=[640, 480], metavar=("W", "H"))
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument("--workdir", type=Path, help="keep the data here (default: a temp dir)")
    parser.add_argument(
        "--video-backends",
        nargs="+",
        choices=("pyav", "torchcodec"),
        default=["pyav"],
        help="LeRobot decoders to measure (torchcodec needs FFmpeg 4-8 shared libraries)",
    )
    args = parser.parse_args()
    if "torchcodec" in args.video_backends:
        import torchcodec  # fails here, with torchcodec's own reason, rather than mid-benchmark

        print(f"torchcodec {torchcodec.__version__} on FFmpeg {torchcodec.ffmpeg_major_version}")

    import av
    import datasets

    av.logging.set_libav_level(av.logging.ERROR)
    datasets.disable_progress_bars()
    work = Path(args.workdir or tempfile.mkdtemp(prefix="bench_loader_"))
    work.mkdir(parents=True, exist_ok=True)
    data = make_data(work, args.episodes, args.steps, tuple(args.size))
    paths = find_episodes(data["episodes"])

    rows = []
    for backend in args.video_backends:
        for codec, name in ((None, "AV1, GOP 2"), (COPY, "copy: H.264, GOP 10")):
            sample, count = lerobot_loader(data[codec], backend)
            rows.append(
                (f"LeRobotDataset ({name}), {backend}", 0.0, *run(sample, count, args.samples))
            )
    for cache in (False, True):
        setup = time.perf_counter()
        loader = EpisodeLoader(paths, cache=cache)
        setup = time.perf_counter() - setup
        name = "open_episode, cache" if cache else "open_episode"
        rows.append((name, setup, *run(loader, len(loader), args.samples)))
        loader.close()

    print(
        f"{len(paths)} episodes x {args.steps} steps, {args.size[0]}x{args.size[1]}, "
        f"{args.samples} random samples, one process"
    )
    print("\n| loader | setup s | samples/s | CPU ms/sample |")
    print("|---|---:|---:|---:|")
    for name, setup, rate, cpu in rows:
        print(f"| {name} | {setup:.1f} | {rate:.1f} | {cpu:.1f} |")
    if args.workdir is None:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
