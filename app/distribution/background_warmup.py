"""The window's warm-up in the background: ``python -m app warmup --progress-json`` in a
child process, its progress read line by line, so that the window knows which kernels are
ready (:class:`BackgroundWarmup`).
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path
from typing import Callable


WINDOW_NICE = 19      # the most a process can lower its own priority


class BackgroundWarmup:
    """``python -m app warmup --progress-json`` in a subprocess, for the window.

    Its stdout is read on a daemon thread; its stderr goes to ``log_path`` (by default
    ``warmup.log`` beside the stamp). The properties are safe to read from any thread.
    ``on_event``, when given, is called with no arguments after each event has been taken in
    (the window passes ``glfw.post_empty_event`` to wake its loop); it runs on the reader
    thread and what it raises is ignored.
    """

    def __init__(self, first_scene=None, jobs: int | None = None,
                 on_event: Callable[[], object] | None = None, log_path=None,
                 extra_args=()):
        from app.distribution.warm_stamp import stamp_path
        from core.paths import ROOT
        self._lock = threading.Condition()
        self._total: int | None = None
        self._done: list[str] = []
        self._current: list[str] = []
        self._scenes_done: set[str] = set()
        self._opened: set[str] = set()          # files whose first picture is compiled
        self._failed: list[str] = []
        self._finished = False
        self._ok: bool | None = None
        self._on_event = on_event
        self._scenes_dir = (ROOT / "scenes").resolve()
        # below the window's priority: while the user works, the window's frames come first
        command = [sys.executable, "-m", "app.distribution.warmup", "--progress-json",
                   "--until-stdin-closes", "--nice", str(WINDOW_NICE)]
        if first_scene is not None:
            command += ["--first", str(first_scene)]
        if jobs:
            command += ["--jobs", str(int(jobs))]
        command += [str(arg) for arg in extra_args]
        self.log_path = Path(log_path) if log_path else stamp_path().with_name("warmup.log")
        self.log_path.parent.mkdir(parents=True, exist_ok=True)
        self._log = open(self.log_path, "ab")
        # its stdin is ours: when this process ends, however it ends, the warm-up ends too
        self._process = subprocess.Popen(command, cwd=ROOT, stdin=subprocess.PIPE,
                                         stdout=subprocess.PIPE, stderr=self._log,
                                         text=True, encoding="utf-8", errors="replace",
                                         bufsize=1)
        self._reader = threading.Thread(target=self._read, name="warm-up progress",
                                        daemon=True)
        self._reader.start()

    # what the subprocess says
    def _read(self) -> None:
        for line in self._process.stdout:
            try:
                event = json.loads(line)
            except ValueError:
                continue                        # not one of ours (a stray print)
            if isinstance(event, dict):
                self._take(event)
        code = self._process.wait()
        with self._lock:
            if not self._finished:              # it ended without saying so (killed, crashed)
                self._finished, self._ok = True, False
                self._failed.append(f"the warm-up exited with code {code} before it finished")
            self._lock.notify_all()
        self._wake()
        self._log.close()

    def _take(self, event: dict) -> None:
        kind = event.get("event")
        with self._lock:
            if kind == "start":
                self._total = int(event.get("total", 0))
            elif kind == "begin":
                self._current.append(str(event.get("label")))
            elif kind in ("done", "failed"):
                label = str(event.get("label"))
                if label in self._current:
                    self._current.remove(label)
                if kind == "done":
                    self._done.append(label)
                    self._scenes_done.update(event.get("scenes") or ())
                    if event.get("opens"):
                        self._opened.add(str(event["opens"]))
                else:
                    self._failed.append(f"{label}: {event.get('error')}")
            elif kind == "finished":
                self._finished = True
                self._ok = bool(event.get("ok"))
                self._current.clear()
            self._lock.notify_all()
        self._wake()

    def _wake(self) -> None:
        if self._on_event is not None:
            try:
                self._on_event()
            except Exception:                   # noqa: BLE001  (the window's; not ours)
                pass

    # what the window asks
    @property
    def total(self) -> int | None:
        """How many steps the warm-up runs (None until it has said)."""
        with self._lock:
            return self._total

    @property
    def done(self) -> int:
        """How many steps have succeeded."""
        with self._lock:
            return len(self._done)

    @property
    def current(self) -> tuple[str, ...]:
        """The labels of the steps the workers are on now."""
        with self._lock:
            return tuple(self._current)

    @property
    def finished(self) -> bool:
        """Whether the warm-up has ended (every step run, stopped, or the process gone)."""
        with self._lock:
            return self._finished

    @property
    def ok(self) -> bool | None:
        """True when every step succeeded (the stamp is written), False when not, None
        while it runs."""
        with self._lock:
            return self._ok

    @property
    def failed(self) -> list[str]:
        """One message a failed step (``label: error``), and one if the process died."""
        with self._lock:
            return list(self._failed)

    def ready_for(self, scene_path, every_setting: bool = False) -> bool:
        """Whether pictures of ``scene_path`` will load, not compile: its first picture (the
        ``--first`` step) or the step for that shipped scene in every renderer, shading and
        filter (only that one with ``every_setting``) has succeeded, or the whole warm-up
        has finished."""
        with self._lock:
            return self._finished or self._covers(scene_path, every_setting)

    def _covers(self, scene_path, every_setting: bool) -> bool:
        path = Path(scene_path).resolve()
        if not every_setting and str(path) in self._opened:
            return True
        return path.parent == self._scenes_dir and path.name in self._scenes_done

    def wait_for(self, scene_path, timeout: float | None = None,
                 every_setting: bool = False) -> bool:
        """Block until :meth:`ready_for` ``scene_path`` (or ``timeout`` seconds); its value."""
        with self._lock:
            return self._lock.wait_for(
                lambda: self._finished or self._covers(scene_path, every_setting), timeout)

    def wait(self, timeout: float | None = None) -> bool:
        """Block until the warm-up has finished (or ``timeout`` seconds); :attr:`finished`."""
        with self._lock:
            return self._lock.wait_for(lambda: self._finished, timeout)

    @property
    def returncode(self) -> int | None:
        """The subprocess's exit status, None while it runs."""
        return self._process.poll()

    def stop(self, timeout: float = 10.0) -> None:
        """End the warm-up: SIGTERM (it terminates its workers and exits), SIGKILL after
        ``timeout`` seconds (the workers then exit on their own: they watch their parent)."""
        if self.finished and self._process.poll() is None:
            try:                                # it has said its last: let it exit itself
                self._process.wait(timeout)
            except subprocess.TimeoutExpired:
                pass
        if self._process.poll() is None:
            self._process.terminate()
            try:
                self._process.wait(timeout)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        self._reader.join(timeout)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()
