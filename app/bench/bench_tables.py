"""The bench's tables and its chart: the rows of ``python -m app bench`` as text (cases, thread
scaling, stages, start-up, depth complexity) and as a bar chart (``bench.png``)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np


def progress(text: str) -> None:
    """A bench's progress line, on stderr."""
    print(f"[bench] {text}", file=sys.stderr, flush=True)


# ----------------------------------------------------------------------------- output

def format_depth(depth: dict) -> str:
    lines = ["depth complexity (core.pipeline.raster.rasterize alone, median ms):"]
    for label, row in depth.items():
        ratio = f", {row['ratio']:.2f}x one layer" if "ratio" in row else ""
        lines.append(f"  {label:28s} {row['triangles']:>9,} triangles {row['median']:9.2f} ms{ratio}")
    return "\n".join(lines)


def _ms(stat: dict) -> str:
    return f"{stat['median']:9.2f} ({stat['min']:.2f}–{stat['max']:.2f})"


def format_table(rows: list[dict]) -> str:
    head = (f"{'scene':<20} {'triangles':>10} {'shading':<8} {'ours ms median (min–max)':>28} "
            f"{'fps':>7} {'llvmpipe ms median (min–max)':>30} {'ours/llvmpipe':>13} "
            f"{'CPU ms ours/llvmpipe':>21} {'lean GL ms':>10} {'ours/lean':>9} "
            f"{'floor ms':>8} {'ours/floor':>10}")
    lines = [head, "-" * len(head)]
    for r in rows:
        lean, floor = r.get("lean"), r.get("floor")
        lean_text = (f"{lean['median']:>10.2f} {r['ratio_lean']:>9.2f}" if lean
                     else f"{'—':>10} {'—':>9}")
        floor_text = (f"{floor['median']:>8.2f} {r['ratio_floor']:>10.2f}" if floor
                      else f"{'—':>8} {'—':>10}")
        lines.append(f"{r['scene']:<20} {r['triangles']:>10,} {r['shading']:<8} "
                     f"{_ms(r['ours']):>28} {r['ours_fps']:>7.1f} {_ms(r['llvmpipe']):>30} "
                     f"{r['ratio']:>13.2f} "
                     f"{r['ours']['cpu_median']:>10.1f}/{r['llvmpipe']['cpu_median']:<10.1f} "
                     f"{lean_text} {floor_text}")
    return "\n".join(lines)


def format_threads(rows: list[dict]) -> str:
    """Speed-up from one thread to all, per stage (medians of the same frames)."""
    lines = []
    for r in rows:
        scaling = r.get("threads")
        if not scaling:
            continue
        n = scaling["threads"]
        total = scaling["total"]
        parts = ", ".join(f"{name} {v['speedup']:.2f}x ({v['1']:.2f}→{v[str(n)]:.2f})"
                          for name, v in sorted(scaling["stages"].items(),
                                                key=lambda kv: -kv[1]["1"]))
        lines.append(f"{r['triangles']:>10,} {r['shading']:<8} 1→{n} threads: frame "
                     f"{total['speedup']:.2f}x ({total['1']:.2f}→{total[str(n)]:.2f} ms); {parts}")
    return "\n".join(lines)


def format_stages(rows: list[dict]) -> str:
    """Where our time goes: the CPU frame's stage medians, largest first, per case."""
    lines = []
    for r in rows:
        stages = sorted(r["ours"]["stages_ms"].items(), key=lambda kv: -kv[1])
        parts = ", ".join(f"{name} {ms:.2f}" for name, ms in stages)
        lines.append(f"{r['triangles']:>10,} {r['shading']:<8} upload {r['ours']['upload_ms']:.2f}; {parts} "
                     f"(llvmpipe readback, not in its time: {r['llvmpipe']['readback_ms']:.2f})")
    return "\n".join(lines)


def format_startup(startup: dict) -> str:
    lines = []
    jit = startup.get("jit", {})
    for key in ("cold", "warm"):
        probe = jit.get(key)
        if probe is None:
            continue
        if "error" in probe:
            lines.append(f"JIT {key} start: failed: {probe['error']}")
            continue
        firsts = ", ".join(f"{s} {ms:.0f} ms" for s, ms in probe["first_frame_ms"].items())
        lines.append(f"JIT {key} start: import {probe['import_ms']:.0f} ms, first frames {firsts}; "
                     f"process wall {probe['process_wall_ms']:.0f} ms")
    for name, ff in startup.get("first_frame_scenes", {}).items():
        if ff.get("measured"):
            lines.append(f"first picture of scenes/{name}: {ff['logged_s']:.2f} s after process "
                         f"start as logged (warm cache)")
        else:
            lines.append(f"first picture of scenes/{name}: not measured: {ff['reason']}")
    for key in ("first_frame_warm", "first_frame_warm_torus", "first_frame_cold"):
        ff = startup.get(key)
        if ff is None:
            continue
        label = ("python -m app" + (" scenes/torus.toml" if key.endswith("torus") else "")
                 + " to first frame shown" + (" (empty JIT cache)" if key.endswith("cold") else ""))
        if ff.get("measured"):
            cpu = f", {ff['cpu_s']:.2f} s CPU" if ff.get("cpu_s") is not None else ""
            lines.append(f"{label}: {ff['logged_s']:.2f} s after process start as logged{cpu}; "
                         f"{ff['wall_s']:.2f} s wall until the line appeared")
        else:
            lines.append(f"{label}: not measured: {ff['reason']}")
    return "\n".join(lines)


def write_chart(rows: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [f"{r['triangles']:,}\n{r['shading']}" for r in rows]
    x = np.arange(len(rows))
    ours = [r["ours"]["median"] for r in rows]
    gl = [r["llvmpipe"]["median"] for r in rows]
    fig, ax = plt.subplots(figsize=(max(6.0, 0.8 * len(rows) + 2), 4.5))
    width = 0.4
    for offset, values, key, name in ((-width / 2, ours, "ours", "ours (CPU pipeline + upload)"),
                                      (width / 2, gl, "llvmpipe", "llvmpipe (OpenGL, draw + finish)")):
        lo = [v - r[key]["min"] for v, r in zip(values, rows)]
        hi = [r[key]["max"] - v for v, r in zip(values, rows)]
        ax.bar(x + offset, values, width, yerr=[lo, hi], capsize=2, label=name)
    ax.set_yscale("log")
    ax.set_ylabel("frame time, ms (median, min–max)")
    ax.set_xticks(x, labels, fontsize=8)
    # sphere_torus_1000, sphere_torus_10000, ... → sphere_torus
    scene_names = sorted({re.sub(r"_\d+$", "", r["scene"]) for r in rows})
    ax.set_title(f"{', '.join(scene_names)}: {rows[0]['size'][0]} x {rows[0]['size'][1]}, "
                 f"{rows[0]['projection']}, ours vs llvmpipe")
    ax.legend()
    ax.grid(axis="y", which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
