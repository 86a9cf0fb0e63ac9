"""Integrate a `Stack` with diffrax: adaptive, float64, batched and differentiable.

The public entry module of the simulator; with its private modules it is the only code that imports
diffrax: `_solver` (options, the unrolled Tsit5, `make_solver`), `_scaling` (units, the default
`t_max`), `_tracking` (the cascade's end and the contacts' bookkeeping inside the solver loop), `_solve`
(the compiled solve, batches, sharding), `_results` (`Solution`, `BatchSolution`, `Trajectory`) and
`_adjoint` (the replayed reverse mode). Entry points:

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

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from . import _config  # noqa: F401  (float64)
from ._adjoint import _replayed_solve
from ._results import BatchSolution, Solution, Trajectory, _to_solution
from ._scaling import Scales, _scales  # noqa: F401  (`_scales`: the benchmarks use it)
from ._solve import (  # noqa: F401  (`_scaled_field`: the benchmarks' scipy comparison uses it)
    _outputs,
    _post_history,
    _scaled_field,
    _setup,
    _solve,
    _solve_batch,
    _solve_impl,
    _solve_sharded,
)
from ._solver import UNTIL, Tolerances, UnrolledTsit5, _Config, _make_adjoint, make_solver
from .contact import AbstractContactLaw
from .errors import ParameterError, SolverError
from .stack import Stack, State, at_impact
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
