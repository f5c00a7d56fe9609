"""A particle system's state at one step, to be handed to whoever renders the frames after it.

The simulation is deterministic for a seed (step k draws from its own generator, seeded by
``(seed, k)``), so the live particles and the step count are the whole state: a system
restored from a checkpoint at step k steps on to exactly the numbers of one that played from
step 0. A movie split across workers sends each contiguous run of frames the checkpoint at
its first frame, so no worker simulates from t = 0.
"""

from __future__ import annotations

from dataclasses import dataclass

from core.animation.particles import ARRAYS, ParticlePool, ParticleSystem, Particles


@dataclass
class Checkpoint:
    step_index: int
    particles: Particles          # the live particles, compact copies (what is pickled)

    @property
    def nbytes(self) -> int:
        return sum(getattr(self.particles, k).nbytes for k in ARRAYS)


def snapshot(system: ParticleSystem) -> Checkpoint:
    """The state of ``system`` now (copies: the system steps on without changing it)."""
    pool = system.particles
    return Checkpoint(system.step_index,
                      Particles(**{k: getattr(pool, k).copy() for k in ARRAYS}))


def restore(system: ParticleSystem, checkpoint: Checkpoint) -> None:
    """Put ``system`` in the state of ``checkpoint`` (made by a system of the same rules)."""
    system.reset()
    pool = ParticlePool(max(1024, len(checkpoint.particles)))
    pool.append(checkpoint.particles)
    system.particles = pool
    system.step_index = checkpoint.step_index
