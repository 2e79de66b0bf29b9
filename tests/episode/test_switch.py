"""switch_format: RMB's SwitchRmbDataFormat, keeping every key and attribute."""

import numpy as np
import pytest

from rmb_lerobot import RmbFormatError, open_episode, switch_format
from rmb_lerobot import keys as K


@pytest.mark.parametrize(("src_name", "dst_name"), [("a.rmb", "b.hdf5"), ("a.hdf5", "b.rmb")])
def test_switch_keeps_keys_attributes_and_data(tmp_path, record, psnr, src_name, dst_name):
    src = record(tmp_path / src_name)
    dst = switch_format(src, tmp_path / dst_name)
    with open_episode(src) as a, open_episode(dst) as b:
        assert sorted(a.keys()) == sorted(b.keys())
        assert b.attrs.pop("format") != a.attrs.pop("format")
        # Only the compact one has videos, so only it records their digests.
        digests = [ep.attrs.pop("video_sha256", None) for ep in (a, b)]
        assert digests.count(None) == 1
        assert a.attrs.keys() == b.attrs.keys()
        for name in a.attrs:
            np.testing.assert_array_equal(a.attrs[name], b.attrs[name])
        for key in a:
            x, y = a[key][:], b[key][:]
            if K.is_rgb_image_key(key):
                assert psnr(x, y) > 30
            elif K.is_depth_image_key(key):
                assert np.abs(x - y).max() <= 0.0005 + 1e-6
            else:
                assert x.dtype == y.dtype
                np.testing.assert_array_equal(x, y)


def test_rel_keys_are_copied_not_recomputed(tmp_path, record):
    import h5py

    src = record(tmp_path / "a.hdf5")
    with h5py.File(src, "a") as h5:
        h5["measured_joint_pos_rel"][...] = 42.0
    with open_episode(switch_format(src, tmp_path / "b.rmb")) as ep:
        assert np.all(ep["measured_joint_pos_rel"][:] == 42.0)


def test_switch_refuses_an_existing_destination(tmp_path, record, psnr):
    import h5py

    src = record(tmp_path / "a.rmb")
    dst = record(tmp_path / "b.hdf5")
    with h5py.File(dst, "a") as h5:  # the old destination, told apart from the new one
        h5["measured_joint_pos"][...] = 42.0
    before = dst.read_bytes()
    with pytest.raises(RmbFormatError, match="destination exists"):
        switch_format(src, dst)
    assert dst.read_bytes() == before
    assert switch_format(src, dst, overwrite=True) == dst
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.rmb", "b.hdf5"]  # no temporaries
    with open_episode(src) as a, open_episode(dst) as b:  # now the switched episode
        assert b.attrs["format"] == "RmbData-SingleHDF5" and sorted(a.keys()) == sorted(b.keys())
        for key in a:
            if K.is_rgb_image_key(key):
                assert psnr(a[key][:], b[key][:]) > 30
            elif K.is_depth_image_key(key):
                assert np.abs(a[key][:] - b[key][:]).max() <= 0.0005 + 1e-6
            else:
                np.testing.assert_array_equal(a[key][:], b[key][:])
