"""The command line's arguments: the parser of every command (``python -m app COMMAND
--help`` is what these build) and the settings their flags give (``None`` keeps the scene's).

The registries' names (renderers, shading modes, lighting models, options) are read when a
parser is built, so that ``--help`` offers whatever is registered.
"""

from __future__ import annotations

import argparse
import re

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


def _global_arguments(parser: argparse.ArgumentParser, top: bool) -> None:
    """The global options in a parser's --help (:func:`app.cli.global_options` has taken them out of
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


def command_parser(command: str | None = None, prog: str = "python -m app") -> argparse.ArgumentParser:
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
        from app.viewer.hands import keys_help
        epilog = "in the window:\n" + "\n".join(
            f"  {key:<24} {what}" if what else f" {key}" for key, what in keys_help())
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
        from app.commands.animate_job import add_arguments as animate_arguments
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


def option_overrides(args) -> dict:
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


def renderer_overrides(args) -> dict:
    adaptive = args.samples == "adaptive"
    samples = (args.samples_max or 16) if adaptive else args.samples
    return {"renderer": args.renderer, "samples": samples,
            "sample_pattern": "adaptive" if adaptive else None,
            "pixel_filter": getattr(args, "pixel_filter", None),
            "filter_radius": getattr(args, "filter_radius", None),
            **painter_overrides(args), **option_overrides(args)}


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


def painter_overrides(args) -> dict:
    return {"depth_cue": getattr(args, "depth_cue", None),
            "transparency": getattr(args, "transparency", None),
            "shading_precision": getattr(args, "shading_precision", None)}


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


# -- texture filter, and the bump demo's map and mode (J3DPanel's clicks)
def _texture_arguments(parser) -> None:
    from core.texture.modes import FILTERS
    parser.add_argument("--texture-filter", choices=tuple(FILTERS), default=None,
                        help="how textures are filtered (default: trilinear)")
    parser.add_argument("--bump-map", type=int, default=None, metavar="K",
                        help="the bump demo's height map B(x, y), 0 to 3")
    parser.add_argument("--no-bump", action="store_true",
                        help="ignore bump and normal maps (the bump demo's Phong mode)")


def texture_overrides(scene, args) -> dict:
    from core.texture.demo_scene import apply_demo_options
    label = apply_demo_options(scene, args.bump_map, not args.no_bump)
    if label:
        print(label)
    return {"texture_filter": args.texture_filter, "bump": False if args.no_bump else None}


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
