"""Success rate of the scripted experts over every world of a task with a random object shift.

Usage::

    .venv/bin/python benchmarks/expert_success.py [--episodes 100] [--random-shift 0.03]
        [--tasks insert door] [--action-mode joint] [--cycle-instructions]

Episode ``i`` uses ``world_idx = i % num_worlds`` (six for the MuJoCo tasks) and seed ``i``;
physics only (no cameras). With ``--cycle-instructions`` (Pick) episode ``i`` gets
instruction ``(i // 6) % 18``, as ``rmb-collect --cycle-instructions`` records them, and the
success rate per instruction is printed too.
"""

from __future__ import annotations

import argparse
import time

from rmb_lerobot.envs.base import ACTION_MODES
from rmb_lerobot.envs.registry import ENVS


def success_rate(
    task: str,
    episodes: int,
    random_shift: float,
    action_mode: str,
    cycle: bool = False,
    progress: bool = False,
) -> dict:
    """Run the task's expert for ``episodes`` episodes; ``progress``: print one line per
    episode as it ends, so a run stopped early still says how its episodes went."""
    entry = ENVS[task]
    env = entry.make(cameras=(), action_mode=action_mode)
    expert = entry.load_expert_class()(env)
    variants = env.task.episode_variants() if cycle else ()
    successes, steps, failed = 0, 0, []
    per_variant: dict[str, list[bool]] = {}
    for episode in range(episodes):
        options = {"world_idx": episode % env.task.num_worlds, "random_shift": random_shift}
        if variants:  # as rmb-collect --cycle-instructions: each variant across the worlds
            options.update(variants[(episode // 6) % len(variants)])
        obs, _ = env.reset(seed=episode, options=options)
        expert.reset()
        env_steps = 0
        for env_steps in range(1, env.task.max_episode_steps + 1):  # noqa: B007 - used below
            obs, _, terminated, _, info = env.step(expert(obs))
            if terminated:
                break
        steps += env_steps
        if progress:
            print(
                f"{task} {action_mode} episode {episode} world {options['world_idx']}: "
                f"{'success' if info['is_success'] else 'failure'} in {env_steps} steps",
                flush=True,
            )
        if info["is_success"]:
            successes += 1
        else:
            failed.append(episode)
        per_variant.setdefault(env.task_description, []).append(bool(info["is_success"]))
    env.close()
    return {
        "rate": successes / episodes,
        "successes": successes,
        "mean_steps": steps / episodes,
        "failed": failed,
        "per_variant": per_variant,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--random-shift", type=float, default=0.03, help="metres")
    parser.add_argument("--tasks", nargs="+", default=sorted(ENVS), choices=sorted(ENVS))
    parser.add_argument("--action-mode", default="joint", choices=ACTION_MODES)
    parser.add_argument(
        "--cycle-instructions",
        action="store_true",
        help="pick: every instruction in turn, each across the worlds; prints per instruction",
    )
    parser.add_argument(
        "--progress", action="store_true", help="print each episode's outcome as it ends"
    )
    args = parser.parse_args()
    print("| task | episodes | success rate | mean steps | seconds | failed episodes |")
    print("|------|----------|--------------|------------|---------|-----------------|")
    for task in args.tasks:
        start = time.perf_counter()
        result = success_rate(
            task,
            args.episodes,
            args.random_shift,
            args.action_mode,
            args.cycle_instructions,
            args.progress,
        )
        seconds = time.perf_counter() - start
        print(
            f"| {task} | {args.episodes} | {result['rate']:.1%} | {result['mean_steps']:.0f} | "
            f"{seconds:.0f} | {result['failed'] or '-'} |"
        )
        if args.cycle_instructions:
            for text, outcomes in sorted(result["per_variant"].items()):
                print(f"|   {text} | {len(outcomes)} | {sum(outcomes) / len(outcomes):.1%} | | | |")


if __name__ == "__main__":
    main()
