"""What a RenderContext keeps from frame to frame, and that a kept answer never outlives its
question: a frame drawn after others in one context is the frame a fresh context draws."""

from __future__ import annotations

import dataclasses

import numpy as np

from core.context import RenderContext
from core.render import render
from core.scene.generators import sphere_torus
from core.settings import RenderSettings


def test_remembered_keeps_the_answer_for_the_last_key_only():
    context, calls = RenderContext(), []

    def compute(value):
        calls.append(value)
        return [value]

    first = context.remembered("kind", ("a", 1), lambda: compute(1))
    assert context.remembered("kind", ("a", 1), lambda: compute(2)) is first
    assert context.remembered("kind", ("a", 2), lambda: compute(3)) == [3]
    assert context.remembered("kind", ("a", 1), lambda: compute(4)) == [4]
    assert calls == [1, 3, 4]


def test_remembered_computes_each_time_for_keys_of_arrays_it_cannot_compare():
    context, calls = RenderContext(), []
    for n in range(2):
        key = (np.arange(3.0),)           # equal numbers, another array: no single answer
        assert context.remembered("kind", key, lambda: calls.append(n) or n) == n
    assert calls == [0, 1]


def _frame(scene, view, context, shading="phong"):
    settings = RenderSettings.for_scene(scene, shading=shading, size=(96, 72))
    return render(scene, view, settings, context).color.copy()


def test_a_frame_after_others_in_one_context_is_the_fresh_contexts_frame():
    scene = sphere_torus(triangles=2_000)
    view = scene.views[0]
    moved = dataclasses.replace(view, vrp=tuple(np.asarray(view.vrp) + (0.3, -0.2, 0.1)))
    kept = RenderContext()
    for shading in ("flat", "gouraud", "phong"):
        _frame(scene, view, kept, shading)
        assert np.array_equal(_frame(scene, moved, kept, shading),
                              _frame(scene, moved, RenderContext(), shading))
        assert np.array_equal(_frame(scene, view, kept, shading),
                              _frame(scene, view, RenderContext(), shading))


def test_a_light_changed_between_frames_is_lit_anew():
    scene = sphere_torus(triangles=2_000)
    view = scene.views[0]
    kept = RenderContext()
    before = _frame(scene, view, kept)
    scene.lights[0] = dataclasses.replace(scene.lights[0], intensity=(1e308, 1e308, 1e308))
    after = _frame(scene, view, kept)                 # float32 cannot hold these terms
    assert np.array_equal(after, _frame(scene, view, RenderContext()))
    assert not np.array_equal(after, before)
