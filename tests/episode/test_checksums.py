"""Checksums in what we write: Fletcher-32 on every HDF5 dataset, SHA-256 of every video.

The claim tested: the original RMB's unmodified reader (plain h5py) still reads our files and
now fails loudly on a flipped data byte; digests are checked on demand; episodes written the
original's way (no checksums) read as before, and a flip in them stays undetected.
"""

from pathlib import Path

import h5py
import numpy as np
import pytest

from rmb_lerobot import EpisodeWriter, MissingKeyError, RmbFormatError, open_episode
from rmb_lerobot.episode.digest import ATTR_VIDEO_SHA256, file_sha256, parse_digests


def main_file(path: Path) -> Path:
    return path / "main.rmb.hdf5" if path.suffix == ".rmb" else path


def flip_data_byte(h5_path: Path, key: str, offset: int = 5) -> None:
    """Flip one bit inside the stored data (first chunk) of dataset ``key``."""
    with h5py.File(h5_path, "r") as h5:
        chunk = h5[key].id.get_chunk_info(0)
    data = bytearray(h5_path.read_bytes())
    data[chunk.byte_offset + min(offset, chunk.size - 1)] ^= 0x10
    h5_path.write_bytes(bytes(data))


@pytest.mark.parametrize("variant", ["rmb", "hdf5"])
def test_every_dataset_is_checksummed_chunked_and_uncompressed(tmp_path, record, variant):
    path = record(tmp_path / f"demo.{variant}")
    with h5py.File(main_file(path), "r") as h5:
        assert len(h5) > 10
        for name, dataset in h5.items():
            assert dataset.fletcher32, name
            assert dataset.chunks is not None and dataset.compression is None, name


@pytest.mark.parametrize(
    ("variant", "key"),
    [("rmb", "measured_joint_pos"), ("hdf5", "time"), ("hdf5", "front_rgb_image")],
)
def test_plain_h5py_fails_loudly_on_a_flipped_data_byte(tmp_path, record, variant, key):
    path = record(tmp_path / f"demo.{variant}")
    with h5py.File(main_file(path), "r") as h5:
        _, before = h5[key].id.read_direct_chunk((0,) * h5[key].ndim)  # data + checksum
    flip_data_byte(main_file(path), key)
    with h5py.File(main_file(path), "r") as h5:  # what the original RMB's loader does
        with pytest.raises(OSError, match="filter returned failure"):
            h5[key][()]
        _, after = h5[key].id.read_direct_chunk((0,) * h5[key].ndim)
    assert after[:-4] != before[:-4] and after[-4:] == before[-4:]  # data flipped, sum kept
    with open_episode(path) as ep, pytest.raises(RmbFormatError, match="corrupt") as info:
        ep[key][:]
    assert info.value.key == key and info.value.path == main_file(path)


def test_compact_episodes_record_each_video_digest(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    with open_episode(path, verify=True) as ep:
        digests = parse_digests(ep.attrs[ATTR_VIDEO_SHA256], main_file(path))
        assert ep.verify_digests() == 4
    videos = sorted(p.name for p in path.glob("*.mp4"))
    assert sorted(digests) == videos
    assert all(digests[name] == file_sha256(path / name) for name in videos)


def test_single_file_episodes_record_no_digest(tmp_path, record):
    with open_episode(record(tmp_path / "demo.hdf5"), verify=True) as ep:
        assert ATTR_VIDEO_SHA256 not in ep.attrs and ep.verify_digests() == 0


def test_a_changed_video_fails_verification_naming_the_file(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    video = path / "hand_depth_image.rmb.mp4"
    data = bytearray(video.read_bytes())
    data[len(data) // 2] ^= 0x01
    video.write_bytes(bytes(data))
    with open_episode(path) as ep:  # digests are checked on demand only
        assert len(ep) == 12
    with pytest.raises(RmbFormatError, match=r"differs from the .* recorded") as info:
        open_episode(path, verify=True)
    assert info.value.path == video


def test_a_missing_recorded_video_fails_verification(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    (path / "hand_depth_image.rmb.mp4").unlink()
    with pytest.raises(MissingKeyError, match="recorded in the 'video_sha256'") as info:
        open_episode(path, allow_missing_depth=True, verify=True)
    assert info.value.path == path / "hand_depth_image.rmb.mp4"


def test_copied_digest_attributes_are_replaced(tmp_path, steps, attrs):
    stale = "0" * 64 + "  front_rgb_image.rmb.mp4\n"
    for variant in ("rmb", "hdf5"):
        path = tmp_path / f"copy.{variant}"
        with EpisodeWriter(path, {**attrs, ATTR_VIDEO_SHA256: stale}) as writer:
            for step in steps:
                writer.append(step)
        with open_episode(path, verify=True) as ep:
            assert ep.attrs.get(ATTR_VIDEO_SHA256) != stale


def test_episodes_of_the_original_rmb_read_as_before(tmp_path, steps, attrs, write_like_original):
    """No checksums: reading and verifying work; a flipped data byte goes unnoticed."""
    path = write_like_original(tmp_path / "orig.rmb", steps, attrs)
    with open_episode(path, verify=True) as ep:
        assert ep.verify_digests() == 0
        before = ep["measured_joint_pos"][:]
    with h5py.File(main_file(path), "r") as h5:
        offset = h5["measured_joint_pos"].id.get_offset()
    data = bytearray(main_file(path).read_bytes())
    data[offset + 3] ^= 0x10
    main_file(path).write_bytes(bytes(data))
    with open_episode(path, verify=True) as ep:
        assert not np.array_equal(ep["measured_joint_pos"][:], before)  # undetectable
