"""Where DP3's 512 points go: camera-frame crop (old default) vs world-frame crop (new default).

DP3 back-projects one depth camera, crops the points to a box and farthest-point samples a fixed
number of them. Cropped in the camera frame (the default before the camera pose was recorded),
the box can only cut by depth, so most samples land on the table and the robot's stand; cropped
in the world frame with the recorded ``<camera>_depth_image_pose``, the box starts above the
table top and the samples go to the task objects and the arm. This benchmark counts it.

An RMB UR5e MuJoCo task (``--task``) is driven by its scripted expert for ``--episodes``
episodes (seed ``i``, world ``i % 6``); at the given steps the front camera's depth frame
(``--image-size`` square) becomes a cloud through the policy's own builder,
``DepthPointClouds`` of ``policies_extra/dp3``, once per crop frame, with the boxes of
``DEFAULT_CROP`` and ``--num-points`` samples. Every pixel carries, in place of its colour, the
root body its geom belongs to in MuJoCo's segmentation render and its pixel index, so the
sampled cloud says which body each sample lies on (the point positions are exactly the
policy's; colours do not change which points are kept or sampled). Pixels kept by the crop are
counted the same way, with a builder sampling every pixel.

Labels: ``table``; ``robot arm`` = every body under the UR5e's root bodies; ``task objects`` =
the task's own bodies (listed in a second table); ``stand`` = the robot's stand box (top below
the table top); ``floor`` = geoms of the world body; ``none`` = pixels without a geom.
The segmentation render and the env's depth can disagree at silhouettes by a pixel, so a few
pixels on an object's edge carry the label of what lies behind it: the few "table", "stand"
and "floor" points left in the world crop (all below its floor, 0.83 m) are such edges (e.g.
3-10 cm above the table top in Pick), not those surfaces.

Usage (~1-2 min on a loaded 2-core machine)::

    OMP_NUM_THREADS=1 MUJOCO_GL=egl .venv/bin/python benchmarks/point_cloud_crop.py --task insert
    ... benchmarks/point_cloud_crop.py --task pick --episodes 3 --frames 0 60 120

Prints markdown tables (means over all frames) for benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
from collections import Counter

import gymnasium as gym
import mujoco
import numpy as np
from tqdm import tqdm

from rmb_lerobot import keys as K
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.policies_extra.dp3.configuration_dp3 import DEFAULT_CROP, DP3Config
from rmb_lerobot.policies_extra.dp3.point_cloud import DepthPointClouds

CAMERA = "front"
FRAMES = {"camera": "camera frame (old default)", "world": "world frame (new default with a pose)"}
ROBOT_ROOTS = ("base", "ur5e_root_frame")  # the UR5e's root bodies in RMB's MuJoCo scenes
CATEGORIES = ("table", "robot arm", "task objects", "stand", "floor", "none")
NO_GEOM = -1


def category_of(model: mujoco.MjModel, root: int) -> str:
    """The label of a root body id (or NO_GEOM)."""
    if root == NO_GEOM:
        return "none"
    if root == 0:
        return "floor"
    name = model.body(root).name
    if name in ("table", "stand"):
        return name
    return "robot arm" if name in ROBOT_ROOTS else "task objects"


def label_image(
    renderer: mujoco.Renderer, data: mujoco.MjData, model: mujoco.MjModel
) -> np.ndarray:
    """(H, W) root body id of the geom seen at each pixel of the camera, NO_GEOM where none."""
    renderer.update_scene(data, camera=CAMERA)
    seg = renderer.render()
    geom, kind = seg[..., 0], seg[..., 1]
    is_geom = (geom >= 0) & (kind == mujoco.mjtObj.mjOBJ_GEOM)
    roots = np.full(geom.shape, NO_GEOM, dtype=np.int64)
    roots[is_geom] = model.body_rootid[model.geom_bodyid[geom[is_geom]]]
    return roots


def builders(attrs: dict, num_points: int, n_pixels: int) -> dict[str, tuple]:
    """Per crop frame: (policy's cloud builder, one that keeps every cropped pixel, box)."""
    fovy = float(attrs[K.fovy_attr(CAMERA)])
    pose = np.asarray(attrs[K.camera_pose_attr(CAMERA)]).tolist()
    out = {}
    for frame, (low, high) in DEFAULT_CROP.items():
        common = dict(
            camera_fovy=fovy,
            camera_pose=pose,
            crop_frame=frame,
            crop_min=low,
            crop_max=high,
            use_pc_color=True,  # the "colour" channels carry (root body, pixel index, 0)
            point_cloud_cache_size=0,
            device="cpu",
        )
        policy = DepthPointClouds(DP3Config(num_points=num_points, **common))
        every = DepthPointClouds(DP3Config(num_points=n_pixels, **common))
        out[frame] = (policy, every, (low, high))
    return out


def measure(depth_mm: np.ndarray, roots: np.ndarray, clouds: dict, model) -> dict[str, dict]:
    """Counts for one frame and each crop frame."""
    height, width = depth_mm.shape
    tags = np.zeros((height, width, 3), dtype=np.float32)  # exact integers in float32
    tags[..., 0] = roots
    tags[..., 1] = np.arange(height * width).reshape(height, width)
    result = {}
    for frame, (policy, every, _) in clouds.items():
        sampled = policy.cloud(depth_mm, tags)
        kept_tags = every.cloud(depth_mm, tags)[:, 3:]
        kept_pixels, first = np.unique(kept_tags[:, 1].astype(np.int64), return_index=True)
        kept_roots = kept_tags[first, 0].astype(np.int64)
        sample_roots = sampled[:, 3].astype(np.int64)
        assert np.isin(sampled[:, 4].astype(np.int64), kept_pixels).all()
        counts = Counter(category_of(model, int(r)) for r in sample_roots)
        objects = Counter(
            model.body(int(r)).name
            for r in sample_roots
            if category_of(model, int(r)) == "task objects"
        )
        result[frame] = {
            "kept": len(kept_pixels),
            "kept_table": sum(category_of(model, int(r)) == "table" for r in kept_roots),
            "samples": {c: counts.get(c, 0) for c in CATEGORIES},
            "objects": dict(objects),
        }
    return result


def collect(args: argparse.Namespace) -> tuple[list[dict], dict, dict]:
    """Drive the expert, measure the requested steps; returns (rows, boxes, meta)."""
    entry = ENVS[args.task]
    size = (args.image_size, args.image_size)
    # The expert's whole motion: RMB's success check can hold early (Insert: step ~41).
    env = gym.make(
        entry.gym_id, cameras=(CAMERA,), image_size=size, depth=True, terminate_on_success=False
    )
    core = env.unwrapped
    model, data = core.sim.model, core.sim.data
    renderer = mujoco.Renderer(model, args.image_size, args.image_size)
    renderer.enable_segmentation_rendering()
    rows, boxes, meta = [], {}, {"short": []}
    last = max(args.frames)
    try:
        expert = entry.load_expert_class()(core)
        bar = tqdm(total=args.episodes * len(args.frames), desc=f"{args.task} frames")
        for episode in range(args.episodes):
            obs, _ = env.reset(seed=episode, options={"world_idx": episode % 6})
            expert.reset()
            attrs = core.rmb_attrs()
            meta["fovy"] = float(attrs[K.fovy_attr(CAMERA)])
            clouds = builders(attrs, args.num_points, args.image_size**2)
            boxes = {frame: box for frame, (_, _, box) in clouds.items()}
            for step in range(last + 1):
                if step in args.frames:
                    depth = np.asarray(obs["depth"][CAMERA], dtype=np.float32)
                    counts = measure(depth, label_image(renderer, data, model), clouds, model)
                    rows.append({"episode": episode, "step": step, **counts})
                    bar.update()
                if step == last:
                    break
                obs, _, terminated, truncated, _ = env.step(expert(obs))
                if terminated or truncated:
                    meta["short"].append((episode, step + 1))
                    break
        bar.close()
    finally:
        renderer.close()
        env.close()
    return rows, boxes, meta


def fmt_box(box: tuple) -> str:
    low, high = box
    return f"({','.join(f'{v:g}' for v in low)})..({','.join(f'{v:g}' for v in high)})"


def report(args: argparse.Namespace, rows: list[dict], boxes: dict, meta: dict) -> str:
    """Markdown tables, means over the measured frames."""
    n = len(rows)
    head = (
        f"{args.task}, {CAMERA} camera {args.image_size}x{args.image_size} depth, fovy "
        f"{meta['fovy']:g} deg, {args.episodes} episodes x steps {list(args.frames)} = {n} frames "
        f"(means), {args.num_points} farthest-point samples"
    )
    lines = [
        head,
        "",
        "| crop | box (m) | pixels kept | of them table | "
        + " | ".join(
            f"{args.num_points} samples: {c}" if i == 0 else c for i, c in enumerate(CATEGORIES)
        )
        + " |",
        "|---|---|---|---|" + "---|" * len(CATEGORIES),
    ]
    for frame, title in FRAMES.items():
        r = [row[frame] for row in rows]
        kept = np.mean([x["kept"] for x in r])
        kept_table = np.mean([x["kept_table"] for x in r])
        samples = [np.mean([x["samples"][c] for x in r]) for c in CATEGORIES]
        lines.append(
            f"| {title} | {fmt_box(boxes[frame])} {frame} | {kept:.0f} | {kept_table:.1f} | "
            + " | ".join(f"{s:.1f}" for s in samples)
            + " |"
        )
    names = sorted({name for row in rows for f in FRAMES for name in row[f]["objects"]})
    lines += ["", "| crop | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for frame in FRAMES:
        means = [np.mean([row[frame]["objects"].get(name, 0) for row in rows]) for name in names]
        lines.append(f"| {frame} | " + " | ".join(f"{m:.1f}" for m in means) + " |")
    kept = {f: [row[f]["kept"] for row in rows] for f in FRAMES}
    short = [f for f, v in kept.items() if min(v) < args.num_points]
    lines += [
        "",
        "pixels kept per frame, min..max: "
        + "; ".join(f"{f} {min(v)}..{max(v)}" for f, v in kept.items())
        + (
            f" ({' and '.join(short)}: fewer than {args.num_points} in some frames, "
            "where farthest-point sampling repeats points)"
            if short
            else ""
        ),
    ]
    if meta["short"]:
        lines.append(f"episodes cut by the time limit (episode, steps): {meta['short']}")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="insert", choices=sorted(ENVS))
    parser.add_argument("--episodes", type=int, default=3, help="seeds 0.., worlds seed %% 6")
    parser.add_argument("--frames", type=int, nargs="+", default=[0, 60, 120], help="steps")
    parser.add_argument("--image-size", type=int, default=64)
    parser.add_argument("--num-points", type=int, default=512)
    args = parser.parse_args()
    if args.episodes < 1 or min(args.frames) < 0 or args.num_points < 1:
        parser.error("--episodes and --num-points must be >= 1, --frames >= 0")
    args.frames = sorted(set(args.frames))
    rows, boxes, meta = collect(args)
    if not rows:
        raise SystemExit("no frame measured: every episode ended before the first step")
    print(report(args, rows, boxes, meta))


if __name__ == "__main__":
    main()
