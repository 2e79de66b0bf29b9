"""rmb-data tile-videos: lerobot-eval's rollout videos in a grid, framed by outcome."""

import json

import av
import numpy as np
import pytest

from rmb_lerobot.data.tile_videos import GREEN, RED, WHITE, find_rollouts, tile_videos
from rmb_lerobot.errors import RmbFormatError


def _decode(path):
    with av.open(str(path)) as container:
        rate = container.streams.video[0].average_rate
        return np.stack([f.to_ndarray(format="rgb24") for f in container.decode(video=0)]), rate


def _close(pixel, color, tol=40):
    return np.abs(pixel.astype(int) - np.array(color)).max() <= tol


def test_outcomes_come_from_eval_info(eval_output):
    for start in (
        eval_output,
        eval_output / "videos",
        eval_output / "videos" / "rmb_ur5e_insert_0",
    ):
        rollouts = find_rollouts(start)
        assert [r.success for r in rollouts] == [True, False, True, False, False]
        assert [r.label for r in rollouts] == [f"ep {k}" for k in range(5)]


def test_several_tasks_keep_their_own_outcomes(tmp_path, write_eval_output):
    root = write_eval_output(
        tmp_path, {"rmb_ur5e_insert_0": [False, True], "rmb_ur5e_door_0": [True]}
    )
    rollouts = find_rollouts(root)
    assert [(r.video.parent.name, r.video.name, r.success) for r in rollouts] == [
        ("rmb_ur5e_door_0", "eval_episode_0.mp4", True),
        ("rmb_ur5e_insert_0", "eval_episode_0.mp4", False),
        ("rmb_ur5e_insert_0", "eval_episode_1.mp4", True),
    ]
    assert rollouts[0].label == "rmb_ur5e_door_0 ep 0"


def test_tiled_video_frames_each_rollout_by_its_outcome(eval_output, tmp_path):
    out = tile_videos(
        find_rollouts(eval_output), tmp_path / "tiled.mp4", labels=False, progress=False
    )
    frames, rate = _decode(out)
    border = 4  # 1/16 of the shorter side (48), at least 4
    cell = (64 + 2 * border, 48 + 2 * border)  # (w, h) of a tile with its frame
    assert rate == 10 and len(frames) == 10  # the longest rollout: 6 + 4 frames
    assert frames.shape[1:] == (2 * cell[1], 3 * cell[0], 3)  # 5 tiles: 3 columns, 2 rows
    expected = [GREEN, RED, GREEN, RED, RED, WHITE]  # the sixth cell is empty
    for i, color in enumerate(expected):
        y, x = (i // 3) * cell[1], (i % 3) * cell[0]
        assert _close(frames[-1][y + 2, x + cell[0] // 2], color), i  # top edge of the frame
        if i < 5:
            centre = frames[-1][y + cell[1] // 2, x + cell[0] // 2]
            assert _close(centre, (20 * i,) * 3, tol=6), i  # the rollout's own grey level
    # Rollout 0 lasts 6 frames and then holds its last frame.
    assert _close(frames[9][cell[1] // 2, cell[0] // 2], (0, 0, 0), tol=6)


def test_labels_and_manual_outcomes(eval_output, tmp_path):
    rollouts = find_rollouts(eval_output, successes=[False] * 5)
    assert [r.success for r in rollouts] == [False] * 5
    out = tile_videos(rollouts, tmp_path / "t.mp4", columns=5, border=4, progress=False)
    frames, _ = _decode(out)
    assert frames.shape[1:] == (56, 360, 3)
    label = frames[-1][4:10, 4 + 72 * 4 : 30 + 72 * 4]  # the label box of tile 5: red
    assert (label[..., 0].astype(int) - label[..., 1] > 100).mean() > 0.3


def test_unknown_outcomes_without_eval_info(eval_output, tmp_path):
    (eval_output / "eval_info.json").unlink()
    rollouts = find_rollouts(eval_output)
    assert [r.success for r in rollouts] == [None] * 5


def test_bad_input(eval_output, tmp_path):
    with pytest.raises(ValueError, match="3 successes given for 5 videos"):
        find_rollouts(eval_output, successes=[True] * 3)
    with pytest.raises(RmbFormatError, match="no videos"):
        find_rollouts(_empty(tmp_path))
    (eval_output / "eval_info.json").write_text("{broken")
    with pytest.raises(RmbFormatError, match="cannot read lerobot-eval's results") as info:
        find_rollouts(eval_output)
    assert info.value.path.name == "eval_info.json"
    (eval_output / "eval_info.json").write_text(json.dumps({"per_task": []}))
    rollouts = find_rollouts(eval_output)
    out = tmp_path / "exists.mp4"
    out.write_bytes(b"old")
    with pytest.raises(FileExistsError, match="--overwrite"):
        tile_videos(rollouts, out, progress=False)
    assert out.read_bytes() == b"old"
    tile_videos(rollouts, out, overwrite=True, progress=False)
    assert _decode(out)[0].shape[0] == 10


def _empty(tmp_path):
    directory = tmp_path / "empty"
    directory.mkdir()
    return directory
