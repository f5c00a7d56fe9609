"""The volume marched a chunk of rays at a time (core.renderers.volume.draw.march_in_chunks, so
that a large frame reports its progress and stops on Ctrl+C): the numbers of one call over every
ray."""

from __future__ import annotations

import numpy as np
import pytest

from core import work
from core.camera.rays import camera_rays
from core.camera.view import View, eye_from_view
from core.scene.model import Light
from core.shading.illumination import pack_ambient, pack_eye, pack_lights
from core.renderers.volume import draw as renderer
from core.volume import generators
from core.volume.data import Volume
from core.volume.raymarch import march_volume

VIEW = View(vrp=(0, 0, 0), vpn=(0.3, 0.2, 1.0), vup=(0, 1, 0), window=(-1.2, 1.2, -1.2, 1.2),
            prp=(0, 0, 6), front=3, back=-3, label="test view")


@pytest.mark.parametrize("mode, lighting", [("emission-absorption", "gradient"),
                                            ("mip", "none")])
def test_chunks_of_rays_give_the_numbers_of_one_call(monkeypatch, mode, lighting):
    values, spacing = generators.shepp_logan(40)
    volume = Volume(values=values, spacing=spacing, mode=mode, lighting=lighting,
                    transfer=np.array([[0.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 0.8, 0.6, 4.0]]))
    origins, directions, t_lo, t_hi = camera_rays(VIEW, "perspective", 61, 47)
    marching = (renderer.step_of(volume), pack_lights([Light(position=(3, 4, 5))]),
                pack_ambient((0.2, 0.2, 0.2)), pack_eye(eye_from_view(VIEW, "perspective")))
    whole = march_volume(volume, origins, directions, t_lo, t_hi, *marching)
    monkeypatch.setattr(renderer, "FIRST_CHUNK", 97)
    monkeypatch.setattr(work, "CHUNK_SECONDS", 1e-9)      # then a ray a chunk
    reports = []
    with work.watching(lambda *report: reports.append(report)):
        chunked = renderer.march_in_chunks(volume, origins, directions, t_lo, t_hi, *marching)
    n = len(origins)
    done = [d for _, d, _, _ in reports]
    assert done[:3] == [0, 97, 98] and done[-1] == n and done == sorted(set(done))
    assert {(what, total, unit) for what, _, total, unit in reports} == {("ray marching", n, "ray")}
    for a, b in zip(whole, chunked):
        assert np.array_equal(a, b)
    assert np.ptp(whole[1] if mode != "mip" else whole[2][np.isfinite(whole[2])]) > 0
