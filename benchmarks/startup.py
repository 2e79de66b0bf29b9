"""What a LeRobot command's start-up costs with and without compiled bytecode (.pyc).

Usage::

    .venv/bin/python benchmarks/startup.py [--rounds 3]

Every stage of the quick start is a new Python process (``rmb-collect``, ``rmb-convert``,
``lerobot-train`` and its data loader worker, ``lerobot-eval``), and each imports torch,
transformers and LeRobot. Where ``PYTHONDONTWRITEBYTECODE`` is set (as on these machines) and the
venv was installed without ``--compile-bytecode``, Python compiles all of that from source in
every process. This times the imports of ``lerobot-train`` (the module and our plugin) in a
fresh interpreter both ways, alternating: "source" points ``-X pycache_prefix`` at an empty
directory, so no .pyc is found (and none is written); "bytecode" uses the venv's own .pyc
files, as ``make setup`` (``uv sync --compile-bytecode``) leaves them. Prints wall and CPU
seconds (the child's user + system) and the ratio.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

IMPORTS = "import lerobot.scripts.lerobot_train, lerobot_env_rmb"


def run_once(no_bytecode: bool) -> tuple[float, float]:
    """Wall and CPU seconds of one fresh interpreter doing :data:`IMPORTS`."""
    with tempfile.TemporaryDirectory() as empty:
        flags = ["-X", f"pycache_prefix={empty}"] if no_bytecode else []
        env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "OMP_NUM_THREADS": "1"}
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        subprocess.run([sys.executable, *flags, "-c", IMPORTS], env=env, check=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3, help="alternating rounds; medians")
    args = parser.parse_args()
    results: dict[str, list[tuple[float, float]]] = {"source": [], "bytecode": []}
    for _ in range(args.rounds):
        for name in results:
            results[name].append(run_once(no_bytecode=name == "source"))
    print(f"`{IMPORTS}` in a fresh interpreter, {args.rounds} alternating rounds (medians)\n")
    print("| .pyc | wall s | CPU s | CPU ratio |")
    print("|---|---:|---:|---:|")
    base = statistics.median(cpu for _, cpu in results["source"])
    for name, runs in results.items():
        wall = statistics.median(w for w, _ in runs)
        cpu = statistics.median(c for _, c in runs)
        print(f"| {name} | {wall:.1f} | {cpu:.1f} | {cpu / base:.2f} |")


if __name__ == "__main__":
    main()
