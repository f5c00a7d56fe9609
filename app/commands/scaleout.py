"""The scale-out measurement: ``animate`` in one process against ``--workers N``, each run as
a user runs it (a fresh ``python -m app animate`` process, cluster start included), with the
CPU time the runs used, the load average before each (other processes on a small machine
change every number here), what ``--workers`` decided, and whether the frames are identical.
The two commands alternate, ``--repeats`` times each; the row shows the medians.

``python -m app.commands.scaleout [SCENE ...] [--frames 240] [--size 500x500] [--workers 2]
[--repeats 3]``
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SCENES = ("scenes/fountain.toml", "scenes/house_flyaround.toml")


def _run(command: list[str]) -> dict:
    """Wall and CPU seconds (user + system, the process and its children) of one command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {done.stderr.strip()[-500:]}")
    return {"wall": wall, "cpu": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "load_before": load, "load_after": os.getloadavg()[0],
            "log": (done.stderr + done.stdout).strip()}


def _median_run(runs: list[dict]) -> dict:
    """The run of median wall time (its CPU and load with it), and every wall time."""
    ordered = sorted(runs, key=lambda r: r["wall"])
    middle = dict(ordered[(len(ordered) - 1) // 2])
    middle["walls"] = [r["wall"] for r in runs]
    middle["median_wall"] = statistics.median(middle["walls"])
    return middle


def _same_frames(a: Path, b: Path, frames: int) -> bool:
    from PIL import Image
    one, many = sorted(a.glob("frame_*.png")), sorted(b.glob("frame_*.png"))
    return len(one) == len(many) == frames and all(
        np.array_equal(np.asarray(Image.open(x)), np.asarray(Image.open(y)))
        for x, y in zip(one, many))


def compare(scene: Path, frames: int, size=(500, 500), workers: int = 2, repeats: int = 1) -> dict:
    """One row: the same movie in one process and on ``workers`` renderers, alternating."""
    ones, manys, same, movies_same = [], [], True, True
    for _ in range(repeats):
        with tempfile.TemporaryDirectory(prefix="fvd-scaleout-") as tmp:
            base = [sys.executable, "-m", "app", "animate", str(scene), "--frames", str(frames),
                    "--size", f"{size[0]}x{size[1]}", "--keep-frames"]
            ones.append(_run(base + ["--out", f"{tmp}/one.mp4"]))
            manys.append(_run(base + ["--out", f"{tmp}/many.mp4", "--workers", str(workers)]))
            same &= _same_frames(Path(tmp, "one.frames"), Path(tmp, "many.frames"), frames)
            movies_same &= Path(tmp, "one.mp4").read_bytes() == Path(tmp, "many.mp4").read_bytes()
    one, many = _median_run(ones), _median_run(manys)
    return {"scene": scene.name, "size": list(size), "frames": frames, "workers": workers,
            "repeats": repeats, "one": one, "many": many,
            "speedup": one["median_wall"] / many["median_wall"],
            "identical_frames": same, "identical_movies": movies_same, "cpus": os.cpu_count()}


def format_row(row: dict) -> str:
    one, many = row["one"], row["many"]
    # what --workers did: its note when it declined, else where the frames were rendered
    lines = many["log"].splitlines()
    where = [line for line in lines if "rendered in" in line] + [line for line in lines if "note:" in line]
    runs = f", median of {row['repeats']}" if row.get("repeats", 1) > 1 else ""
    return (f"animate {row['scene']}, {row['frames']} frames of {row['size'][0]} x {row['size'][1]}"
            f"{runs}: 1 process {one['median_wall']:.1f} s (CPU {one['cpu']:.1f} s, load "
            f"{one['load_before']:.1f}), --workers {row['workers']} {many['median_wall']:.1f} s "
            f"(CPU {many['cpu']:.1f} s, load {many['load_before']:.1f}): x{row['speedup']:.2f}; "
            f"frames {'identical' if row['identical_frames'] else 'DIFFER'}, movies "
            f"{'byte-identical' if row['identical_movies'] else 'differ'}"
            + (f"\n    {where[-1].strip()}" if where else ""))


def main(argv=None) -> int:
    import argparse
    import json

    p = argparse.ArgumentParser(prog="python -m app.commands.scaleout")
    p.add_argument("scenes", nargs="*", default=list(SCENES))
    p.add_argument("--frames", type=int, default=240)
    p.add_argument("--size", type=lambda t: tuple(int(x) for x in t.lower().split("x")),
                   default=(500, 500), help="WxH")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--repeats", type=int, default=1, help="runs of each command (median)")
    p.add_argument("--json", default=None, help="also write the rows here")
    args = p.parse_args(argv)
    rows = []
    for scene in args.scenes:
        rows.append(compare(Path(scene), args.frames, args.size, args.workers, args.repeats))
        print(format_row(rows[-1]), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
