# Two entry points (see README): `make demo` runs the main job, `make test` the test suite.
# Each installs what it needs: Python 3.12 comes from .python-version (pyenv), everything else
# from uv.lock into .venv. Nothing here depends on packages installed by hand.
SHELL := /bin/bash
.DEFAULT_GOAL := help

PYTHON ?= python3
# Only package registries are reachable: never let uv try to download an interpreter.
export UV_PYTHON_DOWNLOADS := never
# Headless rendering (no display on these machines); a user's own setting wins.
export MUJOCO_GL ?= egl
export PYOPENGL_PLATFORM ?= $(MUJOCO_GL)
VENV := .venv
# Optional extras the test suite exercises (VLA policies to their download boundary, MT-ACT's
# sentence encoder, rmb-benchmark on Ray, rmb-data view, the PyBullet TACTO envs, the GELLO
# servo SDK that talks to a fake servo chain on a pty). `keyboard` (Linux input devices) and
# `spacemouse` (system hidapi) are left out: their tests use test doubles. The `docs` group builds the docs site (`make docs`, and
# `make test` builds it --strict).
EXTRAS := --extra vla --extra text --extra benchmark --extra viz --extra pybullet --extra gello --group docs
# The stamp's name changes when the way of syncing does, so an existing venv re-syncs once.
STAMP := $(VENV)/.synced-bytecode

.PHONY: help setup demo test lint docs docs-check format bench bench-learning bench-grid clean

help:
	@echo "make demo   - the main job (quick start)"
	@echo "make test   - lint + the docs build (--strict) + the test suite"
	@echo "make docs   - build the docs site into site/ and say where to open it"
	@echo "make bench  - benchmarks (results go to benchmarks/RESULTS.md by hand)"
	@echo "make bench-learning - train and evaluate every policy from scripted demos (about 1 h+)"
	@echo "make bench-grid - the benchmark grid of benchmarks/grid_small.yaml on local Ray (hours)"

# Re-sync whenever the lock or the project metadata changes. --compile-bytecode writes every
# package's .pyc once at install: where PYTHONDONTWRITEBYTECODE is set (as on these machines)
# Python would otherwise compile torch, transformers and LeRobot from source in every process,
# ~20 CPU s per lerobot-train / lerobot-eval / rmb-convert start (benchmarks/RESULTS.md).
$(STAMP): pyproject.toml uv.lock .python-version
	$(PYTHON) -m uv --version >/dev/null 2>&1 || $(PYTHON) -m pip install --quiet "uv>=0.9,<1"
	$(PYTHON) -m uv sync --locked --compile-bytecode $(EXTRAS)
	touch $@

setup: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/rmb-quickstart --out outputs/quickstart

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

# Two workers, one torch/OpenMP thread each (subprocesses inherit it): more threads than free
# cores makes OpenMP crawl.
test: lint docs-check
	OMP_NUM_THREADS=1 $(VENV)/bin/python -m pytest -n 2 --durations=15

# The docs site (mkdocs.yml, docs/): --strict turns every warning (a broken link, a missing
# API reference, a docstring that does not parse) into a failure.
docs-check: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --quiet --site-dir site

docs: docs-check
	@echo "docs built: open file://$(CURDIR)/site/index.html (or run: $(VENV)/bin/mkdocs serve)"

format: $(STAMP)
	$(VENV)/bin/ruff format .
	$(VENV)/bin/ruff check --fix .

bench: $(STAMP)
	$(VENV)/bin/python benchmarks/depth_codecs.py
	$(VENV)/bin/python benchmarks/env_step.py
	$(VENV)/bin/python benchmarks/expert_success.py
	$(VENV)/bin/python benchmarks/convert.py
	$(VENV)/bin/python benchmarks/loader.py
	$(VENV)/bin/python benchmarks/policies.py

bench-learning: $(STAMP)
	$(VENV)/bin/python benchmarks/learning.py

bench-grid: $(STAMP)
	$(VENV)/bin/rmb-benchmark benchmarks/grid_small.yaml

clean:
	rm -rf outputs .pytest_cache site
