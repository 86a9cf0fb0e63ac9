"""Contact tracking inside the solver loop: the end of the first cascade (`_cascade_over`), the
per-interface bookkeeping of the accepted steps (`_Contacts`, carried by the `_Tracked` wrapper), and
the launch velocities located from it (`_end_of_contacts`, `_launch`). See the `hertz_chain.simulation`
module docstring, "Stopping" and "Launch velocities"."""

from __future__ import annotations

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

from . import _config  # noqa: F401  (float64)
from ._fusion import materialised
from .stack import Stack

#: A scaled velocity that differs from free flight by more than this has felt a contact.
_TOUCHED = 1e-9
#: A free group of masses whose internal energy is below this fraction of its drop energy has settled
#: (`_cascade_over`): a slow inelastic collapse of the lower masses (e.g. a gapped MET stack without
#: gravity) no longer holds the run; their velocities can still change by at most ~1e-3 V.
_SETTLED = 1e-6
#: A touching interface (overlap above `-sqrt(_QUIET) L`) whose relative kinetic plus elastic energy is
#: below this fraction of `m* V^2/2` is quiet: its two masses move as one body (a settled clump), and at
#: most `sqrt(_QUIET) V` = 1e-6 V of velocity is left to exchange.
_QUIET = 1e-12


#: the longest chain whose running sums `_running_sums` writes out as additions in a vmapped solve (measured
#: on 2 cores, alternating processes: five masses ~3 % faster, ten masses with gravity unchanged; the
#: recomputed summands grow as n^2, so longer chains keep `cumsum`)
UNROLLED_SUMS = 16


@jax.custom_batching.custom_vmap
def _cumsum(x):
    return jnp.cumsum(x, axis=-1)


@_cumsum.def_vmap
def _cumsum_vmap(axis_size, in_batched, x):
    (batched,) = in_batched
    n = x.shape[-1]
    if n > UNROLLED_SUMS:
        return jnp.cumsum(x, axis=-1), batched
    out = [x[..., 0]]
    for k in range(1, n):
        out.append(out[-1] + x[..., k])
    return jnp.stack(out, axis=-1), batched


@jax.custom_jvp
def _running_sums(x):
    """`jnp.cumsum(x, axis=-1)`, summed in the same order (the same numbers). Under `jax.vmap`, for at
    most `UNROLLED_SUMS` masses, written out as a chain of additions that XLA fuses with the operations
    around it: a CPU compiles `cumsum` to a `reduce-window` kernel of its own in every step of the
    solver's loop (1,024 five-mass gapped Tsuji designs: 0.264 -> 0.255 ms per design, the same
    numbers). A single solve keeps `cumsum`: there the fused chain recomputes every summand once per
    partial sum that reads it (the elemental emitter), which measured ~8 % slower for ten masses (a Hertz
    potential is a power per summand). Derivatives: those of `cumsum`."""
    return _cumsum(x)


@_running_sums.defjvp
def _running_sums_jvp(primals, tangents):
    return _running_sums(*primals), jnp.cumsum(tangents[0], axis=-1)


def _cascade_over(t, ys, args, x, v, d, dd, closed, q=None):
    """The first cascade is over (issue 16's rule; README, "The launch, the cascade and the statuses"):
    something has touched, and for some `k` (0..n) the masses `1..k` rest on the ground while everything
    above flies apart: every contact above mass `k` is open and no neighbours there approach (their
    relative velocity stays constant under a common gravity, so they never meet again) or is quiet
    (`_QUIET`: two masses that have settled into moving as one body), and

    - `k = 0`: mass 1 is off the ground, or leaving it (`v_1 >= 0`);
    - `k >= 1`: the masses `1..k` are bound to the ground: `sum_{i<=k} (m_i v_i^2/2 + m_i g x_i) +
      sum_{j<k} P_j(delta_j) < 0`, below the energy of resting unloaded at `x = 0`. With the contact above
      them open nothing adds energy to them (the ground does no work), so none of them can rise above
      the depth of the static contact wells: they settle, and their contacts among themselves are
      landings again (rebounds), never a push that reaches the masses flying apart above.

    or (with mass 1 off the ground, or without a ground) a group of masses `1..k` flying freely has
    settled (its internal energy `E_int`, kinetic in its centre-of-mass frame plus its inner contacts'
    elastic energy, is below `_SETTLED` of its drop energy `M_k V^2/2`; or, under gravity with a ground,
    the group falls back to the ground, a rebound, so its masses never get final velocities; without a
    ground gravity is a common free fall and changes nothing of this) and can
    never push mass `k+1` again: mass `k+1` moves away from the group's centre of mass faster than any
    velocity `E_int` could give the group's top mass, `sqrt(2 E_int (M_k - m_k)/(M_k m_k))`. Every mass above the group then
    has its final launch; the masses of a settled or bound group report their velocities at the end of
    the cascade (without gravity within `sqrt(_SETTLED) V` of any later value).

    `args`: the `_scaling.FieldArgs` of the solve (`v0s` the scaled initial velocities: contact has happened
    once a velocity departs from free flight); `x`, `v` (SI), the overlaps `d`, their rates `dd` and the closed
    contacts `closed` of the state `ys`, which the caller (`_Contacts.update`) has at hand, and the
    memory block `q` of a law with memory (`Stack.memory`)."""
    stack, scale, T, v0s = args.stack, args.scale, args.T, args.v0s
    n = stack.n
    mask = stack.interface_mask()
    free_fall = v0s - stack.gravity * T * t / scale[n]
    touched = jnp.any(jnp.abs(ys[n : 2 * n] - free_fall) > _TOUCHED)
    # per interface: open and not approaching, or quiet (its relative kinetic and elastic energy below
    # `_QUIET` of its drop energy: a clump of masses moving as one body), or absent
    mu, m, pot = stack.effective_masses(), stack.masses, stack.potentials(d, q)
    touching = d > -jnp.sqrt(_QUIET) * scale[0]  # in contact, or within 1e-6 of the length scale
    quiet = touching & (0.5 * mu * dd**2 + pot <= _QUIET * 0.5 * mu * scale[n] ** 2)
    # Between two free masses (and mass 1 and the ground) an approach slower than sqrt(_QUIET) V is
    # round-off dust; the contact just above a group bound to the ground must not approach at all
    # (its lower mass is held, so a mass falling onto it speeds up: that landing is still to come).
    dust = jnp.sqrt(_QUIET) * scale[n]
    apart = (~closed & (dd <= dust)) | quiet | ~mask
    strict = (~closed & (dd <= 0)) | quiet | ~mask
    # Every running sum below in one cumulative sum over a (6, n) stack: each `cumsum` (and `flip`) is an
    # operation of its own in every step of the loop, which costs more than its arithmetic on the CPU.
    kin = 0.5 * m * v**2
    mech = m * (0.5 * v**2 + stack.gravity * x)
    sums = _running_sums(jnp.stack([m, m * v, kin, pot * (jnp.arange(n) >= 1), mech + pot,
                                    (~apart).astype(m.dtype)]))
    M, P, K, inner, energy, blocked = sums  # `inner`: interfaces 1..k-1 of masses 1..k; `energy`: masses 1..k
    # and their contacts, k = 1..n; `blocked`: interfaces 0..k that are not apart (small integers: exact)
    # tail[k], k = 0..n: every interface j >= k + 1 is apart (vacuous for k >= n - 1)
    tail = jnp.concatenate([blocked[-1] - blocked == 0, jnp.ones(1, bool)])
    # A free group, masses 1..k (k = 1..n-1) off the ground: its internal energy (kinetic in its centre-of-
    # mass frame plus its inner contacts' elastic energy) bounds how fast its top mass k can ever move
    # relative to the group's centre of mass (gravity is common: the centre of mass frame is free fall);
    # when mass k+1 already moves away faster than that, the group can never push it again.
    e_int = jnp.maximum(K - 0.5 * P**2 / M + inner, 0.0)
    reach = jnp.sqrt(2.0 * e_int * (M - m) / (M * m))
    # its internal motion is negligible; or gravity acts, so the group falls back to the ground anyway:
    # its landing is a rebound, and its masses' velocities never become final
    settled = e_int <= _SETTLED * 0.5 * M * scale[n] ** 2
    if stack.ground:  # without a ground gravity is a common free fall, changing nothing of the group's motion
        settled = settled | (stack.gravity > 0)
    escapes = (~closed[1:] & settled[:-1] & (v[1:] - (P / M)[:-1] >= reach[:-1])) & tail[1:n]  # k = 1..n-1
    free = tail[0] | jnp.any(escapes)
    if not stack.ground:
        return touched & free
    # above[k], k = 0..n: the masses above mass k fly apart (k >= 1: interface k strictly)
    above = tail & jnp.concatenate([jnp.ones(1, bool), strict[1:], jnp.ones(1, bool)])
    bound = jnp.any((energy < 0) & above[1:])
    return touched & ((apart[0] & free) | bound)


def _top_final(v, d, closed, stack, touched_top, q=None):
    """Without gravity, the top mass's launch is final (`until="launch"`): it has been pushed, its
    contact is open and not closing, and no motion of the masses below can ever catch it. With the ground
    their mechanical energy `E` (kinetic plus their contacts' elastic energy; the ground does no work,
    the contacts dissipate) caps mass n-1's speed at `sqrt(2 E / m_{n-1})`; without it, their centre of
    mass moves uniformly and mass n-1 can move away from it at most `sqrt(2 E_int (M - m)/(M m))`
    (as in `_cascade_over`). Mass n moving faster than that cap is never pushed again, whatever happens
    below (the lower masses may go on colliding, as a gapped stack without gravity does for seconds)."""
    n, m = stack.n, stack.masses
    pot = stack.potentials(d, q)
    below = jnp.arange(n) < n - 1
    if stack.ground:
        energy = jnp.sum(jnp.where(below, 0.5 * m * v**2 + pot, 0.0))
        cap = jnp.sqrt(2.0 * energy / m[n - 2])
    else:
        M, P = jnp.sum(jnp.where(below, m, 0.0)), jnp.sum(jnp.where(below, m * v, 0.0))
        inner = jnp.sum(jnp.where(below & (jnp.arange(n) >= 1), pot, 0.0))
        e_int = jnp.maximum(jnp.sum(jnp.where(below, 0.5 * m * v**2, 0.0)) - 0.5 * P**2 / M + inner, 0.0)
        cap = P / M + jnp.sqrt(2.0 * e_int * (M - m[n - 2]) / (M * m[n - 2]))
    # without a ground gravity is a common free fall: these relative speeds are all that matter
    no_fall = (stack.gravity <= 0) if stack.ground else True
    return touched_top & ~closed[n - 1] & no_fall & (v[n - 1] >= cap)


def _cascade_complete(t, ys, args, **kwargs):
    """diffrax event: the cascade-over flag that `_Tracked` wrote into the state's last entry (ends the
    solve at the first accepted step where `_cascade_over` holds)."""
    return ys[-1] > 0.5


# columns of `_Contacts.rows`: the latest accepted point in contact, then the first point after it (its
# time, overlap, overlap rate, lower and upper body velocities, memory `q`)
T_IN, T_OUT, DELTA_OUT, RATE_OUT, V_LOWER_OUT, V_UPPER_OUT, Q_OUT = range(7)
# rows of `_Contacts.peaks` (audit mode): the largest force, the upper and lower bodies' velocities before and
# after the first contact, and the first points in and after that contact
(PEAK_FORCE, V_UPPER_BEFORE, V_LOWER_BEFORE, V_UPPER_AFTER, V_LOWER_AFTER, T_FIRST_IN,
 T_FIRST_OUT) = range(7)


#: slots for the top pulse's samples (`_pulse_update`: a rising edge takes one per sample, a fall or a
#: stretch below the 10 % level one or two); where the samples from its start to its peak do not fit, the
#: duration is NaN
PULSE_RING = 256
#: the level of the pulse duration, a fraction of the peak (the shock-test standards' 10 % points), and the
#: top of the rise time (from `PULSE_LEVEL` to 90 %, as `pulse.pulse_metrics`)
PULSE_LEVEL = 0.1
RISE_TOP = 0.9
# entries of the pulse's running values
P_COUNT, P_AT_PEAK, P_END, P_PENDING, P_T_PREV, P_Y_PREV, P_PREV_BELOW, P_PREV_FALL = range(8)


def _cross(t0, y0, t1, y1, level):
    """Where the line from `(t0, y0)` to `(t1, y1)` reaches `level` (the two samples bracket it)."""
    return t0 + (level - y0) / jnp.where(y1 != y0, y1 - y0, 1.0) * (t1 - t0)


def _pulse_start(t, y):
    """The running values of `_pulse_update` before the first sample."""
    return (jnp.full((2, PULSE_RING + 1), jnp.nan, dtype=y.dtype),
            jnp.stack([0.0 * y, 0.0 * y, jnp.nan * y, 0.0 * y, t + 0.0 * y, y, 0.0 * y, 0.0 * y]))


def _pulse_update(ring, run, t, y, peak, frozen):
    """One sample `(t, y)` of a pulse `y(t) >= 0` whose largest sample so far (before this one) is `peak`,
    streamed through the main pulse's ends at `PULSE_LEVEL` of its peak, as `pulse.pulse_metrics` finds
    them on the whole record (its linear interpolant: the maximal interval around the first largest
    sample over which `y >= PULSE_LEVEL * peak`):

    - the end: after each new peak, the first sample below the level, interpolated from the one before;
    - the start (`_pulse_duration`, after the solve): the last sample `j` before the peak below the level,
      and the sample after it. `ring` holds the samples in order, one slot each, except that a sample
      replaces the one before it where that one can be neither such a `j` (a later sample is lower, or
      also below the level, which only rises) nor the sample after one (that sample rose from `j`): after
      a sample below the level, a sample below it; after a fall, a further fall. So a rising edge takes a
      slot per sample, a fall or a stretch below the level one or two.

    `run`: `[slots used, slot of the peak, end, pending, t_prev, y_prev, prev below, prev fall]`; `frozen`:
    keep everything. Few and elementwise operations (each is a kernel of its own in every step of the
    solver's loop); `ring`, in the solver's state, passes through diffrax's accept/reject select every
    step, so its cost grows with `PULSE_RING`."""
    new_peak = (y > peak) & ~frozen
    level = PULSE_LEVEL * jnp.maximum(peak, y)
    below = y < level
    fall = y <= run[P_Y_PREV]
    again = (below & (run[P_PREV_BELOW] > 0)) | (fall & (run[P_PREV_FALL] > 0))  # replace the previous sample
    pos = run[P_COUNT] - again
    k = ring.shape[1] - 1  # the last column takes the writes of a frozen pulse
    slot = jnp.where(frozen, k, jnp.mod(pos, k)).astype(jnp.int32)
    ring = jax.lax.dynamic_update_slice(ring, jnp.stack([t, y])[:, None], (jnp.zeros_like(slot), slot))
    down = (run[P_PENDING] > 0) & ~new_peak & below & ~frozen
    run = jnp.where(frozen, run, jnp.stack([
        pos + 1.0, jnp.where(new_peak, pos, run[P_AT_PEAK]),
        jnp.where(down, _cross(run[P_T_PREV], run[P_Y_PREV], t, y, level), jnp.where(new_peak, jnp.nan, run[P_END])),
        jnp.where(new_peak, 1.0, jnp.where(down, 0.0, run[P_PENDING])), t, y, below.astype(y.dtype),
        fall.astype(y.dtype)]))
    return ring, run


def _pulse_duration(ring, run, peak):
    """The main pulse's duration at `PULSE_LEVEL` and its rise time (from that level to `RISE_TOP` of the
    peak: the first sample at or above it after the start, interpolated from the one before, as
    `pulse.pulse_metrics`), from `_pulse_update`'s values after the last sample (one pulse): NaN without a
    pulse, while it is still above the level at the end, or where the samples from its start to its peak
    are no longer all in the ring. (The first sample at or above `RISE_TOP` rose from the one before it,
    so neither was replaced: both are in consecutive slots.)"""
    k = ring.shape[-1] - 1
    back = jnp.arange(k)  # slots back from the peak
    p = run[P_AT_PEAK] - back  # their positions
    idx = jnp.mod(p, k).astype(jnp.int32)
    t, y = ring[0][idx], ring[1][idx]
    level = PULSE_LEVEL * peak
    kept = (p >= 0) & (p >= run[P_COUNT] - k)  # written, and not overwritten since
    below = kept & (y < level)
    j = jnp.argmax(below)  # the latest sample before the peak below the level (j >= 1)
    start = _cross(t[j], y[j], t[j - 1], y[j - 1], level)
    ok = jnp.any(below) & (run[P_PENDING] == 0) & (peak > 0)
    top = RISE_TOP * peak
    m = jnp.max(jnp.where(kept & (back < j) & (y >= top), back, 0))  # the first at or above it, after the start
    rise = _cross(t[m + 1], y[m + 1], t[m], y[m], top) - start
    return jnp.where(ok, run[P_END] - start, jnp.nan), jnp.where(ok, rise, jnp.nan)


class _Contacts(eqx.Module):
    """Per-interface bookkeeping of the accepted steps, carried in the solver state (`_Tracked`), so
    that launch velocities and the energy audit need no step history (a history of `max_steps` rows is
    the dominant cost of a vmapped solve, where every step selects over the whole buffer).

    `rows (n, 6)` (`(n, 7)` with a law with memory): per interface, the latest accepted point in contact
    (scaled time, -1 if never) and the first accepted point after it (scaled time, SI overlap, overlap
    rate, the velocities of the lower and upper body, 0 for the ground, and the memory `q` of a law with
    memory); `acc (n,)`: the overlap's second derivative at that first point after it (scaled, from the
    step's derivative `dys`; a separate array: a seventh column of `rows` cost 30 % per step, measured);
    `now (n,)`: in contact at the latest point; `cascade (n + 5,)`:
    `[over, rebounds, t_c, top_done, v_top, v_c...]`: whether the first cascade is over (`_cascade_over` held
    at an accepted point; `rows` and `now` are then frozen), whether any contact closed after that, its
    scaled time `t_c`, whether the top mass has passed the apex of its flight after its last push (the
    top interface is then frozen: a later landing is a rebound) and its velocity at the latest point
    (scaled, to see it change sign), and the scaled velocities at `t_c`; `energy`: the
    energy at `t0` and the largest `|E - E(t0)|` so far (J), when audited; `peaks (5, n)`, when audited:
    each interface's largest contact force at the accepted points of the first cascade (N; the step-sampled
    peak, low by O(h^2)), the upper and lower bodies' velocities (m/s) at the last accepted point
    before the interface's first contact, and at the first accepted point after that contact (NaN
    until then), then the scaled times of the first accepted points in and after that first contact
    (`peaks (7, n)`; NaN until then): in free flight the velocity differences are the approach and separation speeds, which
    gravity does not change between two falling bodies; for the per-design results of a batched solve
    without a step history (`hertz_chain.sweeps`). Packed into few arrays: each
    array is a separate operation in every step of the loop.
    """

    rows: Array
    now: Array
    cascade: Array
    energy: tuple[Array, Array] | None
    acc: Array
    peaks: Array | None = None
    pulse: tuple[Array, Array] | None = None

    @staticmethod
    def update(c: _Contacts | None, t, ys, args, audit: bool, launch: bool = False, dys=None,
               durations: bool = False) -> _Contacts:
        """The bookkeeping after the accepted point `(t, ys)` (scaled); `dys`: the scaled derivative
        there (`_scaled_field`; None at `t0`, where no contact has ended)."""
        stack, scale = args.stack, args.scale
        n = stack.n
        y = ys[: scale.shape[0]] * scale
        x, v, _ = stack.split(y)
        # the overlaps' second derivatives (scaled): linear in the accelerations, as the rates in the velocities
        acc = jnp.zeros(n, ys.dtype) if dys is None else stack.overlap_rates(dys[n : 2 * n])
        q = stack.memory(y)
        d, dd = stack.overlaps(x), stack.overlap_rates(v)
        # the forces once, in a kernel of their own in a vmapped solve (`_fusion`): every column of `rows`
        # and every row of `peaks` reads them
        (forces,) = materialised(stack.forces(d, dd, q))
        active = stack.in_contact(d, dd, q, forces) & stack.interface_mask()
        e = stack.total_energy(y) if audit else None
        v_top = ys[2 * n - 1]
        if c is None:
            cols = 7 if q is not None else 6
            c = _Contacts(jnp.broadcast_to(jnp.asarray([-1.0] + [0.0] * (cols - 1)), d.shape + (cols,)),
                          active & False, jnp.concatenate([jnp.zeros(4), v_top[None], ys[n : 2 * n]]),
                          None if e is None else (e, 0.0 * e), acc,
                          None if e is None else jnp.stack([0.0 * d, v, jnp.concatenate([jnp.zeros(1, v.dtype), v[:-1]]),
                                                            jnp.nan * d, jnp.nan * d, jnp.nan * d, jnp.nan * d]),
                          _pulse_start(jnp.asarray(t, d.dtype), 0.0 * d[-1]) if durations else None)
        was_over, top_done = c.cascade[0] > 0, c.cascade[3] > 0
        frozen = was_over | ((jnp.arange(n) == n - 1) & top_done)
        left = c.now & ~active
        t = jnp.broadcast_to(t, d.shape).astype(d.dtype)
        v_lo = jnp.concatenate([jnp.zeros(1, v.dtype), v[:-1]])
        extra = [] if q is None else [q]  # a law with memory: its memory after the contact
        rows = jnp.where(jnp.stack([active] + [left] * (5 + len(extra)), axis=-1) & ~frozen[:, None],
                         jnp.stack([t, t, d, dd, v_lo, v] + extra, axis=-1), c.rows)
        acc = jnp.where(left & ~frozen, acc, c.acc)
        now = jnp.where(frozen, c.now, active)
        over = _cascade_over(t[0], ys, args, x, v, d, dd, active, q)
        if launch and n >= 2:  # `until="launch"`: or as soon as the top mass's launch is final
            over = over | _top_final(v, d, active, stack, rows[n - 1, T_IN] >= 0, q)
        over = over & ~was_over
        # the top mass's apex: free, pushed before, its velocity turned from up to down
        # (with a ground only: without one gravity is a common free fall, and the top's fall toward the masses
        # below is no landing; it meets them again only as it would without gravity, a push)
        apex = ~active[n - 1] & (rows[n - 1, T_IN] >= 0) & (c.cascade[4] > 0) & (v_top <= 0) & stack.ground
        rebound = (c.cascade[1] > 0) | jnp.any(frozen & active & ~c.now)  # closes after it was open
        head = jnp.stack([(was_over | over), rebound, jnp.where(over, t[0], c.cascade[2]),
                          top_done | apex | over, v_top]).astype(d.dtype)
        cascade = jnp.concatenate([head, jnp.where(over, ys[n : 2 * n], c.cascade[5:])])
        peaks = pulse = None
        if e is not None:  # elementwise, not `.at[].max`: a scatter is a slow unfused operation in the loop
            e = (c.energy[0], jnp.maximum(c.energy[1], jnp.abs(e - c.energy[0])))
            f = jnp.where(active, forces, 0.0)
            never = rows[:, T_IN] < 0  # not yet in contact: the velocities just before the first contact
            first_off = left & jnp.isnan(c.peaks[V_UPPER_AFTER])  # the first point after the first contact
            first_on = (c.rows[:, T_IN] < 0) & active  # the first point in contact (`rows` already holds it)
            pk = c.peaks
            peaks = jnp.stack([jnp.where(frozen, pk[PEAK_FORCE], jnp.maximum(pk[PEAK_FORCE], f)),
                               jnp.where(never, v, pk[V_UPPER_BEFORE]), jnp.where(never, v_lo, pk[V_LOWER_BEFORE]),
                               jnp.where(first_off, v, pk[V_UPPER_AFTER]), jnp.where(first_off, v_lo, pk[V_LOWER_AFTER]),
                               jnp.where(first_on & ~frozen, t, pk[T_FIRST_IN]), jnp.where(first_off, t, pk[T_FIRST_OUT])])
            if durations:  # the top's accelerometer times m_n
                pulse = _pulse_update(*c.pulse, t[0], f[n - 1], pk[PEAK_FORCE, n - 1], frozen[n - 1])
        return _Contacts(rows, now, cascade, e, acc, peaks, pulse)


class _Tracked(dfx.AbstractWrappedSolver):
    """Wraps a diffrax solver and updates `_Contacts` with every step's end point. diffrax keeps the
    solver state of accepted steps only (`_integrate.py`: `solver_state = keep(new, old)`), so the
    bookkeeping sees exactly the accepted points, as a saved step history would."""

    solver: dfx.AbstractSolver
    audit: bool = eqx.field(static=True)
    launch: bool = eqx.field(static=True, default=False)
    durations: bool = eqx.field(static=True, default=False)

    @classmethod
    def around(cls, solver: dfx.AbstractSolver, adjoint: dfx.AbstractAdjoint, audit: bool,
               launch: bool = False, durations: bool = False) -> _Tracked:
        # diffrax's ForwardMode and DirectAdjoint set `scan_kind` of a Runge–Kutta solver left at None
        # ("lax", "bounded") by `eqx.tree_at`, which cannot reach through the wrapper: do it here.
        # (RecursiveCheckpointAdjoint leaves it None: the stages' loop is then "checkpointed", faster.)
        kinds = {dfx.ForwardMode: "lax", dfx.DirectAdjoint: "bounded"}
        kind = next((k for cls_, k in kinds.items() if isinstance(adjoint, cls_)), None)
        if kind is not None and getattr(solver, "scan_kind", "") is None:
            solver = eqx.tree_at(lambda s: s.scan_kind, solver, kind, is_leaf=lambda x: x is None)
        return cls(solver, audit, launch, durations and audit)

    @property
    def scan_kind(self):
        return getattr(self.solver, "scan_kind", None)

    @property
    def root_finder(self):  # implicit solvers: diffrax fills its tolerances from the controller's
        return self.solver.root_finder

    @property
    def term_structure(self):
        return self.solver.term_structure

    @property
    def interpolation_cls(self):  # pyright: ignore
        return self.solver.interpolation_cls

    @property
    def term_compatible_contr_kwargs(self):
        return self.solver.term_compatible_contr_kwargs

    def order(self, terms):
        return self.solver.order(terms)

    def strong_order(self, terms):
        return self.solver.strong_order(terms)

    def error_order(self, terms):
        return self.solver.error_order(terms)

    def init(self, terms, t0, t1, y0, args):
        return self.solver.init(terms, t0, t1, y0, args), _Contacts.update(None, t0, y0, args, self.audit, self.launch, None, self.durations)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        inner, contacts = solver_state
        y1, y_error, dense_info, inner, result = self.solver.step(terms, t0, t1, y0, args, inner, made_jump)
        # the derivative at the step's end: the first-same-as-last stage of the default solver
        # (`UnrolledTsit5`'s state is f(t1, y1), or `(f(t1, y1), t*)` with onset windows), else one more
        # evaluation
        f1 = inner[0] if isinstance(inner, tuple) and len(inner) == 2 else inner
        dys = f1 if isinstance(f1, jax.Array) and f1.shape == y1.shape else terms.vf(t1, y1, args)
        contacts = _Contacts.update(contacts, t1, y1, args, self.audit, self.launch, dys, self.durations)
        # the cascade-over flag, read by the stopping event (`_scaled_field`); its derivative is zero, so
        # its error estimate is zero already
        y1 = y1.at[-1].set(contacts.cascade[0])
        return y1, y_error, dense_info, (inner, contacts), result

    def func(self, terms, t0, y0, args):
        return self.solver.func(terms, t0, y0, args)


def _end_of_contacts(stack: Stack, c: _Contacts, time_scale, t_final, velocity_scale):
    """Per interface: the time its last contact ended (see module docstring), NaN if never in contact,
    `t_final` if still in contact at the end. Differentiable through a final Newton step. `time_scale`,
    `velocity_scale`: the solve's `T` and `V` (`_Contacts.acc` is scaled)."""
    n = stack.n
    cols = jnp.arange(n)
    ever = c.rows[:, T_IN] >= 0
    ended = ever & ~c.now
    t_k = jnp.where(ended, c.rows[:, T_IN] * time_scale, 0.0)
    t_r = jnp.where(ended, c.rows[:, T_OUT] * time_scale, 0.0)
    d_r, dd_r = jnp.where(ended, c.rows[:, DELTA_OUT], 0.0), jnp.where(ended, c.rows[:, RATE_OUT], 0.0)
    q_r = c.rows[:, Q_OUT] if stack.has_memory else None  # the memory after the contact (constant while open)
    # the overlap's second derivative at the recorded point: the back-extrapolation from there is exact while
    # both bodies fly freely (0 between two masses, g at the ground) and keeps the contact end accurate to
    # O(h^3) when a neighbouring contact still pushes one of them (else a first-order extrapolation missed
    # the end by up to ~0.1 of the step, and a launch velocity under gravity by g times that). Its value is
    # the recorded one; its derivative that of free flight (the replayed adjoint maps no cotangent to it)
    free = jnp.where((cols == 0) & stack.ground, stack.gravity, 0.0)
    curv = free + jax.lax.stop_gradient(jnp.where(ended, c.acc * velocity_scale / time_scale, free) - free)
    lo0 = jnp.where(ended, t_k - t_r, -1.0)

    def sep(s, d_r, dd_r, curv):
        return stack.separation_function(d_r + dd_r * s + 0.5 * curv * s**2, dd_r + curv * s, q_r)

    frozen = jax.lax.stop_gradient((d_r, dd_r, curv, lo0))

    def bisect(_, bracket):
        lo, hi = bracket
        mid = 0.5 * (lo + hi)
        pos = sep(mid, *frozen[:3]) > 0
        return jnp.where(pos, mid, lo), jnp.where(pos, hi, mid)

    lo, hi = jax.lax.fori_loop(0, 60, bisect, (frozen[3], jnp.zeros(n)))
    s_b = 0.5 * (lo + hi)
    g_b, dg_b = jax.jvp(lambda s: sep(s, d_r, dd_r, curv), (s_b,), (jnp.ones(n),))
    dg_safe = jax.lax.stop_gradient(jnp.where(jnp.abs(dg_b) > 0, dg_b, 1.0))
    s_newton = s_b - g_b / dg_safe
    good = (jnp.abs(dg_b) > 0) & (sep(frozen[3], *frozen[:3]) > 0)
    s_star = jnp.where(good, s_newton, s_b)
    return jnp.where(ended, t_r + s_star, jnp.where(ever, t_final, jnp.nan))


def _launch(stack: Stack, c: _Contacts, time_scale, t_end_if, t_final, v_final):
    """Per mass: the end of its last push (the later end of its two interfaces), and its velocity then:
    the velocity recorded at the first accepted point after that contact (`_Contacts.rows`), taken back
    to the contact's end in free flight (`v + g (t_r - t_end)`, exact: the mass is free in between). A
    mass still pushed at the end: its final velocity. NaN for a mass never pushed."""
    n = stack.n
    above = jnp.concatenate([t_end_if[1:], jnp.full(1, jnp.nan)])
    use_above = jnp.isfinite(above) & (jnp.isnan(t_end_if) | (above > t_end_if))
    t_end = jnp.where(use_above, above, t_end_if)
    j = jnp.where(use_above, jnp.arange(n) + 1, jnp.arange(n))  # the interface of the last push
    jc = jnp.minimum(j, n - 1)
    rec_v = jnp.where(use_above, c.rows[jc, V_LOWER_OUT], c.rows[jc, V_UPPER_OUT])
    t_r = c.rows[jc, T_OUT] * time_scale
    pushed_now = c.now[jc]
    v_launch = jnp.where(pushed_now, v_final, rec_v + stack.gravity * (t_r - t_end))
    return t_end, jnp.where(jnp.isnan(t_end), jnp.nan, v_launch)
