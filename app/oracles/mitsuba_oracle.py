"""Mitsuba 3 (``scalar_rgb``), the outside oracle of the global-illumination renderers: the same
scene (our triangles written to OBJ files, diffuse BSDFs with ρ = k_d O_d, area emitters with
our ``emission`` as radiance, the view as a perspective sensor) rendered by its path tracer.

Only diffuse materials and area emitters are carried over (the Cornell box's kind); a test-only
dependency (``pip install mitsuba``), imported when used. The bench also times its
``llvm_ad_rgb`` variant (vectorised and JIT-compiled, Mitsuba's fastest on a CPU), which needs
LLVM's shared library: Dr.Jit finds it through ``DRJIT_LIBLLVM_PATH`` (:func:`llvm_library`
points it at Debian's ``libllvm19`` when that is installed).
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np

from core.camera.view import vrc_basis


LLVM_LIBRARIES = ("/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
                  "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")


def llvm_library() -> str | None:
    """The libLLVM that Mitsuba's llvm variants will load (``DRJIT_LIBLLVM_PATH``, else one of
    ``LLVM_LIBRARIES``, which it then names in that variable), or None when there is none."""
    import os
    named = os.environ.get("DRJIT_LIBLLVM_PATH")
    if named:
        return named if Path(named).exists() else None
    found = next((p for p in LLVM_LIBRARIES if Path(p).exists()), None)
    if found:
        os.environ["DRJIT_LIBLLVM_PATH"] = found     # read when Dr.Jit first JITs
    return found


def available() -> bool:
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        return False
    return True


def _sensor(view, width: int, height: int, spp: int, seed: int):
    import mitsuba as mi
    u, v, n = vrc_basis(view)
    vrp = np.asarray(view.vrp, float)
    prp = np.asarray(view.prp, float)
    eye = vrp + prp[0] * u + prp[1] * v + prp[2] * n
    u_min, u_max, v_min, v_max = view.window
    centre = vrp + (u_min + u_max) / 2 * u + (v_min + v_max) / 2 * v
    if abs((u_min + u_max) / 2 - prp[0]) > 1e-9 or abs((v_min + v_max) / 2 - prp[1]) > 1e-9:
        raise ValueError("Mitsuba's perspective sensor needs a window centred on the PRP")
    fov = math.degrees(2 * math.atan((u_max - u_min) / 2 / prp[2]))
    return {"type": "perspective", "fov": fov, "fov_axis": "x",
            "to_world": mi.ScalarTransform4f().look_at(origin=eye.tolist(),
                                                       target=centre.tolist(),
                                                       up=v.tolist()),
            "film": {"type": "hdrfilm", "width": width, "height": height,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed}}


def _write_obj(path: Path, positions, triangles) -> None:
    with open(path, "w") as f:
        for p in positions:
            f.write(f"v {float(p[0])!r} {float(p[1])!r} {float(p[2])!r}\n")
        for t in triangles + 1:
            f.write(f"f {t[0]} {t[1]} {t[2]}\n")


def render(scene, view, width: int, height: int, spp: int, seed: int = 0,
           timed: bool = False, variant: str = "scalar_rgb"):
    """Mitsuba's linear radiance ``(H, W, 3)`` of ``scene`` seen through ``view`` (with
    ``timed``: and the seconds ``mi.render`` took, the scene's loading left out), drawn by its
    ``variant`` (``scalar_rgb``, or ``llvm_ad_rgb`` after :func:`llvm_library`)."""
    import mitsuba as mi
    mi.set_variant(variant)
    from core.radiosity.mesh import reflectance
    with tempfile.TemporaryDirectory() as folder:
        doc = {"type": "scene", "integrator": {"type": "path", "max_depth": -1},
               "sensor": _sensor(view, width, height, spp, seed)}
        for i, mesh in enumerate(scene.meshes):
            if not len(mesh.triangles):
                continue
            path = Path(folder) / f"mesh{i}.obj"
            _write_obj(path, mesh.positions, mesh.triangles)
            shape = {"type": "obj", "filename": str(path), "face_normals": True,
                     "bsdf": {"type": "twosided", "bsdf": {
                         "type": "diffuse",
                         "reflectance": {"type": "rgb",
                                         "value": reflectance(mesh.material).tolist()}}}}
            if any(mesh.material.emission):
                shape["emitter"] = {"type": "area", "radiance": {
                    "type": "rgb", "value": list(mesh.material.emission)}}
            doc[f"mesh{i}"] = shape
        loaded = mi.load_dict(doc)
        began = time.perf_counter()
        image = np.array(mi.render(loaded, spp=spp, seed=seed), dtype=np.float64)[:, :, :3]
        seconds = time.perf_counter() - began
        return (image, seconds) if timed else image
