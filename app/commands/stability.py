"""``python -m app stability [--json]``: the stiff and extreme cases, PASS/FAIL.

Runs :func:`core.analysis.stability.run_suite` (the same code
``tests/core/analysis/test_stability.py`` asserts) and prints one block per case: the result,
the relative error against exact rational arithmetic, the condition number κ and whether the
case is well- or ill-conditioned, then what is expected
and what was measured. ``--json`` prints the same as one JSON object. Progress goes to stderr.
The exit status is 1 when any case fails, 0 otherwise.
"""

from __future__ import annotations

import json
import shutil
import sys
import textwrap

from core.analysis import stability


def _number(x: float | None) -> str:
    return "-" if x is None else f"{x:.1e}"


def format_table(results: list[stability.Result], width: int = 100) -> str:
    """The results as a fixed-width table with the expected and measured text wrapped below."""
    name_width = max(len(r.name) for r in results)
    head = (f"{'#':>2}  {'case':<{name_width}}  result  {'error':>7}  {'κ':>7}  {'κ·u':>7}  "
            f"conditioning")
    lines = [head, "-" * min(width, len(head) + 40)]
    for k, r in enumerate(results, start=1):
        kappa_u = None if r.condition is None else r.condition * stability.U
        note = r.conditioning.split(" (")[0]
        lines.append(f"{k:>2}  {r.name:<{name_width}}  {'PASS' if r.passed else 'FAIL':<6}  "
                     f"{_number(r.error):>7}  {_number(r.condition):>7}  {_number(kappa_u):>7}  "
                     f"{note}")
        for label, text in (("expected", r.expected), ("measured", r.measured),
                            ("accuracy", f"{r.quantity}: {r.conditioning}" if r.quantity else "")):
            if text:
                lines += textwrap.wrap(text, width=width, initial_indent=f"    {label}: ",
                                       subsequent_indent=" " * 14)
    passed = sum(r.passed for r in results)
    lines.append("")
    lines.append(f"{passed} of {len(results)} cases pass (well-conditioned: error <= "
                 f"{stability.TOLERANCE:g} relative; ill-conditioned: error <= "
                 f"{stability.GROWTH:g}·κ·u, u = 2^-53)")
    return "\n".join(lines)


def as_json(results: list[stability.Result]) -> dict:
    return {"tolerance": stability.TOLERANCE, "growth": stability.GROWTH, "unit_roundoff": stability.U,
            "passed": sum(r.passed for r in results), "failed": sum(not r.passed for r in results),
            "cases": [r.as_dict() for r in results]}


def main(args) -> int:
    def progress(name: str) -> None:
        print(f"stability: {name} ...", file=sys.stderr, flush=True)

    results = stability.run_suite(progress=progress)
    if getattr(args, "json", False):
        print(json.dumps(as_json(results), indent=2, ensure_ascii=False))
    else:
        print(format_table(results, width=max(80, shutil.get_terminal_size((110, 24)).columns - 2)))
    return 0 if all(r.passed for r in results) else 1
