"""``rmb-rollout-client "Put the banana in the blue basket."``: talk to ``rmb-rollout``.

Prints every reply line (JSON) to stdout. Exit status: 0 success (or, with ``--no-wait``,
started), 1 failure or aborted, 2 refused (an error reply, bad arguments), 3 no server or no
reply within ``--timeout``.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from rmb_lerobot.cli.help import DefaultsHelpFormatter, apply_formatter
from rmb_lerobot.cli.rollout import DEFAULT_LISTEN
from rmb_lerobot.rollout import protocol as P
from rmb_lerobot.rollout.client import RolloutClient, RolloutError

EXIT_SUCCESS, EXIT_FAILURE, EXIT_REFUSED, EXIT_UNREACHABLE = 0, 1, 2, 3


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rmb-rollout-client",
        description="Send an instruction (or 'done') to a running rmb-rollout and print its "
        "replies; by default wait for the episode's result.",
        epilog="Exit status: 0 success, 1 failure/aborted, 2 refused, 3 unreachable/timeout.",
    )
    parser.add_argument("instruction", nargs="?", help="e.g. 'Put the banana in the blue basket.'")
    parser.add_argument("--connect", default=DEFAULT_LISTEN, help=f"default {DEFAULT_LISTEN}")
    parser.add_argument(
        "--done", action="store_true", help="end the running episode now and print its result"
    )
    parser.add_argument(
        "--no-wait", action="store_true", help="return once the episode has started"
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=None,
        help="seconds to wait for the server and for each reply (default: no limit)",
    )
    return apply_formatter(parser, DefaultsHelpFormatter)


def _print(reply: dict) -> None:
    print(json.dumps(reply, ensure_ascii=False), flush=True)


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if (args.instruction is None) == (not args.done):
        parser.error("give an instruction or --done (one of the two)")
    if args.instruction is not None and (
        P.is_done(args.instruction) or not args.instruction.strip()
    ):
        parser.error(f"not an instruction: {args.instruction!r} (use --done to end an episode)")
    if args.no_wait and args.done:
        parser.error("--no-wait goes with an instruction")
    try:
        address = P.Address.parse(args.connect)
    except ValueError as exc:
        parser.error(str(exc))
    try:
        with RolloutClient(address, timeout=args.timeout) as client:
            if args.done:
                result = client.done()
            else:
                _print(client.instruct(args.instruction))
                if args.no_wait:
                    return EXIT_SUCCESS
                result = client.result()
    except RolloutError as exc:
        _print(exc.reply)
        return EXIT_REFUSED
    except (TimeoutError, OSError) as exc:
        print(f"rmb-rollout-client: {address}: {exc}", file=sys.stderr)
        return EXIT_UNREACHABLE
    _print(result)
    return EXIT_SUCCESS if result["status"] == P.SUCCESS else EXIT_FAILURE


if __name__ == "__main__":
    sys.exit(main())
