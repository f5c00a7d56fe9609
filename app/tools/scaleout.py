"""The scale-out measurement: ``animate`` in one process against ``--workers N``, each run as
a user runs it (a fresh ``python -m app animate`` process, cluster start included), with the
CPU time the runs used, the load average around them (other processes on a small machine
change every number here), and whether the frames are identical.

``python -m app.tools.scaleout [SCENE ...] [--frames 240] [--size 500x500] [--workers 2]``
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


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
    return {"wall": wall, "user": after.ru_utime - before.ru_utime,
            "system": after.ru_stime - before.ru_stime, "load_before": load,
            "load_after": os.getloadavg()[0], "log": (done.stderr + done.stdout).strip()}


def compare(scene: Path, frames: int, size=(500, 500), workers: int = 2) -> dict:
    """One row: the same movie in one process and on ``workers`` local workers."""
    from PIL import Image
    with tempfile.TemporaryDirectory(prefix="fvd-scaleout-") as tmp:
        base = [sys.executable, "-m", "app", "animate", str(scene), "--frames", str(frames),
                "--size", f"{size[0]}x{size[1]}", "--keep-frames"]
        one = _run(base + ["--out", f"{tmp}/one.mp4"])
        many = _run(base + ["--out", f"{tmp}/many.mp4", "--workers", str(workers)])
        same = all(np.array_equal(np.asarray(Image.open(a)), np.asarray(Image.open(b)))
                   for a, b in zip(sorted(Path(tmp, "one.frames").glob("frame_*.png")),
                                   sorted(Path(tmp, "many.frames").glob("frame_*.png"))))
        count = len(list(Path(tmp, "many.frames").glob("frame_*.png")))
        movies_same = Path(tmp, "one.mp4").read_bytes() == Path(tmp, "many.mp4").read_bytes()
    return {"scene": scene.name, "size": list(size), "frames": frames, "workers": workers,
            "one": one, "many": many, "speedup": one["wall"] / many["wall"],
            "identical_frames": same and count == frames, "identical_movies": movies_same,
            "cpus": os.cpu_count()}


def format_row(row: dict) -> str:
    one, many = row["one"], row["many"]
    where = [line for line in many["log"].splitlines() if "rendered in" in line or "note:" in line]
    return (f"animate {row['scene']}, {row['frames']} frames of {row['size'][0]} x {row['size'][1]}: "
            f"1 process {one['wall']:.1f} s (CPU {one['user'] + one['system']:.1f} s, load "
            f"{one['load_before']:.1f}), --workers {row['workers']} {many['wall']:.1f} s (CPU "
            f"{many['user'] + many['system']:.1f} s, load {many['load_before']:.1f}): "
            f"x{row['speedup']:.2f}; frames {'identical' if row['identical_frames'] else 'DIFFER'}, "
            f"movies {'byte-identical' if row['identical_movies'] else 'differ'}"
            + (f"\n    {where[-1].strip()}" if where else ""))


def main(argv=None) -> int:
    import argparse
    import json

    p = argparse.ArgumentParser(prog="python -m app.tools.scaleout")
    p.add_argument("scenes", nargs="*", default=["scenes/fountain.toml", "scenes/house_flyaround.toml"])
    p.add_argument("--frames", type=int, default=240)
    p.add_argument("--size", type=lambda t: tuple(int(x) for x in t.lower().split("x")),
                   default=(500, 500), help="WxH")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--json", default=None, help="also write the rows here")
    args = p.parse_args(argv)
    rows = []
    for scene in args.scenes:
        rows.append(compare(Path(scene), args.frames, args.size, args.workers))
        print(format_row(rows[-1]), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
