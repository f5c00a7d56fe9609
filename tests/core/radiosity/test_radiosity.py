"""Radiosity: form factors against closed forms, energy, the two solvers, the
renderer, saved solutions and bad input."""

from __future__ import annotations

import numpy as np
import pytest

from core.radiosity import closed_forms as cf
from core.radiosity.mesh import RadiosityError, mesh_scene
from core.radiosity.solution import Options, load, save, solve, start
from core.radiosity.solve import Progressive, gauss_seidel
from core.render import render
from core.scene.formats import ReaderError, load_scene
from core.scene.formats.scenefile import read_scene_file
from core.scene.generators import cube
from core.scene.model import Material, Mesh, Scene
from core.settings import RenderSettings

from tests.conftest import ROOT


# --------------------------------------------------------------------------------------------
# Form factors


def test_closed_forms_by_hand():
    # Howell's tables: unit squares one apart 0.19982; perpendicular unit squares 0.20004;
    # unit discs one apart (3 - sqrt 5) / 2.
    assert cf.parallel_rectangles(1, 1, 1) == pytest.approx(0.199825, abs=1e-6)
    assert cf.perpendicular_rectangles(1, 1, 1) == pytest.approx(0.200044, abs=1e-6)
    assert cf.coaxial_discs(1, 1, 1) == pytest.approx((3 - 5 ** 0.5) / 2, abs=1e-12)


# (the shapes, each source triangle cut into pieces² points that average F)
CASES = {"parallel": (cf.parallel_pair, 4), "perpendicular": (cf.perpendicular_pair, 4),
         "discs": (lambda: cf.disc_pair(segments=24), 3)}


@pytest.mark.parametrize("method", ["hemicube", "raycast"])
@pytest.mark.parametrize("case", list(CASES))
def test_form_factors_match_closed_forms(case, method):
    pair, pieces = CASES[case]
    source, target, exact = pair()
    measured = cf.measured(source, target, method, resolution=256, pieces=pieces)
    assert abs(measured - exact) / exact < 0.01, (case, method, measured, exact)


def test_hemicube_error_shrinks_with_resolution():
    # Against the ray-cast factor at the same source points (the same quadrature, whose
    # unoccluded part is exact), the hemicube's own error is its pixels'.
    source, target, _ = cf.parallel_pair()
    exact_here = cf.measured(source, target, "raycast", pieces=2)
    coarse = abs(cf.measured(source, target, "hemicube", 8, 2) - exact_here)
    fine = abs(cf.measured(source, target, "hemicube", 128, 2) - exact_here)
    assert fine < coarse / 8


@pytest.mark.parametrize("method", ["hemicube", "raycast"])
def test_reciprocity(method):
    # A 1 x 1 floor and a 1 x 2 wall on the same edge: A_1 F_12 = A_2 F_21.
    floor, wall, exact = cf.perpendicular_pair(1.0, 1.0, 2.0)
    f12 = cf.measured(floor, wall, method, 128, 8)
    f21 = cf.measured(wall, floor, method, 128, 8)
    assert f12 == pytest.approx(exact, rel=0.01)
    assert 1.0 * f12 == pytest.approx(2.0 * f21, rel=0.01)


def _closed_box(rho=0.5, emission=1.0):
    c = cube(2.0, 1)
    inward = Mesh(c.positions, c.triangles[:, ::-1], name="box",
                  material=Material(kd=1.0, od=(rho,) * 3, emission=(emission,) * 3,
                                    two_sided=False))
    return Scene("closed box", [inward], [], lights=[])


def test_hemicube_rows_sum_to_one_in_a_closed_box():
    e, shooter, _ = start(_closed_box(), Options(max_elements=120, adaptive=False,
                                                  hemicube_resolution=64))
    sums = np.array([shooter.row(p).sum() for p in range(e.patches)])
    assert np.abs(sums - 1).max() < 1e-3


def test_raycast_rows_sum_to_one_in_a_closed_box():
    e, shooter, _ = start(_closed_box(), Options(max_elements=120, adaptive=False,
                                                  form_factors="raycast"))
    # Σ_p F(e → p) over the patches, for every element (the receiver-centred row)
    k = np.stack([shooter.row(p) * e.patch_area[p] / e.area for p in range(e.patches)], axis=1)
    assert np.abs(k.sum(axis=1) - 1).max() < 1e-6


# --------------------------------------------------------------------------------------------
# Energy and the solvers


@pytest.mark.parametrize("method", ["hemicube", "raycast"])
def test_furnace_closed_box(method):
    # Every wall emits E = 1 and reflects rho = 0.6: B = E / (1 - rho) = 2.5 everywhere.
    solution = solve(_closed_box(0.6, 1.0), Options(form_factors=method, max_elements=120,
                                                     converge=1e-6, adaptive=False,
                                                     hemicube_resolution=64))
    e = solution.elements
    total = (solution.radiosity * e.area[:, None]).sum(axis=0)
    assert total == pytest.approx(np.full(3, 2.5 * e.area.sum()), rel=0.005)


def test_progressive_and_gauss_seidel_agree():
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    e, shooter, source = start(scene, Options(max_elements=120, adaptive=False,
                                              hemicube_resolution=32))
    progressive = Progressive(e, shooter, source)
    progressive.run(converge=1e-12, max_steps=100_000)
    exact, sweeps = gauss_seidel(e, shooter, source, tolerance=1e-12)
    assert sweeps > 1 and progressive.steps > e.patches
    assert np.abs(progressive.radiosity - exact).max() < 1e-6


def test_progressive_stops_at_the_residual():
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    e, shooter, source = start(scene, Options(max_elements=120, adaptive=False,
                                              hemicube_resolution=32))
    solver = Progressive(e, shooter, source)
    solver.run(converge=0.05)
    assert solver.unshot_fraction() <= 0.05
    assert 0 < solver.ambient().min() and solver.ambient().max() < solver.radiosity.max()


def test_adaptive_subdivision_keeps_the_budget_and_splits_where_it_changes():
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    solution = solve(scene, Options(max_elements=400, hemicube_resolution=32))
    rounds = solution.stats["rounds"]
    assert len(rounds) == 2 and rounds[0]["elements"] < rounds[1]["elements"] <= 400
    assert (rounds[1]["elements"] - rounds[0]["elements"]) % 3 == 0     # each split: 1 -> 4
    # the first mesh is uniform per surface; the split ones sit beside unsplit neighbours
    first = mesh_scene(scene, 200)
    assert len(np.unique(np.round(solution.elements.area, 6))) > \
        len(np.unique(np.round(first.area, 6)))


# --------------------------------------------------------------------------------------------
# Scenes, the renderer, saved solutions


def _scene(text: str) -> Scene:
    return read_scene_file(text, "test.toml", ROOT / "scenes")


PANEL = """
name = "panel"
views = "auto"
[[geometry]]
generator = "plane"
transform = {{ rotate = [90, 0, 0] }}          # facing +z, the front view's viewer
material = {{ kd = {kd}, od = [1, 1, 1], emission = {emission} }}
"""


def test_a_pure_emitter_shows_its_emission_and_gets_no_default_lights():
    scene = _scene(PANEL.format(kd=0.0, emission="[0.5, 0.25, 0.75]"))
    assert scene.lights == []
    for renderer in ("radiosity", "pathtrace"):
        settings = RenderSettings.for_scene(scene, renderer=renderer, size=(40, 40),
                                            shading="gouraud")
        frame = render(scene, scene.views[0], settings)
        assert frame.message is None
        middle = frame.color[20, 20]
        assert np.abs(middle.astype(int) - [128, 64, 191]).max() <= 1, renderer


def test_bad_emission_is_refused_by_the_reader():
    with pytest.raises(ReaderError, match=r"geometry\[1\]\.material\.emission\[2\]"):
        _scene(PANEL.format(kd=0.5, emission="[1, -1, 1]"))
    with pytest.raises(ReaderError, match="emission"):
        _scene(PANEL.format(kd=0.5, emission="[1, nan, 1]"))


def test_reflectance_of_one_is_refused_by_both_renderers():
    scene = _scene(PANEL.format(kd=1.0, emission="[1, 1, 1]"))
    for renderer in ("radiosity", "pathtrace"):
        frame = render(scene, scene.views[0], RenderSettings.for_scene(
            scene, renderer=renderer, size=(8, 8)))
        assert "rho = kd * od" in frame.message and "below 1" in frame.message
    with pytest.raises(RadiosityError, match="mesh 1"):
        mesh_scene(scene)


def test_no_light_at_all_gives_a_message_and_a_black_picture():
    scene = _scene(PANEL.format(kd=0.5, emission="[0, 0, 0]") + "[[light]]\nposition = [0, 9, 0]\n")
    scene.lights = []
    for renderer in ("radiosity", "pathtrace"):
        frame = render(scene, scene.views[0], RenderSettings.for_scene(
            scene, renderer=renderer, size=(8, 8)))
        assert frame.message is None and not frame.color.any()
        assert "nothing emits light" in frame.stats["warnings"][0]


def test_zero_area_triangles_are_dropped_and_a_scene_of_only_them_is_refused():
    good = _closed_box()
    flat = Mesh(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]]), np.array([[0, 1, 2]]),
                material=Material(emission=(1, 1, 1)))
    e = mesh_scene(Scene("with a sliver", [good.meshes[0], flat], [], lights=[]), 60)
    assert e.area.min() > 0 and set(e.mesh) == {0}
    with pytest.raises(RadiosityError, match="zero area"):
        mesh_scene(Scene("slivers", [flat], [], lights=[]))


def test_point_lights_shoot_first():
    scene = load_scene(ROOT / "scenes" / "house_mirror.toml")
    e, _, source = start(scene, Options(max_elements=300, adaptive=False))
    assert source.max() > 0 and not e.emission.any()


def test_saved_solution_reloads_and_refuses_another_scene(tmp_path):
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    solution = solve(scene, Options(max_elements=100, hemicube_resolution=16, adaptive=False))
    path = tmp_path / "solution.npz"
    save(solution, path)
    again = load(path, load_scene(ROOT / "scenes" / "cornell_box.toml"))
    assert np.array_equal(again.radiosity, solution.radiosity)
    assert np.array_equal(again.elements.corners, solution.elements.corners)
    with pytest.raises(RadiosityError, match="another scene"):
        load(path, load_scene(ROOT / "scenes" / "house_mirror.toml"))
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    with pytest.raises(RadiosityError, match="cannot read"):
        load(junk, scene)


def test_cli_radiosity_and_foreign_solution(tmp_path, capsys):
    from app.cli import main
    out = tmp_path / "s.npz"
    assert main(["radiosity", str(ROOT / "scenes" / "cornell_box.toml"), "--out", str(out),
                 "--max-elements", "80", "--hemicube-resolution", "16"]) == 0
    png = tmp_path / "house.png"
    code = main(["render", str(ROOT / "scenes" / "house_mirror.toml"), "--renderer", "radiosity",
                 "--solution", str(out), "--out", str(png)])
    err = capsys.readouterr().err
    assert code == 2 and "error: --solution" in err and "another scene" in err
    assert not png.exists()


def test_every_view_draws_from_one_solution():
    from core.context import RenderContext
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    context = RenderContext()
    settings = RenderSettings.for_scene(scene, renderer="radiosity", size=(48, 48),
                                        max_elements=100, hemicube_resolution=16)
    first = render(scene, scene.views[0], settings, context)
    held = context.cache(scene)["radiosity solution"]
    moved = scene.views[0].__class__(**{**scene.views[0].__dict__, "vrp": (300, 273, -765)})
    render(scene, moved, settings, context)
    assert context.cache(scene)["radiosity solution"] is held
    assert first.color.mean() > 20                     # lit, not black


def test_inspect_pixel_matches_the_picture():
    from core.context import RenderContext
    from core.renderers.radiosity.inspect import inspect_pixel
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    settings = RenderSettings.for_scene(scene, renderer="radiosity", size=(48, 48),
                                        max_elements=100, hemicube_resolution=16)
    context = RenderContext()
    frame = render(scene, scene.views[0], settings, context)
    record = inspect_pixel(scene, scene.views[0], settings, 10, 40, context,    # the floor
                           render=render)
    assert record["color"] == frame.color[40, 10].tolist()
    assert record["mesh"].startswith("white") and record["reflectance"][0] == 0.725
    assert record["emission"] == [0, 0, 0] and record["radiosity"][0] > 0


def test_window_progress_brightens_step_by_step_then_equals_the_renderer(monkeypatch):
    from core.renderers.radiosity import progressive as progressive_gi
    from core.context import RenderContext
    monkeypatch.setattr(progressive_gi, "PARTIAL_EVERY", 0.0)     # a picture after every shot

    class Control:
        cancelled = False
        partials, reports = [], []

        def check(self):
            pass

        def report(self, fraction, detail):
            self.reports.append(detail)

        def partial(self, frame):
            self.partials.append(frame.color.copy())

    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    settings = RenderSettings.for_scene(scene, renderer="radiosity", size=(32, 32),
                                        max_elements=60, hemicube_resolution=16)
    control = Control()
    frame = progressive_gi.radiosity_progressively(scene, scene.views[0], settings,
                                                   RenderContext(), render, control)
    assert len(control.partials) > 5
    assert control.reports[0].startswith("shooting step 1, unshot energy")
    assert control.reports[-1].endswith(" elements")
    again = render(scene, scene.views[0], settings, RenderContext())
    assert np.array_equal(frame.color, again.color)
    # the picture changes as the light is shot (the ambient term stands in for the rest)
    assert not np.array_equal(control.partials[0], control.partials[-1])


def test_cli_messages_for_bad_scenes(tmp_path, capsys):
    from app.cli import main
    dark = tmp_path / "dark.toml"
    dark.write_text(PANEL.format(kd=0.5, emission="[0, 0, 0]").replace('views = "auto"',
                    'views = "auto"\n[[light]]\nposition = [0, 0, 5]\nintensity = [0, 0, 0]'))
    png = tmp_path / "dark.png"
    assert main(["render", str(dark), "--renderer", "radiosity", "--size", "8x8",
                 "--out", str(png)]) == 0
    assert png.exists()                                   # the black picture is written
    assert "warning: panel: nothing emits light" in capsys.readouterr().err
    hot = tmp_path / "hot.toml"
    # the reader takes kd = 2 only when the file lifts the notes' 0..1; the tracer still refuses
    hot.write_text('coefficients = "unbounded"\n' + PANEL.format(kd=2.0, emission="[1, 1, 1]"))
    assert main(["render", str(hot), "--renderer", "pathtrace", "--size", "8x8",
                 "--out", str(tmp_path / "hot.png")]) == 1
    err = capsys.readouterr().err
    assert "error: panel: cannot path trace: mesh 1" in err and "below 1" in err


def test_bench_refuses_an_unknown_renderer(capsys):
    from app.cli import main
    assert main(["bench", "--renderer", "radiosity,photons"]) == 2
    assert "error: --renderer: photons" in capsys.readouterr().err


def test_bench_table_reads_its_rows():
    from app.bench.gi_bench import table
    report = {"cpus": 2, "loadavg_before": [1.0], "loadavg_after": [1.5],
              "radiosity": [{"form_factors": "hemicube", "resolution": 128, "elements": 848,
                             "patches": 212, "seconds_to_1pct": 2.07, "steps": 590,
                             "rows_per_second": 110.4}],
              "pathtrace": [{"renderer": "ours", "samples": 100, "seconds": 0.5,
                             "samples_per_second": 200.0},
                            {"renderer": "Mitsuba 3 scalar_rgb", "missing": "pip install mitsuba"}]}
    text = table(report)
    assert "| hemicube 128 | 848 | 212 | 2.07 | 590 | 110 |" in text
    assert "| ours | 100 | 0.50 | 200 |" in text and "(pip install mitsuba)" in text
