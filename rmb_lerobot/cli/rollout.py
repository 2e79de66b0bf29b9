"""``rmb-rollout POLICY_PATH --env.type=TYPE --listen ADDR``: interactive language rollout."""

from __future__ import annotations

import argparse
import json
import logging
import signal
import sys
from collections.abc import Sequence
from dataclasses import dataclass

from tqdm import tqdm

from rmb_lerobot.cli.help import DefaultsHelpFormatter, apply_formatter

DEFAULT_LISTEN = "unix:/tmp/rmb.sock"  # RMB's interactive demo uses this socket path


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rmb-rollout",
        description="Wait for one instruction per episode on a local socket and roll out a "
        "language-conditioned LeRobot policy with it (as its task; Pick's env takes it too).",
        epilog="Env options are LeRobot's: --env.type=rmb_ur5e_pick --env.cameras=[front] "
        "--env.image_width=64 ... Protocol (newline-delimited UTF-8): send an instruction "
        "line, get {'status': 'started', ...} and, when the episode ends, {'status': "
        "'success'|'failure', 'steps': N, 'reason': ...}; send 'done' to end it early; errors "
        "come back as {'status': 'error', 'error': CODE, 'message': ...}. Ctrl-C / SIGTERM "
        "aborts a running episode, closes the socket and removes its file (exit 130 / 143).",
    )
    parser.add_argument("policy_path", help="a pretrained_model directory (lerobot-train output)")
    parser.add_argument(
        "--listen",
        default=DEFAULT_LISTEN,
        help=f"unix:PATH or tcp:HOST:PORT (PORT 0: any free port; default {DEFAULT_LISTEN})",
    )
    parser.add_argument("--episodes", type=int, default=None, help="stop after N episodes")
    parser.add_argument(
        "--max-steps", type=int, default=None, help="steps per episode (default: the env's limit)"
    )
    parser.add_argument("--seed", type=int, default=0, help="episode k resets with seed + k")
    parser.add_argument("--device", default=None, help="override the checkpoint's device")
    parser.add_argument(
        "--allow-remote",
        action="store_true",
        help="allow a non-loopback tcp address (the socket has no authentication)",
    )
    return apply_formatter(parser, DefaultsHelpFormatter)


def _parse_env(args: list[str]):
    """The ``--env.*`` options as an ``EnvConfig``, parsed by draccus as LeRobot's CLIs do."""
    import draccus
    from lerobot.envs.configs import EnvConfig
    from lerobot.utils.import_utils import register_third_party_plugins

    import lerobot_env_rmb  # noqa: F401 - our env and policy types

    register_third_party_plugins()
    wrapper = dataclass(type("EnvArgs", (), {"__annotations__": {"env": EnvConfig}}))
    return draccus.parse(config_class=wrapper, args=args).env


def main(argv: Sequence[str] | None = None) -> int:
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    parser = build_parser()
    args, rest = parser.parse_known_args(argv)
    stray = [a for a in rest if not a.startswith("--env.")]
    if stray:
        parser.error(
            f"unrecognized arguments: {' '.join(stray)} (env options are --env.NAME=VALUE)"
        )
    if not any(a.startswith("--env.type") for a in rest):
        parser.error("--env.type is required (e.g. --env.type=rmb_ur5e_pick)")
    if args.episodes is not None and args.episodes < 1:
        parser.error("--episodes must be >= 1")
    if args.max_steps is not None and args.max_steps < 1:
        parser.error("--max-steps must be >= 1")

    from rmb_lerobot.rollout import protocol as P
    from rmb_lerobot.rollout.server import RolloutServer, stop_on_signals

    try:
        address = P.Address.parse(args.listen)
    except ValueError as exc:
        parser.error(str(exc))
    if not args.allow_remote and not address.is_local():
        print(
            f"rmb-rollout: error: refusing to listen on {address}: not a loopback address and "
            "the socket has no authentication; use --allow-remote to force it",
            file=sys.stderr,
        )
        return 2

    env_cfg = _parse_env(rest)
    from rmb_lerobot.rollout.lerobot_policy import LeRobotRolloutPolicy, make_rollout_env

    try:
        policy = LeRobotRolloutPolicy.from_pretrained(args.policy_path, env_cfg, device=args.device)
    except FileNotFoundError as exc:
        print(f"rmb-rollout: error: {exc}", file=sys.stderr)
        return 2
    env, vector_env = make_rollout_env(env_cfg)
    bar = tqdm(total=args.episodes, desc="rollout", unit="episode", file=sys.stderr)

    def report(result) -> None:
        print(json.dumps({"episode_result": result.__dict__}, ensure_ascii=False), flush=True)
        bar.update()

    try:
        server = RolloutServer(
            env,
            policy,
            address,
            max_steps=args.max_steps,
            episodes=args.episodes,
            seed=args.seed,
            allow_remote=args.allow_remote,
            on_result=report,
        )
        with server, stop_on_signals(server) as received:
            print(f"rmb-rollout: listening on {server.address}", flush=True)
            server.serve()
    except (OSError, ValueError, PermissionError) as exc:
        print(f"rmb-rollout: error: {exc}", file=sys.stderr)
        return 2
    finally:
        bar.close()
        vector_env.close()
    if received:
        name = signal.Signals(received[0]).name
        print(f"rmb-rollout: stopped by {name}; socket closed", file=sys.stderr)
        return 128 + received[0]
    return 0


if __name__ == "__main__":
    sys.exit(main())
