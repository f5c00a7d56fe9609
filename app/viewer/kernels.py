"""Frames while the kernels compile in worker processes: draw what needs none, wait for the rest.

On a fresh clone (or after a pull that changed a kernel) numba's disk cache is cold. The window
does not compile in its own process then: it starts the warm-up (``python -m app warmup``) in
worker processes, one per core (:class:`app.distribution.warmup.BackgroundWarmup`), shows its
progress in the panel, and renders each frame under :func:`gated`:

- the frame is first tried with compiling refused on the render thread: numba announces each
  compile (a cache miss) with a ``numba:compile`` event before it starts, and the listener
  raises :class:`KernelsNotReady` there. A frame whose kernels are all cached (the default
  scene's wireframe needs none) is drawn at once, whatever the warm-up is doing;
- a frame that stopped so waits on the render thread, saying so, until the warm-up has
  compiled its file's first picture (the step ``--first`` puts ahead of all others) and then
  tries again, loading what the workers wrote; if it still misses a kernel (another renderer
  or shading) it waits for its file's step in every setting, then for the whole warm-up
  (:data:`STAGES`); once the warm-up has finished (or failed) nothing is refused and a
  kernel still missing compiles here, off the UI thread.

A newer request cancels the wait (:meth:`app.viewer.worker.Control.check`).
"""

from __future__ import annotations

import contextlib
import threading

_refusing = threading.local()
_listening: list[bool] = []


class KernelsNotReady(Exception):
    """A frame needed a kernel that is not in the disk cache yet (named in the message)."""


def _listen() -> bool:
    """Register the listener that refuses compiles on threads that ask it to (once)."""
    if _listening:
        return True
    try:
        from numba.core import event
    except ImportError:                  # no numba: nothing can compile, nothing to refuse
        return False

    class RefuseCompiles(event.Listener):
        def on_start(self, ev):
            if getattr(_refusing, "on", False):
                dispatcher = (ev.data or {}).get("dispatcher")
                name = getattr(getattr(dispatcher, "py_func", None), "__qualname__", "a kernel")
                raise KernelsNotReady(name)

        def on_end(self, ev):
            pass

    event.register("numba:compile", RefuseCompiles())
    _listening.append(True)
    return True


@contextlib.contextmanager
def compiles_refused():
    """Inside the block, a numba compile on this thread raises :class:`KernelsNotReady`."""
    _listen()
    before = getattr(_refusing, "on", False)
    _refusing.on = True
    try:
        yield
    finally:
        _refusing.on = before


# What a frame that found a kernel missing waits for, in turn: its file's first picture (the
# warm-up's --first step), the file's step in every renderer, shading and filter, everything.
STAGES = ("its first picture", "every setting of its file", "the whole warm-up")


def gated(run, warmup, scene_source: str | None, poll: float = 0.25):
    """``run(control)`` that draws at once when its kernels are cached and otherwise waits for
    ``warmup`` (a :class:`app.distribution.warmup.BackgroundWarmup`) as the module says."""

    def run_gated(control=None):
        stage = 0
        while not warmup.finished:
            try:
                with compiles_refused():
                    return run(control)
            except KernelsNotReady as missing:
                _wait(warmup, scene_source, control, str(missing), stage, poll)
                stage = min(stage + 1, len(STAGES) - 1)
        return run(control)

    return run_gated


def _wait(warmup, scene_source, control, kernel: str, stage: int, poll: float) -> None:
    """Until the warm-up has done what :data:`STAGES` ``[stage]`` names for ``scene_source``."""
    whole = stage == len(STAGES) - 1 or scene_source is None

    def ready():
        return warmup.finished or (not whole and warmup.ready_for(scene_source, stage == 1))

    while not ready():
        if control is not None:
            control.check()
            total = warmup.total or 0
            control.report(warmup.done / max(total, 1),
                           f"waiting for its kernels ({kernel}): {warmup.done} of "
                           f"{total or '?'} warm-up steps done in worker processes")
        if whole:
            warmup.wait(poll)
        else:
            warmup.wait_for(scene_source, poll, stage == 1)


def status(warmup) -> str:
    """The panel's line about the warm-up, or "" when there is none to speak of."""
    if warmup is None:
        return ""
    if warmup.finished:
        if warmup.ok:
            return "all kernels ready"
        failed = warmup.failed
        return (f"kernel warm-up failed ({failed[0] if failed else 'see the log'}): "
                "frames that need a missing kernel compile it here")
    return (f"compiling kernels in worker processes: {warmup.done} of {warmup.total or '?'} steps"
            + (f" ({', '.join(warmup.current)})" if warmup.current else ""))
