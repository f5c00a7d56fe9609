"""The painter's renderers' options (``bsp``, ``depth-sort``): the BSP tree's root rule and,
for the draw-order slider, how many triangles of the painting order to paint.

Registered with both painters (``core/renderers/__init__.py``): ``settings.options_of("bsp")``,
``settings.replace(paint_first=10)``, and the command line's flags
(:meth:`PainterOptions.add_arguments`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from core.settings import BSP_ROOTS, require_one_of


@dataclass(frozen=True)
class PainterOptions:
    # Each field's metadata is what the window's panel shows beside it (app.session.options);
    # paint_first has the panel's draw-order slider instead.
    bsp_root: str = field(default="fewest-splits", metadata={
        "choices": BSP_ROOTS, "help": "how each BSP node's root triangle is chosen"})
    paint_first: int | None = field(default=None, metadata={"panel": False})

    def __post_init__(self) -> None:
        require_one_of("BSP root rule", self.bsp_root, BSP_ROOTS)
        if self.paint_first is not None and not isinstance(self.paint_first, int):
            raise ValueError(f"paint_first must be a whole number or None, "
                             f"not {self.paint_first!r}")

    @staticmethod
    def add_arguments(parser) -> None:
        """The command line's flags; None keeps the default."""
        g = parser.add_argument_group("the painter's renderers (bsp, depth-sort)")
        g.add_argument("--bsp-root", choices=BSP_ROOTS, default=None,
                       help="bsp: how each node's root triangle is chosen (default "
                            "fewest-splits: the notes' 'fewest branches'; first: the list's "
                            "head; random: seeded)")
        g.add_argument("--paint-first", type=int, default=None, metavar="K",
                       help="bsp, depth-sort: paint only the first K triangles of the order")

    @staticmethod
    def overrides(args) -> dict:
        paint_first = getattr(args, "paint_first", None)
        if paint_first is not None and paint_first < 0:
            raise ValueError(f"--paint-first must be 0 or more, not {paint_first}")
        return {"bsp_root": getattr(args, "bsp_root", None), "paint_first": paint_first}
