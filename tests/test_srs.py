"""Tests of hertz_chain.spectrum: the maximax absolute-acceleration shock response spectrum.

Independent references:

* an ODE solution (scipy.integrate.solve_ivp, DOP853, rtol 1e-12) of the base-excited oscillator
  `u'' + 2ζω u' + ω² u = −a(t)`, absolute acceleration `x'' = −(2ζω u' + ω² u)`, whose extrema are
  located by a fine grid refined with scipy.optimize.minimize_scalar;
* pyyeti.srs.srs (BSD-3; ISO 18431-4 / Smallwood 1981 filter, `ic='zero'`, `stype='absacce'`,
  `peak='abs'`, `rolloff='none'`, `time='primary'|'residual'|'total'`);
* closed forms: the impulse-response limit at low frequency, the quasi-static limit at high frequency
  (`H(s) = 1 − s²/ω² + O(s³)`), and the published half-sine value (≈ 1.65 A near `f_n D ≈ 0.83`,
  docs/references.md).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from pyyeti import srs as pyyeti_srs
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from hertz_chain.errors import ParameterError
from hertz_chain.spectrum import (
    ShockResponseSpectrum,
    SRSResolutionWarning,
    default_frequency_range,
    octave_frequencies,
    resample_uniform,
    smallwood_coefficients,
    srs,
    srs_uniform,
)

A = 1000.0  # m/s²
D = 1.0e-3  # s
Q = 10.0
ZETA = 1.0 / (2.0 * Q)


def half_sine_samples(fs, amp=A, dur=D):
    """Uniform samples of a half-sine on [0, D] (both ends are samples; the last is exactly 0)."""
    n = round(dur * fs)
    t = np.arange(n + 1) / fs
    a = amp * np.sin(np.pi * t / dur)
    a[-1] = 0.0
    return t, a


# --------------------------------------------------------------------------------------------------
# ODE reference


def ode_abs_acc(fn, base, knots, q=Q):
    """Absolute acceleration x''(t) of the oscillator at rest at knots[0] under `base(t)`, integrated
    piece by piece between `knots` (where `base` may have a kink), as a vectorised callable."""
    w = 2.0 * np.pi * fn
    z = 1.0 / (2.0 * q)

    def rhs(t, y):
        return [y[1], -base(t) - 2.0 * z * w * y[1] - w * w * y[0]]

    scale = A / w**2 + A * D / w  # displacement scale of the quasi-static and the impulse regimes
    pieces, y0 = [], [0.0, 0.0]
    for ta, tb in zip(knots[:-1], knots[1:]):
        sol = solve_ivp(rhs, (ta, tb), y0, method="DOP853", rtol=1e-12,
                        atol=[1e-15 * scale, 1e-15 * scale * w], dense_output=True)
        assert sol.success
        pieces.append((ta, tb, sol.sol))
        y0 = sol.y[:, -1]

    def acc(t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.full(t.shape, np.nan)
        for ta, tb, s in pieces:
            m = (t >= ta) & (t <= tb)
            if m.any():
                y = s(t[m])
                out[m] = -(2.0 * z * w * y[1] + w * w * y[0])
        assert np.all(np.isfinite(out))
        return out

    return acc


def window_max(acc, ta, tb, n=20001):
    """max |acc| over [ta, tb]: fine grid, then a bounded scalar search around the best grid point."""
    tt = np.linspace(ta, tb, n)
    v = np.abs(acc(tt))
    i = int(np.argmax(v))
    lo, hi = tt[max(i - 1, 0)], tt[min(i + 1, n - 1)]
    r = minimize_scalar(lambda s: -abs(acc(s)[0]), bounds=(lo, hi), method="bounded",
                        options={"xatol": 1e-18})
    return max(v[i], -r.fun)


def half_sine_base(t):
    return A * math.sin(math.pi * t / D) if 0.0 <= t <= D else 0.0


FS_ODE = 2.0e6  # Hz: 2 000 samples per D
LIN_ERR = (math.pi / (D * FS_ODE)) ** 2 / 12  # 2.06e-7: the linear interpolant of the half-sine is
# on average (πh/D)²/12 below it, so every response of the filter is that much smaller


@pytest.mark.parametrize("fD", [0.05, 0.2, 0.5, 0.83, 1.5, 3.0, 10.0])
def test_half_sine_against_ode(fD):
    """Primary, residual and maximax of a half-sine against the ODE solution of the true half-sine.

    Windows: primary = [0, D] (the record), residual = [D, D + 1/f_n], maximax = [0, D + 1/f_n].
    Tolerance: the peak-picking bound `1 − cos(π f_n/fs)` (≤ 1.2e-4 here) + 1.1·LIN_ERR + 1e-9
    (relative)."""
    fn = fD / D
    acc = ode_abs_acc(fn, half_sine_base, [0.0, D, D + 1.0 / fn])
    ref_p = window_max(acc, 0.0, D)
    ref_r = window_max(acc, D, D + 1.0 / fn)
    ref_m = max(ref_p, ref_r)
    _, a = half_sine_samples(FS_ODE)
    s = srs_uniform(a, FS_ODE, [fn], Q)
    tol = (1.0 - math.cos(math.pi * fn / FS_ODE)) + 1.1 * LIN_ERR + 1e-9
    assert s.primary[0] == pytest.approx(ref_p, rel=tol)
    assert s.residual[0] == pytest.approx(ref_r, rel=tol)
    assert s.maximax[0] == pytest.approx(ref_m, rel=tol)
    # at the sample times themselves there is no peak-picking error, only the interpolation of the
    # input: the filter's extrema are (1 − LIN_ERR) times the ODE's, to 5e-9
    ts = np.arange(math.floor((D + 1.0 / fn) * FS_ODE) + 1) / FS_ODE
    v = np.abs(acc(ts))
    n_rec = round(D * FS_ODE) + 1
    assert s.primary[0] / v[:n_rec].max() - 1.0 == pytest.approx(-LIN_ERR, abs=5e-9)
    assert s.residual[0] / v[n_rec - 1 :].max() - 1.0 == pytest.approx(-LIN_ERR, abs=5e-9)


def test_filter_is_exact_for_piecewise_linear_input():
    """Terminal-peak sawtooth on a coarse grid (20 steps per D, then a one-step drop to zero): the ramp-
    invariant filter is exact for the piecewise-linear input, so its sampled extrema equal the ODE's
    at the same sample times to 1e-9 relative, even at 3 points per cycle."""
    fs = 20.0 / D
    n = 20
    tk = np.arange(n + 2) / fs  # knots: ramp 0..A over n steps, then 0 at step n+1
    ak = np.concatenate((A * np.arange(n + 1) / n, [0.0]))
    for fn in (0.3 / D, 1.0 / D, 3.0 / D, 6.6 / D):
        t_end = tk[-1] + 2.0 / fn
        knots = np.concatenate((tk, [t_end]))
        acc = ode_abs_acc(fn, lambda t: float(np.interp(t, tk, ak, right=0.0)), knots)
        ts = np.arange(math.floor(t_end * fs) + 1) / fs
        v = np.abs(acc(ts))
        s = srs_uniform(ak[:-1], fs, [fn], Q)  # the record stops at the peak; zeros follow
        assert s.primary[0] == pytest.approx(v[: n + 1].max(), rel=1e-9)
        assert s.residual[0] == pytest.approx(v[n:].max(), rel=1e-9)


# --------------------------------------------------------------------------------------------------
# asymptotes and the published half-sine value


def impulse_peak_ratio(q):
    """max |x''| / (ω ΔV) of the oscillator after a base velocity step ΔV (closed-form free response
    u = −(ΔV/ω_d) e^{−ζωt} sin ω_d t; ω = 1), located on a fine grid and refined."""
    z = 1.0 / (2.0 * q)
    wd = math.sqrt(1.0 - z * z)

    def xdd(t):
        e = np.exp(-z * t)
        u = -e * np.sin(wd * t) / wd
        up = -e * (np.cos(wd * t) - z * np.sin(wd * t) / wd)
        return -(2.0 * z * up + u)

    tt = np.linspace(0.0, 2.0 * np.pi, 200001)
    i = int(np.argmax(np.abs(xdd(tt))))
    r = minimize_scalar(lambda s: -abs(xdd(s)), bounds=(tt[i - 1], tt[i + 1]), method="bounded",
                        options={"xatol": 1e-14})
    return -r.fun


@pytest.mark.parametrize("q", [10.0, 50.0])
def test_low_frequency_asymptote(q):
    """f_n D → 0: the pulse acts as an impulse ΔV = 2AD/π; the SRS (residual) → c(Q)·2πf_n·ΔV, with
    c(Q) from the closed-form impulse response (c → 1, the undamped ω ΔV, as Q → ∞). The relative
    gap is O((f_n D)²): below 1e-4 at f_n D = 0.01 and ≈ 4× smaller at 0.005."""
    c = impulse_peak_ratio(q)
    assert 0.9 < c < 1.0
    fs = 4.0e6
    _, a = half_sine_samples(fs)
    dv = 2.0 * A * D / math.pi
    errs = []
    for fD in (0.01, 0.005):
        fn = fD / D
        s = srs_uniform(a, fs, [fn], q)
        assert s.maximax[0] == s.residual[0]
        errs.append(abs(s.residual[0] / (c * 2.0 * math.pi * fn * dv) - 1.0))
    assert errs[0] < 1e-4
    assert 3.0 < errs[0] / errs[1] < 5.0


@pytest.mark.parametrize("fD", [100.0, 200.0])
def test_high_frequency_asymptote(fD):
    """f_n D → ∞: the oscillator follows the base, x'' = a − a''/ω² + O(ω⁻³)
    (H(s) = 1 − s²/ω² + ...), so the SRS → A·(1 + 1/(4 (f_n D)²)) at the crest; checked to 1e-7 (the
    input interpolation error (πh/D)²/12 = 5e-8 at fs = 4 MHz)."""
    fs = 4.0e6
    _, a = half_sine_samples(fs)
    s = srs_uniform(a, fs, [fD / D], Q)
    assert s.maximax[0] / A - 1.0 == pytest.approx(1.0 / (4.0 * fD**2), abs=1e-7)


def test_half_sine_published_peak():
    """Half-sine, Q = 10: the SRS peaks at ≈ 1.65 A near f_n D ≈ 0.83 (docs/references.md, 'Shock pulses');
    published to two digits, checked to ±0.01 A and ±0.02 in f_n D."""
    fs = 1.0e6
    _, a = half_sine_samples(fs)
    f = np.linspace(0.6, 1.1, 501) / D
    s = srs_uniform(a, fs, f, Q)
    i = int(np.argmax(s.maximax))
    assert s.maximax[i] / A == pytest.approx(1.65, abs=0.01)
    assert f[i] * D == pytest.approx(0.83, abs=0.02)


# --------------------------------------------------------------------------------------------------
# pyyeti


def _pulses():
    fs = 200_000.0
    _, hs = half_sine_samples(fs)
    n = round(D * fs)
    saw = A * np.arange(n + 1) / n  # terminal-peak sawtooth; zeros follow (a one-step drop)
    rng = np.random.default_rng(7)
    noisy = hs + 0.1 * A * rng.standard_normal(hs.size)  # neither starts nor ends at zero
    return fs, {"half-sine": hs, "sawtooth": saw, "noisy": noisy}


@pytest.mark.parametrize("name", ["half-sine", "sawtooth", "noisy"])
def test_against_pyyeti(name):
    """Same samples, Q, frequencies (1/12 octave, 50 Hz–10 kHz, ≥ 20 points per cycle, so pyyeti does
    no resampling with rolloff='none'): primary, residual and total agree to 1e-6 relative
    (measured ≈ 1e-9: pyyeti evaluates the coefficients in their textbook form, with cancellation).
    pyyeti's residual starts one step after the record; ours also holds the last record sample (see
    srs_uniform), so the reference residual is max(pyyeti residual, |pyyeti response at that sample|)."""
    fs, pulses = _pulses()
    a = pulses[name]
    f = octave_frequencies(50.0, 10_000.0)
    mine = srs_uniform(a, fs, f, Q)
    opts = dict(ic="zero", stype="absacce", peak="abs", rolloff="none", parallel="no")
    for time, got in (("primary", mine.primary), ("total", mine.maximax)):
        ref = pyyeti_srs.srs(a, fs, f, Q, time=time, **opts)
        np.testing.assert_allclose(got, ref, rtol=1e-6, err_msg=time)
    ref_r = pyyeti_srs.srs(a, fs, f, Q, time="residual", **opts)
    _, resp = pyyeti_srs.srs(a, fs, f, Q, time="total", getresp=True, **opts)
    last = np.abs(resp["hist"][a.size - 1, 0, :])
    np.testing.assert_allclose(mine.residual, np.maximum(ref_r, last), rtol=1e-6)
    if name != "noisy":  # the extra sample matters (end of pulse at low f_n D; the sawtooth's crest)
        assert np.any(last > ref_r)


def test_coefficients_match_pyyeti_absacce():
    """The rearranged coefficients equal pyyeti.srs.absacce (textbook form) for ωT in [0.01, 2]
    (1e-10 relative, the textbook form's cancellation there) and have the exact limits as ωT → 0:
    b → [0, 0, 0] like ωT (b₀ ≈ A + B²/6), a → [1, −2, 1]."""
    fs = 1.0
    f = np.geomspace(0.01, 2.0, 40) / (2 * np.pi)
    b, a = smallwood_coefficients(f, fs, Q)
    for j, fj in enumerate(f):
        bp, ap = pyyeti_srs.absacce(Q, 1.0 / fs, 2 * np.pi * fj)
        np.testing.assert_allclose(b[j], bp, rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(a[j], ap, rtol=1e-14)
    wT = 1e-6
    b, a = smallwood_coefficients([wT / (2 * np.pi)], 1.0, Q)
    AA, BB = wT / (2 * Q), wT * math.sqrt(1 - 1 / (4 * Q * Q))
    # Taylor series to 3rd order: b0 = A − A²/2 + B²/6, b1 = 2B²/3 (1 − A), b2 = −A + 3A²/2 + B²/6
    assert b[0, 0] == pytest.approx(AA - AA**2 / 2 + BB**2 / 6, rel=1e-9)
    assert b[0, 1] == pytest.approx(2 * BB**2 / 3, rel=1e-5)
    assert b[0, 2] == pytest.approx(-AA + 1.5 * AA**2 + BB**2 / 6, rel=1e-9)
    # unit gain at DC: Σb = Σa = (1 − e^{−A})² + 4 e^{−A} sin²(B/2)
    # (the accurate form of 1 − 2e^{−A}cosB + e^{−2A})
    sum_a = math.expm1(-AA) ** 2 + 4 * math.exp(-AA) * math.sin(BB / 2) ** 2
    assert b[0].sum() == pytest.approx(sum_a, rel=1e-9)


# --------------------------------------------------------------------------------------------------
# frequencies, sampling and the public entry point


def test_octave_frequencies():
    f = octave_frequencies(100.0, 10_000.0)
    assert 1000.0 in f  # centred on 1 kHz
    np.testing.assert_allclose(f[1:] / f[:-1], 2.0 ** (1 / 12), rtol=1e-14)
    # k from ceil(12 log2 0.1) = −39 to floor(12 log2 10) = 39: 79 points
    assert f.size == 79 and f[0] == pytest.approx(1000.0 * 2.0 ** (-39 / 12), rel=1e-15)
    assert f[0] >= 100.0 and f[-1] <= 10_000.0
    assert f[0] / 2 ** (1 / 12) < 100.0 and f[-1] * 2 ** (1 / 12) > 10_000.0
    np.testing.assert_allclose(octave_frequencies(500.0, 2000.0, per_octave=1), [500.0, 1000.0, 2000.0])
    with pytest.raises(ParameterError):
        octave_frequencies(1010.0, 1050.0)  # no 1/12-octave point inside
    with pytest.raises(ParameterError):
        octave_frequencies(0.0, 10.0)


def test_default_frequency_range():
    assert default_frequency_range(1e-3) == pytest.approx((100.0, 20_000.0))
    assert default_frequency_range(1e-3, 100_000.0) == pytest.approx((100.0, 10_000.0))  # fs/10
    with pytest.raises(ParameterError):
        default_frequency_range(1e-3, 500.0)  # cannot resolve even f_min
    with pytest.raises(ParameterError):
        default_frequency_range(-1.0)


def test_resample_uniform_keeps_uniform_samples():
    t = np.linspace(0.0, 1e-3, 11)
    a = np.arange(11.0) ** 2
    tu, au, rate = resample_uniform(t, a, 25_000.0)  # asks 25 kHz from 10 kHz: factor 3
    assert tu.size == 31 and rate == pytest.approx(30_000.0)
    np.testing.assert_array_equal(au[::3], a)
    assert tu[-1] == t[-1]


def test_srs_on_fine_uniform_input_is_srs_uniform():
    """Uniform input already at ≥ ppc·f_max is used as given: identical to srs_uniform."""
    fs = 1.0e6
    t, a = half_sine_samples(fs)
    f = octave_frequencies(100.0, 20_000.0)
    s1, s2 = srs(t, a, f), srs_uniform(a, fs, f)
    np.testing.assert_array_equal(s1.maximax, s2.maximax)
    assert s1.sample_rate_Hz == pytest.approx(fs)


def test_srs_refines_coarse_uniform_input():
    """Uniform input at 12.5 points per cycle at f_max is refined by linear interpolation (factor 4);
    the filter is exact for that interpolant, so the maxima can only grow (original samples kept) and
    get closer to the true ones (computed at 1 MHz, where peak picking errs by < 2e-3 at 10 kHz)."""
    t, a = half_sine_samples(125_000.0)
    f = octave_frequencies(100.0, 10_000.0)
    raw = srs_uniform(a, 125_000.0, f)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # 12.5 ≥ min_ppc: no warning
        ref = srs(t, a, f, ppc=50)
    assert ref.sample_rate_Hz == pytest.approx(500_000.0)
    assert np.all(ref.maximax >= raw.maximax * (1 - 1e-10))  # 1e-10: rounding, ~ε(fs/f_n)²
    _, a_fine = half_sine_samples(1.0e6)
    true = srs_uniform(a_fine, 1.0e6, f).maximax
    assert np.max(np.abs(ref.maximax / true - 1)) < np.max(np.abs(raw.maximax / true - 1))
    assert np.max(np.abs(ref.maximax / true - 1)) < 2.5e-3


def test_srs_nonuniform_time_stamps():
    """Adaptive-like steps: 0.05 µs…2 µs during the pulse, 50 µs steps in the quiet tail (2 ms). The
    resampled SRS, split at pulse_end = D, equals the SRS of a fine uniform half-sine to the
    interpolation error of the steps ((π·2e-6/D)²/8 = 5e-6) plus the peak picking at ppc = 50 (2e-3)."""
    rng = np.random.default_rng(3)
    steps = rng.uniform(0.05e-6, 2e-6, 2000)
    t_pulse = np.concatenate(([0.0], np.cumsum(steps)))
    t_pulse = t_pulse[t_pulse < D]
    t = np.concatenate((t_pulse, [D], D + 50e-6 * np.arange(1, 40)))
    a = np.where(t <= D, A * np.sin(np.pi * np.clip(t, 0, D) / D), 0.0)
    a[t >= D] = 0.0
    f = octave_frequencies(100.0, 10_000.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the coarse tail does not count: no warning
        s = srs(t, a, f, pulse_end=D)
    assert s.sample_rate_Hz >= 50 * f[-1]
    _, a_fine = half_sine_samples(2.0e6)
    ref = srs_uniform(a_fine, 2.0e6, f)
    np.testing.assert_allclose(s.maximax, ref.maximax, rtol=2.5e-3)
    np.testing.assert_allclose(s.primary, ref.primary, rtol=2.5e-3)
    np.testing.assert_allclose(s.residual, ref.residual, rtol=2.5e-3)
    # without pulse_end the quiet tail is part of the record: the primary part then holds the free
    # vibration after the pulse, so it is the maximax
    s_rec = srs(t, a, f)
    np.testing.assert_allclose(s_rec.primary, ref.maximax, rtol=2.5e-3)


def test_coarse_input_warns_or_raises():
    t, a = half_sine_samples(50_000.0)  # 5 points per cycle at 10 kHz
    f = octave_frequencies(100.0, 10_000.0)
    with pytest.warns(SRSResolutionWarning):
        srs(t, a, f)
    with pytest.raises(ParameterError):
        srs(t, a, f, on_coarse="raise")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        srs(t, a, f, on_coarse="ignore")


def test_default_frequencies_and_result_type():
    """No frequencies given: 1/12 octave over [0.1/D10, 20/D10] for the 10 % duration D10 = 0.93623 D."""
    t, a = half_sine_samples(1.0e6)
    t = np.concatenate((t, D + 1e-6 * np.arange(1, 200)))
    a = np.concatenate((a, np.zeros(199)))
    s = srs(t, a)
    assert isinstance(s, ShockResponseSpectrum) and s.Q == 10.0
    d10 = 0.93623 * D
    assert s.frequencies_Hz[0] >= 0.1 / d10 * (1 - 1e-6) and s.frequencies_Hz[0] < 0.1 / d10 * 2 ** (1 / 12)
    assert s.frequencies_Hz[-1] <= 20 / d10 and s.frequencies_Hz[-1] > 20 / d10 / 2 ** (1 / 12)
    np.testing.assert_array_equal(s.maximax, np.maximum(s.primary, s.residual))
    with pytest.raises(ValueError):
        s.maximax[0] = 0.0  # read-only
    with pytest.raises(AttributeError):
        s.Q = 5.0  # frozen


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda t, a: srs(t, a, [1000.0], Q=0.5), "Q"),
        (lambda t, a: srs(t, 0 * a, [1000.0]), "a"),
        (lambda t, a: srs(t[::-1], a, [1000.0]), "t"),
        (lambda t, a: srs(t, a, [0.0, 1000.0]), "frequencies_Hz"),
        (lambda t, a: srs(t, a, [1000.0], on_coarse="maybe"), "on_coarse"),
        (lambda t, a: srs_uniform(a, 1e6, [1000.0], Q=float("nan")), "Q"),
    ],
)
def test_bad_input_raises(call, name):
    t, a = half_sine_samples(1.0e6)
    with pytest.raises(ParameterError) as info:
        call(t, a)
    assert info.value.name == name


@pytest.mark.parametrize("kind, stype", [("acceleration", "absacce"), ("pseudo-velocity", "pvelo")])
@pytest.mark.parametrize("peak", ["abs", "pos", "neg"])
@pytest.mark.parametrize("q", [10.0, 25.0])
def test_options_against_pyyeti(kind, stype, peak, q):
    """Positive, negative and absolute peaks, absolute acceleration and pseudo-velocity (omega times the
    relative displacement), two Q: the maximax (time='total') equals pyyeti's. Acceleration: the same
    filter (measured 1e-11); pseudo-velocity: ours is the first-order-hold (ramp-invariant)
    discretisation by scipy.signal.cont2discrete, pyyeti's its closed-form recursion (measured 3e-10 at
    fs/f_n <= 4000; test_pseudo_velocity_at_high_oversampling_against_an_ode goes further)."""
    fs, pulses = _pulses()
    a = pulses["sawtooth"]
    f = octave_frequencies(50.0, 10_000.0, 6)
    mine = srs_uniform(a, fs, f, q, peak=peak, kind=kind)
    ref = pyyeti_srs.srs(a, fs, f, q, ic="zero", stype=stype, peak=peak, time="total", rolloff="none",
                         parallel="no")
    np.testing.assert_allclose(mine.maximax, np.abs(ref), rtol=1e-9 if kind == "acceleration" else 1e-8)
    assert (mine.kind, mine.peak) == (kind, peak)


def test_srs_options_refuse_bad_values():
    from hertz_chain.spectrum import SRSOptions

    for kw, key in (({"Q": 0.4}, "Q"), ({"per_octave": 0}, "per_octave"), ({"band": (10, 5)}, "band"),
                    ({"peak": "max"}, "peak"), ({"kind": "velocity"}, "kind")):
        with pytest.raises(ParameterError) as err:
            SRSOptions(**kw)
        assert err.value.name == key


def test_pseudo_velocity_at_high_oversampling_against_an_ode():
    """fs/f_n = 10^5 (a 1 ms half-sine at 20 MHz, f_n = 200 Hz): the pseudo-velocity equals omega times
    the largest relative displacement of the oscillator integrated by scipy DOP853 (rtol 1e-11) on the
    same piecewise-linear input, to 1e-7 (measured 1e-8; a discretisation in seconds lost 6 % here)."""
    fs, fn, q = 2e7, 200.0, 25.0
    t = np.arange(0, 1.2e-3, 1 / fs)
    a = np.where(t < 1e-3, np.sin(np.pi * t / 1e-3), 0.0) * 1000.0
    w, z = 2 * np.pi * fn, 1 / (2 * q)
    sol = solve_ivp(lambda s, y: [y[1], -np.interp(s, t, a) * (s <= t[-1]) - 2 * z * w * y[1] - w * w * y[0]],
                    (0, t[-1] + 2 / fn), [0.0, 0.0], method="DOP853", rtol=1e-11, atol=1e-14, max_step=2e-6,
                    dense_output=True)
    zz = sol.sol(np.linspace(0, t[-1] + 2 / fn, 400_001))[0]
    got = srs_uniform(a, fs, [fn], q, kind="pseudo-velocity").maximax[0]
    assert got == pytest.approx(w * np.max(np.abs(zz)), rel=1e-7)


def test_pseudo_velocity_of_a_drop_over_five_decades_is_the_damped_velocity_step(tmp_path):
    """The widest band a stack file allows (1 Hz-100 kHz, 5 decades; fs/f = 5e6 at 1 Hz): far below the
    pulse's frequencies (contact ~0.3 ms) the pulse is a velocity step dV of the oscillator's base, whose
    largest relative displacement is (dV/w) exp(-zeta acos(zeta)/sqrt(1 - zeta^2)) (the damped free
    response (dV/w_d) e^(-zeta w t) sin(w_d t) at its first maximum, w_d t = acos zeta); PV = w z_max.
    dV: the accelerometer's integral over the top's contact, from the run's own velocities
    (launch - impact speed). Agreement to 1e-3 at 1 Hz (the pulse's length, w T ~ 2e-3, is the error)."""
    import hertz_chain as hc

    path = tmp_path / "pv.toml"
    path.write_text("""
[drop]
impact_velocity = "1 m/s"
gravity = 0
[stack]
masses = ["1 kg", "0.1 kg"]
gaps = "1 mm"
[contact]
law = "hertz"
stiffness = "1e9 N/m^1.5"
[srs]
type = "pseudo-velocity"
band = ["1 Hz", "100 kHz"]
""")
    rep = hc.simulate_file(path)
    s = rep.top_srs
    assert s.frequencies_Hz[0] <= 1.0 and s.frequencies_Hz[-1] >= 1e5
    dv = rep.launch_velocities[-1] + 1.0  # from -1 m/s (falling) to the launch velocity
    z = 0.05
    k = int(np.argmin(np.abs(s.frequencies_Hz - 1.0)))
    assert s.maximax[k] == pytest.approx(dv * math.exp(-z * math.acos(z) / math.sqrt(1 - z * z)), rel=1e-3)
