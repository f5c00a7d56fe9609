"""Textured Phong (trilinear) against llvmpipe doing the same, in the same run.

The bench's scene (a UV sphere inside a tilted torus, ``core.scene.generators.sphere_torus``)
at 100k and 1M triangles, each mesh with a procedural checker texture on its generator (u, v),
500 x 500, Phong shading with trilinear filtering: ours through ``core.render.render`` (the
``textured`` shader), llvmpipe through :class:`app.oracles.texture_gl.TexturedPhongGL` (the same
lighting GLSL as the bench's Phong, O_d from the same MIP chain). Median and min of the timed
frames after warm-up; the mean difference of the two pictures says they drew the same thing.

``python -m app bench`` does not run it by default (it adds a minute); run
``python -m app.bench.texture_bench [--sizes 100k,1M] [--frames 10]``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import numpy as np


def textured_scene(triangles: int):
    from core.scene.generators import sphere_torus
    from core.texture import procedural
    from core.texture.material import MAPS_KEY, SurfaceMaps
    scene = sphere_torus(triangles=triangles)
    scene.shading = "phong"
    for mesh, scale in zip(scene.meshes, (16, 32)):
        texture = procedural.make("checker", scale=scale, resolution=512,
                                  a=(0.9, 0.8, 0.3), b=(0.2, 0.3, 0.6))
        mesh.material.extra = {MAPS_KEY: SurfaceMaps(color=texture)}
    return scene


def _times(draw, frames: int, warmup: int) -> list[float]:
    for _ in range(warmup):
        draw()
    out = []
    for _ in range(frames):
        start = time.perf_counter()
        draw()
        out.append(time.perf_counter() - start)
    return out


def run(sizes=(100_000, 1_000_000), frames: int = 10, warmup: int = 4, size=(500, 500)):
    from app.oracles.texture_gl import TexturedPhongGL
    from core import render
    from core.settings import RenderSettings
    rows = []
    for n in sizes:
        scene = textured_scene(n)
        view = scene.views[0]
        settings = RenderSettings.for_scene(scene, shading="phong", size=size,
                                            texture_filter="trilinear")
        ours = _times(lambda: render(scene, view, settings), frames, warmup)
        gl = TexturedPhongGL(size)
        gl.load(scene)
        theirs = _times(lambda: (gl.draw(view, "perspective"), gl.gl.finish()), frames, warmup)
        difference = float(np.abs(render(scene, view, settings).color.astype(int)
                                  - gl.render(view, "perspective").astype(int)).mean())
        gl.release()
        row = {"triangles": scene.triangle_count, "ours_ms": statistics.median(ours) * 1e3,
               "ours_min_ms": min(ours) * 1e3, "llvmpipe_ms": statistics.median(theirs) * 1e3,
               "llvmpipe_min_ms": min(theirs) * 1e3, "mean_abs_difference": difference}
        row["ratio"] = row["ours_ms"] / row["llvmpipe_ms"]
        rows.append(row)
        print(f"{row['triangles']:>9,} textured phong trilinear: ours {row['ours_ms']:.1f} ms "
              f"(min {row['ours_min_ms']:.1f}), llvmpipe {row['llvmpipe_ms']:.1f} ms "
              f"(min {row['llvmpipe_min_ms']:.1f}), ours/llvmpipe {row['ratio']:.2f}, "
              f"mean |difference| {difference:.2f}/255", flush=True)
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m app.bench.texture_bench")
    p.add_argument("--sizes", default="100k,1M")
    p.add_argument("--frames", type=int, default=10)
    args = p.parse_args(argv)
    sizes = [int(float(s[:-1]) * (1000 if s[-1] in "kK" else 1_000_000)) if s[-1] in "kKmM"
             else int(s) for s in args.sizes.split(",")]
    run(sizes, frames=args.frames)
    return 0


if __name__ == "__main__":
    sys.exit(main())
