"""Corrupt video and depth files: damage the file shows becomes an RmbFormatError naming it.

A seeded byte-flip fuzzer over valid files sorts every flip into: refused (RmbFormatError),
harmless (the frames decode exactly as before) or silent (different frames, no error). Before
the decoder was told to report errors, about 2 in 3 flips of an RGB or depth video were silent
(the H.264 decoder conceals damage); what stays silent now is damage that leaves a valid
stream (see rmb_lerobot.codecs.video.VideoFrameReader).
"""

from __future__ import annotations

import json
import struct
import zlib
from collections import Counter
from collections.abc import Callable
from pathlib import Path

import av
import numpy as np
import pytest

from rmb_lerobot.codecs.depth import get_depth_codec
from rmb_lerobot.codecs.rmbz_container import _FOOTER
from rmb_lerobot.codecs.synthetic import clean_depth_mm
from rmb_lerobot.codecs.video import RgbVideoReader, RgbVideoWriter, VideoFileWriter
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.synthetic import ur5e_steps

W, H, N = 160, 120, 30
FLIPS = 60


@pytest.fixture(scope="module")
def videos(tmp_path_factory) -> dict[str, Path]:
    """An RGB video, an RMB depth video and an rmbz file of one synthetic UR5e camera."""
    directory = tmp_path_factory.mktemp("videos")
    steps = list(ur5e_steps(N, ("front",), (W, H), seed=1))
    paths = {"rgb": directory / "front_rgb_image.rmb.mp4"}
    with RgbVideoWriter(paths["rgb"], W, H) as writer:
        for step in steps:
            writer.write(step["front_rgb_image"])
    for name in ("rmb-videoio", "rmbz"):
        codec = get_depth_codec(name)
        paths[name] = directory / f"front_depth_image{codec.file_suffix}"
        with codec.writer(paths[name], W, H) as writer:
            for step in steps:
                writer.write(step["front_depth_image"])
    return paths


def read_all(kind: str, path: Path) -> np.ndarray:
    reader = RgbVideoReader(path) if kind == "rgb" else get_depth_codec(kind).reader(path)
    with reader:
        if len(reader) != N:  # what the episode reader checks against the episode's steps
            raise RmbFormatError(f"{len(reader)} frames, expected {N}", path=path)
        return reader[:]


def flip_outcomes(path: Path, read: Callable[[Path], np.ndarray], flips: int, seed: int) -> Counter:
    """Flip one random bit per trial; anything but RmbFormatError fails the test."""
    clean = path.read_bytes()
    reference = read(path)
    damaged = path.with_name("damaged" + "".join(path.suffixes))
    rng = np.random.default_rng(seed)
    outcomes: Counter = Counter()
    for _ in range(flips):
        data = bytearray(clean)
        data[int(rng.integers(len(data)))] ^= 1 << int(rng.integers(8))
        damaged.write_bytes(bytes(data))
        try:
            frames = read(damaged)
        except RmbFormatError as exc:
            assert str(damaged) in str(exc)
            outcomes["refused"] += 1
            continue
        same = frames.shape == reference.shape and np.array_equal(frames, reference)
        outcomes["harmless" if same else "silent"] += 1
    return outcomes


@pytest.mark.parametrize("kind", ["rgb", "rmb-videoio"])
def test_byte_flips_in_h264_videos_are_refused_or_harmless(videos, kind):
    """Measured with 300 flips each: RGB 223 refused, 64 harmless, 13 silent (before: 35
    refused, 2 crashed, 197 silent); depth 233 / 58 / 9 (before: 20, 2, 216)."""
    outcomes = flip_outcomes(videos[kind], lambda p: read_all(kind, p), FLIPS, seed=0)
    assert outcomes["silent"] <= FLIPS * 0.2, outcomes
    assert outcomes["refused"] >= FLIPS * 0.5, outcomes


def test_every_byte_flip_in_an_rmbz_file_is_refused(videos):
    """rmbz checksums every byte, header included (format version 2)."""
    outcomes = flip_outcomes(videos["rmbz"], lambda p: read_all("rmbz", p), FLIPS, seed=0)
    assert outcomes == Counter(refused=FLIPS)


def corrupt_frame(rgb: Path, tmp_path: Path) -> Path:
    """A copy of ``rgb`` with one bit flipped in a P frame of its first group of pictures."""
    with av.open(str(rgb)) as container:
        packets = [(p.pos, p.size, p.is_keyframe) for p in container.demux(video=0) if p.size]
    first_group = packets[: next(i for i, p in enumerate(packets) if i and p[2])]
    decode_index = max(range(1, len(first_group)), key=lambda i: first_group[i][1])
    position, size, _ = packets[decode_index]
    for offset in range(size // 2, size):
        data = bytearray(rgb.read_bytes())
        data[position + offset] ^= 0x10
        damaged = tmp_path / f"damaged{offset}.mp4"
        damaged.write_bytes(bytes(data))
        try:
            read_all("rgb", damaged)
        except RmbFormatError:
            return damaged
    raise AssertionError("no refused flip in the packet")  # pragma: no cover


def test_a_corrupt_frame_is_named_and_refused_every_time_it_is_read(videos, tmp_path):
    """libav logs a repeated error line once; the reader must not take the repeat as clean."""
    damaged = corrupt_frame(videos["rgb"], tmp_path)
    with RgbVideoReader(damaged) as reader:
        bad = None
        for i in range(N):
            try:
                reader[i]
            except RmbFormatError as exc:
                assert f"video frame {i} is corrupt" in str(exc) and str(damaged) in str(exc)
                bad = i
                break
        assert bad is not None
        for _ in range(2):
            with pytest.raises(RmbFormatError, match=f"video frame {bad} is corrupt"):
                reader[bad]
        reader[N - 1]  # frames of an intact group of pictures still read


def test_reading_leaves_the_libav_log_as_it_was(videos, tmp_path, capfd):
    damaged = corrupt_frame(videos["rgb"], tmp_path)
    before = av.logging.get_level()  # PyAV's default None: libav's log is dropped
    with RgbVideoReader(damaged) as reader, pytest.raises(RmbFormatError):
        reader[:]
    assert av.logging.get_level() == before
    assert "error while decoding" not in capfd.readouterr().err  # captured, not printed


def test_a_broken_sample_description_is_a_format_error(videos, tmp_path):
    """Before: AttributeError ('NoneType' object has no attribute 'flush_buffers')."""
    damaged = tmp_path / "no_codec.mp4"
    damaged.write_bytes(videos["rgb"].read_bytes().replace(b"stsd", b"stsD", 1))
    with pytest.raises(RmbFormatError, match=r"no_codec\.mp4"):
        read_all("rgb", damaged)


def test_undecodable_metadata_text_does_not_hide_the_frames(videos, tmp_path):
    """A flip in the handler name (metadata nobody reads) leaves the frames readable."""
    data = videos["rgb"].read_bytes()
    damaged = tmp_path / "odd_metadata.mp4"
    position = data.index(b"VideoHandler")
    damaged.write_bytes(data[:position] + b"\xd6" + data[position + 1 :])
    np.testing.assert_array_equal(read_all("rgb", damaged), read_all("rgb", videos["rgb"]))


def test_a_depth_video_with_a_non_zero_u_plane_is_refused(tmp_path):
    """RMB's depth video keeps U = 0; decoding damage shows there first."""
    path = tmp_path / "front_depth_image.rmb.mp4"
    writer = VideoFileWriter(
        path, W, H, codec="libx264", pix_fmt="yuv444p", options={"crf": "0", "profile": "high444"}
    )
    for i, depth_mm in enumerate(clean_depth_mm(4, W, H)):
        planes = np.stack(
            [
                (depth_mm & 255).astype(np.uint8),
                np.zeros((H, W), np.uint8),
                (depth_mm >> 8).astype(np.uint8),
            ]
        )
        planes[1, 5, 5] = 7 if i == 2 else 0
        writer.encode(av.VideoFrame.from_ndarray(planes, format="yuv444p"))
    writer.close()
    with get_depth_codec("rmb-videoio").reader(path) as reader:
        assert reader[1].shape == (H, W)
        with pytest.raises(RmbFormatError, match=r"depth video frame 2 is corrupt: its U plane"):
            reader[0:4]


def test_an_rgb_video_must_not_be_a_depth_video(videos):
    with pytest.raises(RmbFormatError, match="depth video in this RGB file's place"):
        RgbVideoReader(videos["rmb-videoio"])
    with pytest.raises(RmbFormatError, match="expected yuv444p"):
        get_depth_codec("rmb-videoio").reader(videos["rgb"])


def rewrite_rmbz_header(path: Path, target: Path, edit: Callable[[dict], dict], crc_v1: bool):
    """Copy an rmbz file with an edited header, its footer checksum made as version 1 or 2."""
    data = path.read_bytes()
    (size,) = struct.unpack("<I", data[4:8])
    header = json.dumps(edit(json.loads(data[8 : 8 + size])), sort_keys=True).encode()
    assert len(header) == size  # same-length edits keep every offset
    offset, n, g, _, end = _FOOTER.unpack(data[-_FOOTER.size :])
    index = data[offset : len(data) - _FOOTER.size]
    crc = zlib.crc32(index) if crc_v1 else zlib.crc32(index, zlib.crc32(header))
    body = data[:8] + header + data[8 + size : len(data) - _FOOTER.size]
    target.write_bytes(body + _FOOTER.pack(offset, n, g, crc, end))


def test_a_flipped_rmbz_step_is_refused_and_version_1_files_still_read(videos, tmp_path):
    clean = read_all("rmbz", videos["rmbz"])
    flipped = tmp_path / "flipped.rmbz"
    data = bytearray(videos["rmbz"].read_bytes())
    position = data.index(b'"step_mm": 3') + len('"step_mm": ')
    data[position] ^= 0x04  # 3 -> 7: a valid odd step that would scale every depth by 7/3
    flipped.write_bytes(bytes(data))
    with pytest.raises(RmbFormatError, match="header or frame index checksum mismatch"):
        read_all("rmbz", flipped)

    version1 = tmp_path / "version1.rmbz"
    rewrite_rmbz_header(videos["rmbz"], version1, lambda h: {**h, "format_version": 1}, True)
    np.testing.assert_array_equal(read_all("rmbz", version1), clean)
    claims2 = tmp_path / "claims2.rmbz"  # a version 2 header needs the header checksum
    rewrite_rmbz_header(videos["rmbz"], claims2, lambda h: h, crc_v1=True)
    with pytest.raises(RmbFormatError, match="header checksum mismatch"):
        read_all("rmbz", claims2)
