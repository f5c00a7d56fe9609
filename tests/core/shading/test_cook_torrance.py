"""The Cook–Torrance lighting model (core.shading.models.cook_torrance; FvDFH 16.7).

- the local model at chosen angles against values derived by hand: N along z, L and V chosen
  so that H and the cosines are simple fractions; the expected values are computed from
  those fractions in exact rational arithmetic (Fraction), Beckmann's exponential the one
  transcendental factor;
- the BRDF: reciprocal, its directional albedo at most 1 (quadrature over the hemisphere),
  and its sampling consistent with its pdf (the importance-sampled albedo equals the
  quadrature's);
- pictures: a lit plane drawn by the z-buffer, the ray tracer and the path tracer gives the
  same pixels (a point light on a plane has no indirect light: every renderer evaluates the
  same model); the shipped scene; the inspector's terms sum to the pixel.
"""

from __future__ import annotations

import math
from fractions import Fraction as Q

import numpy as np
import pytest

from core import RenderSettings, render
from core.camera.view import View
from core.scene.model import Light, Material, Mesh, Scene
from core.shading import illumination as il
from core.shading.models import model_id, with_model
from core.shading.models.cook_torrance import F0, ROUGHNESS
from core.shading.models.dispatch import glossy, illuminate, sample_glossy

F0_RGB = (0.25, 0.5, 0.75)


def _ct(ks=0.5, kd=0.0, roughness=0.5, f0=F0_RGB, **more) -> Material:
    return with_model(Material(ka=0.0, kd=kd, ks=ks, od=(0.5, 0.5, 0.5), **more),
                      "cook-torrance", {"roughness": roughness, "f0": f0})


def _lit(material, light_direction, toward_viewer):
    """The model at the origin, N = +z, one white directional light, a parallel viewer."""
    surfaces = il.pack_surfaces([material], [False])
    lights = il.pack_lights([Light(direction=light_direction)])
    eye = np.array([il.EYE_DIRECTION, *toward_viewer], dtype=float)
    return illuminate(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), np.zeros(1, np.int64),
                      surfaces, lights, np.zeros(3), eye, False)[0]


def _schlick(f0, vh):
    f0 = Q(f0)
    return f0 + (1 - f0) * (1 - vh) ** 5


@pytest.mark.parametrize("case", ["normal", "tilted", "grazing"])
def test_the_model_at_chosen_angles_against_hand_derived_values(case):
    ks, kd, od, m = Q(1, 2), Q(1, 4), Q(1, 2), Q(1, 2)
    if case == "normal":        # L = V = N: H = N, D = 1/(4 m²) = 1, G = 1, F = F0, N·V = 1
        l, v = (0, 0, 1), (0, 0, 1)
        nl, nv, d, g, vh = 1, 1, 1 / (4 * m * m), 1, 1
    elif case == "tilted":      # L, V mirror images at cos 4/5: H = N, V·H = 4/5, G = 1
        l, v = (0.6, 0, 0.8), (-0.6, 0, 0.8)
        nl, nv, d, g, vh = Q(4, 5), Q(4, 5), 1 / (4 * m * m), 1, Q(4, 5)
    else:                       # L = V at cos 3/5: H = L, N·H = 3/5, tan² β = 16/9,
        l, v = (0.8, 0, 0.6), (0.8, 0, 0.6)  # G = min(1, 2·(3/5)(3/5)/1) = 18/25
        nh, nl, nv, vh = Q(3, 5), Q(3, 5), Q(3, 5), 1
        tan2 = (1 - nh * nh) / (nh * nh)
        d = Q(math.exp(-tan2 / (m * m))) / (4 * m * m * nh ** 4)
        g = min(Q(1), 2 * nh * nv / vh)
        assert g == Q(18, 25)
    expected = [kd * od * nl + ks * _schlick(f0, vh) * d * g / nv for f0 in F0_RGB]
    got = _lit(_ct(ks=0.5, kd=0.25, roughness=0.5), l, v)
    assert got == pytest.approx([float(e) for e in expected], rel=1e-12, abs=0)


def test_no_specular_from_behind_or_below_and_the_clamp():
    assert list(_lit(_ct(kd=0.5), (0, 0, -1), (0, 0, 1))) == [0.0, 0.0, 0.0]
    assert list(_lit(_ct(ks=1.0, roughness=0.05), (0, 0, 1), (0, 0, 1))) == [1.0, 1.0, 1.0]


def _row(roughness=0.3, f0=(1.0, 1.0, 1.0), ks=1.0) -> np.ndarray:
    return il.pack_surfaces([_ct(ks=ks, roughness=roughness, f0=f0)], [False])[0]


def _brdf(row, wo, wi):
    fr, fg, fb, _ = glossy(row, 0, 0.0, 0.0, 1.0, *wo, *wi, 1.0)
    return np.array([fr, fg, fb])


def test_the_brdf_is_reciprocal():
    rng = np.random.default_rng(1)
    row = _row(0.4, F0_RGB)
    for _ in range(200):
        a, b = rng.normal(size=3), rng.normal(size=3)
        a[2], b[2] = abs(a[2]), abs(b[2])
        a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
        assert np.allclose(_brdf(row, a, b), _brdf(row, b, a), rtol=1e-12, atol=0)


def _hemisphere(k=160):
    """Midpoint quadrature over the hemisphere in (cos θ, φ): directions and dω."""
    mu = (np.arange(k) + 0.5) / k
    phi = (np.arange(2 * k) + 0.5) * math.pi / k
    mu, phi = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1 - mu * mu)
    dirs = np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=-1).reshape(-1, 3)
    return dirs, (1.0 / k) * (math.pi / k)


@pytest.mark.parametrize("roughness", [0.2, 0.6])
@pytest.mark.parametrize("cos_o", [1.0, 0.3])
def test_energy_the_albedo_is_at_most_one_and_sampling_agrees(roughness, cos_o):
    """With F = 1 and k_s = 1, ∫ f cos θ_i dω_i <= 1 (quadrature); the estimate from
    sample_glossy's directions weighted by f cos / pdf converges to the same integral."""
    row = _row(roughness)
    wo = np.array([math.sqrt(1 - cos_o * cos_o), 0.0, cos_o])
    dirs, dw = _hemisphere(96)
    albedo = sum(_brdf(row, wo, wi)[0] * wi[2] for wi in dirs) * dw
    assert albedo <= 1.0 + 1e-3
    assert albedo > 0.3                   # a rough mirror still reflects most of the light
    rng = np.random.default_rng(7)
    n, total = 8000, 0.0
    for u1, u2 in rng.random((n, 2)):
        wi = sample_glossy(row, 0, 0.0, 0.0, 1.0, *wo, u1, u2)
        fr, _, _, pdf = glossy(row, 0, 0.0, 0.0, 1.0, *wo, *wi, 1.0)
        if pdf > 0.0 and wi[2] > 0.0:
            total += fr * wi[2] / pdf
    assert total / n == pytest.approx(albedo, rel=0.03)


def _plane_scene(model_material) -> Scene:
    """A 2 x 2 square at z = 0 seen from z = 3, one point light: no shadows, no indirect
    light (nothing else for the light to reach), so every renderer sees the local model."""
    positions = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    mesh = Mesh(positions, np.array([[0, 1, 2], [0, 2, 3]]), normals=np.tile([0, 0, 1.0], (4, 1)),
                material=model_material, name="plane")
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-0.9, 0.9, -0.9, 0.9),
                prp=(0, 0, 3), front=1, back=-1, label="above")
    return Scene(name="plane", meshes=[mesh], views=[view], ambient=(0.0, 0.0, 0.0),
                 lights=[Light(position=(0.3, 0.2, 1.2))])


def test_zbuffer_ray_tracer_and_path_tracer_draw_the_same_plane():
    scene = _plane_scene(_ct(ks=0.8, kd=0.3, roughness=0.3, f0=(0.9, 0.6, 0.3)))
    pictures = {}
    for renderer in ("zbuffer", "raytrace", "pathtrace"):
        settings = RenderSettings.for_scene(scene, shading="phong", renderer=renderer,
                                            size=(24, 24))
        pictures[renderer] = render(scene, scene.views[0], settings).color.astype(int)
    z = pictures["zbuffer"]
    assert z.max() > 200 and z[..., 0].max() > z[..., 2].max()    # F0's warm highlight
    for other in ("raytrace", "pathtrace"):
        assert np.abs(pictures[other] - z).max() <= 1, other


def test_phong_materials_are_drawn_as_before_and_an_override_changes_them():
    """A material that names "phong" is the default's bytes; the override to Cook–Torrance
    is the Cook–Torrance material's."""
    base = Material(ka=0.1, kd=0.4, ks=0.6, n=30, od=(0.7, 0.5, 0.3))
    plain = _plane_scene(base)
    named = _plane_scene(with_model(base, "phong"))
    settings = RenderSettings.for_scene(plain, shading="phong", size=(24, 24))
    a = render(plain, plain.views[0], settings).color
    assert np.array_equal(a, render(named, named.views[0], settings).color)
    over = render(plain, plain.views[0], settings.replace(lighting_model="cook-torrance")).color
    ct = _plane_scene(with_model(base, "cook-torrance"))
    assert np.array_equal(over, render(ct, ct.views[0], settings).color)
    assert not np.array_equal(over, a)


def test_the_parameters_travel_in_the_surface_row():
    row = il.pack_surfaces([_ct(roughness=0.2, f0=(0.1, 0.2, 0.3))], [False])[0]
    assert row[il.MODEL] == model_id("cook-torrance")
    assert list(row[ROUGHNESS:F0 + 3]) == [0.2, 0.1, 0.2, 0.3]
    defaults = il.pack_surfaces([with_model(Material(), "cook-torrance")], [False])[0]
    assert list(defaults[ROUGHNESS:F0 + 3]) == [0.3, 0.04, 0.04, 0.04]


_SCENE = """
name = "t"
[[geometry]]
generator = "uv_sphere"
params = {{ radius = 1.0, segments = 16, rings = 8 }}
material = {{ kd = 0.5{material} }}
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-1.2, 1.2, -1.2, 1.2]
prp = [0, 0, 5]
front = 1.1
back = -1.1
"""


def _read(tmp_path, material: str):
    from core.scene.formats import load_scene
    path = tmp_path / "t.toml"
    path.write_text(_SCENE.format(material=material))
    return load_scene(str(path))


def test_the_scene_keys_choose_the_model_and_bad_ones_say_where(tmp_path):
    from core.scene.formats import ReaderError
    from core.shading.models import model_of
    m = _read(tmp_path, ', model = "cook-torrance", roughness = 0.2, f0 = 0.5').meshes[0].material
    assert model_of(m) == ("cook-torrance", {"roughness": 0.2, "f0": (0.5, 0.5, 0.5)})
    assert model_of(_read(tmp_path, "").meshes[0].material) == ("phong", {})
    cases = {', roughness = 0.2': r"geometry\[1\]\.material\.roughness: is a parameter of the "
                                  r"cook-torrance lighting model: name it with model",
             ', model = "blinn"': r"material\.model: 'blinn' is not one of phong, cook-torrance",
             ', model = "cook-torrance", roughness = 0': r"material\.roughness",
             ', model = "cook-torrance", f0 = [1, 2]': r"material\.f0: expected a list of 3",
             ', model = "phong", f0 = 0.5': r"material\.f0: is not a parameter of the phong "
                                           r"lighting model \(it is of cook-torrance\)"}
    for text, message in cases.items():
        with pytest.raises(ReaderError, match=message):
            _read(tmp_path, text)


def test_the_shipped_scene_draws_cook_torrance_highlights():
    """scenes/cook_torrance.toml: the copper sphere's highlight takes F0's colour (red over
    blue), the Phong sphere's is white; on the spheres the z-buffer (tessellated) and the ray
    caster (exact spheres; it draws no planes) agree."""
    from core.scene.formats import load_scene
    scene = load_scene("scenes/cook_torrance.toml")
    settings = RenderSettings.for_scene(scene, size=(144, 80))
    z = render(scene, scene.views[0], settings).color.astype(int)
    cast = render(scene, scene.views[0], settings.replace(renderer="raycast")).color.astype(int)
    spheres = np.any(cast != cast[0, 0], axis=-1)      # the ray caster's background: no floor
    assert spheres.mean() > 0.2
    assert np.mean(np.abs(z - cast)[spheres]) < 2.0
    third = z.shape[1] // 3
    phong, copper = z[:, :third].reshape(-1, 3), z[:, third:2 * third].reshape(-1, 3)
    hot_phong = phong[np.argmax(phong.sum(axis=1))]
    hot_copper = copper[np.argmax(copper.sum(axis=1))]
    assert hot_phong.min() > 160                       # O_s = 1: a whitish highlight
    # F0 of copper: a coloured one, bluer light kept back
    assert hot_copper[2] / hot_copper[0] < hot_phong[2] / hot_phong[0] - 0.1


def test_the_inspector_gives_cook_torrance_terms_that_sum_to_the_pixel():
    """The z-buffer's record and the ray tree's (core.renderers.raytrace.inspect) name the model
    and its terms, and their colour is the picture's pixel."""
    from core.inspect import inspect_pixel
    from core.renderers.raytrace.inspect import ray_tree_record
    scene = _plane_scene(_ct(ks=0.8, kd=0.3, roughness=0.3, f0=(0.9, 0.6, 0.3)))
    settings = RenderSettings.for_scene(scene, shading="phong", size=(24, 24))
    for renderer, inspect in (("zbuffer", inspect_pixel), ("raytrace", ray_tree_record)):
        s = settings.replace(renderer=renderer)
        picture = render(scene, scene.views[0], s).color
        record = inspect(scene, scene.views[0], s, 12, 12, None)
        terms = record["phong"] if "phong" in record else record["ray tree"][0]["phong"]
        assert terms["model"] == "cook-torrance"
        assert {"D", "G", "F", "N.H", "V.H"} <= set(terms["lights"][0])
        assert list(record["color"]) == list(picture[12, 12]), renderer
        total = [terms["ambient"][c] + terms["lights"][0]["sum"][c] for c in range(3)]
        assert total == pytest.approx(terms["sum"], abs=1e-12)
