"""Contact episodes of a simulated stack, and the effective restitution of each.

An *episode* of interface ``j`` is a maximal time interval over which its contact pushes: it starts
where the overlap ``delta_j`` turns positive and ends where the contact force returns to zero (one
definition of a contact's end everywhere: the simulator's launch velocities and `restitution`, these
episodes and the pulses agree). A clamped damped contact (Tsuji, Hunt–Crossley, ...) lets go at
``delta > 0``; an elastic one at ``delta = 0``. The start and end are located between the solver's
steps: from the open (free-flight) side, where the motion is exact (below), with the force-zero
condition given by the caller's ``separation`` function; otherwise by the root of the cubic Hermite
interpolant built from ``delta`` and ``delta_dot`` at the two bracketing steps. Between contacts the relative motion
of two masses is uniform (gravity acts on both alike) and the motion of mass 1 relative to the ground is
uniformly accelerated, so ``delta`` is at most quadratic in time there and the Hermite interpolant —
and with it the crossing time and the relative velocity at the crossing — is exact up to the solver's
own error.

The effective restitution of an episode is the ratio of separation to approach speed
(paper Eq 2): ``e_eff = -(V2 - V1)/(v2 - v1) = -delta_dot(end)/delta_dot(start)``.

Plain numpy: this module works on arrays from any solution (it does not import JAX or diffrax).
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["ContactEpisode", "contact_episodes", "overlap_rates"]


@dataclasses.dataclass(frozen=True)
class ContactEpisode:
    """One contact episode of one interface (SI units).

    `interface` follows the project's numbering (0 = ground–mass 1, j = mass j – mass j+1).
    `approach_velocity` is `delta_dot` at the start (> 0 while approaching) and
    `separation_velocity` is `-delta_dot` at the end (> 0 while separating).
    `complete` is False when the contact was already closed at the first sample or still closed at the
    last one; its restitution is then NaN, by design, and says so. `peak_force` is the largest sample
    (the value the exported data hold); `peak_force_time` and `peak_force_refined` the time and value of
    the peak of the parabola through it and its neighbours (`parabolic_peak`; never below the largest
    sample), the better estimate of the true peak between the solver's steps (O(h^2) of the local step;
    the sample alone is low by O(h^2) too, with a larger constant;
    docs/references.md, "Peaks between steps"). The time is NaN where the largest force is no peak inside the record: a contact closed at
    the first sample whose force never rose above its first value (a held chain the wave has not
    reached), or a force still rising at the record's last sample.
    """

    interface: int
    start: float
    end: float
    max_overlap: float
    peak_force: float
    approach_velocity: float
    separation_velocity: float
    complete: bool
    peak_force_time: float = float("nan")
    peak_force_refined: float = float("nan")

    @property
    def duration(self) -> float:
        return self.end - self.start

    @property
    def restitution(self) -> float:
        """Effective restitution ``e_eff = separation / approach speed`` (paper Eq 2).

        NaN for an incomplete episode and for one without a real approach (masses that start
        touching: an approach speed below 1e-6 of the separation speed is round-off)."""
        if not self.complete or self.approach_velocity <= 1e-6 * abs(self.separation_velocity):
            return float("nan")
        return self.separation_velocity / self.approach_velocity


def overlap_rates(velocities: np.ndarray, ground: bool = True) -> np.ndarray:
    """``delta_dot`` of every interface from mass velocities ``(..., n)``, upward-positive.

    Interface 0: ``-v_1`` (zero-filled when there is no ground); interface j: ``v_j - v_{j+1}``.
    """
    v = np.asarray(velocities, dtype=float)
    ground_rate = -v[..., :1] if ground else np.zeros_like(v[..., :1])
    return np.concatenate([ground_rate, v[..., :-1] - v[..., 1:]], axis=-1)


def _hermite(t0, t1, y0, y1, d0, d1):
    """Cubic Hermite interpolant on [t0, t1] as polynomial coefficients in s = t - t0 (highest first)."""
    h = t1 - t0
    c3 = (2 * (y0 - y1) + h * (d0 + d1)) / h**3
    c2 = (3 * (y1 - y0) - h * (2 * d0 + d1)) / h**2
    return np.array([c3, c2, d0, y0])


def _crossing(t0, t1, y0, y1, d0, d1) -> tuple[float, float]:
    """Time and rate where the Hermite interpolant crosses zero inside [t0, t1] (y0, y1 bracket 0)."""
    if t1 <= t0:
        return float(t0), float(d0)
    coeffs = _hermite(t0, t1, y0, y1, d0, d1)
    h = t1 - t0
    roots = np.roots(coeffs) if np.any(coeffs[:3] != 0) else np.array([])
    real = roots[np.abs(roots.imag) <= 1e-12 * max(h, 1.0)].real
    inside = real[(real >= -1e-12 * h) & (real <= h * (1 + 1e-12))]
    if inside.size == 0:  # fall back to the secant (the bracket guarantees a crossing)
        s = h * y0 / (y0 - y1) if y0 != y1 else 0.0
    else:
        # the crossing nearest the bracketing sign change: for an opening (y0<=0<y1) the last root,
        # for a closing (y0>0>=y1) the first root after the positive side
        s = inside.max() if y0 <= 0 else inside.min()
    s = float(np.clip(s, 0.0, h))
    rate = float(np.polyval(np.polyder(coeffs), s))
    return float(t0 + s), rate


def refined_peak(t, y, dy, i0, i1) -> tuple[float, float]:
    """``(time, value)`` of the maximum of the cubic Hermite interpolant of samples ``y`` with
    derivatives ``dy`` around the largest sample in ``[i0, i1]`` (the one home of this refinement:
    overlaps with their rates, velocities with their accelerations)."""
    k = i0 + int(np.argmax(y[i0 : i1 + 1]))
    best, t_best = float(y[k]), float(t[k])
    for a, b in ((k - 1, k), (k, k + 1)):
        if a < 0 or b >= len(t) or t[b] <= t[a]:
            continue
        c = _hermite(t[a], t[b], y[a], y[b], dy[a], dy[b])
        for s in np.roots(np.polyder(c)) if np.any(c[:2] != 0) else []:
            if abs(s.imag) < 1e-12 and 0.0 <= s.real <= t[b] - t[a]:
                val = float(np.polyval(c, s.real))
                if val > best:
                    best, t_best = val, float(t[a] + s.real)
    return t_best, best


def hermite_slope(t, y, dy, t_new) -> np.ndarray:
    """The derivative at ``t_new`` of the piecewise cubic Hermite interpolant of samples ``y`` with
    derivatives ``dy`` at the increasing times ``t`` (``t_new`` inside ``[t[0], t[-1]]``): a dense
    ``dy`` between the samples, exact at them, error O(h^3) of the local step h for smooth ``y``
    (e.g. velocities with their accelerations: a dense acceleration for the SRS)."""
    t, y, dy = (np.asarray(u, dtype=float) for u in (t, y, dy))
    x = np.asarray(t_new, dtype=float)
    i = np.clip(np.searchsorted(t, x, side="right") - 1, 0, t.size - 2)
    h = t[i + 1] - t[i]
    s = (x - t[i]) / h
    return ((6 * s * s - 6 * s) * (y[i] - y[i + 1]) / h
            + (3 * s * s - 4 * s + 1) * dy[i] + (3 * s * s - 2 * s) * dy[i + 1])


def parabolic_peak(t, y, i0, i1) -> tuple[float, float]:
    """``(time, value)`` of the vertex of the parabola through the largest sample of ``y`` in ``[i0, i1]``
    and its two neighbours (the sample itself at an end of ``[i0, i1]`` or on uneven ground): for samples
    without a derivative, such as contact forces. Error O(h^2) of the local step h. A force largest at
    the contact's first sample (a dashpot's jump at first touch, then falling) is that sample: a
    parabola through the zero force before the contact overshot it (a review: 4.5x a hertz-dashpot
    contact's peak at e = 0.3)."""
    k = i0 + int(np.argmax(y[i0 : i1 + 1]))
    if k - 1 < max(i0, 0) or k + 1 > min(i1, len(t) - 1):
        return float(t[k]), float(y[k])
    (t0, t1, t2), (y0, y1, y2) = t[k - 1 : k + 2], y[k - 1 : k + 2]
    den = (t0 - t1) * (t0 - t2) * (t1 - t2)
    a = (t2 * (y1 - y0) + t1 * (y0 - y2) + t0 * (y2 - y1)) / den
    b = (t2**2 * (y0 - y1) + t1**2 * (y2 - y0) + t0**2 * (y1 - y2)) / den
    if not a < 0:
        return float(t1), float(y1)
    tv = -b / (2 * a)
    if not t0 <= tv <= t2:
        return float(t1), float(y1)
    return float(tv), float(y1 + a * (tv - t1) ** 2 + (2 * a * t1 + b) * (tv - t1))


#: A contact closed at the first sample has a peak only if its force rises above its first value by more
#: than this fraction of it (a held chain's static contacts, which no wave has reached, stay at their
#: preload to round-off and the solver's error, far below it).
PEAK_RISE = 1e-6


def _peak_outside(y, i0, i1, *, closed_at_start: bool) -> bool:
    """The largest force of the run ``[i0, i1]`` is no peak inside the record: the contact was closed at
    the first sample and its force never rose above that value by more than `PEAK_RISE` of it (a static
    contact of a held chain that the wave never reached), or the force is largest at the last sample
    of a run the record cuts off (still rising there). Its time is then unknown (NaN)."""
    seg = y[i0 : i1 + 1]
    if closed_at_start and seg.max() <= y[i0] + PEAK_RISE * abs(y[i0]):
        return True
    return i1 == len(y) - 1 and int(np.argmax(seg)) == len(seg) - 1


def _free_side_release(ta, ya, da, aa, tb, sep) -> tuple[float, float] | None:
    """Where a contact let go: the last zero of ``sep(delta(s), delta_dot(s))`` along the free flight
    ``delta = ya + da s + aa s^2/2`` extrapolated back from the open point ``ta`` towards the last closed
    point ``tb < ta`` (exact: the bodies fly freely after the force returned to zero). Two rounds of 257
    samples, then linear interpolation: the time to ~1e-10 of the step. None if ``sep`` is never
    positive on the way (then the caller falls back to the overlap)."""
    lo, hi = tb - ta, 0.0
    for _ in range(2):
        s = np.linspace(lo, hi, 257)
        g = np.asarray(sep(ya + da * s + 0.5 * aa * s**2, da + aa * s), dtype=float)
        pos = np.flatnonzero(g > 0)
        if pos.size == 0:
            return None
        k = int(pos[-1])
        if k == s.size - 1:
            return float(ta), float(da)
        lo, hi = s[k], s[k + 1]
        g_lo, g_hi = g[k], g[k + 1]
    x = lo + (hi - lo) * g_lo / (g_lo - g_hi) if g_lo != g_hi else hi
    return float(ta + x), float(da + aa * x)


def _free_side_crossing(ta, ya, da, aa, tb) -> tuple[float, float] | None:
    """Crossing of ``y = ya + da s + aa s^2/2`` (exact in free flight) between ``ta`` and ``tb``."""
    h = tb - ta
    roots = np.roots([0.5 * aa, da, ya]) if (aa != 0 or da != 0) else np.array([])
    real = roots[np.abs(roots.imag) <= 1e-14].real
    ok = real[(real * np.sign(h) >= -1e-12 * abs(h)) & (real * np.sign(h) <= abs(h) * (1 + 1e-9))]
    if ok.size == 0:
        return None
    s = ok[np.argmin(np.abs(ok))]
    return float(ta + s), float(da + aa * s)


def contact_episodes(
    t: np.ndarray,
    overlaps: np.ndarray,
    rates: np.ndarray,
    forces: np.ndarray,
    *,
    accelerations: np.ndarray | None = None,
    interfaces: list[int] | None = None,
    free_at_end: bool = False,
    noise_floor: float = 0.0,
    closed: np.ndarray | None = None,
    separation=None,
) -> list[ContactEpisode]:
    """Find every contact episode of every interface.

    **Arguments** (samples at the solver's steps, in time order):

    - `t`: ``(T,)`` times (s).
    - `overlaps`: ``(T, n_if)`` overlaps ``delta`` (m), > 0 in contact.
    - `rates`: ``(T, n_if)`` overlap rates ``delta_dot`` (m/s), see :func:`overlap_rates`.
    - `forces`: ``(T, n_if)`` contact forces (N).
    - `accelerations`: optional ``(T, n_if)`` overlap accelerations ``delta_ddot`` (m/s²). When given,
      each crossing is extrapolated from the open (free-flight) side as a parabola, which is exact in
      free flight; otherwise the cubic Hermite interpolant across the step is used.
    - `interfaces`: which columns to scan (default all); e.g. ``range(1, n)`` with no ground.
    - `free_at_end`: the record ends once every contact force has vanished (a clamped contact lets go
      at ``F = 0`` while ``delta`` is still slightly positive). A contact still overlapping at the last
      sample is then complete: its end is extrapolated forward in free flight to ``delta = 0``.
    - `noise_floor`: episodes whose largest overlap does not exceed it (m) are round-off, not contacts,
      and are dropped (touching masses in float64 overlap by ~1e-24 m).
    - `closed`: optional ``(T, n_if)`` booleans, the contact pushes at each sample (force > 0 for a
      clamped law); default ``overlaps > 0``.
    - `separation`: optional ``separation(j, delta, delta_dot, k) -> G`` (arrays; ``k`` the sample the
      end is extrapolated from), ``> 0`` exactly while interface ``j`` pushes (`Stack.separation_function`). With `accelerations`, every end is located
      where ``G`` returns to zero along the free flight after it: the force's return to zero.

    **Returns** the episodes sorted by start time.
    """
    t = np.asarray(t, dtype=float)
    d = np.asarray(overlaps, dtype=float)
    r = np.asarray(rates, dtype=float)
    f = np.asarray(forces, dtype=float)
    T, n_if = d.shape
    cols = range(n_if) if interfaces is None else interfaces
    episodes: list[ContactEpisode] = []
    mask = d > 0 if closed is None else np.asarray(closed, dtype=bool)
    for j in cols:
        closed = mask[:, j]
        if not closed.any():
            continue
        change = np.diff(closed.astype(np.int8))
        starts = list(np.flatnonzero(change == 1) + 1)
        ends = list(np.flatnonzero(change == -1))  # last closed index of each run
        if closed[0]:
            starts.insert(0, 0)
        if closed[-1]:
            ends.append(T - 1)
        for i0, i1 in zip(starts, ends):
            complete = True
            if i0 == 0:
                t_start, v_in = t[0], r[0, j]
                complete = d[0, j] <= 0  # a contact already closed at t0 has no approach phase
            else:
                k = i0 - 1
                hit = None if accelerations is None else _free_side_crossing(
                    t[k], d[k, j], r[k, j], accelerations[k, j], t[i0])
                t_start, v_in = hit or _crossing(t[k], t[i0], d[k, j], d[i0, j], r[k, j], r[i0, j])
            if d[i0 : i1 + 1, j].max() <= noise_floor:
                continue
            complete_start = complete
            if i1 == T - 1:
                t_end, v_out = t[-1], r[-1, j]
                complete = False
                if free_at_end and r[-1, j] < 0:
                    acc = 0.0 if accelerations is None else accelerations[-1, j]
                    horizon = t[-1] + 1e3 * d[-1, j] / -r[-1, j]
                    hit = _free_side_crossing(t[-1], d[-1, j], r[-1, j], acc, horizon)
                    if hit is not None:
                        (t_end, v_out), complete = hit, complete_start
            else:
                k = i1 + 1
                hit = None
                if accelerations is not None and separation is not None:
                    hit = _free_side_release(t[k], d[k, j], r[k, j], accelerations[k, j], t[i1],
                                             lambda dd_, rr_, j=j, k=k: separation(j, dd_, rr_, k))
                if hit is None and accelerations is not None:
                    hit = _free_side_crossing(t[k], d[k, j], r[k, j], accelerations[k, j], t[i1])
                t_end, v_out = hit or _crossing(t[i1], t[k], d[i1, j], d[k, j], r[i1, j], r[k, j])
            run = slice(i0, i1 + 1)
            peak_t, peak_v = parabolic_peak(t, f[:, j], i0, i1)
            if _peak_outside(f[:, j], i0, i1, closed_at_start=i0 == 0 and d[0, j] > 0):
                peak_t = float("nan")
            episodes.append(
                ContactEpisode(
                    interface=int(j),
                    start=float(t_start),
                    end=float(t_end),
                    max_overlap=refined_peak(t, d[:, j], r[:, j], i0, i1)[1],
                    peak_force=float(f[run, j].max()),
                    peak_force_time=peak_t,
                    peak_force_refined=max(peak_v, float(f[run, j].max())),
                    approach_velocity=float(v_in),
                    separation_velocity=float(-v_out),
                    complete=bool(complete),
                )
            )
    episodes.sort(key=lambda ep: (ep.start, ep.interface))
    return episodes
