"""The window's volume controls without a window (app.session.volume_controls and the
ViewerState methods the panel calls): the iso value re-extracts the sphere's surface where
its ramp puts it, on the render worker's thread; a transfer point's drag changes the rendered
picture by the exact integral; a slice is the array's slice; bad values keep the last good
state with a message."""

from __future__ import annotations

import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest

from app.session import volume_controls
from app.session.state import ViewerState
from app.viewer.volume_panel import from_plot, nearest_point, plot_scale, to_plot
from app.viewer.worker import RenderWorker
from core.camera.view import View
from core.scene.model import Light, Scene
from core.volume import generators
from core.volume.data import Volume, attach_volumes
from core.volume.marching import isosurface, marching_cubes


def looking(size=1.0):
    return View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-size, size, -size, size),
                prp=(0, 0, 6), front=3, back=-3, label="test view")


def volume_state(volume, size=(40, 40), **kwargs):
    scene = Scene(name="volume controls", meshes=[], views=[looking()], background=(0, 0, 0),
                  ambient=(1.0, 1.0, 1.0), lights=[Light(position=(3, 4, 5))])
    if volume.mode == "isosurface":
        scene.meshes.append(isosurface(volume))
    attach_volumes(scene, [volume])
    return ViewerState(scene=scene, scene_source="test", size=size, projection="parallel",
                       shading="flat", **kwargs)


def stub_frame(scene, view, settings, context=None):
    """A frame without rendering (the iso tests count triangles, not pixels)."""
    return SimpleNamespace(color=np.zeros((40, 40, 3), np.uint8), message=None, stats={})


def sphere_volume(iso=0.5):
    # 41 samples over [-1, 1]: h = 0.05; radius 0.6 is 12 samples
    values, spacing = generators.sphere(41, radius=0.6, density=1.0)
    return Volume(values=values, spacing=spacing, mode="isosurface", iso=iso, name="ball")


def test_iso_change_re_extracts_the_triangles_counted_by_hand():
    # sphere(5, radius 0.5): h = 0.5, so the centre sample is 1, its 6 face neighbours
    # (d = h) 0.5, its 12 edge neighbours (d = 1.41 h) 0.086, everything else 0.
    values, spacing = generators.sphere(5, radius=0.5, density=1.0)
    volume = Volume(values=values, spacing=spacing, mode="isosurface", iso=0.7, name="ball")
    state = volume_state(volume, renderer=stub_frame)
    state.frames.update()
    # iso 0.7: only the centre is inside; each of its 8 cells cuts off one corner: 8
    assert len(state.scene.meshes[0].triangles) == 8
    # iso 0.3: the centre and its face neighbours; each of the centre's 8 cells holds the
    # centre and three face neighbours (a hexagon: 4 triangles), and each face neighbour is
    # the one inside corner of 4 more cells: 8 · 4 + 6 · 4 = 56
    assert state.volumes.set_iso(0.3) and state.volumes.extracting and state.dirty
    assert len(state.scene.meshes[0].triangles) == 8          # not before the frame's job
    assert state.frames.update()
    assert len(state.scene.meshes[0].triangles) == 56
    assert state.volumes.current.iso == 0.3 and not state.volumes.extracting
    assert state.volumes.set_iso(0.7) and state.frames.update()
    assert len(state.scene.meshes[0].triangles) == 8


def test_iso_moves_the_sphere_s_surface_where_its_ramp_puts_it():
    # the ramp is density · clip((r − d)/h + 1/2, 0, 1): the value iso is crossed at
    # d = r + h (1/2 − iso): iso 0.25 a quarter sample outside r, 0.75 one inside
    state = volume_state(sphere_volume(), renderer=stub_frame)
    for iso in (0.25, 0.5, 0.75):
        state.volumes.set_iso(iso)
        state.frames.update()
        mesh = state.scene.meshes[0]
        radius = np.linalg.norm(mesh.positions, axis=1).mean()
        assert radius == pytest.approx(0.6 + 0.05 * (0.5 - iso), abs=0.005)   # h / 10
        _, triangles, _ = marching_cubes(state.volumes.current.values, iso, "oracle")
        assert len(mesh.triangles) == len(triangles)


def test_iso_is_extracted_on_the_worker_thread_and_the_panel_says_extracting(monkeypatch):
    state = volume_state(sphere_volume(), renderer=stub_frame)
    threads = []
    real = volume_controls.reextract

    def recorded(scene, volume, iso):
        threads.append(threading.current_thread().name)
        return real(scene, volume, iso)

    monkeypatch.setattr(volume_controls, "reextract", recorded)
    worker = RenderWorker()
    try:
        assert state.volumes.set_iso(0.3)
        assert state.volumes.extracting                    # "extracting…" until the frame is in
        assert state.frames.request(worker)
        deadline = time.monotonic() + 120
        result = None
        while result is None and time.monotonic() < deadline:
            result = worker.collect()
            time.sleep(0.02)
        assert result is not None and result.error is None
        state.frames.accept(result)
    finally:
        worker.stop()
    assert threads == ["render"]
    assert threading.current_thread().name != "render"
    assert not state.volumes.extracting and state.volumes.current.iso == 0.3


def test_iso_outside_the_data_keeps_the_last_surface_with_a_message():
    state = volume_state(sphere_volume(), renderer=stub_frame)
    state.frames.update()
    mesh = state.scene.meshes[0]
    assert not state.volumes.set_iso(1.5)
    assert state.volume_message == ("iso: iso 1.5 is outside the data's range (0, 1): no "
                                    "surface; the surface stays at iso 0.5")
    assert not state.dirty and not state.volumes.extracting
    assert not state.frames.update() and state.scene.meshes[0] is mesh
    assert state.volumes.set_iso(0.4) and state.volume_message == ""


def test_an_isosurface_past_the_triangle_limit_keeps_the_last_one(monkeypatch):
    import core.scene.generators as limits
    state = volume_state(sphere_volume(), renderer=stub_frame)
    state.frames.update()
    mesh = state.scene.meshes[0]
    monkeypatch.setattr(limits, "MAX_TRIANGLES", len(mesh.triangles))
    assert state.volumes.set_iso(0.25)                # more triangles than the (lowered) limit
    assert not state.frames.update()
    assert state.scene.meshes[0] is mesh and state.volumes.current.iso == 0.5
    assert not state.volumes.extracting and state.render_error is None
    assert "the limit is" in state.volume_message and "last good iso" in state.volume_message


def emitting_sphere(sigma=1.0, c=0.8):
    values, spacing = generators.sphere(49, radius=0.8, density=sigma)      # h = 1/24
    return Volume(values=values, spacing=spacing, lighting="none", name="glow",
                  transfer=np.array([[0.0, c, c, c, 0.0], [sigma, c, c, c, sigma]]))


def test_dragging_a_transfer_point_changes_the_picture_by_the_exact_integral():
    # extinction = alpha_1 · value / σ on the ramp; through the centre the field integrates
    # to σ · chord (chord 1.6): the middle pixel is c (1 − e^{−alpha_1 · 1.6})
    state = volume_state(emitting_sphere(), size=(21, 21))
    state.choices.set_renderer("volume")
    assert state.frames.update()
    c = 0.8
    middle = state.frame.color[10, 10].astype(float) / 255
    assert middle == pytest.approx([c * (1 - np.exp(-1.6))] * 3, abs=2 / 255)
    old = state.volumes.current.transfer
    assert state.volumes.move_transfer_point(1, 1.0, 2.0) and state.dirty
    assert old[1, 4] == 1.0                  # a new array: a frame being drawn keeps the old
    assert state.frames.update()
    middle = state.frame.color[10, 10].astype(float) / 255
    assert middle == pytest.approx([c * (1 - np.exp(-3.2))] * 3, abs=2 / 255)
    assert state.frame.color[0, 0].tolist() == [0, 0, 0]          # outside: the background


def test_a_transfer_with_negative_alpha_keeps_the_last_good_one():
    state = volume_state(emitting_sphere(), renderer=stub_frame)
    state.frames.update()
    before = state.volumes.current.transfer.copy()
    assert not state.volumes.move_transfer_point(1, 1.0, -0.5)
    assert state.volume_message == ("transfer: transfer alpha (extinction per unit length) "
                                    "must be >= 0; the last good transfer function stays")
    assert not state.volumes.move_transfer_point(1, -0.5, 1.0)        # before point 0's value
    assert "must increase strictly" in state.volume_message
    assert np.array_equal(state.volumes.current.transfer, before) and not state.dirty


def test_a_slice_is_the_volumes_array_slice_exactly():
    rng = np.random.default_rng(7)
    values = rng.random((5, 6, 7), dtype=np.float32)
    volume = Volume(values=values, name="noise")
    assert np.array_equal(volume_controls.slice_values(volume, "axial", 3), values[:, :, 3])
    assert np.array_equal(volume_controls.slice_values(volume, "coronal", 5), values[:, 5, :])
    assert np.array_equal(volume_controls.slice_values(volume, "sagittal", 0), values[0, :, :])
    with pytest.raises(ValueError, match=r"axial slice index must be in 0..6, not 7"):
        volume_controls.slice_values(volume, "axial", 7)
    # the picture: x across, y up, 10 pixels a sample (50 x 60 holds 5 x 6 exactly)
    picture = volume_controls.slice_picture(volume, "axial", 3, (50, 60))
    lo, hi = volume.value_range
    grey = lambda v: int(np.floor((v - lo) / (hi - lo) * 255 + 0.5))      # noqa: E731
    assert picture[0, 0, 0] == grey(values[0, 5, 3])          # top left: x = 0, y = last
    assert picture[59, 49, 1] == grey(values[4, 0, 3])        # bottom right: x last, y = 0
    assert picture[25, 17, 2] == grey(values[1, 3, 3])


def test_the_state_picks_the_middle_slice_and_refuses_one_past_the_end():
    state = volume_state(sphere_volume(), renderer=stub_frame)
    assert state.volumes.slice_shown() == 20
    state.volumes.set_slice("sagittal", 40)
    assert state.volumes.slice_shown() == 40
    with pytest.raises(ValueError, match="sagittal slice index must be in 0..40, not 41"):
        state.volumes.set_slice("sagittal", 41)
    with pytest.raises(ValueError, match="slice must be one of axial, coronal, sagittal"):
        state.volumes.set_slice("oblique")


def test_the_plot_maps_points_to_pixels_and_back():
    volume = emitting_sphere()
    box, scale = (10.0, 20.0, 200.0, 100.0), plot_scale(volume)
    assert scale == (0.0, 1.0, 1.25)                          # alpha axis 1.25 × the largest
    assert to_plot(1.0, 1.0, box, scale) == (210.0, 40.0)
    assert from_plot(210.0, 40.0, box, scale) == pytest.approx((1.0, 1.0))
    assert nearest_point(volume.transfer, 206.0, 43.0, box, scale) == 1
    assert nearest_point(volume.transfer, 100.0, 60.0, box, scale) is None


def test_the_slice_buffer_view_follows_the_slider_and_the_frame():
    from app.viewer.inspector_tools import PICTURE, InspectorTools
    state = volume_state(sphere_volume(), renderer=stub_frame)
    state.frames.update()
    tools = InspectorTools(state)
    assert tools.buffer_names()[-3:] == ("axial", "coronal", "sagittal")
    tools.choose_buffer("axial", "test")
    assert tools.buffer == "axial" and tools.changed
    expected = volume_controls.slice_picture(state.volumes.current, "axial", 20, (40, 40))
    assert np.array_equal(tools.picture(state.frame), expected)
    tools.show_slice("sagittal", 3, "test")
    assert state.slice_name == "sagittal" and state.volumes.slice_shown() == 3
    expected = volume_controls.slice_picture(state.volumes.current, "sagittal", 3, (40, 40))
    assert np.array_equal(tools.overlay, expected)
    state.dirty = True
    state.frames.update()
    tools.frame_changed(state.frame, state.frame_seconds)      # a new frame keeps the slice
    assert tools.buffer == "sagittal" and np.array_equal(tools.overlay, expected)
    tools.choose_buffer(PICTURE, "test")
    assert tools.buffer == PICTURE and tools.overlay is None
    # a re-extracted surface: the inspector's own caches of the scene are dropped
    tools.context().cache(state.scene)["held"] = "the old mesh's"
    state.volumes.set_iso(0.3)
    state.frames.update()
    tools.frame_changed(state.frame, state.frame_seconds)
    assert "held" not in tools.context().cache(state.scene)
