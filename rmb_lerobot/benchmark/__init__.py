"""rmb-benchmark: the paper's policies x tasks x seeds grid, as Ray tasks.

``load_config`` reads a grid (YAML/JSON, see :mod:`rmb_lerobot.benchmark.config`),
``run_benchmark`` runs the cells not done yet on Ray and writes ``results.jsonl`` and the report
(:mod:`rmb_lerobot.benchmark.report`); the command builders and the per-policy CPU recipes are in
:mod:`rmb_lerobot.benchmark.recipes`.
"""

from rmb_lerobot.benchmark.config import BenchmarkConfig, BenchmarkConfigError, load_config
from rmb_lerobot.benchmark.runner import Summary, run_benchmark

__all__ = ["BenchmarkConfig", "BenchmarkConfigError", "Summary", "load_config", "run_benchmark"]
