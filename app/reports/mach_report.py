"""The Mach bands report (quiz 2): the intensity across the middle scan line of
``scenes/mach_bands.toml``, a 12-sided cylinder, drawn flat and Gouraud.

Flat shading is a staircase: the intensity jumps at each facet edge. Gouraud's is continuous
there, but its slope jumps: the second difference along the line has a spike at each facet
edge, exactly where the eye's lateral inhibition shows a band (FvDFH 16.2.5). Writes
``mach_bands.csv`` (column, flat, Gouraud), ``mach_bands.png`` (the two profiles and Gouraud's
slope) and ``mach_bands.md`` (the numbers); :func:`profiles` is what the tests read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

SIZE = (480, 160)


def profiles(size=SIZE) -> dict:
    """``{"flat", "gouraud"}``: (W,) mean RGB on 0–255 along the middle row, and
    ``"edges"``: the columns of the facet edges the cylinder shows (from its vertices)."""
    from core import RenderSettings, render
    from core.paths import SCENES_DIR
    from core.scene.formats import load_scene
    scene = load_scene(SCENES_DIR / "mach_bands.toml")
    view = scene.views[0]
    out = {}
    for shading in ("flat", "gouraud"):
        frame = render(scene, view, RenderSettings.for_scene(scene, shading=shading, size=size))
        out[shading] = frame.color[size[1] // 2].astype(np.float64).mean(axis=1)
    u_min, u_max = view.window[:2]
    x = scene.meshes[0].positions[:, 0]
    z = scene.meshes[0].positions[:, 2]
    seen = np.unique(np.round(x[z > -1e-9], 12))      # the facet edges in front (z >= 0)
    out["edges"] = (seen - u_min) / (u_max - u_min) * size[0]
    return out


def facet_slopes(profile, edges, margin: int = 2) -> list[tuple[tuple[int, int], float]]:
    """Per facet (between two facet edges, ``margin`` pixels in from each): its columns and
    the least-squares slope of ``profile`` there (the 8-bit rounding averaged out)."""
    out = []
    for left, right in zip(edges[:-1], edges[1:]):
        a, b = int(np.ceil(left)) + margin, int(np.floor(right)) - margin
        if b - a >= 4:
            x = np.arange(a, b + 1)
            out.append(((a, b), float(np.polyfit(x, profile[a:b + 1], 1)[0])))
    return out


def write(out: Path, progress=None) -> list[Path]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if progress:
        progress("report: Mach bands (flat and Gouraud profiles) ...")
    p = profiles()
    flat, gouraud = p["flat"], p["gouraud"]
    inside = np.flatnonzero((flat > 0) & (gouraud > 0))
    lo, hi = inside[0] + 2, inside[-1] - 2
    step_flat = np.abs(np.diff(flat[lo:hi]))
    step_gouraud = np.abs(np.diff(gouraud[lo:hi]))
    bend = np.abs(np.diff(gouraud[lo:hi], 2))
    paths = [out / "mach_bands.csv", out / "mach_bands.png", out / "mach_bands.md"]
    rows = np.column_stack([np.arange(len(flat)), flat, gouraud])
    np.savetxt(paths[0], rows, delimiter=",", header="column,flat,gouraud", comments="",
               fmt=["%d", "%.3f", "%.3f"])
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    top.plot(flat, label="flat", drawstyle="steps-mid")
    top.plot(gouraud, label="Gouraud")
    slopes = facet_slopes(gouraud, p["edges"])
    for (a, b_), slope in slopes:
        bottom.plot([a, b_], [slope, slope], color="C1")
    bottom.plot([], [], color="C1", label="Gouraud: slope on each facet (least squares)")
    bottom.set_ylabel("intensity per pixel")
    for ax in (top, bottom):
        for edge in p["edges"]:
            ax.axvline(edge, color="0.8", lw=0.6, zorder=0)
        ax.legend(loc="upper right")
    top.set_ylabel("intensity (0-255)")
    bottom.set_xlabel("column along the middle scan line (facet edges in grey)")
    top.set_title("Mach bands: intensity continuous (Gouraud), slope not")
    fig.tight_layout()
    fig.savefig(paths[1], dpi=100)
    plt.close(fig)
    paths[2].write_text(
        "# Mach bands\n\n"
        f"`scenes/mach_bands.toml` at {SIZE[0]} x {SIZE[1]}, the middle scan line "
        f"(columns {lo}-{hi} inside the cylinder):\n\n"
        "| | flat | Gouraud |\n|---|---:|---:|\n"
        f"| largest change between neighbouring pixels | {step_flat.max():.1f} | "
        f"{step_gouraud.max():.1f} |\n"
        f"| largest change of slope (second difference) | - | {bend.max():.1f} |\n\n"
        "Gouraud's slope on each facet (intensity per pixel; it is constant on a facet and "
        "jumps at its edges):\n\n| columns | slope |\n|---|---:|\n"
        + "".join(f"| {a}-{b_} | {slope:+.3f} |\n" for (a, b_), slope in slopes) + "\n"
        "Flat shading jumps at each facet edge; Gouraud's intensity is continuous there but "
        "its slope jumps, and the eye sees bands at the kinks (FvDFH 16.2.5).\n\n"
        "![profiles](mach_bands.png)\n")
    return paths
