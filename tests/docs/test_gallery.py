"""The env gallery of the docs covers every registry entry and camera.

A new env (or camera) fails here until ``.venv/bin/python docs/gen_gallery.py`` has rendered
its pictures and rewritten the table on docs/environments.md.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from rmb_lerobot.envs.registry import ENVS

ROOT = Path(__file__).resolve().parents[2]
SPEC = importlib.util.spec_from_file_location("gen_gallery", ROOT / "docs" / "gen_gallery.py")
gen_gallery = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(gen_gallery)
REGENERATE = "run `.venv/bin/python docs/gen_gallery.py` (see docs/development.md)"


@pytest.mark.parametrize("name", sorted(ENVS))
def test_every_env_camera_has_a_picture(name):
    entry = ENVS[name]
    missing = [
        camera
        for camera in entry.cameras
        if not (gen_gallery.GALLERY / gen_gallery.image_name(entry.name, camera)).is_file()
    ]
    assert not missing, f"{name}: no gallery picture for {missing}; {REGENERATE}"


def test_the_environments_page_shows_the_current_gallery():
    page = gen_gallery.PAGE.read_text()
    table = page.split(gen_gallery.START, 1)[1].split(gen_gallery.END, 1)[0].strip()
    assert table == gen_gallery.gallery_table(list(ENVS.values())), REGENERATE


def test_pictures_are_small():
    sizes = {path.name: path.stat().st_size for path in gen_gallery.GALLERY.glob("*.png")}
    assert sizes, REGENERATE
    assert max(sizes.values()) < 100_000, sizes
