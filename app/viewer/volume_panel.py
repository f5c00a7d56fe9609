"""The panel's volume section: widgets only; every change goes through the state's ``volumes``.

- the transfer function as a plot over the data's histogram (grey bars, log counts): each
  point a dot in its own colour at (value, alpha); drag one to move it (the picture re-renders
  as it moves; a drag below the axis, alpha < 0, or past a neighbour is refused with the
  state's message and the last good function stays);
- for an isosurface, the iso slider (marching cubes runs in the next frame's job, off this
  thread; the panel says "extracting…" until the new surface is drawn);
- the slice view: axial, coronal or sagittal and its index, shown among the buffer views.

The plot's mapping between values and pixels (:func:`plot_scale`, :func:`to_plot`,
:func:`from_plot`, :func:`nearest_point`) is plain arithmetic, testable without a window.
"""

from __future__ import annotations

import logging
import math

import numpy as np

log = logging.getLogger("fvd")

PLOT_HEIGHT = 110            # points
PICK_RADIUS = 8.0            # points: how near a press must be to take a transfer point


def plot_scale(volume) -> tuple[float, float, float]:
    """``(lo, hi, top)``: the plot's value range (the data's and the points') and its alpha
    axis's top (a quarter above the largest alpha, at least 1)."""
    lo, hi = volume.value_range
    t = volume.transfer
    lo, hi = min(lo, float(t[0, 0])), max(hi, float(t[-1, 0]))
    if hi <= lo:
        hi = lo + 1.0
    return lo, hi, max(1.0, 1.25 * float(t[:, 4].max()))


def to_plot(value, alpha, box, scale):
    """Plot pixels of (value, alpha); ``box = (x0, y0, width, height)``, y down."""
    x0, y0, w, h = box
    lo, hi, top = scale
    return (x0 + (value - lo) / (hi - lo) * w, y0 + h - alpha / top * h)


def from_plot(x, y, box, scale):
    """(value, alpha) at plot pixel (x, y): the inverse of :func:`to_plot`."""
    x0, y0, w, h = box
    lo, hi, top = scale
    return (lo + (x - x0) / w * (hi - lo), (y0 + h - y) / h * top)


def nearest_point(transfer, x, y, box, scale, radius=PICK_RADIUS) -> int | None:
    """The transfer point drawn within ``radius`` of (x, y), the nearest; None if none."""
    best, found = radius, None
    for k, row in enumerate(transfer):
        px, py = to_plot(row[0], row[4], box, scale)
        d = math.hypot(px - x, py - y)
        if d <= best:
            best, found = d, k
    return found


class VolumePanel:
    """The section's widgets and the one thing they keep: the point being dragged."""

    def __init__(self, state, tools):
        self.state, self.tools = state, tools
        self.dragging: int | None = None
        self._scale = None                  # (volume, the plot's scale), held still
        self._pressed = None                # (box, scale) when the drag began

    def draw(self, imgui, displayable) -> None:
        s = self.state
        if not s.volumes.all:
            return
        if not imgui.collapsing_header("Volume###volume", imgui.TreeNodeFlags_.default_open):
            return
        self._choose_volume(imgui)
        v = s.volumes.current
        lo, hi = v.value_range
        imgui.push_text_wrap_pos(0.0)
        imgui.text_disabled(f"{v.mode}, {' x '.join(map(str, v.dims))}, values {lo:.3g} .. "
                            f"{hi:.3g}")
        imgui.pop_text_wrap_pos()
        if v.mode == "isosurface":
            self._iso(imgui)
        if v.transfer is not None:
            self._transfer(imgui)
        self._slice(imgui)
        if s.volume_message:
            imgui.push_text_wrap_pos(0.0)
            imgui.text_colored((1.0, 0.45, 0.4, 1.0), displayable(s.volume_message))
            imgui.pop_text_wrap_pos()
        imgui.separator()

    def _choose_volume(self, imgui) -> None:
        s = self.state
        if len(s.volumes.all) < 2:
            imgui.text(s.volumes.current.name)
            return
        names = [v.name for v in s.volumes.all]
        imgui.push_item_width(-1)
        changed, k = imgui.combo("##volume", s.volume_index, names)
        imgui.pop_item_width()
        if changed:
            from app.session.volume_controls import SLICES
            s.volumes.select(k)
            self.dragging = None
            if self.tools.buffer in SLICES:          # the slice shown is the new volume's
                self.tools.show_slice(s.slice_name, None, "panel volume")

    def _iso(self, imgui) -> None:
        s, v = self.state, self.state.volumes.current
        lo, hi = v.value_range
        imgui.push_item_width(-1)
        shown = float(s.volumes.iso_shown(v))
        changed, iso = imgui.slider_float("##iso", shown, lo, hi, "iso %.4g")
        imgui.pop_item_width()
        if changed:
            ok = s.volumes.set_iso(iso)
            log.info("action: slider iso -> %s", f"iso {float(iso)!r} asked" if ok else s.volume_message)
        k = _mesh_of(s.scene, v)
        triangles = "" if k is None else f", {len(s.scene.meshes[k].triangles)} triangles"
        if s.volumes.extracting:
            imgui.text_colored((0.55, 0.8, 1.0, 1.0), "extracting…")
        else:
            imgui.text_disabled(f"isosurface at {v.iso:.4g}{triangles}")

    def _transfer(self, imgui) -> None:
        s, v = self.state, self.state.volumes.current
        width = max(imgui.get_content_region_avail().x, 40.0)
        origin = imgui.get_cursor_screen_pos()
        box = (origin.x, origin.y, width, float(PLOT_HEIGHT))
        imgui.invisible_button("##transfer", (width, PLOT_HEIGHT))
        scale = self._plot_scale(v)
        mouse = imgui.get_io().mouse_pos
        if imgui.is_item_activated():
            self.dragging = nearest_point(v.transfer, mouse.x, mouse.y, box, scale)
            self._pressed = (box, scale)
        if self.dragging is not None:       # the release's frame moves it to the last place too
            # the press's box and scale: the panel's lines above may move the plot meanwhile
            point = from_plot(mouse.x, mouse.y, *self._pressed)
            s.volumes.move_transfer_point(self.dragging, *point)
            if not imgui.is_item_active():
                row = v.transfer[self.dragging]
                log.info("action: drag transfer point %d -> value %.4g, alpha %.4g%s",
                         self.dragging, row[0], row[4],
                         f" ({s.volume_message})" if s.volume_message else "")
                self.dragging = None
        _draw_plot(imgui, v, box, scale)
        imgui.push_text_wrap_pos(0.0)
        imgui.text_disabled("transfer: value across, alpha up (histogram: log counts); "
                            "drag a point")
        imgui.pop_text_wrap_pos()

    def _plot_scale(self, volume):
        """The plot's scale, kept while every point fits in it (a dropped point stays where
        it was dropped); made anew for another volume or a point beyond it."""
        held = self._scale
        if self.dragging is not None:
            return self._pressed[1]
        if held is not None and held[0] is volume:
            lo, hi, top = held[1]
            t = volume.transfer
            if lo <= t[0, 0] and t[-1, 0] <= hi and t[:, 4].max() <= top:
                return held[1]
        self._scale = (volume, plot_scale(volume))
        return self._scale[1]

    def _slice(self, imgui) -> None:
        from app.session.volume_controls import SLICE_AXIS, SLICES
        s, tools = self.state, self.tools
        showing = tools.buffer in SLICES
        for name in SLICES:
            if imgui.radio_button(name, showing and s.slice_name == name):
                tools.show_slice(name, None if name != s.slice_name else s.slice_index,
                                 f"panel slice {name}")
            imgui.same_line()
        if imgui.radio_button("off", not showing) and showing:
            tools.choose_buffer("picture", "panel slice off")
        n = s.volumes.current.values.shape[SLICE_AXIS[s.slice_name]]
        imgui.push_item_width(-1)
        changed, k = imgui.slider_int("##slice", s.volumes.slice_shown(), 0, n - 1,
                                      f"{s.slice_name} slice %d of {n}")
        imgui.pop_item_width()
        if changed:
            tools.show_slice(s.slice_name, int(k), "slider slice")


def _mesh_of(scene, volume):
    from app.session.volume_controls import isosurface_index
    return isosurface_index(scene, volume)


def _draw_plot(imgui, volume, box, scale) -> None:
    """Histogram bars (log counts) under the transfer function's alpha, its points in their
    colours; all inside ``box``."""
    from app.session.volume_controls import histogram
    x0, y0, w, h = box
    draw = imgui.get_window_draw_list()
    draw.add_rect_filled((x0, y0), (x0 + w, y0 + h), imgui.IM_COL32(30, 30, 36, 255))
    counts, edges = histogram(volume)
    heights = np.log1p(counts) / max(np.log1p(counts).max(), 1e-30)
    for c, a, b in zip(heights, edges[:-1], edges[1:]):
        left, _ = to_plot(a, 0.0, box, scale)
        right, _ = to_plot(b, 0.0, box, scale)
        draw.add_rect_filled((left, y0 + h * (1 - c)), (max(right - 1, left + 1), y0 + h),
                             imgui.IM_COL32(90, 90, 100, 255))
    t = volume.transfer
    lo, hi, _ = scale
    values = [lo, *t[:, 0], hi]
    alphas = [t[0, 4], *t[:, 4], t[-1, 4]]         # constant beyond the ends
    points = [imgui.ImVec2(*to_plot(a, b, box, scale)) for a, b in zip(values, alphas)]
    draw.add_polyline(points, imgui.IM_COL32(240, 240, 240, 255), 1.5, 0)
    for row in t:
        x, y = to_plot(row[0], row[4], box, scale)
        r, g, b = (int(round(255 * c)) for c in row[1:4])
        draw.add_circle_filled((x, y), 5.0, imgui.IM_COL32(r, g, b, 255))
        draw.add_circle((x, y), 5.0, imgui.IM_COL32(255, 255, 255, 255))
