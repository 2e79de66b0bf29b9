"""Run a grid's cells on this machine without Ray: ``rmb-benchmark --executor local``.

For a machine where Ray cannot be installed (an offline GPU box that takes only carried wheels,
a platform without Ray wheels) or is not wanted. Same cells, records, resume and report as the
Ray runner; what Ray's scheduler does is done here with threads: a cell starts once every cell
it depends on has a result and the CPUs (and GPUs) it asks for are free, each running command
in a thread of its own. A cell asking for more than the machine has runs alone.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait

from rmb_lerobot.benchmark.cells import Cell, CellResult, execute


def visible_gpus() -> int:
    """CUDA devices torch sees (0 without torch or CUDA); asked only when a cell wants GPUs."""
    try:
        import torch
    except ImportError:
        return 0
    return torch.cuda.device_count() if torch.cuda.is_available() else 0


def run_locally(
    cells: dict[str, Cell],
    needed: Sequence[str],
    done: dict[str, CellResult],
    *,
    num_cpus: float,
    num_gpus: float | None = None,
) -> Iterator[tuple[str, CellResult]]:
    """Run the ``needed`` cells (dependency order) and yield ``(id, result)`` as each ends.

    Args:
        cells: every cell of the grid by id.
        needed: the ids to run, upstream cells before the cells that need them.
        done: results known before (cells finished in an earlier run); not modified.
        num_cpus: CPUs the running cells may ask for together.
        num_gpus: GPUs likewise; None counts the visible CUDA devices if a cell asks for one.

    Yields:
        Each cell's id and result, in the order they finish. A cell whose upstream cell failed
        yields the failure without running (as on Ray).

    Raises:
        ValueError: a cell needs a cell that is neither in ``needed`` nor in ``done``.
        KeyboardInterrupt: re-raised after every running command was stopped.
    """
    known = set(needed) | set(done)
    for cid in needed:
        missing = [u for u in cells[cid].upstream if u not in known]
        if missing:
            raise ValueError(f"{cid} needs {missing}, which are neither done nor to run")
    if num_gpus is None:
        num_gpus = visible_gpus() if any(cells[c].num_gpus for c in needed) else 0
    capacity = {"cpu": max(float(num_cpus), 1.0), "gpu": float(num_gpus)}
    results: dict[str, CellResult] = dict(done)
    waiting = list(needed)
    free = dict(capacity)
    cancel = threading.Event()
    running: dict[Future, tuple[str, dict[str, float]]] = {}

    def demand(cell: Cell) -> dict[str, float]:
        return {
            "cpu": min(cell.num_cpus, capacity["cpu"]),
            "gpu": min(cell.num_gpus, capacity["gpu"]),
        }

    with ThreadPoolExecutor(max_workers=max(1, len(needed)), thread_name_prefix="cell") as pool:
        try:
            while waiting or running:
                for cid in list(waiting):
                    cell = cells[cid]
                    if any(u not in results for u in cell.upstream):
                        continue  # upstream still running
                    need = demand(cell)
                    if any(need[k] > free[k] + 1e-9 for k in need):
                        continue  # a smaller cell further on may still fit
                    waiting.remove(cid)
                    for k in need:
                        free[k] -= need[k]
                    upstream = [results[u] for u in cell.upstream]
                    future = pool.submit(execute, cell, upstream, cancel)
                    running[future] = (cid, need)
                if not running:  # nothing fits and nothing runs: cannot happen with clamping
                    raise RuntimeError(f"no cell can start: {waiting[:3]} ...")
                # A timeout, so that a Ctrl-C is seen within it even when no real signal
                # interrupts the wait (e.g. _thread.interrupt_main).
                finished, _ = wait(running, timeout=0.5, return_when=FIRST_COMPLETED)
                for future in finished:
                    cid, need = running.pop(future)
                    for k in need:
                        free[k] += need[k]
                    results[cid] = future.result()
                    yield cid, results[cid]
        except BaseException:  # Ctrl-C, SIGTERM as KeyboardInterrupt, or the caller stopped
            cancel.set()  # every running command is terminated by its thread
            raise
