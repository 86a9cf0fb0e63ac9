"""Channel-frequency-class (CFC) filtering of measured shock data, as SAE J211-1 and ISO 6487 specify.

A CFC filter is a 2-pole low-pass Butterworth run forward and then backward over the record
(`scipy.signal.filtfilt`): 4 poles in all, no phase shift. SAE J211-1 (Appendix C) gives its
coefficients for a sample interval `T` as

    ω_d = 2π · CFC · 2.0775,    ω_a = tan(ω_d T / 2),    D = 1 + √2 ω_a + ω_a²,
    a0 = ω_a² / D,   a1 = 2 a0,   a2 = a0,   b1 = −2 (ω_a² − 1) / D,   b2 = (−1 + √2 ω_a − ω_a²) / D,
    y[k] = a0 x[k] + a1 x[k−1] + a2 x[k−2] + b1 y[k−1] + b2 y[k−2],

which is the bilinear-transform Butterworth of `scipy.signal.butter(2, 2.0775·CFC, fs=1/T)` (the
prewarped digital corner is 2.0775·CFC). One pass attenuates by `1/sqrt(1 + (tan(πfT)/ω_a)^4)`; the two
passes square it, so the response is −3 dB where `(f/(2.0775 CFC))^4 = √2 − 1`, i.e. at
`1.6667·CFC` (100, 300, 1000 and 1667 Hz for CFC 60, 180, 600, 1000): the standards' `F_N` (their
table rounds CFC 1000's to 1650 Hz); it is flat within 0.5 dB up to the standards' `F_H`, the CFC
frequency itself.

**The corridor** (the response's tolerance lines; ISO 6487's table, as restated in UN Regulation
No. 94, Rev. 4, Annex 8): `F_L ≤ 0.1 Hz`, `F_H = CFC`, `F_N` = 100, 300, 1000, 1650 Hz (about 5/3 CFC);
+0.5/−1 dB from `F_L` to `F_H`; +0.5/−4 dB at `F_N`; above `F_N` the upper line falls at −9 dB/octave
(to −30 dB) and the lower one at −24 dB/octave. tests/test_filters.py checks the filter inside it
at the lowest sample rate it accepts and at a hundred times F_N (margins: ≥ 0.5 dB in the passband,
≥ 1 dB at and above F_N). The reading of the table is secondary (docs/references.md, "Lab measures").

The record must be uniformly sampled (`t`, or a sample rate), at least 10 samples per cycle at `F_N`
(J211-1's guidance is a sample rate of at least 8 to 10 times F_N; below 10 the prewarping bends
the response and this refuses). The ends are padded by odd reflection (`filtfilt`'s default), so a
record that starts and ends at rest is filtered without end transients.

References: SAE J211-1, *Instrumentation for Impact Test — Part 1: Electronic Instrumentation*
(Appendix C, the digital filter); ISO 6487, *Road vehicles — Measurement techniques in impact tests —
Instrumentation*. The tests check the filter against the Appendix C recursion written out, the
closed-form response above and the corridor.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from .errors import ParameterError

__all__ = ["CFC_CLASSES", "cfc_coefficients", "cfc_filter", "cfc_response", "cfc_corner"]

#: The channel frequency classes of SAE J211-1 / ISO 6487 (a CFC number is a frequency in Hz).
CFC_CLASSES = (60, 180, 600, 1000)

#: J211-1 Appendix C's factor between the CFC and the single pass's digital corner frequency.
CORNER_FACTOR = 2.0775

#: Fewest samples per cycle at the −3 dB frequency F_N = 5/3 CFC that the filter accepts.
MIN_SAMPLES_PER_CYCLE = 10.0


def _check_cfc(cfc) -> int:
    if isinstance(cfc, bool) or cfc not in CFC_CLASSES:
        raise ParameterError("cfc", cfc, f"one of the channel frequency classes {', '.join(map(str, CFC_CLASSES))}")
    return int(cfc)


def cfc_corner(cfc: int) -> float:
    """The −3 dB frequency (Hz) of the forward-backward CFC filter, the standards' F_N:
    `2.0775·CFC·(√2 − 1)^(1/4)` (= 1.6667·CFC)."""
    return CORNER_FACTOR * _check_cfc(cfc) * (math.sqrt(2.0) - 1.0) ** 0.25


def cfc_coefficients(cfc: int, sample_rate: float) -> tuple[np.ndarray, np.ndarray]:
    """`(b, a)` of one pass of the CFC filter in `scipy.signal` form (`a[0] = 1`), for a sample rate in Hz.

    **Raises:** `ParameterError` for a class not in `CFC_CLASSES`, or a sample rate below
    `MIN_SAMPLES_PER_CYCLE` samples per cycle at F_N (the −3 dB frequency).
    """
    cfc = _check_cfc(cfc)
    fs = float(sample_rate)
    need = MIN_SAMPLES_PER_CYCLE * cfc_corner(cfc)
    if not (np.isfinite(fs) and fs >= need):
        raise ParameterError("sample_rate", sample_rate,
                             f"at least {need:.6g} Hz for CFC {cfc} ({MIN_SAMPLES_PER_CYCLE:g} samples per cycle at "
                             f"F_N = {cfc_corner(cfc):.6g} Hz, the -3 dB frequency)")
    b, a = signal.butter(2, CORNER_FACTOR * cfc, btype="low", fs=fs)
    return b, a


def cfc_response(cfc: int, sample_rate: float, frequencies_Hz) -> np.ndarray:
    """Amplitude response (a ratio, not dB) of the forward-backward CFC filter at the given frequencies:
    the square of one pass's `abs(H)`."""
    b, a = cfc_coefficients(cfc, sample_rate)
    _, h = signal.freqz(b, a, worN=np.asarray(frequencies_Hz, dtype=float), fs=float(sample_rate))
    return np.abs(h) ** 2


def _sample_rate(t) -> float:
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 3 or not np.all(np.isfinite(t)):
        raise ParameterError("t", f"{t.size} samples", "at least 3 finite, uniformly spaced times")
    dt = np.diff(t)
    h = (t[-1] - t[0]) / dt.size
    if not h > 0 or np.max(np.abs(dt - h)) > 1e-6 * h:
        raise ParameterError("t", f"steps from {dt.min():.6g} to {dt.max():.6g} s",
                             "uniformly spaced, increasing times (resample the record first)")
    return 1.0 / h


def cfc_filter(t, a, cfc: int) -> np.ndarray:
    """The record `a(t)` filtered by the channel frequency class `cfc` (SAE J211-1 / ISO 6487).

    **Arguments:**

    - `t`: uniformly spaced sample times (s), or a sample rate in Hz as a scalar.
    - `a`: the samples (any unit; the filter is linear), same length as `t`.
    - `cfc`: 60, 180, 600 or 1000.

    **Returns:** the filtered samples (same shape), phaseless (forward and backward passes).

    **Raises:** `ParameterError` for an unknown class, non-uniform times, non-finite samples, a record
    shorter than the filter's padding, or a sample rate under 10 samples per cycle at F_N.
    """
    fs = float(t) if np.ndim(t) == 0 else _sample_rate(t)
    x = np.asarray(a, dtype=float)
    if x.ndim != 1 or not np.all(np.isfinite(x)):
        raise ParameterError("a", "non-finite or not 1-D", "a 1-D array of finite samples")
    if np.ndim(t) != 0 and x.size != np.size(t):
        raise ParameterError("a", f"{x.size} samples", f"as many samples as times ({np.size(t)})")
    b, den = cfc_coefficients(cfc, fs)
    if x.size <= 3 * max(len(b), len(den)):
        raise ParameterError("a", f"{x.size} samples", "more than 9 samples (the filter's end padding)")
    return signal.filtfilt(b, den, x)
