"""The pipeline's stiff and extreme cases, one function each, registered with ``@case``.

The framework (how a case is run and judged, and the tools the cases share) is
:mod:`core.analysis.stability`; this module only states each case: the scene, what is expected, and
the checks.
"""

from __future__ import annotations

import math
import re
import tempfile
from fractions import Fraction
from pathlib import Path

import numpy as np

from core.settings import RenderSettings
from core.settings import PROJECTIONS, SOLID_SHADINGS
from core.analysis import exact
from core.pipeline import project
from core.shading import shade
from core.scene.generators import uv_sphere
from core.shading.illumination import (Eye, illuminate, pack_ambient, pack_eye, pack_lights,
                               pack_surfaces, to_uint8)
from core.scene.normals import face_normals, vertex_normals
from core.scene.model import Light, Material, Mesh, Scene
from core.transforms import apply, rotate_x, rotate_y
from core.analysis.stability_kit import (BLUE, GREY, RED, SIZE, SMALL_VIEW, Outcome, case, compare_images,
                            coordinate_accuracy, covered, one_pixel_mismatches, probe_all,
                            render_image, scaled_scene, scene_of, sphere_and_cube, square_xy)
from core.camera.view import View, normalizing_transform


# --------------------------------------------------------------------------------------------
# The cases


@case("worked example (baseline)",
      "the notes' worked example: N_per, z_min and the house's coordinates as exact arithmetic")
def worked_example() -> Outcome:
    from core.scene.generators import house
    out = Outcome()
    view = View(vrp=(0, 0, 54), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 17, -1, 17),
                prp=(8, 6, 30), front=10, back=-50)
    f = exact.n_per_factors(view)
    out.check("S_per = diag(1/24, 1/24, 1/80, 1), shy = 1/15 exactly",
              [f["S_per"][i][i] for i in range(4)] == [Fraction(1, 24), Fraction(1, 24),
                                                        Fraction(1, 80), 1]
              and f["SH_par"][1][2] == Fraction(1, 15))
    for projection in PROJECTIONS:
        coordinate_accuracy(out, view, projection, house().positions)
    return out


@case("front plane 1e-6·PRP_n from the eye, far/near 1e9",
      "two surfaces 11 and 21 units from the eye: the nearer one wins at the centre in either "
      "drawing order, the farther one shows around it")
def front_plane_near_eye() -> Outcome:
    out = Outcome()
    # PRP_n = 1, F = 1 - 1e-6: the front plane 1e-6 from the eye; B = -999: 1e3 from the eye.
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                prp=(0, 0, 1), front=1 - 1e-6, back=-999.0)
    near, far = square_xy(3.0, -10.0, RED), square_xy(30.0, -20.0, BLUE)
    z_min = exact.n_per_factors(view)["z_min"]
    out.check(f"z_min = {float(z_min):.3g}", -2e-9 < z_min < 0)
    for order in ((near, far), (far, near)):
        scene = scene_of(order, view, lights=[Light(direction=(0.0, 0.0, 1.0))])
        image, message = render_image(scene, "perspective", "flat")
        centre, corner = tuple(int(c) for c in image[32, 32]), tuple(int(c) for c in image[2, 2])
        label = "near first" if order[0] is near else "far first"
        out.check(f"{label}: centre {centre} is the near (red) surface",
                  message is None and centre[0] > centre[2])
        out.check(f"{label}: corner {corner} is the far (blue) surface",
                  corner[2] > corner[0])
    probe_all(out, scene, projections=("perspective",))
    # The depth gap the z-buffer has to resolve, exactly, at the centre of the image.
    vp = project.viewport(view.window, *SIZE)
    _, (d_near, d_far) = exact.chain(exact.view_numbers(view),
                                     [(0, 0, exact.q(-10)), (0, 0, exact.q(-20))], "perspective", vp)
    gap = float(d_near[2] - d_far[2])
    out.check(f"device depth gap {gap:.2e} (float32 spacing near -1: {2.0 ** -24:.1e}; "
              f"float64: {2.0 ** -53:.1e})", gap > 1e6 * 2.0 ** -53)
    coordinate_accuracy(out, view, "perspective", np.concatenate([near.positions, far.positions]))
    return out


@case("coordinates offset by 1e8",
      "a scene 1 unit across moved 1e8 from the origin (scene, view and light): the same image "
      "as unmoved, within one pixel")
def offset_1e8() -> Outcome:
    out = Outcome()
    base = scene_of(sphere_and_cube(), SMALL_VIEW)
    moved = scaled_scene(base, 1.0, offset=(1e8, -1e8, 1e8))
    for projection in PROJECTIONS:
        a, _ = render_image(base, projection, "gouraud", (96, 96))
        b, message = render_image(moved, projection, "gouraud", (96, 96))
        compare_images(out, projection, a, b)
        coordinate_accuracy(out, moved.views[0], projection,
                            np.concatenate([m.positions for m in moved.meshes]), (96, 96))
    probe_all(out, moved, size=(96, 96))
    return out


def _vup_near_vpn(angle: float) -> View:
    """VPN (1, 2, 2); VUP = VPN turned by ``angle`` radians towards (2, -2, 1)."""
    vpn = np.array([1.0, 2.0, 2.0])
    w = np.array([2.0, -2.0, 1.0]) / 3.0                   # unit, perpendicular to VPN
    vup = vpn + 3.0 * angle * w                            # |VPN| = 3
    return View(vrp=(0, 0, 0), vpn=tuple(vpn), vup=tuple(vup), window=(-0.8, 0.8, -0.8, 0.8),
                prp=(0, 0, 4), front=1, back=-1, label=f"VUP {angle:g} rad from VPN")


@case("VUP 1e-9 rad from VPN",
      "a correct image (the same as with VUP set to the exact v of the VRC), never NaN")
def vup_1e9() -> Outcome:
    out = Outcome()
    view = _vup_near_vpn(1e-9)
    u, v, n = exact.vrc_basis(exact.view_numbers(view))
    good = View(vrp=view.vrp, vpn=view.vpn, vup=tuple(float(x) for x in v),
                window=view.window, prp=view.prp, front=view.front, back=view.back)
    meshes = sphere_and_cube()
    for projection in PROJECTIONS:
        a, message = render_image(scene_of(meshes, view), projection, "gouraud")
        b, _ = render_image(scene_of(meshes, good), projection, "gouraud")
        out.check(f"{projection}: rendered, no message", message is None)
        compare_images(out, f"{projection} against the exact VRC", a, b)
        coordinate_accuracy(out, view, projection, np.concatenate([m.positions for m in meshes]))
    probe_all(out, scene_of(meshes, view))
    return out


@case("VUP 1e-13 rad from VPN, and parallel",
      "the invalid-view message ('VUP is parallel to VPN') and a background frame, never NaN")
def vup_parallel() -> Outcome:
    out = Outcome()
    for view in (_vup_near_vpn(1e-13),
                 View(vrp=(0, 0, 0), vpn=(1, 2, 2), vup=(2, 4, 4), window=(-1, 1, -1, 1),
                      prp=(0, 0, 4), front=1, back=-1, label="VUP = 2 VPN")):
        for projection in PROJECTIONS:
            image, message = render_image(scene_of(sphere_and_cube(), view), projection, "phong")
            out.check(f"{view.label}, {projection}: message {message!r}",
                      message is not None and "VUP is parallel to VPN" in message
                      and not image.any())
    return out


@case("PRP 1e-9 from the view plane (perspective)",
      "the same pinhole camera written with PRP_n = 1e-9 and a window 1e-9 wide gives the image "
      "of PRP_n = 1 with a window 1 wide, within one pixel")
def prp_near_view_plane() -> Outcome:
    out = Outcome()
    # Eye at (0, 0, 2) looking down -z with a 90 degree field: VRP 1e-9 (or 1) in front of it;
    # the front and back planes at z = 1 and z = -1 in both.
    tight = View(vrp=(0, 0, 2 - 1e-9), vpn=(0, 0, 1), vup=(0, 1, 0),
                 window=(-1e-9, 1e-9, -1e-9, 1e-9), prp=(0, 0, 1e-9), front=-1 + 1e-9,
                 back=-3 + 1e-9, label="PRP_n = 1e-9")
    usual = View(vrp=(0, 0, 1), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                 prp=(0, 0, 1), front=0, back=-2, label="PRP_n = 1")
    meshes = sphere_and_cube()
    a, message = render_image(scene_of(meshes, tight), "perspective", "phong")
    b, _ = render_image(scene_of(meshes, usual), "perspective", "phong")
    out.check(f"rendered, message {message!r}", message is None)
    out.check(f"{int(covered(a).sum())} pixels covered", covered(a).sum() > 150)
    compare_images(out, "PRP_n 1e-9 against 1", a, b)
    probe_all(out, scene_of(meshes, tight), projections=("perspective",))
    coordinate_accuracy(out, tight, "perspective", np.concatenate([m.positions for m in meshes]))
    return out


@case("DOP 1e-9 rad from the view plane (parallel)",
      "PRP = (1, 0, 1e-9): a shear of 1e9; the sphere's coverage matches the analytic ray "
      "tracer's (core.renderers.raycast) within one pixel")
def dop_near_view_plane() -> Outcome:
    from core.renderers.raycast.draw import Sphere, render_reference
    out = Outcome()
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1.5, 1.5, -1.5, 1.5),
                prp=(1.0, 0.0, 1e-9), front=1.5, back=-1.5, label="oblique")
    ball = uv_sphere(radius=1.0, segments=64, rings=32)
    ball.material = GREY
    scene = scene_of([ball], view)
    image, message = render_image(scene, "parallel", "phong")
    reference = render_reference([Sphere((0.0, 0.0, 0.0), 1.0, GREY)], scene, view, "parallel",
                                 size=SIZE, samples=1)
    mine, exact_mask = covered(image), reference.coverage > 0.5
    count = one_pixel_mismatches(mine, exact_mask, levels=0)
    out.check(f"rendered, message {message!r}; {int(mine.sum())} pixels covered "
              f"(reference {int(exact_mask.sum())})", message is None and mine.sum() > 500)
    out.check(f"{count} pixels of coverage differ beyond one pixel", count == 0)
    probe_all(out, scene, projections=("parallel",))
    coordinate_accuracy(out, view, "parallel", ball.positions)
    return out


def _window_scale(s: float) -> Outcome:
    out = Outcome()
    view = View(vrp=(0, 0, 0), vpn=(0.2, 0.3, 1.0), vup=(0, 1, 0), window=(-0.9, 0.9, -0.9, 0.9),
                prp=(0, 0, 4), front=1, back=-1, label="unit")
    base = scene_of(sphere_and_cube(), view)
    scaled = scaled_scene(base, s)
    for projection in PROJECTIONS:
        a, _ = render_image(base, projection, "gouraud")
        b, message = render_image(scaled, projection, "gouraud")
        out.check(f"{projection}: rendered, message {message!r}", message is None)
        compare_images(out, f"{projection} scaled by {s:g} against unscaled", a, b)
        coordinate_accuracy(out, scaled.views[0], projection,
                            np.concatenate([m.positions for m in scaled.meshes]))
    probe_all(out, scaled)
    return out


@case("window 1e-9 wide",
      "a scene 1e-9 across in a window 1e-9 wide: the image of the unit scene, within one pixel")
def window_tiny() -> Outcome:
    return _window_scale(1e-9)


@case("window 1e9 wide",
      "a scene 1e9 across in a window 1e9 wide: the image of the unit scene, within one pixel")
def window_huge() -> Outcome:
    return _window_scale(1e9)


FACING = rotate_y(0.7) @ rotate_x(0.4)       # a generic orientation, so nothing is exact
FACING_VIEW = View(vrp=(0, 0, 0), vpn=tuple(FACING[:3, 2]), vup=tuple(FACING[:3, 1]),
                   window=(-1, 1, -1, 1), prp=(0, 0, 4), front=1, back=-1, label="facing")


def _exact_square_mask(corners, view: View, size=SIZE) -> np.ndarray:
    """Pixels whose centres lie inside the projected convex polygon ``corners``, exactly.

    The corners are projected in exact arithmetic; the edge functions are evaluated in float64
    and any pixel centre within 1e-6 of an edge is decided again in exact arithmetic.
    """
    vp = project.viewport(view.window, *size)
    _, device = exact.chain(exact.view_numbers(view),
                            [tuple(exact.q(c) for c in p) for p in corners], "perspective", vp)
    xy = [(d[0], d[1]) for d in device]
    width, height = size
    j, i = np.mgrid[height - 1:-1:-1, 0:width]            # device row of each image row
    x, y = i + 0.5, j + 0.5

    def sides(px, py, number):
        return [(b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0])
                for a, b in zip(number(xy), number(xy[1:] + xy[:1]))]

    floats = sides(x, y, lambda pts: [(float(a), float(b)) for a, b in pts])
    mask = np.all([s > 0 for s in floats], axis=0) | np.all([s < 0 for s in floats], axis=0)
    close = np.any([np.abs(s) < 1e-6 for s in floats], axis=0)
    for r, c in zip(*np.nonzero(close)):
        exact_sides = sides(Fraction(int(2 * x[r, c]), 2), Fraction(int(2 * y[r, c]), 2),
                            lambda pts: pts)
        mask[r, c] = all(s > 0 for s in exact_sides) or all(s < 0 for s in exact_sides)
    return mask


@case("sliver triangles (aspect 1e-9)",
      "a square split along its diagonal with a sliver of aspect 1e-9 between the halves: "
      "exactly the pixels of the square covered (no crack), finite normals")
def slivers() -> Outcome:
    out = Outcome()
    local = np.array([(-0.7, -0.7, 0), (0.7, -0.7, 0), (0.7, 0.7, 0), (-0.7, 0.7, 0),
                      (-1e-9, 1e-9, 0)])                     # A B C D and E off the diagonal AC
    points = apply(FACING, local)[:, :3]
    # A B C, the sliver A C E, then A E D and E C D: every shared edge has the same two ends.
    triangles = np.array([[0, 1, 2], [0, 2, 4], [0, 4, 3], [4, 2, 3]])
    mesh = Mesh(positions=points, triangles=triangles, material=GREY, name="slivers")
    scene = scene_of([mesh], FACING_VIEW, lights=[Light(direction=tuple(FACING[:3, 2]))])
    expected = _exact_square_mask(points[:4], FACING_VIEW)
    for shading in SOLID_SHADINGS:
        image, _ = render_image(scene, "perspective", shading)
        wrong = int(np.count_nonzero(covered(image) != expected))
        out.check(f"{shading}: {wrong} pixels differ from the exact square", wrong == 0)
    probe_all(out, scene, projections=("perspective",))
    # The sliver's normal: float cross product against exact, with its condition number.
    sliver = points[[0, 2, 4]]
    unit_float = face_normals(sliver, np.array([[0, 1, 2]]))[0]

    def normal(values):
        a, b, c = (tuple(values[3 * k:3 * k + 3]) for k in range(3))
        cr = exact.cross(tuple(y - x for x, y in zip(a, b)), tuple(y - x for x, y in zip(a, c)))
        return [[list(exact.unit(cr))]]

    inputs = [exact.q(c) for c in sliver.reshape(-1)]
    ex = normal(inputs)[0]
    out.accuracy(exact.relative_error(unit_float, ex), exact.condition(normal, inputs),
                 "the sliver's unit face normal")
    coordinate_accuracy(out, FACING_VIEW, "perspective", points)
    return out


@case("triangles edge-on to the eye",
      "a triangle whose plane holds the eye (perspective) or the DOP (parallel) draws at most "
      "the pixels within one pixel of its projected line")
def edge_on() -> Outcome:
    out = Outcome()
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                prp=(0, 0, 4), front=1, back=-2, label="edge-on")
    back = square_xy(2.0, -1.0, BLUE)
    # Perspective: the plane y + 0.1 z = 0.4 holds the eye (0, 0, 4); it projects to v = 0.4.
    persp = Mesh(positions=[(-0.8, 0.35, 0.5), (0.8, 0.35, 0.5), (0.0, 0.45, -0.5)],
                 triangles=[[0, 1, 2]], material=RED, name="edge-on")
    # Parallel (DOP along -z): the plane x = 0.3 projects to u = 0.3.
    par = Mesh(positions=[(0.3, -0.5, 0.5), (0.3, 0.5, 0.5), (0.3, 0.0, -0.5)],
               triangles=[[0, 1, 2]], material=RED, name="edge-on")
    width, height = SIZE
    for projection, mesh, axis, at in (("perspective", persp, "row", 0.4), ("parallel", par, "column", 0.3)):
        line = (at + 1) / 2 * (height if axis == "row" else width)        # device coordinate
        for shading in SOLID_SHADINGS:
            a, _ = render_image(scene_of([back], view), projection, shading)
            b, _ = render_image(scene_of([back, mesh], view), projection, shading)
            diff = np.any(a != b, axis=2)
            rows, cols = np.nonzero(diff)
            centres = (height - 1 - rows + 0.5) if axis == "row" else cols + 0.5
            far = int(np.count_nonzero(np.abs(centres - line) > 1.0))
            out.check(f"{projection}/{shading}: {int(diff.sum())} pixels changed, {far} farther "
                      f"than one pixel from the line", far == 0)
        probe_all(out, scene_of([back, mesh], view), projections=(projection,))
        coordinate_accuracy(out, view, projection, mesh.positions)
    return out


@case("zero-area triangles",
      "collinear corners, three equal corners and a repeated index draw nothing: the image is "
      "identical to the one without them, in every mode and projection")
def zero_area() -> Outcome:
    out = Outcome()
    positions = np.array([(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.5, 0.5, 0), (-0.5, 0.5, 0),
                          (0.0, 0.0, 0.0), (0.2, 0.3, 0.1)])
    good = np.array([[0, 1, 2], [0, 2, 3]])
    degenerate = np.array([[0, 2, 4],                # (0,0,0) is the exact midpoint of 0 and 2
                           [5, 5, 5],                # three equal corners
                           [1, 1, 3]])               # a repeated index
    view = View(vrp=(0, 0, 0), vpn=(0.2, 0.1, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                prp=(0, 0, 4), front=1, back=-1, label="zero-area")
    clean = scene_of([Mesh(positions=positions, triangles=good, material=GREY)], view)
    dirty = scene_of([Mesh(positions=positions, triangles=np.concatenate([good, degenerate]),
                           material=GREY)], view)
    for projection in PROJECTIONS:
        for shading in SOLID_SHADINGS:
            a, _ = render_image(clean, projection, shading)
            b, _ = render_image(dirty, projection, shading)
            out.check(f"{projection}/{shading}: {int(np.any(a != b, axis=2).sum())} pixels differ",
                      np.array_equal(a, b))
    probe_all(out, dirty)
    coordinate_accuracy(out, view, "perspective", positions)
    return out


@case("duplicate vertices",
      "a sphere as a soup (every triangle its own copies of its corners) renders identically to "
      "the shared-vertex sphere; the .tri reader merges equal corners")
def duplicates() -> Outcome:
    from core.scene.formats import load_scene
    out = Outcome()
    ball = uv_sphere(radius=0.8, segments=24, rings=12)
    ball.material = RED
    t = ball.triangles
    soup = Mesh(positions=ball.positions[t].reshape(-1, 3), triangles=np.arange(t.size).reshape(-1, 3),
                normals=ball.normals[t].reshape(-1, 3), closed=True, material=RED, name="soup")
    view = SMALL_VIEW
    for projection in PROJECTIONS:
        for shading in SOLID_SHADINGS:
            a, _ = render_image(scene_of([ball], view), projection, shading)
            b, _ = render_image(scene_of([soup], view), projection, shading)
            out.check(f"{projection}/{shading}: {int(np.any(a != b, axis=2).sum())} pixels differ",
                      np.array_equal(a, b))
    probe_all(out, scene_of([soup], view))
    text = ("0 0 5\n-1 1 0\n0.004 0 0\n0 -0.004 0\n2\n"
            "0 0 0  1 0 0  0 1 0\n1 0 0  0 1 0  1 1 0\n")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "duplicates.tri"
        path.write_text(text)
        mesh = load_scene(path).meshes[0]
    out.check(f".tri with 6 corners over 4 points: {len(mesh.positions)} vertices",
              len(mesh.positions) == 4)
    return out


# Views whose N_per and N_par are exact in binary, so that points can sit exactly on planes.
PLANE_VIEWS = {
    # canonical x = x/2, y = y/2, z = (z - 2)/4; z_min = -1/4: planes x = ±(2 - z)/2,
    # z = -2 (back), z = 1 (front)
    "perspective": View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                        prp=(0, 0, 2), front=1, back=-2, label="planes"),
    # canonical x = x, y = y, z = (z - 1)/4: planes x = ±1, y = ±1, z = 1 (front), z = -3 (back)
    "parallel": View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                     prp=(0, 0, 2), front=1, back=-3, label="planes"),
}


def _on_plane_triangles(projection: str) -> list[tuple[str, np.ndarray, bool]]:
    """``(plane, corners (3, 3), inside)``: for each of the six planes one triangle with a
    corner on it (the rest inside), one with an edge on it, and one touching it from outside."""
    if projection == "perspective":
        def side(z):                       # x (or y) on the side plane at depth z
            return (2.0 - z) / 2.0
        z_front, z_back, z_mid = 1.0, -2.0, 0.0
    else:
        def side(z):
            return 1.0
        z_front, z_back, z_mid = 1.0, -3.0, -1.0
    s = side(z_mid)
    found = []
    for axis, name in ((0, "x"), (1, "y")):
        for sign in (1.0, -1.0):
            on = np.zeros(3)
            on[axis], on[2] = sign * s, z_mid
            other = 1 - axis
            # Dyadic numbers only: every canonical coordinate is exact in float64 too.
            inner = np.array([0.125, 0.125, z_mid])
            edge = on.copy()
            edge[other] = 0.375
            on2 = on.copy()
            on2[other] = -0.375
            outside = on.copy()
            outside[axis] = sign * (s + 0.5)
            outside2 = outside.copy()
            outside2[other] = 0.25
            label = f"{'+' if sign > 0 else '-'}{name}"
            found.append((label, np.array([on, inner, inner + (0.125, -0.25, 0.125)]), True))
            found.append((label + " edge", np.array([edge, on2, inner]), True))
            found.append((label + " outside", np.array([on, outside, outside2]), False))
    for name, z in (("front", z_front), ("back", z_back)):
        a, b = np.array([0.0, 0.0, z]), np.array([0.25, 0.125, z])
        inward = np.array([0.0625, -0.125, (z_front + z_back) / 2])
        outward = np.array([0.0625, -0.125, z + (0.5 if name == "front" else -0.5)])
        found.append((name, np.array([a, inward, inward + (0.125, 0.25, 0.0)]), True))
        found.append((name + " edge", np.array([a, b, inward]), True))
        found.append((name + " lying in it", np.array([a, b, (0.0, 0.25, z)]), True))
        found.append((name + " outside", np.array([a, outward, outward + (0.125, 0.25, 0.0)]), False))
    return found


@case("vertices exactly on each clip plane",
      "a corner or an edge exactly on any of the six planes is inside: such triangles pass the "
      "clipper unchanged; a triangle touching a plane from outside draws nothing")
def on_clip_planes() -> Outcome:
    from core.pipeline.clip_polygon import clip_triangles, outcodes
    out = Outcome()
    for projection, view in PLANE_VIEWS.items():
        n, z_min = normalizing_transform(view, projection)
        pl = exact.normalizing_transform(view, projection)
        triangles = _on_plane_triangles(projection)
        on_plane = inside_ok = outside_ok = 0
        for label, corners, inside in triangles:
            canonical = apply(n, corners)[:, :3]
            ex = [exact.apply(pl[0], tuple(exact.q(c) for c in p))[:3] for p in corners]
            on_plane += exact.relative_error(canonical, ex) == 0.0
            clipped = clip_triangles(canonical, np.array([[0, 1, 2]]), np.zeros((3, 0)),
                                     projection, z_min)
            if inside:
                kept = (len(clipped.triangles) == 1
                        and np.array_equal(clipped.points[clipped.triangles[0]], canonical)
                        and not outcodes(canonical, projection, z_min).any())
                inside_ok += kept
                if not kept:
                    out.check(f"{projection} {label}: changed by the clipper", False)
            else:
                pts = clipped.points[clipped.triangles.reshape(-1)] if len(clipped.triangles) else np.zeros((0, 3))
                # What is left must be degenerate: every piece of zero area.
                areas = [np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0]))
                         for p in pts.reshape(-1, 3, 3)]
                nothing = all(a <= 1e-12 for a in areas)
                outside_ok += nothing
                if not nothing:
                    out.check(f"{projection} {label}: area {max(areas):.2e} left", False)
        count_in = sum(1 for t in triangles if t[2])
        out.check(f"{projection}: {on_plane}/{len(triangles)} triangles' canonical corners equal "
                  f"the exact ones; {inside_ok}/{count_in} kept unchanged; "
                  f"{outside_ok}/{len(triangles) - count_in} touching from outside drew nothing",
                  on_plane == len(triangles) and inside_ok == count_in
                  and outside_ok == len(triangles) - count_in)
        meshes = [Mesh(positions=c, triangles=[[0, 1, 2]], material=GREY) for _, c, _ in triangles]
        probe_all(out, scene_of(meshes, view), projections=(projection,))
        coordinate_accuracy(out, view, projection, np.concatenate([c for _, c, _ in triangles]))
    return out


@case("a vertex exactly at the eye",
      "a triangle with a corner at the PRP is edge-on: nothing farther than one pixel from its "
      "projected edge; its wireframe edges are clipped before any divide; never NaN")
def vertex_at_eye() -> Outcome:
    out = Outcome()
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                prp=(0, 0, 4), front=1, back=-2, label="eye")
    a, b = np.array([-0.5, 0.2, 0.0]), np.array([0.5, 0.3, 0.0])
    fan = Mesh(positions=[(0.0, 0.0, 4.0), a, b], triangles=[[0, 1, 2]], material=RED, name="fan")
    back = square_xy(2.0, -1.0, BLUE)
    width, height = SIZE
    # The projected edge a'b' in device pixels (the window maps [-1, 1] to [0, 64]).
    pa, pb = ((p[:2] * 4 / (4 - p[2]) + 1) / 2 * width for p in (a, b))   # u = 4x/(4 - z)
    for shading in ("flat", "gouraud", "phong", "wireframe"):
        before, _ = render_image(scene_of([back], view), "perspective", shading)
        after, message = render_image(scene_of([back, fan], view), "perspective", shading)
        rows, cols = np.nonzero(np.any(before != after, axis=2))
        centres = np.stack([cols + 0.5, height - 1 - rows + 0.5], axis=1)
        far = int(np.count_nonzero(_distance_to_segment(centres, pa, pb) > 1.0))
        out.check(f"{shading}: message {message!r}, {len(rows)} pixels changed, {far} farther "
                  f"than one pixel from a'b'", message is None and far == 0)
    probe_all(out, scene_of([back, fan], view), projections=("perspective",))
    # Gouraud evaluates the model at the eye: V is undefined there; the rule V = N applies.
    s = shade.prepare("gouraud", scene_of([fan], view), shade.eye_from_view(view, "perspective"))
    normal = vertex_normals(fan)[0]
    ex = exact.phong((0, 0, 4), normal, RED, [Light(position=(2.0, 3.0, 6.0))], (0.2, 0.2, 0.2),
                     (0, 0, 4), None, False, two_sided=True)
    out.accuracy(exact.relative_error(s.vertex_attrs[:1], [ex]), 1.0, "the colour at the eye")
    coordinate_accuracy(out, view, "perspective", fan.positions)
    return out


def _distance_to_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(((points - a) @ ab) / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


@case("face normals that cancel at a vertex (Gouraud)",
      "two faces meeting at a vertex with opposite normals (their average is 0, exactly or to "
      "1e-16): the vertex takes its largest face's normal, never NaN")
def cancelling_normals() -> Outcome:
    out = Outcome()
    e1, e2 = FACING[:3, 0] * 0.3, FACING[:3, 1] * 0.3
    worst = 0.0
    meshes = []
    # A = (p0, p0 + e1, p0 + e2) and B = (p0, p0 - k e2, p0 - k e1): B's normal is -A's and B
    # is k^2 times larger. At p0 = 0 with k = 2 every coordinate is exact and the sum of the
    # unit normals is exactly 0; elsewhere with k = 3 the corners are rounded and it is ~1e-17.
    for p0, k in ((np.zeros(3), 2.0), (np.array([0.1, -0.05, 0.0]), 3.0)):
        positions = np.array([p0, p0 + e1, p0 + e2, p0 - k * e2, p0 - k * e1])
        mesh = Mesh(positions=positions, triangles=[[0, 1, 2], [0, 3, 4]], material=GREY,
                    name="fold")
        meshes.append(mesh)
        exact_units = []
        for a, b in ((1, 2), (3, 4)):
            edges = [tuple(exact.q(x) - exact.q(y) for x, y in zip(positions[i], p0)) for i in (a, b)]
            exact_units.append(exact.unit(exact.cross(*edges)))
        exact_sum = float(exact.norm(tuple(x + y for x, y in zip(*exact_units))))
        unit, _ = face_normals(positions, mesh.triangles)
        float_sum = float(np.linalg.norm(unit[0] + unit[1]))
        chord = float(np.linalg.norm(vertex_normals(mesh)[0] - unit[1]))   # accurate when tiny
        worst = max(worst, chord)
        out.check(f"k = {k:g}: |n_A + n_B| exact {exact_sum:.1e}, float64 {float_sum:.1e}; "
                  f"vertex normal {chord:.1e} from the larger face's", chord <= 1e-12)
    scene = scene_of(meshes[1:], FACING_VIEW, lights=[Light(position=tuple(3 * FACING[:3, 2]))])
    probe_all(out, scene)
    image, _ = render_image(scene, "perspective", "gouraud")
    out.check(f"{int(covered(image).sum())} pixels drawn", covered(image).sum() > 50)
    out.conditioning = ("ill-posed: the direction of a zero average is undefined (κ = ∞); "
                        "the rule (|sum| <= 1e-9 Σw: the largest face) decides")
    out.error, out.condition, out.quantity = worst, math.inf, "vertex normal against the rule's"
    out.accurate = worst <= 1e-12
    return out


def _model_accuracy(out: Outcome, points, normals, material, lights, ambient=(0.2, 0.2, 0.2),
                    eye=(0.0, 0.0, 4.0), label="the model") -> np.ndarray:
    """``illuminate`` against :func:`core.analysis.exact.phong` at ``points``; returns the float colours."""
    rgb = illuminate(points, normals, np.zeros(len(points), np.int64),
                     pack_surfaces([material], [False]), pack_lights(lights),
                     pack_ambient(ambient), pack_eye(Eye(np.asarray(eye, float), None)), False)

    def model(values):
        rows = []
        for k in range(len(points)):
            p = values[6 * k:6 * k + 3]
            nrm = values[6 * k + 3:6 * k + 6]
            rows.append(list(exact.phong(p, nrm, material, lights, ambient, eye, None, False)))
        return [rows]

    inputs = [exact.q(c) for p, nrm in zip(points, normals) for c in (*p, *nrm)]
    ex = model(inputs)[0]
    out.accuracy(exact.relative_error(rgb, ex), exact.condition(model, inputs, trials=2), label)
    return rgb


def _lit_sphere(material, lights) -> Scene:
    ball = uv_sphere(radius=1.0, segments=32, rings=16)
    ball.material = material
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1.2, 1.2, -1.2, 1.2),
                prp=(0, 0, 4), front=1.1, back=-1.1, label="sphere")
    return scene_of([ball], view, lights=lights)


@case("specular exponent 1e4",
      "a highlight (R·V)^10000: no overflow or NaN; the model agrees with exact arithmetic "
      "within its condition (x^n has condition n)")
def sharp_highlight() -> Outcome:
    out = Outcome()
    material = Material(ka=0.2, kd=0.5, ks=0.5, n=1e4, od=(0.8, 0.8, 0.8))
    lights = [Light(position=(0.0, 0.0, 4.0))]
    scene = _lit_sphere(material, lights)
    probe_all(out, scene)
    # 65 x 65: the centre pixel's ray meets the sphere where the highlight peaks.
    image, _ = render_image(scene, "perspective", "phong", (65, 65))
    peak = to_uint8([float(c) for c in exact.phong((0, 0, 1), (0, 0, 1), material, lights,
                                                      (0.2, 0.2, 0.2), (0, 0, 4), None, False)])
    centre = image[32, 32].astype(int)
    out.check(f"centre pixel {tuple(int(c) for c in centre)}, the exact peak "
              f"{tuple(int(c) for c in peak)}", np.max(np.abs(centre - peak)) <= 3)
    # Points on the unit sphere within 0.02 rad of the highlight, where (R·V)^n is steep.
    angles = np.linspace(0.0, 0.02, 6)
    normals = np.stack([np.sin(angles), np.zeros_like(angles), np.cos(angles)], axis=1)
    _model_accuracy(out, normals, normals, material, lights, label="colour near the highlight")
    return out


@case("light at distance 0 from a surface",
      "a point light exactly at a vertex: ambient only at that vertex (L is undefined), finite "
      "everywhere")
def light_on_surface() -> Outcome:
    out = Outcome()
    ball = uv_sphere(radius=1.0, segments=32, rings=16)
    vertex = ball.positions[40]
    lights = [Light(position=tuple(vertex))]
    scene = _lit_sphere(GREY, lights)
    probe_all(out, scene)
    colours = _model_accuracy(out, vertex[None], ball.normals[40][None], GREY, lights,
                              label="the colour at the light")
    ambient_only = 0.2 * GREY.ka * np.array(GREY.od)
    out.check(f"colour at the light {np.round(colours[0], 6).tolist()} = ambient only",
              np.allclose(colours[0], ambient_only, rtol=0, atol=1e-15))
    return out


@case("zero-intensity lights",
      "a point and a directional light of intensity 0: every covered pixel is exactly the "
      "ambient colour, in every mode")
def dark_lights() -> Outcome:
    out = Outcome()
    lights = [Light(intensity=(0, 0, 0), position=(1.0, 2.0, 3.0)),
              Light(intensity=(0, 0, 0), direction=(0.0, 0.0, 1.0))]
    scene = _lit_sphere(GREY, lights)
    ambient8 = to_uint8(0.2 * GREY.ka * np.array(GREY.od))
    for projection in PROJECTIONS:
        for shading in SOLID_SHADINGS:
            image, _ = render_image(scene, projection, shading)
            mask = covered(image)
            wrong = int(np.count_nonzero(np.any(image[mask] != ambient8, axis=1)))
            out.check(f"{projection}/{shading}: {wrong} of {int(mask.sum())} pixels not ambient",
                      wrong == 0 and mask.sum() > 500)
    probe_all(out, scene)
    return out


@case("very bright lights",
      "two lights of intensity 1e308 (their sum overflows): lit pixels saturate to white, "
      "unlit ones stay ambient; nothing raises, nothing is NaN")
def bright_lights() -> Outcome:
    out = Outcome()
    material = Material(ka=0.2, kd=0.6, ks=0.3, n=20.0, od=(1.0, 1.0, 1.0))
    lights = [Light(intensity=(1e308,) * 3, position=(0.0, 0.0, 4.0)),
              Light(intensity=(1e308,) * 3, direction=(0.0, 0.0, 1.0))]
    scene = _lit_sphere(material, lights)
    probe_all(out, scene)
    for shading in SOLID_SHADINGS:
        image, _ = render_image(scene, "perspective", shading)
        mask = covered(image)
        white = int(np.count_nonzero(np.all(image[mask] == 255, axis=1)))
        out.check(f"{shading}: {white} of {int(mask.sum())} covered pixels white",
                  mask.sum() > 500 and white == mask.sum())
    ball = scene.meshes[0]
    front = ball.positions[:, 2] > 0.2
    _model_accuracy(out, ball.positions[front][:8], ball.normals[front][:8], material, lights,
                    label="saturated colours")
    return out


# The scene files of the non-finite case. Every number in <angle brackets> is one slot that
# the case spoils in turn (the brackets go; the other slots keep their value).
BAD_FILES = {
    ".tri": "<0> <0> <5>\n<-1> <1> <0>\n<0.004> <0> <0>\n<0> <-0.004> <0>\n1\n"
            "<0> <0> <0>  <1> <0> <0>  <0> <1> <0>\n",
    ".obj": "v <0> <0> <0>\nv <1> <0> <0>\nv <0> <1> <0>\nvn <0> <0> <1>\nf 1//1 2//1 3//1\n",
    ".views": "<0> <0> <54>\n<0> <0> <1>\n<0> <1> <0>\n<-1> <17> <-1> <17>\n<8> <6> <30>\n<1> <-23>\n"
              "0 0 54\n0 0 1\n0 1 0\n-1 17 -1 17\n8 6 30\n1 -23\n",
    ".toml": "name = \"bad\"\nambient = [<0.2>, <0.2>, <0.2>]\nbackground = [<0>, <0>, <0>]\n"
             "[[geometry]]\ngenerator = \"cube\"\nparams = { size = <2.0> }\n"
             "transform = { translate = [<0>, <0>, <0.5>] }\n"
             "material = { ka = <0.2>, kd = <0.7>, ks = <0.3>, n = <20>, od = [<0.8>, <0.8>, <0.8>] }\n"
             "[[view]]\nvrp = [<0>, <0>, <0>]\nvpn = [<0>, <0>, <1>]\nvup = [<0>, <1>, <0>]\n"
             "window = [<-2>, <2>, <-2>, <2>]\nprp = [<0>, <0>, <6>]\nfront = <2>\nback = <-2>\n"
             "[[light]]\nposition = [<4>, <6>, <8>]\nintensity = [<1>, <1>, <1>]\n"
             "attenuation = [<1>, <0>, <0>]\n",
}
SLOT = re.compile(r"<([^>]*)>")


def spoiled(template: str, k: int, bad: str) -> str:
    """``template`` with slot ``k`` replaced by ``bad`` and every other slot by its value."""
    count = iter(range(10 ** 6))
    return SLOT.sub(lambda m: bad if next(count) == k else m.group(1), template)


def _bad_files(bad: str) -> list[tuple[str, str]]:
    """``(file name, text)`` for every slot of every template spoiled by ``bad``."""
    return [(f"slot{k:02d}{suffix}", spoiled(template, k, bad))
            for suffix, template in BAD_FILES.items()
            for k in range(len(SLOT.findall(template)))]


@case("NaN and inf anywhere in a scene file",
      "NaN, inf, -inf or 1e999 in any number of a .tri, OBJ, TOML or view file: the reader's "
      "message (file, line, reason), or for a view file that view's message while the others "
      "load; never a NaN pixel")
def non_finite_files() -> Outcome:
    from core.scene.formats import ReaderError, load_scene
    from core.render import render
    out = Outcome()
    refused = loaded = 0
    problems = []
    example = {}
    with tempfile.TemporaryDirectory() as folder:
        for bad in ("nan", "inf", "-inf", "1e999"):
            for name, text in _bad_files(bad):
                path = Path(folder) / name
                path.write_text(text)
                try:
                    scene = load_scene(path)
                except ReaderError as error:
                    message = str(error)
                    if not message.startswith(str(path)):
                        problems.append(f"{name} ({bad}): message does not name the file: {message}")
                    refused += 1
                    example.setdefault(path.suffix, message.replace(str(path.parent) + "/", ""))
                    continue
                if path.suffix != ".views":
                    problems.append(f"{name} ({bad}) loaded without a message")
                    continue
                loaded += 1
                messages = scene.view_messages
                if len(messages) != 1 or len(scene.views) != 1 or "finite" not in messages[0]:
                    problems.append(f"{name} ({bad}): views {len(scene.views)}, messages {messages}")
                example.setdefault(".views", (messages[0] if messages else "")
                                   .replace(str(path.parent) + "/", ""))
                for projection in PROJECTIONS:
                    frame = render(scene, scene.views[0],
                                   RenderSettings.for_scene(scene, projection=projection, shading="wireframe", size=SIZE))
                    if frame.message is not None:
                        problems.append(f"{name}: the good view did not render: {frame.message}")
    out.check(f"{refused} files refused by their reader, {loaded} view files loaded their good "
              f"view with the bad one's message", refused > 0 and loaded > 0)
    out.check("every message names the file and the reason" if not problems
              else f"{len(problems)} problems: " + "; ".join(problems[:3]), not problems)
    for suffix, message in sorted(example.items()):
        out.note(f"e.g. {message}")
    return out


# --------------------------------------------------------------------------------------------
# Loader and renderer agree: what loads, renders

# Numbers an attacker would write into a view: huge, subnormal, one ulp apart, signed zeros.
_EXTREMES = (0.0, -0.0, 1.0, -1.0, 5.0, 0.9999999999999999, 1.0000000000000002, 1e-300,
             -1e-301, 1e-320, 5e-324, 1e-160, 1e154, 1e200, -1e200, 1e308, -1e308, 3.0, 1e-9)
_AGREEMENT_VIEWS = 300      # seeded random views besides the reproducers
_REPRODUCERS = (
    # VRP, VPN, VUP, window, PRP, F, B — the views the reader accepted and the renderer crashed on
    ((0, 0, 0), (0, 0, 1), (0, 1, 0), (-1, 1, -1, 1), (0, 0, 5), 1, 0.9999999999999999),
    ((0, 0, 0), (0, 0, 1), (0, 1, 0), (-1, 1, -1, 1), (0, 0, 1e-300), 1e-301, -1),
    ((0, 0, 0), (1e308, 1e308, 1e308), (0, 0, 1), (-1, 1, -1, 1), (0, 0, 5), 1, -1),
    ((0, 0, 0), (1e-320, 0, 0), (0, 1, 0), (-1, 1, -1, 1), (0, 0, 5), 1, -1),
)


def _agreement_views_text() -> str:
    """A view file: the reproducers, then random views that mix sane and extreme numbers."""
    rng = np.random.default_rng(15)
    sane = (0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, -1.0, 1.0, -1.0, 1.0, 0.0, 0.0, 5.0,
            1.0, -1.0)
    lines = []
    for view in _REPRODUCERS:
        numbers = [c for part in view for c in (part if isinstance(part, tuple) else (part,))]
        lines.append(" ".join(repr(float(c)) for c in numbers))
    for _ in range(_AGREEMENT_VIEWS):
        numbers = list(sane)
        for slot in rng.choice(18, size=rng.integers(1, 5), replace=False):
            numbers[slot] = float(rng.choice(_EXTREMES)) * (1 if rng.random() < 0.7 else -1)
        lines.append(" ".join(repr(c) for c in numbers))
    return "\n".join(lines) + "\n"


@case("loader and renderer agree on every view",
      "the issue's four views and 300 seeded views of huge, subnormal and one-ulp numbers, read "
      "from a view file: every view the reader accepts renders in both projections (wireframe, "
      "flat, Phong) without an exception; a frame that refuses a view gives the same reason the "
      "validity rules give; a view neither projection can draw is refused at load, with its "
      "reason")
def loader_renderer_agreement() -> Outcome:
    from core.camera.view import problems
    from core.render import render
    from core.scene.formats import load_scene
    out = Outcome()
    crashes, disagreements, refused_frames = [], [], 0
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "agreement.views"
        path.write_text(_agreement_views_text())
        scene = load_scene(path)
    unrenderable = []
    for view in scene.views:
        if all(problems(view, projection) for projection in PROJECTIONS):
            unrenderable.append(view.label)
        for projection in PROJECTIONS:
            for shading in ("wireframe", "flat", "phong"):
                settings = RenderSettings.for_scene(scene, projection=projection,
                                                    shading=shading, size=(24, 24))
                try:
                    frame = render(scene, view, settings)
                except Exception as error:            # the very thing this case looks for
                    crashes.append(f"{view.label} {projection} {shading}: "
                                   f"{type(error).__name__}: {error}")
                    continue
                if frame.message:
                    refused_frames += 1
                    reasons = problems(view, projection)
                    if not reasons or not all(r in frame.message for r in reasons):
                        disagreements.append(f"{view.label} {projection}: {frame.message}")
    total = len(scene.views) + len(scene.view_messages)
    out.check(f"{len(scene.views)} of {total} views loaded, {len(scene.view_messages)} refused "
              f"with a reason", total == _AGREEMENT_VIEWS + len(_REPRODUCERS)
              and all(": " in m for m in scene.view_messages))
    out.check("every loaded view can be drawn in at least one projection" if not unrenderable
              else f"{len(unrenderable)} loaded views draw in neither: {unrenderable[:3]}",
              not unrenderable)
    out.check("every loaded view rendered in both projections without an exception" if not
              crashes else f"{len(crashes)} exceptions: " + "; ".join(crashes[:3]), not crashes)
    out.check(f"{refused_frames} frames refused a view for one projection, each with the rules' "
              f"reason" if not disagreements else
              f"{len(disagreements)} frames disagree: " + "; ".join(disagreements[:3]),
              not disagreements)
    for message in scene.view_messages[:2]:
        out.note(f"e.g. {message.replace(str(path.parent) + '/', '')}")
    return out
