"""A LeRobot camera rendering RGB + depth from a real arm's MuJoCo twin.

:class:`TwinCamera` stands in for a RealSense in dry runs and tests: a background thread
renders the twin (its wrist camera or a fixed front view) at the configured rate, as the
camera's own capture thread does, and the control loop takes the newest frame. The twin's
state is copied under its stepping lock (:meth:`ArmSim.copy_state`) and rendered from a
private copy, so rendering never holds up the simulated arm.
"""

from __future__ import annotations

import logging
import threading
import time
from typing import TYPE_CHECKING, Any

import numpy as np
from lerobot.cameras import Camera
from lerobot.utils.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError

from rmb_lerobot.envs.real.cameras.config_twin import TwinCameraConfig
from rmb_lerobot.envs.real.cameras.frames import CameraFrame

if TYPE_CHECKING:
    from rmb_lerobot.envs.real.twins.sim import ArmSim

log = logging.getLogger(__name__)

# The front view: a free camera looking back at the arm's base from in front of it (+x of
# the world, which the records' arms face), a little above the table.
_FRONT_LOOKAT_OFFSET = (0.45, 0.0, 0.0)  # m from the arm's mount
_FRONT_DISTANCE = 1.5  # m
_FRONT_AZIMUTH, _FRONT_ELEVATION = 180.0, -25.0  # degrees
_CONNECT_TIMEOUT_S = 10.0


class TwinCamera(Camera):
    """RGB + depth of an arm's MuJoCo twin, in LeRobot's camera interface.

    Args:
        config: View, arm, size, rate, depth.
    """

    def __init__(self, config: TwinCameraConfig):
        super().__init__(config)
        self.config = config
        self.use_depth = config.use_depth
        self._sim: ArmSim | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._new = threading.Condition()
        self._frame: CameraFrame | None = None
        self._stamp = 0.0  # time.perf_counter() of the newest frame
        self._consumed = True
        self._error: BaseException | None = None
        self.fovy: float | None = None

    def __str__(self) -> str:
        return f"TwinCamera({self.config.view}, arm {self.config.arm})"

    # ---------------------------------------------------------------- set-up
    def attach(self, sim: ArmSim) -> None:
        """Render this twin (before :meth:`connect`).

        Args:
            sim: The twin's simulation (``driver.twin.sim``).
        """
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self} is connected; attach before connecting")
        self._sim = sim

    @property
    def attached(self) -> bool:
        """Whether a twin is attached."""
        return self._sim is not None

    @property
    def is_connected(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @staticmethod
    def find_cameras() -> list[dict[str, Any]]:
        """Twin cameras are made from configs, never found: an empty list."""
        return []

    def connect(self, warmup: bool = True) -> None:
        """Start rendering; returns once the first frame is there.

        Args:
            warmup: Unused (the first frame is always waited for).

        Raises:
            DeviceAlreadyConnectedError: Already connected.
            DeviceNotConnectedError: No twin attached, or the renderer failed to start.
        """
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        if self._sim is None:
            raise DeviceNotConnectedError(
                f"{self}: no twin attached (RealRobot.connect attaches its arms' twins; "
                "a twin camera needs driver 'sim')"
            )
        self._stop.clear()
        self._frame, self._error, self._consumed = None, None, True
        self._thread = threading.Thread(target=self._run, name=f"twin-camera-{self}", daemon=True)
        self._thread.start()
        with self._new:
            self._new.wait_for(
                lambda: self._frame is not None or self._error is not None,
                timeout=_CONNECT_TIMEOUT_S,
            )
        if self._frame is None:
            self.disconnect()
            raise DeviceNotConnectedError(f"{self}: no first frame: {self._error!r}")

    def disconnect(self) -> None:
        """Stop rendering; safe to call twice."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=5.0)

    # ---------------------------------------------------------------- frames
    def read_frame(self, max_age_ms: float = 500) -> CameraFrame:
        """The newest frame (RGB, depth, fovy), without waiting for a new one.

        Args:
            max_age_ms: Refuse a frame older than this.

        Returns:
            The frame.

        Raises:
            DeviceNotConnectedError: Not connected.
            TimeoutError: The newest frame is older than ``max_age_ms``.
        """
        self._require()
        with self._new:
            frame, stamp = self._frame, self._stamp
            self._consumed = True
        assert frame is not None
        age_ms = (time.perf_counter() - stamp) * 1e3
        if age_ms > max_age_ms:
            raise TimeoutError(f"{self}: newest frame is {age_ms:.0f} ms old (max {max_age_ms})")
        return frame

    def read(self) -> np.ndarray:
        """Wait for the next frame and return its RGB image."""
        return self.async_read(timeout_ms=1000)

    def async_read(self, timeout_ms: float = 200) -> np.ndarray:
        """The newest unconsumed frame's RGB image, waiting up to ``timeout_ms`` for one.

        Raises:
            DeviceNotConnectedError: Not connected.
            TimeoutError: No new frame in time.
        """
        self._require()
        with self._new:
            if not self._new.wait_for(lambda: not self._consumed, timeout=timeout_ms / 1e3):
                raise TimeoutError(f"{self}: no new frame within {timeout_ms} ms")
            self._consumed = True
            assert self._frame is not None
            return self._frame.rgb

    def read_latest(self, max_age_ms: int = 500) -> np.ndarray:
        """The newest frame's RGB image (LeRobot's peek)."""
        return self.read_frame(max_age_ms).rgb

    def read_latest_depth(self, max_age_ms: int = 500) -> np.ndarray:
        """The newest frame's depth as a RealSense gives it: ``uint16 (H, W, 1)`` mm."""
        depth = self.read_frame(max_age_ms).depth
        if depth is None:
            raise RuntimeError(f"{self}: depth is off (use_depth=False)")
        return np.clip(np.round(depth * 1e3), 0, 65535).astype(np.uint16)[..., None]

    def _require(self) -> None:
        if not self.is_connected:
            raise DeviceNotConnectedError(f"{self} is not connected: {self._error!r}")

    # ---------------------------------------------------------------- render thread
    def _run(self) -> None:
        try:
            renderer = _TwinRenderer(self._sim, self.config)
        except BaseException as error:  # no GL: report it to connect()
            with self._new:
                self._error = error
                self._new.notify_all()
            return
        self.fovy = renderer.fovy
        period = 1.0 / float(self.config.fps)
        next_t = time.perf_counter()
        try:
            while not self._stop.is_set():
                rgb, depth = renderer.render()
                frame = CameraFrame(rgb=rgb, depth=depth, fovy=renderer.fovy)
                with self._new:
                    self._frame, self._stamp, self._consumed = frame, time.perf_counter(), False
                    self._new.notify_all()
                next_t = max(next_t + period, time.perf_counter())
                self._stop.wait(max(0.0, next_t - time.perf_counter()))
        except BaseException as error:
            log.exception("%s: rendering failed", self)
            with self._new:
                self._error = error
                self._new.notify_all()
        finally:
            renderer.close()


class _TwinRenderer:
    """Renders one view of a twin into RGB + depth (metres), from a private copy of its data.

    Made and used in one thread (one GL context).
    """

    def __init__(self, sim: Any, config: TwinCameraConfig):
        import mujoco

        from rmb_lerobot.envs.mujoco.gl import gl_context_class

        self._mujoco = mujoco
        self._sim = sim
        model = sim.model
        self.model = model
        self.width, self.height = int(config.width), int(config.height)
        offwidth, offheight = model.vis.global_.offwidth, model.vis.global_.offheight
        if self.width > offwidth or self.height > offheight:
            raise ValueError(
                f"twin camera {self.width}x{self.height} exceeds the twin's offscreen buffer "
                f"{offwidth}x{offheight}"
            )
        self.data = mujoco.MjData(model)
        _, context_class = gl_context_class()
        self._gl = context_class(offwidth, offheight)
        self._gl.make_current()
        self._context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._context)
        self._scene = mujoco.MjvScene(model, maxgeom=2000)
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
        self._scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
        self._option = mujoco.MjvOption()
        self._perturb = mujoco.MjvPerturb()
        self._camera = mujoco.MjvCamera()
        if config.view == "hand":
            name = sim.arm.hand_camera
            if name is None:
                raise ValueError(f"{sim.robot.name} has no hand camera")
            cam_id = model.camera(name).id
            self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
            self._camera.fixedcamid = cam_id
            self.fovy = float(model.cam_fovy[cam_id])
        else:
            mount = np.asarray(sim.arm.record.mount.pos, dtype=np.float64)
            self._camera.type = mujoco.mjtCamera.mjCAMERA_FREE
            self._camera.lookat[:] = mount + np.asarray(_FRONT_LOOKAT_OFFSET)
            self._camera.distance = _FRONT_DISTANCE
            self._camera.azimuth = _FRONT_AZIMUTH
            self._camera.elevation = _FRONT_ELEVATION
            self.fovy = float(model.vis.global_.fovy)
        self._depth_on = bool(config.use_depth)
        self._viewport = mujoco.MjrRect(0, 0, self.width, self.height)
        self._rgb = np.empty((self.height, self.width, 3), dtype=np.uint8)
        self._depth = np.empty((self.height, self.width), dtype=np.float32)
        extent = model.stat.extent
        self._near = float(model.vis.map.znear * extent)
        self._far = float(model.vis.map.zfar * extent)

    def render(self) -> tuple[np.ndarray, np.ndarray | None]:
        """One frame of the twin's current state: ``(rgb, depth or None)``."""
        mj = self._mujoco
        self._sim.copy_state(self.data)
        mj.mj_forward(self.model, self.data)
        self._gl.make_current()
        mj.mjv_updateScene(
            self.model,
            self.data,
            self._option,
            self._perturb,
            self._camera,
            mj.mjtCatBit.mjCAT_ALL.value,
            self._scene,
        )
        mj.mjr_render(self._viewport, self._scene, self._context)
        mj.mjr_readPixels(
            self._rgb, self._depth if self._depth_on else None, self._viewport, self._context
        )
        rgb = np.flipud(self._rgb).copy()
        if not self._depth_on:
            return rgb, None
        buffer = np.flipud(self._depth)
        depth = self._near / (1.0 - buffer * (1.0 - self._near / self._far))
        return rgb, depth.astype(np.float32)

    def close(self) -> None:
        """Free the GL resources."""
        if self._gl is None:
            return
        self._gl.make_current()
        self._context.free()
        self._gl.free()
        self._gl = None
