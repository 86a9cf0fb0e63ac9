"""Shock response spectrum (SRS): maximax absolute acceleration of base-excited SDOF oscillators.

For every natural frequency `f_n` (`ω = 2π f_n`, damping ratio `ζ = 1/(2Q)`), the oscillator of
relative displacement `u` driven by the base acceleration `a(t)`,

    u'' + 2ζω u' + ω² u = −a(t),        absolute acceleration  x'' = −(2ζω u' + ω² u),

starts at rest, and the spectrum is the largest `|x''|` (the *maximax*, ISO 18431-4). It is split
into the **primary** part (during the pulse: `t <= T`, the end of the record by default) and the
**residual** part (`t >= T`: the record is followed by zeros for one period of each natural frequency,
enough since the free response decays, so its largest sample lies in its first period);
`maximax = max(primary, residual)`. `x''` is continuous, so both parts include `t = T`.

**The filter.** The oscillator is integrated exactly for an input that is linear between samples — the
ramp-invariant recursive filter of Smallwood (1981), standardised in ISO 18431-4 — with step
`T = 1/fs`, `A = ζωT`, `B = ω_d T = ωT·sqrt(1 − ζ²)` (`ζ = 1/(2Q)`, so `A = ωT/(2Q)` and
`B = ωT·sqrt(1 − 1/(4Q²))`):

    b = [1 − e^{−A} sin B / B,  2 e^{−A} (sin B / B − cos B),  e^{−2A} − e^{−A} sin B / B]
    a = [1,  −2 e^{−A} cos B,  e^{−2A}]

applied with `scipy.signal.lfilter` (these are the coefficients of `pyyeti.srs.absacce`, which cites
ISO 18431-4 and Smallwood 1981; the tests check the filter against an ODE solution). The filter is
exact for the piecewise-linear interpolant of the samples, so the only errors are (i) how well that
interpolant represents the signal and (ii) peak picking: the maximum is taken over samples, which can
miss the true peak by up to `1 − cos(π f_n/fs)` (0.2 % at 50 points per cycle, 4.9 % at 10).
Like pyyeti's `ic='zero'`, the oscillator is at rest one step before the first sample, where the input
is taken as zero: a record that does not start at zero begins with a one-step ramp. Subtract any
steady component (e.g. gravity during free fall) before calling.

**Sampling.** :func:`srs_uniform` works on uniformly sampled data as given. :func:`srs` accepts any
increasing time stamps (the simulator's adaptive steps) and applies this rule:

1. The *input rate* is judged where the pulse is: `fs_in = 1/max(dt_i)` over the steps with an end
   sample where `|a| >= 10 %` of the peak (elsewhere the interpolant is nearly flat and coarse steps
   are harmless). If `fs_in < min_ppc·f_max` (10 points per cycle by default), the record does not
   resolve the highest natural frequency: :class:`SRSResolutionWarning` is issued (`on_coarse="warn"`,
   the default), or :class:`~hertz_chain.errors.ParameterError` raised (`"raise"`), or nothing
   (`"ignore"`).
2. If the samples are uniform and their rate is already `>= ppc·f_max` (50 by default), they are used
   as they are. Otherwise the piecewise-linear interpolant is resampled (`numpy.interp`) onto a
   uniform grid that spans `[t[0], t[-1]]` exactly with `N = max(ceil(L·ppc·f_max), len(t) − 1)`
   intervals (`L = t[-1] − t[0]`); for uniform input the grid is refined by an integer factor, so the
   original samples are kept. Because the filter is exact for piecewise-linear input, this refinement
   changes nothing but the peak-picking error. When `pulse_end` is given (see below), the grid is
   built so that it is a grid point (:func:`resample_uniform` with `anchor`).
3. Primary and residual are split at `pulse_end` (default: the end of the record).

**Frequencies.** :func:`octave_frequencies` builds the standard 1/12-octave grid `f = 1000·2^{k/12}` Hz
(base 1 kHz) between two bounds; :func:`default_frequency_range` gives `[0.1/D, 20/D]` for a pulse
of 10 %-duration `D`, capped at `fs_in/min_ppc`. For a half-sine (Q = 10) the SRS at `f_n D = 0.1`
is 0.9 % below its low-frequency (impulse) asymptote and at `f_n D = 20` 0.13 % above its
high-frequency plateau, the peak of the input (measured; the asymptotes themselves are tested).

**Rounding.** The recursion has its poles near `z = 1` when `ωT << 1`, so its relative rounding
error grows with `fs/f_n`: measured on a half-sine against the ODE, ≈ 4e-9 at `fs/f_n = 2·10⁴`,
7e-8 at `2·10⁵`, 1e-6 at `10⁶`. The `b` coefficients are evaluated in a cancellation-free form
(`expm1`, a series for `sin B/B − 1`; the textbook form loses `ε/(ωT)²`); the rest is the direct-form
poles. The default band (`[0.1/D, 20/D]` at 50 points per cycle) has `fs/f_n <= 10⁴`.

References: ISO 18431-4:2007, *Mechanical vibration and shock — Signal processing — Part 4: Shock-
response spectrum analysis*; D. O. Smallwood, "An improved recursive formula for calculating shock
response spectra", *Shock and Vibration Bulletin* 51 (1981); pyyeti.srs (BSD-3), used as
the independent implementation in the tests.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
from scipy import signal

from .errors import ParameterError
from .pulse import _validate, pulse_metrics

__all__ = [
    "SRSOptions",
    "PEAKS",
    "KINDS",
    "relative_displacement_coefficients",
    "ShockResponseSpectrum",
    "SRSResolutionWarning",
    "octave_frequencies",
    "default_frequency_range",
    "smallwood_coefficients",
    "resample_uniform",
    "srs_uniform",
    "srs",
]

#: Default points per cycle at the highest natural frequency of the grid the filter runs on.
DEFAULT_PPC = 50.0
#: Points per cycle below which the input record is said not to resolve a natural frequency.
MIN_PPC = 10.0


#: Which extreme of the response a spectrum takes: the largest magnitude, or the largest positive or
#: negative value (`pyyeti.srs.srs`'s `peak`).
PEAKS = ("abs", "pos", "neg")
#: What the spectrum is of: the absolute acceleration of the oscillator, or its pseudo-velocity
#: `ω·z` (z the relative displacement; `pyyeti.srs.srs`'s `stype="pvelo"`).
KINDS = ("acceleration", "pseudo-velocity")


@dataclasses.dataclass(frozen=True)
class SRSOptions:
    """How a report's SRS is computed (the stack file's `[srs]` section).

    - `Q`: amplification factor `1/(2ζ)` (10);
    - `per_octave`: points per octave of the frequency grid (12);
    - `band`: `(f_min, f_max)` in Hz, or None for the default band (at least 100 Hz-10 kHz and
      `[0.1/D, 20/D]`);
    - `peak`: `"abs"` (maximax), `"pos"` or `"neg"`;
    - `kind`: `"acceleration"` (absolute, in g in the report) or `"pseudo-velocity"` (m/s).
    """

    Q: float = 10.0
    per_octave: int = 12
    band: tuple[float, float] | None = None
    peak: str = "abs"
    kind: str = "acceleration"

    def __post_init__(self):
        _check_q(self.Q)
        if isinstance(self.per_octave, bool) or int(self.per_octave) != self.per_octave or not 1 <= self.per_octave <= 48:
            raise ParameterError("per_octave", self.per_octave, "an integer number of points per octave, 1 to 48")
        if self.band is not None:
            lo, hi = (float(x) for x in self.band)
            if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
                raise ParameterError("band", self.band, "(f_min, f_max) in Hz with 0 < f_min < f_max")
        if self.peak not in PEAKS:
            raise ParameterError("peak", self.peak, f"one of {', '.join(PEAKS)}")
        if self.kind not in KINDS:
            raise ParameterError("kind", self.kind, f"one of {', '.join(KINDS)}")


class SRSResolutionWarning(UserWarning):
    """The input is sampled too coarsely to resolve the highest natural frequency."""


@dataclasses.dataclass(frozen=True, eq=False)
class ShockResponseSpectrum:
    """A maximax absolute-acceleration SRS, in the units of the input (m/s² or g).

    | field | meaning |
    |---|---|
    | `frequencies_Hz` | natural frequencies `f_n` (Hz) |
    | `primary` | largest `abs(x'')` during the record |
    | `residual` | largest `abs(x'')` after the record (zero padding) |
    | `maximax` | `max(primary, residual)` |
    | `Q` | amplification factor `1/(2ζ)` |
    | `sample_rate_Hz` | rate of the uniform grid the filter ran on |

    The arrays are read-only.
    """

    # arrays out of the repr (a notebook's echo of a report printed hundreds of lines)
    frequencies_Hz: np.ndarray = dataclasses.field(repr=False)
    primary: np.ndarray = dataclasses.field(repr=False)
    residual: np.ndarray = dataclasses.field(repr=False)
    maximax: np.ndarray = dataclasses.field(repr=False)
    Q: float
    sample_rate_Hz: float
    kind: str = "acceleration"  # or "pseudo-velocity" (`KINDS`)
    peak: str = "abs"  # or "pos", "neg" (`PEAKS`)


# --------------------------------------------------------------------------------------------------
# frequencies


def octave_frequencies(
    f_min: float, f_max: float, per_octave: int = 12, f_ref: float = 1000.0
) -> np.ndarray:
    """The fractional-octave grid `f_ref·2^{k/per_octave}` (integer `k`) inside `[f_min, f_max]`.

    Default: 1/12 octave centred on 1 kHz. Bounds that are grid points (to 1e-9 relative) are included.
    Raises :class:`~hertz_chain.errors.ParameterError` if the bounds are not `0 < f_min <= f_max` or no
    grid point falls between them.
    """
    f_min, f_max = float(f_min), float(f_max)
    if not (np.isfinite(f_min) and f_min > 0):
        raise ParameterError("f_min", f_min, "a finite frequency > 0 Hz")
    if not (np.isfinite(f_max) and f_max >= f_min):
        raise ParameterError("f_max", f_max, f"a finite frequency >= f_min = {f_min} Hz")
    if int(per_octave) != per_octave or per_octave < 1:
        raise ParameterError("per_octave", per_octave, "a positive integer")
    if not (np.isfinite(f_ref) and f_ref > 0):
        raise ParameterError("f_ref", f_ref, "a finite frequency > 0 Hz")
    k0 = math.ceil(per_octave * math.log2(f_min / f_ref) - 1e-9)
    k1 = math.floor(per_octave * math.log2(f_max / f_ref) + 1e-9)
    if k1 < k0:
        raise ParameterError(
            "f_max", f_max, f"a range [f_min, f_max] holding a 1/{per_octave}-octave point (f_min = {f_min})"
        )
    return f_ref * 2.0 ** (np.arange(k0, k1 + 1) / per_octave)


def default_frequency_range(
    duration: float,
    sample_rate: float | None = None,
    *,
    low: float = 0.1,
    high: float = 20.0,
    min_ppc: float = MIN_PPC,
) -> tuple[float, float]:
    """Default SRS band `[low/D, high/D]` for a pulse of duration `D` (s), with `f_max` capped at
    `sample_rate/min_ppc` when the sample rate of the record is given (see the module docstring)."""
    if not (np.isfinite(duration) and duration > 0):
        raise ParameterError("duration", duration, "a finite pulse duration > 0 s")
    if not (0 < low < high):
        raise ParameterError("low, high", (low, high), "factors with 0 < low < high")
    f_min, f_max = low / duration, high / duration
    if sample_rate is not None:
        if not (np.isfinite(sample_rate) and sample_rate > 0):
            raise ParameterError("sample_rate", sample_rate, "a finite sample rate > 0 Hz")
        f_max = min(f_max, sample_rate / min_ppc)
    if f_max < f_min:
        raise ParameterError(
            "sample_rate", sample_rate, f"at least {min_ppc * f_min:.6g} Hz to cover f_min = {f_min:.6g} Hz"
        )
    return f_min, f_max


# --------------------------------------------------------------------------------------------------
# the filter


def _check_q(Q: float) -> float:
    Q = float(Q)
    if not (np.isfinite(Q) and Q > 0.5):
        raise ParameterError("Q", Q, "a finite amplification factor > 0.5 (underdamped oscillators)")
    return Q


def _check_frequencies(frequencies_Hz) -> np.ndarray:
    f = np.atleast_1d(np.asarray(frequencies_Hz, dtype=float))
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ParameterError("frequencies_Hz", frequencies_Hz, "a non-empty 1-D array of frequencies > 0 Hz")
    return f


def smallwood_coefficients(frequencies_Hz, sample_rate: float, Q: float = 10.0):
    """Ramp-invariant filter coefficients `(b, a)`, each of shape `(len(f), 3)`, for the absolute
    acceleration of base-excited oscillators (Smallwood 1981; ISO 18431-4). See the module docstring."""
    f = _check_frequencies(frequencies_Hz)
    Q = _check_q(Q)
    if not (np.isfinite(sample_rate) and sample_rate > 0):
        raise ParameterError("sample_rate", sample_rate, "a finite sample rate > 0 Hz")
    wT = 2.0 * np.pi * f / float(sample_rate)
    A = wT / (2.0 * Q)
    B = wT * np.sqrt(1.0 - 1.0 / (4.0 * Q * Q))
    E = np.exp(-A)
    em1 = np.expm1(-A)  # e^{-A} - 1
    sm1 = _sinc_m1(B)  # sin B / B - 1
    # the textbook forms, rearranged to avoid cancellation when ωT << 1:
    b0 = -em1 * (1.0 + sm1) - sm1  # 1 - e^{-A} sinB/B
    b1 = 2.0 * E * (sm1 + 2.0 * np.sin(0.5 * B) ** 2)  # 2 e^{-A} (sinB/B - cosB)
    b2 = E * (em1 - sm1)  # e^{-2A} - e^{-A} sinB/B
    b = np.stack([b0, b1, b2], axis=-1)
    a = np.stack([np.ones_like(E), -2.0 * E * np.cos(B), E * E], axis=-1)
    return b, a


def _sinc_m1(x: np.ndarray) -> np.ndarray:
    """`sin(x)/x − 1`, accurate for small `x` (Taylor series below 0.1, error < 1e-19)."""
    x = np.asarray(x, dtype=float)
    x2 = x * x
    series = -x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0)))
    with np.errstate(invalid="ignore", divide="ignore"):
        direct = np.sin(x) / x - 1.0
    return np.where(np.abs(x) < 0.1, series, direct)


def relative_displacement_coefficients(frequencies_Hz, sample_rate: float, Q: float = 10.0):
    """Ramp-invariant filter coefficients `(b, a)`, each `(len(f), 3)`, for the relative displacement
    `z` of base-excited oscillators, `z'' + 2ζω z' + ω² z = −a(t)`: the first-order-hold discretisation
    (`scipy.signal.cont2discrete(..., method="foh")`), exact for input linear between samples like
    Smallwood's acceleration filter. The pseudo-velocity is `ω·z`.

    The discretisation runs in the oscillator's own time `τ = ωt` (step `ωT`), where every entry of the
    matrix exponential is O(1); in seconds the input column is O(T²) beside an O(1) identity and
    loses its digits (6 % at `fs/f_n = 10⁵`). The transfer function of the 2×2 system is written out
    (`b = [D, C·B − D·tr A_d, C·M·B + D·det A_d]`, `M = adj(zI − A_d) − zI`), not taken from
    `scipy.signal.ss2tf`'s difference of polynomials."""
    f = _check_frequencies(frequencies_Hz)
    Q = _check_q(Q)
    bs, as_ = [], []
    for fj in f:
        w = 2.0 * np.pi * fj
        h = w / float(sample_rate)  # the step in units of 1/ω
        A = np.array([[0.0, 1.0], [-1.0, -1.0 / Q]])
        Ad, Bd, Cd, Dd, _ = signal.cont2discrete((A, np.array([[0.0], [-1.0]]), np.array([[1.0, 0.0]]),
                                                  np.zeros((1, 1))), h, method="foh")
        B, C, D = Bd[:, 0], Cd[0], float(Dd[0, 0])
        tr, det = Ad[0, 0] + Ad[1, 1], Ad[0, 0] * Ad[1, 1] - Ad[0, 1] * Ad[1, 0]
        M = np.array([[-Ad[1, 1], Ad[0, 1]], [Ad[1, 0], -Ad[0, 0]]])
        b = np.array([D, C @ B - D * tr, C @ M @ B + D * det]) / (w * w)  # z = z_τ / ω² (input in m/s²)
        bs.append(b)
        as_.append(np.array([1.0, -tr, det]))
    return np.array(bs), np.array(as_)


def srs_uniform(
    a, sample_rate: float, frequencies_Hz, Q: float = 10.0, *, n_primary: int | None = None,
    peak: str = "abs", kind: str = "acceleration",
) -> ShockResponseSpectrum:
    """Maximax SRS of a uniformly sampled base acceleration `a` (any units; the SRS has the same).

    No resampling: the peaks are picked on the given samples (error up to `1 − cos(π f_n/fs)`; see
    the module docstring). The primary part is the first `n_primary` samples (default: all of `a`),
    the residual part the last of them, the rest of `a` and then one period of each natural
    frequency, `ceil(fs/f_n) + 1` zero samples (`pyyeti.srs.srs` pads for the lowest one). The
    residual includes the response at the last primary sample because `x''` is continuous
    (`u`, `u'` are), so `sup_{t > T} |x''|` includes its limit at `T`; pyyeti starts its residual one
    step later, which differs where the residual peaks at the end of the pulse (low `f_n·D`).

    `peak` (`PEAKS`): the largest `abs`olute value (default), or the largest `pos`itive or `neg`ative
    (reported as a magnitude). `kind` (`KINDS`): the absolute acceleration (default, in the input's
    units) or the pseudo-velocity `ω·z` (`relative_displacement_coefficients`; input in m/s² gives m/s).
    """
    if peak not in PEAKS:
        raise ParameterError("peak", peak, f"one of {', '.join(PEAKS)}")
    if kind not in KINDS:
        raise ParameterError("kind", kind, f"one of {', '.join(KINDS)}")
    x = np.asarray(a, dtype=float)
    if x.ndim != 1 or x.size < 1 or not np.all(np.isfinite(x)):
        raise ParameterError("a", f"array of shape {x.shape}", "a non-empty 1-D array of finite values")
    if n_primary is None:
        n_primary = x.size
    if int(n_primary) != n_primary or not 1 <= n_primary <= x.size:
        raise ParameterError("n_primary", n_primary, f"an integer number of samples in [1, {x.size}]")
    n_primary = int(n_primary)
    f = _check_frequencies(frequencies_Hz)
    Q = _check_q(Q)
    fs = float(sample_rate)
    if kind == "acceleration":
        b, den = smallwood_coefficients(f, fs, Q)
        scale = np.ones(f.size)
    else:
        b, den = relative_displacement_coefficients(f, fs, Q)
        scale = 2.0 * np.pi * f
    pick = {"abs": np.abs, "pos": lambda y: y, "neg": lambda y: -y}[peak]
    primary = np.empty(f.size)
    residual = np.empty(f.size)
    for j in range(f.size):  # one lfilter call per natural frequency (the time loop is in C)
        y, zf = signal.lfilter(b[j], den[j], x, zi=np.zeros(2))
        primary[j] = scale[j] * max(np.max(pick(y[:n_primary])), 0.0)
        yr, _ = signal.lfilter(b[j], den[j], np.zeros(math.ceil(fs / f[j]) + 1), zi=zf)
        residual[j] = scale[j] * max(np.max(pick(yr)), np.max(pick(y[n_primary - 1 :])), 0.0)
    maximax = np.maximum(primary, residual)
    for arr in (f, primary, residual, maximax):
        arr.setflags(write=False)
    return ShockResponseSpectrum(f, primary, residual, maximax, Q, fs, kind, peak)


# --------------------------------------------------------------------------------------------------
# non-uniform input


def _is_uniform(t: np.ndarray, rtol: float = 1e-9) -> bool:
    """All steps equal to their mean within `rtol` (plus the rounding of the time stamps)."""
    dt = np.diff(t)
    h = (t[-1] - t[0]) / dt.size
    return bool(np.all(np.abs(dt - h) <= rtol * h + 4 * np.finfo(float).eps * np.max(np.abs(t))))


def _active_sample_rate(t: np.ndarray, a: np.ndarray, fraction: float = 0.1) -> float:
    """`1/max(dt)` over the steps with an end sample where `|a| >= fraction·max|a|`."""
    active = np.abs(a) >= fraction * np.max(np.abs(a))
    steps = active[1:] | active[:-1]
    return float(1.0 / np.max(np.diff(t)[steps]))


def resample_uniform(
    t, a, sample_rate: float, anchor: float | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """Linear interpolation of `(t, a)` onto a uniform grid at a rate `>= sample_rate`.

    Without `anchor`, the grid spans `[t[0], t[-1]]` exactly with
    `N = max(ceil(L·sample_rate), len(t) − 1)` intervals (`L = t[-1] − t[0]`); if `t` is already
    uniform, `N` is rounded up to a multiple of `len(t) − 1` and the original samples are kept exactly.
    With `anchor` (a time in `(t[0], t[-1]]`, e.g. the end of the pulse), the grid spans
    `[t[0], anchor]` exactly with `ceil((anchor − t[0])·sample_rate)` intervals and continues with the
    same step to the first point `>= t[-1]` (where `a` is held at `a[-1]` for less than one step).
    Returns `(t_uniform, a_uniform, actual_rate)`.
    """
    t, a = _validate(t, a)
    if not (np.isfinite(sample_rate) and sample_rate > 0):
        raise ParameterError("sample_rate", sample_rate, "a finite sample rate > 0 Hz")
    L = float(t[-1] - t[0])
    if anchor is not None:
        if not (np.isfinite(anchor) and t[0] < anchor <= t[-1]):
            raise ParameterError("anchor", anchor, f"a time in (t[0], t[-1]] = ({t[0]!r}, {t[-1]!r}]")
        n1 = math.ceil((anchor - t[0]) * sample_rate - 1e-9)
        h = (anchor - t[0]) / n1
        n = n1 + math.ceil((t[-1] - anchor) / h - 1e-9)
        tu = t[0] + h * np.arange(n + 1)
        tu[n1] = anchor
        return tu, np.interp(tu, t, a), 1.0 / h
    n = max(math.ceil(L * sample_rate - 1e-9), t.size - 1)
    if _is_uniform(t):  # refine each step into k equal parts; the original samples stay exact
        k = math.ceil(n / (t.size - 1))
        frac = np.arange(k) / k
        au = (a[:-1, None] + (a[1:] - a[:-1])[:, None] * frac).ravel()
        tu = (t[:-1, None] + np.diff(t)[:, None] * frac).ravel()
        return np.append(tu, t[-1]), np.append(au, a[-1]), k * (t.size - 1) / L
    tu = t[0] + L * np.arange(n + 1) / n
    tu[-1] = t[-1]
    return tu, np.interp(tu, t, a), n / L


def srs(
    t,
    a,
    frequencies_Hz=None,
    *,
    Q: float = 10.0,
    ppc: float = DEFAULT_PPC,
    min_ppc: float = MIN_PPC,
    per_octave: int = 12,
    on_coarse: str = "warn",
    pulse_end: float | None = None,
    peak: str = "abs",
    kind: str = "acceleration",
) -> ShockResponseSpectrum:
    """Maximax SRS (primary, residual, overall) of the base acceleration `a` sampled at times `t`.

    **Arguments:**

    - `t`: sample times (s), strictly increasing, uniform or not (adaptive solver steps).
    - `a`: base acceleration at `t`, in m/s² or g (the SRS comes back in the same units).
    - `frequencies_Hz`: natural frequencies; default: the 1/`per_octave`-octave grid
      (:func:`octave_frequencies`) over :func:`default_frequency_range` of the main pulse's 10 %
      duration (:func:`hertz_chain.pulse.pulse_metrics`) and the input rate.
    - `Q`: amplification factor, `Q = 1/(2ζ)` (10).
    - `ppc`: points per cycle at the highest frequency of the grid the filter runs on (50).
    - `min_ppc`: points per cycle of the *input* below which it is called too coarse (10).
    - `on_coarse`: `"warn"` (:class:`SRSResolutionWarning`), `"raise"` (`ParameterError`) or `"ignore"`.
    - `peak`, `kind`: as :func:`srs_uniform` (`"abs"`/`"pos"`/`"neg"`; `"acceleration"` or
      `"pseudo-velocity"`).
    - `pulse_end`: time (s) that separates the primary part (`t <= pulse_end`) from the residual part
      (`t >= pulse_end`, the rest of the record and then the zero padding). Default: the end of the
      record (the ISO 18431-4 / pyyeti convention). A record that goes on, quiet, after the pulse
      needs it (e.g. `t_end_10` or the end of the last contact), or its primary part includes the
      free vibration after the pulse.

    The sampling rule is in the module docstring (linear interpolation onto a uniform grid).
    """
    t, x = _validate(t, a)
    Q = _check_q(Q)
    if on_coarse not in ("warn", "raise", "ignore"):
        raise ParameterError("on_coarse", on_coarse, "'warn', 'raise' or 'ignore'")
    if not (np.isfinite(ppc) and ppc >= 2):
        raise ParameterError("ppc", ppc, "points per cycle >= 2")
    if not (np.isfinite(min_ppc) and min_ppc >= 2):
        raise ParameterError("min_ppc", min_ppc, "points per cycle >= 2")
    if not np.any(x != 0):
        raise ParameterError("a", "all zeros", "a record with a non-zero acceleration")
    fs_in = _active_sample_rate(t, x)
    if frequencies_Hz is None:
        duration = pulse_metrics(t, x).duration_10
        f = octave_frequencies(*default_frequency_range(duration, fs_in, min_ppc=min_ppc), per_octave)
    else:
        f = _check_frequencies(frequencies_Hz)
    f_max = float(np.max(f))
    if fs_in < min_ppc * f_max and on_coarse != "ignore":
        msg = (
            f"the pulse is sampled at {fs_in:.6g} Hz (largest step where |a| >= 10 % of the peak), "
            f"fewer than {min_ppc:g} points per cycle at f_max = {f_max:.6g} Hz"
        )
        if on_coarse == "raise":
            raise ParameterError("t", msg, f"a sample rate >= {min_ppc * f_max:.6g} Hz")
        warnings.warn(msg + "; the SRS at high frequencies reflects the linear interpolation",
                      SRSResolutionWarning, stacklevel=2)
    if pulse_end is not None:
        if not (np.isfinite(pulse_end) and t[0] < pulse_end):
            raise ParameterError("pulse_end", pulse_end, f"a time > t[0] = {t[0]!r} s, or None")
        if pulse_end >= t[-1]:
            pulse_end = None  # the whole record is primary
    fs = (t.size - 1) / (t[-1] - t[0])
    on_grid = pulse_end is None or np.min(np.abs(t - pulse_end)) <= 1e-6 / fs
    if _is_uniform(t) and fs >= ppc * f_max and on_grid:
        tu = t
    else:  # pulse_end, if given, becomes a grid point
        tu, x, fs = resample_uniform(t, x, ppc * f_max, anchor=pulse_end)
    n_primary = None
    if pulse_end is not None:  # grid points at or before pulse_end (to a millionth of a step)
        n_primary = int(np.searchsorted(tu, pulse_end + 1e-6 / fs, side="right"))
    return srs_uniform(x, fs, f, Q, n_primary=n_primary, peak=peak, kind=kind)
