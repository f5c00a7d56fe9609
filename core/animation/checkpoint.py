"""A particle system's state at one step, to be handed to whoever renders the frames after it.

The simulation is deterministic for a seed (step k draws from its own generator, seeded by
``(seed, k)``), so the live particles and the step count are the whole state: a system
restored from a checkpoint at step k steps on to exactly the numbers of one that played from
step 0. A movie split across workers sends each contiguous run of frames the checkpoint at
its first frame, so no worker simulates from t = 0. (A :class:`Checkpoint` is the particle
system's own ``snapshot()``, as the rigid bodies' and the flocks' are theirs.)
"""

from __future__ import annotations

from dataclasses import dataclass

from core.animation.particles import Checkpoint, ParticleSystem


def snapshot(system: ParticleSystem) -> Checkpoint:
    """The state of ``system`` now (copies: the system steps on without changing it)."""
    return system.snapshot()


def restore(system: ParticleSystem, checkpoint: Checkpoint) -> None:
    """Put ``system`` in the state of ``checkpoint`` (made by a system of the same rules)."""
    system.restore(checkpoint)


# ---------------------------------------------------------------------- every simulation


@dataclass
class SceneCheckpoint:
    """Every simulated state of an animation at one time: the particles' and that of each
    mover that steps (rigid bodies, flocks; None for a mover that is a function of time)."""

    particles: Checkpoint | None
    movers: list


def _stepping(mover) -> bool:
    return hasattr(mover, "snapshot")


def restore_animation(animation, checkpoint: SceneCheckpoint) -> None:
    """Put every simulation of ``animation`` in the state of ``checkpoint``."""
    if checkpoint.particles is not None and animation.particle_system is not None:
        restore(animation.particle_system, checkpoint.particles)
    for mover, state in zip(animation.movers, checkpoint.movers):
        if state is not None:
            mover.restore(state)


class Shadow:
    """Copies of an animation's simulations that step on by themselves (no picture drawn),
    to hand out the state at the first frame of each run of frames, asked for in order."""

    def __init__(self, animation):
        self.animation = animation
        system = animation.particle_system
        self.sim = None
        if system is not None:
            self.sim = ParticleSystem([system.specs[i] for i in system.roots], system.fps,
                                      system.seed, system.substeps)
            restore(self.sim, snapshot(system))
        self.movers = [m.copy() if _stepping(m) else None for m in animation.movers]

    @property
    def empty(self) -> bool:
        return self.sim is None and not any(m is not None for m in self.movers)

    def at(self, t: float) -> SceneCheckpoint | None:
        """The state at (the animation's local) time t; None when nothing simulates."""
        if self.empty:
            return None
        t = self.animation.local_time(t)
        particles = None
        if self.sim is not None:
            self.sim.state_at(t)
            particles = snapshot(self.sim)
        states = []
        for mover in self.movers:
            if mover is not None:
                mover.state_at(t)
            states.append(mover.snapshot() if mover is not None else None)
        return SceneCheckpoint(particles, states)
