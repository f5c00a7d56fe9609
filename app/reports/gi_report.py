"""The global-illumination report: ``python -m app.reports.gi_report --out docs/report``.

Writes ``global_illumination.md``, ``.csv`` and ``.png`` into the folder:

1. form factors against Howell's closed forms (parallel squares, perpendicular squares,
   coaxial discs): the hemicube at each resolution and ray casting, relative error and time;
2. radiosity on the Cornell box: elements x hemicube resolution x stopping point, the error of
   the wall averages (mean relative error of the surfaces' mean radiance, pixels away from
   edges) against a converged path-traced reference, against solve time;
3. the path tracer: samples per pixel 4 .. 256 against the same reference (per-pixel mean
   relative error away from edges), with the 1/√N line through the first point.
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from pathlib import Path

import numpy as np

from core.paths import ROOT

SIZE = 32
REFERENCE_SPP = 2048


def form_factor_rows(resolutions=(16, 32, 64, 128, 256)) -> list[dict]:
    from core.radiosity import closed_forms as cf
    cases = {"parallel unit squares, 1 apart": (cf.parallel_pair(), 4),
             "perpendicular unit squares": (cf.perpendicular_pair(), 4),
             "coaxial unit discs, 1 apart": (cf.disc_pair(segments=24), 3)}
    rows = []
    for name, ((source, target, exact), pieces) in cases.items():
        runs = [("hemicube", r) for r in resolutions] + [("raycast", None)]
        for method, res in runs:
            began = time.perf_counter()
            value = cf.measured(source, target, method, res or 256, pieces)
            rows.append({"case": name, "method": method, "resolution": res, "exact": exact,
                         "measured": value, "error_pct": 100 * (value - exact) / exact,
                         "seconds": time.perf_counter() - began})
    return rows


def _reference(scene, view):
    from core.context import RenderContext
    from core.renderers.pathtrace.draw import render_passes
    from core.settings import RenderSettings
    settings = RenderSettings.for_scene(scene, renderer="pathtrace", size=(SIZE, SIZE), seed=7)
    image, _ = render_passes(scene, view, settings, RenderContext(), samples=REFERENCE_SPP)
    return image


def _wall_error(image, reference, ids, mask, on_walls) -> float:
    errors = []
    for surface in np.unique(ids[mask & on_walls]):
        sel = mask & (ids == surface)
        a, b = image[sel].mean(axis=0), reference[sel].mean(axis=0)
        errors.append(np.mean(np.abs(a - b) / b))
    return float(np.mean(errors))


def radiosity_rows(scene, view, reference, ids, mask, on_walls) -> list[dict]:
    from core.renderers.radiosity.draw import radiosity_image
    from core.radiosity.solution import Options, solve
    rows = []
    for elements in (250, 1000, 4000):
        for resolution in (32, 128):
            for converge in (0.1, 0.01, 0.001):
                options = Options(max_elements=elements, hemicube_resolution=resolution,
                                  converge=converge, adaptive=False)
                began = time.perf_counter()
                solution = solve(scene, options)
                seconds = time.perf_counter() - began
                image = radiosity_image(solution, view, "perspective", SIZE, SIZE)
                rows.append({"elements": solution.stats["elements"], "resolution": resolution,
                             "converge": converge, "steps": solution.stats["rounds"][0]["steps"],
                             "seconds": seconds,
                             "error_pct": 100 * _wall_error(image, reference, ids, mask,
                                                            on_walls)})
    return rows


def pathtrace_rows(scene, view, reference, mask) -> list[dict]:
    from core.context import RenderContext
    from core.renderers.pathtrace.draw import render_passes
    from core.settings import RenderSettings
    settings = RenderSettings.for_scene(scene, renderer="pathtrace", size=(SIZE, SIZE))
    context = RenderContext()
    render_passes(scene, view, settings, context, samples=1)
    rows = []
    for spp in (4, 16, 64, 256):
        began = time.perf_counter()
        image, _ = render_passes(scene, view, settings, context, samples=spp)
        seconds = time.perf_counter() - began
        lit = mask[..., None] & (reference > 1e-3 * reference.max())
        error = np.abs(image - reference)[lit] / reference[lit]
        rows.append({"spp": spp, "seconds": seconds, "error_pct": 100 * float(error.mean())})
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m app.reports.gi_report")
    parser.add_argument("--out", default="docs/report")
    args = parser.parse_args(argv)
    from core.pathtrace.compare import interior_mask, surface_ids
    from core.scene.formats import load_scene
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    view = scene.views[0]
    print("form factors ...", flush=True)
    ff = form_factor_rows()
    print(f"path-traced reference ({REFERENCE_SPP} spp) ...", flush=True)
    reference = _reference(scene, view)
    ids, mesh = surface_ids(scene, view, "perspective", SIZE, SIZE, with_meshes=True)
    mask = interior_mask(ids)
    on_walls = np.isin(mesh, [i for i, m in enumerate(scene.meshes) if "wall" in m.name])
    print("radiosity series ...", flush=True)
    rad = radiosity_rows(scene, view, reference, ids, mask, on_walls)
    print("path-tracer series ...", flush=True)
    pt = pathtrace_rows(scene, view, reference, mask)
    _write(out, ff, rad, pt)
    return 0


def _write(out: Path, ff, rad, pt) -> None:
    with open(out / "global_illumination.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["series", "json"])
        for name, rows in (("form factors", ff), ("radiosity", rad), ("pathtrace", pt)):
            for r in rows:
                w.writerow([name, json.dumps(r)])
    lines = ["# Global illumination: form factors, radiosity and the path tracer", "",
             "Made by `python -m app.reports.gi_report`: the error of form factors, "
             "radiosity and the path tracer against exact values and a converged reference, "
             "against the time each takes (summarised in docs/global-illumination.md). Times "
             "are wall seconds on this 2-core machine, shared with other jobs.", "",
             "## Form factors against closed forms (Howell C-11, C-14, C-41)", "",
             "F from the source to the target, averaged over the source cut into small "
             "pieces (the same points for both methods). Error % is against the closed form "
             "and includes that averaging (the ray-cast row, exact at each point, shows it); "
             "'hemicube own %' is the hemicube against the ray-cast value at the same points: "
             "the error of its pixels, which shrinks with the resolution.", "",
             "| case | method | resolution | exact | measured | error % | hemicube own % | s |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    raycast = {r["case"]: r["measured"] for r in ff if r["method"] == "raycast"}
    for r in ff:
        own = (f"{100 * (r['measured'] - raycast[r['case']]) / raycast[r['case']]:+.3f}"
               if r["method"] == "hemicube" else "-")
        lines.append(f"| {r['case']} | {r['method']} | {r['resolution'] or '-'} | "
                     f"{r['exact']:.5f} | {r['measured']:.5f} | {r['error_pct']:+.3f} | "
                     f"{own} | {r['seconds']:.2f} |")
    lines += ["", f"## Radiosity on the Cornell box against a path-traced reference "
              f"({REFERENCE_SPP} spp, {SIZE} x {SIZE})", "",
              "Error: mean relative error of the wall surfaces' mean radiance (pixels away from "
              "edges); time: meshing, form factors and progressive refinement to `converge`.",
              "", "| elements | hemicube | converge | shots | s | error % |",
              "|---:|---:|---:|---:|---:|---:|"]
    for r in rad:
        lines.append(f"| {r['elements']} | {r['resolution']} | {r['converge']} | {r['steps']} | "
                     f"{r['seconds']:.2f} | {r['error_pct']:.2f} |")
    lines += ["", "## The path tracer against the same reference", "",
              "Per-pixel mean relative error away from edges; 1/√N: the first error scaled. "
              f"The reference's own noise ({REFERENCE_SPP} spp) flattens the last points.", "",
              "| spp | s | error % | 1/√N line % |", "|---:|---:|---:|---:|"]
    for r in pt:
        line = pt[0]["error_pct"] * (pt[0]["spp"] / r["spp"]) ** 0.5
        lines.append(f"| {r['spp']} | {r['seconds']:.2f} | {r['error_pct']:.2f} | {line:.2f} |")
    (out / "global_illumination.md").write_text("\n".join(lines) + "\n")
    _plot(out, rad, pt)


def _plot(out: Path, rad, pt) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    for elements in sorted({r["elements"] for r in rad}):
        for res in sorted({r["resolution"] for r in rad}):
            rows = [r for r in rad if r["elements"] == elements and r["resolution"] == res]
            a.plot([r["seconds"] for r in rows], [r["error_pct"] for r in rows], "o-",
                   label=f"{elements} elements, hemicube {res}")
    a.set(xscale="log", yscale="log", xlabel="seconds", ylabel="wall error %",
          title="radiosity (Cornell box)")
    a.legend(fontsize=7)
    b.plot([r["seconds"] for r in pt], [r["error_pct"] for r in pt], "o-", label="path tracer")
    b.plot([r["seconds"] for r in pt],
           [pt[0]["error_pct"] * (pt[0]["spp"] / r["spp"]) ** 0.5 for r in pt], "k--",
           label="1/√N")
    b.set(xscale="log", yscale="log", xlabel="seconds", ylabel="pixel error %",
          title="path tracer (4 .. 256 spp)")
    b.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "global_illumination.png", dpi=100)


def rewrite(out: Path) -> None:
    """The Markdown and the plot again from the CSV (no rendering)."""
    series = {"form factors": [], "radiosity": [], "pathtrace": []}
    with open(out / "global_illumination.csv") as f:
        for name, row in list(csv.reader(f))[1:]:
            series[name].append(json.loads(row))
    _write(out, series["form factors"], series["radiosity"], series["pathtrace"])


if __name__ == "__main__":
    raise SystemExit(main())
