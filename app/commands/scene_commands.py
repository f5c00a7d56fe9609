"""The bodies of the commands that read one scene and draw or describe one of its views:
``render`` (a still, its PNG and its log line), ``matrices``, ``plan`` and the pixel
inspector's ``inspect`` and ``compare``.
"""

from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path
from types import SimpleNamespace

from app.cli_arguments import (option_overrides, painter_overrides, renderer_overrides,
                               texture_overrides)


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
                                        renderer=args.renderer, **painter_overrides(args),
                                        **option_overrides(args))
    frame = render(scene, scene.views[index], settings)
    return {args.renderer: {k: v for k, v in frame.stats.items()
                            if k in ("BSP tree", "depth sort", "painted", "culled")},
            "runs": [{"stage": s.name, "why": s.reason} for s in frame.plan if s.runs]}


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


def render_command(args) -> int:
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
        texture_options = texture_overrides(scene, args)   # the texture filter and bump demo
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
                                        **renderer_overrides(args))
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


def matrices_command(args) -> int:
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


def plan_command(args) -> int:
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


def inspector_command(args) -> int:
    scene = _load(args.scene, size=args.size)
    if scene is None:
        return 2
    index = _pick_view(scene, args.view)
    if index is None:
        return 2
    from core.settings import RenderSettings
    texture_options = texture_overrides(scene, args)
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
                                            **renderer_overrides(args))
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
