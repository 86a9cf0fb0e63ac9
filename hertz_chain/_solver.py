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
    - `max_step`: the largest step, in units of the contact time `T` (0.5 never steps over a contact).
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

    def __check_init__(self):
        for name in ("rtol", "atol", "max_step", "first_step"):
            value = getattr(self, name)
            if isinstance(value, (jax.Array, np.ndarray)) and name in ("rtol", "atol"):
                continue  # already validated (the array copy made by `_prepare`, traced under jit)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise ParameterError(name, value, "a finite number > 0")
        if not 0 <= self.pcoeff <= 1 or not 0 < self.icoeff <= 1:
            raise ParameterError("pcoeff/icoeff", (self.pcoeff, self.icoeff), "0 <= pcoeff <= 1, 0 < icoeff <= 1")

    def controller(self) -> dfx.PIDController:
        return dfx.PIDController(
            rtol=self.rtol, atol=self.atol, pcoeff=self.pcoeff, icoeff=self.icoeff, dtmax=self.max_step
        )


class UnrolledTsit5(dfx.AbstractAdaptiveSolver):
    """Tsitouras' 5(4) pair (Tsitouras 2011, *Comput. Math. Appl.* 62, 770), diffrax's tableau and
    interpolation, with its seven stages written out rather than looped over.

    diffrax's Runge–Kutta solvers run the stages through an inner while loop (general PyTrees, implicit
    tableaus, one compiled stage); for the few dozen numbers of a stack's state the loop's bookkeeping
    costs more than the vector field. Unrolled, XLA fuses each stage into the next: the same arithmetic
    (to rounding) in fewer, larger operations. First same as last: the solver state is `f(t0, y0)`; the
    stack is never solved with jumps (`made_jump` is always False: no `jump_ts`, no events that restart).
    For one flat array state and an ODE term only.
    """

    term_structure: ClassVar = dfx.AbstractTerm
    interpolation_cls: ClassVar = dfx.Tsit5.interpolation_cls

    def order(self, terms):
        return 5

    def init(self, terms, t0, t1, y0, args):
        return terms.vf(t0, y0, args)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        del made_jump
        tab = dfx.Tsit5.tableau
        dt = terms.contr(t0, t1)
        ks = [solver_state * dt]
        for a_row, c in zip(tab.a_lower, tab.c):
            yi = y0 + sum(float(a) * k for a, k in zip(a_row, ks) if a != 0)
            ks.append(terms.vf(t0 + float(c) * dt, yi, args) * dt)
        y1 = yi  # Tsit5's last stage is evaluated at y1 (b_sol equals the last row: "ssal")
        y_error = sum(float(b) * k for b, k in zip(tab.b_error, ks) if b != 0)
        f1 = ks[-1] / dt
        dense_info = dict(y0=y0, y1=y1, k=jnp.stack(ks))
        return y1, y_error, dense_info, f1, dfx.RESULTS.successful

    def func(self, terms, t0, y0, args):
        return terms.vf(t0, y0, args)


def make_solver(name: str | dfx.AbstractSolver, tolerances: Tolerances | None = None) -> dfx.AbstractSolver:
    """A diffrax solver from a name of `hertz_chain.registry.SOLVERS` (`"tsit5"`, the default: this
    module's `UnrolledTsit5`; `"tsit5-diffrax"`, `"dopri5"`, `"dopri8"`, `"kvaerno5"` (implicit, with a
    Chord iteration that terminates properly), `"kvaerno5-stock"`). A solver instance is returned
    unchanged.

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
