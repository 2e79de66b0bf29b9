"""``rmb-convert``: conversions of RMB episodes.

``rmb-convert switch-format SRC DST`` rewrites an episode in the other RMB variant (the
extension of DST chooses it), like RMB's SwitchRmbDataFormat.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from pathlib import Path

from rmb_lerobot.codecs.depth import DEPTH_CODECS
from rmb_lerobot.episode import switch_format
from rmb_lerobot.errors import RmbFormatError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rmb-convert", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    switch = sub.add_parser(
        "switch-format",
        help="convert an episode between NAME.rmb (compact) and NAME.hdf5 (single file)",
    )
    switch.add_argument("src", type=Path, help="episode to read (.rmb directory or .hdf5 file)")
    switch.add_argument("dst", type=Path, help="episode to write; its extension picks the variant")
    switch.add_argument("--overwrite", action="store_true", help="replace DST if it exists")
    switch.add_argument(
        "--depth-codec",
        default="rmb-videoio",
        choices=sorted(DEPTH_CODECS),
        help="depth video codec for the compact variant (default: the original RMB's)",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    args = build_parser().parse_args(argv)
    try:
        if args.command == "switch-format":
            out = switch_format(
                args.src, args.dst, overwrite=args.overwrite, depth_codec=args.depth_codec
            )
            print(f"wrote {out}")
    except RmbFormatError as exc:
        print(f"rmb-convert: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
