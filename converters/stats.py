"""Statistics of numeric features that hold NaN/inf (``--allow-non-finite``).

LeRobot's statistics assume finite values: NaN makes every statistic NaN, and its quantile
histograms cannot even be built (``np.linspace`` from NaN/inf bin edges fails), so one NaN used
to crash or poison ``stats.json`` and, through normalisation, every training batch. Semantics
here: per dimension, min/max/mean/std/quantiles describe the *finite* values only; ``count``
stays the number of frames (LeRobot's per-feature count). A dimension without any finite value
has NaN statistics. Features without non-finite values get exactly LeRobot's statistics.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
from lerobot.datasets.compute_stats import compute_episode_stats, get_feature_stats
from lerobot.datasets.io_utils import load_info, load_stats, write_stats

_NUMERIC_SKIP = ("string", "language", "image", "video")


def _is_numeric(feature: Mapping) -> bool:
    return feature.get("dtype") not in _NUMERIC_SKIP


def finite_feature_stats(data: np.ndarray) -> dict[str, np.ndarray]:
    """Statistics of a numeric feature ``(T,)`` or ``(T, d)`` over its finite values."""
    data = np.asarray(data)
    columns = data.reshape(len(data), -1).astype(np.float64)
    per_column = []
    for column in columns.T:
        finite = column[np.isfinite(column)]
        if finite.size:
            per_column.append(get_feature_stats(finite, axis=0, keepdims=True))
        else:
            per_column.append(None)
    template = next((s for s in per_column if s is not None), None)
    names = [k for k in template if k != "count"] if template else ["min", "max", "mean", "std"]
    stats = {
        name: np.array(
            [np.nan if s is None else float(np.asarray(s[name]).reshape(-1)[0]) for s in per_column]
        )
        for name in names
    }
    stats["count"] = np.array([len(data)])
    return stats


def has_non_finite(data) -> bool:
    array = np.asarray(data)
    return array.dtype.kind in "fc" and not np.isfinite(array).all()


def finite_episode_stats(episode_data: dict, features: dict, quantile_list=None) -> dict:
    """LeRobot's ``compute_episode_stats``; features holding NaN/inf get
    :func:`finite_feature_stats` instead of failing."""
    special = {
        key
        for key, data in episode_data.items()
        if key in features and _is_numeric(features[key]) and has_non_finite(data)
    }
    plain = {key: data for key, data in episode_data.items() if key not in special}
    stats = compute_episode_stats(plain, features, quantile_list)
    stats.update({key: finite_feature_stats(episode_data[key]) for key in special})
    return stats


def refresh_finite_stats(root: Path) -> list[str]:
    """Recompute ``meta/stats.json`` for features whose data hold NaN/inf, from all frames.

    LeRobot aggregates per-episode statistics weighted by frame counts, which for such features
    count frames whose value was not used (and one episode whose dimension has no finite value
    makes that dimension NaN for the whole dataset). Recomputed from the data files, the
    statistics are exactly those of every finite value. Returns the features rewritten.
    """
    stats = load_stats(root) or {}
    features = load_info(root).features
    numeric = [key for key, feature in features.items() if _is_numeric(feature)]
    files = sorted((Path(root) / "data").rglob("*.parquet"))
    if not files or not numeric:
        return []
    table = pq.ParquetDataset(files).read(columns=numeric)
    rewritten = []
    for key in numeric:
        data = np.asarray(table.column(key).to_pylist(), dtype=np.float64)
        if has_non_finite(data):
            stats[key] = finite_feature_stats(data)
            rewritten.append(key)
    if rewritten:
        write_stats(stats, root)
    return rewritten
