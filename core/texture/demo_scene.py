"""The bump demo's scene side, without numba: its constants and labels, the height
functions in numpy, the panel's view, and the options the command line and the window set.
The demo's pixel step (numba) is :mod:`core.texture.bump_demo`."""

from __future__ import annotations

import numpy as np

from core.camera.view import View

DEMO_LIGHT = (50.0, -50.0, 50.0)
DEMO_VIEWPOINT = (50.0, -50.0, 50.0)
WINDOW_SIZE = 100.0                        # the panel spans (0, 0) … (100, −100)
LABELS = ("B(x,y) = sin((x^2 + y^2)^0.5)",
          "B(x,y) = sin(x) + cos(y)",
          "B(x,y) = sin(x) + Math.sin(y)",
          "B(x,y) = sin(((x-50)^2 + (y+50)^2)^0.5)")
MAPS = len(LABELS)


def label(bump_map: int) -> str:
    """The text the demo shows for ``bump_map`` (past the last map, the default case: map 0's
    function, and the demo leaves the label as it was; we show map 0's)."""
    return LABELS[bump_map if 0 <= bump_map < MAPS else 0]


def demo_bump_numpy(bump_map: int, x, y):
    """:func:`demo_bump` on arrays (for the height-map texture of the same functions)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if bump_map == 1:
        return np.sin(x) + np.cos(y)
    if bump_map == 2:
        return np.sin(x) + np.sin(y)
    if bump_map == 3:
        return np.sin(np.sqrt((x - 50) ** 2 + (y + 50) ** 2))
    return np.sin(np.sqrt(x * x + y * y))


def demo_view(width: int, height: int) -> View:
    """The parallel view that puts pixel (x, y)'s centre at ``(x/w · 100, −y/h · 100, 0)``.

    The renderer samples pixel centres; the demo puts pixel (x, y) at its corner, so the
    window (the demo's 100 x 100) is moved half a pixel up and to the left. A frame that is
    not square stretches the window over it, as the Java panel does (unless the settings ask
    to keep the aspect).
    """
    du, dv = WINDOW_SIZE / width / 2, WINDOW_SIZE / height / 2
    window = (-du, WINDOW_SIZE - du, -WINDOW_SIZE + dv, dv)
    centre = ((window[0] + window[1]) / 2, (window[2] + window[3]) / 2)
    return View(vrp=(0.0, 0.0, 0.0), vpn=(0.0, 0.0, 1.0), vup=(0.0, 1.0, 0.0), window=window,
                prp=(centre[0], centre[1], 100.0), front=10.0, back=-10.0,
                label=f"the bump demo's panel, {width} x {height}")


def demo_materials(scene) -> list:
    """The :class:`core.texture.material.DemoMaterial` of every mesh that has one."""
    from core.texture.material import maps_of
    return [maps_of(m.material).demo for m in scene.meshes
            if maps_of(m.material) is not None and maps_of(m.material).demo is not None]


def apply_demo_options(scene, bump_map: int | None, bump: bool) -> str | None:
    """Set every bump-demo material of ``scene`` to ``bump_map`` (when given) and ``bump``;
    returns the demo's label text (``"Bump: B(x,y) = …"`` or ``"Phong"``), or None when the
    scene has no demo material. Raises ValueError for a map the demo does not have."""
    if bump_map is not None and not 0 <= bump_map < MAPS:
        raise ValueError(f"the bump demo's height map must be 0 to {MAPS - 1}, not {bump_map}")
    demos = demo_materials(scene)
    for demo in demos:
        if bump_map is not None:
            demo.bump_map = int(bump_map)
        demo.bump = bool(bump)
    if not demos:
        return None
    return f"Bump: {label(demos[0].bump_map)}" if demos[0].bump else "Phong"


def panel_views(scene) -> list[View]:
    """The demo's panel view for the scene's image size, when a material is the demo's."""
    return [demo_view(*scene.size)] if demo_materials(scene) else []
