"""The command line: ``python -m app [view|render|matrices|plan|bench|report|stability] ...``.

Only parsing and dispatch live here; each command's body is in its own module and is imported
when that command runs, so that ``python -m app --help`` and the window start fast.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


from core.settings import PROJECTIONS as PROJECTION_CHOICES, SHADINGS as SHADING_CHOICES
COMMANDS = ("view", "render", "matrices", "plan", "bench", "report", "stability", "warmup")
RASTERIZER_CHOICES = ("edge", "scanline")


def parse_size(text: str) -> tuple[int, int]:
    """``WxH`` → ``(W, H)`` for argparse, with a message that says what was wrong."""
    try:
        w, h = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"size must look like 500x500, not {text!r}") from None
    from core.scene.model import MAX_IMAGE_SIDE
    if not (1 <= w <= MAX_IMAGE_SIDE and 1 <= h <= MAX_IMAGE_SIDE):
        raise argparse.ArgumentTypeError(f"size {w}x{h} is out of range (1 to {MAX_IMAGE_SIDE} "
                                         "a side)")
    return w, h


def _parser(command: str | None = None) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m app",
        description="A CPU reference renderer: the Foley-van Dam viewing pipeline, scan-line "
                    "z-buffer and shading, shown through OpenGL. With no command, opens the "
                    "viewer on the default scene (the FvDFH house).")
    sub = p.add_subparsers(dest="command")
    scene_help = ("a scene file (.toml), a .tri file, a mesh (.obj/.ply/.off/.stl), a bare view "
                  "file (shown with the house), or - for a view file on standard input")

    v = sub.add_parser("view", help="open the viewer window (renders PNGs when there is no display)")
    v.add_argument("scene", nargs="?", help=scene_help + "; default: the house")
    v.add_argument("--size", type=parse_size, default=None,
                   help="framebuffer size WxH (default: the scene's, 500x500)")
    v.add_argument("--out", default=None,
                   help="where screenshots go, and the PNGs when there is no display "
                        "(default: ./screenshots, and ./fvd-views or $FVD_OUT without a display)")
    _course_options(v)

    r = sub.add_parser("render", help="render one view to a PNG with the CPU core")
    r.add_argument("scene", help=scene_help)
    r.add_argument("--view", type=int, default=1,
                   help="which view: its position in the file, counting from 1 (an invalid "
                        "one prints its message and exits 1)")
    r.add_argument("--projection", choices=PROJECTION_CHOICES, default=None)
    r.add_argument("--shading", choices=SHADING_CHOICES, default=None)
    r.add_argument("--size", type=parse_size, default=None, help="WxH (default: the scene's, 500x500)")
    r.add_argument("--out", required=True, help="the PNG file to write")
    _course_options(r)

    m = sub.add_parser("matrices", help="print every factor of N_per / N_par as JSON")
    m.add_argument("scene", help=scene_help)
    m.add_argument("--view", type=int, default=1,
                   help="which view: its position in the file, counting from 1")
    m.add_argument("--projection", choices=PROJECTION_CHOICES, default="perspective")
    m.add_argument("--size", type=parse_size, default=(500, 500), help="viewport for M_vv3dv")
    m.add_argument("--keep-aspect", action="store_true", default=None,
                   help="letterbox the window in the viewport instead of stretching it")

    pl = sub.add_parser("plan", help="print, as JSON, the stages that will run and those left out")
    pl.add_argument("scene", help=scene_help)
    pl.add_argument("--projection", choices=PROJECTION_CHOICES, default=None)
    pl.add_argument("--shading", choices=SHADING_CHOICES, default=None)
    pl.add_argument("--rasterizer", choices=RASTERIZER_CHOICES, default=None)
    pl.add_argument("--keep-aspect", action="store_true", default=None)

    b = sub.add_parser("bench", help="time the CPU pipeline against llvmpipe (OpenGL in software)")
    if command == "bench":                    # its options live with its body (app/tools/bench.py)
        from app.tools.bench import add_arguments
        add_arguments(b, parse_size)

    rep = sub.add_parser("report", help="error against run time: sweep, CSV, Markdown and plot")
    rep.add_argument("--out", default="report", help="output directory")
    rep.add_argument("--quick", action="store_true", help="a reduced sweep (for tests)")

    st = sub.add_parser("stability", help="the stiff and extreme cases, PASS/FAIL")
    st.add_argument("--json", action="store_true", help="print JSON instead of a table")

    sub.add_parser("warmup", help="compile every kernel once (make does it), with progress")
    return p


def _course_options(p: argparse.ArgumentParser) -> None:
    """The course's options shared by ``view`` and ``render`` (None: the scene's own)."""
    p.add_argument("--rasterizer", choices=RASTERIZER_CHOICES, default=None,
                   help="edge: edge functions, perspective-correct (default); scanline: the "
                        "course's edge table / active edge table, screen-linear shading")
    p.add_argument("--keep-aspect", action="store_true", default=None,
                   help="letterbox the view window instead of stretching it over the viewport "
                        "(the course's mapping stretches)")
    p.add_argument("--course-tri", action="store_true",
                   help="the .tri startup code's rules: skip triangles with viewpoint . N < 0, "
                        "and mouse buttons left Phong, middle Gouraud, right flat")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv and views_on_stdin():
        argv = ["view", "-"]                  # `python -m app < grade.data`, as the course grades
    if not argv or (argv[0] not in COMMANDS and argv[0] not in ("-h", "--help")):
        argv = ["view", *argv]                # `python -m app [SCENE]` opens the viewer
    args = _parser(argv[0]).parse_args(argv)
    try:
        return _dispatch(args)
    except KeyboardInterrupt:
        return 130


def views_on_stdin() -> bool:
    """Is standard input a file or a pipe (``prog < grade.data``, ``cat x | prog``) rather than
    a terminal or /dev/null? Then the views come from it, as the course's grader ran programs."""
    import os
    import stat
    try:
        if sys.stdin is None or sys.stdin.isatty():
            return False
        mode = os.fstat(sys.stdin.fileno()).st_mode
    except (OSError, ValueError, AttributeError):
        return False
    return stat.S_ISREG(mode) or stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)


def _load(source: str, size=None):
    """The scene, or None after printing the reader's message."""
    from core.scene.formats import ReaderError, load_scene
    try:
        scene = load_scene(source, size=size)
    except ReaderError as error:
        print(f"error: {error}", file=sys.stderr)
        return None
    for message in scene.view_messages:
        print(f"invalid view: {message}", file=sys.stderr)
    return scene


def _pick_view(scene, k: int):
    """``scene.views`` index of the file's view ``k``, or None after printing why not."""
    from core.scene.view_numbers import ViewNumberError, index_of
    try:
        return index_of(scene, k)
    except ViewNumberError as error:
        print(f"error: {error}", file=sys.stderr)
        return None


def _dispatch(args) -> int:
    if args.command == "view":
        from app.viewer.launch import main as viewer_main
        return viewer_main(args.scene, args.size, out_dir=args.out,
                           options={"rasterizer": args.rasterizer,
                                    "keep_aspect": args.keep_aspect,
                                    "course_tri": args.course_tri})
    if args.command == "render":
        return _render(args)
    if args.command == "matrices":
        return _matrices(args)
    if args.command == "plan":
        return _plan(args)
    if args.command == "bench":
        from app.tools.bench import main as bench_main
        return bench_main(args)
    if args.command == "report":
        from app.tools.report import main as report_main
        return report_main(args)
    if args.command == "warmup":
        from app.tools.warmup import main as warmup_main
        return warmup_main(args)
    if args.command == "stability":
        from app.tools.stability import main as stability_main
        return stability_main(args)
    raise AssertionError(args.command)


def _render(args) -> int:
    from PIL import Image

    from app.viewer.state import announce_compiles, render
    scene = _load(args.scene, size=args.size)
    if scene is None:
        return 2
    index = _pick_view(scene, args.view)
    if index is None:
        return 2
    from core.settings import RenderSettings
    view = scene.views[index]
    settings = RenderSettings.for_scene(scene, projection=args.projection, shading=args.shading,
                                        size=args.size, rasterizer=args.rasterizer,
                                        keep_aspect=args.keep_aspect)
    if args.course_tri:
        from core.scene.course_tri import course_tri_scene
        scene = course_tri_scene(scene, view)
    with announce_compiles():            # the first run compiles the kernels: say so
        frame = render(scene, view, settings)
    if frame.message:
        print(f"error: {frame.message}", file=sys.stderr)
        return 1
    out = Path(args.out)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(frame.color).save(out)
    except OSError as error:
        print(f"error: cannot write {out}: {error}", file=sys.stderr)
        return 2
    from core.scene.view_numbers import label
    print(f"wrote {out} ({frame.color.shape[1]}x{frame.color.shape[0]}, {label(scene, index)}, "
          f"{settings.projection}, {settings.shading}, {settings.rasterizer} rasterizer, "
          f"aspect {'kept' if settings.keep_aspect else 'stretched'})")
    return 0


def _matrices(args) -> int:
    from core.pipeline import project
    from core.camera.view import ViewError, n_par_factors, n_per_factors
    scene = _load(args.scene)
    if scene is None:
        return 2
    index = _pick_view(scene, args.view)
    if index is None:
        return 2
    view = scene.views[index]
    try:
        factors = (n_per_factors if args.projection == "perspective" else n_par_factors)(view)
    except ViewError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    out = {"view": view.label, "projection": args.projection}
    for name, m in factors.items():
        out[name] = float(m) if m.ndim == 0 else m.tolist()
    keep = scene.keep_aspect if args.keep_aspect is None else args.keep_aspect
    vp = project.viewport(view.window, *args.size, keep_aspect=keep)
    out["viewport"] = list(vp)
    out["M_vv3dv"] = project.m_vv3dv(*vp).tolist()
    if args.projection == "perspective":
        out["M_per"] = project.m_per(-1.0).tolist()
        out["M"] = project.perspective_to_parallel(float(factors["z_min"])).tolist()
    print(json.dumps(out, indent=2, ensure_ascii=False))
    return 0


def _plan(args) -> int:
    from core.plan import plan, plan_as_dict
    scene = _load(args.scene)
    if scene is None:
        return 2
    projection = args.projection or scene.projection
    shading = args.shading or scene.shading
    keep = scene.keep_aspect if args.keep_aspect is None else args.keep_aspect
    rasterizer = args.rasterizer or scene.rasterizer
    out = {"scene": scene.name, "projection": projection, "shading": shading,
           "rasterizer": rasterizer, "keep_aspect": keep,
           **plan_as_dict(plan(scene, projection, shading, keep, rasterizer))}
    print(json.dumps(out, indent=2, ensure_ascii=False))
    return 0
