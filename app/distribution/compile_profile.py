"""``python -m app.distribution.compile_profile``: where the warm-up's compile time goes.

Runs the warm-up's steps (``app/distribution/warmup.py``) in this one process against an
empty kernel cache (a fresh ``NUMBA_CACHE_DIR``), listening to numba's ``numba:compile``
event, and prints the kernels that cost the most. A kernel's compile nests the compiles of the
kernels it calls (they are typed as they are met), so each compile's own time is its span
minus its children's; numba's pass timers (``metadata["pipeline_times"]``) then split that
own time into type inference and the passes around it, and lowering (numba's LLVM IR, then
LLVM's optimisation and machine code). ``inline="always"`` callees compile no dispatcher of
their own: their cost is inside their callers' typing.

``--only TEXT`` keeps the steps whose label contains TEXT; ``--json PATH`` writes every
kernel's row.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field


@dataclass
class KernelCost:
    """What compiling one kernel cost, summed over its signatures."""
    name: str
    signatures: int = 0
    own: float = 0.0            # seconds, children excluded
    lowering: float = 0.0       # numba's lowering and LLVM
    typing: float = 0.0         # type inference, children excluded
    steps: set = field(default_factory=set)


class CompileTimer:
    """A ``numba.core.event`` listener summing each kernel's own compile time."""

    def __init__(self):
        self.kernels: dict[str, KernelCost] = {}
        self._stack: list[list] = []      # [dispatcher, args, start, children's seconds]
        self.step = ""

    def on_start(self, ev):
        self._stack.append([ev.data["dispatcher"], ev.data["args"], time.perf_counter(), 0.0])

    def on_end(self, ev):
        dispatcher, args, start, children = self._stack.pop()
        span = time.perf_counter() - start
        if self._stack:
            self._stack[-1][3] += span
        own = span - children
        name = f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__}"
        cost = self.kernels.setdefault(name, KernelCost(name))
        cost.signatures += 1
        cost.own += own
        cost.steps.add(self.step)
        lowering, typing = _pass_seconds(dispatcher, args)
        cost.lowering += lowering
        cost.typing += max(0.0, typing - children)

    def listener(self):
        from numba.core import event

        timer = self

        class _Listener(event.Listener):
            def on_start(self, ev):
                timer.on_start(ev)

            def on_end(self, ev):
                timer.on_end(ev)
        return _Listener()


def _pass_seconds(dispatcher, args) -> tuple[float, float]:
    """(lowering, type inference) seconds of the compile just finished, from numba's timers."""
    cres = dispatcher.overloads.get(tuple(args))
    times = getattr(cres, "metadata", {}).get("pipeline_times", {}).get("nopython", {})
    lowering = sum(t.run for name, t in times.items() if "lowering" in name)
    typing = sum(t.run for name, t in times.items() if "type_inference" in name)
    return lowering, typing


def profile(only: list[str] | None) -> tuple[CompileTimer, list[tuple[str, float]]]:
    """Run the warm-up's steps (those whose label contains one of ``only``) here, timing
    every compile; returns the timer and each step's seconds."""
    from numba.core import event

    from app.distribution.warmup_steps import all_steps
    timer = CompileTimer()
    event.register("numba:compile", timer.listener())
    steps = []
    for label, run in all_steps():
        if only and not any(text in label for text in only):
            continue
        timer.step = label
        start = time.perf_counter()
        run()
        steps.append((label, time.perf_counter() - start))
        print(f"  {steps[-1][1]:7.2f} s  {label}", file=sys.stderr, flush=True)
    return timer, steps


def report(timer: CompileTimer, steps, top: int) -> str:
    """The table: the ``top`` kernels by own compile time, then the totals."""
    rows = sorted(timer.kernels.values(), key=lambda k: -k.own)
    total = sum(k.own for k in rows)
    lines = [f"{'own s':>7} {'typing':>7} {'lower':>7} {'sigs':>4}  kernel",
             *(f"{k.own:7.2f} {k.typing:7.2f} {k.lowering:7.2f} {k.signatures:4d}  {k.name}"
               for k in rows[:top]),
             f"{total:7.2f} {sum(k.typing for k in rows):7.2f} "
             f"{sum(k.lowering for k in rows):7.2f} {sum(k.signatures for k in rows):4d}  "
             f"all {len(rows)} kernels; the steps took {sum(s for _, s in steps):.1f} s"]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m app.distribution.compile_profile")
    parser.add_argument("--only", action="append", default=None, metavar="TEXT")
    parser.add_argument("--top", type=int, default=20)
    parser.add_argument("--json", default=None, metavar="PATH")
    args = parser.parse_args(argv)
    if "numba" in sys.modules:
        parser.error("run it in a fresh process: numba is imported already")
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="fvd-compile-profile-")
    timer, steps = profile(args.only)
    print(report(timer, steps, args.top))
    if args.json:
        rows = [dict(vars(k), steps=sorted(k.steps)) for k in timer.kernels.values()]
        with open(args.json, "w") as out:
            json.dump({"kernels": rows, "steps": steps}, out, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
