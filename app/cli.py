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
COMMANDS = ("view", "render", "matrices", "plan", "bench", "report", "stability")


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
                        "(default: ., and ./fvd-views or $FVD_OUT without a display)")

    r = sub.add_parser("render", help="render one view to a PNG with the CPU core")
    r.add_argument("scene", help=scene_help)
    r.add_argument("--view", type=int, default=1, help="which valid view, counting from 1")
    r.add_argument("--projection", choices=PROJECTION_CHOICES, default=None)
    r.add_argument("--shading", choices=SHADING_CHOICES, default=None)
    r.add_argument("--size", type=parse_size, default=None, help="WxH (default: the scene's, 500x500)")
    r.add_argument("--out", required=True, help="the PNG file to write")

    m = sub.add_parser("matrices", help="print every factor of N_per / N_par as JSON")
    m.add_argument("scene", help=scene_help)
    m.add_argument("--view", type=int, default=1, help="which valid view, counting from 1")
    m.add_argument("--projection", choices=PROJECTION_CHOICES, default="perspective")
    m.add_argument("--size", type=parse_size, default=(500, 500), help="viewport for M_vv3dv")

    pl = sub.add_parser("plan", help="print, as JSON, the stages that will run and those left out")
    pl.add_argument("scene", help=scene_help)
    pl.add_argument("--projection", choices=PROJECTION_CHOICES, default=None)
    pl.add_argument("--shading", choices=SHADING_CHOICES, default=None)

    b = sub.add_parser("bench", help="time the CPU pipeline against llvmpipe (OpenGL in software)")
    if command == "bench":                    # its options live with its body (app/tools/bench.py)
        from app.tools.bench import add_arguments
        add_arguments(b)

    rep = sub.add_parser("report", help="error against run time: sweep, CSV, Markdown and plot")
    rep.add_argument("--out", default="report", help="output directory")
    rep.add_argument("--quick", action="store_true", help="a reduced sweep (for tests)")

    st = sub.add_parser("stability", help="the stiff and extreme cases, PASS/FAIL")
    st.add_argument("--json", action="store_true", help="print JSON instead of a table")
    return p


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv or (argv[0] not in COMMANDS and argv[0] not in ("-h", "--help")):
        argv = ["view", *argv]                # `python -m app [SCENE]` opens the viewer
    args = _parser(argv[0]).parse_args(argv)
    try:
        return _dispatch(args)
    except KeyboardInterrupt:
        return 130


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
    if not scene.views:
        print(f"error: {scene.name}: no valid view to show", file=sys.stderr)
        return None
    if not 1 <= k <= len(scene.views):
        print(f"error: --view {k}: the scene has {len(scene.views)} valid views (1 to "
              f"{len(scene.views)})", file=sys.stderr)
        return None
    return k - 1


def _dispatch(args) -> int:
    if args.command == "view":
        from app.viewer.launch import main as viewer_main
        return viewer_main(args.scene, args.size, out_dir=args.out)
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
    with announce_compiles():            # the first run compiles the kernels: say so
        frame = render(scene, index, args.projection, args.shading, args.size or scene.size)
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
    print(f"wrote {out} ({frame.color.shape[1]}x{frame.color.shape[0]}, view {args.view} of "
          f"{len(scene.views)}, {frame.stats['projection']}, {frame.stats['shading']})")
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
    vp = project.viewport(view.window, *args.size)
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
    out = {"scene": scene.name, "projection": projection, "shading": shading,
           **plan_as_dict(plan(scene, projection, shading))}
    print(json.dumps(out, indent=2, ensure_ascii=False))
    return 0
