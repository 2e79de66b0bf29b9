"""Render the env gallery: one frame per registry entry and camera, for the docs.

Run after adding or changing an env::

    .venv/bin/python docs/gen_gallery.py            # every env
    .venv/bin/python docs/gen_gallery.py cable ring  # some (short names, as rmb-collect takes)

Each env is made from the registry (``rmb_lerobot.envs.registry.ENVS``) with every camera it
has (fixed cameras, hand cameras, fingertip tactile images) at 160x120, reset with seed 0 in
world 0, and each camera's frame is written to ``docs/images/gallery/<env>_<camera>.png``. The
table between the ``gallery`` markers of ``docs/environments.md`` is rewritten to show them, and
``docs/images/overview.png`` (the README's and the home page's picture) is tiled from the
front cameras of a few envs. ``tests/docs/test_gallery.py`` fails when an env or camera has no
picture or no row.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])

DOCS = Path(__file__).resolve().parent
GALLERY = DOCS / "images" / "gallery"
PAGE = DOCS / "environments.md"
OVERVIEW = DOCS / "images" / "overview.png"
START, END = "<!-- gallery:start -->", "<!-- gallery:end -->"
SIZE = (160, 120)  # width, height of every picture
# The envs tiled into the overview picture (front camera), 4 per row.
OVERVIEW_ENVS = (
    "insert",
    "door",
    "cloth",
    "pick",
    "xarm7_pusht",
    "ur5e_dual_cable",
    "ring",
    "pybullet_sawyer_grasp",
)


def image_name(env: str, camera: str) -> str:
    """The gallery file name of one env's camera."""
    return f"{env}_{camera}.png"


def render(entry) -> dict[str, np.ndarray]:
    """One RGB frame per camera of ``entry`` just after ``reset(seed=0)`` in world 0."""
    env = entry.make(cameras=entry.cameras, image_size=SIZE)
    try:
        obs, _ = env.reset(seed=0, options={"world_idx": 0})
        return {camera: np.asarray(obs["pixels"][camera]) for camera in entry.cameras}
    finally:
        env.close()


def write_png(path: Path, rgb: np.ndarray) -> None:
    """Write an RGB uint8 image as PNG."""
    import cv2

    path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(path), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)):
        raise OSError(f"could not write {path}")


def gallery_table(envs) -> str:
    """The markdown table of the environments page: one row per env, its pictures in a row."""
    rows = ["| env | `--env.type` | cameras |", "|---|---|---|"]
    for entry in envs:
        pictures = " ".join(
            f"![{entry.rmb_env_name} {camera}](images/gallery/{image_name(entry.name, camera)})"
            for camera in entry.cameras
        )
        rows.append(
            f"| `{entry.rmb_env_name}`<br>{', '.join(entry.cameras)} "
            f"| `{entry.lerobot_type}` | {pictures} |"
        )
    return "\n".join(rows)


def rewrite_page(envs) -> None:
    """Replace the table between the gallery markers of the environments page."""
    text = PAGE.read_text()
    head, rest = text.split(START, 1)
    _, tail = rest.split(END, 1)
    PAGE.write_text(f"{head}{START}\n{gallery_table(envs)}\n{END}{tail}")


def write_overview() -> None:
    """Tile the front cameras of :data:`OVERVIEW_ENVS` into one picture, 4 per row."""
    import cv2

    tiles = [cv2.imread(str(GALLERY / image_name(env, "front"))) for env in OVERVIEW_ENVS]
    if any(tile is None for tile in tiles):
        raise FileNotFoundError("render the overview's envs first")
    rows = [np.hstack(tiles[i : i + 4]) for i in range(0, len(tiles), 4)]
    cv2.imwrite(str(OVERVIEW), np.vstack(rows))


def main(argv: list[str]) -> int:
    """Render the named envs (all without names), then rewrite the table and the overview."""
    import rmb_lerobot  # noqa: F401  (registers the envs)
    from rmb_lerobot.envs.registry import ENVS, entry_for

    selected = [entry_for(name) for name in argv] if argv else list(ENVS.values())
    for entry in selected:
        frames = render(entry)
        for camera, rgb in frames.items():
            write_png(GALLERY / image_name(entry.name, camera), rgb)
        print(f"{entry.name}: {', '.join(frames)}", flush=True)
    rewrite_page(list(ENVS.values()))
    write_overview()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
