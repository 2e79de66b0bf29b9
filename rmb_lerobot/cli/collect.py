"""``rmb-collect ENV --episodes N --out DIR``: scripted-expert demonstrations as RMB episodes."""

from __future__ import annotations

import argparse
import logging
import multiprocessing
import os
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from tqdm import tqdm

from rmb_lerobot.cli.help import DefaultsHelpFormatter
from rmb_lerobot.cli.recording_args import add_recording_args
from rmb_lerobot.codecs.depth import DEPTH_CODECS
from rmb_lerobot.envs.registry import ENVS, entry_for
from rmb_lerobot.errors import RmbFormatError

if TYPE_CHECKING:
    from rmb_lerobot.envs.collect import CollectConfig


def build_parser() -> argparse.ArgumentParser:
    names = ", ".join(sorted(e.rmb_env_name for e in ENVS.values()))
    parser = argparse.ArgumentParser(
        prog="rmb-collect",
        formatter_class=DefaultsHelpFormatter,
        description=__doc__.splitlines()[0].split(": ", 1)[1],
        epilog=f"environments: {names} (short names like 'insert' work too). "
        "Each episode is built in a hidden temporary in --out and moved into place when "
        "complete. Ctrl-C or SIGTERM removes the episodes in progress and keeps the complete "
        "ones (exit status 130 or 143); a second one stops at once. A temporary left by a "
        "killed run is removed by the next run: its writer holds an flock on a .lock file "
        "beside it, which the kernel releases when that process ends however it ends, so a "
        "free lock means stale and a held one means a live run, whose temporaries stay.",
    )
    parser.add_argument("env", help="environment, e.g. MujocoUR5eInsert or insert")
    parser.add_argument("--episodes", type=int, required=True, help="episodes to record")
    parser.add_argument("--out", type=Path, required=True, help="output directory")
    parser.add_argument(
        "--format",
        choices=["rmb", "hdf5"],
        default="rmb",
        dest="fmt",
        help="episode variant: rmb (NAME.rmb, compact) or hdf5 (NAME.hdf5, single file)",
    )
    parser.add_argument(
        "--world-idx",
        type=int,
        nargs="+",
        default=None,
        help="worlds to cycle through (default: every world of the task)",
    )
    add_recording_args(parser)
    parser.add_argument(
        "--tactile",
        action="store_true",
        help="also record RMB's fingertip tactile grids (left_tactile_sensor, "
        "right_tactile_sensor: 5 x 8 normal forces in N; UR5e)",
    )
    parser.add_argument(
        "--tactile-size",
        type=int,
        nargs=2,
        default=None,
        metavar=("W", "H"),
        help="size of the fingertip tactile images of the PyBullet (TACTO) envs, recorded as "
        "tactile_left/right_rgb_image (default: --image-size; RMB records both at 640 480)",
    )
    parser.add_argument(
        "--success-only", action="store_true", help="keep only successful episodes (retrying)"
    )
    parser.add_argument("--workers", type=int, default=1, help="parallel worker processes")
    parser.add_argument(
        "--seed", type=int, default=0, help="episode k resets with seed + k (retries: further)"
    )
    parser.add_argument(
        "--depth-codec",
        default="rmb-videoio",
        choices=sorted(DEPTH_CODECS),
        help="depth video codec of the rmb variant (rmb-videoio: the original RMB's)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace existing episodes")
    parser.add_argument(
        "--cycle-instructions",
        action="store_true",
        help="language-conditioned tasks (pick): give episode k the next instruction in turn "
        "instead of drawing one from the seed, so N episodes cover min(N, 18) of Pick's 18 "
        "instructions, each equally often (N a multiple of 18); the worlds cycle alongside, "
        "and 18 x 6 episodes hold every instruction in every world",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    args = build_parser().parse_args(argv)
    from rmb_lerobot.envs.collect import CollectConfig, WorkerDied, collect
    from rmb_lerobot.envs.interrupts import Interrupted, interrupts_raise

    with interrupts_raise(on_repeat=lambda signum: _stop_at_once(signum, args.out)):
        run = None
        try:
            entry = entry_for(args.env)
            cameras = entry.cameras if args.cameras is None else tuple(args.cameras)
            unknown = [c for c in cameras if c not in entry.cameras]
            if unknown:
                raise ValueError(
                    f"--cameras {' '.join(unknown)}: not a camera of {entry.rmb_env_name}; "
                    f"its cameras are {' '.join(entry.cameras)}"
                )
            if args.tactile and entry.simulator != "mujoco":
                raise ValueError(
                    f"--tactile records MuJoCo's fingertip grids; {entry.rmb_env_name} records "
                    f"its tactile images as cameras ({' '.join(entry.robot_record.tactile_sensors)}"
                    ", in --cameras, recorded by default)"
                )
            if args.tactile_size is not None and not entry.robot_record.tactile_sensors:
                raise ValueError(f"--tactile-size: {entry.rmb_env_name} has no tactile images")
            if args.episodes < 1 or args.workers < 1:
                raise ValueError("--episodes and --workers must be >= 1")
            worlds = entry.num_worlds
            if args.world_idx is not None and any(not 0 <= w < worlds for w in args.world_idx):
                raise ValueError(
                    f"--world-idx values must be in 0..{worlds - 1} ({entry.rmb_env_name} has "
                    f"{worlds} worlds), got {args.world_idx}"
                )
            config = CollectConfig(
                env=args.env,
                out=args.out,
                episodes=args.episodes,
                fmt=args.fmt,
                world_idx=None if args.world_idx is None else tuple(args.world_idx),
                cameras=cameras,
                image_size=(args.image_size[0], args.image_size[1]),
                depth=not args.no_depth,
                random_shift=args.random_shift,
                success_only=args.success_only,
                seed=args.seed,
                depth_codec=args.depth_codec,
                overwrite=args.overwrite,
                cycle_variants=args.cycle_instructions,
                tactile=args.tactile,
                tactile_size=None if args.tactile_size is None else tuple(args.tactile_size),
            )
            kept = successes = 0
            run = collect(config, workers=args.workers)
            with tqdm(total=args.episodes, desc=f"collect {args.env}", unit="episode") as bar:
                for result in run:
                    kept += result.path is not None
                    successes += result.success
                    bar.set_postfix(success=f"{successes}/{bar.n + 1}")
                    bar.update()
        except (ValueError, RmbFormatError) as exc:
            print(f"rmb-collect: error: {exc}", file=sys.stderr)
            return 2
        except WorkerDied as exc:
            complete = _complete_episodes(config)
            print(
                f"rmb-collect: error: {exc} ({complete} of {args.episodes} complete; partial "
                f"ones removed)",
                file=sys.stderr,
            )
            return 1
        except (Interrupted, KeyboardInterrupt) as exc:
            signum = exc.signum if isinstance(exc, Interrupted) else signal.SIGINT
            if run is not None:
                run.close()  # the signal may have hit the loop body: stop the workers now
            complete = _complete_episodes(config) if run is not None else 0
            partial = run.partials_removed if run is not None else 0
            print(
                f"rmb-collect: interrupted by {signal.Signals(signum).name}; kept {complete} "
                f"complete episode{'s' * (complete != 1)} in {args.out}, removed {partial} "
                f"partial one{'s' * (partial != 1)}",
                file=sys.stderr,
            )
            return 128 + signum
    print(f"kept {kept} episodes ({successes} successful of {args.episodes}) in {args.out}")
    return 0 if kept == args.episodes else 1


def _complete_episodes(config: CollectConfig) -> int:
    """This run's episodes in place (the writer only ever puts complete ones there)."""
    return sum(
        config.episode_path(i, config.world_idx[i % len(config.world_idx)]).exists()
        for i in range(config.episodes)
    )


def _stop_at_once(signum: int, out: Path) -> None:
    """A second Ctrl-C/SIGTERM: kill the workers and exit without waiting for any clean-up."""
    for child in multiprocessing.active_children():
        child.kill()  # their locks die with them: the next run removes their temporaries
    print(
        f"rmb-collect: interrupted again; stopped at once. Partial episodes may remain as hidden "
        f"temporaries in {out}; the next rmb-collect run there removes them",
        file=sys.stderr,
        flush=True,
    )
    os._exit(128 + signum)


if __name__ == "__main__":
    sys.exit(main())
