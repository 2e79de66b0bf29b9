"""Per-episode fingerprints of every env's expert rollouts: proof that a refactor kept behaviour.

Run it on the same machine before and after a change and compare::

    .venv/bin/python benchmarks/behaviour_hashes.py --out before.jsonl
    # ... refactor ...
    .venv/bin/python benchmarks/behaviour_hashes.py --compare before.jsonl

Each episode (expert in ``joint`` and ``eef_rel`` modes, worlds ``i % num_worlds``, seed
``i``, random shift 0.03 m) is hashed over every action, every observation (joint state and a
32x32 front image, so the scene's composition and lighting count) and every value
``rmb_step_data`` gives a recorder, plus the episode attributes. The hashes are bit-exact, so
they only mean something on one machine: MuJoCo's last bits differ between CPUs (never compare
across machines, and never put these numbers in a test).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np

from rmb_lerobot.envs.registry import ENVS

MODES = ("joint", "eef_rel")


def _update(digest, value) -> None:
    if isinstance(value, dict):
        for key in sorted(value):
            digest.update(str(key).encode())
            _update(digest, value[key])
    elif isinstance(value, list | tuple):
        for item in value:
            _update(digest, item)
    elif isinstance(value, np.ndarray | np.generic | float | int | bool):
        array = np.ascontiguousarray(value)
        digest.update(str(array.dtype).encode() + str(array.shape).encode() + array.tobytes())
    else:
        digest.update(repr(value).encode())


def episode_fingerprint(task: str, mode: str, episode: int) -> dict:
    env = gym.make(ENVS[task].gym_id, cameras=("front",), image_size=(32, 32), action_mode=mode)
    try:
        core = env.unwrapped
        expert = ENVS[task].load_expert_class()(core)
        digest = hashlib.sha256()
        options = {"world_idx": episode % core.task.num_worlds, "random_shift": 0.03}
        obs, info = env.reset(seed=episode, options=options)
        expert.reset()
        _update(digest, core.rmb_attrs())
        steps, success = 0, False
        for steps in range(1, core.task.max_episode_steps + 1):  # noqa: B007 - reported below
            action = expert(obs)
            record = {k: v for k, v in core.rmb_step_data(action).items() if "image" not in k}
            _update(digest, [obs, action, record])
            obs, _, terminated, truncated, info = env.step(action)
            success = bool(info["is_success"])
            if terminated or truncated:
                break
        _update(digest, obs)
        return {
            "env": ENVS[task].rmb_env_name,
            "mode": mode,
            "episode": episode,
            "steps": steps,
            "success": success,
            "sha256": digest.hexdigest(),
        }
    finally:
        env.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=3, help="per env and action mode")
    parser.add_argument("--tasks", nargs="*", default=sorted(ENVS))
    parser.add_argument("--out", type=Path, help="write the fingerprints here (JSON lines)")
    parser.add_argument("--compare", type=Path, help="fingerprints of an earlier run to check")
    args = parser.parse_args()
    rows = []
    for task in args.tasks:
        for mode in MODES:
            for episode in range(args.episodes):
                row = episode_fingerprint(task, mode, episode)
                rows.append(row)
                print(json.dumps(row), flush=True)
    if args.out:
        args.out.write_text("".join(json.dumps(row) + "\n" for row in rows))
    if args.compare:
        earlier = {
            (r["env"], r["mode"], r["episode"]): r
            for r in map(json.loads, args.compare.read_text().splitlines())
        }
        changed = [r for r in rows if earlier.get((r["env"], r["mode"], r["episode"])) != r]
        print(f"{len(rows) - len(changed)} of {len(rows)} episodes identical to {args.compare}")
        for row in changed:
            print(f"  changed: {row['env']} {row['mode']} episode {row['episode']}")
        return 1 if changed else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
