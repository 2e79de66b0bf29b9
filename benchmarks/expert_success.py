"""Success rate of the scripted experts over worlds 0..5 with a random object shift.

Usage::

    .venv/bin/python benchmarks/expert_success.py [--episodes 100] [--random-shift 0.03]
        [--tasks insert door] [--action-mode joint]

Episode ``i`` uses ``world_idx = i % 6`` and seed ``i``; physics only (no cameras).
"""

from __future__ import annotations

import argparse
import time

from rmb_lerobot.envs.base import ACTION_MODES, RmbEnv
from rmb_lerobot.envs.catalog import EXPERTS, TASKS


def success_rate(task: str, episodes: int, random_shift: float, action_mode: str) -> dict:
    env = RmbEnv(TASKS[task](), cameras=(), action_mode=action_mode)
    expert = EXPERTS[task](env)
    successes, steps, failed = 0, 0, []
    for episode in range(episodes):
        obs, _ = env.reset(
            seed=episode, options={"world_idx": episode % 6, "random_shift": random_shift}
        )
        expert.reset()
        env_steps = 0
        for env_steps in range(1, env.task.max_episode_steps + 1):  # noqa: B007 - used below
            obs, _, terminated, _, info = env.step(expert(obs))
            if terminated:
                break
        steps += env_steps
        if info["is_success"]:
            successes += 1
        else:
            failed.append(episode)
    env.close()
    return {
        "rate": successes / episodes,
        "successes": successes,
        "mean_steps": steps / episodes,
        "failed": failed,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--random-shift", type=float, default=0.03, help="metres")
    parser.add_argument("--tasks", nargs="+", default=sorted(TASKS), choices=sorted(TASKS))
    parser.add_argument("--action-mode", default="joint", choices=ACTION_MODES)
    args = parser.parse_args()
    print("| task | episodes | success rate | mean steps | seconds | failed episodes |")
    print("|------|----------|--------------|------------|---------|-----------------|")
    for task in args.tasks:
        start = time.perf_counter()
        result = success_rate(task, args.episodes, args.random_shift, args.action_mode)
        seconds = time.perf_counter() - start
        print(
            f"| {task} | {args.episodes} | {result['rate']:.1%} | {result['mean_steps']:.0f} | "
            f"{seconds:.0f} | {result['failed'] or '-'} |"
        )


if __name__ == "__main__":
    main()
