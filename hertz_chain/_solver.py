"""Options and solvers of `hertz_chain.simulation`: `Tolerances`, the unrolled Tsit5, `make_solver` (from
`hertz_chain.registry.SOLVERS`), the adjoint choice and the static configuration of a solve."""

from __future__ import annotations

from typing import Any, ClassVar

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import _config  # noqa: F401  (float64)
from . import registry as _registry
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

    def controller(self) -> dfx.AbstractAdaptiveStepSizeController:
        """The step-size controller: diffrax's `PIDController`, with `max_step` as its largest step, or
        (`flight_steps`) `FlightController` around it."""
        if not self.flight_steps:
            return dfx.PIDController(
                rtol=self.rtol, atol=self.atol, pcoeff=self.pcoeff, icoeff=self.icoeff, dtmax=self.max_step
            )
        pid = dfx.PIDController(rtol=self.rtol, atol=self.atol, pcoeff=self.pcoeff, icoeff=self.icoeff)
        return FlightController(pid, self.max_step, self.flight_fraction)


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


class FlightController(dfx.AbstractAdaptiveStepSizeController):
    """diffrax's `PIDController` (without `dtmax`) whose next step is at most `flight_limit` of the
    state it starts from: `max_step` contact times in contact, longer in free flight
    (`Tolerances.flight_steps`). The PID's own choice, acceptance and state are untouched."""

    pid: dfx.PIDController
    max_step: float = eqx.field(static=True)
    fraction: float = eqx.field(static=True)

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
        dt0 = dt0 if dt0 is None else jnp.minimum(dt0, self.max_step)
        return self.pid.init(terms, t0, t1, y0, dt0, args, func, error_order)

    def adapt_step_size(self, t0, t1, y0, y1_candidate, args, y_error, error_order, controller_state):
        keep, next_t0, next_t1, made_jump, state, result = self.pid.adapt_step_size(
            t0, t1, y0, y1_candidate, args, y_error, error_order, controller_state)
        # The bound of the state the next step starts from. After a rejection that is `y0` again, whose bound
        # the rejected step kept, and the PID shrinks the step: nothing to do. So only `y1_candidate`'s is
        # needed.
        limit = flight_limit(args, y1_candidate, self.max_step, self.fraction)
        # as `PIDController(dtmax=limit)` computes it where the bound applies (`next_t0 + dtmax`), and the
        # PID's own `next_t1` untouched where it does not: bit for bit the old path wherever limit = max_step
        clip = keep & (next_t1 - next_t0 > limit)
        return keep, next_t0, jnp.where(clip, next_t0 + limit, next_t1), made_jump, state, result


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
    stack is never solved with jumps (`made_jump` is always False: no `jump_ts`, no events that restart).
    For one flat array state and an ODE term only. Subclasses set `tableau`, `interpolation_cls`,
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
    interpolation_cls: ClassVar[Any]
    method_order: ClassVar[int]
    stock: ClassVar[Any]
    scan_kind: str | None = None  # a plain field, as diffrax's (`_Tracked.around` sets it with `eqx.tree_at`)

    def _large(self, y0) -> bool:
        return y0.shape[0] > UNROLL_MAX_STATE

    def order(self, terms):
        return self.method_order

    def init(self, terms, t0, t1, y0, args):
        if self._large(y0):
            return self.stock(scan_kind=self.scan_kind).init(terms, t0, t1, y0, args)
        return terms.vf(t0, y0, args)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        if self._large(y0):
            return self.stock(scan_kind=self.scan_kind).step(terms, t0, t1, y0, args, solver_state, made_jump)
        del made_jump
        tab = self.tableau
        dt = terms.contr(t0, t1)
        ks = [solver_state * dt]
        for a_row, c in zip(tab.a_lower, tab.c):
            yi = y0 + sum(float(a) * k for a, k in zip(a_row, ks) if a != 0)
            ks.append(terms.vf(t0 + float(c) * dt, yi, args) * dt)
        y1 = yi  # the last stage is evaluated at y1 (b_sol equals the last row: "ssal")
        y_error = sum(float(b) * k for b, k in zip(tab.b_error, ks) if b != 0)
        f1 = ks[-1] / dt
        dense_info = dict(y0=y0, y1=y1, k=jnp.stack(ks))
        return y1, y_error, dense_info, f1, dfx.RESULTS.successful

    def func(self, terms, t0, y0, args):
        return terms.vf(t0, y0, args)


class UnrolledTsit5(UnrolledERK):
    """Tsitouras' 5(4) pair (Tsitouras 2011, *Comput. Math. Appl.* 62, 770), unrolled (`UnrolledERK`): the
    default solver."""

    tableau: ClassVar = dfx.Tsit5.tableau
    interpolation_cls: ClassVar = dfx.Tsit5.interpolation_cls
    stock: ClassVar = dfx.Tsit5
    method_order: ClassVar[int] = 5


class UnrolledDopri8(UnrolledERK):
    """Dormand–Prince 8(7) (Prince & Dormand 1981, *J. Comput. Appl. Math.* 7, 67; dense output of
    Bogacki & Shampine 1990), unrolled (`UnrolledERK`): 14 stages a step."""

    tableau: ClassVar = dfx.Dopri8.tableau
    interpolation_cls: ClassVar = dfx.Dopri8.interpolation_cls
    stock: ClassVar = dfx.Dopri8
    method_order: ClassVar[int] = 8


class UnrolledDopri5(UnrolledERK):
    """Dormand–Prince 5(4) (Dormand & Prince 1980, *J. Comput. Appl. Math.* 6, 19), unrolled
    (`UnrolledERK`)."""

    tableau: ClassVar = dfx.Dopri5.tableau
    interpolation_cls: ClassVar = dfx.Dopri5.interpolation_cls
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
