"""The recording options ``rmb-collect`` and ``rmb-teleop`` share, spelt and explained once."""

from __future__ import annotations

import argparse


def add_recording_args(parser: argparse.ArgumentParser) -> None:
    """Add ``--cameras``, ``--image-size``, ``--no-depth`` and ``--random-shift``.

    Args:
        parser: The command's parser.
    """
    parser.add_argument(
        "--cameras",
        nargs="*",
        default=None,
        help="cameras to record, any of the env's (its scene's fixed cameras and its robot's, "
        "e.g. front left right hand for the UR5e envs; default: all of them); none: no images",
    )
    parser.add_argument(
        "--image-size",
        type=int,
        nargs=2,
        default=[640, 480],
        metavar=("W", "H"),
        help="camera image width and height",
    )
    parser.add_argument("--no-depth", action="store_true", help="record RGB only")
    parser.add_argument("--random-shift", type=float, default=0.0, help="metres, uniform")
