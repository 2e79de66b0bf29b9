"""rmb-rollout's own cost: a served episode vs the bare env/policy loop, in the same run.

A trivial 7-d env and a policy that returns its observation, so only the server's work (one
non-blocking socket poll per step) is measured; also the time from sending an instruction to
receiving ``started`` (which includes ``env.reset``).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/rollout_overhead.py
"""

from __future__ import annotations

import statistics
import tempfile
import threading
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

from rmb_lerobot.rollout import RolloutClient, RolloutServer

STEPS = 20_000
LATENCY_SAMPLES = 50


class EchoEnv(gym.Env):
    """Observation = last action: the cheapest env the server can drive."""

    def __init__(self):
        self.observation_space = gym.spaces.Dict(
            {"agent_pos": gym.spaces.Box(-1, 1, (7,), np.float32)}
        )
        self.action_space = gym.spaces.Box(-1, 1, (7,), np.float32)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return {"agent_pos": np.zeros(7, np.float32)}, {}

    def step(self, action):
        return {"agent_pos": np.asarray(action, np.float32)}, 0.0, False, False, {}


class EchoPolicy:
    def reset(self) -> None:
        pass

    def act(self, observation, instruction):
        return observation["agent_pos"]


def bare_loop_seconds_per_step(env: gym.Env, policy: EchoPolicy) -> float:
    start = time.perf_counter()
    observation, _ = env.reset()
    for _ in range(STEPS):
        observation, *_ = env.step(policy.act(observation, "go"))
    return (time.perf_counter() - start) / STEPS


def main() -> None:
    env, policy = gym.wrappers.TimeLimit(EchoEnv(), STEPS), EchoPolicy()
    bare = bare_loop_seconds_per_step(env, policy)
    address = f"unix:{Path(tempfile.mkdtemp()) / 'bench.sock'}"
    server = RolloutServer(env, policy, address, episodes=1 + LATENCY_SAMPLES)
    latencies: list[float] = []
    served: dict = {}

    def client() -> None:
        with RolloutClient(address, timeout=60) as connection:
            start = time.perf_counter()
            connection.instruct("go")
            result = connection.result()
            served["per_step"] = (time.perf_counter() - start) / result["steps"]
            for _ in range(LATENCY_SAMPLES):
                start = time.perf_counter()
                connection.instruct("go")
                latencies.append(time.perf_counter() - start)
                connection.done()

    with server:
        thread = threading.Thread(target=client)
        thread.start()
        server.serve()
        thread.join()
    per_step = served["per_step"]
    print(f"bare loop          {bare * 1e6:8.1f} us/step (baseline)")
    print(
        f"served by rmb-rollout {per_step * 1e6:5.1f} us/step "
        f"({per_step / bare:.2f}x, +{(per_step - bare) * 1e6:.1f} us/step)"
    )
    print(
        f"instruction -> started: median {statistics.median(latencies) * 1e3:.2f} ms, "
        f"max {max(latencies) * 1e3:.2f} ms over {LATENCY_SAMPLES}"
    )


if __name__ == "__main__":
    main()
