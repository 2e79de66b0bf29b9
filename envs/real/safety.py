"""The one safety layer every real-arm command passes.

:class:`SafetyLayer` wraps one :class:`~rmb_lerobot.envs.real.driver.ArmDriver` and is the only
caller of its ``command_joints`` and ``command_gripper``. It has one command path,
:meth:`SafetyLayer.step` (RMB's ``step``) and :meth:`SafetyLayer.move_to` (RMB's reset) being
its two ways of choosing the duration, and no flag that skips a check. Per command, in order:

1. the layer is open and the watchdog has not tripped (:class:`WatchdogTripped`);
2. the command is a finite vector of the arm's joints, a finite gripper value, a finite scale
   and a duration in ``(0, max_duration]`` (:class:`NonFiniteCommand`, :class:`InvalidCommand`);
3. a fresh reading of the arm, finite and with an advancing timestamp (:class:`InvalidState`,
   :class:`StaleReading`);
4. RMB's ``overwrite_command_for_safety``, against that **measured** position ``q_m``:
   a step with ``max |q - q_m| > 90°`` and ``duration < 0.1 s`` is refused
   (:class:`JumpTooLarge`); otherwise the target is clamped to the joint bounds, then each joint
   to ``q_m ± clip(scale, 0.01, 10) · v_lim · duration``. A reset instead takes
   ``duration = clip(max |q - q_m| / (clip(scale, 0.01, 10) · v_lim), 0.1, 10)`` s;
5. the gripper is clamped to its command range;
6. with a workspace box, the TCP along the joint-space path to the target must stay in the box
   (or, where the arm is already outside, get no further out) (:class:`OutsideWorkspace`);
7. the watchdog is checked again, then the target and the gripper are sent.

Why the measured position and not the last sent command: it bounds the gap between where the
arm is and where it is told to be, which is what the controller turns into velocity and torque.
Chaining from the last command lets the gap grow when the arm lags or is blocked (a collision,
a protective stop), and the arm then leaps when released. It is also RMB's choice.

Joint bounds are applied before the velocity clamp, so a sent target never moves a joint faster
than the clamp allows; a joint the arm already holds outside its bounds is moved back towards
them (no faster than the clamp), never further out.

Any refusal, any driver error and any interruption (``KeyboardInterrupt``) inside a command or
a read calls ``driver.stop()`` before the exception propagates; a refusal sends nothing.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from rmb_lerobot.envs.real.driver import ArmDriver, ArmState
from rmb_lerobot.envs.real.errors import (
    InvalidCommand,
    InvalidState,
    JumpTooLarge,
    LayerClosed,
    NonFiniteCommand,
    OutsideWorkspace,
    SafetyError,
    StaleReading,
    WatchdogTripped,
)
from rmb_lerobot.envs.real.limits import CONTROL_PERIOD, SafetyLimits
from rmb_lerobot.envs.real.watchdog import Watchdog

__all__ = [
    "Clip",
    "InvalidCommand",
    "InvalidState",
    "JumpTooLarge",
    "LayerClosed",
    "NonFiniteCommand",
    "OutsideWorkspace",
    "SafetyError",
    "SafetyLayer",
    "SentCommand",
    "StaleReading",
    "WatchdogTripped",
]

# Joint-space spacing of the TCP samples the workspace check takes along a move (rad), and
# the most samples per move (a 10 s step at scale 10 could otherwise ask for thousands).
_PATH_STEP = float(np.deg2rad(2.0))
_MAX_PATH_SAMPLES = 500


@dataclass(frozen=True)
class Clip:
    """One value a limit changed.

    Attributes:
        rule: ``"position"`` (joint bounds), ``"velocity"`` (per-step clamp) or ``"gripper"``.
        name: The joint's name, or ``"gripper"``.
        requested: The value asked for.
        sent: The value sent.
    """

    rule: str
    name: str
    requested: float
    sent: float


@dataclass(frozen=True)
class SentCommand:
    """What the layer actually sent (LeRobot's ``send_action`` returns this, not the request).

    Attributes:
        joint_pos: Arm joint targets sent (rad).
        gripper: Gripper value sent, or ``None`` where the command left the gripper alone.
        duration: Duration given to the arm (s).
        measured: The reading the command was judged against.
        clipped: Each value a limit changed, in joint order, the gripper last.
    """

    joint_pos: np.ndarray
    gripper: float | None
    duration: float
    measured: ArmState
    clipped: tuple[Clip, ...] = ()

    @property
    def clipped_rules(self) -> frozenset[str]:
        """The rules that changed something (empty: sent as asked)."""
        return frozenset(c.rule for c in self.clipped)


class SafetyLayer:
    """The checks between a command stream and one arm.

    Args:
        driver: The arm (an SDK driver or its twin).
        limits: Its limits (:func:`rmb_lerobot.envs.real.limits.limits_for`).
        clock: Monotonic clock (s) for the watchdog and the stale-state rule.
        watchdog_thread: Run the watchdog's background thread (tests with an injected clock
            pass ``False`` and rely on the check each command makes).
    """

    def __init__(
        self,
        driver: ArmDriver,
        limits: SafetyLimits,
        *,
        clock: Callable[[], float] = time.monotonic,
        watchdog_thread: bool = True,
    ):
        self.driver = driver
        self.limits = limits
        self._clock = clock
        self._lock = threading.RLock()
        self._closed = False
        self._last_state: ArmState | None = None
        self._last_timestamp: float | None = None  # the newest controller timestamp seen
        self._last_advance = 0.0  # layer clock when the timestamp last advanced
        self._repeats = 0  # consecutive readings whose timestamp did not advance
        self.watchdog = Watchdog(
            limits.watchdog_timeout,
            self._on_watchdog_trip,
            clock=clock,
            thread=watchdog_thread,
            lock=self._lock,
        )

    # -- lifecycle ------------------------------------------------------------------------

    def connect(self) -> ArmState:
        """Connect the driver and take the first reading.

        Returns:
            The first checked reading.
        """
        with self._lock:
            self._ensure_open()
            self.driver.connect()
            return self.read()

    def close(self) -> None:
        """Stop the watchdog thread, then stop and disconnect the arm; safe to call twice."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        self.watchdog.close()
        self.driver.close()

    def __enter__(self) -> SafetyLayer:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def stop(self) -> None:
        """Stop the arm now and disarm the watchdog (a planned stop)."""
        self.watchdog.disarm()
        with self._lock:
            self.driver.stop()

    def zero_wrench(self) -> None:
        """Zero the force/torque sensor (RMB: after each reset, with the arm at rest)."""
        with self._lock:
            self._ensure_open()
            self.driver.zero_wrench()

    # -- watchdog -------------------------------------------------------------------------

    def arm_watchdog(self) -> None:
        """Start watching the command stream: from now on a command is due within
        ``limits.watchdog_timeout`` s after the previous command's duration."""
        self._ensure_open()
        self.watchdog.arm()

    def disarm_watchdog(self) -> None:
        """Stop watching (a planned pause in the command stream)."""
        self.watchdog.disarm()

    def resume(self) -> None:
        """Clear a watchdog trip and arm it again; commands go through after this."""
        self._ensure_open()
        self.watchdog.resume()

    @contextmanager
    def streaming(self) -> Iterator[SafetyLayer]:
        """Arm the watchdog for a block of streamed commands (an episode), disarm after.

        Yields:
            This layer.
        """
        self.arm_watchdog()
        try:
            yield self
        finally:
            self.disarm_watchdog()

    def _on_watchdog_trip(self) -> None:
        # No lock here: the watchdog takes the command lock itself, and trips without it only
        # when its holder is stuck in a driver call (``stop`` is safe to call at any time).
        self.driver.stop()

    # -- state ----------------------------------------------------------------------------

    def read(self) -> ArmState:
        """A checked reading of the arm.

        Returns:
            The driver's reading, finite, of the arm's shape, with an advancing timestamp.

        Raises:
            InvalidState: A value is not finite, or a shape is wrong (the arm is stopped).
            StaleReading: The timestamp went backwards, or has not advanced for
                ``limits.stale_timeout`` s or ``limits.max_stale_reads`` reads (arm stopped).
        """
        with self._lock:
            self._ensure_open()
            with self._stopping_on_error():
                return self._read_checked()

    @property
    def last_state(self) -> ArmState | None:
        """The last reading that passed the checks."""
        return self._last_state

    def _read_checked(self) -> ArmState:
        state = self.driver.read()
        # The timestamp first: a reading refused for a NaN still shows where the controller's
        # clock is, so it counts towards (and cannot hide) a stale stream.
        self._check_timestamp(state.timestamp)
        self._check_finite_state(state)
        self._last_state = state
        return state

    def _check_timestamp(self, timestamp: float) -> None:
        robot = self.limits.robot
        if not math.isfinite(timestamp):
            raise InvalidState(f"{robot}: state timestamp {timestamp} is not finite")
        now, last = self._clock(), self._last_timestamp
        if last is None or timestamp > last:
            self._last_timestamp, self._last_advance, self._repeats = timestamp, now, 0
            return
        if timestamp < last:
            raise StaleReading(
                f"{robot}: state timestamp went backwards from {last:.6f} s to {timestamp:.6f} s"
            )
        self._repeats += 1
        age = now - self._last_advance
        if self._repeats >= self.limits.max_stale_reads:
            raise StaleReading(
                f"{robot}: state timestamp {timestamp:.6f} s has not advanced for "
                f"{self._repeats} reads (limit {self.limits.max_stale_reads})"
            )
        if age > self.limits.stale_timeout:
            raise StaleReading(
                f"{robot}: state timestamp {timestamp:.6f} s has not advanced for {age:.3f} s "
                f"(limit {self.limits.stale_timeout} s)"
            )

    def _check_finite_state(self, state: ArmState) -> None:
        robot, n = self.limits.robot, self.limits.num_joints
        fields = {"joint_pos": state.joint_pos, "joint_vel": state.joint_vel}
        for field, value in fields.items():
            array = np.asarray(value, dtype=np.float64)
            if array.shape != (n,):
                raise InvalidState(
                    f"{robot}: state {field} has shape {array.shape}, expected ({n},)"
                )
            for name, v in zip(self.limits.joints, array, strict=True):
                if not math.isfinite(v):
                    raise InvalidState(f"{robot}: state {field} of joint {name} is {v}")
        if not math.isfinite(state.gripper):
            raise InvalidState(f"{robot}: state gripper is {state.gripper}")
        if state.wrench is not None:
            wrench = np.asarray(state.wrench, dtype=np.float64)
            if wrench.shape != (6,) or not np.all(np.isfinite(wrench)):
                raise InvalidState(f"{robot}: state wrench {wrench} is not 6 finite values")

    # -- commands -------------------------------------------------------------------------

    def step(
        self,
        joint_pos: np.ndarray,
        gripper: float,
        duration: float = CONTROL_PERIOD,
        scale: float | None = None,
    ) -> SentCommand:
        """One control step (RMB's ``step``): clamp, check and send a joint target.

        Args:
            joint_pos: Arm joint targets (rad).
            gripper: Gripper command (driver units).
            duration: Time the arm is given to get there (s): the control period (0.02 s).
            scale: ``v_lim`` scale of the per-step clamp; ``None``: ``limits.step_scale``
                (RMB's 2.0).

        Returns:
            What was sent.

        Raises:
            WatchdogTripped: The watchdog tripped; call :meth:`resume`.
            NonFiniteCommand: A value of the command is NaN or infinite.
            InvalidCommand: Wrong shape, or duration not in ``(0, limits.max_duration]``.
            JumpTooLarge: ``max |Δq| > limits.jump_threshold`` with ``duration <
                limits.jump_min_duration``.
            OutsideWorkspace: The TCP would leave the workspace box.
            InvalidState: The reading has non-finite values.
            StaleReading: The reading is stale.
            LayerClosed: The layer is closed.
        """
        if duration is None:
            raise InvalidCommand(f"{self.limits.robot}: a step needs a duration")
        return self._command(
            joint_pos, gripper, duration, self.limits.step_scale if scale is None else scale
        )

    def move_to(
        self,
        joint_pos: np.ndarray,
        gripper: float | None = None,
        scale: float | None = None,
    ) -> SentCommand:
        """A reset move (RMB's reset): the duration follows from the distance.

        ``duration = clip(max |Δq| / (clip(scale, 0.01, 10) · v_lim), 0.1, 10)`` s. The call
        returns when the command is sent; the caller waits ``duration`` for the arm.

        Args:
            joint_pos: Arm joint targets (rad).
            gripper: Gripper command, or ``None`` to leave the gripper alone.
            scale: ``v_lim`` scale; ``None``: ``limits.reset_scale`` (RMB: UR5e 0.3,
                xArm7 0.1).

        Returns:
            What was sent, with the duration chosen.

        Raises:
            WatchdogTripped: The watchdog tripped; call :meth:`resume`.
            NonFiniteCommand: A value of the command is NaN or infinite.
            InvalidCommand: Wrong shape.
            JumpTooLarge: Even the longest duration would need more than ``v_lim`` (and more
                than the scaled limit): only when the arm is far outside its bounds.
            OutsideWorkspace: The TCP would leave the workspace box on the way.
            InvalidState: The reading has non-finite values.
            StaleReading: The reading is stale.
            LayerClosed: The layer is closed.
        """
        return self._command(
            joint_pos, gripper, None, self.limits.reset_scale if scale is None else scale
        )

    def _command(
        self,
        joint_pos: np.ndarray,
        gripper: float | None,
        duration: float | None,
        scale: float,
    ) -> SentCommand:
        with self._lock:
            self._ensure_open()
            self._check_watchdog()
            with self._stopping_on_error():
                sent = self._judge(joint_pos, gripper, duration, scale)
                self._check_watchdog()
                self.driver.command_joints(sent.joint_pos.copy(), sent.duration)
                if sent.gripper is not None:
                    self.driver.command_gripper(sent.gripper)
            self.watchdog.feed(sent.duration)
            return sent

    def _judge(
        self,
        joint_pos: np.ndarray,
        gripper: float | None,
        duration: float | None,
        scale: float,
    ) -> SentCommand:
        lim = self.limits
        q = self._joint_vector(joint_pos)
        if gripper is not None:
            gripper = self._finite_scalar("gripper", gripper)
        scale = self._finite_scalar("scale", scale)
        if duration is not None:
            duration = self._finite_scalar("duration", duration)
            if not 0.0 < duration <= lim.max_duration:
                raise InvalidCommand(
                    f"{lim.robot}: duration {duration} s is not in (0, {lim.max_duration}] s"
                )
        state = self._read_checked()
        q_m = np.asarray(state.joint_pos, dtype=np.float64)
        v = lim.scaled_v_lim(scale)
        clips: list[Clip] = []

        if duration is not None:
            self._check_jump(q, q_m, duration)
        target = np.clip(q, lim.low_array, lim.high_array)
        clips += self._clips("position", q, target)
        if duration is None:
            distance = float(np.max(np.abs(target - q_m)))
            duration = float(np.clip(distance / v, *lim.reset_duration_range))
            # Only where the 10 s cap forces a move faster than both the asked and the
            # nominal limit (an arm far outside its bounds): RMB would send it anyway.
            if distance > max(v, lim.v_lim) * duration:
                j = int(np.argmax(np.abs(target - q_m)))
                raise JumpTooLarge(
                    f"{lim.robot} joint {lim.joints[j]}: reset move of "
                    f"{np.rad2deg(distance):.1f}° in {duration} s exceeds v_lim "
                    f"{np.rad2deg(lim.v_lim):.0f}°/s"
                )
        else:
            reach = v * duration
            clamped = q_m + np.clip(target - q_m, -reach, reach)
            clips += self._clips("velocity", target, clamped)
            target = clamped

        if gripper is not None:
            sent_gripper = float(np.clip(gripper, *lim.gripper))
            if sent_gripper != gripper:
                clips.append(Clip("gripper", "gripper", gripper, sent_gripper))
            gripper = sent_gripper

        self._check_workspace(q_m, target)
        return SentCommand(target, gripper, float(duration), state, tuple(clips))

    def _check_jump(self, q: np.ndarray, q_m: np.ndarray, duration: float) -> None:
        lim = self.limits
        delta = np.abs(q - q_m)
        j = int(np.argmax(delta))
        if delta[j] > lim.jump_threshold and duration < lim.jump_min_duration:
            raise JumpTooLarge(
                f"{lim.robot} joint {lim.joints[j]}: command {q[j]:.4f} rad is "
                f"{np.rad2deg(delta[j]):.1f}° from the measured {q_m[j]:.4f} rad, more than "
                f"{np.rad2deg(lim.jump_threshold):.0f}° in {duration} s < "
                f"{lim.jump_min_duration} s"
            )

    def _check_workspace(self, q_m: np.ndarray, target: np.ndarray) -> None:
        box = self.limits.workspace
        if box is None:
            return
        start = box.distance(box.tcp(q_m))
        if not math.isfinite(start):
            raise OutsideWorkspace(f"{self.limits.robot}: TCP of the measured state not finite")
        span = float(np.max(np.abs(target - q_m)))
        samples = min(max(1, math.ceil(span / _PATH_STEP)), _MAX_PATH_SAMPLES)
        for k in range(1, samples + 1):
            q = q_m + (target - q_m) * (k / samples)
            tcp = box.tcp(q)
            out = box.distance(tcp)
            if not out <= max(start, 0.0):  # also catches a NaN from the FK
                where = "target" if k == samples else f"path {k}/{samples} to the target"
                raise OutsideWorkspace(
                    f"{self.limits.robot}: TCP {np.round(tcp, 4).tolist()} m at the {where} "
                    f"is {out:.4f} m outside the workspace box {box.low}..{box.high}"
                    + (f" (the arm is {start:.4f} m outside)" if start > 0 else "")
                )

    def _clips(self, rule: str, requested: np.ndarray, sent: np.ndarray) -> list[Clip]:
        return [
            Clip(rule, name, float(r), float(s))
            for name, r, s in zip(self.limits.joints, requested, sent, strict=True)
            if r != s
        ]

    def _joint_vector(self, joint_pos: np.ndarray) -> np.ndarray:
        lim = self.limits
        try:
            q = np.asarray(joint_pos, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InvalidCommand(f"{lim.robot}: joint command {joint_pos!r}: {exc}") from exc
        if q.shape != (lim.num_joints,):
            raise InvalidCommand(
                f"{lim.robot}: joint command has shape {q.shape}, expected "
                f"({lim.num_joints},) for {lim.joints}"
            )
        for name, value in zip(lim.joints, q, strict=True):
            if not math.isfinite(value):
                raise NonFiniteCommand(f"{lim.robot} joint {name}: command {value} not finite")
        return q

    def _finite_scalar(self, name: str, value: float) -> float:
        try:
            number = float(value)
        except (TypeError, ValueError) as exc:
            raise InvalidCommand(f"{self.limits.robot}: {name} {value!r}: {exc}") from exc
        if not math.isfinite(number):
            raise NonFiniteCommand(f"{self.limits.robot}: {name} {number} is not finite")
        return number

    # -- plumbing -------------------------------------------------------------------------

    def _ensure_open(self) -> None:
        if self._closed:
            raise LayerClosed(f"{self.limits.robot}: the safety layer is closed")

    def _check_watchdog(self) -> None:
        if self.watchdog.poll():
            raise WatchdogTripped(
                f"{self.limits.robot}: no command for {self.limits.watchdog_timeout} s after "
                "the last one's duration: the arm was stopped; call resume() to go on"
            )

    @contextmanager
    def _stopping_on_error(self) -> Iterator[None]:
        """Stop the arm when anything but a watchdog refusal leaves the block."""
        try:
            yield
        except WatchdogTripped:
            raise
        except BaseException as exc:
            try:
                self.driver.stop()
            except Exception as stop_exc:
                exc.add_note(f"stopping the arm after this failed too: {stop_exc!r}")
            raise
