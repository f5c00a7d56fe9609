"""``python -m app torques SCENE [--fps N] [--linkage NAME] [--csv FILE]``: inverse dynamics.

For each linkage of the scene whose links have masses (``mass`` on a ``[[linkage.joint]]``, or
a ``load``), one table of the keyed motion frame by frame: the time, each joint's angle and
the torque its motor must give (core.animation.inverse_dynamics: Newton–Euler).
``--csv`` writes every column, θ, θ' and θ'' included, for a plot or a hand check.
"""

from __future__ import annotations

import csv
import math
import sys
from pathlib import Path

import numpy as np

MAX_ROWS = 100_000


def add_arguments(parser) -> None:
    parser.add_argument("scene", help="a scene file with a [[linkage]] whose joints have masses")
    parser.add_argument("--fps", type=float, default=None,
                        help="rows a second (default: the animation's fps)")
    parser.add_argument("--linkage", default=None, help="only the linkage of this name")
    parser.add_argument("--csv", default=None, metavar="FILE",
                        help="write t and each joint's θ, θ', θ'' and τ (radians, N·m) here")


def _linkages(animation, name):
    from core.animation.linkage import Linkage
    return [m for m in animation.movers if isinstance(m, Linkage) and m.masses is not None
            and (name is None or m.name == name)]


def rows(linkage, times):
    """(t, θ, θ', θ'', τ) per time, the finite differences never straddling a key."""
    from core.animation.inverse_dynamics import STEP, torques_at
    keys = list(linkage.key_times)
    step = min([STEP] + [float(g) / 8 for g in np.diff(keys)])
    return [(t, *torques_at(linkage, linkage.masses, t, keys, step)) for t in times]


def jump_message(linkage, data) -> str | None:
    """One line where the solved motion jumps between two rows (inverse kinematics changing
    branch), naming the key before it; None where it is continuous. Keyed angles alone
    cannot jump (their tracks are continuous)."""
    from core.animation.inverse_dynamics import find_jump
    if linkage.target is None:
        return None
    for (t0, a0, *_), (t1, a1, *_) in zip(data, data[1:]):
        found = find_jump(linkage.angles_at, t0, t1, a0, a1)
        if found is None:
            continue
        t, before, after = found
        j = int(np.argmax(np.abs(after - before)))
        names = linkage.joint_names or [f"joint {k + 1}" for k in range(len(before))]
        where = ([w for k, w in linkage.key_places if k <= t] or [linkage.name])[-1]
        return (f"{where}: the inverse kinematics' solution jumps at t = {t:.6g} s ("
                f"{names[j]!r} from {math.degrees(before[j]):.1f} to "
                f"{math.degrees(after[j]):.1f} degrees at once): no finite torque makes that "
                "motion; key angles through it, or move the target so the arm need not turn over")
    return None


def _table(linkage, data) -> str:
    names = linkage.joint_names or [f"joint {j + 1}" for j in range(len(linkage.parent))]
    head = f"{'t (s)':>8}" + "".join(f"  {n[:12] + ' θ°':>15}  {'τ (N·m)':>10}" for n in names)
    lines = [f"linkage {linkage.name!r}: the joint torques of its keyed motion (gravity "
             f"{tuple(float(g) for g in linkage.masses.gravity)} m/s², load "
             f"{linkage.masses.load:g} kg)", head]
    for t, theta, _, _, tau in data:
        lines.append(f"{t:8.3f}" + "".join(f"  {math.degrees(a):15.3f}  {f:10.4f}"
                                           for a, f in zip(theta, tau)))
    return "\n".join(lines)


def _write_csv(path, found) -> None:
    with open(path, "w", newline="") as handle:
        out = csv.writer(handle)
        out.writerow(["linkage", "t", "joint", "theta", "theta_dot", "theta_ddot", "torque"])
        for linkage, data in found:
            for t, theta, d1, d2, tau in data:
                for j in range(len(theta)):
                    out.writerow([linkage.name, f"{t:.9g}", j + 1, f"{theta[j]:.12g}",
                                  f"{d1[j]:.12g}", f"{d2[j]:.12g}", f"{tau[j]:.12g}"])


def csv_problem(out: Path, scene: Path) -> str | None:
    """Why ``--csv`` cannot be written, or None: a table is replaced freely, nothing else."""
    from app.output_files import same_file
    if out.suffix.lower() != ".csv":
        return f"the name must end in .csv (got {out.suffix or 'no extension'!r})"
    if not out.parent.is_dir():
        return f"the folder {str(out.parent)!r} does not exist (it is not created)"
    if out.exists() and (not out.is_file() or same_file(out, scene)):
        return "it is a folder or the scene itself: it is kept"
    return None


def main(args) -> int:
    from app.loading import load_or_say
    from core.animation.keys import animation_of
    scene = load_or_say(args.scene)
    if scene is None:
        return 2
    animation = animation_of(scene)
    found = [] if animation is None else _linkages(animation, args.linkage)
    if not found:
        print(f"error: {args.scene}: no linkage with masses"
              + (f" named {args.linkage!r}" if args.linkage else "")
              + " (give its joints a mass, kg, for inverse dynamics)", file=sys.stderr)
        return 2
    if args.csv is not None:
        refusal = csv_problem(Path(args.csv), Path(args.scene))
        if refusal:
            print(f"error: --csv {args.csv}: {refusal}", file=sys.stderr)
            return 2
    fps = args.fps or animation.fps
    if not (0 < fps <= 10_000) or animation.duration * fps > MAX_ROWS:
        print(f"error: --fps {fps:g}: from above 0 to 10,000 rows a second, at most "
              f"{MAX_ROWS:,} rows (each row solves the linkage 3 to 5 times)", file=sys.stderr)
        return 2
    times = [k / fps for k in range(int(round(animation.duration * fps)) + 1)]
    results = [(linkage, rows(linkage, times)) for linkage in found]
    for linkage, data in results:
        message = jump_message(linkage, data)
        if message is not None:
            print(f"error: {message}", file=sys.stderr)
            return 2
    for linkage, data in results:
        print(_table(linkage, data))
    if args.csv:
        _write_csv(args.csv, results)
    return 0
