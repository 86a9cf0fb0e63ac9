"""Integrate a `Stack` with diffrax: adaptive, float64, batched and differentiable.

This is the only module that imports diffrax. Entry points:

- `simulate(stack, state, ...) -> Solution` — one design; raises `SolverError` on failure.
- `simulate_batch(stacks, states, ...) -> BatchSolution` — many designs of one structure through one
  compiled, vmapped solve; a failing design is flagged in its own `status`, never aborting the batch.
- `launch_velocity(stack, state, ...) -> Array` — the launch velocity of every mass as a JAX function,
  for `jax.grad` / `jax.jacfwd` with respect to masses, gaps and contact parameters.
- `restitution(law, impact_velocity, effective_mass) -> Restitution` — one contact, measured.

**Scaling.** The solver integrates a dimensionless state: time in units of `T`, the Hertz contact time
`t_c = 2.94328 delta_max / V` of the shortest contact; positions in units of `L = delta_max`, the peak
overlap of the stiffest contact (the root of `potential(delta) = m* V^2/2`, which for Hertz is
`(5 m* V^2/(4k))^{2/5}`); velocities in units of `V`, the drop speed (the largest initial speed, or
relative speed, in general; 1 m/s if everything is at rest); dissipated energies in units of
`E = sum(m) V^2/2`. So `rtol`/`atol` mean the same for every design (Hertz contact: Johnson, *Contact
Mechanics*, 1985, §11.1; docs/references.md, "Hertz single impact").

**Solvers.** `"tsit5"` (default: `UnrolledTsit5`, diffrax's Tsit5 with its stages written out, 2.2x
faster per step on a 10-mass stack: 5.6 -> 2.5 us, and 0.55 -> 0.38 ms per design in a 5-mass batch over 2
cores), `"tsit5-diffrax"`, `"dopri8"`, `"kvaerno5"` (implicit, with a corrected Newton
iteration), `"kvaerno5-stock"`, or any diffrax solver instance. The default is Tsit5: the stack is not
stiff for Hertzian contact (`dt rho(J) <= 0.32` along the steps, docs/references.md, "Solver notes"), so an implicit solver
buys nothing. Measured (2-core CPU, 5/10 masses, ratio 0.5, Hertz, gaps 0.1 mm, rtol = atol = 1e-8, per
`simulate` call): Tsit5 179/313 steps, 6.4/6.5 ms; Dopri8 157/264 steps, 6.6/8.1 ms; Kvaerno5 (fixed)
187/318 steps (30/46 rejected), 19/43 ms; Kvaerno5 (stock) 538/831 steps (122/180 rejected), 46/79 ms. diffrax 0.7.2's implicit
solvers use `VeryChord`, which declares divergence after two iterations (fixed upstream, diffrax PR
#754), so most steps are rejected; `"kvaerno5"` passes an `optimistix.Chord` with proper tolerances as
`root_finder` instead.

**Default tolerances** `rtol = atol = 1e-10` (scaled state) with `resolve_onsets=True` follow from the
benchmark table (`benchmarks/results.md`, README) and from an error-distribution study. The table's
single solves (no onset proxy: the same equations as scipy; reference Dopri8 at 1e-13; n = 2, 5, 10, 20;
gapped Hertz/Tsuji, touching, e = 0.3, soft pad): at 1e-10 Tsit5 puts the top mass's launch velocity
within 1e-7 (relative) in 18 of 20 cases and misses by up to 7x in two (gapped Tsuji, n = 5: 1.0e-7; soft
pad, n = 20: 7.4e-7; the stock diffrax Tsit5, the same method rounded differently, missed in two other
cases by up to 3x); Dopri8 misses in one (soft pad, n = 20: 2.8e-7). At the former 1e-8 errors reached
5e-5. Summed over n at matched accuracy (run of 2026-11-23 11:02; matched = the loosest rtol of a 1-2-5
grid that reaches 1e-7 and keeps it for a decade of tighter rtols), Tsit5 (`UnrolledTsit5`) is the fastest
diffrax method in all five regimes: 9.0 ms gapped Hertz (Dopri8 11.2), 14.4 gapped Tsuji (34.3), 6.5
touching (13.8), 14.6 for e = 0.3 (35.8), 39.7 soft pad (92.8); diffrax's own Tsit5 takes 1.7-2.3x as
long, Kvaerno5 63-87x. The matched rtol of Tsit5 is 1e-10 to 2e-9 in 18 of 20 cases (5e-11 for
gapped Tsuji n = 5 and soft pad n = 20): the default sits at the tight end of that range. (Before the
stages were unrolled, Dopri8 won for gapped Hertz and e = 0.3, by
margins that run-to-run noise of 10-20 % on the shared 2-core machine could reverse.) Its error tail is
tamed by the onset proxy. The study: one case per regime hides a heavy
tail. Over 100 gaps within 1e-11 of 1 cm (paper's six-mass MVG, 1e9 N/m^1.5, 1 m/s; error against Dopri8
at 1e-12), a step that straddles a contact onset is now and then accepted with a large error: without the
onset proxy, Hertz at 1e-10 has median error 1.8e-8 but maximum 3.3e-7; with it, maximum 3.6e-10 (1.4x the
steps). Tsuji (clamped): maximum 9.0e-7 -> 4.4e-7 at 1e-10 and 4.8e-8 -> 2.0e-8 at 1e-11 (its
`delta^{1/4}` damping and the clamp's release keep a tail that the proxy does not remove: ask for 1e-11
when a damped stack needs 1e-7 everywhere).

**Step control.** `PIDController(pcoeff=0.4, icoeff=0.3)` (Söderlind 2003; suits the non-smooth contact
onset), and a largest step of `max_step` contact times (default 0.5) so that a free flight never steps
over a whole contact.

**Stopping: the end of the first cascade.** The solve ends (a boolean `diffrax.Event`) at the first
accepted step where the cascade is over (`_cascade_over`): something has touched (a velocity departs from
free flight), every contact between masses is open and no neighbours approach, and mass 1 moves up from
the ground or rests on it; more generally, the lower masses `1..k` are bound to the ground (their energy
is below that of resting unloaded on it) or, as a settled group in flight, can never reach mass `k+1`
again, while everything above them flies apart. Under a common gravity the relative velocity of two
free masses is constant, so after that only a return to the ground can start anything new: a rebound. With `until="t_max"` the
solve goes on to `t_max`, the contact bookkeeping frozen at the cascade's end, and later contacts make the
status "complete with rebounds". The top mass's launch is frozen earlier if it passes the apex of its
flight before the cascade is over: its landing back on the stack is a rebound too. `t_max` defaults to a
limit from the physics (`_default_t_max`); reaching it, or `max_steps`, first leaves the run
"incomplete" (`hertz_chain.status.Status`).

**Launch velocities.** The launch velocity of a mass is its velocity when its last push of the first
cascade ended: the contact force of its last contact returned to zero (the one definition of a contact's
end, shared by `hertz_chain.episodes`, the pulses and `restitution`). The end `t_end` is located inside
the solver step where the force drops to zero by extrapolating both bodies in free flight from the
first accepted point after it and solving `G(t) = 0` for the separation function `G` of
`Stack.separation_function`: bisection, then one Newton step for the derivative (implicit function
theorem), so the launch velocity is differentiable. The velocity of each body at that accepted point is
recorded, and `v_launch = v(t_r) + g (t_r - t_end)` (free flight in between: exact). The bracketing
points, the recorded velocities and the energy audit are kept while solving, in the solver state of a
wrapper around the diffrax solver (`_Tracked`; diffrax keeps the state of accepted steps only), so no
step history is needed: `launch_velocity` and `simulate_batch(..., save_steps=False)` save none, and
their cost per step does not grow with `max_steps`.

**Batches.** `simulate_batch` vmaps one compiled solve over the designs and, when there are several JAX
devices, splits the designs over them (`jax.shard_map`); on a CPU, `hertz_chain` makes every core a
device before JAX starts (`jax_num_cpu_devices`; `HERTZ_CHAIN_CPU_DEVICES` overrides, and a choice the
user made first is kept). Every device loops until its slowest design is done.

**Gradients.** Discretise-then-optimise through the solver. The tangent of the discretised solve is not
error-controlled, and the contact onset (where `F ~ delta^{3/2}` is not smooth) spoils it: measured on a
3-mass Hunt–Crossley stack with gravity and gaps, jacfwd vs central differences was 16 % off at
`tol = 1e-8` and 4 % at `1e-10` (worst parameter: stiffness and gaps); with `Tolerances(resolve_onsets=True)`
(an auxiliary state that makes the controller resolve every onset) it is 1.1e-4 at `1e-10` and 3.5e-6 at
`1e-11`. `launch_velocity` therefore defaults to `rtol = atol = 1e-11` with `resolve_onsets=True`. Use
`adjoint="forward"` (`diffrax.ForwardMode`, for `jax.jacfwd`/`jax.jvp`; cheapest for a few parameters:
33 ms for 11 parameters) or `"reverse"` (for `jax.grad`, the default of `launch_velocity`; agreed with
forward mode to 5e-7). Reverse mode replays the accepted steps: the solve saves its accepted states
(`4n` numbers per step of `max_steps`), and the backward pass runs once down that history, applying
`jax.vjp` of the solver's own step to each, with the step times frozen, as diffrax's controller freezes
them (it stops gradients through the step size). It is the discrete adjoint that diffrax's
`RecursiveCheckpointAdjoint` computes through its loop (they agree to rounding, 1e-14, tested), without
storing the whole loop state at every step and replaying the controller, the event and the bookkeeping
(`_replayed_solve`): 1.3-1.5x cheaper than that with a checkpoint at every step (benchmarks). It supports reverse mode
only; pass a diffrax adjoint (`RecursiveCheckpointAdjoint()`) for forward-over-reverse (Hessians).
`BacksolveAdjoint` cannot be used: it refuses events. Laws whose Jacobian is
singular at the onset (Tsuji `delta^{1/4}`, viscoelastic `delta^{1/2}` damping) give much less accurate
discrete gradients (percent level at 1e-10 without `resolve_onsets`): check them against finite
differences before relying on them. Measured with the onset proxy (benchmarks, gapped stacks, gradient
with respect to the masses, central differences of a 1e-13 reference, error relative to the largest
component): Hertz agrees to 4e-9 at `1e-11` (n = 5 and 10); Tsuji to 1.4e-3 (n = 5) and 2.7e-4 (n = 10)
at `1e-11`, and 2e-4 (n = 5) at `1e-13`, forward and reverse mode alike.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, ClassVar

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from . import _config  # noqa: F401  (float64)
from . import registry as _registry
from ._export import cached_jit
from .contact import AbstractContactLaw
from .errors import ParameterError, SolverError
from .stack import Stack, State, at_impact, invert_monotone
from .status import Status

__all__ = [
    "Tolerances",
    "Scales",
    "Trajectory",
    "Solution",
    "BatchSolution",
    "Restitution",
    "UNTIL",
    "UnrolledTsit5",
    "make_solver",
    "simulate",
    "simulate_batch",
    "launch_velocity",
    "restitution",
]

HERTZ_TIME = 2.94328  # t_c = 2.94328 delta_max / v (Hertz; docs/references.md, "Hertz single impact")

#: What `simulate(..., until=...)` accepts: stop at the end of the first cascade, or go on to `t_max`.
UNTIL = ("cascade", "t_max")


# ==================================================================== options
class Tolerances(eqx.Module):
    """Step-size control, in the scaled units of the module docstring.

    - `rtol`, `atol`: PID controller tolerances (scaled state, so `atol` is relative to the scales).
    - `pcoeff`, `icoeff`: PID coefficients (0.4, 0.3: docs/references.md, "Solver notes").
    - `max_step`: the largest step, in units of the contact time `T` (0.5 never steps over a contact).
    - `first_step`: the first step, in units of `T`.
    - `resolve_onsets`: add one auxiliary state per interface, `z_j' = sqrt(delta_j+/L)`, whose local
      error is `O(h^1.5)` where a contact starts, so that the controller resolves every contact onset
      (where `F ~ delta^{3/2}` is not smooth) to the tolerance. The solution barely needs it, but
      derivatives do: the tangent of the discretised solve is not error-controlled, and without this
      the gradient with respect to gaps is only accurate to ~`sqrt(tol)` in units of `V/L`.
      It also removes the heavy tail of the launch-velocity error (module docstring). Default on;
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


class _Config(eqx.Module):
    """Everything static about a solve: one compilation per (structure, config)."""

    solver: Any
    tolerances: Tolerances
    max_steps: int = eqx.field(static=True)
    adjoint: Any
    save_steps: bool = eqx.field(static=True)
    until: str = eqx.field(static=True, default="cascade")


# ==================================================================== scales
class Scales(eqx.Module):
    """The units of the scaled state: time `T` (s), length `L` (m), velocity `V` (m/s), energy `E` (J)."""

    time: Array
    length: Array
    velocity: Array
    energy: Array

    def vector(self, n: int) -> Array:
        return jnp.concatenate([jnp.full(n, self.length), jnp.full(n, self.velocity), jnp.full(n, self.energy)])


def _speed(stack: Stack, state: State) -> Array:
    """The velocity scale `V`: the largest initial speed or relative speed; for a stack released at
    rest, the speed of a fall through its whole height under gravity; 1 m/s if nothing would move."""
    x, v = state.positions, state.velocities
    mask = stack.interface_mask()
    rel = jnp.where(mask, jnp.abs(stack.overlap_rates(v)), 0.0)
    vel = jnp.maximum(jnp.max(jnp.abs(v)), jnp.max(rel))
    height = jnp.max(x) - jnp.minimum(jnp.min(x), 0.0)
    fall = jnp.sqrt(2.0 * stack.gravity * height)
    return jnp.where(vel > 0, vel, jnp.where(fall > 0, fall, 1.0))


def _peak_overlaps(stack: Stack, vel) -> Array:
    """`(n,)` peak overlap of every interface hit at `vel` (the root of `potential(delta) = m* vel^2/2`,
    Hertz: `(5 m* vel^2/(4k))^{2/5}`); inf where there is no interface."""
    mask = stack.interface_mask()
    target = 0.5 * stack.effective_masses() * vel**2
    fn = lambda d: jnp.where(mask, stack.potentials(d), d)  # noqa: E731
    return jnp.where(mask, invert_monotone(fn, jnp.where(mask, target, 1.0)), jnp.inf)


def _scales(stack: Stack, state: State) -> Scales:
    """Contact time and peak overlap of the stiffest contact at the drop speed (module docstring)."""
    stack, state = jax.lax.stop_gradient((stack, state))
    vel = _speed(stack, state)
    length = jnp.min(_peak_overlaps(stack, vel))
    return Scales(
        time=HERTZ_TIME * length / vel,
        length=length,
        velocity=vel,
        energy=0.5 * jnp.sum(stack.masses) * vel**2,
    )


def _default_t_max(stack: Stack, state: State, sc: Scales) -> Array:
    """A time limit (s) that covers the first cascade, from the physics (issue 16):

    `t_fall + 2 sum_j t_gap,j + 200 sum_j t_c,j + 4 V/g`, where `t_fall` is when mass 1 reaches the
    ground in free flight (0 without the ground or when it never does), `t_gap,j = min(s_j/V,
    sqrt(2 s_j/g))` the time to close gap `s_j` at the drop speed `V` or by falling from rest,
    `t_c,j = 2.94328 delta_max,j / V` the Hertz contact time estimate of interface `j` (its own
    effective mass; Johnson 1985, §11.1), and `4 V/g` two times of flight of a mass thrown up at `V`
    (mass 1's bounces on the ground during the cascade). The solve stops at the cascade's end, so a
    generous limit costs nothing when the cascade ends."""
    stack, state = jax.lax.stop_gradient((stack, state))
    g, V = stack.gravity, sc.velocity
    x, v = state.positions, state.velocities
    x1, v1 = jnp.maximum(x[0], 0.0), v[0]
    g_safe = jnp.where(g > 0, g, 1.0)
    fall_g = (v1 + jnp.sqrt(v1**2 + 2.0 * g * x1)) / g_safe
    fall_0 = jnp.where(v1 < 0, x1 / jnp.where(v1 < 0, -v1, 1.0), 0.0)
    t_fall = jnp.where(stack.ground, jnp.where(g > 0, fall_g, fall_0), 0.0)
    gaps = jnp.maximum(jnp.diff(x), 0.0)
    t_gap = jnp.minimum(gaps / V, jnp.where(g > 0, jnp.sqrt(2.0 * gaps / g_safe), jnp.inf))
    t_c = jnp.where(stack.interface_mask(), HERTZ_TIME * _peak_overlaps(stack, V) / V, 0.0)
    flight = jnp.where(g > 0, 4.0 * V / g_safe, 0.0)
    return t_fall + 2.0 * jnp.sum(t_gap) + 200.0 * jnp.sum(t_c) + flight


# ==================================================================== the compiled solve
def _scaled_field(t, ys, args):
    """The scaled vector field of the solver's state `[x, v, D (3n) | z (n, with resolve_onsets) | over]`.

    `over` (the last entry) is no variable of the motion: its derivative is zero, and `_Tracked` writes
    the cascade-over flag of `_cascade_over` into it after every step, so that the stopping event reads
    one number instead of evaluating the rule again. A state of exactly `3n` entries (the replayed
    adjoint's physical part) gets the `3n` physical derivatives."""
    stack, scale, T = args[:3]
    n3 = scale.shape[0]
    y = ys[:n3] * scale
    dy = T * stack.vector_field(t * T, y) / scale
    if ys.shape[0] == n3:
        return dy
    parts = [dy]
    if ys.shape[0] > n3 + 1:
        # onset proxy: z_j' = sqrt(delta_j+ / L), whose local error is O(h^1.5) at a contact onset, so the
        # step controller resolves every onset (the kink of F ~ delta^{3/2}) to the tolerance
        d = stack.overlaps(stack.split(y)[0]) / scale[0]
        parts.append(jnp.sqrt(jnp.where(d > 0, d, 0.0) + 1e-300) * stack.interface_mask())
    return jnp.concatenate(parts + [jnp.zeros(1, dy.dtype)])


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


def _cascade_over(t, ys, args, x, v, d, dd, closed):
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
    settled (without gravity: its internal energy `E_int`, kinetic in its centre-of-mass frame plus its
    inner contacts' elastic energy, is below `_SETTLED` of its drop energy `M_k V^2/2`; under gravity
    the group falls back to the ground, a rebound, so its masses never get final velocities) and can
    never push mass `k+1` again: mass `k+1` moves away from the group's centre of mass faster than any
    velocity `E_int` could give the group's top mass, `sqrt(2 E_int (M_k - m_k)/(M_k m_k))`. Every mass above the group then
    has its final launch; the masses of a settled or bound group report their velocities at the end of
    the cascade (without gravity within `sqrt(_SETTLED) V` of any later value).

    `args = (stack, scale, T, v0s)`, `v0s` the scaled initial velocities (contact has happened once a
    velocity departs from free flight); `x`, `v` (SI), the overlaps `d`, their rates `dd` and the closed
    contacts `closed` of the state `ys`, which the caller (`_Contacts.update`) has at hand."""
    stack, scale, T, v0s = args
    n = stack.n
    mask = stack.interface_mask()
    free_fall = v0s - stack.gravity * T * t / scale[n]
    touched = jnp.any(jnp.abs(ys[n : 2 * n] - free_fall) > _TOUCHED)
    # per interface: open and not approaching, or quiet (its relative kinetic and elastic energy below
    # `_QUIET` of its drop energy: a clump of masses moving as one body), or absent
    mu, m, pot = stack.effective_masses(), stack.masses, stack.potentials(d)
    touching = d > -jnp.sqrt(_QUIET) * scale[0]  # in contact, or within 1e-6 of the length scale
    quiet = touching & (0.5 * mu * dd**2 + pot <= _QUIET * 0.5 * mu * scale[n] ** 2)
    # Between two free masses (and mass 1 and the ground) an approach slower than sqrt(_QUIET) V is
    # round-off dust; the contact just above a group bound to the ground must not approach at all
    # (its lower mass is held, so a mass falling onto it speeds up: that landing is still to come).
    dust = jnp.sqrt(_QUIET) * scale[n]
    apart = (~closed & (dd <= dust)) | quiet | ~mask
    strict = (~closed & (dd <= 0)) | quiet | ~mask
    # tail[k], k = 0..n: every interface j >= k + 1 is apart (vacuous for k >= n - 1)
    tail = jnp.concatenate([jnp.flip(jnp.cumprod(jnp.flip(apart[1:]))) > 0, jnp.ones(2, bool)])
    # A free group, masses 1..k (k = 1..n-1) off the ground: its internal energy (kinetic in its centre-of-
    # mass frame plus its inner contacts' elastic energy) bounds how fast its top mass k can ever move
    # relative to the group's centre of mass (gravity is common: the centre of mass frame is free fall);
    # when mass k+1 already moves away faster than that, the group can never push it again.
    M, P = jnp.cumsum(m), jnp.cumsum(m * v)
    inner = jnp.concatenate([jnp.zeros(1), jnp.cumsum(pot[1:])])  # interfaces 1..k-1
    e_int = jnp.maximum(jnp.cumsum(0.5 * m * v**2) - 0.5 * P**2 / M + inner, 0.0)
    reach = jnp.sqrt(2.0 * e_int * (M - m) / (M * m))
    # its internal motion is negligible; or gravity acts, so the group falls back to the ground anyway:
    # its landing is a rebound, and its masses' velocities never become final
    settled = (e_int <= _SETTLED * 0.5 * M * scale[n] ** 2) | (stack.gravity > 0)
    escapes = (~closed[1:] & settled[:-1] & (v[1:] - (P / M)[:-1] >= reach[:-1])) & tail[1:n]  # k = 1..n-1
    free = tail[0] | jnp.any(escapes)
    if not stack.ground:
        return touched & free
    # above[k], k = 0..n: the masses above mass k fly apart (k >= 1: interface k strictly)
    above = tail & jnp.concatenate([jnp.ones(1, bool), strict[1:], jnp.ones(1, bool)])
    mech = m * (0.5 * v**2 + stack.gravity * x)
    energy = jnp.cumsum(mech) + jnp.cumsum(pot)  # masses 1..k and their contacts, k = 1..n
    bound = jnp.any((energy < 0) & above[1:])
    return touched & ((apart[0] & free) | bound)


def _cascade_complete(t, ys, args, **kwargs):
    """diffrax event: the cascade-over flag that `_Tracked` wrote into the state's last entry (ends the
    solve at the first accepted step where `_cascade_over` holds)."""
    return ys[-1] > 0.5


class _Contacts(eqx.Module):
    """Per-interface bookkeeping of the accepted steps, carried in the solver state (`_Tracked`), so
    that launch velocities and the energy audit need no step history (a history of `max_steps` rows is
    the dominant cost of a vmapped solve, where every step selects over the whole buffer).

    `rows (n, 6)`: per interface, the latest accepted point in contact (scaled time, -1 if never) and the
    first accepted point after it (scaled time, SI overlap, overlap rate, and the velocities of the lower
    and upper body, 0 for the ground); `now (n,)`: in contact at the latest point; `cascade (n + 5,)`:
    `[over, rebounds, t_c, top_done, v_top, v_c...]`: whether the first cascade is over (`_cascade_over` held
    at an accepted point; `rows` and `now` are then frozen), whether any contact closed after that, its
    scaled time `t_c`, whether the top mass has passed the apex of its flight after its last push (the
    top interface is then frozen: a later landing is a rebound) and its velocity at the latest point
    (scaled, to see it change sign), and the scaled velocities at `t_c`; `energy`: the
    energy at `t0` and the largest `|E - E(t0)|` so far (J), when audited. Packed into few arrays: each
    array is a separate operation in every step of the loop.
    """

    rows: Array
    now: Array
    cascade: Array
    energy: tuple[Array, Array] | None

    @staticmethod
    def update(c: _Contacts | None, t, ys, args, audit: bool) -> _Contacts:
        stack, scale = args[:2]
        n = stack.n
        y = ys[: scale.shape[0]] * scale
        x, v, _ = stack.split(y)
        d, dd = stack.overlaps(x), stack.overlap_rates(v)
        active = stack.in_contact(d, dd) & stack.interface_mask()
        e = stack.total_energy(y) if audit else None
        v_top = ys[2 * n - 1]
        if c is None:
            c = _Contacts(jnp.broadcast_to(jnp.asarray([-1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), d.shape + (6,)),
                          active & False, jnp.concatenate([jnp.zeros(4), v_top[None], ys[n : 2 * n]]),
                          None if e is None else (e, 0.0 * e))
        was_over, top_done = c.cascade[0] > 0, c.cascade[3] > 0
        frozen = was_over | ((jnp.arange(n) == n - 1) & top_done)
        left = c.now & ~active
        t = jnp.broadcast_to(t, d.shape).astype(d.dtype)
        v_lo = jnp.concatenate([jnp.zeros(1, v.dtype), v[:-1]])
        rows = jnp.where(jnp.stack([active] + [left] * 5, axis=-1) & ~frozen[:, None],
                         jnp.stack([t, t, d, dd, v_lo, v], axis=-1), c.rows)
        now = jnp.where(frozen, c.now, active)
        over = _cascade_over(t[0], ys, args, x, v, d, dd, active) & ~was_over
        # the top mass's apex: free, pushed before, its velocity turned from up to down
        apex = ~active[n - 1] & (rows[n - 1, 0] >= 0) & (c.cascade[4] > 0) & (v_top <= 0)
        rebound = (c.cascade[1] > 0) | jnp.any(frozen & active & ~c.now)  # closes after it was open
        head = jnp.stack([(was_over | over), rebound, jnp.where(over, t[0], c.cascade[2]),
                          top_done | apex | over, v_top]).astype(d.dtype)
        cascade = jnp.concatenate([head, jnp.where(over, ys[n : 2 * n], c.cascade[5:])])
        if e is not None:  # elementwise, not `.at[].max`: a scatter is a slow unfused operation in the loop
            e = (c.energy[0], jnp.maximum(c.energy[1], jnp.abs(e - c.energy[0])))
        return _Contacts(rows, now, cascade, e)


class _Tracked(dfx.AbstractWrappedSolver):
    """Wraps a diffrax solver and updates `_Contacts` with every step's end point. diffrax keeps the
    solver state of accepted steps only (`_integrate.py`: `solver_state = keep(new, old)`), so the
    bookkeeping sees exactly the accepted points, as a saved step history would."""

    solver: dfx.AbstractSolver
    audit: bool = eqx.field(static=True)

    @classmethod
    def around(cls, solver: dfx.AbstractSolver, adjoint: dfx.AbstractAdjoint, audit: bool) -> _Tracked:
        # diffrax's ForwardMode and DirectAdjoint set `scan_kind` of a Runge–Kutta solver left at None
        # ("lax", "bounded") by `eqx.tree_at`, which cannot reach through the wrapper: do it here.
        # (RecursiveCheckpointAdjoint leaves it None: the stages' loop is then "checkpointed", faster.)
        kinds = {dfx.ForwardMode: "lax", dfx.DirectAdjoint: "bounded"}
        kind = next((k for cls_, k in kinds.items() if isinstance(adjoint, cls_)), None)
        if kind is not None and getattr(solver, "scan_kind", "") is None:
            solver = eqx.tree_at(lambda s: s.scan_kind, solver, kind, is_leaf=lambda x: x is None)
        return cls(solver, audit)

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
        return self.solver.init(terms, t0, t1, y0, args), _Contacts.update(None, t0, y0, args, self.audit)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        inner, contacts = solver_state
        y1, y_error, dense_info, inner, result = self.solver.step(terms, t0, t1, y0, args, inner, made_jump)
        contacts = _Contacts.update(contacts, t1, y1, args, self.audit)
        # the cascade-over flag, read by the stopping event (`_scaled_field`); its derivative is zero, so
        # its error estimate is zero already
        y1 = y1.at[-1].set(contacts.cascade[0])
        return y1, y_error, dense_info, (inner, contacts), result

    def func(self, terms, t0, y0, args):
        return self.solver.func(terms, t0, y0, args)


def _end_of_contacts(stack: Stack, c: _Contacts, time_scale, t_final):
    """Per interface: the time its last contact ended (see module docstring), NaN if never in contact,
    `t_final` if still in contact at the end. Differentiable through a final Newton step."""
    n = stack.n
    cols = jnp.arange(n)
    ever = c.rows[:, 0] >= 0
    ended = ever & ~c.now
    t_k = jnp.where(ended, c.rows[:, 0] * time_scale, 0.0)
    t_r = jnp.where(ended, c.rows[:, 1] * time_scale, 0.0)
    d_r, dd_r = jnp.where(ended, c.rows[:, 2], 0.0), jnp.where(ended, c.rows[:, 3], 0.0)
    curv = jnp.where((cols == 0) & stack.ground, stack.gravity, 0.0)  # ground: delta_0 = -x_1 is a parabola
    lo0 = jnp.where(ended, t_k - t_r, -1.0)

    def sep(s, d_r, dd_r, curv):
        return stack.separation_function(d_r + dd_r * s + 0.5 * curv * s**2, dd_r + curv * s)

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
    rec_v = jnp.where(use_above, c.rows[jc, 4], c.rows[jc, 5])
    t_r = c.rows[jc, 1] * time_scale
    pushed_now = c.now[jc]
    v_launch = jnp.where(pushed_now, v_final, rec_v + stack.gravity * (t_r - t_end))
    return t_end, jnp.where(jnp.isnan(t_end), jnp.nan, v_launch)


def _derived(stack: Stack, y):
    """Physical quantities of SI states `(..., 3n)`."""
    x, v, diss = stack.split(y)
    d, dd = stack.overlaps(x), stack.overlap_rates(v)
    f = stack.forces(d, dd)
    return dict(
        positions=x, velocities=v, accelerations=stack.accelerations(f), overlaps=d,
        overlap_rates=dd, forces=f, dissipated=diss, energy=stack.total_energy(y),
    )


def _setup(stack: Stack, state: State, t_max, cfg: _Config):
    """Scales, the scaled initial state and the scaled end time of a solve."""
    n = stack.n
    sc = _scales(stack, state)
    scale = sc.vector(n)
    y0 = state.flat()
    t1 = jnp.where(jnp.isnan(t_max), _default_t_max(stack, state, sc), t_max)
    proxies = jnp.zeros(n if cfg.tolerances.resolve_onsets else 0)
    y0s = jnp.concatenate([y0 / scale, proxies, jnp.zeros(1)])  # `_scaled_field`: [x v D | z | over]
    return sc, scale, y0s, t1 / sc.time


def _diffeqsolve(stack: Stack, y0s, t1s, scale, T, ts_s, cfg: _Config, history: bool, audit: bool):
    """The one call to `diffrax.diffeqsolve` (scaled state and time). Saves, in `sol.ys`/`sol.ts` in
    this order: the accepted steps with `t0` (if `history`), the times `ts_s` (if given), `t1`."""
    subs = []
    if history:
        subs.append(dfx.SubSaveAt(t0=True, steps=True))
    if ts_s is not None:
        subs.append(dfx.SubSaveAt(ts=ts_s))
    subs.append(dfx.SubSaveAt(t1=True))
    return dfx.diffeqsolve(
        dfx.ODETerm(_scaled_field),
        _Tracked.around(cfg.solver, cfg.adjoint, audit=audit),
        t0=0.0,
        t1=t1s,
        dt0=cfg.tolerances.first_step,
        y0=y0s,
        args=(stack, scale, T, y0s[stack.n : 2 * stack.n]),
        saveat=dfx.SaveAt(subs=subs, solver_state=True),
        stepsize_controller=cfg.tolerances.controller(),
        event=dfx.Event(_cascade_complete) if cfg.until == "cascade" else None,
        max_steps=cfg.max_steps,
        adjoint=cfg.adjoint,
        throw=False,
    )


def _core(sol) -> dict:
    """What every solve reports: final scaled time and state, the contacts' bookkeeping, status, steps.

    The status (`hertz_chain.status.Status`): the event (the cascade is over) or, with `until="t_max"`,
    an accepted point where it was over: complete (with rebounds if a contact closed after it); else
    `t_max` or `max_steps` first: incomplete, or no contact if nothing ever touched; a non-finite state
    is checked in `_outputs`."""
    c = sol.solver_state[1]
    over, rebounds = c.cascade[0] > 0, c.cascade[1] > 0
    touched = jnp.any(c.rows[:, 0] >= 0)
    done = jnp.where(rebounds, Status.COMPLETE_WITH_REBOUNDS, Status.COMPLETE)
    status = jnp.where(
        (sol.result == dfx.RESULTS.event_occurred) | over, done,
        jnp.where(sol.result == dfx.RESULTS.successful,
                  jnp.where(touched, Status.INCOMPLETE_T_MAX, Status.NO_CONTACT),
                  jnp.where(sol.result == dfx.RESULTS.max_steps_reached, Status.INCOMPLETE_MAX_STEPS,
                            Status.FAILED)),
    )
    return dict(t_fin=sol.ts[-1][-1], y_fin=sol.ys[-1][-1], contacts=c, status=status,
                num_steps=sol.stats["num_steps"], num_accepted_steps=sol.stats["num_accepted_steps"],
                num_rejected_steps=sol.stats["num_rejected_steps"])


def _outputs(stack: Stack, sc: Scales, scale, core: dict, until: str = "cascade") -> dict:
    """Launch data (in SI) from a solve's `_core` (`_end_of_contacts`, `_launch`). A mass still pushed
    when the cascade ended (mass 1 resting on the ground) is given its velocity then: the final state
    of a solve stopped by the event (`until="cascade"`; it carries the reverse-mode cotangent), the
    velocities kept in `_Contacts.cascade` otherwise."""
    n, n3 = stack.n, 3 * stack.n
    t_fin = core["t_fin"] * sc.time
    y_fin = core["y_fin"][:n3] * scale
    v_fin = stack.split(y_fin)[1]
    c = core["contacts"]
    over = c.cascade[0] > 0
    t_c, v_c = t_fin, v_fin
    if until != "cascade":
        t_c = jnp.where(over, c.cascade[2] * sc.time, t_fin)
        v_c = jnp.where(over, c.cascade[5:] * scale[n : 2 * n], v_fin)
    t_end_if = _end_of_contacts(stack, c, sc.time, t_c)
    t_end, v_launch = _launch(stack, c, sc.time, t_end_if, t_c, v_c)
    status = core["status"]
    status = jnp.where(jnp.all(jnp.isfinite(y_fin)) | (status == Status.INCOMPLETE_MAX_STEPS), status,
                       Status.FAILED)
    return dict(
        status=status,
        t_final=t_fin,
        cascade_end_time=jnp.where(over, c.cascade[2] * sc.time, jnp.nan),
        launch_velocities=v_launch,
        launch_times=t_end,
        contact_end_times=t_end_if,
        final_velocities=v_fin,
        num_steps=core["num_steps"],
        num_accepted_steps=core["num_accepted_steps"],
        num_rejected_steps=core["num_rejected_steps"],
    )


def _solve_impl(stack: Stack, state: State, ts, t_max, cfg: _Config, full: bool = True):
    n3 = 3 * stack.n
    sc, scale, y0s, t1s = _setup(stack, state, t_max, cfg)
    sol = _diffeqsolve(stack, y0s, t1s, scale, sc.time, None if ts is None else ts / sc.time, cfg,
                       history=cfg.save_steps, audit=full and not cfg.save_steps)
    contacts = sol.solver_state[1]
    out = _outputs(stack, sc, scale, _core(sol), cfg.until)
    if not full:
        return out
    out["scales"] = sc
    if cfg.save_steps:  # derived quantities and the energy audit: `_history`, on the rows actually used
        out["history"] = (sol.ys[0][:, :n3], sol.ts[0])
    else:
        out["energy_error"] = contacts.energy[1] / sc.energy
    if ts is not None:
        grid = _derived(stack, sol.ys[int(cfg.save_steps)][:, :n3] * scale)
        grid["t"] = ts
        out["grid"] = grid
    return out


def _solve_plain(stack: Stack, state: State, ts, t_max, cfg: _Config) -> dict:
    """`_solve_impl` with `Scales` as a dict: only dicts, tuples and arrays, which `jax.export` can keep."""
    out = dict(_solve_impl(stack, state, ts, t_max, cfg))
    out["scales"] = {f.name: getattr(out["scales"], f.name) for f in dataclasses.fields(Scales)}
    return out


# a traced solve is kept on disk where that is exact (`_export`: under EQX_ON_ERROR=nan, the CLI's setting)
_solve = cached_jit(_solve_plain, eqx.filter_jit(_solve_plain), "simulate._solve")


def _history_impl(stack: Stack, history, sc: Scales, rows: int):
    """Physical quantities and the energy audit of the first `rows` points of a saved step history
    (scaled; points after the solve's end are inf)."""
    ys, ts = history
    steps = _derived(stack, ys[:rows] * sc.vector(stack.n))
    steps["t"] = ts[:rows] * sc.time
    err = jnp.where(jnp.isfinite(steps["t"]), jnp.abs(steps["energy"] - steps["energy"][0]), 0.0)
    return steps, jnp.max(err) / sc.energy


# `rows` (a Python int) is static: one compilation per bucket of `_history_rows`
_history = eqx.filter_jit(_history_impl)
_history_batch = eqx.filter_jit(eqx.filter_vmap(_history_impl, in_axes=(eqx.if_array(0), 0, 0, None)))


def _history_rows(points: int, buffer: int) -> int:
    """Rows of a step history to post-process: the `points` saved (accepted steps + 1) rounded up to a
    power of two (at least 64), at most the buffer's `max_steps + 1`. Deriving forces, energies, ... on
    the whole buffer made `simulate` cost grow with `max_steps` rather than with the steps taken
    (benchmarks, 10 masses, ~1400 steps: 21 ms at the default 65,536; the solve itself is 7 ms); the
    power of two bounds the number of compilations (about a dozen lengths) while wasting at most half."""
    return int(min(buffer, max(64, 1 << max(points - 1, 0).bit_length())))


def _post_history(out: dict, stack: Stack, batched: bool) -> dict:
    """Replace `out["history"]` by `out["steps"]` and `out["energy_error"]` (see `_history_rows`)."""
    if "history" not in out:
        return out
    out = dict(out)
    history = out.pop("history")
    rows = _history_rows(int(np.max(np.asarray(out["num_accepted_steps"]))) + 1, history[1].shape[-1])
    fn = _history_batch if batched else _history
    out["steps"], out["energy_error"] = fn(stack, history, out["scales"], rows)
    return out


def _solve_full(stack, state, ts, t_max, cfg):
    return _solve_impl(stack, state, ts, t_max, cfg)


_vmapped = eqx.filter_vmap(_solve_full, in_axes=(eqx.if_array(0), eqx.if_array(0), None, eqx.if_array(0), None))
_solve_batch = eqx.filter_jit(_vmapped)


@functools.cache
def _solve_sharded(ndev: int):
    """`_solve_batch` split over the first `ndev` local devices (`jax.shard_map`): every device runs the
    vmapped solve of its share of the designs, with its own loop, so a design waits only for the slowest
    design of its own share. On a CPU, `_config.expose_cpu_cores` makes every core a device."""
    mesh = jax.sharding.Mesh(np.asarray(jax.local_devices()[:ndev]), ("design",))
    split, same = jax.sharding.PartitionSpec("design"), jax.sharding.PartitionSpec()

    @eqx.filter_jit
    def run(stacks, states, ts, t_max, cfg):
        dyn, static = eqx.partition((stacks, states, t_max), eqx.is_array)
        shared, shared_static = eqx.partition((ts, cfg), eqx.is_array)

        def local(dyn, shared):
            s, x, tm = eqx.combine(dyn, static)
            ts_, cfg_ = eqx.combine(shared, shared_static)
            return _vmapped(s, x, ts_, tm, cfg_)

        return jax.shard_map(local, mesh=mesh, in_specs=(split, same), out_specs=split, check_vma=False)(dyn, shared)

    return run


# ==================================================================== results
@dataclasses.dataclass(frozen=True)
class Trajectory:
    """Samples of a solution (numpy, SI units). Shapes: `t (T,)`; mass arrays `(T, n)`; interface
    arrays `(T, n)` (entry 0 = ground; 0 without the ground).

    - `t` (s); `positions` (m), `velocities` (m/s), `accelerations` (m/s²) of the masses, upward;
    - `overlaps` (m, > 0 compression), `overlap_rates` (m/s, > 0 approaching), `forces` (N) and
      `dissipated` (J, cumulative) of the interfaces;
    - `energy` (J): kinetic + gravitational + elastic + dissipated, constant in an exact solution.
    """

    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    overlaps: np.ndarray
    overlap_rates: np.ndarray
    forces: np.ndarray
    dissipated: np.ndarray
    energy: np.ndarray

    @classmethod
    def _from(cls, d: dict, trim: bool) -> Trajectory:
        arrs = {k: np.asarray(v) for k, v in d.items()}
        if trim:
            keep = np.isfinite(arrs["t"])
            arrs = {k: v[keep] for k, v in arrs.items()}
        else:  # grid points after the solve stopped: NaN, not inf
            alive = np.isfinite(arrs["positions"]).all(axis=-1)
            arrs = {k: (v if k == "t" else np.where(alive.reshape(alive.shape + (1,) * (v.ndim - 1)), v, np.nan))
                    for k, v in arrs.items()}
        return cls(**{f.name: arrs[f.name] for f in dataclasses.fields(cls)})


@dataclasses.dataclass(frozen=True)
class Solution:
    """The result of `simulate` (numpy arrays, SI units).

    - `status`: a `Status` (`hertz_chain.status`: complete, complete with rebounds, incomplete, no
      contact, failed); `status_code` its integer. The launch data are valid when `ok`.
    - `cascade_end_time` (s): when the first cascade ended (`_cascade_over`), NaN if it did not.
    - `t_final` (s): when the solve stopped.
    - `launch_velocities` `(n,)` (m/s): the velocity of every mass when its last contact ended (NaN for
      a mass that was never in contact); `launch_times` `(n,)` (s): when that was.
    - `final_velocities` `(n,)` (m/s) at `t_final`; `contact_end_times` `(n,)` (s): end of the last
      contact of every interface.
    - `num_steps`, `num_accepted_steps`, `num_rejected_steps`: solver statistics.
    - `energy_error`: max over the steps of `|E(t) - E(0)| / E_scale` (the energy audit;
      `E_scale = sum(m) V^2/2`, the drop kinetic energy).
    - `steps`: `Trajectory` at the solver's steps (including t = 0; None for a design of
      `simulate_batch(..., save_steps=False)`); `grid`: `Trajectory` on the
      requested `ts` (NaN after `t_final`), or None.
    - `scales`: the `Scales` used; `stack`, `state`: the design and the initial state.
    """

    status: Status
    status_code: int
    t_final: float
    cascade_end_time: float
    launch_velocities: np.ndarray
    launch_times: np.ndarray
    final_velocities: np.ndarray
    contact_end_times: np.ndarray
    num_steps: int
    num_accepted_steps: int
    num_rejected_steps: int
    energy_error: float
    steps: Trajectory
    grid: Trajectory | None
    scales: Scales
    stack: Stack
    state: State

    @property
    def ok(self) -> bool:
        return self.status.ok

    @property
    def gain(self) -> float:
        """Velocity gain of the top mass, `V_n / v_ff` (paper Eq 19's `G_n`), `v_ff = V` scale."""
        return float(self.launch_velocities[-1] / self.scales.velocity)


@dataclasses.dataclass(frozen=True)
class BatchSolution:
    """The result of `simulate_batch`: every field of `Solution` with a leading design axis `B`.

    `status_code (B,)`, `ok (B,)`, `t_final`, `launch_velocities (B, n)`, ..., `steps`/`grid`
    (padded with NaN after each design's end; `steps` is None with `save_steps=False`). `design(i)` returns design `i` as a trimmed `Solution`.
    """

    status_code: np.ndarray
    t_final: np.ndarray
    cascade_end_time: np.ndarray
    launch_velocities: np.ndarray
    launch_times: np.ndarray
    final_velocities: np.ndarray
    contact_end_times: np.ndarray
    num_steps: np.ndarray
    num_accepted_steps: np.ndarray
    num_rejected_steps: np.ndarray
    energy_error: np.ndarray
    steps: dict
    grid: dict | None
    scales: Scales
    stack: Stack
    state: State

    @property
    def ok(self) -> np.ndarray:
        return (self.status_code == Status.COMPLETE) | (self.status_code == Status.COMPLETE_WITH_REBOUNDS)

    @property
    def status(self) -> list[Status]:
        return [Status(int(c)) for c in self.status_code]

    def __len__(self) -> int:
        return len(self.status_code)

    def design(self, i: int) -> Solution:
        pick = lambda tree: jax.tree.map(lambda a: a[i], tree)  # noqa: E731
        return _to_solution(
            {k: getattr(self, k)[i] for k in _SCALAR_KEYS} | dict(
                steps=None if self.steps is None else pick(self.steps),
                grid=None if self.grid is None else pick(self.grid),
                scales=pick(self.scales)),
            pick(self.stack), pick(self.state))


_SCALAR_KEYS = ("status_code", "t_final", "cascade_end_time", "launch_velocities", "launch_times", "final_velocities",
                "contact_end_times", "num_steps", "num_accepted_steps", "num_rejected_steps", "energy_error")


def _to_solution(out: dict, stack, state) -> Solution:
    code = int(out["status_code"])
    return Solution(
        status=Status(code), status_code=code, t_final=float(out["t_final"]),
        cascade_end_time=float(out["cascade_end_time"]),
        launch_velocities=np.asarray(out["launch_velocities"]),
        launch_times=np.asarray(out["launch_times"]),
        final_velocities=np.asarray(out["final_velocities"]),
        contact_end_times=np.asarray(out["contact_end_times"]),
        num_steps=int(out["num_steps"]), num_accepted_steps=int(out["num_accepted_steps"]),
        num_rejected_steps=int(out["num_rejected_steps"]), energy_error=float(out["energy_error"]),
        steps=None if out.get("steps") is None else Trajectory._from(out["steps"], trim=True),
        grid=None if out.get("grid") is None else Trajectory._from(out["grid"], trim=False),
        scales=out["scales"], stack=stack, state=state,
    )


# ==================================================================== entry points
def _prepare(stack, state, ts, t_max, solver, tolerances, max_steps, adjoint, save_steps=True, until="cascade"):
    if until not in UNTIL:
        raise ParameterError("until", until, "'cascade' (stop when the first cascade ends) or 't_max' (go on "
                             "to t_max and report later impacts as rebounds)")
    if until == "t_max" and t_max is None:
        raise ParameterError("t_max", None, "a time > 0 (s) with until='t_max'")
    if not isinstance(stack, Stack):
        raise ParameterError("stack", type(stack).__name__, "a hertz_chain.Stack")
    if not isinstance(state, State):
        raise ParameterError("state", type(state).__name__, "a hertz_chain.State (at_impact, dropped, resting)")
    if not isinstance(max_steps, (int, np.integer)) or max_steps < 1:
        raise ParameterError("max_steps", max_steps, "an integer >= 1")
    tolerances = tolerances or Tolerances()
    if not isinstance(tolerances, Tolerances):
        raise ParameterError("tolerances", tolerances, "a hertz_chain.Tolerances")
    if t_max is None:
        t_max = jnp.nan
    else:
        tm = np.asarray(t_max, dtype=float)
        if not np.all(np.isfinite(tm) & (tm > 0)):
            raise ParameterError("t_max", tm.tolist(), "finite and > 0 (s)")
        t_max = jnp.asarray(tm)
    if ts is not None:
        ts_np = np.asarray(ts, dtype=float)
        if ts_np.ndim != 1 or ts_np.size == 0 or not np.all(np.isfinite(ts_np)) or np.any(np.diff(ts_np) < 0) \
                or ts_np[0] < 0:
            raise ParameterError("ts", ts, "a non-empty, non-decreasing 1-D array of times >= 0 (s)")
        if not np.isnan(np.max(np.asarray(t_max))) and ts_np[-1] > np.min(np.asarray(t_max)):
            raise ParameterError("ts", f"last time {ts_np[-1]}", f"<= t_max = {t_max}")
        ts = jnp.asarray(ts_np)
    tolerances = eqx.tree_at(lambda t: (t.rtol, t.atol), tolerances,
                             (np.asarray(float(tolerances.rtol)), np.asarray(float(tolerances.atol))))
    cfg = _Config(make_solver(solver, tolerances), tolerances, int(max_steps),
                  _make_adjoint(adjoint, int(max_steps)), save_steps, until)
    return ts, t_max, cfg


def _describe(stack: Stack) -> str:
    m = np.asarray(stack.masses)
    laws = ", ".join(f"{type(law).__name__}@{list(idx)}" for law, idx in zip(stack.laws, stack.groups))
    return (f"n = {stack.n}, masses = {np.array2string(m, precision=4)} kg, laws = {laws}, "
            f"ground = {stack.ground}, g = {float(stack.gravity)} m/s²")


def simulate(
    stack: Stack,
    state: State,
    *,
    solver: str | dfx.AbstractSolver = "tsit5",
    tolerances: Tolerances | None = None,
    t_max: float | None = None,
    ts: ArrayLike | None = None,
    max_steps: int = 65_536,
    adjoint: str | dfx.AbstractAdjoint | None = None,
    throw: bool = True,
    until: str = "cascade",
) -> Solution:
    """Simulate one design from an initial state until its first cascade ends (or `t_max`).

    **Arguments:**

    - `stack`: the `Stack`; `state`: the initial `State` (`at_impact`, `dropped`, `resting`, or explicit).
    - `solver`: a name for `make_solver` or a diffrax solver (default Tsit5: see module docstring).
    - `tolerances`: `Tolerances` (default `rtol = atol = 1e-10` in scaled units).
    - `t_max`: time limit (s); default from the physics (`_default_t_max`: the fall to the ground, the
      falls through the gaps, the contact times and the time of flight), long enough for the cascade.
    - `until`: `"cascade"` (default) stops when the first cascade is over (`Solution.cascade_end_time`);
      `"t_max"` goes on to `t_max` (required then): later impacts (mass 1 falling back, masses landing
      again) are rebounds, `status` says so, and the launch velocities stay those of the first cascade.
    - `ts`: optional times (s) at which to also report the state (dense output).
    - `max_steps`: step budget (default 65,536: the paper's ten-mass MET stack dropped under gravity,
      whose lower masses settle on the ground after the cascade, takes about 22,000 steps to the default
      `t_max`; an unused step costs only memory, about 80 n bytes); `throw`: raise `SolverError` when the
      solver is in trouble (max steps before the cascade ended, non-finite state); otherwise, and with
      `throw=False`, read `Solution.status` (incomplete at `t_max`, no contact).

    **Returns** a `Solution`. Compiled once per structure (n, law types, ground, solver, options); the
    compiled solve is kept in JAX's compilation cache and, under `EQX_ON_ERROR=nan` (the command line's
    setting), the traced one too (`hertz_chain._export`), so a new process skips both.
    """
    ts, t_max, cfg = _prepare(stack, state, ts, t_max, solver, tolerances, max_steps, adjoint, until=until)
    if state.positions.shape != stack.masses.shape:
        raise ParameterError("state", state.positions.shape, f"positions of shape {stack.masses.shape}")
    out = _solve(stack, state, ts, t_max, cfg)
    out["scales"] = Scales(**out["scales"])
    out = _post_history(out, stack, batched=False)
    sol = _to_solution(out | {"status_code": out["status"]}, stack, state)
    if throw and sol.status in (Status.INCOMPLETE_MAX_STEPS, Status.FAILED):
        raise SolverError(f"{sol.status} at t = {sol.t_final:.6g} s after {sol.num_steps} steps for the design "
                          f"({_describe(stack)}); hint: {sol.status.hint(max_steps)}")
    return sol


def simulate_batch(
    stacks: Stack,
    states: State,
    *,
    solver: str | dfx.AbstractSolver = "tsit5",
    tolerances: Tolerances | None = None,
    t_max: float | ArrayLike | None = None,
    ts: ArrayLike | None = None,
    max_steps: int = 4096,
    save_steps: bool = True,
    until: str = "cascade",
) -> BatchSolution:
    """Simulate a batch of designs of one structure in one compiled, vmapped solve.

    `stacks` and `states` carry a leading design axis on every array leaf (build them with
    `stack_designs([...])` and `jax.vmap(at_impact)(...)`, or `jax.tree.map(jnp.stack, ...)`). `t_max`
    may be a scalar or one value per design. A design that fails is flagged in `status_code` and never
    aborts the batch (diffrax `throw=False`, results read per element).

    `save_steps=False` keeps no step history (`steps` is None; `design(i)` then cannot be analysed):
    the launch velocities, contact end times and the energy audit are tracked while solving in any case,
    so this is the throughput mode for design sweeps. With the history (default), under `vmap` every
    step updates the `max_steps`-long buffers of every design by a select, so the cost per step grows
    with `max_steps`: keep `max_steps` near what the designs need (default 4096; a design that needs more
    is flagged `"max_steps reached"`). With several JAX devices (every CPU core is one: module
    docstring, "Batches") the designs are split over them. Measured (benchmarks/results.md, 5 masses,
    1024 designs, 2 cores, run of 2026-11-23 11:02): 0.37 ms/design without the history, 0.85 ms with it
    at `max_steps = 1024`.
    """
    ts, t_max, cfg = _prepare(stacks, states, ts, t_max, solver, tolerances, max_steps, None, save_steps, until)
    if getattr(cfg.solver, "scan_kind", "") is None:
        # Runge–Kutta stages as a "bounded" loop: 15 % faster per design under vmap, but 50 % slower
        # for a single solve than diffrax's default (measured, Tsit5, 5 and 10 masses)
        cfg = eqx.tree_at(lambda c: c.solver.scan_kind, cfg, "bounded", is_leaf=lambda x: x is None)
    B = stacks.masses.shape[0] if stacks.masses.ndim == 2 else None
    if B is None or states.positions.shape != stacks.masses.shape:
        raise ParameterError("stacks/states", (stacks.masses.shape, states.positions.shape),
                             "batched designs: masses and positions of shape (B, n)")
    t_max = jnp.broadcast_to(jnp.asarray(t_max, dtype=float), (B,))
    ndev = jax.local_device_count()
    if ndev > 1 and B >= 2 * ndev:
        pad = -B % ndev  # repeat the last design so that every device gets the same share
        grow = lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], pad, axis=0)]) if pad else a  # noqa: E731
        batched = jax.tree.map(lambda a: grow(a) if eqx.is_array(a) else a, (stacks, states, t_max))
        out = _solve_sharded(ndev)(*batched[:2], ts, batched[2], cfg)
        out = jax.tree.map(lambda a: a[:B], out)
    else:
        out = _solve_batch(stacks, states, ts, t_max, cfg)
    out = _post_history(out, stacks, batched=True)
    np_ = lambda a: np.asarray(a)  # noqa: E731
    return BatchSolution(
        status_code=np_(out["status"]), t_final=np_(out["t_final"]),
        cascade_end_time=np_(out["cascade_end_time"]),
        launch_velocities=np_(out["launch_velocities"]), launch_times=np_(out["launch_times"]),
        final_velocities=np_(out["final_velocities"]), contact_end_times=np_(out["contact_end_times"]),
        num_steps=np_(out["num_steps"]), num_accepted_steps=np_(out["num_accepted_steps"]),
        num_rejected_steps=np_(out["num_rejected_steps"]), energy_error=np_(out["energy_error"]),
        steps=None if "steps" not in out else
        {k: np.where(np.isfinite(np_(v)), np_(v), np.nan) for k, v in out["steps"].items()},
        grid=None if "grid" not in out else {k: np_(v) for k, v in out["grid"].items()},
        scales=out["scales"], stack=stacks, state=states,
    )


# ==================================================================== reverse mode: replay the accepted steps
@eqx.filter_custom_vjp
def _replayed_solve(diff, t1s, scale, T, cfg: _Config) -> dict:
    """`_core` of the solve from `diff = (stack, y0s)`, differentiable in reverse mode by a discrete
    adjoint over the accepted steps (`_replay_bwd`). Undifferentiated, it is the lean solve."""
    stack, y0s = diff
    return _core(_diffeqsolve(stack, y0s, t1s, scale, T, None, cfg, history=False, audit=False))


@_replayed_solve.def_fwd
def _replay_fwd(perturbed, diff, t1s, scale, T, cfg: _Config):
    del perturbed
    stack, y0s = diff
    sol = _diffeqsolve(stack, y0s, t1s, scale, T, None, cfg, history=True, audit=False)
    core = _core(sol)
    # per interface: the history index of the point recorded in `_Contacts.rows` (the first accepted
    # point after its last contact), found by its time (the same float), and whether there is one
    c = core["contacts"]
    match = sol.ts[0][None, :] == c.rows[:, 1:2]
    idx, valid = jnp.argmax(match, axis=1), (c.rows[:, 0] >= 0) & ~c.now & jnp.any(match, axis=1)
    return core, (sol.ts[0], sol.ys[0], idx, valid)


@_replayed_solve.def_bwd
def _replay_bwd(residuals, g, perturbed, diff, t1s, scale, T, cfg: _Config):
    """Reverse sweep over the accepted steps `y_k = Phi(y_{k-1}; t_{k-1}, t_k, stack)`: with the step
    times frozen (as diffrax's controller does in reverse mode: it stops gradients through the step size),
    `lambda_{k-1} = (dPhi/dy)^T lambda_k + (cotangent of y_{k-1})` and `stack_bar += (dPhi/dstack)^T
    lambda_k`, each step's vector-Jacobian product by `jax.vjp` of the solver's own step. The outputs
    that depend on the state are the final state and, per interface, the overlap, its rate and the two
    bodies' velocities at the first
    accepted point after the last contact (`_Contacts.rows`); the step times carry no gradient."""
    del perturbed
    hist_t, hist_y, idx, valid = residuals
    stack, y0s = diff
    n3 = 3 * stack.n
    N = jnp.sum(jnp.isfinite(hist_t)) - 1  # accepted steps: rows 0..N of the history are finite
    ct_hist = jnp.zeros_like(hist_y)
    if g["y_fin"] is not None:
        ct_hist = ct_hist.at[N].add(g["y_fin"])
    rows_ct = g["contacts"].rows
    if rows_ct is not None:  # overlap, rate and velocities at the recorded point: linear in that state
        def at_rows(Y):
            x, v, _ = stack.split(Y[:, :n3] * scale)
            v_lo = jnp.concatenate([jnp.zeros(1, v.dtype), jnp.diagonal(v, offset=-1)])
            return (jnp.diagonal(stack.overlaps(x)), jnp.diagonal(stack.overlap_rates(v)), v_lo,
                    jnp.diagonal(v))

        _, vjp = jax.vjp(at_rows, hist_y[idx])
        (ct_Y,) = vjp((rows_ct[:, 2], rows_ct[:, 3], rows_ct[:, 4], rows_ct[:, 5]))
        ct_hist = ct_hist.at[idx].add(jnp.where(valid[:, None], ct_Y, 0.0))
    dyn, static = eqx.partition(stack, eqx.is_inexact_array)
    terms, solver = dfx.ODETerm(_scaled_field), cfg.solver

    def step(dyn, y, t0, t1):
        args = (eqx.combine(dyn, static), scale, T)
        return solver.step(terms, t0, t1, y, args, solver.init(terms, t0, t1, y, args), False)[0]

    # The onset proxies (`resolve_onsets`, entries 3n:) feed nothing back into the motion and no output
    # depends on them: replay the 3n physical equations only (the same arithmetic, component by component).
    ct_hist = ct_hist[:, :n3]

    def body(i, carry):
        lam, acc = carry
        k = N - i
        _, vjp = jax.vjp(lambda d, y: step(d, y, hist_t[k - 1], hist_t[k]), dyn, hist_y[k - 1, :n3])
        g_dyn, g_y = vjp(lam)
        return g_y + ct_hist[k - 1], jax.tree.map(jnp.add, acc, g_dyn)

    lam, acc = jax.lax.fori_loop(0, N, body, (ct_hist[N], jax.tree.map(jnp.zeros_like, dyn)))
    return acc, jnp.zeros_like(y0s).at[:n3].set(lam)


def _launch_impl(stack, state, t_max, cfg, replay: bool):
    if replay:
        sc, scale, y0s, t1s = _setup(stack, state, t_max, cfg)
        frozen = jax.lax.stop_gradient((t1s, scale, sc.time))  # the end time and the scales carry no gradient
        out = _outputs(stack, sc, scale, _replayed_solve((stack, y0s), *frozen, cfg))
    else:
        out = _solve_impl(stack, state, None, t_max, cfg, full=False)
    v = eqx.error_if(
        out["launch_velocities"], out["status"] > Status.COMPLETE_WITH_REBOUNDS,
        "hertz_chain.launch_velocity: the cascade did not end (t_max or max_steps reached, no contact, "
        "or a non-finite state); raise t_max or max_steps, or check the design",
    )
    return v


_launch_jit = eqx.filter_jit(_launch_impl)  # `replay` is a Python bool: static


def launch_velocity(
    stack: Stack,
    state: State,
    *,
    solver: str | dfx.AbstractSolver = "tsit5",
    tolerances: Tolerances | None = None,
    t_max: float | None = None,
    max_steps: int = 16_384,
    adjoint: str | dfx.AbstractAdjoint = "reverse",
) -> Array:
    """`(n,)` launch velocities (m/s) as a differentiable JAX function of the design.

    Use inside `jax.grad` (`adjoint="reverse"`) or `jax.jacfwd`/`jax.jvp` (`adjoint="forward"`), e.g.
    `jax.grad(lambda m: launch_velocity(Stack(m, law, gravity=0.0), at_impact(...))[-1])(masses)`.
    Tolerances default to `rtol = atol = 1e-11` with `resolve_onsets=True`, where gradients matched central
    finite differences to 3.5e-6 (module docstring). A failed solve raises an error at run time
    (`eqx.error_if`), never a silent NaN.

    `adjoint`: `"reverse"` (default; `jax.grad` by replaying the accepted steps, module docstring;
    reverse mode only), `"forward"` (`jax.jacfwd`, `jax.jvp`), or a diffrax adjoint, e.g.
    `diffrax.RecursiveCheckpointAdjoint()` for higher-order derivatives.

    Cost (benchmarks/results.md, 2 CPU cores): for the gradient with respect to all n masses, reverse
    mode costs 2.9x-3.9x one solve (Tsuji and Hertz, n = 5, 10: 5.7-17.3 ms; diffrax's own reverse mode
    4.3x-6.0x); forward mode (`jax.jacfwd`, `adjoint="forward"`, 4.8x-7.5x) grows with the number of
    parameters: prefer it for two or three. Reverse mode keeps the accepted states, `32 n` bytes per
    step of `max_steps`.
    """
    tolerances = tolerances or Tolerances(rtol=1e-11, atol=1e-11, resolve_onsets=True)
    replay = isinstance(adjoint, str) and adjoint == "reverse"
    _, t_max, cfg = _prepare(stack, state, None, t_max, solver, tolerances, max_steps, adjoint, save_steps=False)
    return _launch_jit(stack, state, t_max, cfg, replay)


# ==================================================================== one contact
@dataclasses.dataclass(frozen=True)
class Restitution:
    """One measured contact: restitution `e` (separation / approach speed, paper Eq 2), `contact_time`
    (s, until the force returns to zero), peak overlap `max_overlap` (m) and peak force `max_force` (N)."""

    e: float
    contact_time: float
    max_overlap: float
    max_force: float


def _quintic(t0, t1, y, dy, ddy):
    """Coefficients (in s = t - t0, highest first) of the quintic Hermite interpolant on [t0, t1]."""
    h = t1 - t0
    A = np.array([[0, 0, 0, 0, 0, 1], [0, 0, 0, 0, 1, 0], [0, 0, 0, 2, 0, 0],
                  [h**5, h**4, h**3, h**2, h, 1], [5 * h**4, 4 * h**3, 3 * h**2, 2 * h, 1, 0],
                  [20 * h**3, 12 * h**2, 6 * h, 2, 0, 0]], dtype=float)
    b = np.array([y[0], dy[0], ddy[0], y[1], dy[1], ddy[1]], dtype=float)
    return np.linalg.solve(A, b)


def _peak(t, fn_of_state, d, dd, ddd, i):
    """Maximum of `fn(delta(t), delta_dot(t))` near step `i`, along the quintic Hermite interpolant of
    `delta` (values, rates and accelerations at the steps: interpolation error O(h^6))."""
    best = -np.inf
    for a, b in ((i - 1, i), (i, i + 1)):
        if a < 0 or b >= len(t) or t[b] <= t[a]:
            continue
        c = _quintic(t[a], t[b], d[[a, b]], dd[[a, b]], ddd[[a, b]])
        s = np.linspace(0.0, t[b] - t[a], 2001)
        vals = np.asarray(fn_of_state(np.polyval(c, s), np.polyval(np.polyder(c), s)))
        k = int(np.argmax(vals))
        if 0 < k < len(s) - 1:  # vertex of the parabola through the three best samples
            y0, y1, y2 = vals[k - 1 : k + 2]
            den = y0 - 2 * y1 + y2
            best = max(best, y1 - 0.125 * (y2 - y0) ** 2 / den if den < 0 else y1)
        else:
            best = max(best, float(vals[k]))
    return float(best)


def restitution(
    law: AbstractContactLaw,
    impact_velocity: float,
    effective_mass: float,
    *,
    tolerances: Tolerances | None = None,
    solver: str | dfx.AbstractSolver = "tsit5",
) -> Restitution:
    """Simulate one contact and measure it: a mass `m*` hits an immovable body through `law` at
    `impact_velocity`, with `g = 0` (the relative two-body problem of the two colliding bodies).

    `e = V_out / v_in` (paper Eq 2); with the no-tension clamp the contact ends where the force
    returns to zero (possibly before the overlap does), without it (`law.clamp=False`, tension
    allowed) where the overlap does. Default tolerances `rtol = atol = 1e-11`.
    """
    v = float(impact_velocity)
    m = float(effective_mass)
    if not (np.isfinite(v) and v > 0):
        raise ParameterError("impact_velocity", impact_velocity, "finite and > 0 (m/s)")
    if not (np.isfinite(m) and m > 0):
        raise ParameterError("effective_mass", effective_mass, "finite and > 0 (kg)")
    stack = Stack(jnp.asarray([m]), [law], gravity=0.0, ground=True)
    sol = simulate(stack, at_impact(stack, v), solver=solver,
                   tolerances=tolerances or Tolerances(rtol=1e-11, atol=1e-11))
    st = sol.steps
    d, dd = st.overlaps[:, 0], st.overlap_rates[:, 0]
    ddd = -st.accelerations[:, 0]
    law0 = stack.law_of(0)
    d_max = _peak(st.t, lambda a, b: a, d, dd, ddd, int(np.argmax(d)))
    f_max = _peak(st.t, lambda a, b: law0.force(jnp.asarray(a), jnp.asarray(b)), d, dd, ddd,
                  int(np.argmax(st.forces[:, 0])))
    return Restitution(
        e=float(sol.launch_velocities[0] / v),
        contact_time=float(sol.contact_end_times[0]),
        max_overlap=d_max,
        max_force=f_max,
    )
