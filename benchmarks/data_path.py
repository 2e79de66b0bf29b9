"""The training data path of the quick start's ACT: RGB as AV1 video vs as LeRobot image features.

Usage::

    .venv/bin/python benchmarks/data_path.py [--episodes 10] [--steps 60] [--log-every 10]
        [--rounds 2] [--workers 1] [--samples 200] [--source DIR]

Data: Insert demonstrations as the quick start records them (``rmb-collect``: cameras ``front``
and ``hand`` at 64x64, no depth; or the episodes in ``--source``), converted twice as the quick
start converts them (``rmb-convert to-lerobot --no-extra-keys``): RGB as LeRobot's AV1 videos
(the default) and with ``--image-features`` (PNG bytes in the parquet rows). Then, in
alternating rounds so that the shared machine's load hits both alike:

1. the loader alone: CPU ms per sample of what the quick start's ACT asks for (state and both
   images at t, actions t .. t+19), ``LeRobotDataset[i]`` in this process;
2. ``lerobot-train`` itself with the quick start's ACT recipe
   (:func:`rmb_lerobot.cli.quickstart.act_train_stage`, one torch thread), for each
   ``--workers`` value: LeRobot's own ``data_s`` (waiting for the batch) and ``updt_s`` (the
   update) parsed from its log; the first log window (worker start-up) is dropped, medians of the
   rest are kept.

Before timing, the frames are compared with the RMB episodes' own (decoded) frames: the image
form must equal them exactly; the video form's AV1 error is printed. Prints markdown tables,
the load average before and after, and each form's disk size.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.cli.quickstart import Stage, act_train_stage
from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.episode import find_episodes, open_episode

CAMERAS = ("front", "hand")
SIZE = (64, 64)
CHUNK = 20  # the quick start's ACT chunk_size
FORMS = {"video": [], "image": ["--image-features"]}
_METRIC = re.compile(r"(updt_s|data_s):([0-9.]+)")


def _env() -> dict[str, str]:
    """The quick start's environment for its stages (:func:`rmb_lerobot.cli.quickstart.run`)."""
    return {
        **os.environ,
        "HF_HUB_OFFLINE": "1",
        "WANDB_MODE": "disabled",
        "OMP_NUM_THREADS": os.environ.get("OMP_NUM_THREADS", "1"),
    }


def _run(stage: Stage) -> str:
    """Run a stage quietly; its combined output, or exit with it if the stage failed."""
    result = subprocess.run(stage.argv(), env=_env(), capture_output=True, text=True, check=False)
    if result.returncode != 0:
        sys.exit(f"{stage} failed:\n{result.stdout[-3000:]}\n{result.stderr[-3000:]}")
    return result.stdout + result.stderr


def collect(out: Path, episodes: int) -> Path:
    """Insert demos as the quick start records them."""
    stage = Stage(
        "rmb-collect",
        [
            "insert",
            f"--episodes={episodes}",
            f"--out={out}",
            "--cameras",
            *CAMERAS,
            "--image-size",
            *map(str, SIZE),
            "--no-depth",
            "--success-only",
            "--workers=2",
            "--overwrite",
        ],
    )
    _run(stage)
    return out


def convert(source: Path, work: Path) -> dict[str, Path]:
    """Both forms of the dataset, converted as the quick start converts."""
    roots = {}
    for form, extra in FORMS.items():
        roots[form] = work / f"dataset_{form}"
        args = [
            "to-lerobot",
            str(source),
            f"--repo-id=local/rmb_insert_{form}",
            f"--output={roots[form]}",
            "--no-extra-keys",
            *extra,
            "--overwrite",
        ]
        _run(Stage("rmb-convert", args))
    return roots


def disk_mb(root: Path) -> float:
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file()) / 1e6


def _dataset(root: Path, delta: bool = False):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    fps = LeRobotDataset(f"local/{root.name}", root=root, video_backend="pyav").fps
    timestamps = {N.ACTION_KEY: [i / fps for i in range(CHUNK)]} if delta else None
    return LeRobotDataset(
        f"local/{root.name}", root=root, delta_timestamps=timestamps, video_backend="pyav"
    )


def frame_errors(roots: dict[str, Path], source: Path) -> dict[str, int]:
    """Largest per-pixel difference (0..255) of each form's frames from the RMB episodes'."""
    episodes = find_episodes(source)
    worst = dict.fromkeys(roots, 0)
    for form, root in roots.items():
        dataset = _dataset(root)
        offset = 0
        for index, path in enumerate(episodes):
            with open_episode(path) as episode:
                frames = {c: episode[K.rgb_image_key(c)][:] for c in CAMERAS}
            for i in range(0, len(frames[CAMERAS[0]]), 7):  # every 7th frame of each episode
                item = dataset[offset + i]
                assert int(item["episode_index"]) == index
                for camera in CAMERAS:
                    loaded = item[N.image_key(camera)].numpy().transpose(1, 2, 0)
                    loaded = np.rint(loaded * 255).astype(np.int16)
                    error = int(np.abs(loaded - frames[camera][i].astype(np.int16)).max())
                    worst[form] = max(worst[form], error)
            offset += len(frames[CAMERAS[0]])
    return worst


def loader_cpu(roots: dict[str, Path], samples: int, rounds: int) -> dict[str, float]:
    """Median CPU ms per ACT sample of each form, in alternating rounds."""
    datasets = {form: _dataset(root, delta=True) for form, root in roots.items()}
    count = len(next(iter(datasets.values())))
    indices = np.random.default_rng(0).integers(0, count, samples)
    keys = [N.STATE, N.ACTION_KEY, *(N.image_key(c) for c in CAMERAS)]
    cpu: dict[str, list[float]] = {form: [] for form in roots}
    for _ in range(rounds):
        for form, dataset in datasets.items():
            start = time.process_time()
            for index in indices:
                item = dataset[int(index)]
                _ = [item[k] for k in keys]
            cpu[form].append(1000 * (time.process_time() - start) / samples)
    return {form: float(np.median(values)) for form, values in cpu.items()}


def train_metrics(root: Path, work: Path, steps: int, log_every: int, workers: int) -> dict:
    """``data_s`` and ``updt_s`` medians (first window dropped) of one ``lerobot-train`` run."""
    entry = entry_for("insert")
    env_args = [
        f"--env.type={entry.lerobot_type}",
        f"--env.cameras=[{','.join(CAMERAS)}]",
        f"--env.image_width={SIZE[0]}",
        f"--env.image_height={SIZE[1]}",
    ]
    out = work / "train"
    shutil.rmtree(out, ignore_errors=True)
    stage = act_train_stage(
        f"local/{root.name}",
        root,
        env_args,
        out,
        steps=steps,
        batch_size=8,
        seed=1,
        log_every=log_every,
        num_workers=workers,
    )
    start = time.perf_counter()
    log = _run(stage)
    wall = time.perf_counter() - start
    windows = [
        dict((name, float(value)) for name, value in _METRIC.findall(line))
        for line in log.splitlines()
        if "data_s:" in line and "updt_s:" in line
    ]
    if len(windows) < 2:
        sys.exit(f"lerobot-train logged {len(windows)} windows; need >= 2:\n{log[-3000:]}")
    kept = windows[1:]
    return {
        "first_data_s": windows[0]["data_s"],
        "data_s": float(np.median([w["data_s"] for w in kept])),
        "updt_s": float(np.median([w["updt_s"] for w in kept])),
        "wall_s": wall,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=10, help="Insert demos to collect")
    parser.add_argument("--source", type=Path, help="use these RMB episodes instead of collecting")
    parser.add_argument("--steps", type=int, default=60, help="lerobot-train steps per run")
    parser.add_argument("--log-every", type=int, default=10, help="lerobot-train --log_freq")
    parser.add_argument("--rounds", type=int, default=2, help="alternating rounds")
    parser.add_argument(
        "--workers", type=int, nargs="+", default=[1], help="lerobot-train --num_workers values"
    )
    parser.add_argument("--samples", type=int, default=200, help="loader samples per round")
    args = parser.parse_args()
    import datasets

    datasets.disable_progress_bars()
    load_before = os.getloadavg()
    work = Path(tempfile.mkdtemp(prefix="bench_data_path_"))
    try:
        source = args.source or collect(work / "rmb", args.episodes)
        roots = convert(source, work)
        errors = frame_errors(roots, source)
        assert errors["image"] == 0, f"image features differ from the episodes' frames: {errors}"
        cpu = loader_cpu(roots, args.samples, args.rounds)
        runs: dict[tuple[str, int], list[dict]] = {}
        for _ in range(args.rounds):
            for workers in args.workers:
                for form, root in roots.items():
                    metrics = train_metrics(root, work, args.steps, args.log_every, workers)
                    runs.setdefault((form, workers), []).append(metrics)
        load_after = os.getloadavg()
        print(
            f"{len(find_episodes(source))} Insert episodes, cameras {CAMERAS} at "
            f"{SIZE[0]}x{SIZE[1]}; load average (1/5/15 min) before "
            f"{'/'.join(f'{x:.1f}' for x in load_before)}, after "
            f"{'/'.join(f'{x:.1f}' for x in load_after)}"
        )
        print(
            f"frames vs the RMB episodes' own: video max |diff| {errors['video']}/255 (AV1), "
            f"image max |diff| {errors['image']}/255"
        )
        print("\n| RGB stored as | disk MB | loader CPU ms/sample (median) | CPU ratio |")
        print("|---|---:|---:|---:|")
        for form, root in roots.items():
            ratio = cpu[form] / cpu["video"]
            print(f"| {form} | {disk_mb(root):.2f} | {cpu[form]:.2f} | {ratio:.2f} |")
        print(
            f"\nlerobot-train, quick start's ACT, {args.steps} steps, batch 8, "
            f"log every {args.log_every} (first window dropped), {args.rounds} rounds, medians:\n"
        )
        print(
            "| RGB stored as | num_workers | data_s, first window | data_s | updt_s | "
            "data_s / updt_s | run wall s |"
        )
        print("|---|---:|---:|---:|---:|---:|---:|")
        for (form, workers), metrics in runs.items():
            data = float(np.median([m["data_s"] for m in metrics]))
            update = float(np.median([m["updt_s"] for m in metrics]))
            wall = float(np.median([m["wall_s"] for m in metrics]))
            first = float(np.median([m["first_data_s"] for m in metrics]))
            print(
                f"| {form} | {workers} | {first:.3f} | {data:.3f} | {update:.3f} | "
                f"{100 * data / update:.1f} % | {wall:.0f} |"
            )
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
