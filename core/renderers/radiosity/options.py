"""Radiosity's options: how form factors are found, the hemicube's resolution, the solver,
its stopping point and the element budget of adaptive subdivision.

Registered with the ``radiosity`` renderer: ``settings.options_of("radiosity")``,
``settings.replace(max_elements=500)``, and the command line's flags
(:meth:`RadiosityOptions.add_arguments`, shared by ``render`` and ``radiosity``).
:class:`core.radiosity.solution.Options` is the solver's own form of them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from core.settings import FORM_FACTOR_METHODS, SOLVERS, require_one_of


@dataclass(frozen=True)
class RadiosityOptions:
    # Each field's metadata is what the window's panel shows beside it (app.session.options).
    form_factors: str = field(default="hemicube", metadata={
        "choices": FORM_FACTOR_METHODS, "help": "the hemicube, or rays cast through the BVH"})
    hemicube_resolution: int = field(default=128, metadata={
        "help": "hemicube pixels per side (even)"})
    solver: str = field(default="progressive", metadata={
        "choices": SOLVERS, "help": "progressive refinement or Gauss-Seidel"})
    converge: float = field(default=0.01, metadata={
        "help": "stop when this fraction of the emitted energy is still unshot"})
    max_elements: int = field(default=2000, metadata={
        "help": "the element budget, adaptive subdivision included"})

    def __post_init__(self) -> None:
        require_one_of("form factors", self.form_factors, FORM_FACTOR_METHODS)
        require_one_of("solver", self.solver, SOLVERS)
        r = self.hemicube_resolution
        if not (isinstance(r, int) and 8 <= r <= 4096 and r % 2 == 0):
            raise ValueError(f"hemicube resolution must be an even whole number from 8 to 4096, "
                             f"not {r!r}")
        if not 0.0 <= float(self.converge) < 1.0:
            raise ValueError(f"converge must be a fraction in [0, 1), not {self.converge!r}")
        if not (isinstance(self.max_elements, int) and 1 <= self.max_elements <= 1_000_000):
            raise ValueError(f"max elements must be a whole number from 1 to 1000000, "
                             f"not {self.max_elements!r}")

    @staticmethod
    def add_arguments(parser) -> None:
        """The command line's flags; None keeps the default."""
        g = parser.add_argument_group("radiosity")
        g.add_argument("--form-factors", choices=FORM_FACTOR_METHODS, default=None,
                       help="radiosity: the hemicube drawn by our z-buffer (default) or ray "
                            "casting through the BVH")
        g.add_argument("--hemicube-resolution", type=int, default=None, metavar="N",
                       help="radiosity: hemicube pixels per side (even; default 128)")
        g.add_argument("--solver", choices=SOLVERS, default=None,
                       help="radiosity: progressive refinement (default) or Gauss-Seidel")
        g.add_argument("--converge", type=float, default=None, metavar="FRACTION",
                       help="radiosity: stop when the unshot energy is below this fraction of "
                            "the emitted (default 0.01)")
        g.add_argument("--max-elements", type=int, default=None, metavar="N",
                       help="radiosity: element budget, adaptive subdivision included "
                            "(default 2000)")

    @staticmethod
    def overrides(args) -> dict:
        names = ("form_factors", "hemicube_resolution", "solver", "converge", "max_elements")
        return {name: getattr(args, name, None) for name in names}
