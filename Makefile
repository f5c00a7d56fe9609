# Two commands do all set-up on a fresh machine:
#   make run    the viewer on the default scene (PNG files instead when there is no display)
#   make test   the test suite
# Each creates .venv and installs what it needs the first time.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
WARM   := $(VENV)/.warm
# The files that define numba kernels: when one changes (an edit, a pull), the kernels are
# compiled again here, not in front of the user (core.jit ties every cached kernel to them).
KERNELS := $(shell grep -rl --include='*.py' 'core.jit import' core app 2>/dev/null) core/jit.py

.PHONY: run test bench report stability warmup clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

$(WARM): $(STAMP) $(KERNELS)
	$(PY) -m app warmup    # compile every kernel once now, not in front of the user
	touch $(WARM)

warmup: $(STAMP)
	$(PY) -m app warmup
	touch $(WARM)

run: $(WARM)
	$(PY) -m app

test: $(WARM)
	$(PY) -m pytest -q

bench: $(WARM)
	$(PY) -m app bench --out bench

report: $(WARM)
	$(PY) -m app report --out report

stability: $(WARM)
	$(PY) -m app stability

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis fvd-views screenshots
