# Two commands do all set-up on a fresh machine:
#   make run    the viewer on the default scene (PNG files instead when there is no display)
#   make test   the test suite
# Each creates .venv and installs what it needs the first time.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: run test bench report stability warmup clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	$(PY) -m app warmup    # compile every kernel once now, not in front of the user
	touch $(STAMP)

warmup: $(STAMP)
	$(PY) -m app warmup

run: $(STAMP)
	$(PY) -m app

test: $(STAMP)
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) -m app bench --out bench

report: $(STAMP)
	$(PY) -m app report --out report

stability: $(STAMP)
	$(PY) -m app stability

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis fvd-views screenshots
