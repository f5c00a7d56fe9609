"""``python -m app bench --window``: what a user sees in the window, not what a kernel does.

Each case opens the real window (``python -m app -v view``) under X — a virtual one (Xvfb)
when there is no display — and drives it as a hand would with xdotool:

- **orbit**: a press on the picture, then ``--seconds`` of pointer moves at 100 a second
  (a slow sine sweep), then the release. From the window's own ``-v`` log: the pictures shown
  during the drag (finished frames and the tracers' pictures on the way), frames a second,
  the median and the worst gap between two pictures (the first gap counted from the press),
  and the median render time of the finished frames;
- **rest**: the window left alone (the path tracer accumulating); screenshots of the picture
  at 3 s and 20 s, its samples per pixel then, and the noise over a flat patch (the median
  absolute Laplacian of the grey levels) at both.

Real models: the Stanford bunny (the full 69,451-triangle scan where ``../shared`` has it, else
the shipped 16,301-face one) and the bunny subdivided to about a million triangles (written to
the output folder). Machine load is printed before and after: on a shared 2-core machine the
neighbours show in every number. Writes ``DIR/window.json`` and ``DIR/window.md``.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
LINE = re.compile(r"^fvd\s+(\d+)ms (.*)$")
SHADING_KEYS = {"flat": "1", "gouraud": "2", "phong": "3"}


def _progress(text: str) -> None:
    print(f"[bench --window] {text}", file=sys.stderr, flush=True)


def bunny_file() -> Path:
    full = ROOT.parent / "shared" / "data" / "stanford-bunny" / "bun_zipper.ply"
    return full if full.is_file() else ROOT / "scenes" / "stanford-bunny" / "bun_zipper_res2.ply"


def million_bunny(out: Path) -> Path:
    """The bunny subdivided (each triangle into four) until it has about a million."""
    import trimesh
    path = out / "bunny-1M.ply"
    if path.is_file():
        return path
    mesh = trimesh.load(bunny_file(), process=False)
    while len(mesh.faces) < 900_000:
        mesh = mesh.subdivide()
    mesh.export(path)
    return path


class Display:
    """``$DISPLAY``, or a virtual X server started for the bench (stopped by :meth:`close`)."""

    def __init__(self):
        self.process = None
        self.name = os.environ.get("DISPLAY", "")
        if self.name:
            return
        if shutil.which("Xvfb") is None:
            raise RuntimeError("no display and no Xvfb: install xvfb (apt-get install xvfb)")
        self.name = ":93"
        self.process = subprocess.Popen(["Xvfb", self.name, "-screen", "0", "1920x1200x24"],
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(1.0)

    def close(self) -> None:
        if self.process is not None:
            self.process.terminate()
            self.process.wait()


class Window:
    """One ``python -m app -v view`` process, its log, its window id and geometry."""

    def __init__(self, display: Display, scene: Path, size: tuple[int, int], log: Path,
                 renderer: str | None = None):
        self.env = {**os.environ, "DISPLAY": display.name}
        command = [sys.executable, "-m", "app", "-v", "view", str(scene),
                   "--size", f"{size[0]}x{size[1]}"]
        if renderer:
            command += ["--renderer", renderer]
        self.log_path, self.size = log, size
        self._log = open(log, "w")
        self.launched = time.time()
        self.process = subprocess.Popen(command, cwd=ROOT, env=self.env, stdout=self._log,
                                        stderr=subprocess.STDOUT)
        self._wait_for("first frame shown", 180)
        self.offset_ms = self._offset()
        self.id = self._xdo("search", "--pid", str(self.process.pid)).split()[-1]
        geometry = dict(line.split("=") for line in
                        self._xdo("getwindowgeometry", "--shell", self.id).split())
        self.x, self.y = int(geometry["X"]), int(geometry["Y"])

    def _xdo(self, *args: str) -> str:
        return subprocess.run(["xdotool", *args], env=self.env, capture_output=True, text=True,
                              check=True).stdout

    def events(self) -> list[tuple[float, str]]:
        """(ms since the logger started, message) for every line of the log so far."""
        found = []
        for line in self.log_path.read_text(errors="replace").splitlines():
            match = LINE.match(line)
            if match:
                found.append((float(match.group(1)), match.group(2)))
        return found

    def _wait_for(self, text: str, seconds: float) -> None:
        deadline = time.time() + seconds
        while time.time() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"the window exited: {self.log_path.read_text()[-2000:]}")
            if any(text in message for _, message in self.events()):
                return
            time.sleep(0.1)
        raise RuntimeError(f"no {text!r} in {seconds} s (log: {self.log_path})")

    def _offset(self) -> float:
        """The logger's clock against the wall clock since launch (ms to subtract)."""
        for ms, message in self.events():
            match = re.match(r"window shown ([\d.]+) s after process start", message)
            if match:
                return 1e3 * float(match.group(1)) - ms
        return 0.0

    def now_ms(self) -> float:
        """The wall clock now on the log's clock."""
        return 1e3 * (time.time() - self.launched) - self.offset_ms

    def settle(self, seconds: float = 30.0) -> None:
        """Wait until the worker has said nothing new for a second (a trace finished)."""
        deadline, last = time.time() + seconds, None
        while time.time() < deadline:
            count = len(self.events())
            if count == last:
                return
            last = count
            time.sleep(1.0)

    def key(self, key: str) -> None:
        self._xdo("key", "--window", self.id, key)

    def drag(self, seconds: float) -> tuple[float, float]:
        """A press a third of the way across the picture, moves at 100 a second, a release:
        (press, release) on the log's clock."""
        cx, cy = self.x + self.size[0] // 3, self.y + self.size[1] // 2
        reach = min(200, self.size[0] // 4)         # stays on the picture
        self._xdo("mousemove", str(cx), str(cy))
        time.sleep(0.3)
        moves = []
        for i in range(1, int(seconds * 100)):
            moves += ["mousemove", str(cx + int(reach * np.sin(i / 60))),
                      str(cy + int(reach / 4 * np.sin(i / 60))), "sleep", "0.01"]
        press = self.now_ms()
        self._xdo("mousedown", "1", *moves, "mouseup", "1")
        return press, self.now_ms()

    def screenshot(self, path: Path) -> np.ndarray:
        """The picture's pixels (the window's top-left ``size``), grey levels."""
        from PIL import Image
        subprocess.run(["import", "-window", self.id, str(path)], env=self.env, check=True)
        grey = np.asarray(Image.open(path).convert("L"), np.float64)
        return grey[:self.size[1], :self.size[0]]

    def close(self) -> None:
        self.process.terminate()
        try:
            self.process.wait(10)
        except subprocess.TimeoutExpired:
            self.process.kill()
        self._log.close()


def pictures_between(events, start: float, end: float) -> dict:
    """The pictures the window showed in [start, end]: frames a second, gaps, render times,
    and from its "on screen" lines the window's own time per picture and the wait from an
    input to the picture that shows it."""
    shown, renders, own, cpu, waited = [], [], [], [], []
    for ms, message in events:
        if not start <= ms <= end + 50:
            continue
        if re.match(r"frame \d+:", message) or message.startswith("partial frame"):
            shown.append(ms)
            render = re.search(r"render=([\d.]+)ms", message)
            if render:
                renders.append(float(render.group(1)))
        elif message.startswith("on screen:"):
            own.append(float(re.search(r"own ([\d.]+) ms", message).group(1)))
            cpu.append(float(re.search(r"CPU ([\d.]+) ms", message).group(1)))
            after = re.search(r"([\d.]+) ms after the input", message)
            if after:
                waited.append(float(after.group(1)))
    gaps = np.diff([start] + shown) if shown else np.array([end - start])
    return {"pictures": len(shown), "seconds": (end - start) / 1e3,
            "fps": len(shown) / max((end - start) / 1e3, 1e-9),
            "gap_median_ms": float(np.median(gaps)), "gap_worst_ms": float(np.max(gaps)),
            "render_median_ms": _median(renders), "window_median_ms": _median(own),
            "window_cpu_median_ms": _median(cpu),
            "latency_median_ms": _median(waited),
            "latency_worst_ms": float(max(waited)) if waited else None}


def _median(values: list[float]) -> float | None:
    return float(statistics.median(values)) if values else None


def orbit_case(display, out, label, scene, size, seconds, shading=None, renderer=None) -> dict:
    _progress(f"{label} at {size[0]}x{size[1]}: orbiting {seconds:g} s ...")
    window = Window(display, scene, size, out / f"{_slug(label, size)}.log", renderer)
    try:
        if shading:
            window.key(SHADING_KEYS[shading])
        window.settle()
        press, release = window.drag(seconds)
        time.sleep(0.5)
        row = pictures_between(window.events(), press, release)
    finally:
        window.close()
    return {"case": label, "size": list(size), "kind": "orbit", **row}


def keys_case(display, out, label, scene, size, seconds, shading=None) -> dict:
    """The shading keys 1, 2, 3 in turn, eight a second for ``seconds``: each change's
    picture, and how long after its key it reached the screen."""
    _progress(f"{label} at {size[0]}x{size[1]}: shading keys for {seconds:g} s ...")
    window = Window(display, scene, size, out / f"{_slug(label, size)}.log")
    try:
        window.settle()
        start, began = window.now_ms(), time.time()
        for i in range(int(seconds * 8)):
            window.key("123"[i % 3])
            time.sleep(max(0.0, began + (i + 1) / 8 - time.time()))    # xdotool takes time
        end = window.now_ms()
        time.sleep(0.5)
        row = pictures_between(window.events(), start, end)
    finally:
        window.close()
    return {"case": label, "size": list(size), "kind": "keys", **row}


def laplacian_noise(grey: np.ndarray, box) -> float:
    """The median absolute Laplacian of the grey levels over ``box`` (x0, y0, x1, y1)."""
    x0, y0, x1, y1 = box
    a = grey[y0:y1, x0:x1]
    lap = 4 * a[1:-1, 1:-1] - a[:-2, 1:-1] - a[2:, 1:-1] - a[1:-1, :-2] - a[1:-1, 2:]
    return float(np.median(np.abs(lap)))


def rest_case(display, out, label, scene, size, renderer, box, times=(3.0, 20.0)) -> dict:
    _progress(f"{label} at rest for {times[-1]:g} s ...")
    window = Window(display, scene, size, out / f"{_slug(label, size)}.log", renderer)
    shown = time.time()
    row = {"case": label, "size": list(size), "kind": "rest", "at": []}
    try:
        for t in times:
            time.sleep(max(0.0, shown + t - time.time()))
            grey = window.screenshot(out / f"{_slug(label, size)}-{t:g}s.png")
            spp = [m for _, m in window.events() if "samples per pixel" in m]
            found = re.search(r"(\d+) of \d+ samples per pixel", spp[-1]) if spp else None
            row["at"].append({"seconds": t, "noise": laplacian_noise(grey, box),
                              "samples_per_pixel": int(found.group(1)) if found else None})
    finally:
        window.close()
    first, last = row["at"][0]["noise"], row["at"][-1]["noise"]
    row["noise_falls"] = first / last if last else None
    return row


def _slug(label: str, size) -> str:
    return re.sub(r"[^a-z0-9]+", "-", label.lower()).strip("-") + f"-{size[0]}x{size[1]}"


def cases(args, out: Path) -> list[tuple]:
    bunny = bunny_file()
    small, big = (500, 500), (1580, 1080)
    found = [(orbit_case, f"bunny {bunny.stem}, {s}", bunny, size, args.seconds, s)
             for size in (small, big) for s in ("flat", "gouraud", "phong")]
    found.append((orbit_case, "bunny subdivided to 1.1M, flat", None, small, args.seconds,
                  "flat"))
    found.append((keys_case, f"bunny {bunny.stem}, 8 shading keys a second", bunny, small,
                  args.seconds, None))
    found.append((orbit_case, "whitted.toml, ray traced", ROOT / "scenes" / "whitted.toml", big,
                  args.seconds, None, "raytrace"))
    return found


def main(args) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from app.distribution.warmup import is_warm
    if not is_warm():        # else every window compiles in worker processes beside the frames
        _progress("the kernel cache is cold: compiling it first (python -m app warmup) ...")
        subprocess.run([sys.executable, "-m", "app", "warmup"], cwd=ROOT, check=True)
    load_before = os.getloadavg()
    display = Display()
    rows = []
    try:
        for run, label, scene, size, seconds, shading, *renderer in cases(args, out):
            scene = scene or million_bunny(out)
            rows.append(run(display, out, label, scene, size, seconds, shading, *renderer))
            _print_row(rows[-1])
        rows.append(rest_case(display, out, "cornell_box.toml, path traced",
                              ROOT / "scenes" / "cornell_box.toml", (400, 400), "pathtrace",
                              box=(130, 95, 300, 160)))
        _print_row(rows[-1])
    finally:
        display.close()
    report = {"rows": rows, "load_before": load_before, "load_after": os.getloadavg(),
              "python": sys.version.split()[0]}
    (out / "window.json").write_text(json.dumps(report, indent=2))
    (out / "window.md").write_text(markdown(report))
    print(markdown(report))
    return 0


def _print_row(row: dict) -> None:
    _progress(json.dumps(row))


def _ms(value: float | None, digits: int = 0) -> str:
    return "–" if value is None else f"{value:.{digits}f} ms"


def markdown(report: dict) -> str:
    lines = ["| case | picture | pictures a second (dragging, or pressing keys) | median gap "
             "| worst gap "
             "| render median | input to screen, median (worst) | the window's own, median "
             "(its CPU) |", "|---|---|---|---|---|---|---|---|"]
    for r in report["rows"]:
        if r["kind"] not in ("orbit", "keys"):
            continue
        render = _ms(r["render_median_ms"], 1)
        waited = (f"{_ms(r.get('latency_median_ms'))} ({_ms(r.get('latency_worst_ms'))})"
                  if r.get("latency_median_ms") is not None else "–")
        lines.append(f"| {r['case']} | {r['size'][0]}x{r['size'][1]} | {r['fps']:.1f} "
                     f"| {r['gap_median_ms']:.0f} ms | {r['gap_worst_ms']:.0f} ms | {render} "
                     f"| {waited} | {_ms(r.get('window_median_ms'), 1)} "
                     f"({_ms(r.get('window_cpu_median_ms'), 1)}) |")
    for r in report["rows"]:
        if r["kind"] == "rest":
            at = ", ".join(f"{a['seconds']:g} s: {a['samples_per_pixel']} spp, noise "
                           f"{a['noise']:.1f}" for a in r["at"])
            lines.append(f"\n{r['case']} at rest, {r['size'][0]}x{r['size'][1]}: {at}; the "
                         f"noise falls {r['noise_falls']:.2f}x")
    lines.append(f"\nload average before {report['load_before'][0]:.2f}, after "
                 f"{report['load_after'][0]:.2f}")
    return "\n".join(lines) + "\n"
