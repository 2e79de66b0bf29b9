"""rmb-data: inspect, compare, refine, extend and view RMB episodes; tile rollout videos.

One command for RMB's data utilities (robo_manip_baselines/misc); see ``OVERVIEW``.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from collections.abc import Sequence
from pathlib import Path

from rmb_lerobot.cli.help import (
    DefaultsHelpFormatter,
    RawDescriptionDefaultsHelpFormatter,
    apply_formatter,
    first_line,
)
from rmb_lerobot.cli.sigterm import interrupted_signal, sigterm_as_keyboard_interrupt
from rmb_lerobot.errors import RmbFormatError

OVERVIEW = """\
rmb-data info PATH...                     keys, shapes, dtypes, ranges, attributes (PrintRmbData)
rmb-data compare A B                      differences against tolerances (CompareRmbData)
rmb-data refine PATH... --task-desc TEXT  set the task description (RefineRmbData)
rmb-data add-pointcloud PATH... --camera NAME   clouds from depth (AddPointCloudToRmbData)
rmb-data view EPISODE                     the episode in the rerun viewer (VisualizeData)
rmb-data tile-videos DIR --out FILE       lerobot-eval's rollout videos tiled (TileRolloutVideos)
rmb-data verify PATH...                   read every byte, report corruption (exit code 1 if any)

Exit codes: 0 done; 1 compare found differences beyond the tolerances, info met unreadable
episodes, or verify found a problem; 2 bad input (the message names the file and key); 128 +
signal when interrupted (files being written are discarded, existing ones stay as they were).
"""


def _add_info(sub) -> None:
    p = sub.add_parser("info", help="describe episodes: keys, shapes, dtypes, ranges, attributes")
    p.add_argument("paths", type=Path, nargs="+", metavar="PATH", help="episodes or directories")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.add_argument(
        "--summary-only", action="store_true", help="only the statistics over all episodes"
    )
    p.add_argument(
        "--image-stats",
        action="store_true",
        help="also min/max of images (decodes every frame: slow)",
    )


def _add_compare(sub) -> None:
    p = sub.add_parser(
        "compare",
        help="compare two episodes key by key; exit code 1 when beyond tolerances",
        description="Compare two episodes: low-dimensional keys by maximum absolute difference, "
        "RGB images by the PSNR of the worst frame, depth by the maximum difference in mm. "
        "Keys in one episode only, different lengths, shapes or attributes (but 'format') count "
        "as differences. Exit code 0 within tolerances, 1 beyond them.",
    )
    p.add_argument("a", type=Path, help="first episode (.rmb or .hdf5)")
    p.add_argument("b", type=Path, help="second episode")
    p.add_argument(
        "--atol", type=float, default=1e-6, help="max abs difference of other keys (default 1e-6)"
    )
    p.add_argument(
        "--min-psnr", type=float, default=30.0, help="min PSNR (dB) of RGB frames (default 30)"
    )
    p.add_argument(
        "--depth-mm", type=float, default=1.0, help="max depth difference in mm (default 1)"
    )
    p.add_argument(
        "--ignore-attr",
        action="append",
        default=[],
        metavar="NAME",
        help="attribute not to compare (repeatable; 'format' and 'video_sha256' always)",
    )
    p.add_argument("--failures-only", action="store_true", help="list only keys beyond tolerances")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def _add_refine(sub) -> None:
    p = sub.add_parser(
        "refine",
        help="set the task description (task_desc attribute) of episodes",
        description="Set the task_desc attribute of every episode given (or found in the "
        "directories given). An existing different non-empty value is refused unless "
        "--overwrite; every episode is checked before any is changed, and each file is "
        "replaced atomically.",
    )
    p.add_argument("paths", type=Path, nargs="+", metavar="PATH", help="episodes or directories")
    p.add_argument("--task-desc", required=True, help="the task description to set")
    p.add_argument("--overwrite", action="store_true", help="replace an existing task description")


def _add_pointcloud(sub) -> None:
    from rmb_lerobot.data.add_pointcloud import PointCloudOptions

    d = PointCloudOptions()
    p = sub.add_parser(
        "add-pointcloud",
        help="add <camera>_pointcloud keys computed from RGB + depth",
        description="Add point clouds (xyz + rgb, float32 (T, N, 6)) computed from each camera's "
        "depth and fovy, rotated by --rpy-angle, cropped to the box and farthest-point sampled, "
        "as RMB's AddPointCloudToRmbData (raw clouds <camera>_pointcloud_raw are used if present).",
    )
    p.add_argument("paths", type=Path, nargs="+", metavar="PATH", help="episodes or directories")
    p.add_argument(
        "--camera", action="append", required=True, metavar="NAME", help="camera (repeatable)"
    )
    p.add_argument(
        "--image-size",
        type=int,
        nargs=2,
        default=d.image_size,
        metavar=("W", "H"),
        help="resize images first (default 84 84)",
    )
    p.add_argument(
        "--min-bound",
        type=float,
        nargs=3,
        default=d.min_bound,
        metavar=("X", "Y", "Z"),
        help="crop box min, metres (default -0.4 -0.4 -0.4)",
    )
    p.add_argument(
        "--max-bound",
        type=float,
        nargs=3,
        default=d.max_bound,
        metavar=("X", "Y", "Z"),
        help="crop box max, metres (default 1 1 1)",
    )
    p.add_argument(
        "--rpy-angle",
        type=float,
        nargs=3,
        default=d.rpy_angle,
        metavar=("R", "P", "Y"),
        help="rotation of the points before cropping, degrees",
    )
    p.add_argument(
        "--num-points", type=int, default=d.num_points, help="points per cloud (default 512)"
    )
    p.add_argument("--overwrite", action="store_true", help="replace existing point clouds")


def _add_view(sub) -> None:
    p = sub.add_parser(
        "view",
        help="show an episode in rerun (needs the viz extra)",
        description="Log an episode to rerun: camera RGB and depth (as images and, through the "
        "camera's fovy, a 3D point cloud), stored point clouds, every low-dimensional key as "
        "plots over time, tactile sensor grids. Opens the viewer when a display exists; "
        "otherwise, or with --save, writes an .rrd file (open it with `rerun FILE.rrd`).",
    )
    p.add_argument("episode", type=Path, help="episode (.rmb or .hdf5)")
    p.add_argument(
        "--save",
        type=Path,
        metavar="FILE.rrd",
        help="write a recording instead of opening a viewer (replaced if it exists)",
    )
    p.add_argument("--stride", type=int, default=1, help="log every K-th step (RMB's --skip)")
    p.add_argument(
        "--image-size",
        type=int,
        nargs=2,
        metavar=("W", "H"),
        help="resize images (smaller recordings)",
    )


def _add_tile(sub) -> None:
    p = sub.add_parser(
        "tile-videos",
        help="tile lerobot-eval's rollout videos into one, success framed green, failure red",
        description="Find lerobot-eval's videos (videos/<env>_<task>/eval_episode_K.mp4) under "
        "VIDEO_DIR, read each rollout's success from eval_info.json (beside or above VIDEO_DIR), "
        "and write one video with the rollouts in a grid, framed green (success), red (failure) "
        "or white (unknown).",
    )
    p.add_argument(
        "video_dir",
        type=Path,
        metavar="VIDEO_DIR",
        help="lerobot-eval's output dir or its videos dir",
    )
    p.add_argument("--out", type=Path, required=True, help="the tiled video (.mp4)")
    p.add_argument(
        "--eval-info",
        type=Path,
        help="lerobot-eval's eval_info.json (default: found beside VIDEO_DIR)",
    )
    p.add_argument(
        "--successes",
        type=int,
        nargs="+",
        choices=(0, 1),
        metavar="0|1",
        help="outcome per video in order, instead of eval_info.json",
    )
    p.add_argument("--columns", type=int, help="tiles per row (default: a square grid)")
    p.add_argument(
        "--border", type=int, help="frame width in pixels (default: 1/16 of the tile, at least 4)"
    )
    p.add_argument(
        "--no-labels", action="store_true", help="do not write episode and outcome on the tiles"
    )
    p.add_argument("--overwrite", action="store_true", help="replace --out if it exists")


def _add_verify(sub) -> None:
    p = sub.add_parser(
        "verify",
        help="read every byte of episodes and LeRobot datasets; exit code 1 on any finding",
        description="Check RMB episodes (.rmb, .hdf5) and converted LeRobot v3 datasets in full: "
        "every HDF5 dataset read (checksums of files we wrote), every video frame decoded, "
        "recorded video SHA-256 digests compared, step and frame counts against 'time', NaN/inf "
        "in float keys, every listed camera with RGB (and depth where any camera has depth); "
        "for datasets: parquet files, episode index and timestamps, statistics. Prints a table "
        "and every finding; exit code 1 if anything was found.",
    )
    p.add_argument(
        "paths",
        type=Path,
        nargs="+",
        metavar="PATH",
        help="episodes, LeRobot dataset roots, or directories holding them",
    )
    p.add_argument(
        "--allow-non-finite", action="store_true", help="do not report NaN/inf values in the data"
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rmb-data",
        description=first_line(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=OVERVIEW,
    )
    sub = parser.add_subparsers(dest="command", required=True)
    _add_info(sub)
    _add_compare(sub)
    _add_refine(sub)
    _add_pointcloud(sub)
    _add_view(sub)
    _add_tile(sub)
    _add_verify(sub)
    apply_formatter(parser, DefaultsHelpFormatter)
    parser.formatter_class = RawDescriptionDefaultsHelpFormatter  # its epilog is laid out
    return parser


def _info(args) -> int:
    from rmb_lerobot.data.info import collect_info, format_info, format_summary, summary

    infos, errors = collect_info(args.paths, image_stats=args.image_stats)
    if not infos and not errors:
        raise RmbFormatError(
            "no episodes (*.rmb, *.hdf5) found", path=", ".join(map(str, args.paths))
        )
    stats = summary(infos, len(errors))
    for path, message in errors:
        print(f"rmb-data: error: cannot read {path}: {message}", file=sys.stderr)
    if args.json:
        out = {"summary": stats, "errors": [{"path": str(p), "error": m} for p, m in errors]}
        if not args.summary_only:
            out["episodes"] = infos
        print(json.dumps(out, indent=2))
    else:
        if not args.summary_only:
            for info in infos:
                print(format_info(info))
        print(format_summary(stats))
    return 1 if errors else 0


def _compare(args) -> int:
    from rmb_lerobot.data.compare import (
        IGNORED_ATTRS,
        Tolerances,
        compare_episodes,
        format_comparison,
    )

    tolerances = Tolerances(atol=args.atol, min_psnr=args.min_psnr, depth_mm=args.depth_mm)
    ignore = tuple(dict.fromkeys([*IGNORED_ATTRS, *args.ignore_attr]))
    result = compare_episodes(args.a, args.b, tolerances, ignore_attrs=ignore)
    if args.json:
        print(json.dumps(result.to_json(), indent=2))
    else:
        print(format_comparison(result, only_failures=args.failures_only))
    return 0 if result.ok else 1


def _refine(args) -> int:
    from rmb_lerobot.data.refine import refine_task_desc

    for r in refine_task_desc(args.paths, args.task_desc, overwrite=args.overwrite):
        state = f"task_desc {r.old!r} -> {r.new!r}" if r.changed else "unchanged (already set)"
        print(f"{r.path}: {state}")
    return 0


def _add_pointclouds(args) -> int:
    from rmb_lerobot.data.add_pointcloud import PointCloudOptions, add_pointclouds

    options = PointCloudOptions(
        image_size=tuple(args.image_size),
        min_bound=tuple(args.min_bound),
        max_bound=tuple(args.max_bound),
        rpy_angle=tuple(args.rpy_angle),
        num_points=args.num_points,
    )
    cameras = list(dict.fromkeys(args.camera))
    for path in add_pointclouds(args.paths, cameras, options, overwrite=args.overwrite):
        print(f"{path}: added {', '.join(c + '_pointcloud' for c in cameras)}")
    return 0


def _view(args) -> int:
    from rmb_lerobot.data.view import has_display, view_episode

    size = tuple(args.image_size) if args.image_size else None
    saved = view_episode(args.episode, save=args.save, stride=args.stride, image_size=size)
    if saved is not None:
        why = "" if args.save or has_display() else " (no display found)"
        print(f"wrote {saved}{why}; open it with: rerun {saved}")
    return 0


def _tile(args) -> int:
    from rmb_lerobot.data.tile_videos import find_rollouts, tile_videos

    successes = None if args.successes is None else [bool(s) for s in args.successes]
    rollouts = find_rollouts(args.video_dir, eval_info=args.eval_info, successes=successes)
    unknown = sum(r.success is None for r in rollouts)
    out = tile_videos(
        rollouts,
        args.out,
        columns=args.columns,
        border=args.border,
        labels=not args.no_labels,
        overwrite=args.overwrite,
    )
    wins = sum(bool(r.success) for r in rollouts)
    note = f", {unknown} with unknown outcome (no eval_info.json entry)" if unknown else ""
    print(f"wrote {out}: {len(rollouts)} rollouts, {wins} successful{note}")
    return 0


def _verify(args) -> int:
    from rmb_lerobot.data.verify import format_table, verify_paths

    reports = verify_paths(
        args.paths, allow_non_finite=args.allow_non_finite, progress=not args.no_progress
    )
    if args.json:
        print(json.dumps([r.to_json() for r in reports], indent=2))
    else:
        print(format_table(reports))
    return 0 if all(r.ok for r in reports) else 1


_COMMANDS = {
    "info": _info,
    "compare": _compare,
    "refine": _refine,
    "add-pointcloud": _add_pointclouds,
    "view": _view,
    "tile-videos": _tile,
    "verify": _verify,
}


def main(argv: Sequence[str] | None = None) -> int:
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    args = build_parser().parse_args(argv)
    try:
        with sigterm_as_keyboard_interrupt():
            return _COMMANDS[args.command](args)
    except (RmbFormatError, FileExistsError, ValueError, ImportError) as exc:
        print(f"rmb-data {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        signum = interrupted_signal(exc)
        print(
            f"rmb-data {args.command}: interrupted ({signum.name}); "
            "files being written were discarded, existing ones are unchanged",
            file=sys.stderr,
        )
        return 128 + signum


if __name__ == "__main__":
    sys.exit(main())
