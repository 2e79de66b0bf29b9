"""EpisodeWriter's background encoding: same bytes as encoding in the caller's thread, errors
surface in the caller, bounded queue, atomicity unchanged."""

import threading

import h5py
import numpy as np
import pytest

from rmb_lerobot import EpisodeWriter, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot.episode.encode_worker import EncodeWorker
from rmb_lerobot.kinematics import UR5E


def _h5_content(path):
    with h5py.File(path / K.COMPACT_MAIN_FILE) as h5:
        data = {key: h5[key][()] for key in h5}
        attrs = {key: np.asarray(value).tolist() for key, value in h5.attrs.items()}
    return data, attrs


def _worker_threads():
    return [t for t in threading.enumerate() if t.name.startswith("encode ")]


def test_background_and_caller_thread_encoding_write_the_same_bytes(tmp_path, record, steps):
    sync = record(tmp_path / "sync" / "demo.rmb", background_encoding=False)
    background = record(tmp_path / "background" / "demo.rmb", background_encoding=True)
    names = sorted(p.name for p in sync.iterdir())
    assert names == sorted(p.name for p in background.iterdir())
    for name in names:
        if name != K.COMPACT_MAIN_FILE:  # videos: the same encoder, the same frames in order
            assert (sync / name).read_bytes() == (background / name).read_bytes(), name
    sync_data, sync_attrs = _h5_content(sync)
    background_data, background_attrs = _h5_content(background)
    assert sync_attrs == background_attrs  # video_sha256 included
    assert sorted(sync_data) == sorted(background_data)
    for key, values in sync_data.items():
        np.testing.assert_array_equal(values, background_data[key], err_msg=key)
    with open_episode(sync) as a, open_episode(background) as b:
        for key in ("front_rgb_image", "front_depth_image", "hand_rgb_image"):
            np.testing.assert_array_equal(a[key][:], b[key][:], err_msg=key)
    assert _worker_threads() == []


def test_the_caller_may_reuse_its_image_buffer(tmp_path, steps, attrs):
    buffer = np.empty_like(steps[0]["front_rgb_image"])
    with EpisodeWriter(tmp_path / "demo.rmb", attrs, fk=UR5E, max_queued_images=64) as writer:
        for step in steps:
            buffer[...] = step["front_rgb_image"]
            writer.append({**step, "front_rgb_image": buffer})
            buffer[...] = 0  # overwritten before the background encoder got to it
    with (
        EpisodeWriter(tmp_path / "ref.rmb", attrs, fk=UR5E, background_encoding=False) as ref,
    ):
        for step in steps:
            ref.append(step)
    video = "front_rgb_image.rmb.mp4"
    assert (tmp_path / "demo.rmb" / video).read_bytes() == (
        tmp_path / "ref.rmb" / video
    ).read_bytes()


class _FailingEncoder:
    """Stands in for a video encoder whose disk filled up at frame ``fail_at``."""

    def __init__(self, fail_at: int):
        self.fail_at, self.frames = fail_at, 0

    def write(self, frame):
        self.frames += 1
        if self.frames > self.fail_at:
            raise OSError(28, "No space left on device")

    def close(self):
        pass


@pytest.mark.parametrize("stop", ["append", "close"])
def test_an_encoder_error_is_raised_in_the_caller_and_leaves_nothing(tmp_path, steps, attrs, stop):
    # One queued image at most: the error of step 1's frame shows within two more steps.
    writer = EpisodeWriter(tmp_path / "demo.rmb", attrs, fk=UR5E, max_queued_images=1)
    writer.append(steps[0])
    writer._encoders["front_rgb_image"] = _FailingEncoder(fail_at=0)
    with pytest.raises(OSError, match="No space left"), writer:
        writer.append(steps[1])  # queued; fails on the worker thread
        if stop == "append":
            for step in steps[2:4]:
                writer.append(step)
            pytest.fail("the encoder's error never reached append()")
        writer.close()
    assert list(tmp_path.iterdir()) == []
    assert _worker_threads() == []


def test_a_caller_that_ignores_an_encoder_error_cannot_close_a_broken_episode(
    tmp_path, steps, attrs
):
    writer = EpisodeWriter(tmp_path / "demo.rmb", attrs, fk=UR5E, max_queued_images=1)
    writer.append(steps[0])
    writer._encoders["front_rgb_image"] = _FailingEncoder(fail_at=0)
    with pytest.raises(OSError, match="No space left"):
        for step in steps[1:4]:
            writer.append(step)
    with pytest.raises(OSError, match="No space left"):  # raised again, not committed
        writer.close()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("interrupt", [KeyboardInterrupt(), RuntimeError("robot fault")])
def test_an_interrupted_recording_with_frames_in_flight_leaves_nothing(
    tmp_path, steps, attrs, interrupt
):
    with pytest.raises(type(interrupt)), EpisodeWriter(tmp_path / "demo.rmb", attrs) as writer:
        for step in steps[:8]:
            writer.append(step)
        raise interrupt
    assert list(tmp_path.iterdir()) == []
    assert _worker_threads() == []


def test_submit_waits_while_the_queue_is_full():
    release, done = threading.Event(), []
    worker = EncodeWorker(max_queued=1)
    worker.submit(release.wait)  # running: blocks the worker
    worker.submit(done.append, 1)  # queued: the queue is full now
    submitter = threading.Thread(target=worker.submit, args=(done.append, 2))
    submitter.start()
    submitter.join(timeout=0.2)
    assert submitter.is_alive() and done == []  # back-pressure: the third job waits
    release.set()
    submitter.join()
    worker.finish()
    assert done == [1, 2]  # in submission order


def test_a_cancelled_worker_skips_its_queue_and_refuses_new_jobs():
    release, done = threading.Event(), []
    worker = EncodeWorker(max_queued=4)
    worker.submit(release.wait)
    worker.submit(done.append, 1)
    release.set()
    worker.cancel()
    assert done in ([], [1])  # the running job may have taken the next one already
    with pytest.raises(RuntimeError, match="stopped"):
        worker.submit(done.append, 2)


def test_queue_size_must_be_positive(tmp_path, attrs):
    with pytest.raises(ValueError, match="max_queued_images must be at least 1, got 0"):
        EpisodeWriter(tmp_path / "demo.rmb", attrs, max_queued_images=0)
    assert list(tmp_path.iterdir()) == []
