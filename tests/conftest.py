"""Shared fixtures: small synthetic episodes, and the ORIGINAL RMB's I/O recipe.

``write_like_original``/``read_like_original`` re-implement, independently of our package, what
RoboManipBaselines' ``DataManager.dump_to_rmb`` and ``RmbData`` do (h5py datasets from
``np.array(list)``, ``videoio.videosave``/``uint16save`` through FFmpeg, full-video decoding),
using PyAV in place of the ffmpeg binary. They let the tests check compatibility both ways.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

# Headless rendering, as `make test` exports it, also for a bare `pytest`: set before anything
# imports MuJoCo (which picks its GL backend once, on import).
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])

import av
import h5py
import numpy as np
import pytest

from rmb_lerobot import EpisodeWriter
from rmb_lerobot.kinematics import UR5E
from rmb_lerobot.synthetic import ur5e_attrs, ur5e_steps

CAMERAS = ("front", "hand")
SIZE = (64, 48)
STEPS = 12


@pytest.fixture
def no_network(monkeypatch):
    """Fail any attempt to open a network connection: tests make or ship the data they need."""
    import socket

    def refuse(*args, **kwargs):
        raise AssertionError("a test tried to use the network")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)


@pytest.fixture
def steps() -> list[dict]:
    return list(ur5e_steps(STEPS, CAMERAS, SIZE, seed=1))


@pytest.fixture
def attrs() -> dict:
    return ur5e_attrs(CAMERAS)


@pytest.fixture
def record(steps, attrs):
    """Write the synthetic episode to ``path`` and return the path."""

    def _record(path: Path, **kwargs) -> Path:
        with EpisodeWriter(path, attrs, fk=UR5E, **kwargs) as writer:
            for step in steps:
                writer.append(step)
        return path

    return _record


def _encode(path: Path, frames: list[np.ndarray], pix_fmt: str, options: dict, planar: bool):
    # Like ffmpeg reading rawvideo from a pipe with no -framerate: 25 fps, no frame rate stored.
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=25, options=options)
        stream.height, stream.width = frames[0].shape[-2:] if planar else frames[0].shape[:2]
        stream.pix_fmt = pix_fmt
        for frame in frames:
            if planar:
                video_frame = av.VideoFrame.from_ndarray(frame, format="yuv444p")
            else:
                video_frame = av.VideoFrame.from_ndarray(frame, format="rgb24").reformat(
                    format=pix_fmt
                )
            container.mux(stream.encode(video_frame))
        container.mux(stream.encode(None))


def videoio_fold(depth_mm: np.ndarray) -> np.ndarray:
    """videoio.uint16save's frame layout: planes (Y, U, V) = (folded low byte, 0, high byte)."""
    upper = (depth_mm / 256).astype(np.uint8)
    lower = (depth_mm % 256).astype(np.uint8)
    odd = upper % 2 == 1
    lower[odd] = 255 - lower[odd]
    return np.stack([lower, np.zeros_like(lower), upper])


def videoio_unfold(planes: np.ndarray) -> np.ndarray:
    upper, lower = planes[2], planes[0].copy()
    odd = upper % 2 == 1
    lower[odd] = 255 - lower[odd]
    return lower.astype(np.uint16) + upper.astype(np.uint16) * 256


@pytest.fixture
def write_like_original():
    """DataManager.dump_to_rmb / dump_to_hdf5 of the original RMB, step lists in RAM."""

    def _write(path: Path, steps: list[dict], meta: dict) -> Path:
        seq = {key: [step[key] for step in steps] for key in steps[0]}
        compact = path.suffix == ".rmb"
        if compact:
            path.mkdir()
        h5_path = path / "main.rmb.hdf5" if compact else path
        with h5py.File(h5_path, "w") as h5:
            for key, values in seq.items():
                if compact and key.endswith("_rgb_image"):
                    _encode(
                        path / f"{key}.rmb.mp4", values, "yuv420p", {"preset": "slow"}, planar=False
                    )
                elif compact and key.endswith("_depth_image"):
                    depth_mm = (1e3 * np.array(values)).astype(
                        np.uint16
                    )  # truncation, as the original
                    frames = [videoio_fold(d) for d in depth_mm]
                    options = {"preset": "slow", "crf": "0", "profile": "high444"}
                    _encode(path / f"{key}.rmb.mp4", frames, "yuv444p", options, planar=True)
                else:
                    h5.create_dataset(key, data=np.array(values))
            for key, value in meta.items():
                h5.attrs[key] = value
            h5.attrs["format"] = "RmbData-Compact" if compact else "RmbData-SingleHDF5"
        return path

    return _write


@pytest.fixture
def read_like_original():
    """RmbData's read path: h5py datasets, whole-video decode (rgb24 / yuv444p + unfold)."""

    def _decode(video: Path, fmt: str) -> list[np.ndarray]:
        with av.open(str(video)) as container:
            return [frame.to_ndarray(format=fmt) for frame in container.decode(video=0)]

    def _read(path: Path) -> tuple[dict[str, np.ndarray], dict]:
        compact = path.suffix == ".rmb"
        h5_path = path / "main.rmb.hdf5" if compact else path
        data = {}
        with h5py.File(h5_path, "r") as h5:
            for key in h5:
                data[key] = h5[key][()]
            attrs = dict(h5.attrs)
        if compact:
            for video in path.glob("*.rmb.mp4"):
                key = video.name.removesuffix(".rmb.mp4")
                if key.endswith("_rgb_image"):
                    data[key] = np.stack(_decode(video, "rgb24"))
                elif key.endswith("_depth_image"):
                    frames = _decode(video, "yuv444p")
                    data[key] = (1e-3 * np.stack([videoio_unfold(f) for f in frames])).astype(
                        np.float32
                    )
        return data, attrs

    return _read


@pytest.fixture
def psnr():
    """Peak signal-to-noise ratio of uint8 images, in dB."""

    def _psnr(a: np.ndarray, b: np.ndarray) -> float:
        mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
        return float("inf") if mse == 0 else float(10 * np.log10(255**2 / mse))

    return _psnr


# ------------------------------------------------ the LeRobot CLIs, on expert data, offline
def _run_lerobot_cli(module: str, args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """Run an unmodified LeRobot CLI (``python -m lerobot.scripts.<module>``) offline."""
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "WANDB_MODE": "disabled"}
    return subprocess.run(
        [sys.executable, "-m", f"lerobot.scripts.{module}", *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )


def _expert_dataset(
    task: str,
    root: Path,
    *,
    world_idx: tuple[int, ...] = (0,),
    cameras: tuple[str, ...] = ("front",),
    size: int = 32,
    depth: bool = False,
) -> Path:
    """Demonstrations by ``task``'s scripted expert (one per world, seed = episode index, as
    ``rmb-collect``), converted as ``rmb-convert to-lerobot [--depth]`` does; returns the
    dataset root (``root/dataset``)."""
    from rmb_lerobot.converters import ConvertOptions, to_lerobot
    from rmb_lerobot.envs.collect import CollectConfig, collect

    config = CollectConfig(
        task,
        root / "rmb",
        episodes=len(world_idx),
        world_idx=world_idx,
        cameras=cameras,
        image_size=(size, size),
    )
    assert all(result.success for result in collect(config)), f"{task} expert failed"
    dataset = root / "dataset"
    options = ConvertOptions(depth=depth)
    to_lerobot([root / "rmb"], output=dataset, options=options, video_codec="h264", progress=False)
    return dataset


@pytest.fixture(scope="session")
def lerobot_cli():
    """``lerobot_cli("lerobot_train", args, cwd)``: an unmodified LeRobot CLI, offline."""
    return _run_lerobot_cli


# A test that starts LeRobot's CLIs (lerobot-train, then lerobot-eval: fresh interpreters that
# import LeRobot) took 55-160 s in a full `make test` and up to 400 s alone on a loaded 2-core
# machine: over the suite's default limit (pyproject.toml), so its own unless it names one.
LEROBOT_CLI_TIMEOUT_S = 1200


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        uses_cli = "lerobot_cli" in getattr(item, "fixturenames", ())
        if uses_cli and item.get_closest_marker("timeout") is None:
            item.add_marker(pytest.mark.timeout(LEROBOT_CLI_TIMEOUT_S))


@pytest.fixture(scope="session")
def make_expert_dataset():
    """``make_expert_dataset(task, root, world_idx=..., cameras=..., size=..., depth=...)``:
    scripted-expert demos converted to a LeRobotDataset (see ``_expert_dataset``)."""
    return _expert_dataset


@pytest.fixture(scope="session")
def shared_expert_dataset(tmp_path_factory):
    """``shared_expert_dataset(task, world_idx=..., cameras=..., size=..., depth=...)``: as
    ``make_expert_dataset``, but built once per test run for each set of arguments and shared
    by every test and xdist worker that asks for it (a file lock in the run's temporary root).
    READ-ONLY: a test that changes it copies it first."""
    import hashlib
    import json
    import shutil

    from filelock import FileLock

    # Under xdist each worker's basetemp is <run root>/popen-gwN: the run root is shared.
    base = tmp_path_factory.getbasetemp()
    root = base.parent if base.name.startswith("popen-gw") else base
    shared = root / "shared_expert_datasets"
    shared.mkdir(exist_ok=True)

    def _shared(task: str, **kwargs) -> Path:
        spec = json.dumps({"task": task, **kwargs}, sort_keys=True, default=list)
        done = shared / hashlib.sha256(spec.encode()).hexdigest()[:16]
        with FileLock(f"{done}.lock"):
            if not done.exists():
                partial = Path(f"{done}.partial")
                shutil.rmtree(partial, ignore_errors=True)
                _expert_dataset(task, partial, **kwargs)
                (partial / "spec.json").write_text(spec)
                partial.rename(done)  # complete, or not there at all
        return done / "dataset"

    return _shared


@pytest.fixture
def python_sigint():
    """Python's own SIGINT handler for the test, as in a fresh interpreter: tests that simulate
    Ctrl-C with ``_thread.interrupt_main`` need it, and an earlier test in the same worker (a
    library deferring or ignoring SIGINT) may have left another one. Restored afterwards."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)
