"""Run a benchmark grid on Ray: every collect, convert, train and eval cell is a Ray task (with
``executor="local"``, a thread of this process instead: ``local.py``).

A cell's Ray task gets its upstream cells' results as arguments (``ObjectRef``s, or the results
of cells done in an earlier run), so Ray starts it when they are ready, on any node with the
CPUs/GPUs the config asks for. Cells done in an earlier run are not submitted at all; a failing
cell is reported (its error and the end of its log in the results) and the rest of the grid
goes on. The driver alone writes ``results.jsonl``, ``curves.jsonl`` and the report.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tqdm import tqdm

from rmb_lerobot.benchmark.cells import Cell, CellResult, execute, merged_durations, recorded
from rmb_lerobot.benchmark.config import BenchmarkConfig
from rmb_lerobot.benchmark.grid import plan
from rmb_lerobot.benchmark.local import run_locally
from rmb_lerobot.benchmark.report import (
    CURVES_FILE,
    RESULTS_FILE,
    curve_rows,
    read_jsonl,
    render_report,
    result_row,
    row_key,
    short_error,
    write_jsonl,
)


class BenchmarkBusyError(RuntimeError):
    """Another driver runs a grid in the same output directory."""


@dataclass
class Summary:
    """What a run did: results by cell id, which cells ran, which were done before."""

    results: dict[str, CellResult] = field(default_factory=dict)
    ran: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    report: list[Path] = field(default_factory=list)

    @property
    def failed(self) -> list[CellResult]:
        return [r for r in self.results.values() if not r.ok]

    def first_failures(self) -> list[CellResult]:
        """Failed cells that failed themselves (not only because an upstream cell failed)."""
        return [r for r in self.failed if r.failed_cell == r.id]


def _execute_remote(cell: Cell, *upstream: CellResult) -> CellResult:
    """The Ray task body (module level, so workers import it instead of unpickling code)."""
    return execute(cell, upstream)


def init_ray(address: str | None = None, num_cpus: int | None = None, num_gpus: int | None = None):
    """Connect to the cluster at ``address``, or start a quiet local Ray (no dashboard, the
    machine's CPUs, no usage reporting). Returns the ``ray`` module."""
    ray = import_ray()
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # no network calls
    if ray.is_initialized():
        return ray
    quiet = {"log_to_driver": False, "logging_level": logging.ERROR, "configure_logging": True}
    # Ray's driver replaces the SIGTERM handler with its own (log and exit 1); a handler the
    # caller installed (the CLI's: unwind like Ctrl-C, cancelling running cells) comes back.
    caller_handler = signal.getsignal(signal.SIGTERM)
    if address:
        ray.init(address=address, **quiet)
    else:
        ray.init(
            num_cpus=num_cpus or os.cpu_count() or 1,
            num_gpus=num_gpus,
            include_dashboard=False,
            **quiet,
        )
    if callable(caller_handler) and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, caller_handler)
    return ray


EXECUTORS = ("ray", "local")


def run_benchmark(
    config: BenchmarkConfig,
    *,
    ray_address: str | None = None,
    num_cpus: int | None = None,
    progress: bool = True,
    echo: Callable[[str], None] | None = None,
    executor: str = "ray",
) -> Summary:
    """Run every cell of ``config`` not done yet, write the results and render the report.

    Args:
        config: the grid.
        ray_address: an existing Ray cluster to join (``executor="ray"`` only).
        num_cpus: CPUs of the local Ray, or of the local executor (default: all of them).
        progress: show a progress bar.
        echo: where failure lines go (default: above the progress bar).
        executor: ``"ray"`` (local or cluster Ray; uses the Ray session already initialised in
            this process if there is one and leaves it running, otherwise starts one and shuts
            it down at the end) or ``"local"`` (threads on this machine, no Ray needed).

    Returns:
        What ran, what was done before, what failed, and the report's files.

    Raises:
        BenchmarkBusyError: another driver runs a grid with the same ``--out``.
        ValueError: an unknown ``executor``, or ``ray_address`` with the local executor.
    """
    if executor not in EXECUTORS:
        raise ValueError(f"executor must be one of {EXECUTORS}, not {executor!r}")
    if executor == "local" and ray_address:
        raise ValueError(f"--ray-address {ray_address} needs the ray executor, not local")
    echo = echo or (lambda line: tqdm.write(line))
    out = config.out.absolute()
    out.mkdir(parents=True, exist_ok=True)
    with _exclusive(out):
        return _run(config, out, ray_address, num_cpus, progress, echo, executor)


@contextlib.contextmanager
def _exclusive(out: Path):
    """One driver per output directory: a second one would run the same cells twice."""
    with open(out / ".rmb-benchmark.lock", "w") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise BenchmarkBusyError(
                f"another rmb-benchmark is running with --out {out}; wait for it or use "
                "another output directory"
            ) from None
        yield


def _run(config, out, ray_address, num_cpus, progress, echo, executor) -> Summary:
    cells = plan(config)
    summary = Summary()
    results = summary.results
    for cell in cells.values():  # upstream first: plan() is in dependency order
        done = recorded(cell)
        if done is not None:
            if done.ok:
                ups = [results[u] for u in cell.upstream if u in results and results[u].ok]
                done.durations = {**merged_durations(ups), **done.durations}
                summary.skipped.append(cell.id)
            results[cell.id] = done  # done, or refused: recorded for another command
    needed = _needed(cells, results)
    if needed and executor == "local":
        finished = run_locally(cells, needed, results, num_cpus=num_cpus or os.cpu_count() or 1)
        _collect(finished, config, cells, needed, summary, progress, echo, out)
    elif needed:
        ray = import_ray()
        started_here = not ray.is_initialized()
        if started_here:
            init_ray(ray_address, num_cpus)
        try:
            finished = _on_ray(ray, config, cells, needed, results)
            _collect(finished, config, cells, needed, summary, progress, echo, out)
        finally:
            if started_here:
                ray.shutdown()
    else:
        _write_outputs(config, cells, summary, out)
    summary.report = render_report(out, config)
    return summary


def import_ray():
    """The ``ray`` module, or a clear exit if the benchmark extra is not installed."""
    try:
        import ray
    except ImportError:
        raise SystemExit(
            "rmb-benchmark needs Ray: pip install 'lerobot_env_rmb[benchmark]', or run it with "
            "--executor local (this machine's CPUs, no Ray)"
        ) from None
    return ray


def _needed(cells: dict[str, Cell], results: dict[str, CellResult]) -> list[str]:
    """Cells to run: evaluations not done, and every not-done cell they depend on."""
    needed: set[str] = set()
    stack = [cid for cid, c in cells.items() if c.kind == "eval" and cid not in results]
    while stack:
        cid = stack.pop()
        if cid in needed:
            continue
        needed.add(cid)
        stack += [u for u in cells[cid].upstream if u not in results]
    return [cid for cid in cells if cid in needed]  # dependency order


def _on_ray(ray, config, cells, needed, done) -> Iterator[tuple[str, CellResult]]:
    """Every needed cell as a Ray task (upstream results as ObjectRef arguments); yields
    ``(id, result)`` as they end. Stopped early (Ctrl-C), it cancels the tasks still pending."""
    remote = ray.remote(_execute_remote)
    refs: dict[str, Any] = {}
    for cid in needed:
        cell = cells[cid]
        args = [refs[u] if u in refs else done[u] for u in cell.upstream]
        refs[cid] = remote.options(
            num_cpus=cell.num_cpus,
            num_gpus=cell.num_gpus,
            max_retries=config.retries,
            name=cid,
        ).remote(cell, *args)
    by_ref = {ref: cid for cid, ref in refs.items()}
    pending = list(refs.values())
    results = dict(done)
    try:
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            for ref in ready:
                cid = by_ref[ref]
                results[cid] = _get(ray, ref, cells[cid], results)
                yield cid, results[cid]
    except BaseException:  # Ctrl-C, or the caller stopped early
        for ref in pending:
            ray.cancel(ref)  # KeyboardInterrupt in the task: it stops its command
        raise


def _collect(finished, config, cells, needed, summary, progress, echo, out) -> None:
    """Record each finished cell, report failures, and rewrite the results after every
    evaluation (a grid stopped half-way still has its finished rows)."""
    bar = tqdm(total=len(needed), desc="benchmark cells", unit="cell", disable=not progress)
    failures = 0
    try:
        for cid, result in finished:
            summary.results[cid] = result
            summary.ran.append(cid)
            if not result.ok:
                failures += 1
                if result.failed_cell == cid:
                    echo(f"FAILED {cid}: {short_error(result.error)}")
            bar.set_postfix(failed=failures, last=cid.split("/")[0])
            bar.update()
            if cells[cid].kind == "eval":
                _write_outputs(config, cells, summary, out)
    finally:
        finished.close()  # stopped early: the executor stops what still runs
        bar.close()
        _write_outputs(config, cells, summary, out)


def _get(ray, ref, cell: Cell, results: dict[str, CellResult]) -> CellResult:
    """The cell's result; a Ray-level failure (a worker died, a task raised) as a failed one."""
    try:
        return ray.get(ref)
    except Exception as error:
        upstream_failed = next(
            (results[u] for u in cell.upstream if u in results and not results[u].ok), None
        )
        if upstream_failed is not None:
            origin = upstream_failed.failed_cell or upstream_failed.id
            return CellResult(
                cell.id,
                cell.kind,
                ok=False,
                error=f"not run: {origin} failed: {upstream_failed.error}",
                failed_cell=origin,
            )
        return CellResult(
            cell.id,
            cell.kind,
            ok=False,
            error=f"Ray: {type(error).__name__}: {error}",
            failed_cell=cell.id,
        )


def _write_outputs(config: BenchmarkConfig, cells: dict[str, Cell], summary: Summary, out: Path):
    """``results.jsonl`` (rows of other grids in the same directory kept), ``curves.jsonl`` and
    ``config.json``, each replaced atomically."""
    rows = {row_key(r): r for r in read_jsonl(out / RESULTS_FILE)}
    for cid, cell in cells.items():
        if cell.kind == "eval" and cid in summary.results:
            convert = cells[cell.upstream[0]].upstream[0]  # eval <- train <- convert
            row = result_row(config, cell, summary.results[cid], summary.results.get(convert))
            rows[row_key(row)] = row
    write_jsonl(out / RESULTS_FILE, sorted(rows.values(), key=row_key))
    curves = []
    for cid, cell in cells.items():
        result = summary.results.get(cid)
        if cell.kind == "train" and result is not None and result.ok:
            curves += curve_rows(cell, result)
    write_jsonl(out / CURVES_FILE, curves)
    config_json = out / "config.json"
    tmp = config_json.with_name(f".config.json.tmp-{os.getpid()}")
    tmp.write_text(
        json.dumps({"written": time.strftime("%Y-%m-%dT%H:%M:%S"), **config.to_json()}, indent=1)
    )
    os.replace(tmp, config_json)
