"""The command line: ``python -m app COMMAND ...``, COMMAND one of view, render, matrices, plan,
bench, report, stability, animate, warmup (``view`` when none is given).

Only parsing and dispatch live here; each command's body is in its own module and is imported
when that command runs, so that ``python -m app --help`` and the window start fast.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import tempfile
from pathlib import Path


from core.settings import PROJECTIONS as PROJECTION_CHOICES, SHADINGS as SHADING_CHOICES
COMMANDS = ("view", "render", "matrices", "plan", "bench", "report", "stability", "animate",
            "warmup")
RASTERIZER_CHOICES = ("edge", "scanline")


_SIZE = re.compile(r"([+-]?[0-9]+)[xX]([+-]?[0-9]+)")


def parse_size(text: str) -> tuple[int, int]:
    """``WxH`` → ``(W, H)`` for argparse: ASCII digits only (``int`` would also take ``+5``,
    ``1_0`` and fullwidth digits), with a message that says what was wrong."""
    from core.scene.model import MAX_IMAGE_SIDE
    match = _SIZE.fullmatch(text)
    if not match or len(text) > 40:
        shown = text if len(text) <= 40 else text[:40] + "..."
        raise argparse.ArgumentTypeError(
            f"size must be WIDTHxHEIGHT in ASCII digits, like 500x500, not {shown!r}")
    for side, token in zip(("width", "height"), match.groups()):
        if token[0] == "+":
            raise argparse.ArgumentTypeError(f"the {side} {token!r} must be plain digits, "
                                             f"without a sign")
        if token[0] == "-" or int(token) < 1:
            raise argparse.ArgumentTypeError(f"the {side} must be at least 1, got {token}")
    if len(match.group(1)) > 6 or len(match.group(2)) > 6 \
            or max(int(match.group(1)), int(match.group(2))) > MAX_IMAGE_SIDE:
        raise argparse.ArgumentTypeError(f"size {text} is out of range (1 to {MAX_IMAGE_SIDE} "
                                         "a side)")
    return int(match.group(1)), int(match.group(2))


def attach_values(argv: list[str], options=("--size",)) -> list[str]:
    """``--size -5x5`` → ``--size=-5x5``: argparse takes a value that starts with ``-`` for an
    option (and says "expected one argument"); joined, it reaches :func:`parse_size`, which
    says what is wrong with it."""
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
    v.add_argument("--renderer", choices=("zbuffer", "raytrace", "bsp", "depth-sort"),
                   default=None,                                   # issues 12 and 18
                   help="draw with the z-buffer (default), the ray tracer (progressive), or a "
                        "painter's algorithm (bsp, depth-sort)")

    r = sub.add_parser("render", help="render one view to a PNG with the CPU core")
    r.add_argument("scene", help=scene_help)
    r.add_argument("--view", type=int, default=1,
                   help="which view: its position in the file, counting from 1 (an invalid "
                        "one prints its message and exits 1)")
    r.add_argument("--projection", choices=PROJECTION_CHOICES, default=None)
    r.add_argument("--shading", choices=SHADING_CHOICES, default=None)
    r.add_argument("--size", type=parse_size, default=None, help="WxH (default: the scene's, 500x500)")
    r.add_argument("--out", required=True,
                   help="the PNG file to write (.png only; its folder must exist; an existing "
                        "file that is not a PNG is kept unless --force)")
    r.add_argument("--force", action="store_true",
                   help="overwrite --out even if it is an existing file that is not a PNG")
    _texture_arguments(r)                     # issue 11
    _course_options(r)
    r.add_argument("--time", type=float, default=None, metavar="SECONDS",
                   help="for an animated scene: the moment to draw, particles included "
                        "(the keyed view, objects and lights at that time)")
    _renderer_arguments(r)                    # issue 12
    _painter_arguments(r)                     # issue 18

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
    _painter_arguments(pl, plan=True)         # issue 18

    b = sub.add_parser("bench", help="time the CPU pipeline against llvmpipe (OpenGL in software)")
    if command == "bench":                    # its options live with its body (app/tools/bench.py)
        from app.tools.bench import add_arguments
        add_arguments(b, parse_size)

    rep = sub.add_parser("report", help="error against run time: sweep, CSV, Markdown and plot")
    rep.add_argument("--out", default="report", help="output directory")
    rep.add_argument("--quick", action="store_true", help="a reduced sweep (for tests)")

    an = sub.add_parser("animate", help="render an animation to MP4, GIF or PNGs (on many workers)")
    if command == "animate":                  # its options live with its body (app/tools/animate.py)
        from app.tools.animate import add_arguments as animate_arguments
        animate_arguments(an, parse_size)

    st = sub.add_parser("stability", help="the stiff and extreme cases, PASS/FAIL")
    st.add_argument("--json", action="store_true", help="print JSON instead of a table")

    sub.add_parser("warmup", help="compile every kernel once (make does it), with progress")
    return p


def _renderer_arguments(parser: argparse.ArgumentParser) -> None:
    """--renderer and the ray tracer's settings (issue 12); None keeps the defaults."""
    from core.raytrace.whitted import SHADOW_MODES
    from core.renderers import renderer_names
    parser.add_argument("--renderer", choices=renderer_names(), default=None,
                        help="zbuffer (default), raycast, or raytrace (Whitted: shadows, "
                             "mirrors, glass)")
    parser.add_argument("--samples", type=int, default=None, help="samples per pixel (1, 4, 9, 16 ...)")
    parser.add_argument("--shadows", choices=SHADOW_MODES, default=None,
                        help="raytrace: what an object between a point and a light does "
                             "(default transmit: attenuate by k_t)")
    parser.add_argument("--max-depth", type=int, default=None,
                        help="raytrace: the ray tree's depth limit (default 7)")
    parser.add_argument("--fresnel", action="store_true", default=None,
                        help="raytrace: Schlick's Fresnel weighting of k_r and k_t")


def _renderer_overrides(args) -> dict:
    return {"renderer": args.renderer, "samples": args.samples, "shadows": args.shadows,
            "max_depth": args.max_depth, "fresnel": args.fresnel, **_painter_overrides(args)}


# -- issue 18: the painter's renderers (bsp, depth-sort) ----------------------------------------
def _painter_arguments(parser: argparse.ArgumentParser, plan: bool = False) -> None:
    """--bsp-root and --paint-first (and for ``plan``, --renderer)."""
    from core.settings import BSP_ROOTS
    if plan:
        from core.renderers import renderer_names
        parser.add_argument("--renderer", choices=renderer_names(), default=None,
                            help="bsp and depth-sort also report their tree or sort "
                                 "(nodes, splits, depth, build time; tests run)")
        parser.add_argument("--view", type=int, default=1, help="the view whose order to report")
    parser.add_argument("--bsp-root", choices=BSP_ROOTS, default=None,
                        help="bsp: how each node's root triangle is chosen (default "
                             "fewest-splits: the notes' 'fewest branches'; first: the list's "
                             "head; random: seeded)")
    parser.add_argument("--paint-first", type=int, default=None, metavar="K",
                        help="bsp, depth-sort: paint only the first K triangles of the order")
    parser.add_argument("--transparency", choices=("off", "interpolated", "screen-door"),
                        default=None, help="z-buffer, bsp, depth-sort: materials with k_t > 0 "
                        "laid over the opaque picture (default: the scene's, else off)")
    parser.add_argument("--depth-cue", action=argparse.BooleanOptionalAction, default=None,
                        help="fade with depth towards the cue colour (FvDFH 16.1.3; the scene's "
                             "[depth_cue] table, default on when it has one)")


def _painter_overrides(args) -> dict:
    if getattr(args, "paint_first", None) is not None and args.paint_first < 0:
        raise ValueError(f"--paint-first must be 0 or more, not {args.paint_first}")
    return {"bsp_root": getattr(args, "bsp_root", None),
            "paint_first": getattr(args, "paint_first", None),
            "depth_cue": getattr(args, "depth_cue", None),
            "transparency": getattr(args, "transparency", None)}


def _painter_plan(args, scene) -> dict | None:
    """What the painter's renderer did for the view: the tree's or the sort's numbers."""
    if getattr(args, "renderer", None) not in ("bsp", "depth-sort"):
        return {}
    from core.render import render
    from core.settings import RenderSettings
    index = _pick_view(scene, args.view)
    if index is None:
        return None                                  # _pick_view said why
    settings = RenderSettings.for_scene(scene, projection=args.projection, shading=args.shading,
                                        renderer=args.renderer, **_painter_overrides(args))
    frame = render(scene, scene.views[index], settings)
    return {args.renderer: {k: v for k, v in frame.stats.items()
                            if k in ("BSP tree", "depth sort", "painted", "culled")},
            "runs": [{"stage": s.name, "why": s.reason} for s in frame.plan if s.runs]}
# -- end of issue 18 ------------------------------------------------------------------------------


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
    args = _parser(argv[0]).parse_args(attach_values(argv))
    try:
        return _dispatch(args)
    except KeyboardInterrupt:
        return 130
    except MemoryError:
        return _out_of_memory()


def _out_of_memory() -> int:
    """The last line of defence: every reader bounds its input, but a scene within the limits
    may still need more memory than this machine has (a huge framebuffer of many samples)."""
    print("error: out of memory: the input or the image is too large for this machine's "
          "memory (see the input-size limits in the README)", file=sys.stderr)
    return 3


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
    for message in scene.messages:
        print(f"warning: {message}", file=sys.stderr)
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
                                    "course_tri": args.course_tri,
                                    "renderer_name": args.renderer})
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
    if args.command == "animate":
        from app.tools.animate import main as animate_main
        return animate_main(args)
    if args.command == "warmup":
        from app.tools.warmup import main as warmup_main
        return warmup_main(args)
    if args.command == "stability":
        from app.tools.stability import main as stability_main
        return stability_main(args)
    raise AssertionError(args.command)


def _draw_still(scene, view, settings, time):
    """The frame of ``view``, or with ``time`` an animated scene's frame at that moment
    (core.animation.frames.render_at: keyed view, particles and all)."""
    from app.viewer.state import render          # listens for compiles, to announce them
    from core.animation.keys import animation_of
    animation = animation_of(scene) if time is not None else None
    if animation is None:
        return render(scene, view, settings)
    from core.animation.frames import render_at
    return render_at(animation, time, settings)


def _drawn_by(settings) -> str:
    """What drew the frame, in the render log's words."""
    if settings.renderer == "zbuffer":
        return f"z-buffer, {settings.rasterizer} rasterizer"
    return {"raytrace": "ray traced", "raycast": "ray cast (exact)"}.get(settings.renderer,
                                                                      settings.renderer)


def _render(args) -> int:
    from app.viewer.state import announce_compiles
    refusal = out_problem(Path(args.out), args.scene, args.force)
    if refusal:
        print(f"error: --out {args.out}: {refusal}", file=sys.stderr)
        return 2
    scene = _load(args.scene, size=args.size)
    if scene is None:
        return 2
    index = _pick_view(scene, args.view)
    if index is None:
        return 2
    from core.settings import RenderSettings
    texture_options = _texture_options(scene, args)       # issue 11
    view = scene.views[index]
    try:
        settings = RenderSettings.for_scene(scene, projection=args.projection,
                                            shading=args.shading, size=args.size,
                                            rasterizer=args.rasterizer,
                                            keep_aspect=args.keep_aspect, **texture_options,
                                            **_renderer_overrides(args))
    except ValueError as error:            # e.g. --samples 0 (issue 12's options)
        print(f"error: {error}", file=sys.stderr)
        return 2
    if args.course_tri:
        from core.scene.course_tri import course_tri_scene
        scene = course_tri_scene(scene, view)
    with announce_compiles():            # the first run compiles the kernels: say so
        frame = _draw_still(scene, view, settings, args.time)
    if frame.message:
        print(f"error: {frame.message}", file=sys.stderr)
        return 1
    out = Path(args.out)
    try:
        write_png(frame.color, out)
    except OSError as error:
        print(f"error: cannot write {out}: {error.strerror or error}", file=sys.stderr)
        return 2
    from core.scene.view_numbers import label
    print(f"wrote {out} ({frame.color.shape[1]}x{frame.color.shape[0]}, {label(scene, index)}, "
          f"{settings.projection}, {settings.shading}, {_drawn_by(settings)}, "
          f"aspect {'kept' if settings.keep_aspect else 'stretched'})")
    return 0


PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def out_problem(out: Path, source: str, force: bool) -> str | None:
    """Why ``render`` must not write ``out``, or None. Only PNG is written (``.png``); the
    folder must exist (none is created); the output is never the input (also through links or
    another name); an existing file is replaced only if it is a PNG, or with ``--force``."""
    if out.suffix.lower() != ".png":
        return f"only PNG is written: the name must end in .png (got {out.suffix or 'no extension'!r})"
    parent = out.parent
    if not parent.is_dir():
        return f"the folder {str(parent)!r} does not exist (it is not created)"
    if source != "-" and _same_file(out, Path(source)):
        return f"it is the input {source!r}: writing would destroy it"
    if os.path.lexists(out):
        if out.is_dir():
            return "it is a folder"
        if not out.is_file():
            return "it exists and is not a regular file"
        if not force and not _is_png(out):
            return "it exists and is not a PNG: it is kept (--force replaces it)"
    return None


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _is_png(path: Path) -> bool:
    try:
        with open(path, "rb") as f:
            return f.read(8) == PNG_SIGNATURE
    except OSError:
        return False


def write_png(color, out: Path) -> None:
    """Write a temporary PNG beside ``out`` and rename it over ``out``: a failed write (a full
    disk) leaves whatever was there untouched, and no half-written file behind."""
    from PIL import Image
    fd, temp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    try:
        with os.fdopen(fd, "wb") as stream:
            Image.fromarray(color).save(stream, format="PNG")
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temp, 0o666 & ~umask)         # mkstemp made it private; a PNG is not
        os.replace(temp, out)
    except BaseException:
        os.unlink(temp)
        raise


# -- issue 11: texture filter, and the bump demo's map and mode (J3DPanel's clicks)
def _texture_arguments(parser) -> None:
    from core.texture.modes import FILTERS
    parser.add_argument("--texture-filter", choices=tuple(FILTERS), default=None,
                        help="how textures are filtered (default: trilinear)")
    parser.add_argument("--bump-map", type=int, default=None, metavar="K",
                        help="the bump demo's height map B(x, y), 0 to 3")
    parser.add_argument("--no-bump", action="store_true",
                        help="ignore bump and normal maps (the bump demo's Phong mode)")


def _texture_options(scene, args) -> dict:
    from core.texture.demo_scene import apply_demo_options
    label = apply_demo_options(scene, args.bump_map, not args.no_bump)
    if label:
        print(label)
    return {"texture_filter": args.texture_filter, "bump": False if args.no_bump else None}
# --


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
    renderer = args.renderer or scene.renderer
    try:
        painter = _painter_plan(args, scene)               # issue 18
    except ValueError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    if painter is None:
        return 2
    out = {"scene": scene.name, "projection": projection, "shading": shading,
           "rasterizer": rasterizer, "keep_aspect": keep, "renderer": renderer,
           **plan_as_dict(plan(scene, projection, shading, keep, rasterizer,
                               renderer=renderer)), **painter}
    print(json.dumps(out, indent=2, ensure_ascii=False))
    return 0
