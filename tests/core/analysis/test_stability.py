"""The stability suite (core/analysis/stability.py, the code behind ``python -m app stability``) and the
exact rational chain it measures against (core/analysis/exact.py)."""

from __future__ import annotations

import json
from fractions import Fraction
from types import SimpleNamespace

import numpy as np
import pytest

from core.analysis import exact
from core.analysis import stability, stability_kit
from core.camera.view import View, n_par_factors, n_per_factors

WORKED = View(vrp=(0, 0, 54), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 17, -1, 17),
              prp=(8, 6, 30), front=10, back=-50)
F = Fraction


# --- core/analysis/exact.py against hand values ---------------------------------------------------

def test_worked_example_factors_are_exact_fractions():
    f = exact.n_per_factors(WORKED)
    assert f["S_per"] == exact.scale(F(1, 24), F(1, 24), F(1, 80))
    assert f["SH_par"][1][2] == F(1, 15) and f["SH_par"][0][2] == 0          # DOP = (0, 2, -30)
    assert f["T_vrp"] == exact.translate(0, 0, -54)
    assert f["T_prp"] == exact.translate(-8, -6, -30)
    assert f["R"] == exact.identity()
    # z_min = -(vrp'_z + F)/(vrp'_z + B) = -(-30 + 10)/(-30 - 50) = -1/4
    assert f["z_min"] == F(-1, 4)
    # N_per by hand: rows of S_per · SH_par · T(-PRP) · T(-VRP) (the shear adds z/15 to y).
    assert f["N_per"] == ((F(1, 24), 0, 0, F(-8, 24)),
                          (0, F(1, 24), F(1, 360), F(-6 - F(84, 15), 24)),
                          (0, 0, F(1, 80), F(-84, 80)),
                          (0, 0, 0, 1))


def test_float_chain_is_the_exact_chain_rounded():
    for factors, exact_factors, name in ((n_per_factors, exact.n_per_factors, "N_per"),
                                         (n_par_factors, exact.n_par_factors, "N_par")):
        floats = factors(WORKED)[name]
        # a few rounding errors of a unit round-off each, column by column
        assert exact.relative_error(floats, exact_factors(WORKED)[name]) <= 4 * stability.U


def test_parallel_worked_example():
    f = exact.n_par_factors(WORKED)
    # T_par = T(-8, -8, -10), S_par = S(2/18, 2/18, 1/60)
    assert f["T_par"] == exact.translate(-8, -8, -10)
    assert f["S_par"] == exact.scale(F(1, 9), F(1, 9), F(1, 60))


def test_sqrt_is_exact_for_squares_and_precise_otherwise():
    assert exact.sqrt(F(9, 16)) == F(3, 4)
    assert exact.sqrt(F(0)) == 0
    root2 = exact.sqrt(F(2))
    assert abs(root2 * root2 - 2) < F(1, 2 ** 300)
    # a unit vector along (1, 2, 2) is exactly (1, 2, 2)/3
    assert exact.unit((F(1), F(2), F(2))) == (F(1, 3), F(2, 3), F(2, 3))
    with pytest.raises(ValueError):
        exact.q(float("nan"))


def test_power_is_exact_for_whole_exponents():
    assert exact.power(F(1, 2), F(10)) == F(1, 1024)
    assert exact.power(F(0), F(0)) == 1
    near = exact.power(F(9999, 10000), F(10000))
    assert abs(float(near) - (0.9999 ** 10000)) < 1e-12
    assert abs(float(exact.power(F(1, 4), F(1, 2))) - 0.5) < 1e-15     # through decimal


def test_chain_projects_the_vrp_of_the_worked_example():
    # The VRP (0, 0, 54) lies on the view plane at window (0, 0), 1/18 of the way across
    # (-1, 17): canonical (-1/3, -1/3, -3/8); after M (z_min = -1/4) and /W (W = 3/8),
    # (-8/9, -8/9, -4/9); on a 500 x 500 viewport x = y = 500/18.
    canonical, device = exact.chain(exact.view_numbers(WORKED), [(F(0), F(0), F(54))],
                                    "perspective", (0, 500, 0, 500))
    assert canonical[0] == (F(-1, 3), F(-1, 3), F(-3, 8))
    assert device[0] == (F(250, 9), F(250, 9), F(-4, 9))
    # the eye itself (PRP in world coordinates) has W = 0: no device coordinates
    _, device = exact.chain(exact.view_numbers(WORKED), [(F(8), F(6), F(84))], "perspective",
                            (0, 500, 0, 500))
    assert device[0] is None


def test_relative_error_and_condition():
    exact_rows = [(F(1), F(2)), (F(-3), F(0))]
    assert exact.relative_error([[1.0, 2.0], [-3.0, 0.0]], exact_rows) == 0.0
    assert exact.relative_error([[1.0, 2.0], [-3.0 + 3e-15, 0.0]], exact_rows) == pytest.approx(1e-15, rel=0.1)
    assert exact.relative_error([[np.nan, 2.0], [-3.0, 0.0]], exact_rows) == float("inf")
    # x - y near x = y is ill-conditioned: κ ≈ (|x| + |y|)/|x - y|
    kappa = exact.condition(lambda v: [[[v[0] - v[1]]]], [F(1), F(1) - F(1, 10 ** 6)])
    assert 1e6 <= kappa <= 2.1e6
    assert exact.condition(lambda v: [[[v[0] * v[1]]]], [F(3), F(5)]) <= 2.0


# --- the suite ----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def results():
    return stability.run_suite()


def test_every_extreme_input_the_suite_promises_is_there():
    names = " ".join(c.name for c in stability.CASES)
    for words in ("1e-6", "offset by 1e8", "VUP 1e-9", "PRP", "1e-9 wide", "1e9 wide", "sliver",
                  "edge-on", "zero-area", "duplicate", "clip plane", "at the eye", "cancel",
                  "exponent 1e4", "distance 0", "zero-intensity", "bright", "NaN and inf"):
        assert words in names, words


@pytest.mark.slow
def test_every_case_passes(results):
    failed = [f"{r.name}: {r.measured}" for r in results if not r.passed]
    assert not failed, "\n".join(failed)


@pytest.mark.slow
def test_well_conditioned_cases_agree_with_exact_arithmetic(results):
    rows = [r for r in results if r.error is not None and r.conditioning.startswith("well")]
    assert len(rows) >= 8
    for r in rows:
        assert r.error <= stability.TOLERANCE, r
    # the ill-conditioned ones say so and show the error against κ·u
    ill = {r.name for r in results if r.conditioning.startswith("ill")}
    assert {"coordinates offset by 1e8", "VUP 1e-9 rad from VPN", "sliver triangles (aspect 1e-9)"} <= ill


def test_a_silent_nan_is_a_failure_with_its_message():
    def bad():
        np.zeros(1) / np.zeros(1)                # raises under the case's errstate
        return stability.Outcome()
    result = stability.run_case(stability.Case("nan", "never NaN", bad))
    assert not result.passed and result.measured.startswith("FloatingPointError")


def test_accuracy_judgement():
    out = stability.Outcome()
    out.accuracy(5e-10, 10.0, "x")
    assert stability.judge(out)[0]
    out = stability.Outcome()
    out.accuracy(2e-9, 10.0, "x")                  # well-conditioned but above 1e-9
    assert not stability.judge(out)[0]
    out = stability.Outcome()
    out.accuracy(1e-8, 1e9, "x")                   # ill-conditioned: bound 100·κ·u ≈ 1.1e-5
    ok, note = stability.judge(out)
    assert ok and note.startswith("ill-conditioned")


def test_one_pixel_mismatches():
    a = np.zeros((8, 8, 3), np.uint8)
    b = a.copy()
    a[3, 3] = 200
    b[3, 4] = 200                                 # moved by one pixel: matches
    assert stability_kit.one_pixel_mismatches(a, b) == 0
    b[3, 4] = 0
    b[6, 6] = 200                                 # moved by three: both unmatched
    assert stability_kit.one_pixel_mismatches(a, b) == 2
    b = a.copy()
    b[3, 3] = 199                                 # one level: matches
    assert stability_kit.one_pixel_mismatches(a, b) == 0


@pytest.mark.slow
def test_command_prints_the_table_and_json(results, capsys, monkeypatch):
    from app.commands import stability as command
    monkeypatch.setattr(stability, "run_suite", lambda progress=None: results)
    assert command.main(SimpleNamespace(json=False)) == 0
    table = capsys.readouterr().out
    assert "PASS" in table and "ill-conditioned" in table and f"{len(results)} of {len(results)} cases pass" in table
    assert command.main(SimpleNamespace(json=True)) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["failed"] == 0 and len(data["cases"]) == len(results)


def test_command_exit_status_is_one_when_a_case_fails(capsys, monkeypatch):
    from app.commands import stability as command
    failing = [stability.Result(name="x", expected="y", measured="z", passed=False)]
    monkeypatch.setattr(stability, "run_suite", lambda progress=None: failing)
    assert command.main(SimpleNamespace(json=False)) == 1
    assert "FAIL" in capsys.readouterr().out
