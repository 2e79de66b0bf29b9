"""Real-time scheduling of the control loop's thread: asked for per env, given back on close,
and a clear error where the process may not have it."""

from __future__ import annotations

import os
import threading

import pytest

from rmb_lerobot.envs.real import realtime
from rmb_lerobot.envs.real.config import make_real_env
from rmb_lerobot.envs.real.options import RealOptions
from rmb_lerobot.envs.real.realtime import use_realtime_priority

pytestmark = pytest.mark.skipif(not hasattr(os, "SCHED_FIFO"), reason="Linux scheduling only")


def in_thread(fn):
    """Run ``fn`` in a fresh thread (the pytest worker's own scheduling is never touched),
    under the normal policy: a thread inherits its creator's, and these tests start from
    SCHED_OTHER whatever ran in the worker's main thread before."""
    out: dict = {}

    def target():
        try:
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))  # lowering needs no right
            out["value"] = fn()
        except BaseException as exc:  # handed back to the test
            out["error"] = exc

    thread = threading.Thread(target=target)
    thread.start()
    thread.join(60)
    if "error" in out:
        raise out["error"]
    return out["value"]


def fifo_allowed() -> bool:
    def probe():
        try:
            use_realtime_priority(1).restore()
        except PermissionError:
            return False
        return True

    return in_thread(probe)


def test_priorities_outside_1_to_99_are_refused():
    for bad in (0, 100, -5):
        with pytest.raises(ValueError, match=r"1\.\.99"):
            use_realtime_priority(bad)
        with pytest.raises(ValueError, match="realtime_priority"):
            RealOptions(realtime_priority=bad)


def test_a_process_without_the_right_says_how_to_get_it(monkeypatch):
    def refuse(*args):
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(realtime.os, "sched_setscheduler", refuse)
    with pytest.raises(PermissionError, match="ulimit -r") as info:
        use_realtime_priority(50)
    assert "CAP_SYS_NICE" in str(info.value)


def test_the_thread_runs_fifo_until_restored():
    if not fifo_allowed():
        pytest.skip("this process may not use SCHED_FIFO (no CAP_SYS_NICE / rtprio limit)")

    def run():
        before = os.sched_getscheduler(0)
        previous = use_realtime_priority(30)
        during = (os.sched_getscheduler(0), os.sched_getparam(0).sched_priority)
        previous.restore()
        return before, during, os.sched_getscheduler(0)

    before, during, after = in_thread(run)
    assert during == (os.SCHED_FIFO, 30)
    assert after == before == os.SCHED_OTHER


def test_a_real_env_steps_fifo_from_its_first_reset_and_gives_it_back_on_close():
    if not fifo_allowed():
        pytest.skip("this process may not use SCHED_FIFO (no CAP_SYS_NICE / rtprio limit)")

    def run():
        options = {"driver": "sim", "image_size": (32, 24), "settle_s": 0.0}
        env = make_real_env("RealUR5eDemo", options | {"realtime_priority": 20})
        try:
            built = os.sched_getscheduler(0)
            env.reset(seed=0)
            for _ in range(5):
                env.step(env.home_command)
            stepping = (os.sched_getscheduler(0), os.sched_getparam(0).sched_priority)
        finally:
            env.close()
        return built, stepping, os.sched_getscheduler(0)

    built, stepping, closed = in_thread(run)
    assert built == os.SCHED_OTHER  # nothing changes before the loop starts
    assert stepping == (os.SCHED_FIFO, 20)
    assert closed == os.SCHED_OTHER
