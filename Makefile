# Everything runs inside ./.venv, made and filled on first use, so a fresh machine needs only python3 and make.
VENV ?= .venv
PY := $(VENV)/bin/python
# The CPU build of torch; a bare `torch` requirement would pull a multi-GB CUDA build.
TORCH ?= torch==2.13.0

.PHONY: install demo test lint bench docs
install: $(VENV)/.installed

# The venv with torch alone; each target below adds the package with the extras it needs.
$(VENV)/.torch-installed:
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q "$(TORCH)"
	touch $@

$(VENV)/.installed: pyproject.toml $(VENV)/.torch-installed
	$(PY) -m pip install -q -e ".[dev]"
	touch $@

# Under a minute: ~8,800 training episodes of TilePolicy (the CLI default), a greedy evaluation on 1,000 fresh
# players, and one episode as a GIF.
demo: install
	$(PY) -m sb3_aac.cli train --env RoboCupDribblePaper-v0 --timesteps 150000 --seed 0 --out runs/demo
	$(PY) -m sb3_aac.cli render runs/demo/model.zip --out runs/demo/episode.gif

test: install
	$(PY) -m pytest -q

# The gates CI runs after the tests: ruff (lint, then the format check) and mypy (strict; files and exceptions in
# pyproject.toml).
lint: install
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/mypy

bench: install
	$(PY) -m robocup_dribble.speed

# The documentation site, built into site/ with warnings as errors (as CI does). It needs the package and the docs
# extra only (not the dev extra). View it served, where its search works (a browser blocks the search of a page
# opened from disk): python -m http.server -d site 8000, then http://localhost:8000
docs: $(VENV)/.docs-installed
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict
	@echo "view it: $(PY) -m http.server -d site 8000, then open http://localhost:8000 (search works when served)"

$(VENV)/.docs-installed: pyproject.toml $(VENV)/.torch-installed
	$(PY) -m pip install -q -e ".[docs]"
	touch $@
