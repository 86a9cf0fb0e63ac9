"""Options and solvers of `hertz_chain.simulation`: `Tolerances`, the unrolled Tsit5, `make_solver` (from
`hertz_chain.registry.SOLVERS`), the adjoint choice and the static configuration of a solve."""

from __future__ import annotations

import functools
from typing import Any, ClassVar

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import _config  # noqa: F401  (float64)
from . import registry as _registry
from ._fusion import materialised
from .constants import UNTIL  # noqa: F401  (re-exported by simulate)
from .errors import ParameterError



# ==================================================================== options
class Tolerances(eqx.Module):
    """Step-size control, in the scaled units of the module docstring.

    - `rtol`, `atol`: PID controller tolerances (scaled state, so `atol` is relative to the scales).
    - `pcoeff`, `icoeff`: PID coefficients (0.4, 0.3: docs/references.md, "Solver notes").
    - `max_step`: the largest step, in units of the contact time `T` (0.5 never steps over a contact),
      except in free flight with `flight_steps`.
    - `flight_steps`: while no interface is closed (every overlap `< 0`) and there is no far wall, every
      mass flies under gravity and the end force alone, so each gap's time to close, `t_j`, is the first
      root of `delta_j + delta_dot_j t + a_j t^2 / 2` (`a_j` from those forces: exact). A step may then
      be as long as `flight_fraction * min_j t_j` (never shorter than `max_step`): it ends before any
      contact can begin, and Tsit5 integrates the quadratic motion exactly. A 1 cm gap at 1 m/s takes
      ~10 steps instead of one per half contact time (hundreds). Near a closure (`t_j` below
      `max_step / flight_fraction`) the steps are those of `max_step`, as without it.
    - `flight_fraction`: that fraction (0 < f < 1; default 0.8).
    - `land_onsets`: meet every contact onset with a step end, and step through the contact's start in
      `s = (t - t*)^{1/4}` (`t*` the onset). After each accepted step the controller predicts, for every
      open interface, when it closes (the parabola of its overlap, with the overlap's acceleration from
      the step's two ends: exact in free flight) and ends the next step there if it would pass it; a
      step that starts with an interface closing at an overlap within `ONSET_OVERLAP` of zero starts an
      onset window of `onset_window` contact times in which the steps of the unrolled solvers
      (`UnrolledERK`) are taken in `s` and the controller chooses them in `s`: the motion, non-smooth in
      `t` (`F ~ delta^{3/2}`, `delta^{1/4} delta'`), is a power series in `s`, so the steps grow at
      once instead of over ~50 steps. Only with an unrolled solver on a state of at most
      `UNROLL_MAX_STATE` entries, and not in `launch_velocity`'s replayed reverse mode (whose replay
      takes its own steps at onsets); else off. Default on (docs/solver-defaults.md, "Onsets met").
    - `onset_window`: that window, in contact times (> 0; default 0.05).
    - `first_step`: the first step, in units of `T`.
    - `resolve_onsets`: add one auxiliary state per interface, `z_j' = sqrt(delta_j+/L) + sqrt(F_j/F_s)`
      (`F_s = m*_j V^2/L`), whose local error is `O(h^1.5)` where a contact starts (where `F ~ delta^{3/2}`
      is not smooth, or a damped law's force rises faster) and where a clamped contact lets go (the
      kink of its force at `F = 0`), so that the controller resolves both to the tolerance. Derivatives
      need the onsets resolved: the tangent of the discretised solve is not error-controlled, and
      without this the gradient with respect to gaps is only accurate to ~`sqrt(tol)` in units of
      `V/L`. Both terms remove the heavy tail of the launch-velocity error (docs/solver-defaults.md,
      "Default tolerances": damped laws 4e-7 -> 1e-8 at 1e-10, for 15 % more steps). Default on;
      `False` integrates exactly the `3n` equations (as the scipy comparison in the benchmarks does).
    """

    rtol: float = 1e-10  # not static: traced, so changing a tolerance does not recompile
    atol: float = 1e-10  # defaults: see "Default tolerances" in the module docstring
    pcoeff: float = eqx.field(static=True, default=0.4)
    icoeff: float = eqx.field(static=True, default=0.3)
    max_step: float = eqx.field(static=True, default=0.5)
    first_step: float = eqx.field(static=True, default=0.01)
    resolve_onsets: bool = eqx.field(static=True, default=True)
    flight_steps: bool = eqx.field(static=True, default=True)
    flight_fraction: float = eqx.field(static=True, default=0.8)
    land_onsets: bool = eqx.field(static=True, default=True)
    onset_window: float = eqx.field(static=True, default=0.05)

    def __check_init__(self):
        for name in ("rtol", "atol", "max_step", "first_step"):
            value = getattr(self, name)
            if isinstance(value, (jax.Array, np.ndarray)) and name in ("rtol", "atol"):
                continue  # already validated (the array copy made by `_prepare`, traced under jit)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise ParameterError(name, value, "a finite number > 0")
        if not 0 <= self.pcoeff <= 1 or not 0 < self.icoeff <= 1:
            raise ParameterError("pcoeff/icoeff", (self.pcoeff, self.icoeff), "0 <= pcoeff <= 1, 0 < icoeff <= 1")
        f = self.flight_fraction
        if not (isinstance(f, (int, float)) and 0 < f < 1):
            raise ParameterError("flight_fraction", f, "a number with 0 < flight_fraction < 1")
        for name in ("flight_steps", "land_onsets", "resolve_onsets"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ParameterError(name, getattr(self, name), "True or False")
        w = self.onset_window
        if not (isinstance(w, (int, float)) and not isinstance(w, bool) and np.isfinite(w) and w > 0):
            raise ParameterError("onset_window", w, "a finite number > 0 (contact times)")

    def controller(self, onsets: bool = False) -> dfx.AbstractAdaptiveStepSizeController:
        """The step-size controller: `FlightController` around diffrax's `PIDController`, with `max_step` as
        its largest step (longer in free flight with `flight_steps`), landing onsets with `onsets` (the
        solve lands its onsets: `land_onsets` where the solver can), and `first_step` as its first step."""
        pid = dfx.PIDController(rtol=self.rtol, atol=self.atol, pcoeff=self.pcoeff, icoeff=self.icoeff)
        return FlightController(pid, self.max_step, self.flight_fraction, self.flight_steps, onsets,
                                self.onset_window, self.first_step)


def _closure_times(delta, rate, acc):
    """Time for each overlap `delta(t) = delta + rate t + acc t^2 / 2` to reach 0 from `delta < 0` (the
    first positive root; `inf` if it never does), in the units of the arguments. Written as
    `2 h / (rate + sqrt(rate^2 + 2 acc h))` (`h = -delta`), free of cancellation; the `where`s keep every
    branch finite (`sqrt` of a negative discriminant, a zero denominator)."""
    h = -delta
    disc = rate * rate + 2.0 * acc * h
    den = rate + jnp.sqrt(jnp.maximum(disc, 0.0))
    ok = (disc >= 0) & (den > 0)
    return jnp.where(ok, 2.0 * h / jnp.where(ok, den, 1.0), jnp.inf)


def flight_limit(args, ys, max_step: float, fraction: float):
    """The largest scaled step from the scaled state `ys` (`_solve._scaled_field`'s layout) under
    `Tolerances.flight_steps`: `max(max_step, fraction * min_j t_j)` while every existing interface is
    open (`delta_j < 0`), `max_step` otherwise or with a far wall. `t_j` (`_closure_times`): the time each
    gap closes with the masses in free flight (gravity and the end force only: constant accelerations,
    so the relative motion of two masses is a parabola, of mass 1 and the fixed ground too)."""
    stack, scale = args.stack, args.scale
    if stack.wall:
        return jnp.asarray(max_step, ys.dtype)
    n = stack.n
    x, v = ys[:n] * scale[:n], ys[n : 2 * n] * scale[n : 2 * n]
    a = stack.accelerations(jnp.zeros_like(x), x)
    mask = stack.interface_mask()
    d = stack.overlaps(x)
    t = _closure_times(d, stack.overlap_rates(v), stack.overlaps(a))
    t = jnp.where(mask, t, jnp.inf)
    free = jnp.all(jnp.where(mask, d < 0, True))
    return jnp.where(free, jnp.maximum(max_step, fraction * jnp.min(t) / args.T), max_step)


#: an interface whose overlap is within this many overlap scales `L` of zero, closing, starts an onset
#: window (`Tolerances.land_onsets`); the landing puts a step end within ~1e-14 `L` of the onset in free
#: flight, and within this of it after a few steps in contact
ONSET_OVERLAP = 1e-9
#: no landing step shorter than this many float64 roundings of the time (a run of thousands of contact
#: times resolves time to ~1e-12 T only: a shorter step would not move)
LANDING_MIN_ULPS = 1024.0
#: ... closing faster than this many velocity scales (a gentler closing is smooth enough in `t`)
ONSET_MIN_RATE = 1e-3
#: the first step in an onset window, in `s = (t - t*)^{1/4}` (units `T^{1/4}`): `0.05^4 = 6e-6 T`
ONSET_FIRST_S = 0.05


def _overlaps_and_rates(args, ys):
    """Every interface's overlap and its rate (SI) of a scaled state (`_solve._scaled_field`'s layout)."""
    stack, scale, n = args.stack, args.scale, args.stack.n
    x, v = ys[:n] * scale[:n], ys[n : 2 * n] * scale[n : 2 * n]
    return stack.overlaps(x), stack.overlap_rates(v)


def onset_at(args, ys):
    """Whether a contact starts at the scaled state `ys`: an interface at an overlap within
    `ONSET_OVERLAP` overlap scales of zero, closing faster than `ONSET_MIN_RATE` velocity scales."""
    d, r = _overlaps_and_rates(args, ys)
    return _starts(args, d, r)


def _starts(args, d, r):
    scale, n = args.scale, args.stack.n
    return jnp.any(args.stack.interface_mask() & (jnp.abs(d) <= ONSET_OVERLAP * scale[0])
                   & (r > ONSET_MIN_RATE * scale[n]))


def flight_and_landing(args, y0, y1, h, max_step: float, fraction: float, flight: bool):
    """From an accepted step `y0 -> y1` of scaled length `h`: the largest next step (`flight_limit`, or
    `max_step` without `flight`), the scaled time from `y1` to the first closure of an interface open
    there (overlap below `-ONSET_OVERLAP L`; `inf` if none), and whether a contact starts at `y1`
    (`onset_at`), from one evaluation of the overlaps. Each overlap is a parabola: in free flight with
    the exact free accelerations (`flight_limit`), else with the overlap's acceleration
    `(rate(y1) - rate(y0)) / h` over the step. The times carry no gradient (as the PID's)."""
    stack, scale, T, n = args.stack, args.scale, args.T, args.stack.n
    x1 = y1[:n] * scale[:n]
    d1, r1 = _overlaps_and_rates(args, y1)
    r0 = stack.overlap_rates(y0[n : 2 * n] * scale[n : 2 * n])
    mask = stack.interface_mask()
    free = jnp.all(jnp.where(mask, d1 < 0, True)) & (not stack.wall)
    acc = jnp.where(free, stack.overlaps(stack.accelerations(jnp.zeros_like(x1), x1)),
                    (r1 - r0) / (jnp.maximum(h, 1e-300) * T))
    t = jax.lax.stop_gradient(_closure_times(jnp.minimum(d1, 0.0), r1, acc) / T)
    land = jnp.min(jnp.where(mask & (d1 < -ONSET_OVERLAP * scale[0]), t, jnp.inf))
    limit = jnp.asarray(max_step, y1.dtype)
    if flight:  # every open gap counts here, the nearly closed ones too
        limit = jnp.where(free, jnp.maximum(max_step, fraction * jnp.min(jnp.where(mask, t, jnp.inf))), max_step)
    return limit, land, _starts(args, d1, r1)


def _in_window(t0, t_star, window):
    return (t0 >= t_star) & (t0 - t_star < window)


def _root4(x):
    return jnp.sqrt(jnp.sqrt(x))


def _s_ends(win, t0, t1, t_star):
    """`[s0, s1] = (t - t*)^{1/4}` at a step's ends in an onset window (any positive numbers outside one)."""
    return _root4(jnp.where(win, jnp.stack([t0, t1]) - t_star, jnp.array([1.0, 2.0])))


class FlightController(dfx.AbstractAdaptiveStepSizeController):
    """diffrax's `PIDController` (without `dtmax`) whose next step is at most `flight_limit` of the
    state it starts from: `max_step` contact times in contact, longer in free flight
    (`Tolerances.flight_steps`; `flight=False`: `max_step` always). The PID's own choice, acceptance and
    state are untouched.

    With `onsets` (`Tolerances.land_onsets`) it also lands every contact onset it can predict
    (`flight_and_landing`: the next step ends there if it would pass it), and inside an onset window (a step
    that starts at `onset_at`, for `window` contact times) it applies the PID's factor to the step in
    `s = (t - t*)^{1/4}`, the variable the solver steps in there (`UnrolledERK` with `onsets`): the first
    step of a window is `ONSET_FIRST_S` in `s`. It tells the solver of an onset at the next step's start
    through `made_jump`. Its state is then `(PID state, t*)` (`t* = -inf` before the first onset)."""

    pid: dfx.PIDController
    max_step: float = eqx.field(static=True)
    fraction: float = eqx.field(static=True)
    flight: bool = eqx.field(static=True, default=True)
    onsets: bool = eqx.field(static=True, default=False)
    window: float = eqx.field(static=True, default=0.05)
    first_step: float | None = eqx.field(static=True, default=None)

    @property
    def rtol(self):
        return self.pid.rtol

    @property
    def atol(self):
        return self.pid.atol

    @property
    def norm(self):
        return self.pid.norm

    def wrap(self, direction):
        return self

    def init(self, terms, t0, t1, y0, dt0, args, func, error_order):
        # the first step is the controller's own (`first_step`): `diffeqsolve(dt0=None)` compiles no
        # run-time check of dt0's sign, whose host callback would keep the solve out of JAX's persistent
        # compilation cache
        dt0 = self.first_step if dt0 is None else dt0
        dt0 = dt0 if dt0 is None else jnp.minimum(dt0, self.max_step)
        first, state = self.pid.init(terms, t0, t1, y0, dt0, args, func, error_order)
        if not self.onsets:
            return first, state
        onset = onset_at(args, y0)  # a touching stack's first contact starts at t0
        first = jnp.where(onset, jnp.minimum(t0 + ONSET_FIRST_S**4, t1), first)
        return first, (state, jnp.where(onset, t0, -jnp.inf))

    def adapt_step_size(self, t0, t1, y0, y1_candidate, args, y_error, error_order, controller_state):
        if not self.onsets:
            keep, next_t0, next_t1, made_jump, state, result = self.pid.adapt_step_size(
                t0, t1, y0, y1_candidate, args, y_error, error_order, controller_state)
            # The bound of the state the next step starts from. After a rejection that is `y0` again, whose
            # bound the rejected step kept, and the PID shrinks the step: nothing to do. So only
            # `y1_candidate`'s is needed.
            limit = (flight_limit(args, y1_candidate, self.max_step, self.fraction) if self.flight
                     else self.max_step)
            # as `PIDController(dtmax=limit)` computes it where the bound applies (`next_t0 + dtmax`), and
            # the PID's own `next_t1` untouched where it does not: bit for bit the old path wherever
            # limit = max_step
            clip = keep & (next_t1 - next_t0 > limit)
            return keep, next_t0, jnp.where(clip, next_t0 + limit, next_t1), made_jump, state, result
        pid_state, t_star = controller_state
        # in an onset window the step was taken in s (`UnrolledERK.step`): the PID chooses the next in s
        keep, next_t0, next_t1, _, pid_state, result = self.pid.adapt_step_size(
            t0, t1, y0, y1_candidate, args, y_error, error_order, pid_state)
        # the PID's factor on the step, applied in s = (t - t*)^{1/4} (as if it had been given s0, s1)
        win = _in_window(t0, t_star, self.window)
        s01 = _s_ends(win, t0, t1, t_star)
        factor = (next_t1 - next_t0) / (t1 - t0)
        s_next = jnp.where(keep, s01[1], s01[0]) + factor * (s01[1] - s01[0])
        next_t1 = jnp.where(win, t_star + s_next**4, next_t1)
        limit, land, onset = flight_and_landing(args, y0, y1_candidate, t1 - t0, self.max_step, self.fraction,
                                                self.flight)
        next_t1 = jnp.where(keep & (next_t1 - next_t0 > limit), next_t0 + limit, next_t1)
        # land the next onset: end the next step where an open interface closes (unless that step would be
        # too short for the time's rounding)
        resolvable = land > LANDING_MIN_ULPS * jnp.finfo(land.dtype).eps * jnp.maximum(jnp.abs(next_t0), 1.0)
        next_t1 = jnp.where(keep & resolvable & (next_t1 - next_t0 > land), next_t0 + land, next_t1)
        # a new window where the accepted step ends at an onset; `made_jump` tells the solver (diffrax passes
        # it to the next step, and keeps the old one with a rejected step)
        onset = keep & onset
        t_star = jnp.where(onset, t1, t_star)
        next_t1 = jnp.where(onset, t1 + ONSET_FIRST_S**4, next_t1)
        return keep, next_t0, next_t1, onset, (pid_state, t_star), result


#: largest state (entries) that `UnrolledERK` steps with its stages written out; above, diffrax's loop
UNROLL_MAX_STATE = 128


class UnrolledERK(dfx.AbstractAdaptiveSolver):
    """An explicit Runge–Kutta pair with the first-same-as-last and solution-is-last-stage properties
    (diffrax's `tableau.fsal` and `ssal`: Tsit5, Dopri5, Dopri8), diffrax's tableau and interpolation,
    with its stages written out rather than looped over.

    diffrax's Runge–Kutta solvers run the stages through an inner while loop (general PyTrees, implicit
    tableaus, one compiled stage); for the few dozen numbers of a stack's state the loop's bookkeeping
    costs more than the vector field. Unrolled, XLA fuses each stage into the next: the same arithmetic
    (to rounding) in fewer, larger operations. The solver state is `f(t0, y0)` (first same as last); the
    stack is never solved with jumps (no `jump_ts`, no events that restart): `made_jump` is read only with
    `onsets`, where `FlightController` sets it at a contact onset.
    For one flat array state and an ODE term only. Subclasses set `tableau`, `base_interpolation`,
    `method_order` and `stock`, diffrax's own solver of the same method.

    Written out pays only for small states: from ~30 masses on (a state of `UNROLL_MAX_STATE` = 128
    entries) diffrax's loop, which fills one buffer of stages, is as fast or faster (measured on the
    Nesterenko chain, `benchmarks/long_chains.py`: Dopri8 at n = 100 / 300 / 1,000 took 64 / 317 / 2,557
    ms written out against 51 / 218 / 1,664 ms in diffrax's loop; equal at n = 30; at n = 10, 8.4 against
    13.9 us per step), so above it the step is diffrax's (`stock`; the shape is static: one or the other
    per compiled solve). `scan_kind` is passed to it (diffrax sets it for forward-mode adjoints).
    """

    term_structure: ClassVar = dfx.AbstractTerm
    tableau: ClassVar[Any]
    base_interpolation: ClassVar[Any]
    method_order: ClassVar[int]
    stock: ClassVar[Any]
    scan_kind: str | None = None  # a plain field, as diffrax's (`_Tracked.around` sets it with `eqx.tree_at`)
    #: onset windows (`Tolerances.land_onsets`; set by the solve for states of at most `UNROLL_MAX_STATE`
    #: entries, with `FlightController(onsets=True)`): the state is then `(f(t0, y0), t*)`
    onsets: bool = eqx.field(static=True, default=False)
    window: float = eqx.field(static=True, default=0.05)

    @property
    def interpolation_cls(self):
        return _onset_interpolation(self.base_interpolation) if self.onsets else self.base_interpolation

    def _large(self, y0) -> bool:
        return y0.shape[0] > UNROLL_MAX_STATE

    def order(self, terms):
        return self.method_order

    def init(self, terms, t0, t1, y0, args):
        if self._large(y0):
            return self.stock(scan_kind=self.scan_kind).init(terms, t0, t1, y0, args)
        f0 = terms.vf(t0, y0, args)
        if not self.onsets:
            return f0
        # an onset at the start (a touching stack's first contact), as `FlightController.init` finds it
        return f0, jnp.where(onset_at(args, y0), t0, -jnp.inf).astype(y0.dtype)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        """One step `t0 -> t1`. With `onsets`, a step that starts where a contact starts (`onset_at`) opens
        a window of `window` contact times from `t* = t0`, and a step that starts in it is the same
        Runge–Kutta step in `s = (t - t*)^{1/4}`, `dy/ds = f(t* + s^4, y) 4 s^3` (stage `i` at
        `s0 + c_i (s1 - s0)`), where the motion after a contact's start is a power series; elsewhere the
        step is the plain one, operation for operation."""
        if self._large(y0):
            return self.stock(scan_kind=self.scan_kind).step(terms, t0, t1, y0, args, solver_state, made_jump)
        tab = self.tableau
        dt = terms.contr(t0, t1)
        if self.onsets:
            f0, t_star = solver_state
            t_star = jnp.where(made_jump, t0, t_star)  # the controller found an onset at t0
            win = _in_window(t0, t_star, self.window)
            s01 = _s_ends(win, t0, t1, t_star)
            ds = s01[1] - s01[0]
            # every stage's time and weight in one operation each (XLA on a CPU runs every operation that it
            # cannot fuse as a kernel of its own, ~80 ns: few, wider operations)
            cs = np.array([0.0] + [float(c) for c in tab.c])
            sc = s01[0] + cs * ds
            times = jnp.where(win, t_star + sc**4, t0 + cs * dt).at[0].set(t0).at[-1].set(t1)
            weights = jnp.where(win, 4.0 * sc**3 * ds, dt)
            # vmapped on a CPU, computed once per step: XLA otherwise fused them into every stage's state
            # and recomputed them for each of its entries (`_fusion`)
            times, weights = materialised(times, weights)
            index = {c: i for i, c in enumerate(cs)}

            def at(c):  # (time, weight) of a stage at the fraction c of the step
                return times[index[c]], weights[index[c]]
        else:
            f0 = solver_state

            def at(c):
                return t0 + c * dt, dt
        ks = [f0 * at(0.0)[1]]
        for a_row, c in zip(tab.a_lower, tab.c):
            yi = y0 + sum(float(a) * k for a, k in zip(a_row, ks) if a != 0)
            ti, wi = at(float(c))
            ks.append(terms.vf(ti, yi, args) * wi)
        y1 = yi  # the last stage is evaluated at y1 (b_sol equals the last row: "ssal")
        y_error = sum(float(b) * k for b, k in zip(tab.b_error, ks) if b != 0)
        f1 = ks[-1] / wi
        if not self.onsets:
            return y1, y_error, dict(y0=y0, y1=y1, k=jnp.stack(ks)), f1, dfx.RESULTS.successful
        dense_info = dict(y0=y0, y1=y1, k=jnp.stack(ks), t_star=t_star, window=win)
        return y1, y_error, dense_info, (f1, t_star), dfx.RESULTS.successful

    def func(self, terms, t0, y0, args):
        return terms.vf(t0, y0, args)


@functools.cache
def _onset_interpolation(base):
    """The dense output of `UnrolledERK(onsets=True)`: `base` (the method's own interpolation) in the
    step's variable, `s = (t - t*)^{1/4}` in an onset window, `t` elsewhere."""

    class OnsetInterpolation(dfx.AbstractLocalInterpolation):
        t0: Any
        t1: Any
        y0: Any
        y1: Any
        k: Any
        t_star: Any
        window: Any

        def _base(self):
            return base(t0=self.t0, t1=self.t1, y0=self.y0, y1=self.y1, k=self.k)

        def _mapped(self, t):
            # the time at which the plain step's interpolation reads the fraction (s - s0) / (s1 - s0)
            s0 = _root4(jnp.where(self.window, self.t0 - self.t_star, 1.0))
            s1 = _root4(jnp.where(self.window, self.t1 - self.t_star, 2.0))
            s = _root4(jnp.where(self.window, jnp.maximum(t - self.t_star, 0.0), 1.0))
            return jnp.where(self.window, self.t0 + (s - s0) / (s1 - s0) * (self.t1 - self.t0), t)

        def evaluate(self, t0, t1=None, left=True):
            b = self._base()
            if t1 is None:
                return b.evaluate(self._mapped(t0), None, left)
            return b.evaluate(self._mapped(t1), None, left) - b.evaluate(self._mapped(t0), None, left)

    OnsetInterpolation.__name__ = OnsetInterpolation.__qualname__ = f"Onset{base.__name__}"
    return OnsetInterpolation


class UnrolledTsit5(UnrolledERK):
    """Tsitouras' 5(4) pair (Tsitouras 2011, *Comput. Math. Appl.* 62, 770), unrolled (`UnrolledERK`): the
    default solver."""

    tableau: ClassVar = dfx.Tsit5.tableau
    base_interpolation: ClassVar = dfx.Tsit5.interpolation_cls
    stock: ClassVar = dfx.Tsit5
    method_order: ClassVar[int] = 5


class UnrolledDopri8(UnrolledERK):
    """Dormand–Prince 8(7) (Prince & Dormand 1981, *J. Comput. Appl. Math.* 7, 67; dense output of
    Bogacki & Shampine 1990), unrolled (`UnrolledERK`): 14 stages a step."""

    tableau: ClassVar = dfx.Dopri8.tableau
    base_interpolation: ClassVar = dfx.Dopri8.interpolation_cls
    stock: ClassVar = dfx.Dopri8
    method_order: ClassVar[int] = 8


class UnrolledDopri5(UnrolledERK):
    """Dormand–Prince 5(4) (Dormand & Prince 1980, *J. Comput. Appl. Math.* 6, 19), unrolled
    (`UnrolledERK`)."""

    tableau: ClassVar = dfx.Dopri5.tableau
    base_interpolation: ClassVar = dfx.Dopri5.interpolation_cls
    stock: ClassVar = dfx.Dopri5
    method_order: ClassVar[int] = 5


def make_solver(name: str | dfx.AbstractSolver, tolerances: Tolerances | None = None) -> dfx.AbstractSolver:
    """A diffrax solver from a name of `hertz_chain.registry.SOLVERS` (`"tsit5"`, the default: this
    module's `UnrolledTsit5`; `"dopri5"`, `"dopri8"`, unrolled the same way (`UnrolledDopri5`,
    `UnrolledDopri8`); `"tsit5-diffrax"`, `"dopri5-diffrax"`, `"dopri8-diffrax"`, diffrax's own;
    `"kvaerno5"` (implicit, with a Chord iteration that terminates properly), `"kvaerno5-stock"`). A solver
    instance is returned unchanged.

    **Raises** `ParameterError` for a name that is not in the registry."""
    if isinstance(name, dfx.AbstractSolver):
        return name
    row = _registry.SOLVERS.get(str(name).lower())
    if row is None:
        raise ParameterError("solver", name, f"one of {', '.join(repr(k) for k in _registry.SOLVERS)} or a "
                             "diffrax solver")
    return row.make(tolerances or Tolerances())


def _make_adjoint(adjoint, max_steps: int) -> dfx.AbstractAdjoint:
    if isinstance(adjoint, dfx.AbstractAdjoint):
        if isinstance(adjoint, dfx.BacksolveAdjoint):
            raise ParameterError("adjoint", "BacksolveAdjoint", "'reverse' or 'forward' (BacksolveAdjoint "
                                 "cannot be used with the stopping event)")
        return adjoint
    if adjoint in (None, "reverse"):
        # `launch_velocity` differentiates "reverse" by replaying the steps (`_replayed_solve`), and then
        # runs this adjoint's primal loop only. Otherwise one checkpoint per step: the state is a few dozen
        # numbers, so storing every step is cheap, and reverse mode then recomputes nothing (diffrax's
        # default, ~sqrt(2 max_steps) checkpoints, recomputes every step two to three times).
        return dfx.RecursiveCheckpointAdjoint(checkpoints=max_steps)
    if adjoint == "forward":
        return dfx.ForwardMode()
    raise ParameterError("adjoint", adjoint, "'reverse' (jax.grad), 'forward' (jax.jacfwd) or a diffrax adjoint")


class _SolveConfig(eqx.Module):
    """Everything static about a solve: one compilation per (structure, config)."""

    solver: Any
    tolerances: Tolerances
    max_steps: int = eqx.field(static=True)
    adjoint: Any
    save_steps: bool = eqx.field(static=True)
    until: str = eqx.field(static=True, default="cascade")
    #: without a step history, also stream the top pulse's 10 % duration (`simulate_batch(pulse_durations=True)`)
    durations: bool = eqx.field(static=True, default=False)
