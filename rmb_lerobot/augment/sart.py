"""SART: augment one demonstration with motions that converge onto it (RMB's RoboManipAug).

For each acceptable region (:mod:`rmb_lerobot.augment.regions`) and each of N samples:

1. restore the world and the robot as the demonstration had them at the region's convergence
   step, by resetting the simulated env to the demo's world (``world_idx``, the same seed) and
   replaying the demo's joint commands up to that step (deterministic on one machine; the
   replayed joints are compared with the recorded ones and a divergence is reported);
2. draw a tool position on the sphere's *surface* (uniform) and a tool rotation within
   ``max_rotation`` of the centre's (random axis, uniform angle: RoboManipAug's sampling), and
   drive the tool there in ``duration`` seconds (geodesic SE(3) interpolation with a smooth
   start and stop, solved by the env's IK) while recording every RMB key the env records;
3. play that recording backwards (:func:`~rmb_lerobot.augment.reverse.reverse_recording`; the
   command keys advanced by twice the controller lag measured in the demo), drop its last
   frames where they retrace the arm's carry-on along the demo (:meth:`Augmenter.find_join`),
   give the frames whose advanced commands ran out the demo's own commands from the
   convergence step up to the join step, append the rest of the demonstration after the join
   step, renumber ``time``, recompute the relative keys over the join, and write a complete
   RMB episode atomically with :class:`~rmb_lerobot.EpisodeWriter`.

The first frame of each episode is the perturbed pose; its last part is the demonstration.

Real robots (none exist in this package yet): step 1 cannot replay a world; as RoboManipAug
does, the robot would follow the demo's commands once to the convergence step and return there
(a joint-space move) before each sample, and every command of steps 1-2 would have to pass the
real env's safety layer (joint, velocity and workspace limits) before it reaches the arm; the
acceptable region is the demonstrator's promise that nothing is touched inside it.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from rmb_lerobot import keys as K
from rmb_lerobot.augment.regions import Region
from rmb_lerobot.augment.reverse import derive_relative, reverse_recording
from rmb_lerobot.episode import EpisodeFormat, EpisodeWriter, open_episode
from rmb_lerobot.episode.timing import control_rate
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.pose import matrix_to_pose, pose_to_matrix
from rmb_lerobot.staging import remove_stale

logger = logging.getLogger(__name__)

__all__ = [
    "AugmentConfig",
    "Augmenter",
    "SampleResult",
    "demo_at",
    "estimate_lag",
    "propose_demo_regions",
    "sample_rotation",
    "sample_sphere_surface",
]

REPLAY_TOLERANCE = 1e-3  # rad: a replayed joint further than this from the demo is reported
IMAGE_CHUNK = 64  # demo frames decoded at a time when appending the remainder


def sample_sphere_surface(
    rng: np.random.Generator, centre: np.ndarray, radius: float
) -> np.ndarray:
    """A point drawn uniformly from the surface of a sphere."""
    direction = rng.standard_normal(3)
    while np.linalg.norm(direction) < 1e-9:
        direction = rng.standard_normal(3)
    return np.asarray(centre, dtype=np.float64) + radius * direction / np.linalg.norm(direction)


def sample_rotation(rng: np.random.Generator, max_angle: float) -> np.ndarray:
    """A rotation matrix about a uniformly random axis by an angle uniform in
    ``[-max_angle, max_angle]`` (RoboManipAug's ``sample_random_rotation``)."""
    axis = rng.standard_normal(3)
    axis /= max(np.linalg.norm(axis), 1e-12)
    angle = rng.uniform(-max_angle, max_angle)
    return Rotation.from_rotvec(axis * angle).as_matrix()


def demo_at(values: np.ndarray, tau: np.ndarray, *, pose: bool = False) -> np.ndarray:
    """``values`` (step-major) at fractional steps ``tau``: linear between neighbouring steps;
    for eef poses (7 numbers per eef, position + wxyz quaternion) the quaternions are
    interpolated on the short arc and normalised."""
    values = np.asarray(values, dtype=np.float64)
    tau = np.clip(np.asarray(tau, dtype=np.float64), 0, len(values) - 1)
    low = np.minimum(np.floor(tau).astype(int), len(values) - 1)
    high = np.minimum(low + 1, len(values) - 1)
    w = (tau - low)[:, None]
    a, b = values[low], values[high]
    if not pose:
        return (1 - w) * a + w * b
    a = a.reshape(len(tau), -1, 7)
    b = b.reshape(len(tau), -1, 7).copy()
    flip = np.sum(a[..., 3:] * b[..., 3:], axis=-1) < 0
    b[..., 3:][flip] *= -1
    out = (1 - w[..., None]) * a + w[..., None] * b
    out[..., 3:] /= np.linalg.norm(out[..., 3:], axis=-1, keepdims=True)
    return out.reshape(len(tau), -1)


def estimate_lag(command: np.ndarray, measured: np.ndarray, max_lag: int = 20) -> int:
    """Steps after which the measured joints move as the commands moved (the controller's
    lag), from per-step changes, so that a steady offset (a servo sagging under gravity) does
    not count."""
    dc = np.diff(np.asarray(command, dtype=np.float64), axis=0)
    dm = np.diff(np.asarray(measured, dtype=np.float64), axis=0)
    n = len(dc)
    if n < 2:
        return 0
    errors = [np.abs(dc[: n - k] - dm[k:]).mean() for k in range(min(max_lag, n - 1) + 1)]
    return int(np.argmin(errors))


@dataclass(frozen=True)
class AugmentConfig:
    """How samples are drawn and driven (defaults: RoboManipAug's)."""

    samples_per_region: int = 16
    duration_s: float = 2.0  # drive from the convergence pose to the sample (RMB: 2 s)
    rotation_scale: float = 2.0  # rad per metre of radius when a region sets no max rotation
    seed: int = 0  # reset seed (the demo's world) and the base of the sampling seeds
    fmt: str | None = None  # "rmb" or "hdf5"; default: the demo's
    overwrite: bool = False
    command_shift: int | None = None  # None: 2 x the controller lag measured in the demo
    # The demo's random object shift (metres; rmb-collect --random-shift). The episode records
    # only its world, so a shifted demo's objects are placed again by resetting with the same
    # shift and the seed the demo was reset with: ``seed`` must then be that seed.
    random_shift: float = 0.0

    def __post_init__(self) -> None:
        if self.samples_per_region < 1:
            raise ValueError(f"samples_per_region must be >= 1, got {self.samples_per_region}")
        if self.random_shift < 0:
            raise ValueError(f"random_shift must be >= 0 metres, got {self.random_shift}")
        if self.duration_s <= 0:
            raise ValueError(f"duration_s must be > 0, got {self.duration_s}")


@dataclass
class SampleResult:
    region: int
    sample: int
    path: Path
    steps: int  # of the written episode
    reversed_steps: int  # of them, the reversed motion (frames 0..reversed_steps-1)
    target_error_m: float  # tool position reached at the end of the drive vs the sample
    replay_error_rad: float  # replayed joints vs the demo's at the convergence step
    command_shift: int
    join_idx: int = 0  # demo step the last reversed frame stands for; the demo resumes after it
    demo_commands_from: int = 0  # first frame whose commands are the demo's (up to the join)
    extra: dict[str, Any] = field(default_factory=dict)


class Augmenter:
    """Augments one demonstration in its simulated env; see the module docs.

    ``env_name``: any name the env registry knows (``MujocoUR5eInsert``, ``insert``); it must be
    the demo's env. ``out``: directory the episodes are written to (flat, so ``rmb-convert
    to-lerobot DEMO OUT`` takes them with the demo).
    """

    def __init__(
        self, env_name: str, demo_path: str | Path, out: str | Path, config: AugmentConfig
    ):
        from rmb_lerobot.envs.registry import entry_for

        self.config = config
        self.demo_path = Path(demo_path)
        self.out = Path(out)
        self.demo = open_episode(self.demo_path)
        try:
            self.entry = entry_for(env_name)
            env_attr = self.demo.attrs.get(K.ATTR_ENV)
            if env_attr != self.entry.env_attr:
                raise RmbFormatError(
                    f"the demo was recorded in {env_attr!r}, not in {self.entry.env_attr!r} "
                    f"({env_name!r})",
                    path=self.demo_path,
                    key=K.ATTR_ENV,
                )
            self._load_demo()
            self.env = self._make_env()
            self.env.reset(seed=config.seed, options=self._reset_options())
            self.tool_offset = self._tool_offset()
        except BaseException:
            self.demo.close()
            raise
        self.fmt = EpisodeFormat.from_name(config.fmt) if config.fmt else self.demo.format

    # ------------------------------------------------------------------ setup
    def _load_demo(self) -> None:
        demo = self.demo
        self.length = len(demo)
        self.lowdim_keys = [k for k in demo if not K.is_image_key(k)]
        self.image_keys = [k for k in demo if K.is_image_key(k)]
        unsupported = [k for k in demo if K.is_pointcloud_key(k)]
        if unsupported:
            raise RmbFormatError(
                "point-cloud keys cannot be re-recorded; convert without them first",
                path=self.demo_path,
                key=unsupported[0],
            )
        for key in (K.COMMAND_JOINT_POS, K.MEASURED_JOINT_POS, K.COMMAND_EEF_POSE, K.TIME):
            if key not in demo:
                raise RmbFormatError(
                    "SART needs this key in the demo", path=self.demo_path, key=key
                )
        self.data = {key: np.asarray(demo[key][:]) for key in self.lowdim_keys}
        # The controller's lag, measured where the demo moves: commands lead states by it.
        self.lag = estimate_lag(self.data[K.COMMAND_JOINT_POS], self.data[K.MEASURED_JOINT_POS])
        rate = control_rate(self.data[K.TIME], path=self.demo_path)
        self.dt = 1.0 / rate
        self.cameras = list(dict.fromkeys(K.camera_of(k) for k in self.image_keys))
        self.depth = any(K.is_depth_image_key(k) for k in self.image_keys)
        self.image_size = None
        if self.image_keys:
            height, width = demo[self.image_keys[0]][0].shape[:2]
            self.image_size = (width, height)

    def _make_env(self):
        kwargs: dict[str, Any] = {"cameras": self.cameras, "depth": self.depth}
        if self.image_size is not None:
            kwargs["image_size"] = self.image_size
        env = self.entry.make(**kwargs)
        if len(env.robot.arms) != 1:
            env.close()
            raise RmbFormatError(
                f"SART drives one arm; {self.entry.rmb_env_name} has {len(env.robot.arms)}",
                path=self.demo_path,
                key=K.ATTR_ENV,
            )
        if abs(env.control_dt - self.dt) > 1e-3 * self.dt:
            env.close()
            raise RmbFormatError(
                f"the demo steps every {self.dt:.4f} s, the env every {env.control_dt:.4f} s",
                path=self.demo_path,
                key=K.TIME,
            )
        return env

    def close(self) -> None:
        self.env.close()
        self.demo.close()

    def __enter__(self) -> Augmenter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------------ env helpers
    def _reset_options(self) -> dict[str, Any]:
        options: dict[str, Any] = {"world_idx": int(self.demo.attrs.get(K.ATTR_WORLD_IDX, 0))}
        if self.config.random_shift:
            options["random_shift"] = self.config.random_shift
        if "instruction" in self.env.task.reset_options and self.demo.attrs.get(K.ATTR_TASK_DESC):
            options["instruction"] = self.demo.attrs[K.ATTR_TASK_DESC]
        return options

    def _tool_offset(self) -> np.ndarray:
        """Flange -> tool centre point (4x4), measured in the env (RMB's poses are the flange's;
        the demonstrator's sphere is around the tool point)."""
        arm = self.env.robot.arms[0]
        flange_pos, flange_rot = self.env.sim.site_pose(arm.eef_frame)
        tcp_pos, tcp_rot = self.env.sim.site_pose(arm.tcp_frame)
        offset = np.eye(4)
        offset[:3, :3] = flange_rot.T @ tcp_rot
        offset[:3, 3] = flange_rot.T @ (tcp_pos - flange_pos)
        return offset

    def _restore(self, step: int) -> float:
        """Reset to the demo's world and replay its commands ``0..step-1``; returns the largest
        joint difference from the demo's measured joints at ``step``."""
        env = self.env
        env.reset(seed=self.config.seed, options=self._reset_options())
        commands = self.data[K.COMMAND_JOINT_POS]
        for t in range(step):
            env.step(commands[t])
        return float(np.abs(env.measured_joint_pos() - self.data[K.MEASURED_JOINT_POS][step]).max())

    # ------------------------------------------------------------------ sampling
    def sample_targets(self, region: Region, region_idx: int) -> list[np.ndarray]:
        """The N tool poses (4x4, in the arm's root frame) of a region, reproducible from the
        seed, the region's index and the sample's index."""
        centre = (
            pose_to_matrix(self.data[K.COMMAND_EEF_POSE][region.time_idx][:7]) @ self.tool_offset
        )
        max_angle = region.max_rotation_rad(self.config.rotation_scale)
        targets = []
        for i in range(self.config.samples_per_region):
            rng = np.random.default_rng([self.config.seed, region_idx, i])
            target = np.eye(4)
            target[:3, 3] = sample_sphere_surface(rng, centre[:3, 3], region.radius)
            target[:3, :3] = centre[:3, :3] @ sample_rotation(rng, max_angle)
            targets.append(target)
        return targets

    def _drive(self, target_tool: np.ndarray) -> tuple[dict[str, list], float]:
        """Drive the tool from the current command's pose to ``target_tool`` while recording."""
        env, offset = self.env, self.tool_offset
        start = pose_to_matrix(env.command_eef_pose[:7]) @ offset
        steps = max(2, round(self.config.duration_s / self.dt))
        slerp = Slerp([0.0, 1.0], Rotation.from_matrix([start[:3, :3], target_tool[:3, :3]]))
        inv_offset = np.linalg.inv(offset)
        command = env.command
        arm, _grip = env.robot.joint_slices()[0]
        recording: dict[str, list] = {}
        for i in range(1, steps + 1):
            u = 0.5 - 0.5 * np.cos(np.pi * i / steps)  # smooth start and stop
            tool = np.eye(4)
            tool[:3, :3] = slerp([u]).as_matrix()[0]
            tool[:3, 3] = (1 - u) * start[:3, 3] + u * target_tool[:3, 3]
            flange = matrix_to_pose(tool @ inv_offset)
            action = command.copy()
            action[arm] = env.sim.ik(0, flange, command[arm])
            for key, value in env.rmb_step_data(action).items():
                recording.setdefault(key, []).append(np.asarray(value))
            env.step(action)
            command = env.command
        for key, value in env.rmb_step_data().items():  # the pose reached, command held
            recording.setdefault(key, []).append(np.asarray(value))
        reached = pose_to_matrix(env.eef_pose(env.measured_joint_pos())[:7]) @ offset
        return recording, float(np.linalg.norm(reached[:3, 3] - target_tool[:3, 3]))

    # ------------------------------------------------------------------ assembling
    def _assemble(self, recording: dict[str, list], end_idx: int) -> tuple[dict, int]:
        """Reverse the recording and prepare the low-dimensional keys of the whole episode."""
        missing = [k for k in self.demo if k not in recording and not K.is_relative_key(k)]
        if missing:
            raise RmbFormatError(
                f"the env does not record {missing}, which the demo holds",
                path=self.demo_path,
                key=missing[0],
            )
        forward = {k: np.stack(v) for k, v in recording.items() if k in self.demo}
        forward.update(derive_relative(forward, set(self.demo.keys())))
        shift = self.config.command_shift
        if shift is None:
            shift = 2 * self.lag
        backward = reverse_recording(forward, command_shift=shift)
        return backward, shift

    def find_join(self, backward: dict, end_idx: int) -> tuple[int, int]:
        """Where the reversed motion hands over to the demo: ``(last reversed frame kept, demo
        step it stands for)``.

        The arm is moving along the demo when the drive out begins and its commands lead it by
        the controller's lag, so the first forward steps carry on along the demo's path before
        the arm turns to the sample; played backwards, the last frames would move the arm
        *backwards* along the demo (up, out of Insert's hole) to the convergence pose. Those
        frames are dropped: the forward steps that stay on the demo's path ahead (within half a
        demo step of it, the matched demo step not going back) are the carry-on, the reversed
        motion is cut at the last of them, and the demo resumes after the step it matched.
        Without such a carry-on the join is the convergence step itself.
        """
        tool = backward[K.MEASURED_EEF_POSE][::-1, :3]  # forward order
        demo = self.data[K.MEASURED_EEF_POSE][:, :3]
        n = len(tool)
        ahead = np.arange(end_idx, min(self.length - 1, end_idx + n))  # leaves a step after
        if len(ahead) < 2:
            return n - 1, end_idx
        step = np.linalg.norm(np.diff(demo[ahead], axis=0), axis=1).mean()
        matched = end_idx
        for j in range(1, n // 2):
            gaps = np.linalg.norm(demo[ahead] - tool[j], axis=1)
            m = int(ahead[np.argmin(gaps)])
            if gaps.min() > 0.5 * step or m < matched:
                return n - j, matched
            matched = m
        return n - n // 2, matched

    def _write(self, path: Path, backward: dict, end_idx: int, name: str, shift: int) -> tuple:
        """Join the reversed motion to the demo (:meth:`find_join`) and write the episode.

        Commands across the join: a reversed command is the forward command ``shift`` steps
        further back in the recording, so the last ``shift`` reversed frames have none (the
        drive's first command, about the demo's command before the convergence step, is the
        last one). Those frames take the demo's own commands from there on, stretched over
        them: from the convergence step's to the join step's command (joint values and
        positions interpolated linearly between demo steps, orientations by normalised
        quaternion interpolation), and the demo's next command follows after the join. The
        command stream thus runs on into the demo's remainder without holding anywhere.
        Relative command keys (and ``command_joint_vel``) are recomputed from the absolute
        ones over that span.
        """
        cut, join = self.find_join(backward, end_idx)
        n_rev = cut + 1
        n_total = len(backward[K.TIME])
        fill_from = max(1, n_total - shift)
        rest = slice(join + 1, self.length)
        lowdim = {}
        for key in self.lowdim_keys:
            lowdim[key] = np.concatenate([backward[key][:n_rev], self.data[key][rest]])
        total = len(lowdim[K.TIME])
        lowdim[K.TIME] = self.data[K.TIME][0] + self.dt * np.arange(total)
        if fill_from < n_rev:
            start = max(end_idx - 1, 0)
            frames = np.arange(1, n_rev - fill_from + 1)
            tau = start + (join - start) * frames / len(frames)
            for key in self.lowdim_keys:
                spec = K.KEYS.get(key)
                if spec is None or spec.source != K.COMMAND or spec.is_relative:
                    continue
                if key == K.COMMAND_JOINT_VEL:
                    continue  # a difference of command_joint_pos, recomputed below
                pose = spec.quantity is K.Quantity.EEF_POSE
                lowdim[key][fill_from:n_rev] = demo_at(self.data[key], tau, pose=pose)
        # Relative keys (and command_joint_vel) recomputed from the absolute values over the
        # span that changed: the filled commands and the demo's first appended step.
        first = max(min(fill_from, n_rev) - 1, 0)
        span = slice(first, min(n_rev + 1, total))
        absolute = {k: v[span] for k, v in lowdim.items() if k in K.KEYS}
        for key, rel in derive_relative(absolute, set(lowdim)).items():
            lowdim[key][first + 1 : span.stop] = rel[1:]
        if K.COMMAND_JOINT_VEL in lowdim:
            c = lowdim[K.COMMAND_JOINT_POS]
            lowdim[K.COMMAND_JOINT_VEL][first + 1 : span.stop] = (
                c[first + 1 : span.stop] - c[first : span.stop - 1]
            ) / self.dt
        attrs = dict(self.demo.attrs)
        attrs.pop(K.ATTR_FORMAT, None)
        attrs[K.ATTR_DEMO_NAME] = name
        writer = EpisodeWriter(path, attrs, derive_relative=False, overwrite=self.config.overwrite)
        with writer:
            chunk: dict[str, np.ndarray] = {}
            for t in range(total):
                step = {key: values[t] for key, values in lowdim.items()}
                for key in self.image_keys:
                    if t < n_rev:
                        step[key] = backward[key][t]
                    else:
                        j = (t - n_rev) % IMAGE_CHUNK
                        if j == 0:
                            start = join + 1 + t - n_rev
                            stop = min(start + IMAGE_CHUNK, self.length)
                            chunk[key] = np.asarray(self.demo[key][start:stop])
                        step[key] = chunk[key][j]
                writer.append(step)
        return total, n_rev, join, fill_from

    # ------------------------------------------------------------------ running
    def episode_path(self, region_idx: int, sample_idx: int) -> Path:
        stem = self.demo.attrs.get(K.ATTR_DEMO_NAME) or self.demo_path.stem.split(".")[0]
        return (
            self.out
            / f"{stem}_augmented_region{region_idx:03d}_{sample_idx:02d}.{self.fmt.short_name}"
        )

    def run(self, regions: Sequence[Region]) -> Iterator[SampleResult]:
        """Write N episodes per region, yielding each as it is written."""
        for i, region in enumerate(regions):
            region.check(self.length, path=self.demo_path, where=f"regions[{i}]")
        if not self.config.overwrite:
            for region_idx in range(len(regions)):
                for sample_idx in range(self.config.samples_per_region):
                    path = self.episode_path(region_idx, sample_idx)
                    if path.exists():
                        raise RmbFormatError(
                            "destination exists (use overwrite / --overwrite to replace it)",
                            path=path,
                        )
        self.out.mkdir(parents=True, exist_ok=True)
        remove_stale(self.out)  # temporaries of killed runs; a live run's stay
        for region_idx, region in enumerate(regions):
            end_idx = region.end_idx
            for sample_idx, target in enumerate(self.sample_targets(region, region_idx)):
                path = self.episode_path(region_idx, sample_idx)
                replay_error = self._restore(end_idx)
                if replay_error > REPLAY_TOLERANCE:
                    logger.warning(
                        "replaying %s to step %d ends %.4f rad from the recorded joints (recorded "
                        "on another machine or with another seed?); the join may jump",
                        self.demo_path,
                        end_idx,
                        replay_error,
                    )
                recording, target_error = self._drive(target)
                backward, shift = self._assemble(recording, end_idx)
                steps, n_rev, join, fill_from = self._write(
                    path, backward, end_idx, path.name.split(".")[0], shift
                )
                yield SampleResult(
                    region_idx,
                    sample_idx,
                    path,
                    steps,
                    n_rev,
                    target_error,
                    replay_error,
                    shift,
                    join_idx=join,
                    demo_commands_from=fill_from,
                )


def propose_demo_regions(augmenter: Augmenter, *, radius: float = 0.02) -> list[Region]:
    """:func:`~rmb_lerobot.augment.regions.propose_regions` for the augmenter's demo (its
    commanded gripper and tool path)."""
    from rmb_lerobot.augment.regions import propose_regions

    data = augmenter.data
    gripper_key = K.COMMAND_GRIPPER_JOINT_POS
    if gripper_key in data:
        gripper = data[gripper_key]
    else:
        gripper = data[K.COMMAND_JOINT_POS][:, augmenter.env.robot.joint_slices()[0][1]]
    poses = pose_to_matrix(data[K.COMMAND_EEF_POSE][:, :7]) @ augmenter.tool_offset
    return propose_regions(gripper, poses[:, :3, 3], radius=radius)
