"""``python -m app bench --renderer bsp,depth-sort,zbuffer``: the painter's
algorithms against the z-buffer, the costs the notes weigh ("time & memory drawbacks of Z
buffer").

For the bench scene (a sphere plus a torus) at each ``--sizes`` count:

- the BSP tree for each root rule (first, random, fewest-splits): build time, nodes, splits,
  fragments, depth and the tree's memory;
- a frame of each renderer (median of ``--frames`` after ``--warmup``; the BSP tree already
  built and kept in the context, as the viewer keeps it), and the depth sort's tests and
  splits;
- memory: the z-buffer's per-pixel buffers (depth, triangle id, two barycentrics) against the
  BSP tree's arrays and the depth sort's per-frame arrays.

Wall times on a shared machine mostly measure the other processes; the CPU time of this
process is given beside them. Writes ``DIR/painters.json`` and ``DIR/painters.md`` (the
tables); prints them.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

RULES = ("first", "random", "fewest-splits")
PAINTERS = ("bsp", "depth-sort", "zbuffer")


def _progress(text: str) -> None:
    print(f"[bench] {text}", file=sys.stderr, flush=True)


def _tree_bytes(tree) -> int:
    return int(sum(a.nbytes for a in (tree.points, tree.recipe, tree.fragments, tree.source,
                                      tree.plane, tree.front, tree.back, tree.first, tree.count,
                                      tree.node_fragments)))


def _frame_ms(scene, settings, context, frames, warmup) -> tuple[float, dict]:
    from core.render import render
    times, cpu, frame = [], [], None
    for k in range(warmup + frames):
        start, start_cpu = time.perf_counter(), time.process_time()
        frame = render(scene, scene.views[0], settings, context)
        if k >= warmup:
            times.append((time.perf_counter() - start) * 1e3)
            cpu.append((time.process_time() - start_cpu) * 1e3)
    return float(np.median(times)), float(np.median(cpu)), frame.stats


def run(args, renderers: list[str]) -> int:
    from core.context import RenderContext
    from core.scene.generators import sphere_torus as bench_scene      # the bench's scene
    from core.shading.shade import geometry
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    width, height = args.size
    shading = args.shading[0]
    rows, trees = [], []
    if "bsp" in renderers:                       # load the compiled build before timing it
        _build_trees(*geometry(bench_scene(triangles=1000), RenderContext()))
    for count in args.sizes:
        scene = bench_scene(triangles=count)
        triangles = scene.triangle_count
        context = RenderContext()
        positions, tris = geometry(scene, context)
        if "bsp" in renderers:
            trees += _tree_rows(positions, tris, triangles)
        for name in renderers:
            rows.append(_frame_row(args, scene, name, shading, context, trees))
    result = {"size": [width, height], "projection": args.projection, "shading": shading,
              "trees": trees, "frames": rows}
    (out / "painters.json").write_text(json.dumps(result, indent=2))
    text = format_tables(result)
    (out / "painters.md").write_text(text)
    print(text)
    return 0


def _build_trees(positions, tris) -> None:
    from core.visibility import bsp
    for rule in RULES:
        bsp.build(positions, tris, rule)


def _tree_rows(positions, tris, triangles: int) -> list[dict]:
    """The BSP tree of each root rule: its build's numbers and its memory."""
    from core.visibility import bsp
    trees = []
    for rule in RULES:
        _progress(f"{triangles} triangles: BSP tree, root rule {rule} ...")
        tree = bsp.build(positions, tris, rule)
        trees.append({"triangles": triangles, **tree.stats(), "tree_bytes": _tree_bytes(tree)})
    return trees


def _frame_row(args, scene, name: str, shading: str, context, trees: list[dict]) -> dict:
    """One renderer's frames of the scene: the first (tree built, kernels loaded), the median
    after it, and what it keeps in memory."""
    from core.render import render
    from core.settings import RenderSettings
    triangles = scene.triangle_count
    _progress(f"{triangles} triangles: {name} frames ...")
    settings = RenderSettings.for_scene(scene, renderer=name, shading=shading,
                                        projection=args.projection, size=args.size)
    first = time.perf_counter()
    render(scene, scene.views[0], settings, context)        # builds the tree, compiles
    first_ms = (time.perf_counter() - first) * 1e3
    ms, cpu_ms, stats = _frame_ms(scene, settings, context, args.frames, args.warmup)
    row = {"triangles": triangles, "renderer": name, "shading": shading,
           "first_frame_ms": first_ms, "frame_ms": ms, "frame_cpu_ms": cpu_ms,
           "painted": stats.get("painted"), "stage_ms": stats.get("ms", {})}
    width, height = args.size
    if name == "zbuffer":
        row["memory_bytes"] = width * height * (8 + 4 + 8 + 8)   # depth, tri, b1, b2
    if name == "depth-sort":
        row["depth_sort"] = stats.get("depth sort")
        row["memory_bytes"] = int(stats["painted"]) * (3 * 8 * 4 + 8 * 8)
    if name == "scanline":
        row["scan_line"] = stats.get("scan line")
        counts = row["scan_line"] or {}       # PT: 9 ints, 4 floats; ET: 9 ints
        row["memory_bytes"] = (counts.get("polygons", 0) * 13 * 8
                               + counts.get("edges", 0) * 9 * 8)
    if name == "bsp":
        tree_stats = stats.get("BSP tree", {})
        row["bsp"] = tree_stats
        row["memory_bytes"] = next((t["tree_bytes"] for t in trees
                                    if t["triangles"] == triangles
                                    and t["rule"] == tree_stats.get("rule")), None)
    return row


def format_tables(result: dict) -> str:
    w, h = result["size"]
    lines = ["## BSP trees (sphere + torus; build once per scene)", "",
             "| triangles | root rule | build ms (wall) | build ms (CPU) | nodes | splits | "
             "fragments | depth | tree MB |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for t in result["trees"]:
        lines.append(f"| {t['triangles']} | {t['rule']} | {t['build ms']:.0f} | "
                     f"{t['build cpu ms']:.0f} | {t['nodes']} | "
                     f"{t['splits']} | {t['fragments']} | {t['depth']} | "
                     f"{t['tree_bytes'] / 1e6:.2f} |")
    lines += ["", f"## Frames ({w} x {h}, {result['projection']}, {result['shading']}; median)", "",
              "| triangles | renderer | frame ms | frame CPU ms | first frame ms | painted | "
              "memory MB | notes |",
              "|---:|---|---:|---:|---:|---:|---:|---|"]
    for r in result["frames"]:
        notes = ""
        if r["renderer"] == "depth-sort" and r.get("depth_sort"):
            d = r["depth_sort"]
            beyond, before = d["P beyond Q's plane"], d["Q before P's plane"]
            notes = (f"tests: z {d['z extents']}, x {d['x extents']}, y {d['y extents']}, "
                     f"planes {beyond}+{before}, projections {d['projections']}; "
                     f"moves {d['moves']}, splits {d['splits']}")
        if r["renderer"] == "bsp" and r.get("bsp"):
            notes = f"tree: {r['bsp'].get('rule')}, kept in the context"
        if r["renderer"] == "zbuffer":
            notes = "depth + triangle id + 2 barycentrics per pixel"
        if r["renderer"] == "scanline" and r.get("scan_line"):
            c = r["scan_line"]
            notes = (f"tables (PT + ET); AET up to {c['largest AET']}, {c['spans']} spans "
                     f"({c['one-polygon spans']} with one polygon), {c['depth evaluations']} "
                     f"depth evaluations, {c['penetration splits']} cuts")
        memory = r.get("memory_bytes")
        lines.append(f"| {r['triangles']} | {r['renderer']} | {r['frame_ms']:.1f} | "
                     f"{r['frame_cpu_ms']:.1f} | "
                     f"{r['first_frame_ms']:.0f} | {r['painted']} | "
                     f"{'' if memory is None else f'{memory / 1e6:.2f}'} | {notes} |")
    return "\n".join(lines) + "\n"
