"""Long commands in a real process: a progress line on stderr once they have run a while
(none with -q), and Ctrl+C (SIGINT) as one line that says what stopped and what stays, status
130, no traceback and no half-written file."""

from __future__ import annotations

import queue
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from PIL import Image

from app.progress_line import SHOW_AFTER
from core.paths import SCENES_DIR

# one ball on a floor for 40,000 s: 9.6M steps, within the budget, and minutes to simulate
BALL = """
name = "ball"
size = [64, 48]
[[geometry]]
primitive = "sphere"
name = "ball"
center = [0, 1, 0]
radius = 0.2
[[light]]
position = [3, 6, 4]
[[view]]
vrp = [0, 0.6, 0]
vpn = [0, 0.3, 1]
vup = [0, 1, 0]
window = [-2, 2, -1.5, 1.5]
prp = [0, 0, 9]
front = 5
back = -5
[animation]
duration = 40000
fps = 30
[dynamics]
planes = [{ point = [0, 0, 0], normal = [0, 1, 0] }]
[[body]]
mesh = "ball"
mass = 1.0
restitution = 0.9
"""


class Running:
    """A command in a child process whose stderr is read line by line as it comes. The child
    gets SIGINT's default handler, as from a terminal (a shell that runs the suite in the
    background passes SIGINT on ignored)."""

    def __init__(self, *argv, cwd: Path):
        self.start = time.monotonic()
        self.process = subprocess.Popen(
            [sys.executable, "-m", "app", *argv], cwd=cwd, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        self.lines: queue.Queue = queue.Queue()
        self.err: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self.process.stderr:
            self.lines.put(line)
        self.lines.put(None)

    def wait_for(self, pattern: str, timeout: float = 120.0) -> str:
        """The first stderr line that matches ``pattern`` (the child still running)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                line = self.lines.get(timeout=1.0)
            except queue.Empty:
                continue
            assert line is not None, f"the command ended first: {''.join(self.err)}"
            self.err.append(line)
            if re.search(pattern, line):
                return line
        raise AssertionError(f"no line matching {pattern!r}: {''.join(self.err)}")

    def interrupt(self) -> tuple[int, str, str]:
        """Ctrl+C; ``(status, stdout, the whole stderr)``."""
        self.process.send_signal(signal.SIGINT)
        out = self.process.stdout.read()
        self.process.wait(timeout=120)
        while (line := self.lines.get(timeout=120)) is not None:
            self.err.append(line)
        return self.process.returncode, out, "".join(self.err)


def leftovers(folder: Path) -> list[str]:
    """Temporary files (ours are .tmp, hidden or not)."""
    return sorted(p.name for p in folder.rglob("*") if ".tmp" in p.name)


def test_ctrl_c_stops_a_long_render_with_one_line_and_no_file(tmp_path):
    (tmp_path / "ball.toml").write_text(BALL)
    run = Running("render", "ball.toml", "--time", "40000", "--out", "ball.png", cwd=tmp_path)
    shown = run.wait_for(r"^simulating the rigid bodies: step [0-9,]+ of 9,600,000 \(\d+ %\); "
                         r"\d+ s")
    status, out, err = run.interrupt()
    assert status == 130
    assert "Traceback" not in err and out == ""
    assert err.splitlines()[-1].startswith("stopped by Ctrl+C after ")
    assert re.fullmatch(r"stopped by Ctrl\+C after \d+ s \(simulating the rigid bodies: step "
                        r"[0-9,]+ of 9,600,000\): nothing was written \(ball\.png was not made\)",
                        err.splitlines()[-1])
    assert shown in run.err                             # progress lines, then the stop line
    assert all(line.startswith("simulating the rigid bodies: step ")
               for line in err.splitlines()[:-1])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ball.toml"]


def test_the_progress_line_is_shown_on_a_long_run_and_not_with_quiet(tmp_path):
    (tmp_path / "ball.toml").write_text(BALL)
    loud = Running("render", "ball.toml", "--time", "40000", "--out", "ball.png", cwd=tmp_path)
    loud.wait_for(r"^simulating the rigid bodies: step ")
    shown_after = time.monotonic() - loud.start
    assert loud.interrupt()[0] == 130

    quiet = Running("-q", "render", "ball.toml", "--time", "40000", "--out", "ball.png",
                    cwd=tmp_path)
    time.sleep(max(shown_after, SHOW_AFTER) + 1.0)      # past where the loud one showed it
    status, _, err = quiet.interrupt()
    assert status == 130
    (stop,) = err.splitlines()                          # the stop line and nothing else
    seconds = int(re.match(r"stopped by Ctrl\+C after (\d+) s \(simulating the rigid bodies: "
                           r"step [0-9,]+ of 9,600,000\)", stop).group(1))
    assert seconds >= SHOW_AFTER                        # it ran long enough to have shown one


def test_ctrl_c_keeps_a_movies_finished_frames_and_no_half_written_file(tmp_path):
    scene = SCENES_DIR / "blocks_falling.toml"
    argv = ["animate", str(scene), "--size", "480x360", "--out", "movie.mp4"]
    run = Running(*argv, "--frames", "5000", cwd=tmp_path)
    run.wait_for(r"^rendering the frames: frame [0-9,]+ of 5,000 ")
    status, out, err = run.interrupt()
    assert status == 130
    assert "Traceback" not in err and out == ""
    last = err.splitlines()[-1]
    kept = re.fullmatch(r"stopped by Ctrl\+C after \d+ s \(rendering the frames: frame [0-9,]+ "
                        r"of 5,000(; simulating the rigid bodies: step [0-9,]+ of [0-9,]+)?\): "
                        r"(\d+) of 5000 frames are in movie\.frames; the same command renders "
                        r"the rest and writes movie\.mp4 \(not written now\)", last)
    assert kept, last
    count = int(kept.group(2))
    frames = sorted((tmp_path / "movie.frames").glob("frame_*.png"))
    assert count > 0 and len(frames) == count
    for frame in frames:                                 # each one whole
        with Image.open(frame) as image:
            image.load()
    assert leftovers(tmp_path) == []
    assert not (tmp_path / "movie.mp4").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["movie.frames"]
    # the frames kept are used: a movie of two more renders only those two
    done = subprocess.run([sys.executable, "-m", "app", *argv, "--frames", str(count + 2)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert f"{count} of {count + 2} frames already in movie.frames: skipped" in done.stderr
    assert f"wrote movie.mp4 ({count + 2} frames, 480x360, 30 fps; 2 rendered" in done.stdout
