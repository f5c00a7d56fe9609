"""``python -m app warmup`` on worker processes: the order and spread of its steps,
the stamp that says the cache is warm, what an interrupted or failing warm-up leaves, the
JSON progress lines, :class:`app.distribution.background_warmup.BackgroundWarmup`, and numba's cache when two
processes save one kernel at once.

The runs here take only the tests' own cheap steps (``tests/warmup_steps.py``, chosen with
the hidden ``--only``) and write their stamp where the test says (``--stamp``): the tree's
real stamp and kernels are not touched.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from app.distribution import (background_warmup, warm_stamp, warmup, warmup_pool,
                              warmup_steps)
from tests.conftest import ROOT

EXTRA = ["--extra-steps", "tests.warmup_steps:steps"]


def _command(stamp: Path, *only: str, jobs: int = 2, as_json: bool = True) -> list[str]:
    command = [sys.executable, "-m", "app.distribution.warmup", *EXTRA, "--stamp", str(stamp),
               "--jobs", str(jobs)]
    for text in only:
        command += ["--only", text]
    return command + (["--progress-json"] if as_json else [])


def _env(folder: Path) -> dict:
    return {**os.environ, "FVD_WARMUP_TEST_DIR": str(folder)}


def _run(folder: Path, stamp: Path, *only: str, jobs: int = 2, as_json: bool = True):
    return subprocess.run(_command(stamp, *only, jobs=jobs, as_json=as_json), cwd=ROOT,
                          env=_env(folder), capture_output=True, text=True, timeout=600)


def _events(stdout: str) -> list[dict]:
    return [json.loads(line) for line in stdout.splitlines() if line.strip()]


def _zombie(pid: int) -> bool:
    try:
        stat = open(f"/proc/{pid}/stat").read()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] == "Z"


def _gone(pid: int, within: float = 60.0) -> bool:
    end = time.monotonic() + within
    while time.monotonic() < end:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        if _zombie(pid):              # dead; a container's init may never reap it
            return True
        time.sleep(0.1)
    return False


# ---------------------------------------------------------------------------------------
# the scheduler

def test_the_longest_steps_go_first_and_the_first_scenes_before_them():
    costs = {"a": 1.0, "b": 30.0, "c": 5.0}
    assert warmup_pool.order(["a", "b", "c", "new"], costs, 2.0) == ["b", "c", "new", "a"]
    first = warmup_pool.order(["a", "b", "c", "new"], costs, 2.0, first=lambda l: l in "ac")
    assert first == ["c", "a", "b", "new"]
    assert warmup_pool.order(["x", "y", "z"], {}, 1.0) == ["x", "y", "z"]   # stable


def test_every_step_is_in_the_cost_table_and_first_puts_a_scene_first():
    labels = [label for label, _ in warmup_steps.all_steps()]
    assert len(labels) == len(set(labels))
    assert set(labels) <= set(warmup.COSTS), "measure the new steps into COSTS"
    scenes = warmup_steps.step_scenes()
    assert all(label in labels for label in scenes)
    bunny = warmup_steps.scene_label("glass_bunny.toml")
    ordered = warmup_pool.order(labels, warmup.COSTS, warmup.DEFAULT_COST,
                                first=lambda l: "glass_bunny.toml" in scenes.get(l, ()))
    assert ordered[0] == bunny
    assert ordered[1] == max(warmup.COSTS, key=warmup.COSTS.get)


def test_the_queue_hands_out_the_costliest_step_first(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(warmup, "COSTS", {"test: fails": 9.0, "test: quick kernel": 1.0})
    status = warmup.main([*EXTRA, "--only", "test: quick", "--only", "test: fails", "--jobs",
                          "1", "--progress-json", "--stamp", str(tmp_path / "warm.json")])
    events = _events(capsys.readouterr().out)
    assert [e["label"] for e in events if e["event"] == "begin"] == \
        ["test: fails", "test: quick kernel"]
    assert [e["event"] for e in events if e["event"] in ("done", "failed")] == \
        ["failed", "done"]
    assert [e["k"] for e in events if e["event"] in ("done", "failed")] == [1, 2]
    assert status == 1


def test_two_workers_run_two_steps_at_once(tmp_path):
    """Each of the two steps finishes only once the other has started."""
    done = _run(tmp_path, tmp_path / "warm.json", "test: meets", jobs=2)
    assert done.returncode == 0, done.stderr[-2000:]
    events = _events(done.stdout)
    assert sorted(e["label"] for e in events if e["event"] == "done") == \
        ["test: meets A", "test: meets B"]
    pids = {path.suffix for path in tmp_path.glob("[AB].*")}
    assert len(pids) == 2                              # two processes, one step each


# ---------------------------------------------------------------------------------------
# the stamp

def test_is_warm_only_for_a_stamp_of_this_code_numba_and_python(tmp_path):
    stamp = tmp_path / "warm.json"
    assert not warm_stamp.is_warm(stamp)               # missing
    warm_stamp.write(1.0, 3, stamp)
    assert warm_stamp.is_warm(stamp)
    written = json.loads(stamp.read_text())
    assert {"digest", "numba", "python", "written"} <= set(written)
    for key, other in (("digest", "0" * 64), ("numba", "0.1.0"), ("python", "2.7.18")):
        stamp.write_text(json.dumps({**written, key: other}))
        assert not warm_stamp.is_warm(stamp), key
    for corrupt in ("", "{", "[1, 2]", "\xff\xfe", '{"digest": null}'):
        stamp.write_text(corrupt, encoding="latin-1")
        assert not warm_stamp.is_warm(stamp), corrupt
    assert list(tmp_path.iterdir()) == [stamp]         # no temporary file left


def test_a_complete_run_writes_the_stamp_and_the_json_lines_parse(tmp_path):
    stamp = tmp_path / "warm.json"
    done = _run(tmp_path, stamp, "test: quick")
    assert done.returncode == 0, done.stderr[-2000:]
    events = _events(done.stdout)
    assert events[0] == {"event": "start", "total": 1, "jobs": 1}
    assert events[-1]["event"] == "finished" and events[-1]["ok"] is True
    assert isinstance(events[-1]["seconds"], float)
    (finished,) = [e for e in events if e["event"] == "done"]
    assert finished["k"] == 1 and finished["total"] == 1
    assert finished["label"] == "test: quick kernel" and finished["scenes"] == []
    assert warm_stamp.is_warm(stamp)


def test_the_table_says_each_step_and_the_total(tmp_path):
    done = _run(tmp_path, tmp_path / "warm.json", "test: quick", as_json=False)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "[ 1/1] test: quick kernel: " in done.stdout
    assert "warm: " in done.stdout.splitlines()[-1]


def test_a_failing_step_is_named_the_others_run_and_there_is_no_stamp(tmp_path):
    stamp = tmp_path / "warm.json"
    warm_stamp.write(1.0, 1, stamp)                    # warm before: not after a failure
    done = _run(tmp_path, stamp, "test: quick", "test: fails", as_json=False)
    assert done.returncode == 1
    lines = [line for line in done.stderr.splitlines() if "FAILED" in line]
    assert len(lines) == 1 and "test: fails" in lines[0] and "ZeroDivisionError" in lines[0]
    assert "[ 1/2] test: quick kernel" in done.stdout or "[ 2/2] test: quick kernel" in \
        done.stdout
    assert not stamp.exists()
    events = _events(_run(tmp_path, stamp, "test: fails").stdout)
    (failed,) = [e for e in events if e["event"] == "failed"]
    assert failed["label"] == "test: fails" and "ZeroDivisionError" in failed["error"]
    assert events[-1] == {**events[-1], "event": "finished", "ok": False,
                          "failed": ["test: fails"]}


@pytest.mark.parametrize("how", [signal.SIGINT, signal.SIGKILL, signal.SIGTERM])
def test_an_interrupted_warm_up_leaves_no_stamp_and_a_rerun_finishes(tmp_path, how):
    stamp = tmp_path / "warm.json"
    # SIGINT as a terminal gives it: a suite started in the background by a non-interactive
    # shell (`.ci/run &`) passes SIGINT on ignored, Python keeps it so, and the warm-up
    # would sleep on through the test's Ctrl+C
    process = subprocess.Popen(_command(stamp, "test: quick", "test: waits"), cwd=ROOT,
                               env=_env(tmp_path), stdout=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    for line in process.stdout:                        # the quick one done, the other asleep
        event = json.loads(line)
        if event["event"] == "done":
            break
    while not list(tmp_path.glob("sleeping.*")):
        time.sleep(0.05)
    (sleeping,) = tmp_path.glob("sleeping.*")
    worker = int(sleeping.read_text())
    process.send_signal(how)
    rest = process.communicate(timeout=120)[0]
    assert process.returncode != 0
    if how != signal.SIGKILL:                          # it says so on its way out
        assert _events(rest)[-1]["ok"] is False
    assert _gone(worker), "a worker outlived the warm-up"
    assert not stamp.exists()
    assert [p.name for p in tmp_path.iterdir() if "warm" in p.name] == []
    again = _run(tmp_path, stamp, "test: quick")
    assert again.returncode == 0, again.stderr[-2000:]
    assert warm_stamp.is_warm(stamp)


# ---------------------------------------------------------------------------------------
# the window's handle

def test_background_warmup_reports_a_tiny_run(tmp_path, monkeypatch):
    monkeypatch.setenv("FVD_WARMUP_TEST_DIR", str(tmp_path))
    woken = []
    stamp = tmp_path / "warm.json"
    run = background_warmup.BackgroundWarmup(jobs=1, on_event=lambda: woken.append(1),
                                  log_path=tmp_path / "warmup.log",
                                  extra_args=[*EXTRA, "--stamp", stamp, "--only", "test: quick"])
    scene = ROOT / "scenes" / "sphere.toml"
    assert run.wait_for(scene, timeout=600)            # no step of its own: the whole run
    assert run.wait(timeout=60)
    assert (run.total, run.done, run.current, run.finished, run.ok, run.failed) == \
        (1, 1, (), True, True, [])
    assert run.ready_for(scene) and run.ready_for(tmp_path / "elsewhere.toml")
    assert len(woken) >= 3                             # start, begin, done, finished
    run.stop()
    assert run.returncode == 0
    assert warm_stamp.is_warm(stamp)


def test_background_warmup_stops_its_workers(tmp_path, monkeypatch):
    monkeypatch.setenv("FVD_WARMUP_TEST_DIR", str(tmp_path))
    run = background_warmup.BackgroundWarmup(jobs=1, log_path=tmp_path / "warmup.log", extra_args=[
        *EXTRA, "--stamp", tmp_path / "warm.json", "--only", "test: waits"])
    while not list(tmp_path.glob("sleeping.*")):
        assert not run.finished, run.failed
        time.sleep(0.05)
    worker = int(next(tmp_path.glob("sleeping.*")).read_text())
    assert run.current == ("test: waits for a kill",) or not run.current   # (a race: begin)
    run.stop()
    assert run.finished and run.ok is False
    assert run.returncode is not None
    assert _gone(worker)


@pytest.mark.skipif(not hasattr(os, "getpriority"), reason="no process priorities here")
def test_the_windows_warm_up_and_its_workers_run_below_the_window(tmp_path, monkeypatch):
    """The window's warm-up renders every shipped scene after compiling; it and its workers
    run at nice 19, so that a drag in the window gets the cores first."""
    monkeypatch.setenv("FVD_WARMUP_TEST_DIR", str(tmp_path))
    run = background_warmup.BackgroundWarmup(jobs=1, log_path=tmp_path / "warmup.log", extra_args=[
        *EXTRA, "--stamp", tmp_path / "warm.json", "--only", "test: waits"])
    try:
        while not list(tmp_path.glob("sleeping.*")):
            assert not run.finished, run.failed
            time.sleep(0.05)
        worker = int(next(tmp_path.glob("sleeping.*")).read_text())
        assert os.getpriority(os.PRIO_PROCESS, 0) < background_warmup.WINDOW_NICE
        assert os.getpriority(os.PRIO_PROCESS, run._process.pid) == background_warmup.WINDOW_NICE
        assert os.getpriority(os.PRIO_PROCESS, worker) == background_warmup.WINDOW_NICE
    finally:
        run.stop()


def test_the_warm_up_ends_when_the_window_that_started_it_is_killed(tmp_path):
    """The window holds the warm-up's standard input: a window killed with SIGKILL (no
    clean-up of its own) closes it, and the warm-up stops its workers and exits, no stamp."""
    stamp = tmp_path / "warm.json"
    starter = textwrap.dedent(f"""
        import sys, time
        from app.distribution import background_warmup
        run = background_warmup.BackgroundWarmup(jobs=1, log_path={str(tmp_path / "warmup.log")!r},
            extra_args={[*EXTRA, "--stamp", str(stamp), "--only", "test: waits"]!r})
        print(run._process.pid, flush=True)
        time.sleep(600)
    """)
    window = subprocess.Popen([sys.executable, "-c", starter], cwd=ROOT, env=_env(tmp_path),
                              stdout=subprocess.PIPE, text=True)
    try:
        child = int(window.stdout.readline())
        while not list(tmp_path.glob("sleeping.*")):      # its worker is in the step
            assert window.poll() is None
            time.sleep(0.05)
        worker = int(next(tmp_path.glob("sleeping.*")).read_text())
        window.kill()                                     # no chance to stop it itself
        window.wait(timeout=10)
        assert _gone(child), "the warm-up outlived the window"
        assert _gone(worker), "its worker outlived the window"
        assert not stamp.exists()
    finally:
        if window.poll() is None:
            window.kill()


def test_ready_for_a_shipped_scene_when_its_step_is_done():
    """The bookkeeping alone: the events a run would print, fed to the reader."""
    run = background_warmup.BackgroundWarmup.__new__(background_warmup.BackgroundWarmup)
    import threading
    run._lock = threading.Condition()
    run._total, run._done, run._current, run._scenes_done = None, [], [], set()
    run._opened = set()
    run._failed, run._finished, run._ok, run._on_event = [], False, None, None
    run._scenes_dir = (ROOT / "scenes").resolve()
    bunny = ROOT / "scenes" / "glass_bunny.toml"
    run._take({"event": "start", "total": 2})
    run._take({"event": "begin", "label": warmup_steps.scene_label(bunny), "scenes": [bunny.name]})
    assert run.current == (warmup_steps.scene_label(bunny),) and not run.ready_for(bunny)
    run._take({"event": "done", "k": 1, "total": 2, "label": warmup_steps.scene_label(bunny),
               "seconds": 1.0, "scenes": [bunny.name]})
    assert run.ready_for(bunny) and not run.ready_for(ROOT / "scenes" / "sphere.toml")
    assert run.ready_for(bunny, every_setting=True)
    assert not run.ready_for(Path("/elsewhere") / bunny.name)   # a file of the same name
    assert run.wait_for(bunny, timeout=0)
    mine = Path("/elsewhere/mine.obj")
    run._take({"event": "done", "k": 2, "total": 3, "label": warmup_steps.opening_label(mine),
               "seconds": 1.0, "scenes": [], "opens": str(mine)})
    assert run.ready_for(mine) and not run.ready_for(mine, every_setting=True)
    run._take({"event": "failed", "k": 3, "total": 3, "label": "x", "error": "E: e",
               "seconds": 0.1, "scenes": []})
    run._take({"event": "finished", "seconds": 2.0, "ok": False, "failed": ["x"]})
    assert (run.done, run.finished, run.ok, run.failed) == (2, True, False, ["x: E: e"])
    assert run.ready_for(ROOT / "scenes" / "sphere.toml")


def test_first_puts_the_files_first_picture_ahead_of_every_step(tmp_path):
    """``--first FILE`` (the window's cold start) adds one step, run first: FILE's first
    picture with its own settings; its ``done`` event names the file it opens."""
    scene = tmp_path / "mine.obj"                      # a file of the user's, not shipped
    scene.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    command = _command(tmp_path / "warm.json", "test: quick", jobs=1) + ["--first", str(scene)]
    done = subprocess.run(command, cwd=ROOT, env=_env(tmp_path), capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    events = _events(done.stdout)
    assert events[0] == {"event": "start", "total": 2, "jobs": 1}
    begun = [e["label"] for e in events if e["event"] == "begin"]
    assert begun == ["mine.obj as it opens", "test: quick kernel"]
    opened = [e for e in events if e["event"] == "done" and "opens" in e]
    assert [e["opens"] for e in opened] == [str(scene.resolve())]


def test_first_with_a_missing_file_adds_no_step(tmp_path):
    command = _command(tmp_path / "warm.json", "test: quick", jobs=1) + [
        "--first", str(tmp_path / "gone.toml")]
    done = subprocess.run(command, cwd=ROOT, env=_env(tmp_path), capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert [e["label"] for e in _events(done.stdout) if e["event"] == "begin"] == ["test: quick kernel"]


# ---------------------------------------------------------------------------------------
# numba's cache when processes save one kernel at once

_COMPILE_ONE = r"""
import sys, numpy as np
import core.jit  # noqa: F401  (the serialised saves)
from tests.warmup_steps import scaled_sum
kinds = [np.float64, np.float32, np.int64, np.int32, np.int16, np.uint8, np.uint32, np.int8]
scaled_sum(np.arange(5).astype(kinds[int(sys.argv[1])]), 1.5)
"""

_LOAD_ALL = r"""
import json, numpy as np
import core.jit  # noqa: F401
from numba.core import event
compiled = []
class Listener(event.Listener):
    def on_start(self, ev): compiled.append(1)
    def on_end(self, ev): pass
event.register("numba:compile", Listener())
from tests.warmup_steps import scaled_sum
kinds = [np.float64, np.float32, np.int64, np.int32, np.int16, np.uint8, np.uint32, np.int8]
sums = [float(scaled_sum(np.arange(5).astype(kind), 1.5)) for kind in kinds]
print(json.dumps({"compiled": len(compiled), "sums": sums}))
"""


def test_processes_saving_one_kernel_at_once_keep_every_signature(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    # eight processes at once, each compiling and saving one signature of the same kernel
    racers = [subprocess.Popen([sys.executable, "-c", _COMPILE_ONE, str(k)], cwd=ROOT,
                               env=env, stderr=subprocess.PIPE, text=True) for k in range(8)]
    for racer in racers:
        assert racer.wait(timeout=600) == 0, racer.stderr.read()[-2000:]
    done = subprocess.run([sys.executable, "-c", _LOAD_ALL], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout)
    assert result["compiled"] == 0                     # all eight loaded, none lost
    assert result["sums"] == [15.0] * 8                # and each is its own machine code
    leftovers = [p.name for p in (tmp_path / "cache").rglob("*") if ".tmp." in p.name]
    assert leftovers == []


def test_the_zbuffers_own_step_goes_first_beside_the_costliest():
    """The first flat frame compiles the z-buffer's kernels, which the volume renderer's, the
    painters' and the inspectors' steps draw through too: it is handed out first, so that a
    second worker never compiles them beside it; the costliest step goes to the other
    worker."""
    class Options:
        extra_steps, only, first = (), None, None
    todo, _, _ = warmup._steps_to_run(Options())
    assert todo[0] == warmup_steps.foundation_label() == "flat, perspective, edge rasterizer"
    rest = [label for label in todo[1:] if label not in warmup_steps.step_scenes()]
    assert rest[0] == max(rest, key=lambda label: warmup.COSTS.get(label, 0.0))
