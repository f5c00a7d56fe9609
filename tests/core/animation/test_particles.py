"""Particle systems: N(t) = N_mean ± V, lifetimes, forces and the plane, generations,
determinism, and the particle stage (never through an opaque surface)."""

from __future__ import annotations

import numpy as np
import pytest

from core.animation.keys import animation_of
from core.animation.particles import ParticleSystem, Spec
from core.scene.formats import ReaderError, read_scene_file


def fountain(**changes) -> Spec:
    spec = Spec(shape="disc", position=np.zeros(3), radius=0.2, normal=np.array([0, 1.0, 0]),
                rate=(40.0, 10.0), velocity=(np.array([0, 5.0, 0]), np.array([1.0, 0.5, 1.0])),
                lifetime=(1.0, 0.25), gravity=np.array([0, -9.8, 0]),
                plane=(np.zeros(3), np.array([0, 1.0, 0])))
    for key, value in changes.items():
        setattr(spec, key, value)
    return spec


def test_counts_per_frame_follow_n_mean_plus_or_minus_v():
    system = ParticleSystem([fountain()], fps=30, seed=3)
    system.state_at(200 / 30)
    counts = np.array([c[0] for c in system.emitted])
    assert len(counts) == 200
    assert counts.min() >= 30 and counts.max() <= 50            # N_mean ± V = 40 ± 10
    assert abs(counts.mean() - 40) < 1.5                          # Rand uniform in [-1, 1]
    assert counts.std() > 3                                        # and it does vary


def test_lifetimes_are_respected():
    system = ParticleSystem([fountain(stop=1.0)], fps=30, seed=4)
    for t in np.arange(0.1, 1.0, 0.1):
        p = system.state_at(t)
        assert len(p) > 0 and np.all(p.age < p.life)
        assert np.all(p.life >= 0.75 - 1e-12) and np.all(p.life <= 1.25 + 1e-12)
    assert len(system.state_at(1.0 + 1.25 + 2 / 30)) == 0          # the last is gone by then
    assert len(system.state_at(1.0 + 0.5)) > 0                     # but not before


def test_plane_collision_keeps_particles_above_it_and_forces_act():
    system = ParticleSystem([fountain(lifetime=(3.0, 0.0))], fps=30, seed=5)
    for t in np.arange(0.2, 3.0, 0.2):
        p = system.state_at(t)
        assert np.all(p.position[:, 1] >= -1e-12)
    # a particle alone under gravity from rest: y = -g t^2 / 2 up to the step's error
    drop = ParticleSystem([Spec(rate=(1.0, 0.0), stop=1e-3, lifetime=(5.0, 0.0),
                                gravity=np.array([0, -9.8, 0]), position=np.array([0, 10.0, 0]))],
                          fps=30, seed=1)
    p = drop.state_at(1.0)
    t = p.age[0]
    assert abs(p.position[0, 1] - (10 - 9.8 * t * t / 2)) < 0.06     # Euler: g dt t / 2 = 0.04
    assert np.allclose(p.velocity[0], [0, -9.8 * t, 0], atol=1e-9)


def test_removal_by_region_and_threshold():
    spec = fountain(region=(np.array([-10, -1, -10.0]), np.array([10, 1.0, 10])), plane=None,
                    lifetime=(5.0, 0.0))
    system = ParticleSystem([spec], fps=30, seed=6)
    for t in (0.5, 1.0, 2.0):
        assert np.all(system.state_at(t).position[:, 1] <= 1.0)
    faded = ParticleSystem([fountain(alpha=(1.0, 0.0), alpha_end=0.0, alpha_min=0.5,
                                     lifetime=(2.0, 0.0))], fps=30, seed=6)
    p = faded.state_at(3.0)
    assert len(p) > 0 and np.all(p.age < 1.0 + 1e-9)           # alpha < 0.5 after half a life


def test_children_are_born_where_their_parents_die():
    spark = Spec(shape="point", lifetime=(0.5, 0.0), speed=(3.0, 0.0), inherit=0.0)
    rocket = Spec(rate=(2.0, 0.0), stop=0.01, lifetime=(1.0, 0.0),
                  velocity=(np.array([0, 10.0, 0]), np.zeros(3)),
                  children=(50.0, 10.0), child=spark)
    system = ParticleSystem([rocket], fps=30, seed=8)
    p = system.state_at(1.2)
    kids = p.generation == 1
    assert 2 * 40 <= kids.sum() <= 2 * 60 and not np.any(p.generation == 0)   # 2 rockets burst
    # each spark flew at 3 units/s for its age from where its rocket died, (0, 10, 0) to
    # within one step of the rocket's flight (10 units/s / 120 steps/s)
    assert np.allclose(np.linalg.norm(p.velocity[kids], axis=1), 3.0, atol=1e-9)
    gone = np.linalg.norm(p.position[kids] - [0, 10, 0], axis=1)
    assert np.all(np.abs(gone - 3.0 * p.age[kids]) < 10 / 120 + 1e-9)


def test_deterministic_from_scratch_and_when_played():
    a = ParticleSystem([fountain()], fps=30, seed=9)
    for k in range(101):                              # played frame by frame
        a.state_at(k / 30)
    b = ParticleSystem([fountain()], fps=30, seed=9)  # straight to frame 100
    pa, pb = a.particles, b.state_at(100 / 30)
    assert len(pa) == len(pb)
    assert np.array_equal(pa.position, pb.position) and np.array_equal(pa.color, pb.color)
    c = ParticleSystem([fountain()], fps=30, seed=10)
    assert not np.array_equal(c.state_at(100 / 30).position[:10], pb.position[:10])


def test_a_hundred_thousand_live_particles():
    system = ParticleSystem([fountain(rate=(5000.0, 0.0), lifetime=(1.0, 0.0))], fps=30, seed=11)
    p = system.state_at(1.0)
    assert 100_000 <= len(p) <= 160_000


WALL_SCENE = """
shading = "flat"
background = [0, 0, 0]
[[geometry]]
generator = "cube"
name = "wall"
transform = { scale = [2, 2, 0.1], translate = [0, 0, 2] }
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-4, 4, -4, 4]
prp = [0, 0, 10]
front = 5
back = -5
[animation]
duration = 1
fps = 10
[[emitter]]
shape = "sphere"
radius = 2.5
rate = 3000
lifetime = 10
size = 0.15
color = [1, 1, 0]
alpha = 0.9
"""


def render_frame(text, k, size=(64, 64), samples=1):
    from core.animation.frames import render_at
    from core.settings import RenderSettings
    scene = read_scene_file(text, "scene.toml")
    anim = animation_of(scene)
    return render_at(anim, anim.time_of(k), RenderSettings.for_scene(scene, size=size,
                                                                     samples=samples))


def test_a_particle_is_never_drawn_through_an_opaque_surface():
    """A wall in front of a shell of particles: where the wall is, the picture with particles
    equals the picture without; around it the particles show."""
    with_particles = render_frame(WALL_SCENE, 5)
    without = render_frame(WALL_SCENE.replace("rate = 3000", "rate = 0"), 5)
    depth = without.depth
    wall = np.isfinite(depth)
    assert wall.sum() > 200 and (~wall).sum() > 200
    # particles behind the wall (z = -2.5 side of the shell) stay hidden; the front half of
    # the shell (z up to 2.5, nearer than the wall at z = 2.05) may cover it, so compare only
    # with the particles in front removed
    behind = render_frame(WALL_SCENE.replace('shape = "sphere"', 'shape = "disc"\nnormal = [0, 0, 1]\n'
                                             'position = [0, 0, -1]').replace('radius = 2.5', 'radius = 4'), 5)
    assert np.array_equal(behind.color[wall], without.color[wall])
    assert not np.array_equal(behind.color[~wall], without.color[~wall])
    assert not np.array_equal(with_particles.color[wall], without.color[wall])   # in front: drawn


def test_supersampled_particles_are_hidden_by_the_wall_sample_by_sample():
    behind_text = WALL_SCENE.replace('shape = "sphere"', 'shape = "disc"\nnormal = [0, 0, 1]\n'
                                     'position = [0, 0, -1]').replace('radius = 2.5', 'radius = 4')
    behind = render_frame(behind_text, 5, samples=4)
    without = render_frame(WALL_SCENE.replace("rate = 3000", "rate = 0"), 5, samples=4)
    inside = np.isfinite(render_frame(WALL_SCENE, 5).depth)
    inside[1:-1] &= inside[:-2] & inside[2:]                 # away from the wall's edge
    inside[:, 1:-1] &= inside[:, :-2] & inside[:, 2:]
    assert inside.sum() > 200
    assert np.array_equal(behind.color[inside], without.color[inside])
    assert not np.array_equal(behind.color, without.color)
    assert behind.stats["samples per pixel"] == 4


def test_frame_100_twice_from_scratch_is_pixel_identical():
    text = WALL_SCENE.replace("duration = 1", "duration = 12").replace("lifetime = 10", "lifetime = 2")
    first = render_frame(text, 100).color.copy()
    second = render_frame(text, 100).color
    assert np.array_equal(first, second)
    assert (first[..., 0] > 100).sum() > 50            # yellow particles are there


@pytest.mark.parametrize("change,message", [
    (("rate = 3000", "rate = -1"), "emitter[1].rate: -1 is out of range"),
    (('shape = "sphere"', 'shape = "cone"'), "emitter[1].shape: 'cone' is not one of"),
    (('shape = "sphere"', 'shape = "mesh"\nmesh = "roof"'), "emitter[1].mesh: no geometry is named 'roof'"),
    (("lifetime = 10", "lifetime = 1\nlifetime_var = 1"), "lifetime - lifetime_var must stay above 0"),
    (("alpha = 0.9", "alpha = 0.9\nchildren = 3"), "children need a 'child' table"),
])
def test_bad_emitters_name_the_key(change, message):
    with pytest.raises(ReaderError) as error:
        read_scene_file(WALL_SCENE.replace(*change), "scene.toml")
    assert message in str(error.value)


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
def test_depth_test_is_the_z_buffers_own_convention(projection):
    """Sprites just in front of a wall (z = 2.1) show, those just behind it do not: the
    particle stage's depth is the z-buffer's canonical depth, larger nearer, in both
    projections."""
    from core import RenderSettings, render
    from core.animation.draw import SPRITE, Sprites, draw_particles
    scene = read_scene_file(WALL_SCENE, "scene.toml")
    view = scene.views[0]
    settings = RenderSettings.for_scene(scene, size=(64, 64), projection=projection)
    xy = np.array([[-1.0, -1.0], [1.0, 1.0]])
    for dz, visible in ((+0.02, True), (-0.02, False)):
        frame = render(scene, view, settings)
        before = frame.color.copy()
        points = np.column_stack([xy, np.full(2, 2.1 + dz)])
        sprites = Sprites(position=points, tail=points, radius=np.full(2, 0.3),
                          rgb=np.tile([0.0, 1.0, 0.0], (2, 1)), alpha=np.ones(2),
                          mode=np.full(2, SPRITE))
        assert draw_particles(frame, sprites, view, settings) == 2
        changed = np.any(frame.color != before, axis=2)
        assert changed.any() == visible
        if visible:                                   # green, where the sprites are
            drawn, under = frame.color[changed].astype(int), before[changed].astype(int)
            assert np.all(drawn[:, 1] > under[:, 1]) and drawn[:, 1].max() > 200


@pytest.mark.parametrize("keep_aspect", [False, True])
def test_a_point_lands_on_the_pixel_the_z_buffer_uses(keep_aspect):
    """A point particle just in front of the wall's face near its corner lands on a wall pixel;
    one just beyond the corner lands on the background: the stage maps to the device as the
    z-buffer does, letterboxed or stretched, on a framebuffer of another aspect."""
    from core import RenderSettings, render
    from core.animation.draw import POINT, Sprites, draw_particles
    scene = read_scene_file(WALL_SCENE, "scene.toml")
    view = scene.views[0]
    settings = RenderSettings.for_scene(scene, size=(96, 64), keep_aspect=keep_aspect)
    for corner, on_wall in ((1.85, True), (2.15, False)):
        frame = render(scene, view, settings)
        depth, before = frame.depth.copy(), frame.color.copy()
        point = np.array([[corner, corner, 2.11]])
        sprites = Sprites(position=point, tail=point, radius=np.ones(1), rgb=np.ones((1, 3)),
                          alpha=np.ones(1), mode=np.full(1, POINT))
        draw_particles(frame, sprites, view, settings)
        rows, cols = np.nonzero(np.any(frame.color != before, axis=2))
        assert len(rows) == 1
        assert np.isfinite(depth[rows[0], cols[0]]) == on_wall


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
@pytest.mark.parametrize("listed", ["near first", "far first"])
def test_particles_blend_back_to_front_whatever_their_order(projection, listed):
    """Two half-transparent points on one pixel, a red one behind a blue one, over a black
    frame with nothing to hide them: "over" applied back to front gives, by hand,
    blue over (red over black) = 0.5 blue + 0.5 (0.5 red) = (0.25, 0, 0.5), in whichever
    order the particles are listed; front to back would give (0.5, 0, 0.25)."""
    from core import RenderSettings, render
    from core.animation.draw import POINT, Sprites, draw_particles
    scene = read_scene_file(WALL_SCENE, "scene.toml")
    view = scene.views[0]
    settings = RenderSettings.for_scene(scene, size=(64, 64), projection=projection)
    frame = render(scene, view, settings)
    frame.color[:] = 0
    frame.depth = None                                 # nothing opaque in front of them
    far, near = [0.0, 0.0, 2.3], [0.0, 0.0, 2.6]       # the eye looks down -z from z > 3
    points = np.array([near, far] if listed == "near first" else [far, near])
    rgb = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]] if listed == "near first"
                   else [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    sprites = Sprites(position=points, tail=points, radius=np.ones(2), rgb=rgb,
                      alpha=np.full(2, 0.5), mode=np.full(2, POINT))
    assert draw_particles(frame, sprites, view, settings) == 2
    rows, cols = np.nonzero(np.any(frame.color != 0, axis=2))
    assert len(rows) == 1                              # both on the same pixel
    assert frame.color[rows[0], cols[0]].tolist() == [64, 0, 128]   # 0.25, 0, 0.5 rounded up
