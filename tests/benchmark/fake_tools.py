"""Stand-ins for the four tools of a grid cell (``launcher: [python, THIS]``), for the cluster
and local-executor tests.

A cell's command reaches this script as its arguments (``rmb-collect ...``, ``python -m
lerobot.scripts.lerobot_train ...``); instead of running it, this writes what the real tool
would leave for the runner (episodes with a joint trajectory, a dataset's ``meta/info.json``, a
checkpoint folder, an ``eval_info.json``) after ``$FAKE_TOOL_SECONDS``. It first records which
cell started on which node and when (``$FAKE_TOOL_MARKS/<start ns>-<node>-<cell>``, the node
from ``$RMB_TEST_NODE``, set per ``ray start``), so a test knows where to kill; at its end the
mark holds the end time and gets ``.done`` appended.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

MODULES = {
    "lerobot.scripts.lerobot_train": "lerobot-train",
    "lerobot.scripts.lerobot_eval": "lerobot-eval",
}


def option(args: list[str], name: str) -> str:
    return next(a.split("=", 1)[1] for a in args if a.startswith(f"{name}="))


def main(argv: list[str]) -> int:
    if len(argv) > 2 and argv[1] == "-m":
        tool, args = MODULES[argv[2]], argv[3:]
    else:
        tool, args = Path(argv[0]).name, argv[1:]
    target = {"rmb-collect": "--out", "rmb-convert": "--output"}.get(tool, "--output_dir")
    out = Path(option(args, target))
    marks = Path(os.environ["FAKE_TOOL_MARKS"])
    name = str(out).replace("/", "_")[-120:]
    mark = marks / f"{time.time_ns()}-{os.environ.get('RMB_TEST_NODE', '?')}-{tool}-{name}"
    mark.touch()
    time.sleep(float(os.environ.get("FAKE_TOOL_SECONDS", "0")))
    unknown = [a for a in args if a.startswith("--policy.no_such=")]
    if unknown:  # as draccus refuses an option LeRobot's config does not have
        print(f"error: unrecognized arguments: {unknown[0]}", file=sys.stderr)
        return 2
    if tool == "rmb-collect":
        import h5py
        import numpy as np

        env, episodes = args[0], int(option(args, "--episodes"))
        worlds = [int(w) for w in args[args.index("--world-idx") + 1 :] if w.isdigit()]
        for index in range(episodes):
            world = worlds[index % len(worlds)]
            episode = out / f"{env}_world{world}_{index:03d}.rmb"
            episode.mkdir(parents=True)
            with h5py.File(episode / "main.rmb.hdf5", "w") as stream:  # one trajectory per world
                stream["command_joint_pos"] = np.full((10, 7), float(world))
    elif tool == "rmb-convert":
        (out / "meta").mkdir(parents=True)
        (out / "meta" / "info.json").write_text(json.dumps({"total_episodes": len(args) - 3}))
    elif tool == "lerobot-train":
        (out / "checkpoints" / "last" / "pretrained_model").mkdir(parents=True)
        print(f"step:{option(args, '--steps')} smpl:2 ep:1 epch:1.00 loss:0.125")
    else:  # lerobot-eval: world K's episodes succeed for even K
        episodes = int(option(args, "--eval.n_episodes"))
        success = int(option(args, "--env.world_idx")) % 2 == 0
        out.mkdir(parents=True)
        overall = {"pc_success": 100.0 * success, "n_episodes": episodes, "avg_sum_reward": 0.0}
        info = {"overall": overall, "per_task": [{"metrics": {"successes": [success] * episodes}}]}
        (out / "eval_info.json").write_text(json.dumps(info))
    mark.write_text(str(time.time_ns()))  # when it ended: tests check how many ran at once
    mark.rename(mark.with_name(mark.name + ".done"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
