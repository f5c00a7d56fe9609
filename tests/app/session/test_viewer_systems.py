"""The viewer's parts for the ray tracer, animation and textures, without a
display: ViewerState's transitions, the settings its frames are drawn with, and the worker's
cancelling of a superseded ray-traced frame."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from app.session.playback import Playback, render_animated
from core.progressive import upscale
from core.renderers.raytrace.progressive import COARSE, trace_progressively
from app.session.state import ViewerState
from app.viewer.worker import RenderWorker
from core.paths import SCENES_DIR
from core.render import render


def _wait(worker, final=True, timeout=120.0):
    """The next result from ``worker`` (the next final one with ``final``)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        result = worker.collect()
        if result is not None and (result.final or not final):
            return result
        time.sleep(0.01)
    raise AssertionError("no result from the worker")


class Recorder:
    """A Control that never cancels and keeps what the job reported and handed over."""

    cancelled = False

    def __init__(self):
        self.partials, self.reports = [], []

    def check(self):
        pass

    def report(self, fraction, detail):
        self.reports.append((fraction, detail))

    def partial(self, frame):
        self.partials.append(frame)


# -- the ray tracer in the window ------------------------------------------------------------

@pytest.fixture
def whitted():
    # 60 x 44: not a multiple of the coarse step, so the upscaled picture is cut to size
    # opened in the z-buffer (the file asks for the ray tracer), so the tests can switch
    return ViewerState.open(SCENES_DIR / "whitted.toml", size=(60, 44), renderer_name="zbuffer")


def test_ray_traced_is_a_setting_of_the_next_frame(whitted):
    state = whitted
    assert state.renderer_name == "zbuffer" and state.choices.settings().renderer == "zbuffer"
    state.frames.update()
    state.choices.set_renderer("raytrace")
    assert state.dirty and state.choices.settings().renderer == "raytrace"
    with pytest.raises(ValueError, match="zbuffer"):
        state.choices.set_renderer("photon map")
    assert state.renderer_name == "raytrace"


def test_progressive_frame_is_coarse_first_and_ends_as_the_renderers_frame(whitted):
    state = whitted
    state.choices.set_renderer("raytrace")
    settings, control = state.choices.settings(), Recorder()
    final = trace_progressively(state.scene, state.views.current, settings, state.context, render,
                                control=control)
    whole = render(state.scene, state.views.current, settings)
    assert np.array_equal(final.color, whole.color)          # the same rays, filter, rounding
    view = state.views.current
    coarse = render(state.scene, view, settings.replace(size=(8, 6)))   # ceil(60/8) x ...
    assert control.partials[0].stats["pass"] == "coarse (1 ray per 8 x 8 pixels)"
    assert np.array_equal(control.partials[0].color, upscale(coarse.color, COARSE, 60, 44))
    assert control.partials[0].color.shape == (44, 60, 3)
    fractions = [f for f, _ in control.reports]
    assert fractions[0] == 0.0 and fractions[-1] == 1.0 and fractions == sorted(fractions)
    assert control.reports[-1][1] == "refining: tile 4 of 4"     # 60 x 44 in 32-pixel tiles
    # state.frames.update() draws the same finished frame
    assert state.frames.update() and np.array_equal(state.frame.color, whole.color)
    assert not state.frame_partial


def test_a_view_change_cancels_the_ray_traced_frame_at_its_next_tile(whitted, monkeypatch):
    import core.renderers.raytrace.draw as tracer

    state = whitted
    state.choices.set_renderer("raytrace")
    real, traced, first_tile = tracer.trace_tile, [], threading.Event()

    def slow_tile(setup, r0, r1, c0, c1):
        traced.append(setup.view)
        first_tile.set()
        time.sleep(0.3)
        return real(setup, r0, r1, c0, c1)

    monkeypatch.setattr(tracer, "trace_tile", slow_tile)
    worker = RenderWorker()
    try:
        first_view = state.views.current
        assert state.frames.request(worker)
        coarse = _wait(worker, final=False)
        assert not coarse.final and state.frames.accept(coarse) and state.frame_partial
        assert worker.waiting and worker.progress().frame
        assert first_tile.wait(30)
        deadline = time.monotonic() + 30                  # the progress line follows the tiles
        while not worker.progress().detail.startswith("refining") and time.monotonic() < deadline:
            time.sleep(0.02)
        progress = worker.progress()
        assert progress.detail == "refining: tile 1 of 4" and progress.fraction == 0.25
        state.views.next_view()                                 # the user moves on
        assert state.frames.request(worker)
        result = _wait(worker)
        assert state.frames.accept(result) and not state.frame_partial
        old = sum(1 for v in traced if v is first_view)
        assert 1 <= old < 4, "the superseded frame stopped at its next tile"
        whole = render(state.scene, state.views.current, state.choices.settings())
        assert np.array_equal(state.frame.color, whole.color)
    finally:
        worker.stop()


def test_the_zbuffer_picture_stays_until_the_coarse_traced_one_arrives(whitted):
    state = whitted
    state.frames.update()
    zbuffer = state.frame
    state.choices.set_renderer("raytrace")
    gate = threading.Event()
    run, _ = state.frames.job()
    worker = RenderWorker()
    try:
        worker.submit(lambda control: gate.wait(30) and run(control), "traced", control=True)
        state.dirty = False
        time.sleep(0.2)
        assert worker.collect() is None and state.frame is zbuffer    # still the z-buffer's
        gate.set()
        first = _wait(worker, final=False)
        state.frames.accept(first)
        # The first traced picture replaces it: the coarse one, or the finished one when the
        # small frame was traced before the worker was polled (the newest result is kept).
        assert state.frame is not zbuffer and state.frame.stats["renderer"] == "raytrace"
        assert state.frame_partial == (not first.final)
    finally:
        worker.stop()


def test_a_superseded_job_learns_it_and_its_pictures_are_dropped():
    worker = RenderWorker()
    seen, release = [], threading.Event()

    def job(control):
        control.partial("old coarse")
        release.wait(5)
        seen.append(control.cancelled)
        control.partial("old refined")          # too late: dropped
        control.check()                          # raises Cancelled
        seen.append("not reached")

    try:
        worker.submit(job, "old", control=True)
        assert _wait(worker, final=False).frame == "old coarse"
        worker.submit(lambda: "new frame", "new")
        release.set()
        assert _wait(worker).frame == "new frame"
        assert seen == [True]
    finally:
        worker.stop()


# -- playing an animated scene ---------------------------------------------------------------

class Clip:
    """The least an Animation needs for a Playback."""

    def __init__(self, duration=2.0, fps=10.0, loop=False):
        self.duration, self.fps, self.loop = duration, fps, loop

    @property
    def frame_count(self):
        return max(1, int(round(self.duration * self.fps)))


def test_playback_runs_on_the_wall_clock_and_steps_whole_frames():
    p = Playback(Clip(duration=2.0, fps=10.0))
    assert not p.tick(5.0) and p.time == 0.0                # paused: nothing moves
    p.toggle(now=10.0)
    assert p.playing and p.tick(10.5) and p.time == pytest.approx(0.5)
    p.set_speed(2.0)
    assert p.tick(10.75) and p.time == pytest.approx(1.0)
    assert p.tick(12.0) and p.time == pytest.approx(1.9) and not p.playing
    # no loop: it stops on its last frame, the last picture `animate` writes: "20 of 20"
    assert p.frame_index == 19 and "frame 20 of 20" in p.label()
    p.seek(5.0)
    assert p.time == pytest.approx(1.9) and "frame 20 of 20" in p.label()
    p.toggle(now=20.0)
    assert p.playing and p.time == 0.0                       # play at the end starts again
    p.step(+1)
    assert not p.playing and p.time == pytest.approx(0.1) and p.frame_index == 1
    p.step(-3)
    assert p.time == 0.0                                      # clamped at the start
    p.seek(1.25)
    assert p.frame_index == 12 and p.label().startswith("t = 1.25 s of 2.00 s, frame 13 of 20")
    looping = Playback(Clip(duration=2.0, fps=10.0, loop=True))
    looping.toggle(now=0.0)
    looping.tick(2.5)
    assert looping.playing and looping.time == pytest.approx(0.5)   # wraps
    looping.step(-6)
    assert looping.time == pytest.approx(1.9)
    with pytest.raises(ValueError, match="speed"):
        p.set_speed(0)


def test_the_timeline_never_counts_past_its_last_frame():
    # 2.04 s at 10 fps rounds to 20 frames; neither end reads "frame 21 of 20"
    for loop in (False, True):
        p = Playback(Clip(duration=2.04, fps=10.0, loop=loop))
        p.toggle(now=0.0)
        p.tick(2.035)
        assert p.frame_index <= 19 and "of 20" in p.label() and "frame 21" not in p.label()
    ends = Playback(Clip(duration=2.0, fps=10.0))
    ends.step(+1000)
    assert ends.time == pytest.approx(1.9) and ends.label().startswith("t = 1.90 s of 2.00 s, frame 20 of 20")


@pytest.fixture
def fountain():
    return ViewerState.open(SCENES_DIR / "fountain.toml", size=(48, 40))


def test_animated_scene_plays_steps_and_left_click_views(fountain):
    state = fountain
    assert state.player.animated and state.keyed_view and not state.player.playing
    state.frames.update()
    state.player.toggle(100.0)
    assert state.player.playing and state.dirty
    state.frames.update()
    assert not state.player.tick(100.4, busy=True)                 # the frame is still being drawn
    assert state.player.tick(100.4, busy=False) and state.dirty
    assert state.playback.time == pytest.approx(0.4)
    state.player.toggle(101.0)
    assert not state.player.playing
    state.player.step(+1)                                      # '.': frame 13 at 30 fps
    assert state.playback.time == pytest.approx(13 / 30) and state.dirty
    state.player.step(-1)
    assert state.playback.time == pytest.approx(12 / 30)
    # views: the keyed camera, then the file's views, then the keyed camera again
    labels = []
    for _ in range(state.views.count + 1):
        state.views.next_view()
        labels.append(state.views.label)
    assert labels[-1].startswith("the keyed view") and labels[0] == "view 1 of 2"


def test_animated_frames_are_render_at_and_seeking_back_resimulates(fountain):
    from core.animation.frames import render_at
    from core.animation.keys import animation_of
    from core.scene.formats import load_scene

    state = fountain
    state.player.seek(0.3)
    state.frames.update()
    state.player.seek(0.6)                       # forward: the particle simulation continues
    state.frames.update()
    system = state.playback.animation.particle_system
    at_06 = system.step_index
    fresh = animation_of(load_scene(SCENES_DIR / "fountain.toml", size=(48, 40)))
    expected = render_at(fresh, 0.6, state.choices.settings(), view_index=0)
    assert np.array_equal(state.frame.color, expected.color)
    assert len(np.unique(expected.color.reshape(-1, 3), axis=0)) > 10
    # back to 0.45: the simulation starts again from its snapshot at step 0 (one every 240
    # steps), reporting how far it is
    control = Recorder()
    again = render_animated(state.playback.animation, 0.45, state.choices.settings(), state.context,
                            0, control)
    assert system.step_index < at_06
    assert control.reports and "simulating the particles again from step 0" in control.reports[0][1]
    assert np.array_equal(again.color, render_at(fresh, 0.45, state.choices.settings(),
                                                 view_index=0).color)


def test_a_file_view_of_an_animated_scene_is_render_ats_numbering(fountain):
    from core.animation.frames import render_at

    state = fountain
    state.views.set_view(1)                      # the file's second view: render_at's index 2
    assert not state.keyed_view
    state.frames.update()
    expected = render_at(state.playback.animation, 0.0, state.choices.settings(), view_index=2)
    assert np.array_equal(state.frame.color, expected.color)


# -- texture filter and the bump demo ------------------------------------------------------

def test_texture_filter_and_bump_are_settings_of_the_next_frame(whitted):
    state = whitted
    assert state.choices.settings().texture_filter == "trilinear" and state.choices.settings().bump
    state.frames.update()
    assert state.choices.next_texture_filter() == "anisotropic" and state.dirty
    assert state.choices.next_texture_filter() == "nearest"
    state.choices.set_texture_filter("bilinear")
    assert state.choices.settings().texture_filter == "bilinear"
    with pytest.raises(ValueError, match="nearest"):
        state.choices.set_texture_filter("cubic")
    state.choices.set_bump(False)
    assert state.choices.settings().bump is False
    assert not state.choices.is_bump_demo and state.choices.bump_label is None


def test_bump_demo_clicks_change_map_and_mode_like_the_cli():
    from core.scene.formats import load_scene
    from core.settings import RenderSettings
    from core.texture.demo_scene import apply_demo_options

    path = SCENES_DIR / "bump_demo.toml"
    state = ViewerState.open(path, size=(64, 64))
    assert state.choices.is_bump_demo
    assert state.choices.bump_label == "Bump: B(x,y) = sin((x^2 + y^2)^0.5)"
    assert [state.choices.next_bump_map() for _ in range(4)] == [1, 2, 3, 0]
    state.choices.next_bump_map()
    state.choices.next_bump_map()                                  # map 2
    for bump in (True, False):
        state.choices.set_bump(bump)
        assert state.frames.update()
        # what `render scenes/bump_demo.toml --bump-map 2 [--no-bump]` draws
        scene = load_scene(path, size=(64, 64))
        apply_demo_options(scene, 2, bump)
        cli = render(scene, scene.views[0],
                     RenderSettings.for_scene(scene, size=(64, 64),
                                              bump=None if bump else False))
        assert np.array_equal(state.frame.color, cli.color)
    assert state.choices.bump_label == "Phong"


def test_a_scene_file_can_ask_for_the_ray_tracer(tmp_path):
    from core.scene.formats import ReaderError, load_scene
    from core.settings import RenderSettings

    text = (SCENES_DIR / "torus.toml").read_text()
    traced = tmp_path / "traced.toml"
    traced.write_text('renderer = "raytrace"\n' + text)
    scene = load_scene(traced)
    assert scene.renderer == "raytrace"
    assert RenderSettings.for_scene(scene).renderer == "raytrace"
    state = ViewerState.open(traced, size=(40, 30))
    assert state.renderer_name == "raytrace"
    # the command line's `view --renderer zbuffer` wins over the file
    assert ViewerState.open(traced, size=(40, 30), renderer_name="zbuffer").renderer_name == \
        "zbuffer"
    assert load_scene(SCENES_DIR / "torus.toml").renderer == "zbuffer"      # the default
    bad = tmp_path / "bad.toml"
    bad.write_text('renderer = "photon-mapping"\n' + text)
    with pytest.raises(ReaderError, match=r"bad.toml:1: renderer: .*raytrace"):
        load_scene(bad)


def test_the_status_speaks_of_textures_only_where_there_are_some(whitted):
    assert not whitted.choices.has_textures
    assert ViewerState.open(SCENES_DIR / "texture_floor.toml", size=(40, 30)).choices.has_textures


def test_a_letterboxed_progressive_frame_is_the_renderers_too(whitted):
    whitted.choices.set_renderer("raytrace")
    whitted.choices.set_keep_aspect(True)                   # 60 x 44: letterboxed, not stretched
    settings, view = whitted.choices.settings(), whitted.views.current
    final = trace_progressively(whitted.scene, view, settings, whitted.context, render)
    assert np.array_equal(final.color, render(whitted.scene, view, settings).color)
    stretched = render(whitted.scene, view, settings.replace(keep_aspect=False))
    assert not np.array_equal(final.color, stretched.color)
