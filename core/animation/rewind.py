"""Going back in a simulation without starting it again from t = 0.

A simulation (rigid bodies, actors, particles) steps forward from its state at t = 0; a moment
before its present (a seek back, a loop wrapping, a scrub) used to mean every step again from
0, so a jump back cost more the later the movie was. :class:`Rewind` keeps a snapshot every
``every`` steps as the simulation passes them, and going back restores the nearest one at or
before the moment, so a jump back costs at most ``every`` steps at any t. Snapshots are the
simulation's own (``snapshot()``/``restore()``, or the particles' checkpoints); the simulation
is deterministic, so one restored steps on to exactly the numbers of one that never stopped.
At most ``most`` are kept: past that every other one is dropped and the spacing doubles, so
the memory stays bounded on a long simulation.
"""

from __future__ import annotations

EVERY = 240          # steps between snapshots (1 s of rigid bodies at 1/240 s)
MOST = 64            # snapshots kept before thinning


class Rewind:
    def __init__(self, every: int = EVERY, most: int = MOST):
        self.every, self.most = max(1, int(every)), max(2, int(most))
        self.kept: dict[int, object] = {}

    def note(self, step_index: int, snapshot) -> None:
        """The simulation is at ``step_index``; ``snapshot()`` makes its state, when due."""
        if step_index % self.every or step_index in self.kept:
            return
        self.kept[step_index] = snapshot()
        if len(self.kept) > self.most:
            self.every *= 2
            self.kept = {k: v for k, v in self.kept.items() if k % self.every == 0}

    def nearest(self, target: int):
        """The kept snapshot at the latest step at or before ``target``, or None."""
        steps = [k for k in self.kept if k <= target]
        return self.kept[max(steps)] if steps else None
