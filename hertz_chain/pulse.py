"""Metrics of an acceleration pulse sampled at arbitrary (e.g. adaptive-step) times.

The analysis calls :func:`pulse_metrics` for the acceleration history `a(t)` of every mass of the
stack. The samples are read as the **piecewise-linear interpolant** through `(t_i, a_i)`: every level
crossing is located by linear interpolation between the two bracketing samples, and every integral is
the exact integral of that interpolant (the trapezoid rule on non-uniform steps). Nothing else is
assumed about the sampling, so the solver's adaptive steps can be used as they are.

Definitions (the classical shock-test vocabulary: MIL-STD-810H Method 516.8 and MIL-STD-883
Method 2002 specify half-sine pulses by their *peak* and *duration*; the duration of a measured pulse
is read between its 10 % points, as in docs/references.md, "Shock pulses"):

* **dominant sign** `s`: +1 if `max(a) >= -min(a)`, else −1 (ties go to +1). All the metrics below are
  taken on `s·a`, so that the main pulse is positive; `peak` is a magnitude (> 0) and `sign` keeps `s`.
* **peak** `= max(s·a)` and **time of peak**: the first sample reaching it or, when the caller passes
  the `velocity` (as the report does), the largest value of the slope of the velocity's cubic Hermite
  interpolant between the samples around it (so the report's peak can exceed the exported samples,
  by O(h²) of the local step; docs/references.md, "Peaks between steps").
* **main pulse at level L**: the maximal interval around the peak over which `s·a(t) >= L·peak`.
  `t_start_10`/`t_end_10` are its ends for `L = duration_level` (10 % by default) and
  **duration_10** their difference. Half-sine of duration `D`: `(1 − 2 asin(0.1)/π)·D = 0.93623·D`.
* **rise time**: from the start of the main pulse at `rise_levels[0]` (10 %) to the first upward
  crossing of `rise_levels[1]` (90 %) inside it. Half-sine: `(asin 0.9 − asin 0.1)·D/π = 0.32497·D`.
* **delta_v** `= ∫ a dt` over the whole record, signed, in m/s (or the exact value if the caller passes
  one, e.g. the difference of the simulated velocities). Half-sine: `ΔV = 2AD/π`.
* **delta_v_main**: `∫ a dt` over the *main lobe* — the interval around the peak bounded by the
  zero crossings of `s·a` (or the record ends) — signed like `delta_v`. For a record that holds one
  pulse it equals `delta_v`; for a bouncing record it is the velocity change of the main impact only.
* **equivalent half-sine duration** `= π·|delta_v_main| / (2·peak)`: the duration of the half-sine
  with the same peak and the same velocity change (= `D` for a half-sine). It is always > 0.
* **n_pulses**: the number of separate episodes where `|a(t)| >= pulse_threshold·peak`
  (10 % by default), the interpolant returning below the threshold between two episodes. A pulse of
  the opposite sign that exceeds the threshold counts as a separate pulse; noise that chatters around
  the threshold counts every excursion (raise the threshold for noisy data).
* **truncated**: True when the main pulse (at any of the levels above) reaches the first or the last
  sample, or its lobe does while above `LOBE_EDGE` (0.1 %) of the peak, i.e. the record cut the pulse;
  the durations are then measured to the record end.

Degenerate input (fewer than 2 samples, non-finite values, time not strictly increasing, an
all-zero record, levels outside (0, 1)) raises :class:`~hertz_chain.errors.ParameterError`; no metric
is ever NaN.
"""

from __future__ import annotations

import dataclasses

import math

import numpy as np

from .constants import G0
from .errors import ParameterError

__all__ = ["G0", "PulseMetrics", "pulse_metrics", "to_g", "from_g", "count_pulses"]



def to_g(a):
    """Convert an acceleration from m/s² to g (`g0 = 9.80665 m/s²`)."""
    return np.asarray(a, dtype=float) / G0


def from_g(a_g):
    """Convert an acceleration from g to m/s² (`g0 = 9.80665 m/s²`)."""
    return np.asarray(a_g, dtype=float) * G0


@dataclasses.dataclass(frozen=True)
class PulseMetrics:
    """Metrics of one acceleration pulse (SI units; see the module docstring for the definitions).

    | field | unit | meaning |
    |---|---|---|
    | `peak` | m/s² | maximum of `s·a` (> 0) |
    | `peak_g` | g | `peak / 9.80665` |
    | `sign` | – | dominant sign `s` (+1 or −1) |
    | `time_of_peak` | s | time of the (first) peak sample |
    | `t_start_10`, `t_end_10` | s | ends of the main pulse at `duration_level` |
    | `duration_10` | s | `t_end_10 − t_start_10` |
    | `rise_time` | s | `rise_levels[0]` → `rise_levels[1]` on the rising edge; NaN where the record starts above `rise_levels[1]` of the peak (no rising edge in it) |
    | `delta_v` | m/s | `∫ a dt` over the record (signed) |
    | `delta_v_main` | m/s | `∫ a dt` over the main lobe (signed) |
    | `equivalent_half_sine_duration` | s | `π·abs(delta_v_main)/(2·peak)` |
    | `n_pulses` | – | episodes with `abs(a) >= pulse_threshold·peak` |
    | `truncated` | – | the record cuts the main pulse |
    """

    peak: float
    peak_g: float
    sign: int
    time_of_peak: float
    t_start_10: float
    t_end_10: float
    duration_10: float
    rise_time: float
    delta_v: float
    delta_v_main: float
    equivalent_half_sine_duration: float
    n_pulses: int
    truncated: bool


# --------------------------------------------------------------------------------------------------
# validation and piecewise-linear helpers


def _validate(t, a) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=float)
    a = np.asarray(a, dtype=float)
    if t.ndim != 1:
        raise ParameterError("t", f"array of shape {t.shape}", "a 1-D array of sample times")
    if a.shape != t.shape:
        raise ParameterError("a", f"array of shape {a.shape}", f"a 1-D array of the shape of t {t.shape}")
    if t.size < 2:
        raise ParameterError("t", f"{t.size} sample(s)", "at least 2 samples")
    if not np.all(np.isfinite(t)):
        raise ParameterError("t", "array with non-finite values", "finite sample times")
    if not np.all(np.isfinite(a)):
        raise ParameterError("a", "array with non-finite values", "finite accelerations")
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise ParameterError(
            "t", f"t[{i}] = {t[i]!r}, t[{i + 1}] = {t[i + 1]!r}", "strictly increasing sample times"
        )
    return t, a


def _check_level(name: str, value: float) -> float:
    value = float(value)
    if not (0.0 < value < 1.0):
        raise ParameterError(name, value, "a fraction of the peak strictly between 0 and 1")
    return value


def _cross(t: np.ndarray, y: np.ndarray, i: int, level: float) -> float:
    """Time where the line from sample `i` to `i+1` reaches `level` (`y[i]` and `y[i+1]` bracket it)."""
    y0, y1 = y[i], y[i + 1]
    frac = (level - y0) / (y1 - y0)
    return float(t[i] + frac * (t[i + 1] - t[i]))


#: the fraction of the peak above which a lobe that reaches the record's first or last sample is cut
#: (`truncated`)
LOBE_EDGE = 1e-3


def _bounds(t: np.ndarray, y: np.ndarray, ip: int, level: float, strict: bool):
    """Ends of the maximal interval around sample `ip` over which the interpolant of `y` stays at or
    above `level` (above, if `strict`). Returns `(t_start, t_end, i_first, i_last, truncated)`, where
    `i_first..i_last` are the samples inside the interval."""
    below = (y <= level) if strict else (y < level)
    left = np.flatnonzero(below[:ip])
    right = np.flatnonzero(below[ip:])
    truncated = False
    if left.size:
        j = int(left[-1])
        t_start, i_first = _cross(t, y, j, level), j + 1
    else:
        t_start, i_first, truncated = float(t[0]), 0, True
    if right.size:
        k = ip + int(right[0])
        t_end, i_last = _cross(t, y, k - 1, level), k - 1
    else:
        t_end, i_last, truncated = float(t[-1]), y.size - 1, True
    return t_start, t_end, i_first, i_last, truncated


def _integral_to(t: np.ndarray, y: np.ndarray, cum: np.ndarray, tau: float) -> float:
    """Exact integral of the piecewise-linear interpolant of `y` from `t[0]` to `tau`."""
    i = int(np.clip(np.searchsorted(t, tau, side="right") - 1, 0, t.size - 2))
    h = tau - t[i]
    y_tau = y[i] + (y[i + 1] - y[i]) * h / (t[i + 1] - t[i])
    return float(cum[i] + 0.5 * h * (y[i] + y_tau))


#: `_refine_peak` refines the peak on a step only where both its ends carry more than this fraction of
#: the peak (a step from free flight, zero, into a contact whose force jumps is not refined)
PEAK_STEP_FLOOR = 0.01


def _refine_peak(t, v, a, ip, sign, peak, t_peak, smooth=None):
    """Largest `sign·a` of the quadratic `a(t) = v'(t)` of the cubic Hermite interpolant of `v`
    (values `v`, slopes `a`) on the two steps around sample `ip`; O(h^3) instead of O(h^2). Only on a
    step whose two ends are both inside the pulse (`sign·a` above `PEAK_STEP_FLOOR` of the peak): across
    a contact's onset the acceleration jumps (a dashpot's force is largest at first touch), and the
    interpolant there overshot (a review: 1155 g for a hertz-dashpot contact whose peak is 866.5 g); and,
    with `smooth` (one boolean per step), only on smooth steps."""
    for i in (ip - 1, ip):
        if i < 0 or i + 1 >= t.size or (smooth is not None and not smooth[i]):
            continue
        if not (sign * a[i] > PEAK_STEP_FLOOR * peak and sign * a[i + 1] > PEAK_STEP_FLOOR * peak):
            continue
        h = t[i + 1] - t[i]
        dv = (v[i + 1] - v[i]) / h
        # v'(s) on [0, h] for the Hermite cubic, as a quadratic c2 s^2 + c1 s + c0
        c3 = (a[i] + a[i + 1] - 2 * dv) / h**2
        c2 = (3 * dv - 2 * a[i] - a[i + 1]) / h
        q2, q1 = 3 * c3, 2 * c2
        if q2 == 0:
            continue
        s = -q1 / (2 * q2)
        if 0.0 < s < h:
            val = sign * (q2 * s * s + q1 * s + a[i])
            if val > peak:
                peak, t_peak = float(val), float(t[i] + s)
    return peak, t_peak


def count_pulses(t, a, threshold: float = 0.1) -> int:
    """Number of separate episodes where `|a(t)| >= threshold·max|a|` (see the module docstring).

    Two consecutive samples on opposite sides (one `>= +thr`, the next `<= -thr`) belong to two
    episodes, since the interpolant passes through the band `|a| < thr` between them.
    """
    t, a = _validate(t, a)
    threshold = _check_level("threshold", threshold)
    amax = float(np.max(np.abs(a)))
    if amax == 0.0:
        raise ParameterError("a", "all zeros", "a record with a non-zero acceleration")
    thr = threshold * amax
    state = np.where(a >= thr, 1, np.where(a <= -thr, -1, 0))
    starts = (state != 0) & np.concatenate(([True], state[1:] != state[:-1]))
    return int(np.count_nonzero(starts))


def pulse_metrics(
    t,
    a,
    *,
    delta_v: float | None = None,
    velocity=None,
    smooth=None,
    duration_level: float = 0.1,
    rise_levels: tuple[float, float] = (0.1, 0.9),
    pulse_threshold: float = 0.1,
) -> PulseMetrics:
    """Peak, 10 % duration, rise time, ΔV, equivalent half-sine duration and pulse count of `a(t)`.

    **Arguments:**

    - `t`: sample times in s, 1-D, strictly increasing, not necessarily uniform.
    - `a`: accelerations in m/s² at `t` (convert from g with :func:`from_g`).
    - `delta_v`: the exact velocity change over the record, if known (m/s); otherwise the trapezoid
      integral of the samples is used.
    - `velocity`: optional exact running integral of `a` at the samples (m/s; e.g. the simulated
      velocity `v + g t` of the mass). When given, ΔV and the main-lobe ΔV use it instead of the
      trapezoid rule, so they are exact at the samples (only the lobe ends, where `a ≈ 0`, are
      interpolated). The peak is then refined between the samples (the slope of the velocity's cubic
      Hermite interpolant).
    - `smooth`: optional booleans (with `velocity`, which the refinement needs), one per step between
      samples (`(len(t) - 1,)`): whether the
      acceleration is smooth across it (no contact of the mass opens or closes inside it); the peak is
      refined only on smooth steps (across a contact's kink the interpolant overshoots: a middle mass
      pushed by a dashpot contact read +9.8 %, a review).
    - `duration_level`: level of the duration points, as a fraction of the peak (0.1).
    - `rise_levels`: the two levels of the rise time (0.1, 0.9).
    - `pulse_threshold`: threshold fraction of the peak that defines separate pulses (0.1).

    **Returns:** a :class:`PulseMetrics`. The definitions (dominant sign, main pulse, main lobe, ...)
    are those of the module docstring; the half-sine values quoted there are the analytic references
    (MIL-STD-810H Method 516.8 half-sine; ΔV = 2AD/π).

    **Raises:** :class:`~hertz_chain.errors.ParameterError` for fewer than 2 samples, non-finite
    values, non-increasing times, an all-zero record, or levels outside (0, 1).
    """
    t, a = _validate(t, a)
    duration_level = _check_level("duration_level", duration_level)
    lo, hi = (float(x) for x in rise_levels)
    _check_level("rise_levels[0]", lo)
    _check_level("rise_levels[1]", hi)
    if not lo < hi:
        raise ParameterError("rise_levels", rise_levels, "two fractions (lo, hi) with 0 < lo < hi < 1")
    pulse_threshold = _check_level("pulse_threshold", pulse_threshold)
    if delta_v is not None and not np.isfinite(delta_v):
        raise ParameterError("delta_v", delta_v, "a finite velocity change in m/s, or None")

    amax, amin = float(np.max(a)), float(np.min(a))
    sign = 1 if amax >= -amin else -1
    y = sign * a
    ip = int(np.argmax(y))
    peak = float(y[ip])
    if peak == 0.0:
        raise ParameterError("a", "all zeros", "a record with a non-zero acceleration")

    # main pulse at the duration level
    t0, t1, _, _, trunc_d = _bounds(t, y, ip, duration_level * peak, strict=False)

    # rise time: start of the main pulse at `lo`, first upward crossing of `hi` inside it
    t_lo, _, i_lo, _, trunc_r = _bounds(t, y, ip, lo * peak, strict=False)
    m = i_lo + int(np.argmax(y[i_lo : ip + 1] >= hi * peak))  # exists: y[ip] = peak > hi·peak
    # y[m-1] < hi·peak <= y[m] (for m == i_lo > 0, y[m-1] < lo·peak); m == 0 only when truncated
    t_hi = float(t[0]) if m == 0 else _cross(t, y, m - 1, hi * peak)
    # a record that starts above `hi` has no rising edge: its rise time is not measured (was 0)
    rise_time = math.nan if m == 0 else t_hi - t_lo

    # integrals of the interpolant
    if velocity is not None:
        vel = np.asarray(velocity, dtype=float)
        if vel.shape != a.shape or not np.all(np.isfinite(vel)):
            raise ParameterError("velocity", vel.shape, f"finite values of the shape of a {a.shape}")
        cum = vel - vel[0]
    else:
        cum = np.concatenate(([0.0], np.cumsum(0.5 * np.diff(t) * (a[1:] + a[:-1]))))
    dv = float(cum[-1]) if delta_v is None else float(delta_v)
    z0, z1, _, _, trunc_l = _bounds(t, y, ip, 0.0, strict=True)
    # the lobe cut where it is still above `LOBE_EDGE` of the peak (a record that starts or ends on the
    # tail of a contact's force, a few millionths of the peak, has the whole pulse)
    trunc_l = trunc_l and ((z0 == t[0] and y[0] > LOBE_EDGE * peak) or (z1 == t[-1] and y[-1] > LOBE_EDGE * peak))
    dv_main = _integral_to(t, a, cum, z1) - _integral_to(t, a, cum, z0)

    t_peak = float(t[ip])
    if velocity is not None:  # refine the peak between samples: a = d/dt of v's cubic Hermite
        ok = None
        if smooth is not None:
            ok = np.asarray(smooth, dtype=bool)
            if ok.shape != (t.size - 1,):
                raise ParameterError("smooth", ok.shape, f"one boolean per step between samples, shape ({t.size - 1},)")
        peak, t_peak = _refine_peak(t, cum, a, ip, sign, peak, t_peak, ok)

    return PulseMetrics(
        peak=peak,
        peak_g=peak / G0,
        sign=sign,
        time_of_peak=t_peak,
        t_start_10=t0,
        t_end_10=t1,
        duration_10=t1 - t0,
        rise_time=rise_time,
        delta_v=dv,
        delta_v_main=dv_main,
        equivalent_half_sine_duration=np.pi * abs(dv_main) / (2.0 * peak),
        n_pulses=count_pulses(t, a, pulse_threshold),
        truncated=bool(trunc_d or trunc_r or trunc_l),
    )
