# Everything runs inside ./.venv, made and filled on first use, so a fresh machine needs only python3 and make.
VENV ?= .venv
PY := $(VENV)/bin/python
# The CPU build of torch; a bare `torch` requirement would pull a multi-GB CUDA build.
TORCH ?= torch==2.13.0

.PHONY: install demo test bench
install: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q "$(TORCH)"
	$(PY) -m pip install -q -e ".[dev]"
	touch $@

demo: install
	$(PY) -m sb3_aac.cli train --env RoboCupDribblePaper-v0 --episodes 3000 --seed 0 --out runs/demo

test: install
	$(PY) -m pytest -q

bench: install
	$(PY) benchmarks/env_speed.py
