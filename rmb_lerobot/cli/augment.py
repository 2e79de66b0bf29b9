"""``rmb-augment ENV BASE_EPISODE --regions REGIONS.yaml --samples-per-region N --out DIR``:
SART data augmentation around one demonstration (RoboManipAug)."""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from pathlib import Path

from tqdm import tqdm

from rmb_lerobot.cli.help import DefaultsHelpFormatter, apply_formatter
from rmb_lerobot.errors import RmbFormatError

REGIONS_FILE = "regions.yaml"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rmb-augment",
        description="SART data augmentation around one demonstration (RoboManipAug): for each "
        "acceptable region (a sphere around the demo's tool pose at one step), restore the "
        "demo's world and robot at that step in the simulator, drive the tool to N random "
        "poses on the sphere's surface while recording, play each recording backwards and "
        "append the rest of the demo. Every result is a complete RMB episode, written "
        "atomically.",
        epilog="Regions YAML: 'regions:' list of {time_idx: STEP, radius: METRES, "
        "[convergence_idx: STEP], [max_rotation_deg: DEG]}. --propose-regions places them at "
        "the gripper's close/open events (or, without any, at the start of the final approach) "
        f"and writes them to DIR/{REGIONS_FILE} for review. Simulated envs only: a real robot "
        "would need its safety layer on every augmentation command (none exist yet).",
    )
    parser.add_argument("env", help="environment of the demo, e.g. MujocoUR5eInsert or insert")
    parser.add_argument("base_episode", type=Path, help="the demonstration (NAME.rmb / NAME.hdf5)")
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--regions", type=Path, help="acceptable regions (YAML)")
    source.add_argument(
        "--propose-regions",
        action="store_true",
        help=f"propose regions from the demo (written to DIR/{REGIONS_FILE})",
    )
    parser.add_argument(
        "--samples-per-region",
        type=int,
        required=True,
        metavar="N",
        help="augmented episodes per acceptable region",
    )
    parser.add_argument(
        "--out", type=Path, required=True, metavar="DIR", help="directory for the new episodes"
    )
    parser.add_argument("--seed", type=int, default=0, help="env reset seed and sampling seed")
    parser.add_argument(
        "--random-shift",
        type=float,
        default=0.0,
        metavar="METRES",
        help="the demo's rmb-collect --random-shift: its objects are placed again from --seed, "
        "which must then be the seed the demo was reset with (rmb-collect: --seed + episode "
        "index, for an episode kept at its first attempt); without it a shifted demo is "
        "augmented in its world's unshifted scene",
    )
    parser.add_argument(
        "--radius", type=float, default=0.02, help="metres, for proposed regions (default 0.02)"
    )
    parser.add_argument(
        "--duration",
        type=float,
        default=2.0,
        help="seconds to drive out to each sample (RoboManipAug: 2.0)",
    )
    parser.add_argument(
        "--rotation-scale",
        type=float,
        default=2.0,
        help="max random rotation in rad per metre of radius, for regions that set no "
        "max_rotation_deg (RoboManipAug: 2.0)",
    )
    parser.add_argument(
        "--format",
        choices=["rmb", "hdf5"],
        default=None,
        dest="fmt",
        help="episode variant of the results (default: the base episode's)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace existing episodes")
    return apply_formatter(parser, DefaultsHelpFormatter)


def main(argv: Sequence[str] | None = None) -> int:
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    args = build_parser().parse_args(argv)
    from rmb_lerobot.augment import (
        AugmentConfig,
        Augmenter,
        dump_regions,
        load_regions,
        propose_demo_regions,
    )

    written = 0
    try:
        if args.samples_per_region < 1:
            raise ValueError(f"--samples-per-region must be >= 1, got {args.samples_per_region}")
        config = AugmentConfig(
            samples_per_region=args.samples_per_region,
            duration_s=args.duration,
            rotation_scale=args.rotation_scale,
            seed=args.seed,
            random_shift=args.random_shift,
            fmt=args.fmt,
            overwrite=args.overwrite,
        )
        with Augmenter(args.env, args.base_episode, args.out, config) as augmenter:
            if args.propose_regions:
                regions = propose_demo_regions(augmenter, radius=args.radius)
                args.out.mkdir(parents=True, exist_ok=True)
                dump_regions(regions, args.out / REGIONS_FILE)
                print(f"proposed {len(regions)} region(s) -> {args.out / REGIONS_FILE}")
            else:
                regions = load_regions(args.regions, augmenter.length)
            total = len(regions) * args.samples_per_region
            with tqdm(total=total, desc="augment", unit="sample") as bar:
                for result in augmenter.run(regions):
                    written += 1
                    bar.set_postfix(
                        region=result.region, off_target_mm=f"{result.target_error_m * 1e3:.1f}"
                    )
                    bar.update()
    except (ValueError, RmbFormatError) as exc:
        print(f"rmb-augment: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(
            f"rmb-augment: interrupted; kept {written} complete episode(s) in {args.out}, the one "
            "in progress was discarded",
            file=sys.stderr,
        )
        return 130
    print(f"wrote {written} augmented episodes to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
