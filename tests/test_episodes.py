"""Contact episodes and effective restitution, on analytic overlap histories.

Reference: the unclamped linear spring-dashpot impact has the closed-form overlap
delta(t) = (v0/wd) exp(-zeta w t) sin(wd t) for 0 <= t <= pi/wd, with restitution
e = exp(-zeta pi / sqrt(1 - zeta^2)) and peak overlap at tan(wd t) = wd/(zeta w)
(e.g. Schwager & Pöschel 2007). Before and after, the bodies move freely (delta linear in t).
"""

import numpy as np
import pytest

from hertz_chain.episodes import contact_episodes, overlap_rates


def _kv_history(t, t0, v0, w, zeta):
    wd = w * np.sqrt(1 - zeta**2)
    tc = np.pi / wd
    s = t - t0
    inside = (s >= 0) & (s <= tc)
    d = np.where(inside, v0 / wd * np.exp(-zeta * w * s) * np.sin(wd * s), 0.0)
    dd = np.where(inside, v0 * np.exp(-zeta * w * s) * (np.cos(wd * s) - zeta * w / wd * np.sin(wd * s)), 0.0)
    v_end = v0 * np.exp(-zeta * w * tc) * (-1.0)  # delta_dot at the end of contact
    before, after = s < 0, s > tc
    d = np.where(before, v0 * s, d)
    dd = np.where(before, v0, dd)
    d = np.where(after, v_end * (s - tc), d)
    dd = np.where(after, v_end, dd)
    return d, dd, tc


@pytest.mark.parametrize("zeta", [0.05, 0.2, 0.5])
def test_restitution_and_times_of_a_kelvin_voigt_impact(zeta):
    rng = np.random.default_rng(0)
    w, v0, t0 = 2 * np.pi * 1e3, 1.3, 1.234e-3
    # non-uniform samples, about 400 per contact, as an adaptive solver would give
    t = np.sort(np.concatenate([[0.0, 4e-3], rng.uniform(0, 4e-3, 1600)]))
    d, dd, tc = _kv_history(t, t0, v0, w, zeta)
    force = 1e6 * np.maximum(d, 0)
    # free flight: delta_ddot = 0 outside the contact (two masses, no gravity difference)
    acc = np.zeros_like(d)
    eps = contact_episodes(t, d[:, None], dd[:, None], force[:, None], accelerations=acc[:, None])
    assert len(eps) == 1
    ep = eps[0]
    e_exact = np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))  # closed form
    wd = w * np.sqrt(1 - zeta**2)
    t_peak = np.arctan2(wd, zeta * w) / wd  # closed form of the peak time
    d_peak = v0 / wd * np.exp(-zeta * w * t_peak) * np.sin(wd * t_peak)
    assert ep.complete
    # extrapolation from the free-flight side is exact: float64 round-off only
    assert ep.start == pytest.approx(t0, rel=1e-12)
    assert ep.end == pytest.approx(t0 + tc, rel=1e-12)
    assert ep.approach_velocity == pytest.approx(v0, rel=1e-12)
    assert ep.restitution == pytest.approx(e_exact, rel=1e-12)
    # without accelerations the cubic Hermite interpolant across the kink is O(h^2) accurate
    ep_h = contact_episodes(t, d[:, None], dd[:, None], force[:, None])[0]
    assert ep_h.start == pytest.approx(t0, rel=2e-6)
    assert ep_h.restitution == pytest.approx(e_exact, rel=1e-2)  # KV acceleration jumps at contact
    assert ep.max_overlap == pytest.approx(d_peak, rel=1e-8)


def test_two_episodes_and_open_ends():
    t = np.linspace(0.0, 9.0, 901)
    d = np.sin(t)  # closed on (0, pi), (2pi, 3pi): the first starts at t=0 with delta=0
    dd = np.cos(t)
    eps = contact_episodes(t, d[:, None], dd[:, None], d[:, None])
    assert [round(e.start, 9) for e in eps] == [0.0, round(2 * np.pi, 9)]
    assert eps[0].end == pytest.approx(np.pi, abs=1e-10)  # sin has its root at pi
    assert eps[0].restitution == pytest.approx(1.0, abs=1e-9)  # |cos| equal at both roots
    # still closed at t = 9 < 3 pi: incomplete, restitution NaN
    assert eps[1].complete is False and np.isnan(eps[1].restitution)


def test_overlap_rates_follow_the_interface_convention():
    v = np.array([[-1.0, -2.0, 3.0]])
    # interface 0: -v1; interface j: v_j - v_{j+1} (notes/CONVENTIONS.md)
    np.testing.assert_array_equal(overlap_rates(v), [[1.0, 1.0, -5.0]])
    np.testing.assert_array_equal(overlap_rates(v, ground=False), [[0.0, 1.0, -5.0]])


def test_one_contact_end_everywhere_clamped_tsuji():
    # Issue 16: a contact ends where its force returns to zero, for the simulator's launch (and so
    # `simulate_impact()`), the episodes of the analysis, and the rigid comparison alike. Reference: an
    # independent scipy integration (Radau, rtol 1e-12) of the same single impact, m = 1 kg on the ground,
    # g = 0, F = k d^1.5 + eta sqrt(m k) d^0.25 d' clamped at F >= 0 (Tsuji, Tanaka & Ishida 1992),
    # with a terminal event at F = 0 after the peak. For e = 0.5 the force returns to zero while
    # d > 0, 21 % earlier than the overlap (the measurement), so the two ends differ visibly.
    from scipy.integrate import solve_ivp

    import hertz_chain as hc

    k, m, v0 = 1e9, 1.0, 1.0
    law = hc.Tsuji.from_restitution(k, 0.5, m)
    eta = float(law.eta)
    c = eta * np.sqrt(m * k)

    def rhs(t, y):
        d, dd = y
        f = max(k * max(d, 0.0) ** 1.5 + c * max(d, 0.0) ** 0.25 * dd, 0.0)
        return [dd, -f / m]

    def force_zero(t, y):
        d, dd = y
        return k * d**1.5 + c * d**0.25 * dd if d > 0 else d

    force_zero.terminal, force_zero.direction = True, -1
    t_guess = 10 * 2.94328 * (5 * m * v0**2 / (4 * k)) ** 0.4 / v0
    ref = solve_ivp(rhs, (0, t_guess), [1e-30, v0], method="Radau", rtol=1e-12, atol=1e-20,
                    events=force_zero, first_step=1e-12)
    t_end_ref, v_end_ref = float(ref.t_events[0][0]), float(-ref.y_events[0][0][1])
    d_end_ref = float(ref.y_events[0][0][0])
    assert d_end_ref > 0  # the clamped contact lets go before the overlap closes

    measured = hc.simulate_impact(law, v0, m)
    assert measured.contact_time == pytest.approx(t_end_ref, rel=1e-7)
    assert measured.e == pytest.approx(v_end_ref / v0, rel=1e-7)
    stack = hc.Stack([m], [law], gravity=0.0)
    sol = hc.simulate(stack, hc.at_impact(stack, v0), tolerances=hc.Tolerances(1e-11, 1e-11))
    report = hc.analyse(sol)
    (ep,) = report.episodes
    assert ep.start == pytest.approx(0.0, abs=1e-12 * t_end_ref)
    assert ep.end == pytest.approx(t_end_ref, rel=1e-7)
    assert ep.end == pytest.approx(float(sol.contact_end_times[0]), rel=1e-9)
    assert ep.restitution == pytest.approx(v_end_ref / v0, rel=1e-7)


def test_refined_peak_force_of_one_hertz_impact_against_the_closed_form(tmp_path):
    """Johnson (1985): F_max = k d_max^1.5, d_max = (5 m v^2 / (4 k))^(2/5). At rtol 1e-10 the largest
    sample is low by ~1.8e-4 (the steps straddle the peak), the parabola through it and its neighbours
    by ~1.5e-7, the Hermite-refined top pulse (m a) by ~7e-9: bounds 1e-6 and 1e-7, and the sample lower."""
    import hertz_chain as hc

    M, K, V = 0.1, 1e9, 1.0
    F = K * (5 * M * V**2 / (4 * K)) ** 0.6
    p = tmp_path / "s.toml"
    p.write_text('[drop]\nimpact_velocity = "1 m/s"\ngravity = 0\n[stack]\nmasses = ["0.1 kg"]\n[contact]\n'
                 'law = "hertz"\nstiffness = "1e9 N/m^1.5"\n[solver]\nrtol = 1e-10\natol = 1e-10\n')
    r = hc.simulate_file(p)
    (ep,) = [e for e in r.episodes if e.interface == 0]
    assert ep.peak_force_refined == pytest.approx(F, rel=1e-6)
    assert ep.peak_force <= ep.peak_force_refined <= F * (1 + 1e-9)
    assert abs(ep.peak_force_refined - F) < abs(ep.peak_force - F)
    assert r.top_pulse.peak_g * 9.80665 * M == pytest.approx(F, rel=1e-7)


@pytest.mark.parametrize("law, stiffness, e, param", [("hertz-dashpot", "1e9 N/m^1.5", 0.3, "gamma"),
                                                      ("kelvin-voigt", "1e7 N/m", 0.05, "c")])
def test_a_force_largest_at_first_touch_is_not_overshot(tmp_path, law, stiffness, e, param):
    """A review: a dashpot acting from first touch makes the force jump to F(0+) = c v and then fall (at
    delta = 0, dF/dt = c delta'' = -c^2 v / m < 0): the closed form F_max = c v. The refinements through
    the zero force before the contact read it 4.5x (the episode's refined peak), +33 % (the top pulse's
    peak g) and +12.5 % (`simulate_impact`) high for hertz-dashpot at e = 0.3; Kelvin-Voigt at e = 0.05
    alike. The first step ends ~1e-10 s after the onset, where F has fallen by c^2 v t / m (~1e-6 of it):
    bounds 2e-6, and never above c v."""
    import hertz_chain as hc

    M, V = 0.1, 1.0
    kw = dict(calibration_velocity=V) if law == "hertz-dashpot" else {}
    law_obj = hc.make_law(law, stiffness=float(stiffness.split()[0]), restitution=e, effective_mass=M, **kw)
    F = float(getattr(law_obj, param)) * V  # c v
    p = tmp_path / "s.toml"
    p.write_text(f'[drop]\nimpact_velocity = "1 m/s"\ngravity = 0\n[stack]\nmasses = ["0.1 kg"]\n[contact]\n'
                 f'law = "{law}"\nstiffness = "{stiffness}"\nrestitution = {e}\n'
                 + ('calibration_velocity = "1 m/s"\n' if kw else "")
                 + '[solver]\nrtol = 1e-11\natol = 1e-11\n')
    r = hc.simulate_file(p)
    (ep,) = [x for x in r.episodes if x.interface == 0]
    for value in (ep.peak_force_refined, r.top_pulse.peak_g * 9.80665 * M,
                  hc.simulate_impact(law_obj, V, M).max_force):
        assert value == pytest.approx(F, rel=2e-6) and value <= F * (1 + 1e-12)


def test_peak_time_is_nan_where_the_force_never_peaks_inside_the_record():
    # three columns on one record t in [0, 1]:
    # 0: a static contact of a held chain (closed from t0, force = its preload to 1e-9): no peak -> NaN
    # 1: closed from t0 and struck: F = 1 + sin(pi t)^2 peaks at t = 1/2 (closed form) -> a time
    # 2: a contact still loading at the record's end (F rising to the last sample) -> NaN
    t = np.linspace(0.0, 1.0, 2001)
    static = 2.0 * (1 + 1e-9 * np.sin(37 * t))
    struck = 1.0 + np.sin(np.pi * t) ** 2
    rising = np.where(t > 0.6, (t - 0.6) ** 2, 0.0)
    forces = np.stack([static, struck, rising], axis=1)
    overlaps = np.stack([np.full_like(t, 1e-6), 1e-6 * struck, np.where(t > 0.6, t - 0.6, -(0.6 - t))], axis=1)
    eps = {ep.interface: ep for ep in contact_episodes(t, overlaps, np.gradient(overlaps, t, axis=0), forces)}
    assert np.isnan(eps[0].peak_force_time) and eps[0].peak_force == pytest.approx(2.0, rel=1e-8)
    assert eps[1].peak_force_time == pytest.approx(0.5, abs=1e-9)  # the parabola through the samples
    assert np.isnan(eps[2].peak_force_time) and eps[2].peak_force == pytest.approx(0.16, rel=1e-12)
