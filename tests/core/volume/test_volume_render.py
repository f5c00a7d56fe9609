"""The volume renderer (core.renderers.volume.draw, core.volume.raymarch) against exact integrals:
the emission–absorption of a homogeneous sphere, MIP against scipy's trilinear samples, and
the rays cut at an opaque sphere's depth, each pixel derived by hand."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera.rays import camera_rays
from core.camera.view import View
from core.render import render
from core.scene.generators import uv_sphere
from core.scene.model import Light, Material, Scene
from core.settings import RenderSettings
from core.volume import generators
from core.volume.data import Volume, attach_volumes
from core.volume.raymarch import march_volume
from core.renderers.volume.draw import step_of
from tests.tools import need_module

ndimage = need_module("scipy.ndimage", "scipy's map_coordinates is the trilinear oracle")


def looking(vpn, size=1.0):
    return View(vrp=(0, 0, 0), vpn=vpn, vup=(0, 1, 0), window=(-size, size, -size, size),
                prp=(0, 0, 6), front=3, back=-3, label="test view")


def scene_with(volumes, meshes=(), background=(0, 0, 0), view=None):
    scene = Scene(name="volume test", meshes=list(meshes), views=[view or looking((0, 0, 1))],
                  background=background, ambient=(1.0, 1.0, 1.0),
                  lights=[Light(position=(3, 4, 5))])
    attach_volumes(scene, volumes)
    return scene


def draw(scene, size, projection="parallel"):
    settings = RenderSettings.for_scene(scene, renderer="volume", size=size,
                                        projection=projection, shading="flat")
    frame = render(scene, scene.views[0], settings)
    assert frame.message is None
    return frame.color.astype(np.float64) / 255.0


def pixel_centres(n, size=1.0):
    """World (x, y) of each pixel centre of an n x n frame over the window [-size, size]²
    seen along -z (rows top first)."""
    c = -size + (np.arange(n) + 0.5) * 2 * size / n
    return np.meshgrid(c, c[::-1])


def test_homogeneous_sphere_is_c_times_one_minus_exp_of_sigma_chord():
    sigma, c, r = 2.0, 0.8, 0.8
    values, spacing = generators.sphere(97, radius=r, density=sigma)     # h = 1/48
    volume = Volume(values=values, spacing=spacing, lighting="none",
                    transfer=np.array([[0.0, c, c, c, 0.0], [sigma, c, c, c, sigma]]))
    n = 49                                     # odd: the middle pixel looks through the centre
    image = draw(scene_with([volume]), (n, n))
    x, y = pixel_centres(n)
    rho = np.hypot(x, y)
    chord = 2 * np.sqrt(np.clip(r * r - rho * rho, 0.0, None))
    expected = c * (1 - np.exp(-sigma * chord))
    assert image[n // 2, n // 2, 0] == pytest.approx(c * (1 - np.exp(-sigma * 2 * r)),
                                                     abs=1 / 255)
    h = spacing[0]
    # within three samples of the silhouette the data is the boundary's ramp sampled on a
    # grid, not the sphere (measured before rounding: 0.0030 at 2 samples, 0.0017 at 3, the
    # same at half and a quarter of the step: the data's error, not the integrator's);
    # everywhere else the integral holds to 1/255
    inside, outside = rho < r - 3 * h, rho > r + 2 * h
    assert np.abs(image[..., 0] - expected)[inside].max() <= 1 / 255
    assert np.all(image[outside] == 0.0)
    assert np.all(image[..., 0] == image[..., 2])          # grey: the emission is grey


def test_mip_of_the_phantom_is_the_largest_sample_along_each_ray():
    values, spacing = generators.shepp_logan(48)
    volume = Volume(values=values, spacing=spacing, mode="mip")
    view = looking((0.3, 0.2, 1.0), 1.2)
    n = 24
    origins, directions, t_lo, t_hi = camera_rays(view, "parallel", n, n)
    _, _, largest = march_volume(volume, origins, directions, t_lo, t_hi, step_of(volume),
                                 np.zeros((0, 10)), np.zeros(3), np.array([0.0, 0, 0, 1]))
    # the samples, placed independently: each ray clipped to the grid's box in index space,
    # segment midpoints, and scipy's trilinear interpolation
    m_inv = np.linalg.inv(volume.world_from_index())
    o = origins @ m_inv[:3, :3].T + m_inv[:3, 3]
    d = directions @ m_inv[:3, :3].T
    hi = np.array(values.shape) - 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (0.0 - o) / d, (hi - o) / d
    t0 = np.maximum(np.minimum(ta, tb).max(1), t_lo)
    t1 = np.minimum(np.maximum(ta, tb).min(1), t_hi)
    step = step_of(volume)
    hit = 0
    for k in range(len(o)):
        if not t0[k] < t1[k]:
            assert largest[k] == -np.inf
            continue
        starts = t0[k] + step * np.arange(int((t1[k] - t0[k]) // step) + 1)
        starts = starts[starts < t1[k]]
        mids = starts + 0.5 * np.minimum(step, t1[k] - starts)
        points = o[k] + mids[:, None] * d[k]
        samples = ndimage.map_coordinates(values.astype(np.float64), points.T, order=1)
        assert largest[k] == pytest.approx(samples.max(), rel=1e-12, abs=1e-12)
        hit += 1
    assert hit > n * n // 2
    # and the picture shows it as grey over the data's range
    image = draw(scene_with([volume], view=view), (n, n))
    lo, top = volume.value_range
    grey = np.where(np.isfinite(largest), (largest - lo) / (top - lo), 0.0).reshape(n, n)
    assert np.array_equal(np.round(image[..., 0] * 255), np.floor(grey * 255 + 0.5))


def test_an_opaque_sphere_half_inside_cuts_the_rays_at_its_depth():
    # A homogeneous cube [-1, 1]³ (σ, grey c) seen along +z, an opaque sphere of radius 0.5
    # about (0, 0, 1) half inside it, lit by ambient only (its colour is O_d).
    sigma, c, od = 1.5, 0.6, (0.2, 0.9, 0.3)
    volume = Volume(values=np.ones((9, 9, 9), np.float32), spacing=(0.25, 0.25, 0.25),
                    lighting="none",
                    transfer=np.array([[0.0, c, c, c, sigma], [1.0, c, c, c, sigma]]))
    ball = uv_sphere(0.5, segments=192, rings=96)
    ball.positions = ball.positions + (0.0, 0.0, 1.0)
    ball.closed = True
    ball.material = Material(ka=1.0, kd=0.0, ks=0.0, od=od)
    background = (0.1, 0.1, 0.1)
    n = 41
    image = draw(scene_with([volume], [ball], background, view=looking((0, 0, -1))), (n, n))
    x, y = pixel_centres(n)
    rho = np.hypot(x, y)
    hits = rho < 0.5
    # the ray enters the cube at z = -1 and stops on the sphere's near side, at
    # z = 1 - sqrt(0.25 - rho²): L = 2 - sqrt(0.25 - rho²); without the sphere L = 2
    length = np.where(hits, 2 - np.sqrt(np.clip(0.25 - rho * rho, 0.0, None)), 2.0)
    behind = np.where(hits[..., None], np.array(od), np.array(background))
    through = np.exp(-sigma * length)[..., None]
    expected = c * (1 - through) + through * behind
    clear = np.abs(rho - 0.5) > 2 * 2.0 / n              # away from the sphere's outline
    assert np.abs(image - expected)[clear].max() <= 1 / 255
    assert np.abs(image - expected)[hits & clear].max() <= 1 / 255
    # the sphere shows through less where more of the cube lies in front of it
    assert image[n // 2, n // 2, 1] > image[n // 2, n // 2 + 8, 1]


def test_gradient_shading_lights_the_side_facing_the_light():
    values, spacing = generators.sphere(49, radius=0.7, density=8.0)
    volume = Volume(values=values, spacing=spacing, lighting="gradient",
                    material=Material(ka=0.1, kd=0.9, ks=0.0),
                    transfer=np.array([[0.0, 1, 1, 1, 0.0], [8.0, 1, 1, 1, 8.0]]))
    scene = scene_with([volume])
    scene.ambient = (0.2, 0.2, 0.2)
    scene.lights = [Light(direction=(1.0, 0.0, 0.3))]         # from +x
    image = draw(scene, (33, 33))
    row = image[16, :, 0]
    assert row[16 + 8] > row[16 - 8] + 0.2                     # the lit side is brighter
    assert row[16 - 8] > 0.05                                  # the dark side has ambient


def test_the_inspector_names_the_ray_the_volumes_and_the_isosurface_cell():
    from core.inspect import inspect_pixel
    from core.volume.marching import isosurface
    values, spacing = generators.sphere(17, radius=0.5, density=1.0)
    surface_volume = Volume(values=values, spacing=spacing, mode="isosurface", iso=0.5,
                            name="ball", material=Material(ka=1.0, kd=0.0, ks=0.0))
    fog = Volume(values=np.ones((5, 5, 5), np.float32), spacing=(0.5, 0.5, 0.5),
                 lighting="none", name="fog",
                 transfer=np.array([[0.0, 0.5, 0.5, 0.5, 0.7], [1.0, 0.5, 0.5, 0.5, 0.7]]))
    glow = Volume(values=values, spacing=spacing, mode="mip", name="glow",
                  transform=np.diag([1.0, 1.0, 1.0, 1.0]))
    glow.transform[:3, 3] = (0.0, 0.0, -0.9)
    scene = scene_with([surface_volume, fog], [isosurface(surface_volume)])
    settings = RenderSettings.for_scene(scene, renderer="volume", size=(21, 21),
                                        projection="parallel", shading="flat")
    frame = render(scene, scene.views[0], settings)
    for x, y in ((10, 10), (1, 1)):
        record = inspect_pixel(scene, scene.views[0], settings, x, y)
        assert record["renderer"] == "volume" and record["pixel"] == [x, y]
        assert record["color"] == frame.color[y, x].tolist()
        (fogged,) = record["volumes"]
        assert fogged["volume"] == "fog" and fogged["samples"] > 0
    centre = inspect_pixel(scene, scene.views[0], settings, 10, 10)
    cell = centre["isosurface cell"]
    # the ray through the centre meets the ball's near pole (0, 0, 0.5): index z 12 of 16
    assert cell["volume"] == "ball" and cell["cell"][2] in (11, 12)
    corners = np.array(cell["corner values"])
    assert corners.min() <= 0.5 <= corners.max()          # the surface crosses this cell
    assert centre["ray"]["stopped by the opaque surface at t"] < np.inf
    # the fog is marched only up to the ball: from its front face (z = 1) to z = 0.5
    fogged = centre["volumes"][0]
    assert fogged["enters at t"] == pytest.approx(3.0 - 1.0)
    assert fogged["leaves at t"] == pytest.approx(3.0 - 0.5, abs=0.01)
    # MIP: the largest sample and the cell it lies in
    scene = scene_with([glow])
    record = inspect_pixel(scene, scene.views[0], settings, 10, 10)
    (mip,) = record["volumes"]
    assert mip["largest sample"] == pytest.approx(1.0)
    assert np.max(mip["at"]["corner values"]) == pytest.approx(1.0)
    assert record["color"] == render(scene, scene.views[0], settings).color[10, 10].tolist()


def test_other_renderers_say_they_leave_the_marched_volumes_out():
    values, spacing = generators.sphere(9)
    fog = Volume(values=values, spacing=spacing, mode="mip", name="fog")
    scene = scene_with([fog], [uv_sphere(0.3)])
    settings = RenderSettings.for_scene(scene, renderer="zbuffer", size=(8, 8))
    notes = render(scene, scene.views[0], settings).stats["not drawn"]
    assert "the volumes drawn by ray marching (fog): --renderer volume draws them" in notes
    settings = settings.replace(renderer="volume")
    assert not any("ray marching" in n for n in render(scene, scene.views[0], settings).stats[
        "not drawn"])
