"""Picture of RMB's TACTO Grasp: the front camera and both DIGIT images through a grasp.

Runs the scripted expert in ``TactoSawyerGrasp`` and tiles, at four moments (start, the pads
closing on the box, squeezed as the lift begins, lifted), the front camera above the left and
right fingertip tactile images, labelled::

    .venv/bin/python examples/tactile_grasp_figure.py [--out docs/images/tactile_grasp.png]

The README's PyBullet section shows the result.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import rmb_lerobot  # noqa: F401 - registers the envs
from rmb_lerobot.envs.registry import ENVS

SENSORS = ("tactile_left", "tactile_right")


def record_moments(size: tuple[int, int], seed: int = 0) -> list[tuple[str, dict[str, np.ndarray]]]:
    """The expert's grasp: frames at the start, as the pads reach the box, once squeezed (the
    lift begins) and when the box is held up (success)."""
    entry = ENVS["pybullet_sawyer_grasp"]
    env = entry.make(cameras=("front", *SENSORS), image_size=size)
    try:
        expert = entry.load_expert_class()(env)
        obs, _ = env.reset(seed=seed)
        expert.reset()
        moments = [("start", obs["pixels"])]
        seen = {"start"}
        for step in range(env.task.max_episode_steps):
            obs, _, terminated, _, _ = env.step(expert(obs))
            phase = expert.phase.value
            label = {"close": "closing", "lift": "squeezed, lifting"}.get(phase)
            if label is not None and label not in seen:
                seen.add(label)
                moments.append((f"{label} (step {step})", obs["pixels"]))
            if terminated:
                moments.append((f"lifted (step {step}, success)", obs["pixels"]))
                break
        return moments
    finally:
        env.close()


def tile(moments: list[tuple[str, dict[str, np.ndarray]]]) -> Image.Image:
    """One column per moment: its label, the front camera, then the two tactile images."""
    label_h, gap = 18, 4
    front_h, front_w, _ = moments[0][1]["front"].shape
    tac_h, tac_w, _ = moments[0][1]["tactile_left"].shape
    column_w = max(front_w, 2 * tac_w + gap)
    height = label_h + front_h + gap + tac_h + label_h
    canvas = Image.new("RGB", (len(moments) * (column_w + gap), height), "white")
    draw = ImageDraw.Draw(canvas)
    for i, (label, pixels) in enumerate(moments):
        x = i * (column_w + gap)
        draw.text((x + 2, 3), label, fill="black")
        canvas.paste(Image.fromarray(pixels["front"]), (x, label_h))
        for j, sensor in enumerate(SENSORS):
            at = (x + j * (tac_w + gap), label_h + front_h + gap)
            canvas.paste(Image.fromarray(pixels[sensor]), at)
            draw.text((at[0] + 2, at[1] + tac_h + 3), sensor, fill="black")
    return canvas


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/images/tactile_grasp.png"))
    parser.add_argument("--size", type=int, nargs=2, default=(240, 180), metavar=("W", "H"))
    args = parser.parse_args()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tile(record_moments(tuple(args.size))).save(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
