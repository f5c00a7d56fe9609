# Two commands do all set-up on a fresh machine:
#   make run    the viewer on the default scene (PNG files instead when there is no display)
#   make test   the test suite
# Each creates .venv and installs what it needs the first time.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
TESTED := $(VENV)/.installed-test
WARM   := $(VENV)/.warm
# The files that define numba kernels: when one changes (an edit, a pull), the warm-up runs
# again here, not in front of the user, and compiles the kernels whose code changed and those
# that call them (core.jit.kernel_digest); it loads the rest.
KERNELS := $(shell grep -rl --include='*.py' 'core.jit import' core app 2>/dev/null) core/jit.py

.PHONY: run test bench report stability warmup clean

# What running needs (the viewer, `animate`'s movies); the tests' oracles (Embree, Mitsuba,
# scikit-image, pytest) only with `make test`.
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[anim]'
	touch $(STAMP)

$(TESTED): $(STAMP)
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(TESTED)

# The warm-up compiles on one worker process a core (JOBS=N for another number); when its
# stamp says this code's kernels are all cached already (app/distribution/warm_stamp.py) it is
# skipped, e.g. after a checkout that touched the kernel files but left them as they were.
WARMUP := $(PY) -m app.distribution.warmup $(if $(JOBS),--jobs $(JOBS))
IS_WARM := $(PY) -c "import sys; from app.distribution.warm_stamp import is_warm; sys.exit(not is_warm())"

$(WARM): $(STAMP) $(KERNELS)
	$(IS_WARM) || $(WARMUP)    # compile every kernel once now, not in front of the user
	touch $(WARM)

warmup: $(STAMP)
	$(WARMUP)
	touch $(WARM)

# The window opens at once: on a cold kernel cache it starts the warm-up in worker processes
# itself and draws each frame as soon as its kernels are ready (app/viewer/kernels.py).
run: $(STAMP)
	$(PY) -m app

test: $(TESTED) $(WARM)
	$(PY) -m pytest -q

bench: $(TESTED) $(WARM)
	$(PY) -m app bench --out bench

report: $(TESTED) $(WARM)
	$(PY) -m app report --out report

stability: $(TESTED) $(WARM)
	$(PY) -m app stability

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis fvd-views screenshots
