"""``python -m app bench --renderer radiosity,pathtrace,twopass``: the global-illumination
rows on the Cornell box (``scenes/cornell_box.toml``), and the two-pass method's on its room:

- radiosity: seconds from the scene to 1 % unshot energy (meshing, BVH, form factors, progressive
  refinement; no adaptive round) at about 1,000 and 10,000 elements, hemicube (resolution
  ``--hemicube-resolution``, default 128) and ray-cast form factors (ray casting at 1,000 only
  unless ``--gi-large-raycast``), and form-factor rows per second;
- pathtrace: samples (camera paths) per second of our path tracer and of Mitsuba 3
  ``scalar_rgb`` and ``llvm_ad_rgb`` (when libLLVM is there) in the same run, same picture
  (``--size``, default 128 x 128 here, 64 spp);
- twopass: ``scenes/two_pass.toml`` at its own size (``--size`` otherwise): the first frame
  (pass 1, the radiosity solution, then pass 2) and a second one from the held solution
  (pass 2 alone: the eye rays and the specular rays), with the rays of each kind.

The first solve and the first picture run once untimed (compiling). Writes
``DIR/bench_gi.json`` and prints a table.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

from core.paths import ROOT

RENDERERS = ("radiosity", "pathtrace", "twopass")


def _progress(text: str) -> None:
    print(f"[bench] {text}", file=sys.stderr, flush=True)


def radiosity_rows(scene, resolution: int, sizes=(1000, 10000), raycast_sizes=(1000,)) -> list:
    from core.radiosity.solution import Options, solve
    solve(scene, Options(max_elements=200, hemicube_resolution=resolution,
                         adaptive=False))                              # compile
    solve(scene, Options(max_elements=200, form_factors="raycast", adaptive=False))
    rows = []
    for method, counts in (("hemicube", sizes), ("raycast", raycast_sizes)):
        for count in counts:
            _progress(f"radiosity: {method}, about {count} elements ...")
            options = Options(form_factors=method, hemicube_resolution=resolution,
                              max_elements=count, converge=0.01, adaptive=False)
            began = time.perf_counter()
            solution = solve(scene, options)
            seconds = time.perf_counter() - began
            s, r = solution.stats, solution.stats["rounds"][0]
            rows.append({"form_factors": method, "resolution": resolution if method == "hemicube"
                         else None, "elements": s["elements"], "patches": s["patches"],
                         "seconds_to_1pct": seconds, "steps": r["steps"], "unshot": r["unshot"],
                         "rows": s["form factor rows"],
                         "rows_per_second": s["form factor rows"] / max(s["form factor seconds"],
                                                                        1e-9)})
    return rows


def pathtrace_rows(scene, size, spp: int) -> list:
    from core.context import RenderContext
    from core.renderers.pathtrace.draw import render_passes
    from core.settings import RenderSettings
    view = scene.views[0]
    width, height = size
    settings = RenderSettings.for_scene(scene, renderer="pathtrace", size=(width, height))
    render_passes(scene, view, settings.replace(size=(16, 16)), RenderContext(), samples=1)
    _progress(f"pathtrace: ours, {width} x {height} at {spp} spp ...")
    context = RenderContext()
    render_passes(scene, view, settings, context, samples=1)                 # pack, BVH
    began = time.perf_counter()
    _, stats = render_passes(scene, view, settings, context, samples=spp)
    ours = time.perf_counter() - began
    rows = [{"renderer": "ours (core.pathtrace)", "samples": width * height * spp,
             "seconds": ours, "samples_per_second": width * height * spp / ours,
             "bounces_per_path": stats["bounces"] / stats["paths"]}]
    from app.oracles import mitsuba_oracle
    if mitsuba_oracle.available():
        _progress(f"pathtrace: Mitsuba 3 scalar_rgb, {width} x {height} at {spp} spp ...")
        mitsuba_oracle.render(scene, view, 16, 16, 1)                        # load, JIT
        _, seconds = mitsuba_oracle.render(scene, view, width, height, spp, timed=True)
        rows.append({"renderer": "Mitsuba 3 scalar_rgb", "samples": width * height * spp,
                     "seconds": seconds, "samples_per_second": width * height * spp / seconds})
        rows.append(_mitsuba_llvm_row(scene, view, width, height, spp))
    else:
        rows.append({"renderer": "Mitsuba 3 scalar_rgb", "missing": "pip install mitsuba"})
    return rows


def twopass_rows(size=None) -> list:
    """The two-pass room: both passes from nothing, then pass 2 alone (the solution held)."""
    from core.context import RenderContext
    from core.render import render
    from core.scene.formats import load_scene
    from core.settings import RenderSettings
    scene = load_scene(ROOT / "scenes" / "two_pass.toml")
    view = scene.views[0]
    settings = RenderSettings.for_scene(scene, renderer="twopass", size=size)
    render(scene, view, settings.replace(size=(16, 12), max_elements=64,
                                         hemicube_resolution=16), RenderContext())  # compile
    _progress(f"twopass: {scene.name}, {settings.size[0]} x {settings.size[1]} ...")
    context = RenderContext()
    began = time.perf_counter()
    render(scene, view, settings, context)
    both = time.perf_counter() - began
    began = time.perf_counter()
    frame = render(scene, view, settings, context)
    second = time.perf_counter() - began
    stats = frame.stats["twopass"]
    return [{"scene": "scenes/two_pass.toml", "size": list(settings.size),
             "elements": stats["radiosity"]["elements"], "both_passes_seconds": both,
             "second_pass_seconds": second, "rays": stats["rays"]}]


def _mitsuba_llvm_row(scene, view, width: int, height: int, spp: int) -> dict:
    """Mitsuba's ``llvm_ad_rgb`` on the same picture, its JIT warmed first on the same size
    (Dr.Jit compiles a kernel per launch shape); or what is missing to run it."""
    from app.oracles import mitsuba_oracle
    name = "Mitsuba 3 llvm_ad_rgb"
    if mitsuba_oracle.llvm_library() is None:
        return {"renderer": name, "missing": "libLLVM (apt-get install libllvm19, or set "
                                             "DRJIT_LIBLLVM_PATH)"}
    _progress(f"pathtrace: {name}, {width} x {height} at {spp} spp ...")
    try:
        mitsuba_oracle.render(scene, view, width, height, spp, variant="llvm_ad_rgb")
        _, seconds = mitsuba_oracle.render(scene, view, width, height, spp, timed=True,
                                           variant="llvm_ad_rgb")
    except (ImportError, RuntimeError) as error:
        return {"renderer": name, "missing": f"the variant would not run: {error}"}
    return {"renderer": name, "samples": width * height * spp, "seconds": seconds,
            "samples_per_second": width * height * spp / seconds}


def main(args) -> int:
    from core.scene.formats import load_scene
    wanted = [r.strip() for r in args.renderer.split(",") if r.strip()]
    bad = [r for r in wanted if r not in RENDERERS]
    if bad or not wanted:
        print(f"error: --renderer: {', '.join(bad) or 'nothing'}: choose zbuffer, raytrace, or "
              f"any of {', '.join(RENDERERS)}", file=sys.stderr)
        return 2
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report = {"scene": "scenes/cornell_box.toml", "cpus": os.cpu_count(),
              "loadavg_before": list(os.getloadavg())}
    resolution = getattr(args, "hemicube_resolution", None) or 128
    if "radiosity" in wanted:
        report["radiosity"] = radiosity_rows(scene, resolution)
    if "pathtrace" in wanted:
        size = tuple(args.size) if tuple(args.size) != (500, 500) else (128, 128)
        report["pathtrace"] = pathtrace_rows(scene, size, 64)      # 64 spp: Mitsuba's llvm JIT amortised
    if "twopass" in wanted:
        report["twopass"] = twopass_rows(tuple(args.size) if tuple(args.size) != (500, 500)
                                         else None)
    report["loadavg_after"] = list(os.getloadavg())
    (out / "bench_gi.json").write_text(json.dumps(report, indent=2))
    print(table(report))
    print(f"wrote {out / 'bench_gi.json'}")
    return 0


def table(report) -> str:
    lines = []
    if "radiosity" in report:
        lines += ["| form factors | elements | patches | s to 1 % unshot | shots | rows/s |",
                  "|---|---:|---:|---:|---:|---:|"]
        for r in report["radiosity"]:
            method = (f"hemicube {r['resolution']}" if r["form_factors"] == "hemicube"
                      else "ray cast")
            lines.append(f"| {method} | {r['elements']} | {r['patches']} | "
                         f"{r['seconds_to_1pct']:.2f} | {r['steps']} | "
                         f"{r['rows_per_second']:.0f} |")
    if "pathtrace" in report:
        lines += ["", "| path tracer | samples | s | samples/s |", "|---|---:|---:|---:|"]
        for r in report["pathtrace"]:
            if "missing" in r:
                lines.append(f"| {r['renderer']} | - | - | ({r['missing']}) |")
            else:
                lines.append(f"| {r['renderer']} | {r['samples']} | {r['seconds']:.2f} | "
                             f"{r['samples_per_second']:.0f} |")
    if "twopass" in report:
        lines += ["", "| two-pass | size | elements | both passes s | pass 2 alone s | "
                      "primary, reflected, refracted, shadow rays |",
                  "|---|---|---:|---:|---:|---|"]
        for r in report["twopass"]:
            rays = r["rays"]
            lines.append(f"| {r['scene']} | {r['size'][0]} x {r['size'][1]} | "
                         f"{r['elements']} | {r['both_passes_seconds']:.2f} | "
                         f"{r['second_pass_seconds']:.2f} | {rays['primary']:,}, "
                         f"{rays['reflected']:,}, {rays['refracted']:,}, {rays['shadow']:,} |")
    lines.append(f"\nload average {report['loadavg_before'][0]:.1f} -> "
                 f"{report['loadavg_after'][0]:.1f} on {report['cpus']} CPUs")
    return "\n".join(lines)
