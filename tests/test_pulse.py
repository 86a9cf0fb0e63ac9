"""Tests of hertz_chain.pulse: acceleration-pulse metrics.

Expected values are closed forms of the classical shock pulses (MIL-STD-810H Method 516.8 defines the
half-sine and terminal-peak sawtooth by peak and duration):

* half-sine `A sin(πt/D)`, `0 <= t <= D`: 10 % duration `(1 − 2 asin(0.1)/π) D = 0.93623 D`,
  rise time 10→90 % `(asin 0.9 − asin 0.1) D/π`, `ΔV = 2AD/π`, equivalent half-sine duration `D`;
* symmetric triangle (peak `A` at `D/2`): 10 % duration `0.9 D`, rise `0.4 D`, `ΔV = AD/2`;
* terminal-peak sawtooth (linear rise to `A` over `D`, drop to 0 over one step `h`): 10 % duration
  `0.9 D + 0.9 h`, rise `0.8 D`, `ΔV = A (D + h)/2`.

The metrics read samples as their piecewise-linear interpolant, so piecewise-linear pulses sampled at
their corners are exact (float64 tolerances); smooth pulses converge as O(h²).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from hertz_chain.errors import ParameterError
from hertz_chain.pulse import G0, PulseMetrics, count_pulses, from_g, pulse_metrics, to_g

A = 1000.0  # m/s² (about 102 g)
D = 1.0e-3  # s

HS_DUR10 = (1.0 - 2.0 * math.asin(0.1) / math.pi) * D  # 0.93623 D
HS_RISE = (math.asin(0.9) - math.asin(0.1)) * D / math.pi
HS_DV = 2.0 * A * D / math.pi


def half_sine(t, t0=0.0, amp=A, dur=D):
    s = (t - t0) / dur
    return np.where((s >= 0) & (s <= 1), amp * np.sin(np.pi * np.clip(s, 0, 1)), 0.0)


def test_g_conversion():
    assert G0 == 9.80665  # CGPM 1901 standard gravity
    assert to_g(9.80665) == 1.0
    np.testing.assert_allclose(from_g([1.0, 2.0]), [9.80665, 19.6133], rtol=1e-15)


def test_half_sine_uniform():
    """Uniform sampling h = D/10 000, half-sine starting at t0 = 0.2 ms, zeros around it.

    Tolerance 1e-7 relative: the interpolation errors are O((πh/D)²) = 1e-7 at most
    (trapezoid ΔV: −(πh/D)²/12 = −8e-9)."""
    t0 = 2e-4
    t = np.linspace(0.0, 2e-3, 20001)  # h = 1e-7 s = D/10 000; t0 and t0 + D are samples
    m = pulse_metrics(t, half_sine(t, t0))
    assert isinstance(m, PulseMetrics)
    assert m.sign == 1 and m.n_pulses == 1 and not m.truncated
    assert m.peak == pytest.approx(A, rel=1e-12)  # t0 + D/2 is a sample
    assert m.peak_g == pytest.approx(A / 9.80665, rel=1e-12)
    assert m.time_of_peak == pytest.approx(t0 + D / 2, rel=1e-12)
    assert m.duration_10 == pytest.approx(HS_DUR10, rel=1e-7)
    assert m.duration_10 / D == pytest.approx(0.93623, abs=5e-6)  # the value quoted in docs/references.md
    assert m.t_start_10 == pytest.approx(t0 + math.asin(0.1) * D / math.pi, rel=1e-7)
    assert m.rise_time == pytest.approx(HS_RISE, rel=1e-7)
    assert m.delta_v == pytest.approx(HS_DV, rel=1e-7)
    assert m.delta_v_main == pytest.approx(HS_DV, rel=1e-7)
    assert m.equivalent_half_sine_duration == pytest.approx(D, rel=1e-7)


def test_negative_half_sine_uses_dominant_sign():
    t = np.linspace(0.0, 2e-3, 20001)
    m = pulse_metrics(t, -half_sine(t, 2e-4))
    assert m.sign == -1
    assert m.peak == pytest.approx(A, rel=1e-12)
    assert m.delta_v == pytest.approx(-HS_DV, rel=1e-7)
    assert m.delta_v_main == pytest.approx(-HS_DV, rel=1e-7)
    assert m.duration_10 == pytest.approx(HS_DUR10, rel=1e-7)
    assert m.equivalent_half_sine_duration == pytest.approx(D, rel=1e-7)


def test_triangle_exact():
    """Symmetric triangle sampled at its corners (plus zeros around it): exact for the interpolant."""
    t = np.array([0.0, 1e-4, 1e-4 + D / 2, 1e-4 + D, 2e-3])
    a = np.array([0.0, 0.0, A, 0.0, 0.0])
    m = pulse_metrics(t, a)
    assert m.peak == A and m.time_of_peak == 1e-4 + D / 2
    assert m.duration_10 == pytest.approx(0.9 * D, rel=1e-12)
    assert m.rise_time == pytest.approx(0.4 * D, rel=1e-12)
    assert m.delta_v == pytest.approx(A * D / 2, rel=1e-12)
    assert m.delta_v_main == pytest.approx(A * D / 2, rel=1e-12)
    assert m.equivalent_half_sine_duration == pytest.approx(math.pi * D / 4, rel=1e-12)
    assert m.n_pulses == 1 and not m.truncated


def test_terminal_peak_sawtooth_exact():
    """Terminal-peak sawtooth: linear rise over D, drop to zero over one step h (MIL-STD-810H 516.8)."""
    h = 1e-6
    t = np.array([0.0, D, D + h, 2 * D])
    a = np.array([0.0, A, 0.0, 0.0])
    m = pulse_metrics(t, a)
    assert m.time_of_peak == D
    assert m.duration_10 == pytest.approx(0.9 * D + 0.9 * h, rel=1e-12)
    assert m.rise_time == pytest.approx(0.8 * D, rel=1e-12)
    assert m.delta_v == pytest.approx(A * (D + h) / 2, rel=1e-12)
    assert m.equivalent_half_sine_duration == pytest.approx(math.pi * (D + h) / 4, rel=1e-12)
    assert m.n_pulses == 1


def test_a_record_that_starts_past_the_rise_has_no_rise_time():
    """A half-sine record that starts at 0.45 D, where sin(0.45 pi) = 0.988 of the peak, above the 90 % level:
    no rising edge in the record, so the rise time is NaN (not 0, as `compare --cfc 60` printed for a pulse
    the filter spread past the record's start), the pulse truncated; a record that starts at 0.2 D
    (sin(0.2 pi) = 0.588: inside the rise) keeps the part it has, from its start to the 90 % crossing at
    asin(0.9) D / pi, also truncated."""
    for start, rise in ((0.45, math.nan), (0.2, math.asin(0.9) / math.pi - 0.2)):
        t = np.linspace(start * D, D, 20001)
        m = pulse_metrics(t, A * np.sin(np.pi * t / D))
        assert m.truncated
        if math.isnan(rise):
            assert math.isnan(m.rise_time)
        else:
            assert m.rise_time == pytest.approx(rise * D, rel=1e-6)


def test_two_separated_half_sines():
    """Two half-sines, the second at 60 % amplitude: 2 pulses; the main pulse is the first one."""
    t = np.linspace(0.0, 4e-3, 40001)  # h = 1e-7 s
    a = half_sine(t, 2e-4) + half_sine(t, 2.2e-3, amp=0.6 * A)
    m = pulse_metrics(t, a)
    assert m.n_pulses == 2
    assert m.time_of_peak == pytest.approx(2e-4 + D / 2, rel=1e-12)
    assert m.duration_10 == pytest.approx(HS_DUR10, rel=1e-7)
    assert m.delta_v == pytest.approx(1.6 * HS_DV, rel=1e-7)
    assert m.delta_v_main == pytest.approx(HS_DV, rel=1e-7)
    assert m.equivalent_half_sine_duration == pytest.approx(D, rel=1e-7)


def test_opposite_sign_rebound_is_a_separate_pulse():
    """A rebound of the opposite sign that directly follows the main pulse (no quiet gap) still counts,
    as the interpolant passes through the band |a| < 10 % between them; its lobe bounds delta_v_main."""
    t = np.linspace(0.0, 3e-3, 30001)
    a = half_sine(t, 0.0) - half_sine(t, D, amp=0.5 * A)
    m = pulse_metrics(t, a)
    assert m.n_pulses == 2 and m.sign == 1
    assert m.delta_v == pytest.approx(0.5 * HS_DV, rel=1e-7)
    assert m.delta_v_main == pytest.approx(HS_DV, rel=1e-7)
    assert not m.truncated


def test_pulse_threshold_parameter():
    """A 5 %-of-peak second pulse counts only when the threshold is below 5 %."""
    t = np.linspace(0.0, 4e-3, 4001)
    a = half_sine(t, 2e-4) + half_sine(t, 2.2e-3, amp=0.05 * A)
    assert pulse_metrics(t, a).n_pulses == 1
    assert pulse_metrics(t, a, pulse_threshold=0.03).n_pulses == 2
    assert count_pulses(t, a, threshold=0.03) == 2


def test_exact_delta_v_is_used():
    t = np.linspace(0.0, 2e-3, 2001)
    m = pulse_metrics(t, half_sine(t, 2e-4), delta_v=HS_DV)
    assert m.delta_v == HS_DV


def test_a_record_that_starts_on_the_tail_of_the_lobe_is_not_truncated():
    """A record that starts where the pulse is a few millionths of its peak (a check window after a contact's
    tail) holds the whole pulse; one that starts at 5 % of it (below the 10 % level) cuts its lobe."""
    t = np.linspace(0.0, D, 1001)
    tail = 1e-6 * A * np.exp(-t / D)  # a positive tail under the half-sine
    assert not pulse_metrics(t, half_sine(t) + tail).truncated
    t5 = t[t >= D * math.asin(0.05) / math.pi]
    assert pulse_metrics(t5, half_sine(t5)).truncated


def test_truncated_record_is_flagged_and_finite():
    t = np.linspace(0.0, 0.7 * D, 701)  # the record stops before the pulse ends
    m = pulse_metrics(t, half_sine(t))
    assert m.truncated
    assert m.t_end_10 == t[-1]
    vals = [getattr(m, f) for f in PulseMetrics.__dataclass_fields__]
    assert all(np.isfinite(v) for v in vals)


def _nonuniform_times(n, rng, t_end=2e-3):
    """n strictly increasing times on [0, t_end] with random steps (ratio up to 10 between steps)."""
    steps = rng.uniform(0.1, 1.0, n - 1)
    return np.concatenate(([0.0], np.cumsum(steps))) * (t_end / steps.sum())


def test_nonuniform_sampling_converges():
    """Random non-uniform steps (ratio up to 10) with n = 1 001, 10 001, 100 001 points on 2 ms.

    Every relative error stays below the O(h²) bound `(π h_max/D)²` of linear interpolation of the
    sine (h_max = largest step: about 3.6e-6, 3.6e-7, 3.6e-8 s, i.e. bounds 1.3e-4, 1.3e-6, 1.3e-8),
    the peak time within `h_max/2` (the crest sample), and at n = 100 001 all are below 1e-7."""
    rng = np.random.default_rng(1234)
    t0 = 2e-4
    ref = {
        "peak": A,
        "duration_10": HS_DUR10,
        "rise_time": HS_RISE,
        "delta_v": HS_DV,
        "delta_v_main": HS_DV,
        "equivalent_half_sine_duration": D,
    }
    for n in (1001, 10001, 100001):
        t = _nonuniform_times(n, rng)
        h_max = float(np.max(np.diff(t)))
        m = pulse_metrics(t, half_sine(t, t0))
        assert m.n_pulses == 1 and not m.truncated
        assert abs(m.time_of_peak - (t0 + D / 2)) <= 0.5 * h_max
        bound = (math.pi * h_max / D) ** 2
        for k, v in ref.items():
            err = abs(getattr(m, k) - v) / v
            assert err <= bound, (n, k, err, bound)
            if n == 100001:
                assert err < 1e-7, (k, err)


# --------------------------------------------------------------------------------------------------
# degenerate input


@pytest.mark.parametrize(
    "t, a, name",
    [
        ([0.0, 1.0, 2.0], [0.0, 0.0, 0.0], "a"),  # all zeros
        ([0.0], [1.0], "t"),  # a single sample
        ([], [], "t"),
        ([0.0, 2.0, 1.0], [0.0, 1.0, 0.0], "t"),  # non-monotonic
        ([0.0, 1.0, 1.0], [0.0, 1.0, 0.0], "t"),  # repeated time
        ([0.0, 1.0, 2.0], [0.0, np.nan, 0.0], "a"),
        ([0.0, np.inf, 2.0], [0.0, 1.0, 0.0], "t"),
        ([0.0, 1.0, 2.0], [0.0, 1.0], "a"),  # shape mismatch
        ([[0.0, 1.0]], [[0.0, 1.0]], "t"),  # 2-D
    ],
)
def test_degenerate_input_raises(t, a, name):
    with pytest.raises(ParameterError) as info:
        pulse_metrics(t, a)
    assert info.value.name == name


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"duration_level": 0.0}, "duration_level"),
        ({"duration_level": 1.0}, "duration_level"),
        ({"pulse_threshold": -0.1}, "pulse_threshold"),
        ({"rise_levels": (0.9, 0.1)}, "rise_levels"),
        ({"rise_levels": (0.1, 1.5)}, "rise_levels[1]"),
        ({"delta_v": float("nan")}, "delta_v"),
    ],
)
def test_bad_levels_raise(kwargs, name):
    t = np.linspace(0.0, 2e-3, 201)
    with pytest.raises(ParameterError) as info:
        pulse_metrics(t, half_sine(t), **kwargs)
    assert info.value.name == name


# --------------------------------------------------------------------------------------------------
# properties


LEVELS = (0.0, 0.1, 0.9)  # levels (fractions of the peak) at which the metrics cut the samples


@st.composite
def records(draw):
    n = draw(st.integers(3, 40))
    steps = draw(st.lists(st.floats(1e-3, 1.0), min_size=n - 1, max_size=n - 1))
    # no subnormals: c * 5e-324 rounds to 0 and changes a sample's sign, a boundary like those below
    a = np.array(draw(st.lists(st.floats(-1e3, 1e3, allow_subnormal=False), min_size=n, max_size=n)))
    t = np.concatenate(([0.0], np.cumsum(steps)))
    peak = np.max(np.abs(a))
    assume(peak > 1e-6)
    # stay away from the decision boundaries, where an ulp may flip a comparison after scaling
    assume(abs(np.max(a) + np.min(a)) > 1e-9 * peak)  # the dominant sign is not a tie
    srt = np.sort(np.abs(a))
    assume(srt[-1] - srt[-2] > 1e-9 * peak)  # a unique peak sample
    for lev in LEVELS[1:]:
        assume(np.all(np.abs(np.abs(a) - lev * peak) > 1e-9 * peak))
    return t, a


FIELDS_TIME = ("t_start_10", "t_end_10", "time_of_peak")
FIELDS_DURATION = ("duration_10", "rise_time", "equivalent_half_sine_duration")


@settings(max_examples=150, deadline=None)
@given(rec=records(), c=st.floats(1e-3, 1e3), negate=st.booleans())
def test_scaling_property(rec, c, negate):
    """a → c·a scales peak by |c| and the ΔVs by c, flips the sign with c, keeps every time."""
    t, a = rec
    c = -c if negate else c
    m0, m1 = pulse_metrics(t, a), pulse_metrics(t, c * a)
    assert m1.peak == pytest.approx(abs(c) * m0.peak, rel=1e-12)
    assert m1.peak_g == pytest.approx(abs(c) * m0.peak_g, rel=1e-12)
    assert m1.sign == (m0.sign if c > 0 else -m0.sign)
    scale_v = np.sum(np.abs(a)) * t[-1]
    assert m1.delta_v == pytest.approx(c * m0.delta_v, rel=1e-12, abs=1e-13 * abs(c) * scale_v)
    assert m1.delta_v_main == pytest.approx(c * m0.delta_v_main, rel=1e-12, abs=1e-13 * abs(c) * scale_v)
    for f in FIELDS_TIME + FIELDS_DURATION:
        assert getattr(m1, f) == pytest.approx(getattr(m0, f), rel=1e-9, abs=1e-12 * t[-1], nan_ok=True), f
    assert m1.n_pulses == m0.n_pulses and m1.truncated == m0.truncated


@settings(max_examples=150, deadline=None)
@given(rec=records(), tau=st.floats(-100.0, 100.0))
def test_time_shift_property(rec, tau):
    """t → t + τ shifts every time by τ and leaves the peak, ΔV, durations and count unchanged."""
    t, a = rec
    m0, m1 = pulse_metrics(t, a), pulse_metrics(t + tau, a)
    tol = 1e-12 * (abs(tau) + t[-1]) * 16  # rounding of the shifted time stamps
    assert m1.peak == m0.peak and m1.sign == m0.sign and m1.n_pulses == m0.n_pulses
    for f in FIELDS_TIME:
        assert getattr(m1, f) == pytest.approx(getattr(m0, f) + tau, abs=tol), f
    for f in FIELDS_DURATION:
        assert getattr(m1, f) == pytest.approx(getattr(m0, f), abs=tol, nan_ok=True), f
    assert m1.delta_v == pytest.approx(m0.delta_v, abs=tol * np.max(np.abs(a)) * 4)


def test_streamed_duration_equals_pulse_metrics_on_the_whole_record():
    """The 10 % duration and the 10-90 % rise time that `simulate_batch(pulse_durations=True)` streams
    through the solve
    (`_tracking._pulse_update` sample by sample, `_pulse_duration` at the end), against `pulse_metrics`
    on the whole record (the reference): random records, smooth and noisy, one to three humps of growing
    or shrinking height, with plateaus and ties (values rounded), to round-off; and NaN, not a wrong
    value, where the rising edge to the peak is longer than the kept slots."""
    import jax
    import jax.numpy as jnp

    from hertz_chain._tracking import PULSE_RING, _pulse_duration, _pulse_start, _pulse_update

    @jax.jit
    def stream(t, y):
        def body(c, ty):
            st, peak = c
            return (_pulse_update(*st, ty[0], ty[1], peak, jnp.asarray(False)), jnp.maximum(peak, ty[1])), None

        (st, peak), _ = jax.lax.scan(body, (_pulse_start(t[0], 0.0 * y[0]), 0.0 * y[0]), (t, y))
        return jnp.stack(_pulse_duration(*st, peak))

    rng = np.random.default_rng(5)
    n, found = 200, 0
    for trial in range(40):
        t = np.concatenate([[0.0], np.sort(rng.uniform(0, 1, n - 1))])
        y = np.sin(rng.integers(1, 4) * np.pi * t) * (1 + rng.uniform(-1, 1) * t)
        y = np.maximum(0.0, y + [0.0, 0.05, 0.3][trial % 3] * rng.standard_normal(n)) ** 2
        y[0] = y[-1] = 0.0
        if trial % 4 == 0:
            y = np.round(y, 1)  # plateaus, and ties of the peak
        got, rise = (float(v) for v in stream(jnp.asarray(t), jnp.asarray(y)))
        if np.isfinite(got):
            found += 1
            pm = pulse_metrics(t, y)
            assert got == pytest.approx(pm.duration_10, rel=1e-12, abs=1e-15)
            assert rise == pytest.approx(pm.rise_time, rel=1e-12, abs=1e-15)
    assert found >= 35
    t = np.linspace(0.0, 1.0, 4 * PULSE_RING)
    y = np.sin(np.pi * t) ** 2  # a rising edge of ~1.6 PULSE_RING samples above the 10 % level
    assert np.all(np.isnan(np.asarray(stream(jnp.asarray(t), jnp.asarray(y)))))
