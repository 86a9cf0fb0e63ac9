"""The matched-accuracy rule of the benchmarks (`benchmarks/methods.py`: `fine_grid`, `find_matched`).

Expected answers follow by hand from the rule stated in `find_matched`'s docstring: the loosest grid rtol
whose error is <= the target and stays so at every grid rtol down to a tenth of it.
"""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from methods import fine_grid, find_matched  # noqa: E402

MATCH = 1e-7
GRID = fine_grid(1e-5, 1e-12)


def _getter(errors: dict):
    calls = []

    def get(rtol):
        calls.append(rtol)
        return dict(ok=True, err=errors[rtol], rtol=rtol)

    return get, calls


def test_fine_grid_is_the_1_2_5_sequence():
    assert GRID[:4] == (1e-5, 5e-6, 2e-6, 1e-6)
    assert GRID[-3:] == (5e-12, 2e-12, 1e-12)
    assert len(GRID) == 3 * 7 + 1


def test_a_lucky_rtol_does_not_count():
    # scipy Radau, 10-mass gapped Tsuji stack (benchmark run of 2026-11-23): 1e-6 lands at 1.3e-8 by luck,
    # 5e-7 and 2e-7 do not reach 1e-7; from 1e-7 on every rtol does (tighter errors set to 1e-9 here).
    errors = {r: 1e-9 for r in GRID}
    errors.update({1e-5: 1.2e-4, 5e-6: 1.7e-5, 2e-6: 6.0e-6, 1e-6: 1.3e-8, 5e-7: 4.2e-7, 2e-7: 2.1e-7, 1e-7: 5.8e-8})
    get, _ = _getter(errors)
    assert find_matched(get, GRID, MATCH)["rtol"] == 1e-7


def test_monotone_errors_match_at_the_first_rtol_that_reaches_the_target_and_solve_lazily():
    errors = {r: 900 * r for r in GRID}  # error = 900 rtol: 1e-7 is reached from rtol = 1e-10 on
    get, calls = _getter(errors)
    assert find_matched(get, GRID, MATCH)["rtol"] == 1e-10
    # every rtol loose to tight once, and nothing tighter than the tenth of the answer
    assert sorted(set(calls), reverse=True) == [r for r in GRID if r >= 1e-11]


def test_a_failure_within_the_decade_below_moves_the_match_tighter():
    errors = {r: 1e-9 for r in GRID}
    errors.update({r: 1e-6 for r in GRID if r >= 1e-9})
    errors[2e-10] = 2e-7  # 5e-10 reaches 1e-7, but 2e-10 (within its decade) does not
    get, _ = _getter(errors)
    assert find_matched(get, GRID, MATCH)["rtol"] == 1e-10


@pytest.mark.parametrize(
    "errors, expected",
    [
        ({1e-6: 1e-8, 1e-8: 1e-6, 1e-10: 1e-9}, 1e-10),  # coarse grid: the next rtol decides; the last stands alone
        ({1e-6: 1e-8, 1e-8: 1e-8, 1e-10: 1e-6}, 1e-6),
        ({1e-6: 1e-5, 1e-8: 1e-6, 1e-10: 1e-6}, None),
    ],
)
def test_coarse_grid(errors, expected):
    get, _ = _getter(errors)
    m = find_matched(get, (1e-6, 1e-8, 1e-10), MATCH)
    assert (m and m["rtol"]) == expected


def test_failed_runs_never_match():
    def get(rtol):
        return dict(ok=False, err=float("inf"), rtol=rtol)

    assert find_matched(get, GRID, MATCH) is None


def test_numba_baseline_integrates_the_library_equations():
    """The issue-22 baselines (`benchmarks/baselines.py`) integrate the same equations: the numba field
    equals the library's scaled field at random states (with and without the onset proxies) to 1e-12,
    and the numba Tsit5 loop with the library's controller gives the library's launch velocity to the
    tolerance's own level (1e-7 at rtol 1e-10; measured 1e-8 on n = 5: the two step sequences part at a
    contact onset by rounding, then both meet the tolerance)."""
    import baselines as bl

    import hertz_chain as hc

    c = bl.Case(2, "gapped-tsuji")
    assert c.check_field(samples=5) < 1e-12
    rtol = 1e-10
    # the numba loop is the plain algorithm: the library's without landing its onsets
    sol = hc.simulate(c.stack, c.state, tolerances=hc.Tolerances(rtol=rtol, atol=rtol, land_onsets=False))
    y, steps, _ = bl.tsit5(c.y0p, sol.t_final / c.T, rtol, rtol, bl.MAX_STEP, bl.FIRST_STEP, *c.args,
                           bl._A, bl._B, bl._E)
    assert abs(y[2 * c.n - 1] * c.V / float(sol.launch_velocities[-1]) - 1) < 1e-7
    assert abs(steps / int(sol.num_steps) - 1) < 0.1
