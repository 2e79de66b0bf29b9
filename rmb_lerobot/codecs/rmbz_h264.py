"""Lossless H.264 "reference + frame" pairs: the motion-compensated coder inside ``rmbz``.

Each depth frame is coded as the second frame of its own two-frame lossless H.264 stream whose
first frame is the group's reference image. x264 is deterministic, so the reference's IDR packet
is the same bytes in every pair: it is stored once per group, and frame i decodes from exactly
two packets (the group's IDR, then frame i's P packet) with x264's motion compensation and
CABAC, instead of from the whole chain of previous frames. The writer checks the IDR bytes of
every pair, so correctness never rests on that determinism.

Values (0..65535) travel as 10-bit planes: yuv444p10le with Y = folded low 10 bits, U = 0,
V = high bits (see :func:`rmbz_arrays.fold10`); encoding is lossless (qp 0).
"""

from __future__ import annotations

from fractions import Fraction

import av
import numpy as np

from rmb_lerobot.codecs.rmbz_arrays import fold10, unfold10

PIX_FMT = "yuv444p10le"
# No B-frames, no scene-cut I-frames, no lookahead, one thread: frame 2 is a P-frame that
# references frame 1 only, and the IDR does not depend on what follows it.
X264_PARAMS = "keyint=infinite:scenecut=0:bframes=0:threads=1:rc-lookahead=0:sync-lookahead=0"


def _to_frame(q: np.ndarray, pts: int) -> av.VideoFrame:
    height, width = q.shape
    frame = av.VideoFrame(width, height, PIX_FMT)
    y, v = fold10(q)
    for plane, values in zip(frame.planes, (y, np.zeros_like(y), v), strict=True):
        padded = np.zeros((height, plane.line_size // 2), dtype=np.uint16)
        padded[:, :width] = values
        plane.update(padded.tobytes())
    frame.pts = pts
    return frame


def _plane(frame: av.VideoFrame, index: int) -> np.ndarray:
    plane = frame.planes[index]
    rows = np.frombuffer(plane, dtype=np.uint16).reshape(frame.height, plane.line_size // 2)
    return rows[:, : frame.width]


def encode_pair(reference: np.ndarray, target: np.ndarray, preset: str) -> tuple[bytes, bytes]:
    """(IDR packet of ``reference``, P packet of ``target`` predicted from it), both lossless."""
    height, width = reference.shape
    encoder = av.CodecContext.create("libx264", "w")
    encoder.width, encoder.height, encoder.pix_fmt = width, height, PIX_FMT
    encoder.time_base = Fraction(1, 25)
    encoder.options = {"qp": "0", "preset": preset, "x264-params": X264_PARAMS}
    packets = [*encoder.encode(_to_frame(reference, 0)), *encoder.encode(_to_frame(target, 1))]
    packets += encoder.encode(None)
    if len(packets) != 2 or not packets[0].is_keyframe:
        raise RuntimeError(f"x264 produced {len(packets)} packets, expected IDR + P")
    return bytes(packets[0]), bytes(packets[1])


class PairDecoder:
    """Decodes (IDR, P) pairs with one reusable H.264 decoder."""

    def __init__(self):
        self._decoder = av.CodecContext.create("h264", "r")

    def decode(self, idr: bytes, packet: bytes) -> np.ndarray:
        """The P frame's values (int32, H x W). Raises av.FFmpegError / ValueError if corrupt."""
        self._decoder.flush_buffers()
        frames = []
        for pts, data in enumerate((idr, packet)):
            av_packet = av.Packet(data)
            av_packet.pts = pts
            frames += self._decoder.decode(av_packet)
        if not any(f.pts == 1 for f in frames):
            frames += self._decoder.decode(None)  # drain a decoder that delays output
        target = [f for f in frames if f.pts == 1]
        if len(target) != 1 or target[0].format.name != PIX_FMT:
            raise ValueError("the H.264 packets did not decode to one yuv444p10le frame")
        return unfold10(_plane(target[0], 0), _plane(target[0], 2))
