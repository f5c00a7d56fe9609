"""The command line: ``fvd-viewer COMMAND ...`` or ``python -m app COMMAND ...``, COMMAND one of
view, render, matrices, plan, bench, report, stability, animate, warmup, inspect, compare,
radiosity (``view`` when none is given), with the global options ``--version``, ``-v`` /
``--verbose`` and ``-q`` / ``--quiet`` before or after it.

Only dispatch lives here: the parsers are built by :mod:`app.cli_arguments`, and each
command's body is in its own module (the scene commands' in
:mod:`app.commands.scene_commands`), imported when that command runs, so that ``--help`` and
the window start fast (``--version`` imports neither numpy nor numba).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from app import startup_gc
from app.cli_arguments import command_parser
COMMANDS = ("view", "render", "matrices", "plan", "bench", "report", "stability", "animate",
            "warmup", "inspect", "compare", "radiosity", "torques", "colour")


def attach_values(argv: list[str], options=("--size",)) -> list[str]:
    """``--size -5x5`` → ``--size=-5x5``: argparse takes a value that starts with ``-`` for an
    option (and says "expected one argument"); joined, it reaches
    :func:`app.cli_arguments.parse_size`, which says what is wrong with it."""
    out = []
    i = 0
    while i < len(argv):
        if argv[i] in options and i + 1 < len(argv) and argv[i + 1].startswith("-") \
                and argv[i + 1] != "--":
            out.append(f"{argv[i]}={argv[i + 1]}")
            i += 2
        else:
            out.append(argv[i])
            i += 1
    return out


# -- global options: --version, -v / --verbose, -q / --quiet, before or after the command
VERBOSE = ("-v", "--verbose")
QUIET = ("-q", "--quiet")


def global_options(argv: list[str]) -> tuple[list[str], bool, str | None]:
    """``(argv without them, --version asked, "verbose" | "quiet" | None)``: the global options
    taken out wherever they stand before a ``--``, so that every command accepts them before
    or after its name (``fvd-viewer -q render ...``, ``fvd-viewer render ... -q``)."""
    rest, version, loudness = [], False, None
    for i, token in enumerate(argv):
        if token == "--":
            rest.extend(argv[i:])
            break
        if token == "--version":
            version = True
        elif token in VERBOSE + QUIET:
            said = "verbose" if token in VERBOSE else "quiet"
            if loudness not in (None, said):
                raise ValueError("-v/--verbose and -q/--quiet cannot be used together")
            loudness = said
        else:
            rest.append(token)
    return rest, version, loudness


def default_prog() -> str:
    """The program's name as it was started: ``fvd-viewer`` (the installed script, by its
    file's name) or ``python -m app``."""
    name = Path(sys.argv[0]).name if sys.argv and sys.argv[0] else ""
    if not name or name in ("__main__.py", "-c") or name.startswith("python"):
        return "python -m app"
    return name.removesuffix(".exe").removesuffix("-script.py")
# --


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    """Run the command line ``argv`` (default: this process's); 0 on success. ``prog`` names
    the program in --help and in usage errors (default: as it was started)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    prog = prog or default_prog()
    try:
        argv, version, loudness = global_options(argv)
    except ValueError as error:
        print(f"{prog}: error: {error}", file=sys.stderr)
        return 2
    if version:
        from app.versions import version_text
        print(version_text())
        return 0
    import logging
    from app.viewer.launch import setup_logging
    setup_logging({"verbose": logging.INFO, "quiet": logging.ERROR}.get(loudness,
                                                                        logging.WARNING))
    if not argv and views_on_stdin():
        argv = ["view", "-"]                  # `python -m app < grade.data`, as the course grades
    if not argv or (argv[0] not in COMMANDS and argv[0] not in ("-h", "--help")):
        argv = ["view", *argv]                # `python -m app [SCENE]` opens the viewer
    args = command_parser(argv[0], prog).parse_args(attach_values(argv))
    if argv[0] != "view":           # the viewer resumes at its first frame
        startup_gc.resume()
    from app.progress_line import INTERRUPTED, ProgressLine
    from core.work import watching
    args.progress = ProgressLine(quiet=loudness == "quiet")
    try:
        with watching(args.progress if args.command in WATCHED else None):
            return _dispatch(args)
    except KeyboardInterrupt:       # a command that keeps files says what it kept itself
        args.progress.say(args.progress.stopped())
        return INTERRUPTED
    except MemoryError:
        return _out_of_memory()


WATCHED = ("render", "animate")     # long work's progress line (app.progress_line)


def _out_of_memory() -> int:
    """The last line of defence: every reader bounds its input, but a scene within the limits
    may still need more memory than this machine has (a huge framebuffer of many samples)."""
    print("error: out of memory: the input or the image is too large for this machine's "
          "memory (see the input-size limits in the README)", file=sys.stderr)
    return 3


def views_on_stdin() -> bool:
    """Is standard input a file or a pipe (``prog < grade.data``, ``cat x | prog``) rather than
    a terminal or /dev/null? Then the views come from it, as the course's grader ran programs."""
    import stat
    try:
        if sys.stdin is None or sys.stdin.isatty():
            return False
        mode = os.fstat(sys.stdin.fileno()).st_mode
    except (OSError, ValueError, AttributeError):
        return False
    return stat.S_ISREG(mode) or stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)


def _dispatch(args) -> int:
    if args.command == "view":
        from app.viewer.launch import main as viewer_main
        loader = None
        if args.crease_angle is not None:        # every scene the window opens, File > Open too
            import functools
            from app.session.state import load_scene
            loader = functools.partial(load_scene, crease_angle=args.crease_angle)
        return viewer_main(args.scene, args.size, out_dir=args.out, reference=args.reference,
                           options={"rasterizer": args.rasterizer,
                                    "keep_aspect": args.keep_aspect,
                                    "course_tri": args.course_tri,
                                    "lighting_model": args.lighting_model,
                                    "renderer_name": args.renderer, "samples": args.samples,
                                    "loader": loader})
    if args.command == "render":
        from app.commands.scene_commands import render_command
        return render_command(args)
    if args.command == "matrices":
        from app.commands.scene_commands import matrices_command
        return matrices_command(args)
    if args.command == "plan":
        from app.commands.scene_commands import plan_command
        return plan_command(args)
    if args.command == "bench":
        from app.bench.bench import main as bench_main
        return bench_main(args)
    if args.command == "report":
        from app.reports.report import main as report_main
        return report_main(args)
    if args.command == "animate":
        from app.commands.animate import main as animate_main
        return animate_main(args)
    if args.command == "warmup":
        from app.distribution.warmup import main as warmup_main
        return warmup_main(args)
    if args.command in ("inspect", "compare"):      # the pixel inspector
        from app.commands.scene_commands import inspector_command
        return inspector_command(args)
    if args.command == "radiosity":           # solve once, save for --solution
        from app.commands.radiosity import main as radiosity_main
        return radiosity_main(args)
    if args.command in ("torques", "colour"):    # app/commands/torques.py, colour.py
        import importlib
        return importlib.import_module(f"app.commands.{args.command}").main(args)
    if args.command == "stability":
        from app.commands.stability import main as stability_main
        return stability_main(args)
    raise AssertionError(args.command)
