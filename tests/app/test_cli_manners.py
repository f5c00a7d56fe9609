"""An installed program's manners: ``--version``, ``--help`` named as it was started, and a
quiet log on stderr by default (``-v`` for INFO, ``-q`` for errors only; ``$FVD_LOG`` always
gets every INFO line)."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests.conftest import ROOT
from tools import unavailable

VERSION = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["version"]
SCRIPT = Path(sys.executable).parent / ("fvd-viewer.exe" if os.name == "nt" else "fvd-viewer")


def run(*argv: str, env: dict | None = None, timeout: float = 120) -> subprocess.CompletedProcess:
    """``python -m app ARGV`` (or, if argv[0] is a path, that program) in a fresh process."""
    command = list(argv) if Path(argv[0]).is_absolute() else [sys.executable, "-m", "app", *argv]
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, **(env or {})})


def script() -> str:
    if not SCRIPT.exists():
        unavailable(f"{SCRIPT} not found: the project is not installed (pip install -e .)")
    return str(SCRIPT)


def check_version_lines(out: str) -> None:
    lines = out.splitlines()
    assert lines[0] == f"fvd-viewer {VERSION}", out
    assert lines[1].startswith(f"Python {sys.version_info.major}.{sys.version_info.minor}."), out
    for name in ("numpy", "numba", "moderngl", "imgui-bundle"):
        assert f", {name} " in lines[1], out
    assert len(lines) == 2, out


def test_version_from_python_dash_m():
    done = run("--version")
    assert done.returncode == 0, done.stderr
    check_version_lines(done.stdout)
    assert done.stderr == ""


def test_version_from_the_installed_script():
    done = run(script(), "--version")
    assert done.returncode == 0, done.stderr
    check_version_lines(done.stdout)


def test_version_after_a_command_and_without_heavy_imports():
    code = ("import sys; from app.cli import main; status = main(['render', '--version']); "
            "print([m for m in ('numpy', 'numba', 'core') if m in sys.modules], status)")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "[] 0", done.stdout


def test_version_falls_back_to_pyproject_when_not_installed(monkeypatch):
    from importlib import metadata

    from app import versions

    def not_installed(name):
        raise metadata.PackageNotFoundError(name)

    monkeypatch.setattr(versions.metadata, "version", not_installed)
    assert versions.own_version() == VERSION
    assert versions.version_text().splitlines()[0] == f"fvd-viewer {VERSION}"
    assert "numba not installed" in versions.version_text()


def test_help_names_the_program_as_it_was_started():
    assert run("--help").stdout.startswith("usage: python -m app ")
    assert run("render", "--help").stdout.startswith("usage: python -m app render ")
    done = run(script(), "--help")
    assert done.returncode == 0 and done.stdout.startswith("usage: fvd-viewer "), done.stdout
    assert "-v, --verbose" in done.stdout and "-q, --quiet" in done.stdout
    assert "--version" in done.stdout
    bad = run(script(), "render")                    # a usage error names it too
    assert bad.returncode == 2 and bad.stderr.startswith("usage: fvd-viewer render "), bad.stderr


def no_display(tmp_path: Path, *options: str, where: str = "after"):
    """The default scene's views to PNGs without a display, with ``options`` before or after
    the command: (stderr lines, $FVD_LOG's lines)."""
    log = tmp_path / "fvd.log"
    out = tmp_path / "views"
    argv = ["view", "--out", str(out)]
    argv = [*options, *argv] if where == "before" else [*argv, *options]
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    done = subprocess.run([sys.executable, "-m", "app", *argv], cwd=ROOT, capture_output=True,
                          text=True, timeout=300, env={**env, "FVD_LOG": str(log)})
    assert done.returncode == 0, done.stderr
    assert len(list(out.glob("*.png"))) == 14
    return done.stderr.splitlines(), log.read_text(encoding="utf-8").splitlines()


def logged(lines: list[str]) -> list[str]:
    return [line for line in lines if line.startswith("fvd ")]


def test_the_default_log_on_stderr_is_quiet_but_says_what_a_user_needs(tmp_path):
    err, log = no_display(tmp_path)
    assert logged(err) == [], err
    assert any(line.startswith("no display found") for line in err), err
    assert any(line.startswith("invalid view: ") for line in err), err
    assert any(" scene scenes/house.toml: 14 valid views" in line for line in log), log
    assert len(logged(log)) == len(log) >= 15          # every INFO line still in $FVD_LOG


@pytest.mark.parametrize("where", ["before", "after"])
def test_verbose_logs_the_info_lines_on_stderr(tmp_path, where):
    err, log = no_display(tmp_path, "-v", where=where)
    said = logged(err)
    assert any(" scene scenes/house.toml: 14 valid views" in line for line in said), err
    assert len(said) == len(log)


@pytest.mark.parametrize("where", ["before", "after"])
def test_quiet_logs_errors_only_and_the_log_file_keeps_everything(tmp_path, where):
    err, log = no_display(tmp_path, "--quiet", where=where)
    assert logged(err) == [], err
    assert len(log) >= 15


LOGGING = ("import logging, sys; from app.viewer.launch import setup_logging; "
           "setup_logging(getattr(logging, sys.argv[1])); log = logging.getLogger('fvd'); "
           "log.info('an info line'); log.warning('a warning line'); log.error('an error line')")


@pytest.mark.parametrize("level, shown", [("WARNING", ["a warning line", "an error line"]),
                                          ("ERROR", ["an error line"]),
                                          ("INFO", ["an info line", "a warning line",
                                                    "an error line"])])
def test_logged_errors_reach_stderr_at_every_level(tmp_path, level, shown):
    log = tmp_path / "fvd.log"
    done = subprocess.run([sys.executable, "-c", LOGGING, level], cwd=ROOT, capture_output=True,
                          text=True, timeout=60, env={**os.environ, "FVD_LOG": str(log)})
    assert done.returncode == 0, done.stderr
    assert [line.split("ms ", 1)[1] for line in done.stderr.splitlines()] == shown
    assert len(log.read_text(encoding="utf-8").splitlines()) == 3


def test_a_commands_errors_reach_stderr_even_when_quiet():
    done = run("-q", "render", "nowhere.toml", "--out", "nowhere.png")
    assert done.returncode == 2 and "nowhere.toml" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def test_verbose_and_quiet_together_is_a_usage_error():
    done = run("-v", "render", "scenes/torus.toml", "-q")
    assert done.returncode == 2
    assert "-v/--verbose and -q/--quiet cannot be used together" in done.stderr


def test_global_options_are_taken_out_wherever_they_stand_before_a_double_dash():
    from app.cli import global_options
    assert global_options(["-q", "render", "a.toml", "--size", "8x8"]) == \
        (["render", "a.toml", "--size", "8x8"], False, "quiet")
    assert global_options(["render", "--verbose", "a.toml"]) == (["render", "a.toml"], False,
                                                                  "verbose")
    assert global_options(["view", "--", "-v"]) == (["view", "--", "-v"], False, None)
    assert global_options(["--version"]) == ([], True, None)
