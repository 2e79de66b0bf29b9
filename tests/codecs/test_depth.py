"""Depth codecs: the original RMB depth video (exact) and ours (max error 1 mm, random access)."""

from __future__ import annotations

import av
import numpy as np
import pytest

from rmb_lerobot.codecs.depth import (
    DEPTH_CODECS,
    find_depth_file,
    get_depth_codec,
    metres_to_mm,
    mm_to_metres,
)
from rmb_lerobot.codecs.synthetic import clean_depth_mm, noisy_depth_mm
from rmb_lerobot.errors import RmbFormatError

W, H, N = 64, 48, 10
KEY = "front_depth_image"


def encode(codec_name: str, directory, frames) -> str:
    codec = get_depth_codec(codec_name)
    path = directory / f"{KEY}{codec.file_suffix}"
    with codec.writer(path, frames[0].shape[1], frames[0].shape[0]) as writer:
        for frame in frames:
            writer.write(frame)
    return path


def decode_all(codec_name: str, path) -> np.ndarray:
    with get_depth_codec(codec_name).reader(path) as reader:
        return reader[:]


def every_fold_case() -> list[np.ndarray]:
    """uint16 frames covering 0, 65535, odd/even high bytes and every low byte."""
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 65536, (H, W), dtype=np.uint16) for _ in range(3)]
    frames.append(np.arange(H * W, dtype=np.uint16).reshape(H, W) * 13)
    frames.append(np.full((H, W), 65535, dtype=np.uint16))
    frames.append(np.zeros((H, W), dtype=np.uint16))
    return frames


# --- millimetres and metres ------------------------------------------------------------------


def test_metres_to_mm_rounds_to_the_nearest_millimetre():
    depth_m = np.array([0.0, 0.0014, 0.0016, 1.2344, 1.2346, 65.535], dtype=np.float64)
    np.testing.assert_array_equal(metres_to_mm(depth_m), [0, 1, 2, 1234, 1235, 65535])
    assert metres_to_mm(depth_m).dtype == np.uint16


def test_metres_to_mm_maps_values_without_a_uint16_mm_to_no_data():
    depth_m = np.array([np.nan, np.inf, -np.inf, -0.5, 65.536, 1e9, 0.5], dtype=np.float32)
    np.testing.assert_array_equal(metres_to_mm(depth_m), [0, 0, 0, 0, 0, 0, 500])


def test_mm_to_metres_is_float32_and_inverts_metres_to_mm():
    mm = np.array([0, 1, 999, 65535], dtype=np.uint16)
    metres = mm_to_metres(mm)
    assert metres.dtype == np.float32
    np.testing.assert_allclose(metres, [0, 0.001, 0.999, 65.535], rtol=1e-6)
    np.testing.assert_array_equal(metres_to_mm(metres), mm)


# --- registry ----------------------------------------------------------------------------------


def test_codecs_are_found_by_name_and_unknown_names_list_the_known_ones():
    assert {"rmb-videoio", "rmbz", "rmbz-exact"} <= set(DEPTH_CODECS)
    assert get_depth_codec("rmb-videoio").file_suffix == ".rmb.mp4"
    with pytest.raises(ValueError, match="rmb-videoio") as excinfo:
        get_depth_codec("png")
    assert "rmbz" in str(excinfo.value)


def test_find_depth_file_finds_any_registered_codec(tmp_path):
    assert find_depth_file(tmp_path, KEY) is None
    frames = list(clean_depth_mm(2, W, H))
    path = encode("rmbz", tmp_path, frames)
    found_path, codec = find_depth_file(tmp_path, KEY)
    assert found_path == path
    np.testing.assert_array_equal(codec.reader(found_path)[1].shape, (H, W))
    assert find_depth_file(tmp_path, "left_depth_image") is None


# --- rmb-videoio: the original RMB depth video ------------------------------------------------


def test_rmb_videoio_round_trip_is_exact(tmp_path):
    frames = every_fold_case()
    path = encode("rmb-videoio", tmp_path, frames)
    assert path.name == "front_depth_image.rmb.mp4"
    decoded = decode_all("rmb-videoio", path)
    assert decoded.dtype == np.uint16
    np.testing.assert_array_equal(decoded, np.stack(frames))


def write_like_original(path, frames: list[np.ndarray]) -> None:
    """videoio.uint16save, rebuilt here with PyAV: fold in numpy, x264 high444 CRF 0, preset
    slow, x264's default GOP (250), and no frame rate given (the muxer's default is used)."""
    with av.open(str(path), "w") as container:
        stream = container.add_stream(
            "libx264", options={"crf": "0", "preset": "slow", "profile": "high444"}
        )
        stream.width, stream.height, stream.pix_fmt = W, H, "yuv444p"
        for frame in frames:
            upper = (frame / 256).astype(np.uint8)
            lower = (frame % 256).astype(np.uint8)
            odd = upper % 2 == 1
            lower[odd] = 255 - lower[odd]
            planes = np.stack([lower, np.zeros_like(lower), upper])
            for packet in stream.encode(av.VideoFrame.from_ndarray(planes, format="yuv444p")):
                container.mux(packet)
        for packet in stream.encode(None):
            container.mux(packet)


def test_reads_depth_video_written_with_the_original_recipe(tmp_path):
    frames = every_fold_case() + list(clean_depth_mm(24, W, H))
    path = tmp_path / f"{KEY}.rmb.mp4"
    write_like_original(path, frames)
    with get_depth_codec("rmb-videoio").reader(path) as reader:
        assert reader.shape == (len(frames), H, W)
        np.testing.assert_array_equal(reader[20], frames[20])  # random access first
        np.testing.assert_array_equal(reader[:], np.stack(frames))


# --- rmbz: ours ---------------------------------------------------------------------------------


@pytest.mark.parametrize("content", [clean_depth_mm, noisy_depth_mm])
def test_rmbz_error_is_at_most_1mm_and_dropouts_stay_zero(tmp_path, content):
    frames = list(content(N, W, H))
    path = encode("rmbz", tmp_path, frames)
    assert path.name == "front_depth_image.rmbz"
    decoded = decode_all("rmbz", path)
    error = np.abs(decoded.astype(np.int32) - np.stack(frames))
    assert error.max() <= 1
    dropouts = np.stack(frames) == 0
    assert (decoded[dropouts] == 0).all()
    assert (decoded[~dropouts & (np.stack(frames) > 1)] > 0).all()


def test_rmbz_exact_is_lossless_and_takes_metres(tmp_path):
    frames = every_fold_case()
    np.testing.assert_array_equal(
        decode_all("rmbz-exact", encode("rmbz-exact", tmp_path, frames)), frames
    )
    metres = [mm_to_metres(f) for f in frames[:2]]
    path = encode("rmbz-exact", tmp_path, metres)
    np.testing.assert_array_equal(decode_all("rmbz-exact", path), frames[:2])


def test_rmbz_random_access_matches_sequential_decoding(tmp_path):
    frames = list(noisy_depth_mm(N, W, H))
    path = encode("rmbz", tmp_path, frames)
    with get_depth_codec("rmbz").reader(path) as reader:
        sequential = reader[:]
        assert reader.shape == (N, H, W)
    with get_depth_codec("rmbz").reader(path) as reader:
        np.testing.assert_array_equal(reader[7], sequential[7])
        np.testing.assert_array_equal(reader[-1], sequential[-1])
        np.testing.assert_array_equal(reader[2:9:3], sequential[2:9:3])
        np.testing.assert_array_equal(reader[[5, 0, 5]], sequential[[5, 0, 5]])
        assert reader[3:3].shape == (0, H, W)
        with pytest.raises(IndexError):
            reader[N]
        with pytest.raises(IndexError):
            reader[[0, -N - 1]]


def test_rmbz_starts_a_new_group_when_the_scene_changes(tmp_path):
    """A scene cut makes the old reference useless: the writer must notice and still decode."""
    frames = list(clean_depth_mm(6, W, H)) + [f[::-1].copy() for f in clean_depth_mm(6, W, H)]
    path = encode("rmbz", tmp_path, frames)
    with get_depth_codec("rmbz").reader(path) as reader:
        assert reader.groups[0] == 0
        assert reader.groups[-1] >= 1
        decoded = reader[:]
    assert np.abs(decoded.astype(np.int32) - np.stack(frames)).max() <= 1


@pytest.mark.parametrize("count", [0, 1])
def test_rmbz_handles_empty_and_single_frame_streams(tmp_path, count):
    frames = list(clean_depth_mm(count, 33, 25))  # odd sizes too
    codec = get_depth_codec("rmbz")
    path = tmp_path / f"{KEY}{codec.file_suffix}"
    with codec.writer(path, 33, 25) as writer:
        for frame in frames:
            writer.write(frame[..., None])  # (H, W, 1) like LeRobot depth features
    with codec.reader(path) as reader:
        assert reader.shape == (count, 25, 33)
        if count:
            assert np.abs(reader[0].astype(np.int32) - frames[0]).max() <= 1


# --- bad input and damaged files -----------------------------------------------------------------


@pytest.mark.parametrize("codec_name", ["rmb-videoio", "rmbz"])
def test_write_rejects_wrong_dtype_or_shape(tmp_path, codec_name):
    codec = get_depth_codec(codec_name)
    path = tmp_path / f"{KEY}{codec.file_suffix}"
    with codec.writer(path, W, H) as writer:
        with pytest.raises(RmbFormatError, match=KEY) as excinfo:
            writer.write(np.zeros((H, W), dtype=np.int32))
        assert "uint16 mm or float metres" in str(excinfo.value)
        with pytest.raises(RmbFormatError, match=r"\(48, 64\)"):
            writer.write(np.zeros((W, H), dtype=np.uint16))
        writer.write(np.zeros((H, W), dtype=np.uint16))


@pytest.mark.parametrize("codec_name", ["rmb-videoio", "rmbz"])
def test_truncated_missing_or_foreign_files_raise_format_error(tmp_path, codec_name):
    codec = get_depth_codec(codec_name)
    path = encode(codec_name, tmp_path, list(noisy_depth_mm(4, W, H)))
    truncated = tmp_path / f"truncated{codec.file_suffix}"
    truncated.write_bytes(path.read_bytes()[: path.stat().st_size * 2 // 3])
    with pytest.raises(RmbFormatError, match="truncated"):
        codec.reader(truncated)[:]
    with pytest.raises(RmbFormatError, match="missing"):
        codec.reader(tmp_path / f"missing{codec.file_suffix}")
    foreign = tmp_path / f"foreign{codec.file_suffix}"
    foreign.write_bytes(b"\x00" * 4096)
    with pytest.raises(RmbFormatError, match="foreign"):
        codec.reader(foreign)[:]


def test_rmbz_detects_corrupted_frame_bytes(tmp_path):
    path = encode("rmbz", tmp_path, list(noisy_depth_mm(4, W, H)))
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    reader = get_depth_codec("rmbz").reader(path)
    with pytest.raises(RmbFormatError, match=r"corrupt.*front_depth_image\.rmbz"):
        reader[:]
    reader.close()


def test_rmbz_rejects_a_file_whose_writer_never_finished(tmp_path):
    codec = get_depth_codec("rmbz")
    path = tmp_path / f"{KEY}{codec.file_suffix}"
    writer = codec.writer(path, W, H)
    for frame in clean_depth_mm(3, W, H):
        writer.write(frame)
    writer._container._file.flush()  # simulate a crash: data on disk, no index
    with pytest.raises(RmbFormatError, match="did not finish"):
        codec.reader(path)
    writer.close()
    assert len(codec.reader(path)) == 3
