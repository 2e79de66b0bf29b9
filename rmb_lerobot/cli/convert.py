"""``rmb-convert``: conversions of RMB episodes.

``rmb-convert switch-format SRC DST`` rewrites an episode in the other RMB variant (the
extension of DST chooses it), like RMB's SwitchRmbDataFormat.

``rmb-convert to-lerobot SRC... (--repo-id ID | --output DIR)`` converts RMB episodes into one
LeRobotDataset v3 (optionally pushed to the Hub); ``rmb-convert from-lerobot (REPO_ID | --root
DIR) --output DIR`` converts a local LeRobotDataset back into RMB episodes.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from rmb_lerobot import keys as K
from rmb_lerobot.cli.help import DefaultsHelpFormatter, apply_formatter, first_line
from rmb_lerobot.cli.hub_errors import HubUnavailable, describe_hub_error, is_hub_error
from rmb_lerobot.cli.sigterm import interrupted_signal, sigterm_as_keyboard_interrupt
from rmb_lerobot.codecs.depth import DEPTH_CODECS
from rmb_lerobot.episode import switch_format
from rmb_lerobot.errors import RmbFormatError

_FORMATS = ("rmb", "hdf5")


def _add_switch(sub) -> None:
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


def _add_allow_non_finite(parser) -> None:
    parser.add_argument(
        "--allow-non-finite",
        action="store_true",
        help="keep NaN/inf in low-dimensional data and in depth images instead of refusing the "
        "episode (statistics then describe the finite values only; depth is stored clamped)",
    )


def _add_to_lerobot(sub) -> None:
    to = sub.add_parser(
        "to-lerobot",
        help="convert RMB episodes into a LeRobotDataset v3",
        description="Convert RMB episodes (NAME.rmb / NAME.hdf5, or directories of them) into "
        "one LeRobotDataset v3. The frame rate comes from the episodes' 'time' key and is kept "
        "exact (31.25 Hz for RMB's UR5e envs); meta/rmb.json keeps every episode attribute.",
    )
    to.add_argument("src", type=Path, nargs="+", help="episodes or directories of episodes")
    to.add_argument("--repo-id", help="dataset id, e.g. user/rmb_insert (Hub name when pushing)")
    to.add_argument(
        "--output", type=Path, help="dataset directory (default: $HF_LEROBOT_HOME/REPO_ID)"
    )
    to.add_argument(
        "--state-keys",
        nargs="+",
        default=[K.MEASURED_JOINT_POS],
        metavar="KEY",
        help=f"RMB keys concatenated into observation.state (default: {K.MEASURED_JOINT_POS})",
    )
    to.add_argument(
        "--action-keys",
        nargs="+",
        default=[K.COMMAND_JOINT_POS],
        metavar="KEY",
        help=f"RMB keys concatenated into action (default: {K.COMMAND_JOINT_POS})",
    )
    to.add_argument(
        "--camera-names", nargs="+", metavar="CAM", help="cameras to keep (default: all)"
    )
    to.add_argument(
        "--depth",
        action=argparse.BooleanOptionalAction,
        default=False,
        help="also convert depth, as LeRobot depth features (default: off, because LeRobot "
        "0.6 policies take every video feature as an RGB camera input)",
    )
    to.add_argument(
        "--allow-missing-depth",
        action="store_true",
        help="with --depth, convert a camera whose depth file is missing while other listed "
        "cameras have depth, without its depth (default: refuse the episode, naming the file)",
    )
    to.add_argument(
        "--extra-keys",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="keep every other RMB key (eef poses, velocities, wrench, fovy, ...) as its own "
        "feature (default). --no-extra-keys writes only observation.state, action and the "
        "cameras: LeRobot's loader reads every column of each sampled row, so a lean dataset "
        "trains faster (benchmarks/RESULTS.md, 'Training data path'); from-lerobot then "
        "restores only those keys",
    )
    to.add_argument(
        "--image-features",
        action="store_true",
        help="store RGB cameras as LeRobot image features (PNG in the parquet rows) instead of "
        "AV1 videos: the episodes' own frames, without AV1's loss, for ~7x the disk; not faster "
        "to train on with action chunks (LeRobot decodes the images of every row a sample "
        "touches; benchmarks/RESULTS.md, 'Training data path'). Depth stays video; not with "
        "--video-codec copy",
    )
    to.add_argument("--task", help="task text for every episode (default: its task_desc)")
    to.add_argument(
        "--fps",
        help="frame rate of the episodes, e.g. 31.25 or 125/4 (default: from 'time', which must "
        "then be regular seconds at 1..1000 Hz, without gaps; with --fps, problems with 'time' "
        "are only warnings)",
    )
    to.add_argument("--skip", type=int, default=1, help="keep every K-th step, like RMB's --skip")
    to.add_argument(
        "--video-codec",
        help="RGB codec: one of LeRobot's vcodec names (libsvtav1 = av1 (LeRobot's default), "
        "h264, hevc, libaom-av1, auto), or 'copy' to keep the episodes' H.264 packets (fastest, "
        "no generation loss; random access as fast as the source's keyframe interval); depth "
        "always uses LeRobot's depth encoder",
    )
    to.add_argument("--workers", type=int, default=1, help="parallel worker processes")
    _add_allow_non_finite(to)
    to.add_argument("--overwrite", action="store_true", help="replace an existing dataset")
    to.add_argument("--push-to-hub", action="store_true", help="upload with LeRobot's push_to_hub")
    to.add_argument("--private", action="store_true", help="create the Hub repository private")
    to.add_argument("--branch", help="Hub branch to push to")
    to.add_argument("--tags", nargs="+", default=[], help="extra dataset card tags")
    _add_verbose(to)


def _add_from_lerobot(sub) -> None:
    back = sub.add_parser(
        "from-lerobot",
        help="convert a local LeRobotDataset v3 into RMB episodes",
        description="Convert a LeRobotDataset v3 into RMB episodes. Datasets made by "
        "to-lerobot come back exactly (meta/rmb.json); for others: observation.state -> "
        "measured_joint_pos, action -> command_joint_pos, observation.images.CAM -> "
        "CAM_rgb_image, depth features observation.images.CAM_depth -> CAM_depth_image, "
        "observation.Q / action.Q -> measured_Q / command_Q, next.reward -> reward.",
    )
    back.add_argument(
        "repo_id",
        nargs="?",
        help="dataset id: read from $HF_LEROBOT_HOME/REPO_ID, or, if it is not there, "
        "downloaded from the Hub into it (never with HF_HUB_OFFLINE=1: then a missing dataset "
        "is an error)",
    )
    back.add_argument("--root", type=Path, help="dataset directory (never downloaded)")
    back.add_argument("--output", type=Path, required=True, help="directory for the episodes")
    back.add_argument(
        "--format",
        choices=_FORMATS,
        default="rmb",
        dest="fmt",
        help="episode variant: rmb (NAME.rmb, compact) or hdf5 (NAME.hdf5, single file)",
    )
    back.add_argument("--episodes", type=int, nargs="+", help="episode indices (default: all)")
    back.add_argument(
        "--state-keys",
        nargs="+",
        default=[],
        metavar="KEY[:DIM]",
        help="RMB keys observation.state splits into, in order (sizes for all but the last)",
    )
    back.add_argument(
        "--action-keys",
        nargs="+",
        default=[],
        metavar="KEY[:DIM]",
        help="RMB keys action splits into, in order (sizes for all but the last)",
    )
    back.add_argument(
        "--camera-map",
        nargs="+",
        default=[],
        metavar="FEATURE=CAM",
        help="camera name for an image feature, e.g. observation.images.laptop=front",
    )
    back.add_argument(
        "--key-map",
        nargs="+",
        default=[],
        metavar="FEATURE=KEY",
        help="RMB key for another feature, e.g. observation.effort=measured_joint_torque",
    )
    back.add_argument("--overwrite", action="store_true", help="replace an existing --output")
    _add_allow_non_finite(back)
    _add_verbose(back)


def _add_verbose(parser) -> None:
    parser.add_argument(
        "--verbose",
        action="store_true",
        help="show the video libraries' own output (FFmpeg reports, the SVT-AV1 encoder's "
        "Svt[info] lines), which is quiet otherwise",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rmb-convert",
        description=first_line(__doc__),
        formatter_class=DefaultsHelpFormatter,
        epilog="Hub errors (a download or an upload that failed) end in one line saying what "
        "failed, why and what to do (exit status 1); bad input exits 2.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    _add_switch(sub)
    _add_to_lerobot(sub)
    _add_from_lerobot(sub)
    return apply_formatter(parser, DefaultsHelpFormatter)


def _pairs(items: Sequence[str], option: str) -> dict[str, str]:
    pairs = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name or not value:
            raise ValueError(f"{option} takes NAME=VALUE, got {item!r}")
        pairs[name] = value
    return pairs


# SVT-AV1 (LeRobot's default video codec) prints its banner and settings, a dozen Svt[info]
# lines per video, straight to stderr at its own log level, which it reads from SVT_LOG whenever
# an encoder starts (1: errors only); spawned conversion workers inherit it.
SVT_LOG_ERRORS = "1"


def _quiet_libraries(verbose: bool = False) -> None:
    """FFmpeg's per-video encoder reports, SVT-AV1's Svt[info] lines and ``datasets``'
    per-episode bars drown our bars: errors only, unless ``verbose``.

    Args:
        verbose: ``--verbose``: leave the libraries' output as it is.
    """
    if verbose:
        return
    import av
    import datasets

    os.environ.setdefault("SVT_LOG", SVT_LOG_ERRORS)  # a level the user set is kept
    av.logging.set_libav_level(av.logging.ERROR)
    datasets.disable_progress_bars()


def _to_lerobot(args) -> None:
    from rmb_lerobot.converters import ConvertOptions, push_dataset, to_lerobot
    from rmb_lerobot.converters.hub import check_repo_id

    if args.push_to_hub:
        check_repo_id(args.repo_id)
    if args.workers < 1:
        raise ValueError("--workers must be >= 1")
    _quiet_libraries(args.verbose)
    options = ConvertOptions(
        state_keys=tuple(args.state_keys),
        action_keys=tuple(args.action_keys),
        camera_names=tuple(args.camera_names) if args.camera_names else None,
        depth=args.depth,
        task=args.task,
        fps=args.fps,
        skip=args.skip,
        allow_non_finite=args.allow_non_finite,
        allow_missing_depth=args.allow_missing_depth,
        extra_keys=args.extra_keys,
        image_features=args.image_features,
    )
    repo_id, root = to_lerobot(
        args.src,
        repo_id=args.repo_id,
        output=args.output,
        options=options,
        video_codec=args.video_codec,
        workers=args.workers,
        overwrite=args.overwrite,
    )
    print(f"wrote LeRobotDataset {repo_id} at {root}")
    if args.push_to_hub:
        try:
            push_dataset(repo_id, root, private=args.private, branch=args.branch, tags=args.tags)
        except Exception as exc:
            if not is_hub_error(exc):
                raise
            raise HubUnavailable(
                describe_hub_error(f"pushing {repo_id} to the Hub", exc, upload=True)
                + f" (the converted dataset is kept at {root})"
            ) from exc
        print(f"pushed to https://huggingface.co/datasets/{repo_id}")


def _from_lerobot(args) -> None:
    from rmb_lerobot.converters import MappingOverrides, from_lerobot

    _quiet_libraries(args.verbose)
    overrides = MappingOverrides(
        state_keys=tuple(args.state_keys),
        action_keys=tuple(args.action_keys),
        cameras=_pairs(args.camera_map, "--camera-map"),
        keys=_pairs(args.key_map, "--key-map"),
    )
    try:
        written = from_lerobot(
            args.repo_id,
            root=args.root,
            output=args.output,
            fmt=args.fmt,
            episodes=args.episodes,
            overrides=overrides,
            overwrite=args.overwrite,
            allow_non_finite=args.allow_non_finite,
        )
    except Exception as exc:
        if not is_hub_error(exc):
            raise
        raise HubUnavailable(
            describe_hub_error(f"downloading dataset {args.repo_id} from the Hub", exc)
        ) from exc
    print(f"wrote {len(written)} episodes to {args.output}")


def main(argv: Sequence[str] | None = None) -> int:
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    args = build_parser().parse_args(argv)
    try:
        with sigterm_as_keyboard_interrupt():
            _run(args)
    except HubUnavailable as exc:
        print(f"rmb-convert: error: {exc}", file=sys.stderr)
        return 1
    except (RmbFormatError, FileExistsError, ValueError) as exc:
        print(f"rmb-convert: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        signum = interrupted_signal(exc)
        kept = " (an existing destination is unchanged)" if getattr(args, "overwrite", 0) else ""
        print(
            f"rmb-convert: interrupted ({signum.name}); nothing was written{kept}", file=sys.stderr
        )
        return 128 + signum
    return 0


def _run(args: argparse.Namespace) -> None:
    if args.command == "switch-format":
        out = switch_format(
            args.src, args.dst, overwrite=args.overwrite, depth_codec=args.depth_codec
        )
        print(f"wrote {out}")
    elif args.command == "to-lerobot":
        _to_lerobot(args)
    else:
        _from_lerobot(args)


if __name__ == "__main__":
    sys.exit(main())
