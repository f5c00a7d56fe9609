"""The command line: ``fvd-viewer COMMAND ...`` or ``python -m app COMMAND ...``, COMMAND one of
view, render, matrices, plan, bench, report, stability, animate, warmup, inspect, compare,
radiosity (``view`` when none is given), with the global options ``--version``, ``-v`` /
``--verbose`` and ``-q`` / ``--quiet`` before or after it.

Only parsing and dispatch live here; each command's body is in its own module and is imported
when that command runs, so that ``--help`` and the window start fast (``--version`` imports
neither numpy nor numba).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
from pathlib import Path
from types import SimpleNamespace

from app import startup_gc
COMMANDS = ("view", "render", "matrices", "plan", "bench", "report", "stability", "animate",
            "warmup", "inspect", "compare", "radiosity", "torques", "colour")


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


def _global_arguments(parser: argparse.ArgumentParser, top: bool) -> None:
    """The global options in a parser's --help (:func:`global_options` has taken them out of
    the command line before argparse sees it)."""
    g = parser.add_argument_group("global options (before or after the command)")
    if top:
        g.add_argument("--version", action="store_true",
                       help="print the version, and Python's and the key packages', and exit")
    g.add_argument("-v", "--verbose", action="store_true",
                   help="also log what happens and how long it takes (INFO lines on stderr)")
    g.add_argument("-q", "--quiet", action="store_true",
                   help="log errors only (a command's own results and error lines stay)")


class _CommandParser(argparse.ArgumentParser):
    """A command's parser: its --help lists -v and -q too."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        _global_arguments(self, top=False)


def default_prog() -> str:
    """The program's name as it was started: ``fvd-viewer`` (the installed script, by its
    file's name) or ``python -m app``."""
    name = Path(sys.argv[0]).name if sys.argv and sys.argv[0] else ""
    if not name or name in ("__main__.py", "-c") or name.startswith("python"):
        return "python -m app"
    return name.removesuffix(".exe").removesuffix("-script.py")
# --


def _parser(command: str | None = None, prog: str = "python -m app") -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog=prog,
        description="A CPU reference renderer: the Foley-van Dam viewing pipeline, scan-line "
                    "z-buffer and shading, shown through OpenGL. With no command, opens the "
                    "viewer on the default scene (the FvDFH house).")
    _global_arguments(p, top=True)
    sub = p.add_subparsers(dest="command", parser_class=_CommandParser)
    scene_help = ("a scene file (.toml), a .tri file, a mesh (.obj/.ply/.off/.stl), a bare view "
                  "file (shown with the house), or - for a view file on standard input")
    _view_parser(sub, scene_help, command)
    _render_parser(sub, scene_help)
    _radiosity_parser(sub, command)
    _matrices_parser(sub, scene_help)
    _plan_parser(sub, scene_help)
    _tool_parsers(sub, command)
    _inspector_parsers(sub, scene_help)
    return p


def _view_parser(sub, scene_help: str, command: str | None = None) -> None:
    """``view``: the window, or PNGs when there is no display; its help lists every key and
    mouse action (the F1 panel's list, read only when ``view`` is the command)."""
    epilog = None
    if command == "view":
        from app.viewer.hands import KEYS_HELP
        epilog = "in the window:\n" + "\n".join(
            f"  {key:<24} {what}" if what else f" {key}" for key, what in KEYS_HELP)
    v = sub.add_parser("view", help="open the viewer window (renders PNGs when there is no "
                       "display)", epilog=epilog,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    v.add_argument("scene", nargs="?", help=scene_help + "; default: the house")
    v.add_argument("--size", type=parse_size, default=None,
                   help="framebuffer size WxH (default: the scene's, 500x500)")
    v.add_argument("--out", default=None,
                   help="where screenshots go, and the PNGs when there is no display "
                        "(default: ./screenshots, and ./fvd-views or $FVD_OUT without a display)")
    _course_options(v)
    from core.renderers import renderers
    v.add_argument("--renderer", choices=[r.name for r in renderers()], default=None,
                   help="draw with one of the registered renderers (default zbuffer): "
                        + "; ".join(f"{r.name}: {r.label or r.description}"
                                    for r in renderers()))
    _crease_argument(v)
    v.add_argument("--samples", type=_positive_samples, default=None, metavar="N",
                   help="samples per pixel (default: the path tracer adds passes up to 256 "
                        "while the camera rests; the others 1); also in the panel")
    v.add_argument("--reference", default=None, metavar="PNG",
                   help="a picture to hold ours against: h cycles our picture, the reference "
                        "and their difference heat map (with the numbers compare prints)")


def _render_parser(sub, scene_help: str) -> None:
    """``render``: one view to a PNG, with every renderer's options."""
    from core.registry import shading_names
    from core.settings import PROJECTIONS as PROJECTION_CHOICES
    shadings = shading_names()
    r = sub.add_parser("render", help="render one view to a PNG with the CPU core")
    r.add_argument("scene", help=scene_help)
    r.add_argument("--view", type=int, default=1,
                   help="which view: its position in the file, counting from 1 (a view that "
                        "cannot be drawn, invalid in the file or in this projection, prints "
                        "its message and exits with status 2)")
    r.add_argument("--projection", choices=PROJECTION_CHOICES, default=None)
    r.add_argument("--shading", choices=shadings, default=None)
    r.add_argument("--size", type=parse_size, default=None, help="WxH (default: the scene's, 500x500)")
    r.add_argument("--out", default=None,
                   help="the PNG file to write (.png only; its folder must exist; an existing "
                        "file that is not a PNG is kept unless --force; default: named for "
                        "the scene, view, projection, shading and renderer in the current "
                        "folder, e.g. torus-view01-perspective-phong-zbuffer.png)")
    r.add_argument("--force", action="store_true",
                   help="overwrite --out even if it is an existing file that is not a PNG")
    _texture_arguments(r)
    _course_options(r)
    r.add_argument("--time", type=float, default=None, metavar="SECONDS",
                   help="for an animated scene: the moment to draw, particles included "
                        "(the keyed view, objects and lights at that time)")
    r.add_argument("--motion-blur", type=int, default=None, metavar="SAMPLES",
                   help="with --time: the frame at that time motion-blurred, SAMPLES times over "
                        "the shutter interval, as animate blurs its frames (1: sharp; default: "
                        "the scene's [animation] motion_blur, else sharp)")
    r.add_argument("--shutter", type=float, nargs=2, default=None, metavar=("OPEN", "CLOSE"),
                   help="with --motion-blur: when the shutter opens and closes, in frames from "
                        "the frame's time (default -0.25 0.25)")
    r.add_argument("--blur-method", choices=("auto", "accumulate", "per-ray"), default=None,
                   help="with --motion-blur: accumulate whole frames, or the ray tracer's time "
                        "per ray (auto, the default: per-ray for the ray tracer)")
    _renderer_arguments(r)                    # the ray tracer's and the clipper's choices
    _buffer_argument(r)
    _cluster_arguments(r)                     # scale-out
    _crease_argument(r)
    from app.commands.radiosity import add_solution_argument
    add_solution_argument(r)                  # radiosity drawn from a saved solution
    _painter_arguments(r)                     # painter's renderers


def _radiosity_parser(sub, command: str | None) -> None:
    """``radiosity``: its options are only built when it is the command (they import more)."""
    rad = sub.add_parser("radiosity", help="solve a scene's radiosity once and save it (.npz)")
    if command in (None, "radiosity"):
        from app.commands.radiosity import add_arguments as radiosity_arguments
        radiosity_arguments(rad)


def _matrices_parser(sub, scene_help: str) -> None:
    from core.settings import PROJECTIONS as PROJECTION_CHOICES
    m = sub.add_parser("matrices", help="print every factor of N_per / N_par as JSON")
    m.add_argument("scene", help=scene_help)
    m.add_argument("--view", type=int, default=1,
                   help="which view: its position in the file, counting from 1")
    m.add_argument("--projection", choices=PROJECTION_CHOICES, default="perspective")
    m.add_argument("--size", type=parse_size, default=(500, 500), help="viewport for M_vv3dv")
    m.add_argument("--keep-aspect", action="store_true", default=None,
                   help="letterbox the window in the viewport instead of stretching it")
    m.add_argument("--general", default=None, metavar="ZP,Q,DX,DY,DZ",
                   help="also print M_general (FvDFH eq. 6.18) for the projection plane z = ZP "
                        "and a centre of projection Q from (0, 0, ZP) along (DX, DY, DZ); Q = "
                        "inf: parallel (e.g. -1,1,0,0,1 is M_per with d = -1, 0,inf,0,0,-1 is "
                        "M_ort)")


def _plan_parser(sub, scene_help: str) -> None:
    from core.registry import shading_names
    from core.settings import PROJECTIONS as PROJECTION_CHOICES, RASTERIZERS
    shadings = shading_names()
    pl = sub.add_parser("plan", help="print, as JSON, the stages that will run and those left out")
    pl.add_argument("scene", help=scene_help)
    pl.add_argument("--projection", choices=PROJECTION_CHOICES, default=None)
    pl.add_argument("--shading", choices=shadings, default=None)
    pl.add_argument("--rasterizer", choices=RASTERIZERS, default=None)
    pl.add_argument("--keep-aspect", action="store_true", default=None)
    _painter_arguments(pl, plan=True)         # the painter's renderers report their order


def _tool_parsers(sub, command: str | None) -> None:
    """The tools' commands; bench, animate and warmup keep their options with their bodies
    and build them only when they are the command."""
    b = sub.add_parser("bench", help="time the CPU pipeline against llvmpipe (OpenGL in software)")
    if command == "bench":                    # its options live with its body (app/bench/bench.py)
        from app.bench.bench import add_arguments
        add_arguments(b, parse_size)

    rep = sub.add_parser("report", help="error against run time: sweep, CSV, Markdown and plot")
    rep.add_argument("--out", default="report", help="output directory")
    rep.add_argument("--quick", action="store_true", help="a reduced sweep (for tests)")

    an = sub.add_parser("animate", help="render an animation to MP4, GIF or PNGs (on many workers)")
    if command == "animate":                  # options live with the body (app/commands/animate.py)
        from app.commands.animate import add_arguments as animate_arguments
        animate_arguments(an, parse_size)

    st = sub.add_parser("stability", help="the stiff and extreme cases, PASS/FAIL")
    st.add_argument("--json", action="store_true", help="print JSON instead of a table")

    tq = sub.add_parser("torques", help="inverse dynamics: a linkage's joint torques, frame by frame")
    if command == "torques":                  # options: app/commands/torques.py
        from app.commands.torques import add_arguments as torques_arguments
        torques_arguments(tq)
    co = sub.add_parser("colour", help="the CIE 1931 chromaticity diagram with the sRGB gamut (PNG)")
    if command == "colour":                   # options: app/commands/colour.py
        from app.commands.colour import add_arguments as colour_arguments
        colour_arguments(co)

    wu = sub.add_parser("warmup", help="compile every kernel once, on every core, with progress")
    if command == "warmup":                   # options: app/distribution/warmup.py
        from app.distribution.warmup import add_arguments as warmup_arguments
        warmup_arguments(wu)


def _renderer_arguments(parser: argparse.ArgumentParser) -> None:
    """--renderer, the film's and the clipper's choices, and every renderer's own flags;
    None keeps the defaults."""
    from core.renderers import renderers
    from core.settings import CLIPPERS
    parser.add_argument("--renderer", choices=[r.name for r in renderers()], default=None,
                        help="one of the registered renderers (default: the scene's, else "
                             "zbuffer): " + "; ".join(f"{r.name}: {r.label or r.description}"
                                                      for r in renderers()))
    parser.add_argument("--samples", type=_samples, default=None,
                        help="samples per pixel (1, 4, 9, 16 ...), or 'adaptive' (raytrace: "
                             "Whitted's adaptive supersampling, up to 16 a pixel, or up to "
                             "--samples-max)")
    parser.add_argument("--filter", choices=("box", "tent", "gaussian", "mitchell"),
                        default=None, dest="pixel_filter",
                        help="the reconstruction filter of a supersampled frame (default box: "
                             "the mean of the pixel's samples)")
    parser.add_argument("--filter-radius", type=float, default=None, metavar="PIXELS",
                        help="its radius (default: box 0.5, tent 1, gaussian 1.5, mitchell 2)")
    parser.add_argument("--antialias-lines", action="store_true", default=None,
                        help="draw the wireframe with Wu's antialiased lines instead of the "
                             "midpoint line")
    parser.add_argument("--clipper", choices=CLIPPERS,
                        default=None, help="the line and polygon clipper: cohen-sutherland (the "
                        "course's outcodes and Sutherland-Hodgman, default), liang-barsky "
                        "(parametric tests) or homogeneous (in clip space before the divide); "
                        "the same picture")
    # adaptive supersampling's limits
    parser.add_argument("--samples-max", type=int, default=None, metavar="N",
                        help="raytrace, --samples adaptive: the most samples a pixel gets "
                             "(4, 16, 64 or 256; default 16)")
    _options_arguments(parser)


def _options_arguments(parser: argparse.ArgumentParser) -> None:
    """Each registered renderer's own flags (its options class's ``add_arguments``)."""
    from core.registry import option_classes
    for options in option_classes():
        options.add_arguments(parser)


def _option_overrides(args) -> dict:
    """What the renderers' own flags set (None: not given)."""
    from core.registry import option_classes
    return {k: v for options in option_classes() for k, v in options.overrides(args).items()}


def _positive_samples(text: str) -> int:
    """``view --samples``: a whole number of samples per pixel the settings take."""
    from core.settings import MAX_SAMPLES
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= MAX_SAMPLES:
        raise argparse.ArgumentTypeError(f"samples must be a whole number from 1 to "
                                         f"{MAX_SAMPLES}, not {text!r}")
    return value


def _samples(text: str):
    """``--samples``: a whole number, or ``adaptive``."""
    if text == "adaptive":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"samples must be a whole number or 'adaptive', "
                                         f"not {text!r}") from None


def _cluster_arguments(parser: argparse.ArgumentParser) -> None:
    """--workers and --scheduler: a ray-traced frame traced by bands on a Dask cluster."""
    parser.add_argument("--workers", type=_count, default=1,
                        help="local worker processes for a ray-traced frame (a local cluster "
                             "is started only when it can beat this process; it says so)")
    parser.add_argument("--scheduler", default=None,
                        help="trace a ray-traced frame by bands on the Dask scheduler at this "
                             "address (tcp://host:8786); the picture is the one-process one")


def _count(text: str) -> int:
    """A whole number of at least 1, for argparse."""
    if not re.fullmatch(r"[0-9]{1,6}", text) or int(text) < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number from 1 to 999999, got {text!r}")
    return int(text)


def _split(args, settings):
    """``(frame colour or None, what to say)``: the frame traced across a cluster when asked
    and possible; None when this process draws it (or an error was printed: then say is None)."""
    if args.workers == 1 and not args.scheduler:
        return None, ""
    from app.commands.cluster import ClusterError
    from app.commands.split_render import split_frame
    try:
        return split_frame(args, settings)
    except ClusterError as error:
        print(f"error: {error}", file=sys.stderr)
        return None, None
    except Exception as error:                # noqa: BLE001 - a failed task, in one line
        print(f"error: the cluster could not trace the frame: {type(error).__name__}: "
              f"{' '.join(str(error).split())}", file=sys.stderr)
        return None, None


def _renderer_overrides(args) -> dict:
    adaptive = args.samples == "adaptive"
    samples = (args.samples_max or 16) if adaptive else args.samples
    return {"renderer": args.renderer, "samples": samples,
            "sample_pattern": "adaptive" if adaptive else None,
            "pixel_filter": getattr(args, "pixel_filter", None),
            "filter_radius": getattr(args, "filter_radius", None),
            **_painter_overrides(args), **_option_overrides(args)}


def _crease_argument(parser: argparse.ArgumentParser) -> None:
    """--crease-angle: where meshes without normals of their own keep sharp edges."""
    parser.add_argument("--crease-angle", type=float, default=None, metavar="DEGREES",
                        help="faces meeting at more than this keep their own normals along "
                             "the edge (default: the scene's crease_angle, else 45)")


# -- the painter's renderers (bsp, depth-sort) -------------------------------------------------
def _painter_arguments(parser: argparse.ArgumentParser, plan: bool = False) -> None:
    """Transparency, Phong's precision and the depth cue (and for ``plan``, --renderer, --view
    and every renderer's own flags: the painters' report their order)."""
    if plan:
        from core.renderers import renderer_names
        parser.add_argument("--renderer", choices=renderer_names(), default=None,
                            help="bsp and depth-sort also report their tree or sort "
                                 "(nodes, splits, depth, build time; tests run)")
        parser.add_argument("--view", type=int, default=1, help="the view whose order to report")
        _options_arguments(parser)
    from core.settings import TRANSPARENCIES
    parser.add_argument("--transparency", choices=tuple(TRANSPARENCIES),
                        default=None, help="z-buffer, bsp, depth-sort: materials with k_t > 0 "
                        "laid over the opaque picture (default: the scene's, else "
                        "interpolated where a material has k_t > 0; interpolated-specular: "
                        "the near surface's ambient and diffuse interpolated, its specular "
                        "added, the notes' more realistic recipe; off draws them opaque)")
    parser.add_argument("--shading-precision", choices=("float32", "float64"), default=None,
                        help="Phong's pixel step: float32 over each row, 8 pixels at a time "
                             "(default; within 1/255 of float64), or the textbook float64 "
                             "kernel, one pixel at a time")
    parser.add_argument("--depth-cue", action=argparse.BooleanOptionalAction, default=None,
                        help="fade with depth towards the cue colour (FvDFH 16.1.3; the scene's "
                             "[depth_cue] table, default on when it has one)")


def _painter_overrides(args) -> dict:
    return {"depth_cue": getattr(args, "depth_cue", None),
            "transparency": getattr(args, "transparency", None),
            "shading_precision": getattr(args, "shading_precision", None)}


def _painter_plan(args, scene) -> dict | None:
    """What the painter's renderer did for the view: the tree's or the sort's numbers."""
    from core.renderers import get_renderer, renderer_names
    name = getattr(args, "renderer", None)
    if name not in renderer_names() or get_renderer(name).painting is None:
        return {}                                    # not a painter (its entry's painting)
    from core.render import render
    from core.settings import RenderSettings
    index = _pick_view(scene, args.view)
    if index is None:
        return None                                  # _pick_view said why
    settings = RenderSettings.for_scene(scene, projection=args.projection, shading=args.shading,
                                        renderer=args.renderer, **_painter_overrides(args),
                                        **_option_overrides(args))
    frame = render(scene, scene.views[index], settings)
    return {args.renderer: {k: v for k, v in frame.stats.items()
                            if k in ("BSP tree", "depth sort", "painted", "culled")},
            "runs": [{"stage": s.name, "why": s.reason} for s in frame.plan if s.runs]}
# -- end of the painter's renderers -------------------------------------------------------------


def _course_options(p: argparse.ArgumentParser) -> None:
    """The course's options shared by ``view`` and ``render`` (None: the scene's own)."""
    from core.settings import RASTERIZERS
    p.add_argument("--rasterizer", choices=RASTERIZERS, default=None,
                   help="edge: edge functions, perspective-correct (default); scanline: the "
                        "course's edge table / active edge table, screen-linear shading")
    p.add_argument("--keep-aspect", action="store_true", default=None,
                   help="letterbox the view window instead of stretching it over the viewport "
                        "(the course's mapping stretches)")
    p.add_argument("--course-tri", action="store_true",
                   help="the .tri startup code's rules: skip triangles with viewpoint . N < 0, "
                        "and mouse buttons left Phong, middle Gouraud, right flat")
    from core.shading.models import lighting_models
    p.add_argument("--lighting-model", choices=[m.name for m in lighting_models()], default=None,
                   help="light every material with this model (default: each material's own "
                        "model key, Phong where it has none): "
                        + "; ".join(f"{m.name}: {m.label}" for m in lighting_models()))


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
    args = _parser(argv[0], prog).parse_args(attach_values(argv))
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


def _load(source: str, size=None, crease_angle=None):
    """The scene, or None after printing the reader's message (:mod:`app.loading`)."""
    from app.loading import load_or_say
    return load_or_say(source, size, crease_angle)


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
        return _render(args)
    if args.command == "matrices":
        return _matrices(args)
    if args.command == "plan":
        return _plan(args)
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
        return _inspector_command(args)
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


def _draw_still(scene, view, settings, time, shutter=None):
    """The frame of ``view``, or with ``time`` an animated scene's frame at that moment
    (core.animation.frames.render_at: keyed view, particles and all), blurred by ``shutter``
    (None: the scene file's own motion blur, if any). A still scene is the same at every
    moment of any shutter: its sharp frame."""
    from app.session.state import render          # listens for compiles, to announce them
    from core.animation.keys import animation_of
    animation = animation_of(scene) if time is not None else None
    if animation is None:
        return render(scene, view, settings)
    from core.animation.frames import render_at
    return render_at(animation, time, settings, shutter=shutter)   # its simulations report


def _still_shutter(args):
    """``render``'s --motion-blur, --shutter and --blur-method as a Shutter (None: not given);
    a ValueError says what is wrong with them."""
    samples, opening, method = args.motion_blur, args.shutter, args.blur_method
    if samples is None:
        if opening is not None or method is not None:
            raise ValueError(f"{'--shutter' if opening is not None else '--blur-method'} is the "
                             "motion blur's: give --motion-blur SAMPLES too")
        return None
    if args.time is None:
        raise ValueError("--motion-blur blurs an animated scene's frame at a moment: give "
                         "--time SECONDS too")
    from core.animation.frames import Shutter
    return Shutter(samples, *(opening or (Shutter.open, Shutter.close)), method or "auto")


def _drawn_by(settings) -> str:
    """What drew the frame, in the render log's words (its registry entry's ``drawn_by``)."""
    from core.renderers import get_renderer
    return get_renderer(settings.renderer).words(settings)


def _render(args) -> int:
    if args.time is not None and not math.isfinite(args.time):
        print(f"error: --time {args.time}: expected a finite number of seconds", file=sys.stderr)
        return 2
    if args.out is not None and _refused(args.out, args):
        return 2
    try:
        args.still_shutter = _still_shutter(args)
    except ValueError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    scene = _load(args.scene, size=args.size, crease_angle=args.crease_angle)
    if scene is None:
        return 2
    index = _pick_view(scene, args.view)
    if index is None:
        return 2
    settings = _render_settings(scene, args)
    if settings is None:
        return 2
    view = scene.views[index]
    if args.out is None and _name_out(args, scene, index, settings):
        return 2
    scene = _scene_to_draw(scene, view, args)
    if scene is None:
        return 2
    if args.buffer:                      # a buffer view instead of the picture
        from app.commands.inspector import render_buffer
        return render_buffer(scene, view, settings, args.buffer, Path(args.out), write_png)
    there = os.path.lexists(args.out)
    try:
        frame, status = _render_frame(scene, view, settings, args)
        if frame is None:
            return status
        status = _frame_problems(frame)
        if status is not None:
            return status
        return _write_frame(frame, args, scene, index, settings)
    except KeyboardInterrupt:            # the PNG is written whole or not at all (write_png)
        return _stopped(args, f"nothing was written ({args.out} "
                              f"{'is as it was' if there else 'was not made'})")


def _stopped(args, kept: str) -> int:
    """Say what Ctrl+C stopped and what stays; the status of an interrupted command."""
    from app.progress_line import INTERRUPTED, ProgressLine
    progress = getattr(args, "progress", None) or ProgressLine()
    progress.say(progress.stopped(kept))
    return INTERRUPTED


def _render_settings(scene, args):
    """The settings of ``render`` from the scene and the command line, or None (said why)."""
    from core.settings import RenderSettings
    try:
        texture_options = _texture_options(scene, args)   # the texture filter and bump demo
    except ValueError as error:                           # e.g. --bump-map 99
        print(f"error: --bump-map: {error}", file=sys.stderr)
        return None
    try:
        return RenderSettings.for_scene(scene, projection=args.projection,
                                        shading=args.shading, size=args.size,
                                        rasterizer=args.rasterizer,
                                        clipper=getattr(args, "clipper", None),
                                        antialias_lines=getattr(args, "antialias_lines", None),
                                        keep_aspect=args.keep_aspect, **texture_options,
                                        lighting_model=args.lighting_model,
                                        **_renderer_overrides(args))
    except ValueError as error:            # e.g. --samples 0 (the ray tracer's options)
        print(f"error: {error}", file=sys.stderr)
        return None


def _name_out(args, scene, index, settings) -> bool:
    """Name --out by the rule every output follows; True when that file must not be written."""
    from app.naming import picture_name
    from core.scene.view_numbers import file_number
    args.out = picture_name(scene.name, file_number(scene, index), settings.projection,
                            settings.shading, settings.renderer)
    return _refused(args.out, args)


def _scene_to_draw(scene, view, args):
    """The scene as --course-tri and --solution make it, or None when --solution is refused."""
    if args.course_tri:
        from core.scene.course_tri import course_tri_scene
        scene = course_tri_scene(scene, view)
    if args.solution:                     # a saved radiosity solution instead of solving
        from app.commands.radiosity import load_solution
        from core.context import DEFAULT_CONTEXT
        refusal = load_solution(scene, args.solution, DEFAULT_CONTEXT)
        if refusal:
            print(f"error: --solution: {refusal}", file=sys.stderr)
            return None
    return scene


def _render_frame(scene, view, settings, args):
    """(the frame, None), drawn here or split over the cluster; or (None, exit status)."""
    from app.session.state import announce_compiles
    split, said = _split(args, settings)
    if said is None:
        return None, 1
    if said:
        print(said, file=sys.stderr if split is None else sys.stdout)
    from core.animation.particles import ParticleBudgetError
    try:
        if split is not None:
            return SimpleNamespace(color=split, message=None, stats={}), None
        with announce_compiles():    # the first run compiles the kernels: say so
            return _draw_still(scene, view, settings, args.time,
                               getattr(args, "still_shutter", None)), None
    except ParticleBudgetError as error:
        print(f"error: {error}", file=sys.stderr)
        return None, 1


def _frame_problems(frame) -> int | None:
    """Print the frame's warnings; the exit status when it has no picture to write, else None."""
    for warning in frame.stats.get("warnings", ()):       # e.g. nothing emits light
        print(f"warning: {warning}", file=sys.stderr)
    if frame.stats.get("particles not born"):
        print(f"warning: {frame.stats['particles not born']:,} particles were not born: at most "
              f"{frame.stats['particle cap']:,} live at once", file=sys.stderr)
    if frame.message:                    # a view only the other projection can draw: 2, as
        print(f"error: {frame.message}", file=sys.stderr)          # --help says; else 1
        return 2 if frame.stats.get("refused") == "view" else 1
    for note in frame.stats.get("not drawn", []):   # what was left out is said, never dropped
        print(f"warning: not drawn: {note}", file=sys.stderr)
    return None


def _write_frame(frame, args, scene, index, settings) -> int:
    """Write the picture to --out and say what it is."""
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


def _refused(out: str, args) -> bool:
    """Print why ``render`` must not write ``out`` and say so, or say nothing and return False."""
    refusal = out_problem(Path(out), args.scene, args.force)
    if refusal:
        print(f"error: --out {out}: {refusal}", file=sys.stderr)
    return bool(refusal)


from app.output_files import PNG_SIGNATURE  # noqa: E402,F401  (tests read it here)


def out_problem(out: Path, source: str, force: bool) -> str | None:
    """Why ``render`` must not write ``out``, or None: only PNG is written (``.png``), by the
    one output rule of every command (:mod:`app.output_files`)."""
    from app.output_files import out_problem as problem
    return problem(out, source, force, (".png",))


def write_png(color, out: Path) -> None:
    """Write a temporary PNG beside ``out`` and rename it over ``out``: a failed write (a full
    disk) leaves whatever was there untouched, and no half-written file behind."""
    from PIL import Image

    from app.output_files import write_beside
    write_beside(out, lambda temp: Image.fromarray(color).save(temp, format="PNG"))


# -- texture filter, and the bump demo's map and mode (J3DPanel's clicks)
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
    except ViewError as error:           # a view only the other projection can draw
        print(f"error: {error}", file=sys.stderr)
        return 2
    from core.camera.taxonomy import describe
    out = {"view": view.label, "projection": args.projection,
           "class": describe(view, args.projection)}      # its place in the projection tree
    for name, m in factors.items():
        out[name] = float(m) if m.ndim == 0 else m.tolist()
    keep = scene.keep_aspect if args.keep_aspect is None else args.keep_aspect
    vp = project.viewport(view.window, *args.size, keep_aspect=keep)
    out["viewport"] = list(vp)
    out["M_vv3dv"] = project.m_vv3dv(*vp).tolist()
    if args.projection == "perspective":
        out["M_per"] = project.m_per(-1.0).tolist()
        out["M"] = project.perspective_to_parallel(float(factors["z_min"])).tolist()
    if args.general is not None:
        try:
            z_p, q, *direction = (float(c) for c in args.general.split(","))
            if len(direction) != 3:
                raise ValueError("expected five numbers: ZP,Q,DX,DY,DZ")
            out["M_general"] = project.m_general(z_p, q, direction).tolist()
        except ValueError as error:
            print(f"error: --general {args.general}: {error}", file=sys.stderr)
            return 2
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
        painter = _painter_plan(args, scene)               # the tree's or sort's numbers
    except ValueError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    if painter is None:
        return 2
    out = {"scene": scene.name, "projection": projection, "shading": shading,
           "rasterizer": rasterizer, "keep_aspect": keep, "renderer": renderer,
           **plan_as_dict(plan(scene, projection, shading, keep, rasterizer,
                               renderer=renderer,
                               transparency=getattr(args, "transparency", None))), **painter}
    print(json.dumps(out, indent=2, ensure_ascii=False))
    return 0


# -- the pixel inspector, buffer views and compare
def _buffer_argument(parser) -> None:
    from core.inspect.buffers import BUFFERS
    parser.add_argument("--buffer", choices=BUFFERS, default=None,
                        help="write a buffer view instead of the picture: a colour-mapped PNG "
                             "(--out) and the raw values beside it (.npy, same name)")


def _inspector_parsers(sub, scene_help: str) -> None:
    from core.registry import shading_names
    from core.settings import PROJECTIONS as PROJECTION_CHOICES
    shadings = shading_names()
    i = sub.add_parser("inspect", help="why one pixel has its colour: the renderer's record")
    c = sub.add_parser("compare", help="hold a picture (PNG) against our render of the same "
                                       "view: a diff heat map and a verdict (exit 1: differs)")
    for p in (i, c):
        p.add_argument("scene", help=scene_help)
        p.add_argument("--view", type=int, default=1,
                       help="which view: its position in the file, counting from 1")
        p.add_argument("--projection", choices=PROJECTION_CHOICES, default=None)
        p.add_argument("--shading", choices=shadings, default=None)
        p.add_argument("--size", type=parse_size, default=None,
                       help="WxH (default: the scene's; compare: the picture's)")
        _texture_arguments(p)
        _course_options(p)
        _renderer_arguments(p)
    i.add_argument("--pixel", required=True, metavar="X,Y",
                   help="the pixel: x right, y down, from 0 (row 0 is the top)")
    i.add_argument("--json", action="store_true", help="print the whole record as JSON")
    c.add_argument("--image", required=True, help="the picture to check (PNG)")
    c.add_argument("--tolerance", type=float, default=1 / 255,
                   help="largest channel difference that counts as equal, on 0-1 "
                        "(default 1/255)")
    c.add_argument("--out", default=None, help="write the diff heat map here (.png)")
    c.add_argument("--opengl", action="store_true",
                   help="the reference is real OpenGL (the GLSL oracle, Mesa llvmpipe) "
                        "instead of our CPU render")


def _inspector_command(args) -> int:
    scene = _load(args.scene, size=args.size)
    if scene is None:
        return 2
    index = _pick_view(scene, args.view)
    if index is None:
        return 2
    from core.settings import RenderSettings
    texture_options = _texture_options(scene, args)
    view = scene.views[index]
    try:
        settings = RenderSettings.for_scene(scene, projection=args.projection,
                                            shading=args.shading, size=args.size,
                                            rasterizer=args.rasterizer,
                                            clipper=getattr(args, "clipper", None),
                                            antialias_lines=getattr(args, "antialias_lines",
                                                                    None),
                                            keep_aspect=args.keep_aspect, **texture_options,
                                            lighting_model=args.lighting_model,
                                            **_renderer_overrides(args))
    except ValueError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    if args.course_tri:
        from core.scene.course_tri import course_tri_scene
        scene = course_tri_scene(scene, view)
    from app.commands import inspector
    if args.command == "inspect":
        return inspector.inspect_main(scene, view, settings, args.pixel, args.json)
    return inspector.compare_main(scene, view, settings, args, write_png)
# --
