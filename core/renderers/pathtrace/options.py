"""The path tracer's options: how each pixel's paths draw their random numbers.

Registered with the ``pathtrace`` renderer: ``settings.options_of("pathtrace")``,
``settings.replace(sampler="independent")``, the command line's ``--path-sampler`` and the
window's panel (each field's metadata).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from core.settings import require_one_of

# "stratified": the first hit's light sample and bounce direction of a pixel's k-th path are
# point k of a shifted R3 sequence (core.pathtrace.kernel); "independent": every number from
# splitmix64, as plain Monte Carlo draws them. Both are unbiased.
SAMPLERS = ("stratified", "independent")


@dataclass(frozen=True)
class PathtraceOptions:
    # Each field's metadata is what the window's panel shows beside it (app.session.options).
    sampler: str = field(default="stratified", metadata={
        "choices": SAMPLERS,
        "help": "the first bounce's numbers stratified over a pixel's passes (noise falls "
                "faster) or independent (plain Monte Carlo)"})

    def __post_init__(self) -> None:
        require_one_of("path sampler", self.sampler, SAMPLERS)

    @staticmethod
    def add_arguments(parser) -> None:
        """The command line's flags; None keeps the default."""
        g = parser.add_argument_group("path tracer")
        g.add_argument("--path-sampler", choices=SAMPLERS, default=None, dest="sampler",
                       help="pathtrace: stratified (default: each pixel's first bounce over "
                            "its passes from a shifted R3 sequence) or independent (plain "
                            "Monte Carlo)")

    @staticmethod
    def overrides(args) -> dict:
        return {"sampler": getattr(args, "sampler", None)}
