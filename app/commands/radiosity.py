"""``python -m app radiosity SCENE --out solution.npz``: solve once, save the solution keyed to
the scene's hash (``render --renderer radiosity --solution FILE`` draws from it; a file of
another scene is refused). Also the global-illumination options shared by ``render``."""

from __future__ import annotations

import sys
import time


def add_options(parser) -> None:
    """The radiosity and path-tracing settings; None keeps the defaults."""
    from core.settings import FORM_FACTOR_METHODS, SOLVERS
    g = parser.add_argument_group("global illumination (radiosity, pathtrace)")
    g.add_argument("--form-factors", choices=FORM_FACTOR_METHODS, default=None,
                   help="radiosity: the hemicube drawn by our z-buffer (default) or ray casting "
                        "through the BVH")
    g.add_argument("--hemicube-resolution", type=int, default=None, metavar="N",
                   help="radiosity: hemicube pixels per side (even; default 128)")
    g.add_argument("--solver", choices=SOLVERS, default=None,
                   help="radiosity: progressive refinement (default) or Gauss-Seidel")
    g.add_argument("--converge", type=float, default=None, metavar="FRACTION",
                   help="radiosity: stop when the unshot energy is below this fraction of the "
                        "emitted (default 0.01)")
    g.add_argument("--max-elements", type=int, default=None, metavar="N",
                   help="radiosity: element budget, adaptive subdivision included (default 2000)")
    if parser.prog.endswith("render"):
        g.add_argument("--solution", default=None, metavar="FILE.npz",
                       help="radiosity: draw from this saved solution (python -m app radiosity)")


def overrides(args) -> dict:
    return {"form_factors": args.form_factors, "hemicube_resolution": args.hemicube_resolution,
            "solver": args.solver, "converge": args.converge, "max_elements": args.max_elements}


def load_solution(scene, path, context) -> str | None:
    """Make the saved solution the one ``scene`` is drawn with; the error, or None."""
    from core.radiosity.mesh import RadiosityError
    from core.radiosity.renderer import use_solution
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
    add_options(parser)


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
        settings = RenderSettings.for_scene(scene, **overrides(args))
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
