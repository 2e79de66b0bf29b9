"""rmb-data add-pointcloud: RMB's point clouds from depth, added atomically."""

import h5py
import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot import open_episode
from rmb_lerobot.data.add_pointcloud import PointCloudOptions, add_pointclouds, rpy_matrix
from rmb_lerobot.errors import MissingKeyError, RmbFormatError
from rmb_lerobot.pointcloud import camera_intrinsics, depth_to_points

SIZE = (40, 30)
WIDE = PointCloudOptions(
    image_size=SIZE, min_bound=(-9, -9, -9), max_bound=(9, 9, 9), num_points=64
)


def _clouds(path, camera="front"):
    with open_episode(path) as ep:
        attrs = {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in ep.attrs.items()}
        return ep[K.pointcloud_key(camera)][:], attrs


@pytest.mark.parametrize("name", ["ep.rmb", "ep.hdf5"])
def test_adds_clouds_and_attributes_as_rmb_names_them(tmp_path, record, name):
    path = record(tmp_path / name)
    add_pointclouds([path], ["front", "hand"], progress=False)  # RMB's defaults
    for camera in ("front", "hand"):
        clouds, attrs = _clouds(path, camera)
        key = K.pointcloud_key(camera)
        assert clouds.shape == (12, 512, 6) and clouds.dtype == np.float32
        assert attrs[key + "_image_size"] == [84, 84]
        assert attrs[key + "_min_bound"] == [-0.4] * 3 and attrs[key + "_max_bound"] == [1.0] * 3
        assert attrs[key + "_rpy_angle"] == [0.0] * 3
        xyz, rgb = clouds[..., :3], clouds[..., 3:]
        assert (xyz >= -0.4).all() and (xyz <= 1.0).all()
        assert (rgb >= 0).all() and (rgb <= 1).all() and rgb.std() > 0
    with open_episode(path) as ep:
        ep.validate()
    assert not list(tmp_path.rglob(".*"))


def test_points_are_the_resized_depth_back_projected(tmp_path, record):
    path = record(tmp_path / "ep.hdf5")
    add_pointclouds([path], ["front"], WIDE, progress=False)
    clouds, attrs = _clouds(path)
    k = camera_intrinsics(*SIZE, attrs[K.fovy_attr("front")])
    with open_episode(path, image_size=SIZE) as ep:
        depth, rgb = ep["front_depth_image"][:], ep["front_rgb_image"][:]
    for step in (0, 7, 11):
        xyz = clouds[step, :, :3].astype(np.float64)
        u = np.rint(xyz[:, 0] * k[0, 0] / xyz[:, 2] + k[0, 2]).astype(int)
        v = np.rint(xyz[:, 1] * k[1, 1] / xyz[:, 2] + k[1, 2]).astype(int)
        np.testing.assert_allclose(depth[step][v, u], xyz[:, 2], rtol=1e-5)
        np.testing.assert_allclose(rgb[step][v, u] / 255.0, clouds[step, :, 3:], atol=1e-6)
        assert len(np.unique(np.stack([u, v]), axis=1).T) == 64  # distinct pixels


def test_rpy_rotates_the_points_before_cropping(tmp_path, record):
    plain = record(tmp_path / "plain.hdf5")
    turned = record(tmp_path / "turned.hdf5")
    add_pointclouds([plain], ["front"], WIDE, progress=False)
    rpy = (10.0, -20.0, 90.0)
    add_pointclouds([turned], ["front"], PointCloudOptions(**{**WIDE.__dict__, "rpy_angle": rpy}))
    reference = _clouds(plain)[0]
    rotated, attrs = _clouds(turned)
    assert attrs["front_pointcloud_rpy_angle"] == list(rpy)
    back = rotated[..., :3] @ rpy_matrix(rpy)  # R^T applied row-wise
    # Every point rotated back is a back-projected pixel of the same step.
    with open_episode(plain, image_size=SIZE) as ep:
        all_points, _ = depth_to_points(ep["front_depth_image"][4], attrs[K.fovy_attr("front")])
    dist = np.linalg.norm(back[4][:, None, :] - all_points[None], axis=2).min(axis=1)
    assert dist.max() < 1e-5
    assert not np.allclose(rotated[4, :, :3], reference[4, :, :3], atol=1e-2)


def test_existing_clouds_need_overwrite_and_are_replaced_not_grown(tmp_path, record):
    path = record(tmp_path / "ep.hdf5")
    add_pointclouds([path], ["front"], progress=False)
    size = path.stat().st_size
    before = path.read_bytes()
    with pytest.raises(RmbFormatError, match="already exists; pass --overwrite") as info:
        add_pointclouds([path], ["front"], progress=False)
    assert info.value.key == "front_pointcloud" and path.read_bytes() == before
    add_pointclouds([path], ["front"], WIDE, overwrite=True, progress=False)
    clouds, attrs = _clouds(path)
    assert clouds.shape == (12, 64, 6) and attrs["front_pointcloud_image_size"] == list(SIZE)
    assert path.stat().st_size < size  # the old 512-point clouds are gone, not just unlinked


def test_raw_clouds_are_rotated_cropped_and_sampled(tmp_path, record_with):
    rng = np.random.default_rng(0)
    raw = rng.uniform(-1, 1, (12, 300, 6)).astype(np.float32)

    path = record_with(tmp_path / "ep.hdf5", extra=lambda i: {"front_pointcloud_raw": raw[i]})
    options = PointCloudOptions(min_bound=(0, -1, -1), max_bound=(1, 1, 1), num_points=50)
    add_pointclouds([path], ["front"], options, progress=False)
    clouds, attrs = _clouds(path)
    assert attrs["front_pointcloud_image_size"] == [-1, -1]
    assert clouds.shape == (12, 50, 6)
    for step in (0, 11):
        kept = {tuple(p) for p in raw[step][raw[step][:, 0] >= 0]}
        assert {tuple(p) for p in clouds[step]} <= kept  # cropped to x >= 0, points unchanged


def test_bad_input_is_refused_before_anything_is_written(tmp_path, record, record_with):
    good = record(tmp_path / "a.hdf5")
    no_fovy = record_with(tmp_path / "b.hdf5", **{K.fovy_attr("front"): "n/a"})
    before = good.read_bytes()
    with pytest.raises(RmbFormatError, match="fovy") as info:
        add_pointclouds([good, no_fovy], ["front"], progress=False)
    assert info.value.key == K.fovy_attr("front") and good.read_bytes() == before
    with pytest.raises(MissingKeyError, match="camera 'left' has no 'left_rgb_image'"):
        add_pointclouds([good], ["left"], progress=False)
    empty_box = PointCloudOptions(min_bound=(5, 5, 5), max_bound=(6, 6, 6))
    with pytest.raises(RmbFormatError, match=r"step 0: points is empty.*box \[5, 5, 5\]"):
        add_pointclouds([good], ["front"], empty_box, progress=False)
    assert good.read_bytes() == before
    with h5py.File(good) as h5:
        assert "front_pointcloud" not in h5
