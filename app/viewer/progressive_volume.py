"""The window's volume frames, progressive: a coarse picture first, then the whole frame.

Ray marching a 256³ volume at 500 x 500 takes seconds on a small machine, so
:func:`volume_progressively` first draws the frame at 1/``COARSE`` of its size in each
direction through the front door (``core.render`` with the ``"volume"`` renderer: its checks
and messages are the usual ones) and hands it over upscaled by pixel repetition, then draws
the full frame, which is exactly what ``core.render`` gives. Between the two it asks its
:class:`app.viewer.worker.Control` whether a newer request has superseded it.
"""

from __future__ import annotations

import math

import numpy as np

from app.viewer.progressive import _Quiet, upscale

COARSE = 4                # the first picture: one ray per COARSE x COARSE pixels


def volume_progressively(scene, view, settings, context=None, render=None, control=None):
    """The volume renderer's frame of ``view`` for ``settings``, a coarse one on the way."""
    if render is None:
        from core.render import render
    control = control or _Quiet()
    width, height = settings.size
    small = (max(1, math.ceil(width / COARSE)), max(1, math.ceil(height / COARSE)))
    control.report(0.0, f"coarse pass (every {COARSE}th pixel)")
    coarse = render(scene, view, settings.replace(size=small, samples=1), context)
    if coarse.message:                        # an invalid view: said once, nothing to refine
        return coarse
    shown = type(coarse)(rgbx=np.empty((height, width, 4), np.uint8), plan=coarse.plan,
                         stats={**coarse.stats, "pass": "coarse"})
    shown.color[:] = upscale(coarse.color, COARSE, width, height)
    control.partial(shown)
    control.check()
    control.report(0.2, "full frame")
    frame = render(scene, view, settings, context)
    frame.stats["pass"] = "final"
    return frame
