"""``python -m app radiosity SCENE --out solution.npz``: solve once, save the solution keyed to
the scene's hash (``render --renderer radiosity --solution FILE`` draws from it; a file of
another scene is refused). Radiosity's options and their flags are
:class:`core.renderers.radiosity.options.RadiosityOptions`'s."""

from __future__ import annotations

import sys
import time


def add_solution_argument(parser) -> None:
    """``render --solution FILE``: draw radiosity from a saved solution."""
    parser.add_argument("--solution", default=None, metavar="FILE.npz",
                        help="radiosity: draw from this saved solution (python -m app radiosity)")


def load_solution(scene, path, context) -> str | None:
    """Make the saved solution the one ``scene`` is drawn with; the error, or None."""
    from core.radiosity.mesh import RadiosityError
    from core.renderers.radiosity.draw import use_solution
    from core.radiosity.solution import load
    try:
        solution = load(path, scene)
    except RadiosityError as error:
        return str(error)
    solution.stats["loaded"] = str(path)
    use_solution(scene, solution, context)
    return None


def add_arguments(parser) -> None:
    parser.add_argument("scene", help="a scene file (.toml)")
    parser.add_argument("--out", required=True, help="the solution file to write (.npz)")
    from core.renderers.radiosity.options import RadiosityOptions
    RadiosityOptions.add_arguments(parser)


def main(args) -> int:
    from core.radiosity.mesh import RadiosityError
    from core.radiosity.solution import Options, save, solve
    from core.settings import RenderSettings
    if not args.out.endswith(".npz"):
        print(f"error: --out {args.out}: a solution file ends in .npz", file=sys.stderr)
        return 2
    from core.scene.formats import ReaderError, load_scene
    try:
        scene = load_scene(args.scene)
    except ReaderError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    try:
        from core.renderers.radiosity.options import RadiosityOptions
        settings = RenderSettings.for_scene(scene, **RadiosityOptions.overrides(args))
        options = Options.from_settings(settings)
    except ValueError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2

    def progress(solver):
        if solver.steps % 50 == 0:
            print(f"shooting step {solver.steps}, unshot energy "
                  f"{100 * solver.unshot_fraction():.2f} %", file=sys.stderr)

    began = time.perf_counter()
    try:
        solution = solve(scene, options, progress)
    except RadiosityError as error:
        print(f"error: {scene.name}: cannot solve for radiosity: {error}", file=sys.stderr)
        return 1
    try:
        save(solution, args.out)
    except OSError as error:
        print(f"error: cannot write {args.out}: {error.strerror or error}", file=sys.stderr)
        return 2
    s = solution.stats
    print(f"wrote {args.out} ({s['elements']} elements, {s['patches']} patches, "
          f"{s['form factor rows']} form-factor rows, {time.perf_counter() - began:.2f} s, "
          f"scene {solution.scene_hash[:12]})")
    return 0
