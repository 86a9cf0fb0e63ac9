"""Closed forms of the seed paper (Eqs 1–30) and the MVG/MET designs (hertz_chain.rigid).

Every expected number is named beside it: a paper equation or figure, `docs/references.md`, or an
independent computation in the test itself (a linear solve of Eqs 1–2, scipy root finding or
minimisation, direct sums of Eq 25). The misprints of Eqs 8, 23 and 24 are re-derived here, and the
printed forms are shown to disagree.
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from hertz_chain import rigid
from hertz_chain.errors import ParameterError

RNG = np.random.default_rng(20240601)


def _two_body(m1, m2, v1, v2, e):
    """Independent solve of Eqs 1–2 as a 2x2 linear system for (V1, V2)."""
    a = np.array([[m1, m2], [-1.0, 1.0]])
    b = np.array([m1 * v1 + m2 * v2, -e * (v2 - v1)])
    return np.linalg.solve(a, b)


# ------------------------------------------------------------------------------------------------
# Section 2: two masses


def test_impact_velocities_and_gains_match_eqs_1_to_4():
    for _ in range(50):
        m1, m2 = RNG.uniform(0.1, 10, 2)
        v1 = RNG.uniform(0.5, 3)
        v2 = RNG.uniform(-5, 0.9) * v1  # g < 1: the bodies collide
        e = RNG.uniform(0.05, 1)
        ref = _two_body(m1, m2, v1, v2, e)  # Eqs 1-2, linear solve
        got = rigid.impact_velocities(m1, m2, v1, v2, e)
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)
        a1, a2 = rigid.velocity_gains(m2 / m1, v2 / v1, e)  # Eqs 3-4
        np.testing.assert_allclose([a1 * v1, a2 * v2], ref, rtol=1e-12, atol=1e-12)


def test_eq7_m1_at_rest_derived_by_root_finding():
    # Eq 7: g such that V1 = 0, found with brentq on V1(g) from the linear solve of Eqs 1-2
    for r, e in [(0.3, 0.8), (0.5, 0.5), (0.9, 1.0)]:
        g_root = brentq(lambda g: _two_body(1.0, r, 1.0, g, e)[0], -1e3, 1 - 1e-12, xtol=1e-14)
        assert rigid.velocity_ratio_m1_at_rest(r, e) == pytest.approx(g_root, rel=1e-10)


def test_eq8_misprint_m2_at_rest_derived_by_root_finding():
    # Eq 8 (paper): g = (1+e)/(e - r_{2,3}). Derivation: solve Eq 4 / Eqs 1-2 for V2 = 0 with brentq.
    # A root in the collision range g < 1 exists for r > e (then g < 0, head-on).
    m1, m2, m3 = 4.0, 3.6, 1.2  # a three-mass chain, so that the printed r_{2,3} = m2/m3 has a value
    r21, r23 = m2 / m1, m2 / m3
    for e in [0.3, 0.5, 0.8]:
        g_root = brentq(lambda g: _two_body(m1, m2, 1.0, g, e)[1], -1e6, -1e-9, xtol=1e-15, rtol=1e-15)
        corrected = (1 + e) / (e - r21)  # g = (1+e)/(e - r_{2,1})
        printed = (1 + e) / (e - r23)
        assert rigid.velocity_ratio_m2_at_rest(r21, e) == pytest.approx(g_root, rel=1e-10)
        assert corrected == pytest.approx(g_root, rel=1e-10)
        assert abs(printed - g_root) > 0.5 * abs(g_root)  # the printed form is not a root
        assert abs(_two_body(m1, m2, 1.0, printed, e)[1]) > 0.1


def test_eq9_target_at_rest():
    # Eq 9: V1 = v2 = 0 needs r = 1/e (Eq 7 at g = 0) and then G2 = 1/r = e
    for e in [0.3, 0.7, 1.0]:
        r = 1 / e
        v1_after, v2_after = _two_body(1.0, r, 1.0, 0.0, e)
        assert v1_after == pytest.approx(0.0, abs=1e-14)
        assert v2_after == pytest.approx(e, rel=1e-14)
        assert rigid.gain_target_at_rest(r, e) == pytest.approx(e, rel=1e-14)
    # general target at rest: the factor (1+e)/(1+r) of Eq 13
    assert rigid.gain_target_at_rest(0.25, 0.8) == pytest.approx(_two_body(1.0, 0.25, 1.0, 0.0, 0.8)[1], rel=1e-14)


def test_energy_efficiencies_eqs_10_to_12():
    r = RNG.uniform(0.01, 3, 40)
    g = RNG.uniform(-4, 0.95, 40)
    e = RNG.uniform(0.1, 1, 40)
    k1, k2 = rigid.energy_efficiencies(r, g, e)
    for i in range(40):  # definition of K (Section 2.1) with velocities from the linear solve
        V1, V2 = _two_body(1.0, r[i], 1.0, g[i], e[i])
        ke0 = 0.5 * (1.0 + r[i] * g[i] ** 2)
        assert k1[i] == pytest.approx(0.5 * V1**2 / ke0, rel=1e-11, abs=1e-15)
        assert k2[i] == pytest.approx(0.5 * r[i] * V2**2 / ke0, rel=1e-11, abs=1e-15)
    # K1 + K2 = 1 for e = 1 (text after Eq 11)
    k1, k2 = rigid.energy_efficiencies(r, g, 1.0)
    np.testing.assert_allclose(k1 + k2, 1.0, rtol=1e-13)
    # Eq 12 from Eq 11 at g = 0
    _, k2 = rigid.energy_efficiencies(r, 0.0, e)
    np.testing.assert_allclose(k2, r * (1 + e) ** 2 / (1 + r) ** 2, rtol=1e-14)


# ------------------------------------------------------------------------------------------------
# Section 3: horizontal chain


def test_eq13_chain_gain_equals_sequential_two_body_impacts():
    for _ in range(20):
        n = RNG.integers(2, 9)
        m = np.sort(RNG.uniform(0.05, 5, n))[::-1]
        e = RNG.uniform(0.2, 1, n)
        v = 1.0
        for k in range(1, n):  # m_k (moving) strikes m_{k+1} at rest: Eqs 1-2
            v = _two_body(m[k - 1], m[k], v, 0.0, e[k])[1]
        assert rigid.chain_gain(m, e) == pytest.approx(v, rel=1e-12)
        assert rigid.cascade_velocities(m, e)[0][-1] == pytest.approx(v, rel=1e-12)


def test_eqs_16_17_mvg_chain():
    for R, e, n in [(0.012, 0.8, 6), (0.1, 0.5, 3), (1e-4, 0.95, 20)]:
        m = rigid.mvg_masses(R, n)
        assert m[-1] == pytest.approx(R, rel=1e-13)  # Eq 14
        np.testing.assert_allclose(m[1:] / m[:-1], R ** (1 / (n - 1)), rtol=1e-13)  # Eq 15
        g13 = rigid.chain_gain(m, e)  # Eq 13 with the masses
        assert rigid.mvg_chain_gain(R, e, n) == pytest.approx(g13, rel=1e-12)  # Eq 16
        # Eq 17: K_n = top kinetic energy / kinetic energy of m1, from the cascade velocities
        v_top = rigid.cascade_velocities(m, e)[0][-1]
        assert rigid.mvg_chain_efficiency(R, e, n) == pytest.approx(m[-1] * v_top**2 / m[0], rel=1e-12)


@pytest.mark.parametrize("R", [0.3, 0.012, 1e-4])
def test_elastic_limits_eq18_eq21(R):
    # (1+R^{1/m})^m = 2^m sqrt(R) (1 + ln^2 R/(8m) + ...): relative error ~ ln^2R/(8m) <= 1.1e-6 at m = 1e7
    n = 10_000_001
    assert rigid.mvg_chain_gain(R, 1.0, n) == pytest.approx(1 / np.sqrt(R), rel=1e-5)  # Eq 18
    assert rigid.mvg_chain_gain_limit(R) == pytest.approx(1 / np.sqrt(R), rel=1e-15)
    assert rigid.mvg_gain(R, 1.0, n) == pytest.approx((2 - np.sqrt(R)) / np.sqrt(R), rel=1e-5)  # Eq 21
    assert rigid.mvg_gain_limit(R) == pytest.approx((2 - np.sqrt(R)) / np.sqrt(R), rel=1e-15)
    g = rigid.mvg_gain(R, 1.0, np.array([2, 5, 20, 100, 1000]))  # increases monotonically for e = 1
    assert np.all(np.diff(g) > 0) and np.all(g < rigid.mvg_gain_limit(R))
    # Eq 18's meaning: all of m1's energy reaches the top, K_n = R G_n^2 -> 1
    assert rigid.mvg_chain_efficiency(R, 1.0, n) == pytest.approx(1.0, rel=1e-5)


# ------------------------------------------------------------------------------------------------
# Section 4: vertical stack


def test_eq19_stack_gain_equals_dropped_cascade_including_active_ground():
    for _ in range(20):
        n = RNG.integers(2, 9)
        m = np.sort(RNG.uniform(0.05, 5, n))[::-1]
        e = RNG.uniform(0.2, 1, n)
        for e0 in [e[0], 1.5]:  # 1.5: 'active ground' (text after Eq 19)
            v = e0 * 1.0  # v_ff = 1: m1 leaves the ground at e0
            for k in range(1, n):  # m_{k+1} still falls at -1 when struck
                v = _two_body(m[k - 1], m[k], v, -1.0, e[k])[1]
            assert rigid.stack_gain(m, e, ground_restitution=e0) == pytest.approx(v, rel=1e-12)
    m = rigid.mvg_masses(0.012, 6)  # restitution[0] is the ground when ground_restitution is None
    assert rigid.stack_gain(m, 0.8) == pytest.approx(rigid.mvg_gain(0.012, 0.8, 6), rel=1e-13)  # Eq 20


def test_harter_light_mass_limit():
    # Harter 1971 (docs/references.md): elastic stack with vanishing mass ratios launches the top at (2^n - 1) v0
    for n in range(2, 8):
        m = 1e-7 ** np.arange(n)
        assert rigid.stack_gain(m, 1.0) == pytest.approx(2**n - 1, rel=1e-5)
        assert rigid.cascade_velocities(m, 1.0, 1.0)[0][-1] == pytest.approx(2**n - 1, rel=1e-5)


def test_mvg_power_law_is_optimal_for_fixed_n_and_R():
    # Eq 15 maximises Eq 13 / Eq 19 for given n and R (Hart & Herrmann; Section 3.1): random ratios
    # with the same product never beat it (evaluated directly from Eq 13 / Eq 19).
    for R, e, n in [(0.012, 0.8, 6), (0.05, 0.6, 4), (1e-3, 0.95, 10)]:
        best19 = rigid.mvg_gain(R, e, n)
        best13 = rigid.mvg_chain_gain(R, e, n)
        w = RNG.dirichlet(np.ones(n - 1), size=2000)  # log-ratios summing to ln R
        ratios = np.exp(w * np.log(R))
        m = np.concatenate([np.ones((2000, 1)), np.cumprod(ratios, axis=1)], axis=1)
        assert np.all(rigid.stack_gain(m, e) <= best19 * (1 + 1e-13))
        assert np.all(rigid.chain_gain(m, e) <= best13 * (1 + 1e-13))
        assert rigid.stack_gain(rigid.mvg_masses(R, n), e) == pytest.approx(best19, rel=1e-12)


def test_fig17_optimal_mvg_for_R_0012():
    # Fig 17: R = 0.012, e = 0.8 -> the optimal MVG stack has 6 masses;
    # docs/references.md: G(MVG, n = 6) = 5.0407 (Eq 20)
    assert rigid.mvg_optimal_n(0.012, 0.8) == 6
    assert rigid.mvg_optimal_n_pb(0.012, 0.8) == 6
    assert rigid.mvg_gain(0.012, 0.8, 6) == pytest.approx(5.0407, abs=1e-4)
    # brute force over n (independent of the unimodal search)
    n = np.arange(2, 400)
    assert n[np.argmax(rigid.mvg_gain(0.012, 0.8, n))] == 6


def test_mvg_velocity_gain_threshold_near_035():
    # Section 4.1: for R = 0.012 there is no velocity amplification (max_n G_n <= 1) for e < 0.35.
    # brentq on max_n G_n(e) - 1 (continuous in e) gives e* = 0.3503; tolerance 0.005.
    n = np.arange(2, 200)

    def excess(e):
        return np.max(rigid.mvg_gain(0.012, e, n)) - 1

    e_star = brentq(excess, 0.2, 0.6, xtol=1e-10)
    assert e_star == pytest.approx(0.35, abs=0.005)
    assert rigid.mvg_gain(0.012, e_star, rigid.mvg_optimal_n(0.012, e_star)) == pytest.approx(1.0, abs=1e-8)


def _eq20_real_n(R, e, n):
    """Eq 20 continued to real n, written independently in log form (the powers overflow separately)."""
    return math.exp(n * math.log1p(e) - (n - 1) * math.log1p(R ** (1 / (n - 1)))) - 1


def test_eq23_misprint_derived_from_maximising_eq20():
    # Maximise Eq 20 over continuous n (minimize_scalar); the optimum's x = R^{1/(n-1)} satisfies
    # 1 + x = (1+e) x^{x/(1+x)} (corrected Eq 23), not the printed x^{x/1+x} = x^{2x}.
    for R, e in [(0.012, 0.8), (1e-4, 0.6), (0.2, 0.95)]:
        f = lambda n: -_eq20_real_n(R, e, n)
        res = minimize_scalar(f, bounds=(1.5, 60), method="bounded", options={"xatol": 1e-10})
        x_opt = R ** (1 / (res.x - 1))
        x0 = rigid.optimal_pair_ratio(e)
        assert x0 == pytest.approx(x_opt, rel=1e-6)
        assert 1 + x0 == pytest.approx((1 + e) * x0 ** (x0 / (1 + x0)), rel=1e-13)  # corrected Eq 23
        printed = lambda x: (1 + x) - (1 + e) * x ** (x / 1 + x)  # the literal print: exponent x + x
        assert abs(printed(x_opt)) > 1e-2
        x_printed = brentq(printed, 1e-12, 1 - 1e-12)
        assert abs(x_printed - x_opt) > 1e-2
        assert rigid.continuous_optimal_n(R, e) == pytest.approx(res.x, rel=1e-5)  # Eq 22


def test_eq23_root_structure():
    # h(x) = ln(1+x) - ln(1+e) - x ln x/(1+x): trivial root x = 1 at e = 1 (n* = inf),
    # a second root x > 1 (increasing masses), exactly one root inside (0, 1) for 0 < e < 1.
    h = lambda x, e: np.log1p(x) - np.log1p(e) - x * np.log(x) / (1 + x)
    assert h(1.0, 1.0) == pytest.approx(0.0, abs=1e-15)
    for e in [0.1, 0.5, 0.8, 0.99]:
        x_big = brentq(h, 1.0 + 1e-12, 1e6, args=(e,))
        assert x_big > 1
        x = np.linspace(1e-9, 1 - 1e-9, 10001)
        assert np.sum(np.diff(np.sign(h(x, e))) != 0) == 1
        assert 0 < rigid.optimal_pair_ratio(e) < 1
        assert h(rigid.optimal_pair_ratio(e), e) == pytest.approx(0.0, abs=1e-14)
    with pytest.raises(ParameterError, match="e"):
        rigid.optimal_pair_ratio(1.0)


def test_eq24_misprint_gstar_is_eq20_at_continuous_nstar():
    for R, e in [(0.012, 0.8), (1e-4, 0.6), (0.2, 0.95)]:
        ns = rigid.continuous_optimal_n(R, e)
        eq20_at_ns = _eq20_real_n(R, e, ns)  # Eq 20, real n
        assert rigid.continuous_optimal_gain(R, e) == pytest.approx(eq20_at_ns, rel=1e-12)
        printed = (1 + e) ** ns / (1 + R) ** (ns - 1) - 1  # Eq 24 as printed
        assert abs(printed - eq20_at_ns) > 0.05 * abs(eq20_at_ns)
        # G* bounds the integer optimum and is the continuous maximum (minimize_scalar)
        res = minimize_scalar(lambda n: -_eq20_real_n(R, e, n),
                              bounds=(1.5, 60), method="bounded", options={"xatol": 1e-10})
        assert rigid.continuous_optimal_gain(R, e) == pytest.approx(-res.fun, rel=1e-10)
        assert rigid.continuous_optimal_gain(R, e) >= rigid.mvg_gain(R, e, rigid.mvg_optimal_n(R, e)) - 1e-12


def test_exact_search_and_poschel_brilliantov_agree_on_a_grid():
    R = np.logspace(-7, np.log10(0.9), 35)[:, None]
    e = np.linspace(0.02, 0.995, 35)[None, :]
    n_exact = rigid.mvg_optimal_n(R, e)
    n_pb = rigid.mvg_optimal_n_pb(R, e)
    assert n_exact.shape == (35, 35)
    np.testing.assert_array_equal(n_exact, n_pb)
    # and both equal a brute-force argmax over n = 2..N for a few points
    n = np.arange(2, 3000)
    for i, j in [(0, 34), (10, 20), (34, 0), (20, 30)]:
        assert n[np.argmax(rigid.mvg_gain(R[i, 0], e[0, j], n))] == n_exact[i, j]


# ------------------------------------------------------------------------------------------------
# Section 4.2: MET


def _met_ratios_eq25(e, n):
    """Eq 25 by direct sums: r_{i+1,i} = S_i/(1 + S_{i+1}), S_i = sum_{k=1}^i e^k."""
    S = np.cumsum(e ** np.arange(1, n + 1))
    return np.array([S[i - 1] / (1 + S[i]) for i in range(1, n)])


def test_met_ratios_eqs_25_to_28():
    for e in [0.3, 0.6, 0.8, 0.95]:
        np.testing.assert_allclose(rigid.met_ratios(e, 12), _met_ratios_eq25(e, 12), rtol=1e-13)  # Eq 25 = 27
        assert rigid.met_ratios(e, 2000)[-1] == pytest.approx(e, rel=1e-12)  # Eq 28 (e^2000 < 1e-44)
    i = np.arange(1, 12)
    np.testing.assert_allclose(rigid.met_ratios(1.0, 12), i / (i + 2), rtol=1e-15)  # Eq 26
    np.testing.assert_allclose(_met_ratios_eq25(1.0, 12), i / (i + 2), rtol=1e-15)
    # vectorised over e
    np.testing.assert_allclose(rigid.met_ratios(np.array([0.6, 1.0]), 5)[1], np.arange(1, 5) / np.arange(3, 7))


def test_met_definition_leaves_all_but_top_at_rest():
    # MET (Section 4.2): run the dropped stack through Eqs 1-2 pair by pair (linear solve)
    for e in [0.55, 0.8, 1.0]:
        m = rigid.met_masses(e, 8)
        v = e  # m1 off the ground, v_ff = 1
        for k in range(1, 8):
            V_low, v = _two_body(m[k - 1], m[k], v, -1.0, e)
            assert V_low == pytest.approx(0.0, abs=1e-13)
        assert v == pytest.approx(np.sum(e ** np.arange(1, 9)), rel=1e-12)  # Eq 29
        _, after = rigid.cascade_velocities(m, e, e)
        np.testing.assert_allclose(after[:-1], 0.0, atol=1e-13)


def test_met_gain_eq29_eq30():
    # Eq 29: ten-mass MET at e = 0.8: sum_{k=1}^{10} 0.8^k = 3.5705 (docs/references.md)
    assert rigid.met_gain(0.8, 10) == pytest.approx(3.5705, abs=1e-4)
    assert rigid.met_gain(0.8, 10) == pytest.approx(sum(0.8**k for k in range(1, 11)), rel=1e-14)
    np.testing.assert_array_equal(rigid.met_gain(1.0, np.arange(2, 12)), np.arange(2, 12))  # G_n = n
    # Eq 30: limit e/(1-e); velocity gain (G > 1) needs e > 1/2
    assert rigid.met_gain_limit(0.5) == pytest.approx(1.0, rel=1e-15)
    n = np.arange(2, 500)
    # 1 - 0.5^n rounds to 1.0 from n = 54 on, so strict '< 1' is asserted where float64 resolves it
    assert np.all(rigid.met_gain(0.5, n[:50]) < 1) and np.all(rigid.met_gain(0.5, n) <= 1)
    assert np.all(rigid.met_gain(0.45, n) < 1)
    assert np.any(rigid.met_gain(0.55, n) > 1)
    assert rigid.met_gain(0.7, 400) == pytest.approx(0.7 / 0.3, rel=1e-13)


def test_fig16_17_ten_mass_met_chain():
    # Figs 16-17: e = 0.8, ten masses, m1 = 8.4 kg -> R = 0.0118, m10 = 0.099 kg (paper: "0.1")
    R10 = np.prod(_met_ratios_eq25(0.8, 10))
    assert R10 == pytest.approx(0.0118, abs=5e-5)
    assert rigid.met_mass_ratio(0.8, 10) == pytest.approx(R10, rel=1e-13)
    assert rigid.met_masses(0.8, 10, m1=8.4)[-1] == pytest.approx(0.099, abs=5e-4)
    assert rigid.met_n_for_ratio(0.012, 0.8) == 10


def test_efficiency_and_total_mass_from_energies():
    # K_n = top kinetic energy after the cascade / kinetic energy of the stack at impact (definition,
    # Section 2.1); checked with velocities from cascade_velocities and masses summed directly.
    for R, e, n in [(0.012, 0.8, 6), (0.1, 0.6, 3)]:
        m = rigid.mvg_masses(R, n)
        v_top = rigid.cascade_velocities(m, e, e)[0][-1]
        assert rigid.mvg_total_mass(R, n) == pytest.approx(m.sum(), rel=1e-13)
        assert rigid.mvg_efficiency(R, e, n) == pytest.approx(m[-1] * v_top**2 / m.sum(), rel=1e-12)
    for e, n in [(0.8, 10), (1.0, 5)]:
        m = _met_ratios_eq25(e, n)
        m = np.concatenate([[1.0], np.cumprod(m)])
        v_top = rigid.cascade_velocities(m, e, e)[0][-1]
        assert rigid.met_total_mass(e, n) == pytest.approx(m.sum(), rel=1e-13)
        assert rigid.met_efficiency(e, n) == pytest.approx(m[-1] * v_top**2 / m.sum(), rel=1e-12)
    assert rigid.met_efficiency(1.0, 7) == pytest.approx(1.0, rel=1e-13)  # elastic MET: all energy on top


def test_numbers_numpy_reads_pass_and_text_is_refused():
    """Eq 19 by hand, (1 + e_0) prod (1 + e)/(1 + r) - 1 = 1.9 (1.8/1.5)^2 - 1 = 1.736 for masses 1, 0.5,
    0.25, e = 0.8, e_0 = 0.9: with None in the restitution's unused ground entry (it worked before the
    input checks and must still), with fractions; text (even "0.012") is refused, naming the argument."""
    from fractions import Fraction

    assert rigid.stack_gain([1, 0.5, 0.25], [None, 0.8, 0.8], ground_restitution=0.9) == pytest.approx(1.736, rel=1e-14)
    assert rigid.stack_gain([1, Fraction(1, 2), 0.25], Fraction(4, 5), ground_restitution=0.9) == pytest.approx(
        1.736, rel=1e-14)
    for bad in ("0.012", ["a", 1]):
        with pytest.raises(ParameterError, match=r"^R = .* is invalid: a real number"):
            rigid.mvg_gain(bad, 0.8, 6)


def test_mvg_total_mass_near_r_one_is_the_sum_of_the_masses():
    """Eq 15's geometric sum (1 - x^n)/(1 - x) was 0/0 = NaN where x = R^(1/(n-1)) rounds to 1 (a review:
    R = 1 - 1e-15, n = 1000); against math.fsum of the masses m_1 R^((i-1)/(n-1)), summed here."""
    for R, n in [(1 - 1e-15, 1000), (0.9999999999999998, 10), (1 - 1e-9, 1000), (0.5, 3)]:
        want = math.fsum(R ** (i / (n - 1)) for i in range(n))
        assert rigid.mvg_total_mass(R, n) == pytest.approx(want, rel=1e-14), (R, n)
        assert np.isfinite(rigid.mvg_efficiency(R, 0.8, n))


def test_optimal_pair_ratio_down_to_the_smallest_e():
    """Eq 23 (corrected) as e -> 0: h(x) = ln(1+x) - ln(1+e) - x ln x/(1+x) = 0 tends to x (1 - ln x) = e;
    at e = 1e-297 its root, by fixed-point iteration x = e/(1 - ln x) here, is 1.45e-300, inside the
    bracket; e = 0 (no root in (0, 1)) is refused with a ParameterError, where scipy's brentq failed."""
    e = 1e-297
    x = e
    for _ in range(50):
        x = e / (1 - math.log(x))
    assert rigid.optimal_pair_ratio(e) == pytest.approx(x, rel=1e-9)
    with pytest.raises(ParameterError, match="e = 0.0 is invalid: the continuous-n optimum"):
        rigid.continuous_optimal_n(0.012, 0.0)
    assert rigid.mvg_optimal_n(0.012, 0.0) == 2  # the integer search takes e = 0: Eq 20 falls with n


# ------------------------------------------------------------------------------------------------
# Section 5: designs


def test_design_functions_take_n_and_m1_by_keyword_only():
    """mvg_design(R, e, n, m1) and met_design(R, e, m1, n) took n and m1 positionally in opposite orders
    (a review: met_design(0.012, 0.8, 6) silently made the ten-mass stack with m_1 = 6); both are
    keyword-only now. MET with a given n needs no R: Eq 25's ratios follow from e alone (n = 10, e = 0.8:
    R_10 = 0.0118435, docs/references.md's Figs 16-17 stack)."""
    with pytest.raises(TypeError):
        rigid.met_design(0.012, 0.8, 6)
    with pytest.raises(TypeError):
        rigid.mvg_design(0.012, 0.8, 6)
    d = rigid.met_design(None, 0.8, n=10, m1=8.4)
    assert d.n == 10 and d.masses[0] == 8.4
    assert d.mass_ratio == pytest.approx(np.prod(_met_ratios_eq25(0.8, 10)), rel=1e-13)
    assert rigid.mvg_design(0.012, 0.8, n=6, m1=8.4).masses[-1] == pytest.approx(8.4 * 0.012, rel=1e-13)


def test_design_R_0012_e_08():
    d = rigid.design(R=0.012, e=0.8)
    assert d.mvg.kind == "MVG" and d.mvg.n == 6  # Fig 17
    assert d.met.kind == "MET" and d.met.n == 10  # Figs 16-17
    assert d.mvg.gain == pytest.approx(5.0407, abs=1e-4)  # docs/references.md
    assert d.met.gain == pytest.approx(3.5705, abs=1e-4)  # docs/references.md, Eq 29
    assert d.mvg.masses[-1] == pytest.approx(0.012, rel=1e-13)
    np.testing.assert_allclose(np.prod(d.met.ratios), np.prod(_met_ratios_eq25(0.8, 10)), rtol=1e-13)
    assert d.gain_ratio == pytest.approx(5.0407 / 3.5705, rel=1e-4)
    # Section 5 says MET's gain is "about 23%" lower; with Eqs 20 and 29 it is 29% lower (docs/references.md)
    assert 1 - d.met.gain / d.mvg.gain == pytest.approx(0.2917, abs=5e-4)
    # Section 5: "the total mass in both the MET and the six-mass MVG systems is about the same"
    assert d.mass_ratio == pytest.approx(1.0, abs=0.05)
    with pytest.raises(dataclasses_frozen_error()):
        d.mvg.n = 3  # frozen
    assert not d.mvg.masses.flags.writeable


def dataclasses_frozen_error():
    import dataclasses

    return dataclasses.FrozenInstanceError


def test_design_from_masses_in_kg():
    # Figs 16-17: m1 = 8.4 kg, m10 = 0.1 kg, e = 0.8
    d = rigid.design(m1=8.4, mn=0.1, e=0.8)
    assert d.mvg.n == 6 and d.met.n == 10
    assert d.mvg.masses[0] == pytest.approx(8.4) and d.mvg.masses[-1] == pytest.approx(0.1, rel=1e-13)
    assert d.met.masses[-1] == pytest.approx(0.099, abs=5e-4)
    assert d.mvg.total_mass == pytest.approx(d.mvg.masses.sum(), rel=1e-14)


def test_design_ratios_vectorised_matches_scalar_design():
    R = np.array([[0.5], [0.012], [1e-4]])
    e = np.array([[0.6, 0.8, 0.95]])
    dr = rigid.design_ratios(R, e)
    assert dr.gain.shape == (3, 3)
    for i in range(3):
        for j in range(3):
            d = rigid.design(R=R[i, 0], e=e[0, j])
            assert dr.n_mvg[i, j] == d.mvg.n and dr.n_met[i, j] == d.met.n
            assert dr.gain[i, j] == pytest.approx(d.gain_ratio, rel=1e-12)
            assert dr.efficiency[i, j] == pytest.approx(d.efficiency_ratio, rel=1e-12)
            assert dr.total_mass[i, j] == pytest.approx(d.mass_ratio, rel=1e-12)
    dm = rigid.design_ratios(R, e, at_met_ratio=True)  # Figs 13-15: R on the MET curve (Eq 25)
    np.testing.assert_allclose(dm.R[1, 1], np.prod(_met_ratios_eq25(0.8, 10)), rtol=1e-13)


# ------------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: rigid.mvg_gain(0.012, 1.2, 6), "e"),
        (lambda: rigid.mvg_gain(0.012, -0.1, 6), "e"),
        (lambda: rigid.mvg_gain(1.5, 0.8, 6), "R"),
        (lambda: rigid.mvg_gain(0.0, 0.8, 6), "R"),
        (lambda: rigid.mvg_gain(0.012, 0.8, 1), "n"),
        (lambda: rigid.mvg_gain(0.012, 0.8, 2.5), "n"),
        (lambda: rigid.met_ratios(0.8, 1), "n"),
        (lambda: rigid.chain_gain([1.0, -0.5], 0.8), "masses"),
        (lambda: rigid.chain_gain([1.0], 0.8), "masses"),
        (lambda: rigid.chain_gain([1.0, 0.5, 0.2], [0.8, 0.8]), "restitution"),
        (lambda: rigid.stack_gain([1.0, 0.5], 0.8, ground_restitution=-1.0), "ground_restitution"),
        (lambda: rigid.impact_velocities(1.0, 0.0, 1.0, 0.0, 0.8), "m2"),
        (lambda: rigid.velocity_gains(0.5, 1.5, 0.8), "g"),
        (lambda: rigid.mvg_optimal_n(0.012, 1.0), "e"),
        (lambda: rigid.design(e=0.8), "R"),
        (lambda: rigid.design(m1=1.0, mn=2.0, e=0.8), "mn"),
        (lambda: rigid.design(R=np.nan, e=0.8), "R"),
    ],
)
def test_bad_input_raises_parameter_error_naming_the_parameter(call, name):
    with pytest.raises(ParameterError, match=rf"^{name} = ") as info:
        call()
    assert info.value.name == name


def test_perfectly_plastic_pair_moves_on_together():
    """e = 0 is a valid restitution (Eq 2 with V2 = V1): momentum (Eq 1) then gives the common velocity
    (m1 v1 + m2 v2)/(m1 + m2). The MET ratios (Eq 27) vanish at e = 0, so MET rejects it by name."""
    V1, V2 = rigid.impact_velocities(3.0, 1.0, 2.0, -1.0, 0.0)
    assert V1 == pytest.approx(1.25, rel=1e-15) and V2 == pytest.approx(1.25, rel=1e-15)
    # Eq 19 with e_{1,0} = 0: mass 1 stops on the ground and mass 2 (falling at -1) hits it at rest:
    # V2 = -1 + (1 + e)(1)/(1 + r) -> with e = 0.8, r = m2/m1 = 0.1: -1 + 1.8/1.1
    assert rigid.stack_gain([1.0, 0.1], 0.8, ground_restitution=0.0) == pytest.approx(1.8 / 1.1 - 1, rel=1e-14)
    with pytest.raises(ParameterError, match=r"^e = .*MET ratios"):
        rigid.met_ratios(0.0, 5)


def test_active_ground_allowed():
    # text after Eq 19: e_{1,0} > 1 is allowed
    assert rigid.stack_gain([1.0, 0.1], 0.8, ground_restitution=1.5) == pytest.approx(2.5 * 1.8 / 1.1 - 1, rel=1e-14)
