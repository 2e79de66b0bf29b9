"""``rmb-teleop ENV --input-device DEVICE``: record demonstrations by hand (RMB's ``Teleop.py``).

Phases: standby -> (sync) -> teleop (recording) -> save (s) / discard (f) -> next
episode; Esc quits. Keys come from the terminal (cbreak mode: no display needed, works over
SSH) or, without one, from the desktop through pynput. ``--num-envs N`` drives N sim envs in
different worlds with the same joint command (one episode each per demonstration);
``--live-view`` shows the session in rerun (a window, or an ``.rrd`` file headless).
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from rmb_lerobot import keys as K
from rmb_lerobot.cli.help import DefaultsHelpFormatter
from rmb_lerobot.cli.recording_args import add_recording_args
from rmb_lerobot.envs.registry import ENVS, REAL_ENVS, entry_for
from rmb_lerobot.envs.teleop.devices import INPUT_DEVICES, make_device
from rmb_lerobot.envs.teleop.keys import KEY_SOURCES, make_key_source
from rmb_lerobot.errors import RmbFormatError

if TYPE_CHECKING:
    from rmb_lerobot.envs.base import RmbEnv
    from rmb_lerobot.envs.registry import EnvEntry

KEY_HELP = """\
phase keys: n next phase (initial -> standby -> [sync ->] teleop -> end), s save, f discard,
  h stop a replay, Esc quit
keyboard device (world frame, per press): W/S +-x, A/D +-y, Q/E +-z by 1 cm; J/L roll,
  I/K pitch by 0.05 rad; U/O yaw by 0.1 rad; Z/X gripper towards closed/open;
  Tab or 1..9 selects the arm of a bimanual robot"""


def build_parser() -> argparse.ArgumentParser:
    names = ", ".join(sorted(e.rmb_env_name for e in (*ENVS.values(), *REAL_ENVS.values())))
    parser = argparse.ArgumentParser(
        prog="rmb-teleop",
        formatter_class=DefaultsHelpFormatter,
        description=__doc__.splitlines()[0].split(": ", 1)[1].replace("``", ""),
        epilog=f"environments: {names} (short names like 'cable' work too). Each episode is "
        "built in a hidden temporary in --out and moved into place only when saved: a "
        "discarded episode, Esc or Ctrl-C leaves nothing. " + KEY_HELP.replace("\n", " "),
    )
    parser.add_argument("env", help="environment, e.g. MujocoUR5eCable or cable")
    parser.add_argument(
        "--input-device", choices=INPUT_DEVICES, default="keyboard", help="what drives the robot"
    )
    parser.add_argument(
        "--input-device-config", type=Path, default=None, help="the device's YAML (gello)"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output directory (default: dataset/<demo>_<YYYYmmdd_HHMMSS>, as RMB's)",
    )
    parser.add_argument(
        "--format",
        choices=["rmb", "hdf5"],
        default="rmb",
        dest="fmt",
        help="episode file format: RMB's compact .rmb or single-file .hdf5",
    )
    parser.add_argument("--demo-name", default=None, help="file name prefix (default: the env's)")
    parser.add_argument(
        "--world-idx", type=int, nargs="+", default=None, help="worlds the episodes cycle through"
    )
    parser.add_argument("--task-desc", default=None, help="task description written to episodes")
    parser.add_argument(
        "--save-success-only", action="store_true", help="s keeps successful episodes only"
    )
    parser.add_argument(
        "--sync-before-record",
        action="store_true",
        help="let the device drive the robot unrecorded first (n starts recording)",
    )
    parser.add_argument("--max-episodes", type=int, default=None, help="quit after N saved")
    parser.add_argument("--replay-log", type=Path, default=None, help="episode to replay")
    parser.add_argument(
        "--replay-key", default=K.COMMAND_JOINT_POS, help="key of the log to re-command"
    )
    parser.add_argument("--replay-repeat-count", type=int, default=1, help="replays to run")
    parser.add_argument(
        "--auto-replay", action="store_true", help="replay without waiting for n (headless)"
    )
    parser.add_argument("--save-replay", action="store_true", help="record each replay")
    parser.add_argument("--seed", type=int, default=0, help="reset k uses seed + k")
    add_recording_args(parser)
    parser.add_argument(
        "--no-antialias",
        action="store_true",
        help="MuJoCo: render without 4x multisampling (about 2x faster in software rendering)",
    )
    parser.add_argument(
        "--keys",
        choices=KEY_SOURCES,
        default="auto",
        help="key source: the terminal, pynput (a desktop), none (--auto-replay only); auto: "
        "the terminal if standard input is one, else pynput",
    )
    parser.add_argument(
        "--no-realtime", action="store_true", help="do not pace the loop to the control period"
    )
    parser.add_argument(
        "--real-config", type=Path, default=None, help="a real env's YAML (RMB's keys + driver)"
    )
    parser.add_argument(
        "--num-envs",
        type=int,
        default=1,
        help="sim envs driven at once, in different worlds (env 0's IK, the same joint "
        "command to all); each demonstration records one episode per env",
    )
    parser.add_argument(
        "--live-view",
        nargs="?",
        const="",
        default=None,
        metavar="PATH.rrd",
        help="show images, eef targets and the phase in rerun (viz extra): a viewer window "
        "when a display exists, else OUT/live_view.rrd; with PATH always that file",
    )
    parser.add_argument(
        "--live-view-image-every", type=int, default=1, help="log images every N steps"
    )
    return parser


def _make_env(entry: EnvEntry, args: argparse.Namespace) -> RmbEnv:
    cameras = entry.cameras if args.cameras is None else tuple(args.cameras)
    kwargs = {"cameras": cameras, "depth": not args.no_depth}
    if entry.simulator == "real":
        from rmb_lerobot.envs.real.config import make_real_env

        return make_real_env(entry.name, args.real_config, **kwargs)
    unknown = [c for c in cameras if c not in entry.cameras]
    if unknown:
        raise ValueError(
            f"--cameras {' '.join(unknown)}: not a camera of {entry.rmb_env_name}; its cameras "
            f"are {' '.join(entry.cameras)}"
        )
    size = (args.image_size[0], args.image_size[1])
    if args.no_antialias:
        kwargs["antialias"] = False
    return entry.make(image_size=size, random_shift=args.random_shift, **kwargs)


def _check(args: argparse.Namespace, entry: EnvEntry) -> None:
    if entry.simulator == "real" and args.real_config is None:
        raise ValueError(
            f"{entry.rmb_env_name} is a real env: pass --real-config YAML (robot_ip, "
            "camera_ids, driver: sim for the twins)"
        )
    if args.world_idx is not None and entry.simulator != "real":
        worlds = entry.num_worlds
        if any(not 0 <= w < worlds for w in args.world_idx):
            raise ValueError(
                f"--world-idx values must be in 0..{worlds - 1} ({entry.rmb_env_name} has "
                f"{worlds} worlds), got {args.world_idx}"
            )
    if args.input_device != "replay" and (args.auto_replay or args.save_replay):
        raise ValueError("--auto-replay and --save-replay go with --input-device replay")
    if args.keys == "none" and not (args.input_device == "replay" and args.auto_replay):
        raise ValueError("--keys none works only with --input-device replay --auto-replay")
    if args.max_episodes is not None and args.max_episodes < 1:
        raise ValueError(f"--max-episodes must be >= 1, got {args.max_episodes}")
    if args.replay_repeat_count < 1:
        raise ValueError(f"--replay-repeat-count must be >= 1, got {args.replay_repeat_count}")
    if args.no_antialias and entry.simulator != "mujoco":
        raise ValueError(f"--no-antialias is a MuJoCo option; {entry.rmb_env_name} is not MuJoCo")
    if args.num_envs < 1:
        raise ValueError(f"--num-envs must be >= 1, got {args.num_envs}")
    if args.num_envs > 1 and entry.simulator == "real":
        raise ValueError(f"--num-envs {args.num_envs}: {entry.rmb_env_name} is a real env (one)")


def main(argv: Sequence[str] | None = None) -> int:
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    args = build_parser().parse_args(argv)
    from rmb_lerobot.envs.interrupts import Interrupted, interrupts_raise
    from rmb_lerobot.envs.teleop.session import TeleopConfig, TeleopSession

    env = device = keys = session = view = None
    parallel: list[RmbEnv] = []
    with interrupts_raise():
        try:
            entry = entry_for(args.env)
            _check(args, entry)
            replay = args.input_device == "replay"
            keys_kind = "none" if replay and args.auto_replay and args.keys == "auto" else args.keys
            out = args.out or Path("dataset") / (
                f"{args.demo_name or entry.rmb_env_name}_{time.strftime('%Y%m%d_%H%M%S')}"
            )
            device = make_device(
                args.input_device,
                entry.robot_record,
                config=args.input_device_config,
                replay_log=args.replay_log,
                replay_key=args.replay_key,
            )
            keys = make_key_source(keys_kind)  # before the slow part: no terminal fails fast
            device.connect()
            if replay and getattr(device, "env_attr", entry.env_attr) != entry.env_attr:
                print(
                    f"rmb-teleop: warning: the log was recorded in {device.env_attr}, "
                    f"replaying in {entry.env_attr}",
                    file=sys.stderr,
                )
            env = _make_env(entry, args)
            parallel = [_make_env(entry, args) for _ in range(args.num_envs - 1)]
            view = _make_view(args, out)
            config = TeleopConfig(
                out=out,
                fmt=args.fmt,
                demo_name=args.demo_name,
                world_idx=None if args.world_idx is None else tuple(args.world_idx),
                task_desc=args.task_desc,
                save_success_only=args.save_success_only,
                sync_before_record=args.sync_before_record,
                seed=args.seed,
                realtime=not args.no_realtime,
                max_episodes=args.max_episodes,
                replay=replay,
                auto_replay=args.auto_replay,
                save_replay=args.save_replay,
                replay_repeat=args.replay_repeat_count,
            )
            if not replay:
                print(KEY_HELP, file=sys.stderr)
            session = TeleopSession(
                env, device, keys, config, log=_say, parallel_envs=parallel, view=view
            )
            result = session.run()
        except (ValueError, RmbFormatError, ImportError, OSError) as exc:
            print(f"rmb-teleop: error: {exc}", file=sys.stderr)
            return 2
        except (Interrupted, KeyboardInterrupt) as exc:
            signum = exc.signum if isinstance(exc, Interrupted) else signal.SIGINT
            saved = len(session.result.saved) if session is not None else 0
            print(
                f"rmb-teleop: interrupted by {signal.Signals(signum).name}; kept {saved} saved "
                "episode(s), the one in progress was discarded",
                file=sys.stderr,
            )
            return 128 + signum
        finally:
            for thing in (keys, device, env, *parallel):
                if thing is not None:
                    thing.close()
            if view is not None and (rrd := view.close()) is not None:
                print(f"live view: {rrd} (open it with: rerun {rrd})", file=sys.stderr)
    print(f"saved {len(result.saved)} episode(s) in {config.out} ({result.discarded} discarded)")
    return 0


def _make_view(args: argparse.Namespace, out: Path):
    """The live view ``--live-view`` asks for (None without the flag)."""
    if args.live_view is None:
        return None
    from rmb_lerobot.envs.teleop.live_view import LiveView

    every = args.live_view_image_every
    if args.live_view:
        return LiveView(Path(args.live_view), image_every=every)
    return LiveView.for_display(out / "live_view.rrd", image_every=every)


def _say(message: str) -> None:
    print(f"[rmb-teleop] {message}", file=sys.stderr, flush=True)


if __name__ == "__main__":
    sys.exit(main())
