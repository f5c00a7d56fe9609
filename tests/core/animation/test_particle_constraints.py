"""Particles constrained to a subspace (a cylinder, a curve) and regions of influence (the
course notes of 18 April), held to closed forms worked by hand: the helix of a free particle
on a cylinder, the discrete sum of semi-implicit Euler along a ramp, the impulse of a force
over the steps a particle spends inside a box or a sphere."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.animation.keys import animation_of
from core.animation.particle_constraint import Curve, Cylinder
from core.animation.particle_influence import BOX, SPHERE, Region
from core.animation.particles import Particles, ParticleSystem, Spec
from core.scene.formats import ReaderError, read_scene_file

FPS = 30                     # 4 steps a frame: dt = 1/120 s


def one_particle(spec: Spec, x, v) -> ParticleSystem:
    """A system that emits nothing, holding one particle at x with velocity v, age 0."""
    system = ParticleSystem([spec], fps=FPS, seed=1)
    one = lambda value: np.full(1, value, np.float64)
    system.particles.append(Particles(
        position=np.array([x], np.float64), velocity=np.array([v], np.float64), age=one(0.0),
        life=one(1e9), size=one(1.0), color=np.ones((1, 3)), color_end=np.ones((1, 3)),
        alpha=one(1.0), alpha_end=one(1.0), size_end=one(1.0), spec=np.zeros(1, np.int64),
        generation=np.zeros(1, np.int64)))
    return system


def steps(system: ParticleSystem, n: int) -> ParticleSystem:
    for _ in range(n):
        system.step()
    return system


CYLINDER = Cylinder(point=np.array([0.5, -1.0, 0.25]), axis=np.array([0.0, 1.0, 0.0]),
                    radius=1.5, height=np.inf)


def test_a_free_particle_on_a_cylinder_runs_its_helix_and_keeps_its_radius():
    """No force: the angle about the axis grows by v_t t / r and the height by v_h t, at
    constant speed (the geodesic of a cylinder); the radius stays r to round-off."""
    system = one_particle(Spec(rate=(0.0, 0.0), constraint=CYLINDER),
                          x=[0.5 + 1.5, -1.0, 0.25], v=[0.0, 0.3, -2.0])
    n = 10_000
    radii = []
    for _ in range(n // 100):
        steps(system, 100)
        d = system.particles.position[0] - CYLINDER.point
        radii.append(math.hypot(d[0], d[2]))
    assert np.max(np.abs(np.array(radii) - 1.5)) < 1e-12
    t = n * system.dt
    # e_r = +x at the start; e_t = axis x e_r = -z, so v_t = 2 and the point turns toward -z
    theta = 2.0 * t / 1.5
    expected = CYLINDER.point + [1.5 * math.cos(theta), 0.3 * t, -1.5 * math.sin(theta)]
    assert np.allclose(system.particles.position[0], expected, atol=1e-9, rtol=0)
    assert abs(np.linalg.norm(system.particles.velocity[0]) - math.hypot(0.3, 2.0)) < 1e-11


def test_gravity_along_the_axis_gives_the_discrete_fall_and_leaves_the_turning_alone():
    """Gravity g down the axis: the height is semi-implicit Euler's sum,
    h_n = h_0 + n v dt - g dt^2 n (n + 1) / 2, the angle v_t n dt / r as without it."""
    spec = Spec(rate=(0.0, 0.0), constraint=CYLINDER, gravity=np.array([0.0, -9.8, 0.0]))
    n = 480
    system = steps(one_particle(spec, x=[2.0, -1.0, 0.25], v=[0.0, 1.0, -3.0]), n)
    dt = system.dt
    h = n * 1.0 * dt - 9.8 * dt * dt * n * (n + 1) / 2
    theta = 3.0 * n * dt / 1.5
    expected = CYLINDER.point + [1.5 * math.cos(theta), h, -1.5 * math.sin(theta)]
    assert np.allclose(system.particles.position[0], expected, atol=1e-10, rtol=0)


def test_a_bead_on_a_ramp_slides_by_the_discrete_closed_form():
    """A straight curve from (0,0,0) to (4,-3,0): the tangent is (0.8, -0.6, 0) and gravity's
    part along it is 9.8 * 0.6 = 5.88; s_n = n v0 dt + 5.88 dt^2 n (n + 1) / 2."""
    ramp = Curve(points=np.array([[0.0, 0, 0], [4.0, -3.0, 0]]), closed=False)
    spec = Spec(rate=(0.0, 0.0), constraint=ramp, gravity=np.array([0.0, -9.8, 0.0]))
    n = 60
    system = steps(one_particle(spec, x=[0.0, 0, 0], v=[0.8, -0.6, 0]), n)
    dt = system.dt
    s = n * 1.0 * dt + 5.88 * dt * dt * n * (n + 1) / 2
    tangent = np.array([0.8, -0.6, 0.0])
    assert np.allclose(system.particles.position[0], s * tangent, atol=1e-12, rtol=0)
    assert np.allclose(system.particles.velocity[0], (1.0 + 5.88 * n * dt) * tangent,
                       atol=1e-12, rtol=0)
    # a sideways push does nothing: the wire takes it
    pushed = steps(one_particle(Spec(rate=(0.0, 0.0), constraint=ramp,
                                     gravity=np.array([0.0, -9.8, 0.0]),
                                     wind=np.array([0.0, 0.0, 50.0])),
                                x=[0.0, 0, 0], v=[0.8, -0.6, 0]), n)
    assert np.allclose(pushed.particles.position[0], s * tangent, atol=1e-12, rtol=0)


def test_an_open_curve_ends_its_particles_a_closed_one_carries_them_round():
    line = Curve(points=np.array([[0.0, 0, 0], [1.0, 0, 0], [1.0, 1.0, 0]]), closed=False)
    system = one_particle(Spec(rate=(0.0, 0.0), constraint=line), x=[0.0, 0, 0], v=[1.0, 0, 0])
    steps(system, 239)                       # 239/120 s: 1.99 of the 2 units of length
    assert len(system.particles) == 1
    assert np.allclose(system.particles.position[0], [1.0, 239 / 120 - 1.0, 0], atol=1e-12)
    assert np.allclose(system.particles.velocity[0], [0.0, 1.0, 0], atol=1e-15)  # turned the corner
    steps(system, 2)
    assert len(system.particles) == 0        # ran off the end
    square = Curve(points=np.array([[0.0, 0, 0], [1.0, 0, 0], [1.0, 1.0, 0], [0, 1.0, 0],
                                    [0.0, 0, 0]]), closed=True)
    loop = steps(one_particle(Spec(rate=(0.0, 0.0), constraint=square), x=[0.0, 0, 0],
                              v=[1.0, 0, 0]), 4 * 120 + 30)          # once round and a quarter
    assert np.allclose(loop.particles.position[0], [0.25, 0, 0], atol=1e-12)


def test_a_box_of_influence_changes_the_velocity_only_inside():
    """x_k = -1 + k dt at speed 1 across x in [0.0042, 0.5042]: the steps k = 121 .. 180
    start inside (60 of them), each adding a dt = 2/120 to v_y: 1.0 in all, the force times
    the half second spent inside. Before and after, v_y does not change."""
    box = Region(name="gust", kind=BOX, lo=np.array([0.0042, -10, -10]),
                 hi=np.array([0.5042, 10, 10]), radius=0.0, acceleration=np.array([0, 2.0, 0]))
    system = one_particle(Spec(rate=(0.0, 0.0), influences=(box,)), x=[-1.0, 0, 0], v=[1.0, 0, 0])
    vy = []
    for _ in range(300):
        system.step()
        vy.append(system.particles.velocity[0, 1])
    vy = np.array(vy)
    assert np.all(vy[:121] == 0.0)                               # steps 0 .. 120: outside
    assert np.allclose(np.diff(vy[120:181]), 2.0 / 120, rtol=1e-12)
    assert np.all(vy[180:] == vy[180]) and abs(vy[180] - 1.0) < 1e-12
    assert system.particles.velocity[0, 0] == 1.0                # along x: untouched


def test_a_sphere_of_influence_gives_the_impulse_of_its_chord():
    """A path at distance d from the centre crosses a chord 2 sqrt(R^2 - d^2); at speed s
    the impulse is a * chord / s, to within one step's a dt (the force is weak enough that
    the path drifts by under 0.01 inside: the chord changes by under 1e-4)."""
    sphere = Region(name="fan", kind=SPHERE, lo=np.array([0.0, 0.6, 0]), hi=np.zeros(3),
                    radius=1.0, acceleration=np.array([0, 0, 0.03]))
    system = steps(one_particle(Spec(rate=(0.0, 0.0), influences=(sphere,)), x=[-2.0, 0, 0],
                                v=[2.0, 0, 0]), 240)
    chord = 2 * math.sqrt(1.0 - 0.6 ** 2)
    assert abs(system.particles.velocity[0, 2] - 0.03 * chord / 2.0) <= 0.03 / 120 + 1e-12
    drag = Region(name="thick air", kind=SPHERE, lo=np.zeros(3), hi=np.zeros(3), radius=1.0,
                  acceleration=np.zeros(3), drag=6.0)
    # drag k inside: from the centre at 0.5 units/s the particle stays inside for 70 steps
    # (it goes under 0.3), so v_n = 0.5 (1 - k dt)^n; one passing at 1.2 from the centre: none
    slowed = steps(one_particle(Spec(rate=(0.0, 0.0), influences=(drag,)), x=[0.0, 0, 0],
                                v=[0.5, 0, 0]), 70)
    assert abs(slowed.particles.velocity[0, 0] - 0.5 * (1 - 6.0 / 120) ** 70) < 1e-14
    missed = steps(one_particle(Spec(rate=(0.0, 0.0), influences=(drag,)), x=[-2.0, 1.2, 0],
                                v=[1.0, 0, 0]), 480)
    assert missed.particles.velocity[0, 0] == 1.0


SCENE = "scenes/particle_constraints.toml"


def test_the_scene_keeps_its_beads_on_their_subspaces_and_the_updraft_in_its_column():
    anim = animation_of(read_scene_file(open(SCENE).read(), SCENE))
    system = anim.particle_system
    p = system.state_at(3.0)
    names = [s.name for s in system.specs]
    post = p.position[p.spec == names.index("beads on the post")]
    wire = p.position[p.spec == names.index("beads on the wire")]
    # the wire's 40 a frame at t = 0, 1/30, 2/30 (it stops at 0.1 s), none lost: a closed
    # curve has no end and they live 1000 s
    assert len(wire) == 120 and 20 < len(post) < 3 * 91
    cylinder = system.specs[names.index("beads on the post")].constraint
    assert np.max(cylinder.distance(post)) < 1e-12
    assert np.all((post[:, 1] >= -1e-12) & (post[:, 1] <= 3.0 + 1e-12))
    curve = system.specs[names.index("beads on the wire")].constraint
    assert np.max(curve.distance(wire)) < 1e-12


BASE = """
[[geometry]]
generator = "cube"
[animation]
duration = 1
[[emitter]]
name = "beads"
shape = "point"
position = [1, 0.5, 0]
constraint = { type = "cylinder", radius = 1, height = 2 }
[[influence]]
box = { min = [-1, -1, -1], max = [1, 1, 1] }
acceleration = [1, 0, 0]
"""


@pytest.mark.parametrize("change,message", [
    (("max = [1, 1, 1]", "max = [1, -1, 1]"),
     ":12: influence[1].box: the box has zero size along y (min -1, max -1)"),
    (("box = { min = [-1, -1, -1], max = [1, 1, 1] }", "sphere = { center = [0, 0, 0], radius = 0 }"),
     ":12: influence[1].sphere.radius: the sphere has zero size"),
    (("box = { min = [-1, -1, -1], max = [1, 1, 1] }", "sphere = { center = [0, 0, 0], radius = inf }"),
     ":12: influence[1].sphere.radius: a region of influence has a finite size"),
    (("max = [1, 1, 1]", "max = [inf, 1, 1]"), "influence[1].box.max: a region of influence has a finite size"),
    (("min = [-1, -1, -1]", "min = [-1e9, -1, -1]"), "influence[1].box.min: a region of influence lies within 1e+06"),
    (("acceleration = [1, 0, 0]", "acceleration = [nan, 0, 0]"),
     "influence[1].acceleration[1]: expected a finite number, got nan"),
    (("acceleration = [1, 0, 0]", ""), "needs an acceleration or a drag"),
    (("acceleration = [1, 0, 0]", "acceleration = [1, 0, 0]\nemitters = [\"sparks\"]"),
     "influence[1].emitters: no emitter is named 'sparks' (names: beads)"),
    (("position = [1, 0.5, 0]", "position = [1.5, 0.5, 0]"),
     ":9: emitter[1].position: the particles would start off their constraint: (1.5, 0.5, 0.0) "
     "is 0.5 from the cylinder's surface"),
    (('shape = "point"', 'shape = "disc"'), "emitter[1].shape: a constrained emitter's particles are born on its cylinder"),
    (("radius = 1, height = 2", "radius = nan, height = 2"), "emitter[1].constraint.radius: expected a finite number, got nan"),
    (("radius = 1, height = 2", "radius = 0, height = 2"), "the cylinder's radius must be above 0"),
    (("radius = 1, height = 2", "radius = 1"), None),                     # endless: a point is fine
    (('shape = "point"', 'shape = "constraint"'), None),
    (('{ type = "cylinder", radius = 1, height = 2 }', '{ type = "curve", points = [[1, 0.5, 0], [1, 0.5, 0], [2, 0, 0]] }'),
     "emitter[1].constraint.points[2]: two points in a row are the same"),
    (('{ type = "cylinder", radius = 1, height = 2 }', '{ type = "curve", points = [[0, 0.5, 0], [2, 0.5, 0]] }'), None),
    (('{ type = "cylinder", radius = 1, height = 2 }', '{ type = "curve", points = [[0, 0, 0], [2, 0.5, 0]] }'),
     "emitter[1].position: the particles would start off their constraint: (1.0, 0.5, 0.0) is"),
    (('{ type = "cylinder", radius = 1, height = 2 }', '{ type = "sphere" }'),
     "emitter[1].constraint.type: 'sphere' is not one of cylinder, curve"),
])
def test_bad_constraints_and_regions_are_one_line_naming_the_key(change, message):
    text = BASE.replace(*change)
    assert text != BASE
    if message is None:
        read_scene_file(text, "scene.toml")
        return
    with pytest.raises(ReaderError) as error:
        read_scene_file(text, "scene.toml")
    said = str(error.value)
    assert said.startswith("scene.toml:") and "\n" not in said and message in said, said


def test_constrained_births_spread_over_a_frame_still_lie_on_the_subspace():
    """Births are spread over their frame (each moved on by its age): on the subspace too."""
    scene = read_scene_file(BASE.replace('shape = "point"', 'shape = "constraint"\nrate = 500\n'
                                         'speed = 4\ngravity = [0, -9.8, 0]'), "scene.toml")
    system = animation_of(scene).particle_system
    p = system.state_at(0.5)
    assert len(p) > 1000 and np.max(system.specs[0].constraint.distance(p.position)) < 1e-12
    assert np.all(p.age > 0)
