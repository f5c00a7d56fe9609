"""``python -m app report --out DIR [--quick]``: error against run time.

Runs the sweep of :mod:`core.analysis.accuracy` (``--quick``: the reduced one the tests use) with a
progress line per setting on stderr, then writes

- ``DIR/error_vs_time.csv``: one row per setting;
- ``DIR/error_vs_time.md``: a short reading at the top (which setting to choose for a frame-time
  budget), how to read the table, then the table;
- ``DIR/error_vs_time.png``: log-log, run time on x and RMSE on y, one panel per scene, one
  colour per shading mode (one line per samples-a-pixel, through the tessellation levels), the
  Pareto front marked.
"""

from __future__ import annotations

import csv
import os
import platform
import sys
import time
from pathlib import Path

from core.analysis import accuracy
from core.analysis.accuracy import Point

COLOURS = {"flat": "tab:orange", "gouraud": "tab:green", "phong": "tab:blue",
           "gouraud scanline": "tab:red", "gouraud bsp": "tab:purple",       # the painters
           "gouraud depth-sort": "tab:brown"}
MARKERS = {1: "o", 4: "s", 16: "^"}
LINES = {1: "-", 4: "--", 16: ":"}


def write_csv(points: list[Point], path: Path) -> None:
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=accuracy.COLUMNS)
        writer.writeheader()
        for row in accuracy.as_rows(points):
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})


def markdown_table(points: list[Point]) -> str:
    head = ("| scene | shading | level | triangles | samples/pixel | time ms (median of n) | "
            "fastest ms | RMSE | max error | RMSE inside | coverage differs | Pareto |")
    rule = "|" + "---|" * 12
    rows = [head, rule]
    for p in sorted(points, key=lambda p: (accuracy.SCENES.index(p.scene), p.shading != "flat",
                                           p.shading != "gouraud", p.level, p.samples)):
        rows.append(f"| {p.scene} | {p.shading} | {p.level} | {p.triangles} | {p.samples} | "
                    f"{p.ms:.1f} ({p.frames}) | {p.ms_min:.1f} | {p.rmse:.2f} | {p.max_error:.0f} | "
                    f"{p.rmse_inside:.2f} | {100 * p.coverage_differs:.2f}% | "
                    f"{'**yes**' if p.pareto else ''} |")
    return "\n".join(rows)


def _load() -> str:
    try:
        return "load average %.1f" % os.getloadavg()[0]
    except OSError:
        return "load average unknown"


def write_markdown(points: list[Point], config: accuracy.SweepConfig, wall: float,
                   path: Path, load: str = "") -> None:
    size = f"{config.size} x {config.size}"
    text = [
        "# Error against run time",
        "",
        f"`python -m app report` ({'quick' if config == accuracy.QUICK else 'default'} sweep): "
        f"{size} pixels, {len(points)} settings, {wall:.0f} s wall time on "
        f"{os.cpu_count()} cores ({platform.machine()}; {load or _load()} when it began, "
        f"{_load()} at the end), {time.strftime('%Y-%m-%d')}. Errors on "
        f"the 0–255 scale against the exact image (the true surface, float64, 16 samples a "
        f"pixel).",
        "",
        "## Reading",
        "",
        *[f"- {line}" for line in accuracy.reading(points)],
        "",
        "## How to read the table",
        "",
        "- *level*: the tessellation (sphere: `level` rings and `2 level` segments; torus: "
        "`level` sides around the tube and `2 level` around the ring).",
        "- *samples/pixel*: the pipeline rendered at 1, 2 or 4 times the size and box-filtered "
        "(1, 4, 16 samples a pixel).",
        "- *time*: median frame time (render and box filter) over the *n* timed frames, in the "
        "steady state of a viewer (caches filled), taken round-robin over the settings of one "
        "size; *fastest*: the quickest of those frames, what the setting costs when nothing else "
        "runs (the machine is shared, and a busy core slows the two-thread kernels most).",
        "- *RMSE* and *max error*: over every pixel and channel of the image; *RMSE inside*: over "
        "the pixels both images cover fully, i.e. the shading error without the silhouette.",
        "- *coverage differs*: the pixels where the number of samples that see the surface "
        "differs from the exact surface's at the same sample points (tessellation changes the "
        "silhouette); more samples a pixel give more chances to differ.",
        "- *Pareto*: no other setting of the same scene is both faster and more accurate.",
        "",
        "## Table",
        "",
        markdown_table(points),
        "",
    ]
    path.write_text("\n".join(text))


def write_plot(points: list[Point], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FuncFormatter

    scenes = [s for s in accuracy.SCENES if any(p.scene == s for p in points)]
    fig, axes = plt.subplots(1, len(scenes), figsize=(6.2 * len(scenes), 5.4), squeeze=False)
    samples = sorted({p.samples for p in points})
    for ax, scene in zip(axes[0], scenes):
        mine = [p for p in points if p.scene == scene]
        for shading in accuracy.SHADINGS:
            for s in samples:
                line = sorted((p for p in mine if p.shading == shading and p.samples == s),
                              key=lambda p: p.level)
                if not line:
                    continue
                ax.plot([p.ms for p in line], [p.rmse for p in line], color=COLOURS[shading],
                        linestyle=LINES.get(s, "-"), marker=MARKERS.get(s, "o"), markersize=5,
                        linewidth=1.3, alpha=0.9)
                if s == samples[0]:
                    for p in line:            # label the levels once per mode
                        ax.annotate(str(p.level), (p.ms, p.rmse), textcoords="offset points",
                                    xytext=(4, 3), fontsize=7, color=COLOURS[shading])
        front = sorted((p for p in mine if p.pareto), key=lambda p: p.ms)
        ax.step([p.ms for p in front], [p.rmse for p in front], where="post", color="black",
                linewidth=1.0, alpha=0.7)
        ax.scatter([p.ms for p in front], [p.rmse for p in front], s=110, facecolors="none",
                   edgecolors="black", linewidths=1.2, zorder=5)
        ax.set_xscale("log")
        ax.set_yscale("log")
        plain = FuncFormatter(lambda v, _: f"{v:g}")
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(plain)
            axis.set_minor_formatter(FuncFormatter(
                lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "25" else ""))
        ax.set_title(f"{scene}: RMSE against frame time")
        ax.set_xlabel("frame time, ms (median; render + box filter)")
        ax.set_ylabel("RMSE against the exact image (0–255)")
        ax.grid(True, which="both", alpha=0.25)
    handles = [Line2D([], [], color=c, linewidth=2, label=m.capitalize()) for m, c in COLOURS.items()]
    handles += [Line2D([], [], color="grey", linestyle=LINES.get(s, "-"), marker=MARKERS.get(s, "o"),
                       label=f"{s} sample{'s' if s > 1 else ''}/pixel") for s in samples]
    handles.append(Line2D([], [], color="black", marker="o", markerfacecolor="none", markersize=10,
                          label="Pareto front"))
    handles.append(Line2D([], [], linestyle="none", label="numbers: tessellation level"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=8,
               frameon=False)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(args) -> int:
    out = Path(getattr(args, "out", None) or "report")
    config = accuracy.QUICK if getattr(args, "quick", False) else accuracy.DEFAULT
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        print(f"error: cannot create {out}: {error}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    load = _load()
    steps = len(accuracy.settings(config))
    print(f"report: {steps} settings at {config.size} x {config.size}"
          f"{' (quick)' if config == accuracy.QUICK else ''}", file=sys.stderr, flush=True)
    points = accuracy.sweep(config, progress=lambda line: print(line, file=sys.stderr, flush=True))
    wall = time.perf_counter() - start
    paths = (out / "error_vs_time.csv", out / "error_vs_time.md", out / "error_vs_time.png")
    try:
        write_csv(points, paths[0])
        write_markdown(points, config, wall, paths[1], load)
        write_plot(points, paths[2])
    except OSError as error:
        print(f"error: cannot write the report into {out}: {error}", file=sys.stderr)
        return 2
    try:
        from app.reports.mach_report import write as mach_bands
        paths += tuple(mach_bands(out, progress=lambda line: print(line, file=sys.stderr,
                                                                     flush=True)))
    except OSError as error:
        print(f"error: cannot write the report into {out}: {error}", file=sys.stderr)
        return 2
    if config != accuracy.QUICK:     # the texture and ray-traced rows (the quick sweep has none)
        from app.reports.raytrace_report import write as raytrace_rows
        from app.reports.texture_report import write as texture_rows
        say = lambda line: print(line, file=sys.stderr, flush=True)  # noqa: E731
        paths += tuple(texture_rows(out, progress=say))
        paths += tuple(raytrace_rows(out, config.size, cache=config.cache, progress=say))
        from app.reports.raytrace_report import write_adaptive          # adaptive supersampling
        paths += tuple(write_adaptive(out, progress=say))
        from app.reports.volume_report import write as volume_rows
        paths += tuple(volume_rows(out, progress=say))
    for line in accuracy.reading(points):
        print(line)
    print(f"wrote {', '.join(str(p) for p in paths)} ({wall:.0f} s sweep)")
    return 0
