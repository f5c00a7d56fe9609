"""The ray tracer's options: what a scene, the command line and the window may set for it.

Registered with the ``raytrace`` renderer (``core/renderers/__init__.py``): the front door's
:class:`core.settings.RenderSettings` carries one of these (``settings.options_of("raytrace")``),
``settings.replace(max_depth=3)`` reaches it by its field's name, and the command line's flags
are this module's (:meth:`RaytraceOptions.add_arguments`). The notes' options:

- ``max_depth``: the ray tree's depth limit (the notes' 7);
- ``adaptive_epsilon``: the adaptive cut-off ε on the product of the k's;
- ``shadows``: what an object between a point and a light does (``SHADOW_MODES``);
- ``fresnel``, ``fresnel_form``: Fresnel weighting of k_r and k_t, Schlick's or exact;
- ``secondary_attenuation``: (C1, C2) of 1 / (1 + C1 R + C2 R²) over a secondary ray's length;
- ``adaptive_threshold``: adaptive supersampling's colour threshold (Whitted 1980).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from core.settings import FRESNEL_FORMS, SHADOW_MODES, require_one_of

MAX_DEPTH_LIMIT = 64


@dataclass(frozen=True)
class RaytraceOptions:
    # Each field's metadata is what the window's panel shows beside it (app.session.options):
    # the choices of a named option and a line of help.
    max_depth: int = field(default=7, metadata={"help": "the ray tree's depth limit"})
    adaptive_epsilon: float = field(default=1e-3, metadata={
        "help": "stop a branch when the product of its k's falls below this"})
    shadows: str = field(default="transmit", metadata={
        "choices": SHADOW_MODES, "help": "what an object between a point and a light does"})
    fresnel: bool = field(default=False, metadata={"help": "Fresnel weighting of k_r and k_t"})
    fresnel_form: str = field(default="schlick", metadata={
        "choices": FRESNEL_FORMS, "help": "Schlick's approximation or the exact equations"})
    secondary_attenuation: tuple[float, float] = field(default=(0.0, 0.0), metadata={
        "help": "C1, C2 of 1 / (1 + C1 R + C2 R^2) over a secondary ray's length R"})
    adaptive_threshold: float = field(default=0.1, metadata={
        "help": "adaptive supersampling: split a pixel whose corners differ by more"})

    def __post_init__(self) -> None:
        if not (isinstance(self.max_depth, int) and 1 <= self.max_depth <= MAX_DEPTH_LIMIT):
            raise ValueError(f"max_depth must be a whole number from 1 to {MAX_DEPTH_LIMIT}, "
                             f"not {self.max_depth!r}")
        if not (isinstance(self.adaptive_epsilon, (int, float))
                and 0.0 <= self.adaptive_epsilon <= 1.0):
            raise ValueError(f"adaptive_epsilon must be a number in [0, 1], "
                             f"not {self.adaptive_epsilon!r}")
        require_one_of("shadows", self.shadows, SHADOW_MODES)
        require_one_of("fresnel", self.fresnel_form, FRESNEL_FORMS)
        c1, c2 = (float(c) for c in self.secondary_attenuation)
        if not (0.0 <= c1 < math.inf and 0.0 <= c2 < math.inf):
            raise ValueError(f"the secondary rays' attenuation C1, C2 must be finite and >= 0, "
                             f"not {self.secondary_attenuation!r}")
        if not (0.0 <= float(self.adaptive_threshold) <= 1.0):
            raise ValueError(f"the adaptive threshold must be from 0 to 1, "
                             f"not {self.adaptive_threshold!r}")
        object.__setattr__(self, "secondary_attenuation", (c1, c2))

    @staticmethod
    def add_arguments(parser) -> None:
        """The command line's flags; None keeps the default."""
        parser.add_argument("--shadows", choices=SHADOW_MODES, default=None,
                            help="raytrace: what an object between a point and a light does "
                                 "(default transmit: attenuate by k_t)")
        parser.add_argument("--max-depth", type=int, default=None,
                            help="raytrace: the ray tree's depth limit (default 7)")
        parser.add_argument("--fresnel", nargs="?", const="schlick", default=None,
                            choices=FRESNEL_FORMS,
                            help="raytrace: Fresnel weighting of k_r and k_t, Schlick's "
                                 "approximation (the default form) or the exact equations")
        parser.add_argument("--adaptive-threshold", type=float, default=None, metavar="T",
                            help="raytrace, --samples adaptive: split a pixel whose corners "
                                 "differ by more than T (0-1, any channel; default 0.1)")
        parser.add_argument("--attenuation", type=float, nargs=2, default=None,
                            metavar=("C1", "C2"),
                            help="raytrace: attenuate a secondary ray's light by "
                                 "1 / (1 + C1 R + C2 R^2) over its length R (default off)")

    @staticmethod
    def overrides(args) -> dict:
        """The fields the command line's flags set (None: not given)."""
        fresnel = getattr(args, "fresnel", None)
        attenuation = getattr(args, "attenuation", None)
        return {"shadows": getattr(args, "shadows", None),
                "max_depth": getattr(args, "max_depth", None),
                "fresnel": None if fresnel is None else True, "fresnel_form": fresnel,
                "adaptive_threshold": getattr(args, "adaptive_threshold", None),
                "secondary_attenuation": None if attenuation is None else tuple(attenuation)}
