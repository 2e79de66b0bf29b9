"""--workers: shards converted in parallel and merged equal a one-process conversion."""

from __future__ import annotations

import numpy as np
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters import ConvertOptions, to_lerobot


def test_two_workers_write_the_same_dataset(demos, converted_depth, tmp_path, hidden_entries):
    root = tmp_path / "parallel"
    to_lerobot([demos], output=root, options=ConvertOptions(depth=True), workers=2, progress=False)
    assert hidden_entries(tmp_path) == []  # shards and staging removed
    single = LeRobotDataset("local/a", root=converted_depth, video_backend="pyav")
    parallel = LeRobotDataset("local/b", root=root, video_backend="pyav")
    assert parallel.fps == single.fps and parallel.meta.total_episodes == 2
    a = single.hf_dataset.with_format("numpy")[:]
    b = parallel.hf_dataset.with_format("numpy")[:]
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], key)
    last = len(parallel) - 1
    for index in (0, last):
        for key in (N.image_key("front"), N.depth_image_key("hand")):
            np.testing.assert_array_equal(parallel[index][key], single[index][key])
    assert (root / N.RMB_METADATA_PATH).read_text() == (
        converted_depth / N.RMB_METADATA_PATH
    ).read_text()
