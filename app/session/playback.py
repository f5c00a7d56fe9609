"""Playing an animated scene in the window: the clock, and the frame at a moment.

:class:`Playback` is the timeline of one :class:`core.animation.animation.Animation`: the time
shown, playing or paused, the speed, frame steps (the animation's own frames, ``k / fps``) and
seeking. Time runs on the wall clock while playing (``tick(now)``): a slow frame makes the next
one jump ahead instead of slowing the movie down. An animation that does not loop stops at its
end; one that loops wraps.

:func:`render_animated` draws the frame at a moment (``core.animation.frames.render_at``: the
opaque picture and the particles). The simulations (particles, rigid bodies, actors) play
forward from the last frame (cheap), but a moment before their present (a seek back, a loop
wrapping) starts again from their nearest snapshot, and a far seek forward may take seconds:
that stepping reports its progress and stops when a newer request supersedes it
(:mod:`core.work`).

No GL and no window library here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

SPEEDS = (0.125, 0.25, 0.5, 1.0, 2.0, 4.0)      # the speed control's choices (x real time)


@dataclass
class Playback:
    """The timeline of an animation: ``time`` in seconds, ``playing``, ``speed``."""

    animation: object
    time: float = 0.0
    playing: bool = False
    speed: float = 1.0
    _clock: float | None = None       # wall time when ``time`` was last advanced

    @property
    def duration(self) -> float:
        return float(self.animation.duration)

    @property
    def fps(self) -> float:
        return float(self.animation.fps)

    @property
    def frame_index(self) -> int:
        """The animation frame at or just before ``time`` (frame k is at k / fps), from 0 to
        ``frame_count - 1``."""
        return min(int(math.floor(self.time * self.fps + 1e-9)), self.frame_count - 1)

    @property
    def end(self) -> float:
        """The last moment of the timeline: a movie that does not loop ends on its last frame,
        ``(frame_count - 1) / fps``, the last picture ``animate`` writes; one that loops runs
        on to ``duration``, where it starts again."""
        if self.animation.loop:
            return self.duration
        return min(self.duration, (self.frame_count - 1) / self.fps)

    @property
    def frame_count(self) -> int:
        return int(self.animation.frame_count)

    def label(self) -> str:
        state = "playing" if self.playing else "paused"
        return (f"t = {self.time:.2f} s of {self.duration:.2f} s, frame {self.frame_index + 1} "
                f"of {self.frame_count}, {state}, speed {self.speed:g}x")

    def toggle(self, now: float) -> None:
        """Play or pause. Playing from the end of a movie that does not loop starts it again."""
        self.playing = not self.playing
        if self.playing and not self.animation.loop and self.time >= self.end:
            self.time = 0.0
        self._clock = now if self.playing else None

    def step(self, frames: int) -> None:
        """Pause and move ``frames`` animation frames (``,`` back, ``.`` forward)."""
        self.playing, self._clock = False, None
        self.time = self._fit((self.frame_index + frames) / self.fps)

    def seek(self, t: float, now: float | None = None) -> None:
        """Go to ``t`` seconds (the timeline slider); playing carries on from there."""
        self.time = self._fit(float(t))
        if self.playing:
            self._clock = now

    def set_speed(self, speed: float) -> None:
        if not (isinstance(speed, (int, float)) and 0.0 < speed <= 64.0):
            raise ValueError(f"speed must be a number in (0, 64], not {speed!r}")
        self.speed = float(speed)

    def tick(self, now: float) -> bool:
        """While playing: advance ``time`` by the wall time since the last tick times the
        speed; returns whether it moved. A movie that does not loop pauses at its end."""
        if not self.playing:
            return False
        if self._clock is None:
            self._clock = now
            return False
        elapsed, self._clock = now - self._clock, now
        if elapsed <= 0.0:
            return False
        t = self.time + elapsed * self.speed
        if self.animation.loop and self.duration > 0.0:
            t = math.fmod(t, self.duration)
        elif t >= self.end:
            t, self.playing, self._clock = self.end, False, None
        self.time = t
        return True

    def _fit(self, t: float) -> float:
        """``t`` inside the timeline: wrapped when the movie loops, else clamped."""
        if self.duration <= 0.0:
            return 0.0
        if self.animation.loop:
            return t % self.duration
        return min(max(t, 0.0), self.end)


def render_animated(animation, t: float, settings, context, view_index: int, control=None):
    """The frame at ``t`` seen through ``view_index`` (``render_at``'s numbering: the keyed
    view first). Its simulations (particles, rigid bodies, actors) step in chunks that report
    to ``control`` (:func:`core.work.control_watcher`): how far they are, and a newer request
    stops them between two chunks; a simulation stopped so steps on from there next time."""
    from core.animation.frames import render_at
    from core.work import control_watcher, watching
    with watching(control_watcher(control) if control is not None else None):
        return render_at(animation, t, settings, context, view_index=view_index)


class Player:
    """An animated scene's play, pause, step, seek and speed, as the window's controls ask
    (``state.player`` of :class:`app.session.state.ViewerState`, whose ``playback`` field is
    the :class:`Playback` moved, None for a still scene). Each move that changes the moment
    shown sets the state's ``dirty``."""

    def __init__(self, state):
        self.state = state        # the ViewerState: the fields live there, not here

    @property
    def animated(self) -> bool:
        return self.state.playback is not None

    @property
    def playing(self) -> bool:
        return self.animated and self.state.playback.playing

    def toggle(self, now: float) -> None:
        if self.animated:
            self.state.playback.toggle(now)
            self.state.dirty = True

    def step(self, frames: int) -> None:
        if self.animated:
            self.state.playback.step(frames)
            self.state.dirty = True

    def seek(self, t: float, now: float | None = None) -> None:
        if self.animated and float(t) != self.state.playback.time:
            self.state.playback.seek(t, now)
            self.state.dirty = True

    def set_speed(self, speed: float) -> None:
        if self.animated:
            self.state.playback.set_speed(speed)

    def tick(self, now: float, busy: bool) -> bool:
        """While playing: move time on (the wall clock times the speed) unless the last frame
        asked for is still being drawn (``busy``: the picture then skips ahead)."""
        s = self.state
        if s.playback is None or busy or not s.renderable:
            return False
        if s.playback.tick(now):
            s.dirty = True
            return True
        return False
