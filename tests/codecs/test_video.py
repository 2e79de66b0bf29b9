"""RGB video streams: write as frames arrive, read any frame by index."""

from __future__ import annotations

from fractions import Fraction

import av
import cv2
import numpy as np
import pytest

from rmb_lerobot.codecs.video import RgbVideoReader, RgbVideoWriter, VideoFrameReader
from rmb_lerobot.errors import RmbFormatError

W, H, N = 64, 48, 24


def smooth_frames(n: int = N) -> list[np.ndarray]:
    """Colour gradients with a moving soft blob: smooth, so lossy H.264 keeps a high PSNR."""
    yy, xx = np.mgrid[0:H, 0:W]
    frames = []
    for t in range(n):
        blob = 60 * np.exp(-((xx - 10 - 2 * t) ** 2 + (yy - 20) ** 2) / 120)
        r = 110 + 60 * np.sin(xx / 16 + t / 5) + blob
        g = 120 + 60 * np.cos(yy / 14 - t / 7) + blob
        b = 60 + 1.5 * (xx + yy) + t
        frames.append(np.clip(np.stack([r, g, b], axis=-1), 0, 255).astype(np.uint8))
    return frames


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float(10 * np.log10(255**2 / mse))


@pytest.fixture(scope="module")
def rgb_video(tmp_path_factory) -> tuple[str, list[np.ndarray]]:
    path = tmp_path_factory.mktemp("rgb") / "front_rgb_image.rmb.mp4"
    frames = smooth_frames()
    with RgbVideoWriter(path, W, H, gop=5) as writer:  # B-frames + several keyframes
        for frame in frames:
            writer.write(frame)
    return path, frames


def test_rgb_round_trip_is_close_to_the_input(rgb_video):
    path, frames = rgb_video
    with RgbVideoReader(path) as reader:
        assert len(reader) == N
        assert reader.shape == (N, H, W, 3)
        decoded = reader[:]
    assert decoded.dtype == np.uint8
    assert decoded.shape == (N, H, W, 3)
    assert min(psnr(d, f) for d, f in zip(decoded, frames, strict=True)) > 35


def test_random_access_matches_sequential_decoding(rgb_video):
    path, _ = rgb_video
    with RgbVideoReader(path) as reader:
        sequential = reader[:]
    with RgbVideoReader(path) as reader:
        np.testing.assert_array_equal(reader[17], sequential[17])
        np.testing.assert_array_equal(reader[3], sequential[3])  # backwards: seeks again
        np.testing.assert_array_equal(reader[-1], sequential[-1])
        np.testing.assert_array_equal(reader[5:11:2], sequential[5:11:2])
        np.testing.assert_array_equal(reader[[20, 2, 2, 9]], sequential[[20, 2, 2, 9]])
        np.testing.assert_array_equal(reader[np.array([1, 0])], sequential[[1, 0]])
        assert reader[7:7].shape == (0, H, W, 3)


def test_out_of_range_index_raises_index_error(rgb_video):
    path, _ = rgb_video
    with RgbVideoReader(path) as reader:
        with pytest.raises(IndexError):
            reader[N]
        with pytest.raises(IndexError):
            reader[-N - 1]
        with pytest.raises(IndexError):
            reader[[0, N]]


@pytest.mark.parametrize("size", [(32, 24), (40, 29), (100, 75)])  # half, uneven, up
def test_resize_on_read_like_the_original_loader(rgb_video, size):
    """RMB's ``RmbData.RmbRgbVideo`` decodes the full frame, then ``cv2.resize(frame,
    image_size, interpolation=cv2.INTER_LINEAR)`` per frame: the same pixels, not only sizes."""
    path, _ = rgb_video
    width, height = size
    with RgbVideoReader(path) as full:
        frames = full[[0, 7, N - 1]]
    original = np.stack(
        [cv2.resize(frame, size, interpolation=cv2.INTER_LINEAR) for frame in frames]
    )
    with RgbVideoReader(path, image_size=size) as reader:
        assert reader.shape == (N, height, width, 3)
        np.testing.assert_array_equal(reader[0], original[0])
        np.testing.assert_array_equal(reader[[0, 7, N - 1]], original)
        assert reader[0:3].shape == (3, height, width, 3)
    # The interpolation matters at these sizes, so the comparison above tells them apart (at an
    # exact halving INTER_AREA averages the same 2x2 pixels as INTER_LINEAR).
    others = [cv2.INTER_NEAREST, cv2.INTER_CUBIC] + ([cv2.INTER_AREA] if width * 2 != W else [])
    for other in others:
        resized = np.stack([cv2.resize(frame, size, interpolation=other) for frame in frames])
        assert not np.array_equal(resized, original), other


def test_reads_a_video_without_frame_rate_and_with_b_frames(tmp_path):
    """Order comes from timestamps only: irregular pts and x264's B-frames must not matter."""
    path = tmp_path / "odd.mp4"
    frames = smooth_frames(12)
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", options={"crf": "18", "bf": "3", "g": "250"})
        stream.width, stream.height, stream.pix_fmt = W, H, "yuv420p"
        stream.codec_context.time_base = Fraction(1, 1000)
        for t, frame in enumerate(frames):
            video_frame = av.VideoFrame.from_ndarray(frame, format="rgb24")
            video_frame.pts = t * 37 + (t % 3)  # no fixed frame rate at all
            video_frame.time_base = Fraction(1, 1000)
            for packet in stream.encode(video_frame):
                container.mux(packet)
        for packet in stream.encode(None):
            container.mux(packet)
    with RgbVideoReader(path) as reader:
        assert len(reader) == 12
        sequential = reader[:]
        assert min(psnr(d, f) for d, f in zip(sequential, frames, strict=True)) > 35
        for i in (9, 4, 11, 0):
            np.testing.assert_array_equal(reader[i], sequential[i])


def test_frame_reader_returns_av_frames(rgb_video):
    path, _ = rgb_video
    with VideoFrameReader(path) as video:
        frame = video.frames(2)
        assert isinstance(frame, av.VideoFrame)
        assert (frame.width, frame.height) == (W, H)
        assert len(video.frames([0, 1])) == 2


def test_write_rejects_wrong_dtype_or_shape(tmp_path):
    path = tmp_path / "bad.mp4"
    with RgbVideoWriter(path, W, H) as writer:
        with pytest.raises(RmbFormatError, match=r"bad\.mp4") as excinfo:
            writer.write(np.zeros((H, W, 3), dtype=np.float32))
        assert "uint8" in str(excinfo.value)
        with pytest.raises(RmbFormatError, match=r"\(48, 64, 3\)"):
            writer.write(np.zeros((H, W + 1, 3), dtype=np.uint8))
        writer.write(np.zeros((H, W, 3), dtype=np.uint8))
    assert len(RgbVideoReader(path)) == 1


def test_missing_truncated_or_non_video_files_raise_format_error(tmp_path, rgb_video):
    path, _ = rgb_video
    with pytest.raises(RmbFormatError, match=r"missing\.mp4"):
        RgbVideoReader(tmp_path / "missing.mp4")
    truncated = tmp_path / "truncated.mp4"
    truncated.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(RmbFormatError, match=r"truncated\.mp4"):
        RgbVideoReader(truncated)
    garbage = tmp_path / "garbage.mp4"
    garbage.write_bytes(b"not a video" * 100)
    with pytest.raises(RmbFormatError, match=r"garbage\.mp4"):
        RgbVideoReader(garbage)
    audio_only = tmp_path / "audio.mkv"
    with av.open(str(audio_only), "w") as container:
        stream = container.add_stream("pcm_s16le", rate=8000)
        frame = av.AudioFrame.from_ndarray(
            np.zeros((1, 800), np.int16), format="s16", layout="mono"
        )
        frame.sample_rate = 8000
        for packet in stream.encode(frame):
            container.mux(packet)
    with pytest.raises(RmbFormatError, match="no video stream"):
        RgbVideoReader(audio_only)
