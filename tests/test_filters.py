"""CFC filters (SAE J211-1 Appendix C / ISO 6487): coefficients, response, and refusals.

References:
- SAE J211-1 Appendix C, written out here: w_d = 2 pi CFC 2.0775, w_a = tan(w_d T/2),
  a0 = w_a^2/(1 + sqrt2 w_a + w_a^2), a1 = 2 a0, a2 = a0, b1 = -2 (w_a^2 - 1)/(...),
  b2 = (-1 + sqrt2 w_a - w_a^2)/(...), y[k] = a0 x[k] + a1 x[k-1] + a2 x[k-2] + b1 y[k-1] + b2 y[k-2],
  run forward and backward.
- The bilinear Butterworth's response in closed form: one pass |H|^2 = 1/(1 + (tan(pi f T)/w_a)^4), so the
  forward-backward response is 1/(1 + (tan(pi f T)/w_a)^4), -3 dB at F_H = 2.0775 CFC (sqrt2 - 1)^(1/4).
"""

import numpy as np
import pytest

from hertz_chain.errors import ParameterError
from hertz_chain.filters import CFC_CLASSES, cfc_coefficients, cfc_corner, cfc_filter, cfc_response


def j211_coefficients(cfc, fs):
    wd = 2 * np.pi * cfc * 2.0775
    wa = np.sin(wd / fs / 2) / np.cos(wd / fs / 2)
    den = 1 + np.sqrt(2) * wa + wa**2
    a0 = wa**2 / den
    b1 = -2 * (wa**2 - 1) / den
    b2 = (-1 + np.sqrt(2) * wa - wa**2) / den
    return np.array([a0, 2 * a0, a0]), np.array([1.0, -b1, -b2])  # scipy's sign convention for the poles


def j211_filter(x, cfc, fs):
    """The J211-1 recursion, written as a loop, forward then backward (zero initial state)."""
    (a0, a1, a2), (_, mb1, mb2) = j211_coefficients(cfc, fs)

    def one(u):
        y = np.zeros_like(u)
        for k in range(len(u)):
            y[k] = (a0 * u[k] + (a1 * u[k - 1] if k >= 1 else 0) + (a2 * u[k - 2] if k >= 2 else 0)
                    - (mb1 * y[k - 1] if k >= 1 else 0) - (mb2 * y[k - 2] if k >= 2 else 0))
        return y

    return one(one(x)[::-1])[::-1]


@pytest.mark.parametrize("cfc", CFC_CLASSES)
@pytest.mark.parametrize("fs", [2e4, 1e5, 1e6])
def test_coefficients_are_j211_appendix_c(cfc, fs):
    b, a = cfc_coefficients(cfc, fs)
    rb, ra = j211_coefficients(cfc, fs)
    np.testing.assert_allclose(b, rb, rtol=1e-12)
    np.testing.assert_allclose(a, ra, rtol=1e-12, atol=1e-15)


def test_filter_equals_the_j211_recursion_away_from_the_ends():
    """Same pulse, the J211 loop with zero start (the record starts and ends at rest, padded with zeros)
    against cfc_filter (odd-reflection padding): equal to 1e-9 of the peak."""
    fs, cfc = 1e5, 600
    t = np.arange(0, 0.02, 1 / fs)
    x = np.where((t > 0.005) & (t < 0.006), np.sin(np.pi * (t - 0.005) / 0.001), 0.0)
    np.testing.assert_allclose(cfc_filter(t, x, cfc), j211_filter(x, cfc, fs), atol=1e-9)


@pytest.mark.parametrize("cfc", CFC_CLASSES)
def test_response_closed_form_and_corner(cfc):
    fs = 50 * cfc
    wa = np.tan(np.pi * 2.0775 * cfc / fs)
    f = np.geomspace(0.1, 10 * cfc, 200)
    closed = 1 / (1 + (np.tan(np.pi * f / fs) / wa) ** 4)
    np.testing.assert_allclose(cfc_response(cfc, fs, f), closed, rtol=1e-10, atol=1e-14)
    # F_H = 5/3 CFC within 0.04 %: 100, 300, 1000, 1667 Hz (the standards round CFC 1000's to 1650 Hz)
    assert cfc_corner(cfc) == pytest.approx(5 / 3 * cfc, rel=4e-4)


def test_filtered_sine_has_the_closed_form_amplitude():
    """A long sine through filtfilt: its amplitude in the middle of the record is the closed-form
    forward-backward response (to 1e-6)."""
    cfc, fs = 180, 1e4
    wa = np.tan(np.pi * 2.0775 * cfc / fs)
    t = np.arange(0, 2.0, 1 / fs)
    for f in (50.0, 180.0, 300.0, 600.0):
        y = cfc_filter(t, np.sin(2 * np.pi * f * t), cfc)
        mid = (t > 0.5) & (t < 1.5)
        amp = np.sqrt(2 * np.mean(y[mid] ** 2))
        assert amp == pytest.approx(1 / (1 + (np.tan(np.pi * f / fs) / wa) ** 4), rel=1e-4, abs=1e-6)


def test_constant_passes_unchanged():
    t = np.arange(0, 0.01, 1e-5)
    np.testing.assert_allclose(cfc_filter(t, np.full(t.size, 3.5), 1000), 3.5, rtol=1e-12)
    np.testing.assert_allclose(cfc_filter(1e5, np.full(t.size, 3.5), 1000), 3.5, rtol=1e-12)  # a sample rate


@pytest.mark.parametrize("args, key", [
    ((np.arange(100) * 1e-5, np.zeros(100), 500), "cfc"),
    ((np.arange(100) * 1e-5, np.zeros(100), True), "cfc"),
    ((np.r_[0, np.cumsum(np.linspace(1, 2, 99)) * 1e-5], np.zeros(100), 60), "t"),
    ((np.arange(100) * 1e-3, np.zeros(100), 1000), "sample_rate"),  # 1 kHz < 10 x 1667 Hz
    ((np.arange(100) * 1e-5, np.r_[np.zeros(99), np.nan], 60), "a"),
    ((np.arange(100) * 1e-5, np.zeros(99), 60), "a"),
    ((np.arange(5) * 1e-5, np.zeros(5), 60), "a"),
])
def test_bad_input_is_one_clear_error(args, key):
    with pytest.raises(ParameterError) as err:
        cfc_filter(*args)
    assert err.value.name == key and "\n" not in str(err.value)


#: The corridor of ISO 6487's table as restated in UN Regulation No. 94, Rev. 4, Annex 8 (a secondary,
#: machine-read copy; docs/references.md, "Lab measures"): F_N per class, the passband F_L..F_H = CFC.
F_N = {60: 100.0, 180: 300.0, 600: 1000.0, 1000: 1650.0}


@pytest.mark.parametrize("cfc", CFC_CLASSES)
@pytest.mark.parametrize("per_fn", [10.01, 100.0])
def test_response_lies_in_the_corridor(cfc, per_fn):
    """+0.5/-1 dB from 0.1 Hz to F_H = CFC; +0.5/-4 dB at F_N; above F_N under the upper line (+0.5 dB
    at F_N, -9 dB/octave, floor -30 dB) up to 0.4 fs, and over the lower line (-4 dB at F_N,
    -24 dB/octave) down to -30 dB; at the lowest sample rate the filter accepts (10 per cycle at its
    -3 dB frequency, 1.667 CFC) and at 100 F_N."""
    fs = per_fn * max(F_N[cfc], 5 / 3 * cfc)
    db = lambda f: 20 * np.log10(cfc_response(cfc, fs, f))  # noqa: E731
    band = db(np.geomspace(0.1, cfc, 300))
    assert band.max() <= 0.5 and band.min() >= -1.0
    assert -4.0 <= db([F_N[cfc]])[0] <= 0.5
    f = np.geomspace(F_N[cfc], 0.4 * fs, 300)
    r = db(f)
    upper = np.maximum(0.5 - 9 * np.log2(f / F_N[cfc]), -30.0)
    lower = -4.0 - 24 * np.log2(f / F_N[cfc])
    assert np.all(r <= upper)
    assert np.all(r[lower >= -30.0] >= lower[lower >= -30.0])
