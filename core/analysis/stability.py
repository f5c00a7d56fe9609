"""Stiff and extreme cases for the whole pipeline, each with its expected behaviour.

Takes nothing; :func:`run_suite` returns one :class:`Result` per case: its name, what is
expected, what was measured, the relative error of the float64 pipeline against exact rational
arithmetic (:mod:`core.analysis.exact`) where the case has numbers to compare, the condition number of
the problem, a note whether the case is well- or ill-conditioned, and PASS/FAIL.
``python -m app stability`` prints the same results (``app/commands/stability.py``) and
``tests/core/analysis/test_stability.py`` asserts them: one code path.

How a case is judged:

- its own checks (the image, the message, the depth order, ...) must all hold;
- every case runs under ``np.errstate(all="raise", under="ignore")``, so a silent NaN, an
  overflow or a division by zero anywhere in numpy code is an exception, reported as FAIL with
  its message; the compiled stages cannot raise, so :func:`probe` renders through the real
  pipeline with ``render``'s inspect hook and checks that every array between the stages is
  finite;
- accuracy: with κ the componentwise relative condition number of the case's quantities
  (estimated exactly, :func:`core.analysis.exact.condition`) and u = 2⁻⁵³ the unit round-off, a case
  is **well-conditioned** when κ·u <= ``TOLERANCE / GROWTH`` (1e-11), and then the float64
  results must agree with exact arithmetic to ``TOLERANCE`` = 1e-9 relative; otherwise it is
  **ill-conditioned**: no algorithm can promise 1e-9 there, and the table shows the measured
  error against κ·u, which it must not exceed by more than ``GROWTH`` = 100 (what a
  backward-stable chain of a few dozen operations delivers).

Images are compared "within one pixel" (:func:`one_pixel_mismatches`): a pixel matches when the
other image has a pixel within one (8-neighbourhood or itself) whose channels differ by at most
one level. Coverage is read off an image whose background is black: every case's lighting has
an ambient term of at least one level, so a covered pixel is never black.
"""

from core.analysis import stability_cases  # noqa: F401  (registers the cases)
from core.analysis.stability_kit import (CASES, GROWTH, TOLERANCE, U, Case, Outcome, Result,
                                         judge, run_case, run_suite)

__all__ = ["CASES", "GROWTH", "TOLERANCE", "U", "Case", "Outcome", "Result", "judge", "run_case",
           "run_suite"]
