"""Picture of RMB's TACTO Grasp: the front camera and both DIGIT images through a grasp.

Runs the scripted expert in ``TactoSawyerGrasp`` and tiles, at four moments (approach, the
pads closing on the box, squeezed, lifted), the front camera above the left and right
fingertip tactile images, labelled::

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
    """The expert's grasp; frames at the start, first contact, full squeeze and after lifting."""
    entry = ENVS["pybullet_sawyer_grasp"]
    env = entry.make(cameras=("front", *SENSORS), image_size=size)
    try:
        expert = entry.load_expert_class()(env)
        obs, _ = env.reset(seed=seed)
        expert.reset()
        moments = [("start", obs["pixels"])]
        reference = obs["pixels"]["tactile_left"].astype(float)
        touched = squeezed = None
        for step in range(env.task.max_episode_steps):
            obs, _, terminated, _, _ = env.step(expert(obs))
            change = np.abs(obs["pixels"]["tactile_left"].astype(float) - reference).mean()
            if touched is None and change > 3.0:
                touched = step
                moments.append((f"contact (step {step})", obs["pixels"]))
            if touched is not None and squeezed is None and step >= touched + 10:
                squeezed = step
                moments.append((f"squeezed (step {step})", obs["pixels"]))
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
