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
- `simulate_impact(law, impact_velocity, effective_mass) -> Restitution` — one contact, simulated and measured
  (`restitution`: its deprecated old name).

**Scaling.** The solver integrates a dimensionless state: time in units of `T`, the Hertz contact time
`t_c = 2.94328 delta_max / V` of the shortest contact; positions in units of `L = delta_max`, the peak
overlap of the stiffest contact (the root of `potential(delta) = m* V^2/2`, which for Hertz is
`(5 m* V^2/(4k))^{2/5}`); velocities in units of `V`, the drop speed (the largest initial speed, or
relative speed, in general; 1 m/s if everything is at rest); dissipated energies in units of
`E = sum(m) V^2/2`. So `rtol`/`atol` mean the same for every design (Hertz contact: Johnson, *Contact
Mechanics*, 1985, §11.1; docs/references.md, "Hertz single impact").

**Solvers.** `"tsit5"` (the default: `UnrolledTsit5`, Tsitouras' 5(4) pair with its stages written
out) or any row of `hertz_chain.registry.SOLVERS`, or a diffrax solver instance. The stack is not stiff
for Hertzian contact, so an explicit method is the right default.

**Default tolerances** `rtol = atol = 1e-10` in the scaled units, with `Tolerances.resolve_onsets`
(an auxiliary state that makes the step controller resolve every contact onset and every release of a
clamped contact); `launch_velocity`
uses `1e-11` for its gradients. **Step control:** diffrax's PID controller (`pcoeff = 0.4`,
`icoeff = 0.3`) with a largest step of half a contact time, so a free flight never steps over a contact.

**Stopping: the end of the first cascade.** The solve ends (a boolean `diffrax.Event`) at the first
accepted step where the cascade is over (`_cascade_over`): something has touched (a velocity departs from
free flight), every contact between masses is open and no neighbours approach, and mass 1 moves up from
the ground or rests on it; more generally, the lower masses `1..k` are bound to the ground (their energy
is below that of resting unloaded on it) or, as a settled group in flight, can never reach mass `k+1`
again, while everything above them flies apart. Under a common gravity the relative velocity of two
free masses is constant, so after that only a return to the ground can start anything new: a rebound.
With `until="t_max"` the solve goes on to `t_max`, the contact bookkeeping frozen at the cascade's end,
and later contacts make the status "complete with rebounds". The top mass's launch is frozen earlier if it passes the apex of its
flight before the cascade is over: its landing back on the stack is a rebound too. `t_max` defaults to a
limit from the physics (`_default_t_max`); reaching it, or `max_steps`, first leaves the run
"incomplete" (`hertz_chain.status.Status`).

**Launch velocities.** The launch velocity of a mass is its velocity when its last push of the first
cascade ended: the contact force of its last contact returned to zero (the one definition of a contact's
end, shared by `hertz_chain.episodes`, the pulses and `restitution`). The end `t_end` is located inside
the solver step where the force drops to zero by extrapolating the overlap back from the first accepted
point after it, `t_r`, as a parabola (its value, rate and second derivative there: exact while both bodies
fly freely, and accurate to O(h^3) when a neighbouring contact still pushes one of them) and solving
`G(t) = 0` for the separation function `G` of `Stack.separation_function`: bisection, then one Newton
step for the derivative (implicit function theorem), so the launch velocity is differentiable. The
velocity of each body at that accepted point is recorded, and `v_launch = v(t_r) + g (t_r - t_end)` (the
mass itself flies freely in between: exact). A straight-line extrapolation missed the end by up to ~5e-8 s
where the contact below still pushed, which moved a launch velocity under gravity by g times that
(`tests/test_launch_gravity.py`, "a launch while a neighbour still pushes"). The bracketing
points, the recorded velocities and the energy audit are kept while solving, in the solver state of a
wrapper around the diffrax solver (`_Tracked`; diffrax keeps the state of accepted steps only), so no
step history is needed: `launch_velocity` and `simulate_batch(..., save_steps=False)` save none, and
their cost per step does not grow with `max_steps`.

**Batches.** `simulate_batch` vmaps one compiled solve over the designs. Up to `CPU_PIECE` designs (all
of them on a GPU) are split over the JAX devices (`jax.shard_map`; on a CPU every core is made a device
before JAX starts, `HERTZ_CHAIN_CPU_DEVICES` overrides, a choice the user made first is kept); more, on a
CPU, are solved in pieces of `CPU_PIECE` by a thread per core (`_solve_pieces`).

**Gradients.** Discretise-then-optimise through the solver: `launch_velocity` differentiates the
discrete solve, forward (`adjoint="forward"`, `jax.jacfwd`) or reverse (`"reverse"`, `jax.grad`), both by
replaying the accepted steps (forward or backward), with contact onsets and the clamp's releases split
out of them so that the derivative sees how they move: docs/solver-defaults.md, "Onsets and releases in
the replay"; the two modes give the same discrete derivative. The derivative is as accurate as the
solve's tolerance, no better: within 2e-6 of central differences in the masses, stiffnesses and
restitutions for every law of the registry's five (Hertz, Hunt–Crossley, Tsuji, Kelvin–Voigt,
viscoelastic) with gaps or touching, at the default 1e-11; in the drop speed 3.6e-6 (reviews). In the
gaps less: 1.8e-4 relative measured (three Hertz masses, 2 mm gaps, gravity; without gravity 4e-3
absolute where the exact derivative is 0; viscoelastic 5-7e-5), converging as the tolerance is
tightened (1.4e-6 at 1e-13). Through Thornton's elastic–plastic law within 2e-5 (the replay also splits
each step where a contact turns from loading to unloading; 4e-5 over twelve designs 1e-6 apart, with and
without gravity: docs/contact-laws.md); in its gaps under gravity 5.7e-4 (a review, four masses). Derivatives through Jackson–Green (its
loading curve jumps where its fit starts: a factor 5,000 off with gaps under gravity) and through an
implicit solver (kvaerno5: 13-19 % off) are refused with `ParameterError`.

The reasoning behind these defaults, with the measurements that decided them, is the developer page
`docs/solver-defaults.md`.
"""

from __future__ import annotations

import dataclasses

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from . import _config  # float64; SOLVE_COMPILER_OPTIONS
from ._adjoint import _forward_replayed_solve, _replayed_solve
from ._export import _top_level, jit_per_options
from ._results import BatchSolution, Solution, Trajectory, _to_solution
from ._scaling import Scales, _scales  # noqa: F401  (`_scales`: the benchmarks use it)
from ._solve import (  # noqa: F401  (`_scaled_field`: the benchmarks' scipy comparison uses it)
    _launch_outputs,
    _post_history,
    _scaled_field,
    _setup,
    _solve,
    _solve_batch,
    _solve_impl,
    _solve_sharded,
    _vmapped,
)
from ._solver import UNTIL, Tolerances, UnrolledTsit5, _SolveConfig, _make_adjoint, make_solver
from .contact import AbstractContactLaw
from .errors import ParameterError, SolverError, check_positive
from .stack import Stack, State, at_impact
from .status import Status

__all__ = [
    "Tolerances",
    "Trajectory",
    "Solution",
    "BatchSolution",
    "Restitution",
    "UnrolledTsit5",
    "simulate",
    "simulate_batch",
    "launch_velocity",
    "prepare_launch",
    "restitution",
    "simulate_impact",
]


# ==================================================================== entry points
def _not_traced(fn: str, stack, state) -> None:
    """`ParameterError` where `stack` or `state` holds a JAX tracer: `simulate` and `simulate_batch` run on
    the host and return NumPy results, so they cannot be traced (`jax.jit`, `jax.grad`, `jax.vmap`)."""
    if any(isinstance(a, jax.core.Tracer) for a in jax.tree.leaves((stack, state))):
        raise ParameterError("stack/state", "a traced value", f"concrete arrays: {fn} runs on the host and returns "
                             "NumPy results; under jax.jit/grad/vmap use launch_velocity (differentiable) or "
                             "prepare_launch's function")


def _check_one_design(stack) -> None:
    """`ParameterError` for a batch of designs (`stack_designs`) given where one design is solved."""
    if isinstance(stack, Stack) and len(_shape(stack.masses)) != 1:
        raise ParameterError("stack", f"a batch of designs (masses of shape {_shape(stack.masses)})",
                             "one design (masses of shape (n,)); solve a batch with simulate_batch, or "
                             "jax.vmap over launch_velocity")


def _check_state_shape(stack: Stack, state: State) -> None:
    """`ParameterError` unless the state's positions and velocities have the masses' shape."""
    if np.shape(state.positions) != np.shape(stack.masses) or np.shape(state.velocities) != np.shape(stack.masses):
        raise ParameterError("state", f"positions {np.shape(state.positions)}, velocities {np.shape(state.velocities)}",
                             f"positions and velocities of the masses' shape {np.shape(stack.masses)}")


def _prepare(stack, state, ts, t_max, solver, tolerances, max_steps, adjoint, save_steps=True, until="cascade"):
    if until not in UNTIL:
        raise ParameterError("until", until, "'cascade' (stop when the first cascade ends), 'launch' (stop when "
                             "the top mass's launch is final) or 't_max' (go on "
                             "to t_max and report later impacts as rebounds)")
    if until == "t_max" and t_max is None:
        raise ParameterError("t_max", None, "a time > 0 (s) with until='t_max'")
    if not isinstance(stack, Stack):
        raise ParameterError("stack", type(stack).__name__, "a hertz_chain.Stack")
    if not isinstance(state, State):
        raise ParameterError("state", type(state).__name__, "a hertz_chain.State (at_impact, dropped, resting)")
    _check_state_shape(stack, state)
    if until != "t_max" and (stack.wall or (not isinstance(stack.end_force, jax.core.Tracer) and stack.held)):
        raise ParameterError("until", until, "'t_max' (with a t_max) for a chain held by an end force or a wall: "
                             "it never flies apart, so no cascade ends")
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or max_steps < 1:
        raise ParameterError("max_steps", max_steps, "an integer >= 1")
    tolerances = tolerances or Tolerances()
    if not isinstance(tolerances, Tolerances):
        raise ParameterError("tolerances", tolerances, "a hertz_chain.Tolerances")
    if t_max is None:
        t_max = jnp.nan
    else:
        try:
            tm = np.asarray(t_max, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError("t_max", t_max, "a time > 0 (s)") from None
        batch = np.ndim(stack.masses) == 2
        if tm.ndim > int(batch) or (tm.ndim == 1 and tm.shape[0] != np.shape(stack.masses)[0]):
            raise ParameterError("t_max", f"shape {tm.shape}", f"one time, or one per design ({np.shape(stack.masses)[0]},)"
                                 if batch else "one time (s)")
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
    return ts, t_max, _config_for(solver, tolerances, int(max_steps), adjoint, save_steps, until)


_CONFIGS: dict = {}  # the solve configurations made, by their options (a repeated call builds none: ~0.1 ms)


def _config_for(solver, tolerances, max_steps, adjoint, save_steps, until) -> _SolveConfig:
    """The `_SolveConfig` of these (checked) options, made once per distinct set of hashable options (and
    made again when the registry row of a solver name has been replaced since)."""
    from .registry import SOLVERS

    row = SOLVERS.get(str(solver).lower()) if isinstance(solver, str) else None
    try:
        key = (solver, id(row), tolerances, max_steps, adjoint, bool(save_steps), until)
        hash(key)
    except TypeError:  # a solver, adjoint or tolerance that cannot be hashed: made afresh
        key = None
    if key is not None and key in _CONFIGS and _CONFIGS[key][0] is row:
        return _CONFIGS[key][1]
    tol = eqx.tree_at(lambda t: (t.rtol, t.atol), tolerances,
                      (np.asarray(float(tolerances.rtol)), np.asarray(float(tolerances.atol))))
    cfg = _SolveConfig(make_solver(solver, tol), tol, max_steps, _make_adjoint(adjoint, max_steps), save_steps, until)
    if key is not None:
        if len(_CONFIGS) >= 256:
            _CONFIGS.pop(next(iter(_CONFIGS)))
        _CONFIGS[key] = (row, cfg)  # the row kept alive: its id cannot be reused while the entry lives
    return cfg


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
      `"launch"` stops as soon as the top mass's launch is final: as `"cascade"`, or earlier without
      gravity once no motion of the masses below can reach the top mass (`_tracking._top_final`; a
      gapped stack without gravity can go on colliding below for seconds). The top's launch velocity is
      then exact and `complete` refers to it; the lower masses' velocities are those at the stop.
    - `ts`: optional times (s) at which to also report the state (dense output).
    - `max_steps`: step budget (default 65,536: the paper's ten-mass MET stack dropped under gravity,
      whose lower masses settle on the ground after the cascade, takes about 22,000 steps to the default
      `t_max`; an unused step costs only memory, about 80 n bytes); `throw`: raise `SolverError` when the
      solver is in trouble (max steps before the cascade ended, non-finite state); otherwise, and with
      `throw=False`, read `Solution.status` (incomplete at `t_max`, no contact).

    **Returns** a `Solution`. Compiled once per structure (n, law types, ground, solver, options); the
    compiled solve is kept in JAX's compilation cache and the traced one too (`hertz_chain._export`, under
    equinox's `EQX_ON_ERROR=raise` or `nan`), so a new process skips both.
    """
    _not_traced("simulate", stack, state)
    _check_one_design(stack)
    ts, t_max, cfg = _prepare(stack, state, ts, t_max, solver, tolerances, max_steps, adjoint, until=until)
    try:
        out = _solve(stack, state, ts, t_max, cfg)
    except eqx.EquinoxRuntimeError as e:  # diffrax's check of the times, against the default t_max
        if ts is None or "saveat.ts must lie between" not in str(e):
            raise
        sc, _, _, t1s = _setup(stack, state, t_max, cfg)
        t_used = float(t1s * sc.time)
        raise ParameterError("ts", f"last time {float(ts[-1]):g} s", f"times up to t_max = {t_used:.6g} s (the "
                             "default from the physics; give t_max to go further)") from None
    out["scales"] = Scales(**out["scales"])
    out = _post_history(out, stack, batched=False)
    sol = _to_solution(out | {"status_code": out["status"]}, stack, state, until)
    if throw and sol.status in (Status.INCOMPLETE_MAX_STEPS, Status.FAILED):
        raise SolverError(f"{sol.status} at t = {sol.t_final:.6g} s after {sol.num_steps} steps for the design "
                          f"({_describe(stack)}); hint: {sol.status.hint(max_steps).replace('solver.', '')}")  # Python's words
    return sol


#: On a CPU, `simulate_batch` solves more designs than this in pieces of this many, each piece one vmapped
#: solve, a thread per core (`_solve_pieces`): a vmapped loop runs until its slowest design ends and works
#: on all of them every step, so smaller pieces waste less on the designs that ended, and their arrays
#: stay in the caches (measured 2026-11-25 on 2 cores: 128 per core fastest; 2,048 five-mass sweep designs
#: 1.71 s against 2.07 s in one call, gapped; 64 slower again, and again on 2026-11-27 with the threads:
#: 1,104-1,179 against 1,177-1,188 sweep designs/s). A GPU takes the batch whole.
CPU_PIECE = 128


def _solve_pieces(stacks, states, ts, t_max, cfg, workers: int) -> dict:
    """The designs in pieces of `CPU_PIECE` (all but a lone piece of fewer padded by repeating their last
    design), taken in the order of their regime number (`_regime_numbers`: designs whose cascades take
    alike many steps share a piece, so fewer lanes wait for a piece's slowest design), each piece one
    vmapped solve, run by `workers` threads that each take the next piece as they finish. The solve
    releases Python's lock and a CPU computation runs on its calling thread
    (`_config.run_cpu_computations_inline`; with JAX's asynchronous CPU dispatch too), so one compiled
    program on the default device keeps every core busy (measured: 2,048 designs on 2 cores as fast as
    one thread per device, which compiled the program once per device: +3 s and +0.3 GB on a cold
    cache). A design's piece and companions do not depend on the number of workers, so neither do the
    results (a sweep's Dask workers, one core each, give a local run's numbers). The slicing is on the
    host, in NumPy (JAX would dispatch one operation per array and piece: ~3 % of a sweep's time).
    Returns the outputs as NumPy arrays, in the order given."""
    import concurrent.futures
    import threading

    B = t_max.shape[0]
    size = CPU_PIECE if B > CPU_PIECE else B
    order = np.argsort(np.asarray(_regime_numbers(stacks, states)), kind="stable") if B > size else np.arange(B)
    sorted_ = jax.tree.map(lambda a: np.asarray(a)[order] if eqx.is_array(a) else a, (stacks, states, t_max))
    starts = list(range(0, B, size))
    todo, lock, stop = iter(starts), threading.Lock(), threading.Event()
    outs = {}

    def work():
        while not stop.is_set():
            with lock:
                i = next(todo, None)
            if i is None:
                return
            part = jax.tree.map(lambda a: _grow(a[i : i + size], size) if eqx.is_array(a) else a, sorted_)
            try:
                outs[i] = jax.tree.map(lambda a: np.asarray(a)[: min(size, B - i)],
                                       _solve_batch(*part[:2], ts, part[2], cfg))
            except BaseException:
                stop.set()  # the other threads take no further piece
                raise

    workers = max(1, min(workers, len(starts)))
    if workers == 1:
        work()
    else:
        with concurrent.futures.ThreadPoolExecutor(workers) as pool:
            futures = [pool.submit(work) for _ in range(workers)]
            try:
                for f in futures:
                    f.result()
            except BaseException:  # (an error in a thread, or Ctrl-C here): no further piece starts
                stop.set()
                raise
    back = np.argsort(order)
    return jax.tree.map(lambda *a: np.concatenate(a)[back], *[outs[i] for i in starts])


@eqx.filter_jit
def _regime_numbers(stacks: Stack, states: State) -> Array:
    """`(B,)` log of each design's regime number: its summed initial gaps over the peak overlap of its
    stiffest contact at the drop speed (`_scaling._scales`; a gap over the contact-time scale, Pi =
    gap / (t_c V), up to a constant). The designs' step counts follow it (the regime decides how many
    separate impacts and free flights the cascade has): solving the designs of a batch in this order,
    a CPU piece's designs end closer together (measured on 19,740 designs of `benchmarks/sweep.py`,
    gap x stiffness: the steps of the lanes that wait for a piece's slowest design fall from 13.4 % to
    7.1 % of the work; the best possible order, by the steps themselves, 1.2 %)."""

    def one(stack, state):
        gaps = jnp.sum(jnp.maximum(jnp.diff(state.positions), 0.0))
        return jnp.log(gaps / _scales(stack, state).length + 1e-6)

    return jax.vmap(one)(stacks, states)


def _grow(a, size: int):
    """`a` padded to `size` rows by repeating its last row (NumPy for a NumPy array)."""
    pad = size - a.shape[0]
    xp = np if isinstance(a, np.ndarray) else jnp
    return xp.concatenate([a, xp.repeat(a[-1:], pad, axis=0)]) if pad > 0 else a


def _invalid_designs(stacks: Stack, states: State) -> np.ndarray | None:
    """`(B,)` the designs of a batch that cannot be solved: a mass not finite and > 0, a gravity not
    finite and >= 0, a law parameter outside its rule (`AbstractContactLaw.field_rules`: a stiffness > 0,
    a damping >= 0, ...), or a non-finite number anywhere in the stack or the state (values set past
    `Stack`'s checks, e.g. by `jax.vmap`ped constructors or `eqx.tree_at`; the rules `_design_invalid`
    checks for a traced single design). None under a trace (nothing to read)."""
    leaves = [a for a in jax.tree.leaves((stacks, states)) if eqx.is_array(a)]
    if any(isinstance(a, jax.core.Tracer) for a in leaves):
        return None
    m = np.asarray(stacks.masses)
    bad = ~np.all(np.isfinite(m) & (m > 0), axis=1)
    B = m.shape[0]

    def per_design(ok):  # `ok` of one design's array, or of all designs' at once (leading axis B)
        ok = np.asarray(ok)
        return np.all(ok.reshape(B, -1), axis=1) if ok.ndim and ok.shape[0] == B else np.full(B, bool(np.all(ok)))

    g = np.asarray(stacks.gravity, dtype=float)
    bad |= ~per_design(np.isfinite(g) & (g >= 0))  # a review: gravity -9.8 in a batch ran "complete"
    f0 = np.asarray(stacks.end_force, dtype=float)
    bad |= ~per_design(np.isfinite(f0) & (f0 >= 0))  # a negative end force ran "complete" (a review)
    if stacks.wall:  # a wall stiffness <= 0 ran without a wall, or to max_steps (a review)
        kw = np.asarray(stacks.wall_stiffness, dtype=float)
        bad |= ~per_design(np.isfinite(kw) & (kw > 0))
    for law in stacks.laws:  # a review: a negative stiffness in a batch came back "complete" with NaN
        for field, (lowest, strict, _) in law.field_rules.items():
            a = np.asarray(getattr(law, field), dtype=float)
            bad |= ~per_design(np.isfinite(a) & ((a > lowest) if strict else (a >= lowest)))
    for a in leaves:
        a = np.asarray(a)
        if a.ndim and a.shape[0] == B and np.issubdtype(a.dtype, np.inexact):
            bad |= ~np.all(np.isfinite(a.reshape(B, -1)), axis=1)
    return bad


def _fail_designs(out: dict, invalid: np.ndarray) -> dict:
    """`out` with the designs `invalid` (not solved: `_invalid_designs`) failed: status `failed`, no steps,
    NaN results."""
    def fail(key, a):
        a = np.array(a)
        if key == "status":
            a[invalid] = int(Status.FAILED)
        elif np.issubdtype(a.dtype, np.integer):
            a[invalid] = 0
        elif np.issubdtype(a.dtype, np.inexact):
            a[invalid] = np.nan
        return a

    return {k: v if k == "scales" else (jax.tree.map(lambda a: fail(k, a), v) if isinstance(v, dict) else fail(k, v))
            for k, v in out.items()}


def _bucket(B: int) -> int:
    """The number of designs a CPU batch of `B` is solved as: the next power of two, the last design
    repeated (`_solve_designs`), so that the sizes 1..`CPU_PIECE` compile 8 programs instead of one each
    (a review: every new batch size compiled again, ~10 s), at most twice the work."""
    return 1 << max(B - 1, 0).bit_length()


def _solve_designs(stacks, states, ts, t_max, cfg, ndev: int) -> dict:
    """One vmapped solve of the designs, split over the `ndev` devices where there are enough; on a CPU
    padded to `_bucket(B)` designs (a GPU takes the batch as it is)."""
    B = t_max.shape[0]
    if jax.default_backend() == "cpu" and _bucket(B) > B:
        size = _bucket(B)
        padded = jax.tree.map(lambda a: _grow(a, size) if eqx.is_array(a) else a, (stacks, states, t_max))
        out = _solve_designs(*padded[:2], ts, padded[2], cfg, ndev)
        return jax.tree.map(lambda a: a[:B], out)
    if ndev > 1 and B >= 2 * ndev:
        size = B + (-B % ndev)  # repeat the last design so that every device gets the same share
        batched = jax.tree.map(lambda a: _grow(a, size) if eqx.is_array(a) else a, (stacks, states, t_max))
        out = _solve_sharded(ndev)(*batched[:2], ts, batched[2], cfg)
        return out if size == B else jax.tree.map(lambda a: a[:B], out)
    return _solve_batch(stacks, states, ts, t_max, cfg)


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
    pulse_durations: bool = False,
    _pieces: bool = False,
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
    is flagged "incomplete: max_steps reached"). With several JAX devices (every CPU core is one:
    module docstring, "Batches") the designs are split over them. On a CPU a batch of up to `CPU_PIECE`
    is solved as the next power of two, its last design repeated (`_bucket`: the sizes up to 128 share 8
    compiled programs; the results come back for the designs given). On a CPU, more than `CPU_PIECE`
    designs are solved in pieces of `CPU_PIECE`, taken in the order of the designs' regime number
    (`_regime_numbers`: designs whose cascades take alike many steps share a piece, so fewer lanes wait
    for a piece's slowest design), each piece one vmapped solve, a thread per core taking the next piece as
    it finishes; which designs share a piece does not depend on the number of cores, so neither do the
    results. Results come back in the order given; a design's solution depends on its companions in a
    piece only by rounding (vectorised kernels round differently, and adaptive steps carry that to the
    tolerance: the top mass's launch velocity within ~1e-8 relative, a near-resting bottom mass's launch,
    whose release from the ground is ill-conditioned, up to ~3 %). `until` as for `simulate`. Costs per
    design are measured in `benchmarks/` (`make bench`). Designs whose numbers no stack may have (a mass
    not finite and > 0, a non-finite value; set past `Stack`'s checks, e.g. by `jax.vmap`) are not solved
    and come back `failed` with NaN results.

    `pulse_durations=True` (with `save_steps=False`) also streams the top mass's pulse through the solve
    for its 10 % duration and 10-90 % rise time (`BatchSolution.top_duration_10`, `top_rise_time`): up
    to 256 samples of the pulse are kept per design, and every step's state passes through diffrax's
    accept/reject select, so it costs about 20 % per step (measured: five-mass Tsuji designs,
    `benchmarks/sweep.md`). Raises `ParameterError`
    with `save_steps=True` (analyse a design's history instead).

    `_pieces` (internal, `hertz_chain.sweeps`): on a CPU, a batch of up to `CPU_PIECE` designs is one
    piece on one device too (otherwise it is split over the devices), so that a chunk's results do not
    depend on the number of devices either.
    """
    if pulse_durations and save_steps:
        raise ParameterError("pulse_durations", True, "only with save_steps=False (with a step history, "
                             "analyse the design: its pulse metrics have the durations)")
    _not_traced("simulate_batch", stacks, states)
    ts, t_max, cfg = _prepare(stacks, states, ts, t_max, solver, tolerances, max_steps, None, save_steps, until)
    if pulse_durations:
        cfg = dataclasses.replace(cfg, durations=True)
    if getattr(cfg.solver, "scan_kind", "") is None:
        # Runge–Kutta stages as a "bounded" loop: 15 % faster per design under vmap, but 50 % slower
        # for a single solve than diffrax's default (measured, Tsit5, 5 and 10 masses)
        cfg = eqx.tree_at(lambda c: c.solver.scan_kind, cfg, "bounded", is_leaf=lambda x: x is None)
    B = stacks.masses.shape[0] if stacks.masses.ndim == 2 else None
    if B is None:
        raise ParameterError("stacks/states", (stacks.masses.shape, states.positions.shape),
                             "batched designs: masses and positions of shape (B, n)")
    t_max = jnp.broadcast_to(jnp.asarray(t_max, dtype=float), (B,))
    given = (stacks, states)  # what the solution reports (`_invalid_designs` below may stand in for some)
    invalid = _invalid_designs(stacks, states)
    if invalid is not None and invalid.any() and not invalid.all():
        # not solved (a zero or NaN mass held its piece to max_steps at t = 0): the first valid design
        # runs in their place, and their results are set to `failed` with NaN below
        ok = int(np.argmin(invalid))
        stacks, states = jax.tree.map(
            lambda a: np.where(invalid.reshape((B,) + (1,) * (np.ndim(a) - 1)), np.asarray(a)[ok], a)
            if eqx.is_array(a) else a, (stacks, states))
    ndev = jax.local_device_count()
    if invalid is not None and invalid.all():  # nothing to solve: the outputs' layout, every design failed
        shapes = eqx.filter_eval_shape(_vmapped, stacks, states, ts, t_max, cfg)
        out = jax.tree.map(lambda a: np.full(a.shape, np.nan if jnp.issubdtype(a.dtype, jnp.inexact) else 0, a.dtype),
                           shapes)
    elif jax.default_backend() == "cpu" and (B > CPU_PIECE or (_pieces and B > 1)):
        out = _solve_pieces(stacks, states, ts, t_max, cfg, ndev)
    else:  # one vmapped solve, split over the devices (not an implicit solver's: its linear solves fail
        # under `jax.shard_map`)
        out = _solve_designs(stacks, states, ts, t_max, cfg,
                             1 if isinstance(cfg.solver, dfx.AbstractImplicitSolver) else ndev)
    out = _post_history(out, stacks, batched=True)
    if invalid is not None and invalid.any():
        out = _fail_designs(out, invalid)
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
        scales=out["scales"], stack=given[0], state=given[1],
        peak_forces=np_(out["peak_forces"]) if "peak_forces" in out else None,
        impact_velocities=np_(out["impact_velocities"]) if "impact_velocities" in out else None,
        restitutions=np_(out["restitutions"]) if "restitutions" in out else None,
        first_contacts=np_(out["first_contacts"]) if "first_contacts" in out else None,
        top_duration_10=np_(out["top_duration_10"]) if "top_duration_10" in out else None,
        top_rise_time=np_(out["top_rise_time"]) if "top_rise_time" in out else None,
        until=until,
    )


def _launch_impl(stack, state, t_max, cfg, replay):
    """The launch velocities and the status of one solve (`launch_velocity`, unchecked: `_checked`).
    `replay`: `"reverse"` or `"forward"` (the replayed derivatives, `_adjoint`), or False (a diffrax
    adjoint's)."""
    if replay:
        sc, scale, y0s, t1s = _setup(stack, state, t_max, cfg)
        frozen = jax.lax.stop_gradient((t1s, scale, sc.time))  # the end time and the scales carry no gradient
        solve = _replayed_solve if replay == "reverse" else _forward_replayed_solve
        out = _launch_outputs(stack, sc, scale, solve((stack, y0s), *frozen, cfg))
    else:
        out = _solve_impl(stack, state, None, t_max, cfg, launch_only=True)
    return out["launch_velocities"], out["status"]


_NOT_ENDED = ("hertz_chain.launch_velocity: the cascade did not end (t_max or max_steps reached, no contact, "
              "or a non-finite state), or the traced design breaks a rule (masses finite and > 0, gravity >= 0, "
              "gaps and drop speed finite and >= 0, each law's parameters, e.g. a stiffness > 0: traced, they are checked only here, after the "
              "solve); raise t_max or max_steps, or check the design")


_LAST_ENDED = int(Status.COMPLETE_WITH_REBOUNDS)


def _checked(v, status, replay=False, design=None):
    """`v`, or an error where the solve did not end: `SolverError` when called on arrays, a run-time
    error of the caller's compiled function under a trace (`eqx.error_if`). Kept out of `_launch_jit`:
    a host callback would keep the compiled solve out of JAX's persistent compilation cache.

    Under a trace the check is also on the derivative's path (`_guard_reverse`, `_guard_forward`): under
    the caller's `jit`, `jax.grad` drops the primal value, and with it an `eqx.error_if` on it alone,
    which left zero gradients of a failed solve. `replay`: the reverse-mode replay (`adjoint="reverse"`),
    whose gradients raise; otherwise a failed solve's forward derivatives raise and its reverse-mode ones
    (through a diffrax adjoint) are NaN wherever the result depends on the parameter."""
    if not isinstance(status, jax.core.Tracer):
        # under jax.grad or jax.jacfwd without the caller's jit the status is concrete, and so are the
        # traced design's values: its rules are checked here (a review: a Tsuji law with eta = -0.5 under
        # plain jax.grad created energy, v_top 2.55 m/s from 1 m/s, without a word)
        if design is not None and any(isinstance(x, jax.core.Tracer) for x in jax.tree.leaves(design)):
            try:
                invalid = bool(_design_invalid(*design))
            except jax.errors.ConcretizationTypeError:  # values unknown here (checked by the guard instead)
                invalid = False
            if invalid:
                raise ParameterError("design", "traced", "masses finite and > 0, gravity finite and >= 0, and "
                                     "each law's parameters within their rules (e.g. a stiffness > 0, a damping "
                                     ">= 0): the traced design breaks one")
        if np.asarray(status).max() > _LAST_ENDED:  # 2 us; np.any(... > Status.X) took 10 us per call
            # the cause, by the worst status (a review: the generic words suggested max_steps for a t_max)
            worst = Status(int(np.asarray(status).max()))
            # traced: a design under the caller's grad or vmap, whose masses and laws no check could read (a
            # review: a negative mass under jax.grad read only "raise max_steps")
            traced = design is not None and any(isinstance(x, jax.core.Tracer) for x in jax.tree.leaves(design))
            raise SolverError(f"hertz_chain.launch_velocity: the cascade did not end ({worst.text}): "
                              + worst.hint().replace("solver.", "")
                              + ("; the design's numbers were traced (jax.grad, jax.vmap), so the checks of "
                                 "masses > 0 and the laws' parameters could not run: check them too" if traced else ""))
        return v
    # a traced design whose numbers break the rules its concrete checks enforce (a review: a stiffness of 0
    # under jit gave NaN and, differentiated, a gradient of zeros, with the cascade reported complete)
    bad = (status > _LAST_ENDED) | (_design_invalid(*design) if design is not None else False)
    return _guard_reverse(v, bad) if replay == "reverse" else _guard_forward(v, bad)


def _design_invalid(stack, state):
    """Under a trace: whether the design's numbers break a rule that `Stack`, `State` and the laws' own
    checks (`AbstractContactLaw.field_rules`) enforce on concrete values: masses finite and > 0, gravity
    and the end force finite and >= 0, a wall's stiffness > 0, each law parameter within its rule, a
    finite initial state (a traced bool)."""
    bad = ~jnp.all(jnp.isfinite(stack.masses) & (stack.masses > 0))
    bad |= ~(jnp.isfinite(stack.gravity) & (stack.gravity >= 0))
    bad |= ~(jnp.isfinite(stack.end_force) & (stack.end_force >= 0))
    if stack.wall:
        bad |= ~(jnp.isfinite(stack.wall_stiffness) & (stack.wall_stiffness > 0))
    for law in stack.laws:
        for field, (lowest, strict, _) in law.field_rules.items():
            a = jnp.asarray(getattr(law, field))
            bad |= ~jnp.all(jnp.isfinite(a) & ((a > lowest) if strict else (a >= lowest)))
    return bad | ~jnp.all(jnp.isfinite(state.positions) & jnp.isfinite(state.velocities))


@jax.custom_vjp
def _guard_reverse(v, bad):
    """`v`, with a run-time error where `bad`, on the value and on its cotangent (reverse mode only)."""
    return eqx.error_if(v, bad, _NOT_ENDED)


_guard_reverse.defvjp(lambda v, bad: (_guard_reverse(v, bad), bad),
                      lambda bad, ct: (eqx.error_if(ct, bad, _NOT_ENDED), None))


@jax.custom_jvp
def _guard_forward(v, bad):
    """`v`, with a run-time error where `bad`, on the value and on its tangent; transposed (reverse mode
    through a diffrax adjoint) the cotangent is NaN where `bad`."""
    return eqx.error_if(v, bad, _NOT_ENDED)


@_guard_forward.defjvp
def _guard_forward_jvp(primals, tangents):
    v, bad = primals
    return _guard_forward(v, bad), eqx.error_if(tangents[0] * jnp.where(bad, jnp.nan, 1.0), bad, _NOT_ENDED)


# `replay` ("reverse", "forward" or False, `_launch_impl`) is static. Used under the caller's trace (the top level runs a `_Launch`) and for
# options that cannot be hashed. At the top level compiled with `_config.solve_compiler_options()` (JAX
# takes options only there); not kept on disk by `_export` as `simulate`'s solve is: the exported call's checks cost
# ~0.3 ms per call, more than this function's whole fixed cost (JAX's compilation cache still keeps it)
_launch_with = jit_per_options(_launch_impl)


def _launch_jit(*args):
    return _launch_with(_config.solve_compiler_options() if _top_level(args) else None)(*args)


def launch_velocity(
    stack: Stack,
    state: State,
    *,
    solver: str | dfx.AbstractSolver = "tsit5",
    tolerances: Tolerances | None = None,
    t_max: float | None = None,
    max_steps: int = 16_384,
    adjoint: str | dfx.AbstractAdjoint = "reverse",
    until: str = "cascade",
) -> Array:
    """`(n,)` launch velocities (m/s) as a differentiable JAX function of the design.

    Use inside `jax.grad` (`adjoint="reverse"`) or `jax.jacfwd`/`jax.jvp` (`adjoint="forward"`), e.g.
    `jax.grad(lambda m: launch_velocity(Stack(m, law, gravity=0.0), at_impact(...))[-1])(masses)`.
    Tolerances default to `rtol = atol = 1e-11` with `resolve_onsets=True`, where gradients matched central
    finite differences to 2e-6 (module docstring). A failed solve raises `SolverError` (under the
    caller's own `jit`/`grad`/`vmap`, a run-time error through `eqx.error_if`, on the value and on its
    derivative: `_checked`), never a silent NaN.

    **Laws whose onset is not smooth** (`registry.LawRow.smooth_onset` is False: Tsuji, Kelvin–Voigt,
    viscoelastic): their `delta^(1/4)`, `sqrt(delta)` or jumping dashpot term has an unbounded derivative
    where a contact closes. The reverse mode (`adjoint="reverse"`) splits every onset and every release of
    a clamped contact out of the replayed steps and replays the steps right after an onset in
    `s = (t - t*)^(1/4)` (module docstring), and matches central differences to 2e-6 with gaps or
    touching (`benchmarks/optimize.md`); so does `adjoint="forward"`, which replays the same steps forward
    (the same discrete derivative); diffrax's adjoints do not, and are off by up to order 1 with gaps for
    those laws.

    `adjoint`: `"reverse"` (default; `jax.grad` by replaying the accepted steps, module docstring;
    reverse mode only: `jax.jacfwd` of it raises `ParameterError` naming `"forward"`), `"forward"`
    (`jax.jacfwd`, `jax.jvp`, by replaying them forward; forward mode only), or a diffrax adjoint, e.g.
    `diffrax.RecursiveCheckpointAdjoint()` for higher-order derivatives.

    Cost: a repeated call at the top level (not under `jit`/`grad`/`vmap`) with the same options and
    `t_max=None`, on a stack and state of the same structure (tree, shapes, dtypes), runs the solve compiled
    by the first such call without checking its options or preparing it again (`_LAUNCHES`: ~60 us of
    fixed cost per call instead of ~300 us; `prepare_launch` fixes the options once, ~40 us). Reverse
    mode costs a few solves whatever the number of parameters; forward mode grows with
    it (prefer it for two or three). Reverse mode keeps the accepted states, `32 n` bytes per step of
    `max_steps`. Measured ratios: `benchmarks/results.md`.

    `until`: `"cascade"` (default) or `"launch"` (stop as soon as the top mass's launch is final, as for
    `simulate`: the top's entry is exact, the others are the velocities at that time).
    """
    replay = adjoint if isinstance(adjoint, str) and adjoint in ("reverse", "forward") else False
    key = None
    top = _top_level((stack, state))
    if top:  # at the top level: the compiled program of this structure (`_Launch`)
        lv, tree = jax.tree_util.tree_flatten((stack, state))
        if t_max is None:  # a repeated call finds its launch with its options unchecked
            key = _launch_key(lv, tree, solver, tolerances, max_steps, adjoint, until)
            hit = _LAUNCHES.get(key) if key is not None else None
            if hit is not None and hit[0] is _solver_row(solver) and not stack.held:
                return hit[1].run_leaves(lv)
    t_max_, cfg = _launch_config(stack, state, solver, tolerances, t_max, max_steps, adjoint, until)
    launch = _Launch.of(stack, state, t_max_, cfg, replay, shared=True) if top else None
    if launch is not None:
        if key is not None:
            _remember(_LAUNCHES, key, (_solver_row(solver), launch), 256)
        return launch.run_leaves(lv)
    # traced (the caller's jit, grad, vmap), or options that cannot be hashed
    try:
        out = _launch_jit(stack, state, t_max_, cfg, replay)
    except TypeError as e:  # JAX's words for jvp of the reverse mode's custom_vjp: name the option instead
        if replay == "reverse" and "forward-mode autodiff" in str(e):
            raise ParameterError("adjoint", "reverse", "adjoint='forward' for forward-mode derivatives "
                                 "(jax.jacfwd, jax.jvp); 'reverse' (the default) serves jax.grad, jax.vjp and "
                                 "jax.jacrev") from None
        raise
    return _checked(*out, replay, design=(stack, state))


# `launch_velocity`'s solves at the top level, by its options as written and the structure of its
# arguments (`_launch_key`): a repeated call runs its `_Launch` (~30 us of Python) without checking its
# options again (~170 us with `eqx.filter_jit`'s partition and hashing of the configuration). An option
# written another way, or a new tolerance, misses here and finds its compiled program in `_PROGRAMS`.
_LAUNCHES: dict = {}
# the compiled programs, by what is static about them (`_Program.key_of`): the tolerances and `t_max` are
# arguments, so a new tolerance compiles nothing
_PROGRAMS: dict = {}


def _remember(memo: dict, key, value, size: int) -> None:
    """`memo[key] = value`, the oldest entry dropped beyond `size` (tolerant of another thread's drop)."""
    memo[key] = value
    while len(memo) > size:
        try:
            memo.pop(next(iter(memo)), None)
        except (RuntimeError, StopIteration):  # changed by another thread meanwhile
            break


def _solver_row(solver):
    """The registry row of a solver name (None for a solver object): an entry of `_LAUNCHES` is valid
    only while the row it was made with is the registry's (`_config_for`)."""
    from .registry import SOLVERS

    return SOLVERS.get(str(solver).lower()) if isinstance(solver, str) else None


def _leaf_key(x):
    """A leaf of `(stack, state)` in a key: an array (JAX's, NumPy's, NumPy scalars: what `eqx.is_array`
    counts) by its shape and dtype, anything else by its value."""
    shape = getattr(x, "shape", None)
    return x if shape is None else (tuple(shape), x.dtype)


def _launch_key(lv, tree, solver, tolerances, max_steps, adjoint, until):
    """The key of a launch solve in `_LAUNCHES`: the options as written, the structure of `(stack, state)`
    (its tree, its arrays' shapes and dtypes, its other leaves) and the compile options in use; None where
    an option or a leaf cannot be hashed (then no fast path)."""
    options = _config.solve_compiler_options()
    key = (tree, tuple(map(_leaf_key, lv)), solver, tolerances, type(max_steps), max_steps, adjoint, until,
           None if options is None else tuple(sorted(options.items())))
    try:
        return _Key(key)
    except TypeError:
        return None


class _Key:
    """A dict key that hashes its tuple once (a `Tolerances`' hash costs ~5 us: the dict's lookup hashed it
    again)."""

    __slots__ = ("key", "hash")

    def __init__(self, key: tuple):
        self.key, self.hash = key, hash(key)

    def __hash__(self) -> int:
        return self.hash

    def __eq__(self, other) -> bool:
        return isinstance(other, _Key) and self.hash == other.hash and self.key == other.key


def _launch_config(stack, state, solver, tolerances, t_max, max_steps, adjoint, until):
    """`(t_max, cfg)` of a launch solve: `launch_velocity`'s defaults (rtol = atol = 1e-11 with the onset
    proxies), its `until` values, the checks of `_prepare`."""
    tolerances = tolerances or Tolerances(rtol=1e-11, atol=1e-11, resolve_onsets=True)
    if until not in ("cascade", "launch"):
        raise ParameterError("until", until, "'cascade' or 'launch' (a launch solve stops at the cascade's end)")
    _check_one_design(stack)
    _, t_max, cfg = _prepare(stack, state, None, t_max, solver, tolerances, max_steps, adjoint, save_steps=False,
                             until=until)
    return t_max, cfg


def prepare_launch(
    stack: Stack,
    state: State,
    *,
    solver: str | dfx.AbstractSolver = "tsit5",
    tolerances: Tolerances | None = None,
    t_max: float | None = None,
    max_steps: int = 16_384,
    until: str = "cascade",
):
    """A compiled `launch(stack, state) -> (n,)` launch velocities (m/s) for stacks of the structure of
    `stack` and `state` (the same number of masses, law classes and interface groups, the same ground and
    wall; gravity, masses and law parameters are numbers of the design): `launch_velocity` without its
    per-call preparation. The options are checked once, here; each call only flattens its arguments,
    compares their structure with the prepared one and runs the compiled solve (JAX's `jax.jit` over the
    arrays): a fixed cost of ~40 us per call (`benchmarks/baselines.md`, "Fixed cost per call").
    A repeated `launch_velocity` call of the same options on a stack of the same structure reuses such a
    compiled solve by itself (`_LAUNCHES`), for ~20 us more (it looks its options up); a prepared
    function fixes them once and names the structure it was prepared for in its error. Values equal
    `launch_velocity`'s with the same options. For derivatives use `launch_velocity`: `jax.grad` through
    this callable runs, through diffrax's own loop, without the replayed reverse mode's handling of
    contact onsets (docs/solver-defaults.md: off by up to order 1 with gaps for damped laws).

    **Arguments:** as `launch_velocity`; `stack`, `state` fix the structure (and are a valid first call).

    **Returns:** the function `launch(stack, state)`.

    **Raises:** `ParameterError` for bad options (here), and, from `launch`, for a stack or state of
    another structure or a chain held by an end force; from `launch`, a solve that does not end raises
    `SolverError` (under the caller's own `jit`, `grad` or `vmap`, a run-time error through
    `eqx.error_if`), as `launch_velocity` does.
    """
    t_max_, cfg = _launch_config(stack, state, solver, tolerances, t_max, max_steps, "reverse", until)
    return _Launch.of(stack, state, t_max_, cfg, False).__call__


class _Program:
    """The compiled launch solve of one structure of `(stack, state)` and one static configuration: a
    function of the arrays of `(stack, state)`, the arrays of the configuration (its tolerances) and
    `t_max`, shared by every `_Launch` of that structure (`_PROGRAMS`).

    At the top level the status is checked on the host after the compiled solve (`_checked`: a
    `SolverError`; an `eqx.error_if` inside would raise only when the result is read on a GPU, and keeps
    the program out of JAX's persistent cache), with compile options (CPU ones on the CPU backend only);
    under the caller's own `jit`/`vmap`/`grad`, `eqx.error_if` in the caller's program, no options."""

    def __init__(self, stack: Stack, state: State, cfg: _SolveConfig, replay):
        all_leaves, tree = jax.tree_util.tree_flatten((stack, state))
        is_array = [eqx.is_array(x) for x in all_leaves]
        self.array_at = [i for i, a in enumerate(is_array) if a]
        self.other_at = [i for i, a in enumerate(is_array) if not a]
        self.others = [all_leaves[i] for i in self.other_at]
        self.tree = tree
        # the leaf of the stack's end force (`Stack.held`, checked by a prepared function's calls)
        paths = [p for p, _ in jax.tree_util.tree_flatten_with_path((stack, state))[0]]
        self.end_force_at = next((i for i, p in enumerate(paths) if len(p) == 2 and getattr(p[1], "name", None)
                                  == "end_force" and i in self.array_at), None)
        cfg_arrays, cfg_static = eqx.partition(cfg, eqx.is_array)
        cfg_tree = jax.tree_util.tree_structure(cfg_arrays)
        na, nc = len(self.array_at), cfg_tree.num_leaves

        def design(*args):  # (stack, state) of the arrays `args[:na]`
            it = iter(args[:na])
            return jax.tree_util.tree_unflatten(tree, [next(it) if a else x for x, a in zip(all_leaves, is_array)])

        def run(*args):  # (launch velocities, status)
            s, st = design(*args)
            c = eqx.combine(jax.tree_util.tree_unflatten(cfg_tree, args[na : na + nc]), cfg_static)
            return _launch_impl(s, st, args[-1], c, replay)

        # under the caller's trace the design's rules are checked too (`_checked`; a review: a prepared
        # callable under jit or vmap ran a Tsuji law with a negative eta silently, creating energy)
        self.nested = jax.jit(lambda *args: _checked(*run(*args), replay, design=design(*args)))
        options = _config.solve_compiler_options()
        self.compiled = jax.jit(run, compiler_options=options) if options else jax.jit(run)

    @staticmethod
    def key_of(all_leaves, tree, cfg_static, cfg_tree, replay):
        """What the program is compiled for (None where it cannot be hashed): the structure of
        `(stack, state)`, the static part of the configuration, `replay`, the compile options."""
        options = _config.solve_compiler_options()
        key = (tree, tuple(map(_leaf_key, all_leaves)), cfg_static, cfg_tree, replay,
               None if options is None else tuple(sorted(options.items())))
        try:
            hash(key)
        except TypeError:
            return None
        return key


class _Launch:
    """A `_Program` with the numbers of one set of checked options (the tolerances' arrays, `t_max`):
    `prepare_launch`'s function, and `launch_velocity`'s repeated calls (`_LAUNCHES`). A call flattens its
    arguments and runs the compiled program on their arrays (JAX's `jax.jit`), ~10 us of Python."""

    def __init__(self, program: _Program, numbers: list, shapes: tuple, prepared_for: str):
        self.program, self.numbers, self.shapes, self.prepared_for = program, numbers, shapes, prepared_for

    @classmethod
    def of(cls, stack: Stack, state: State, t_max, cfg: _SolveConfig, replay,
           shared: bool = False) -> "_Launch | None":
        """The launch of these (checked) arguments, on the program compiled for their structure (made on
        the first use of that structure, `_PROGRAMS`). `shared`: None where the program cannot be kept
        (options that cannot be hashed) instead of a program of its own."""
        all_leaves, tree = jax.tree_util.tree_flatten((stack, state))
        cfg_arrays, cfg_static = eqx.partition(cfg, eqx.is_array)
        key = _Program.key_of(all_leaves, tree, cfg_static, jax.tree_util.tree_structure(cfg_arrays), replay)
        if key is None and shared:
            return None
        program = _PROGRAMS.pop(key, None) if key is not None else None  # (put back last: most recent)
        if program is None:
            program = _Program(stack, state, cfg, replay)
        if key is not None:
            before = len(_PROGRAMS)
            _remember(_PROGRAMS, key, program, 64)
            if len(_PROGRAMS) <= before:  # an old program was dropped: the launches on it go too (memory)
                live = {id(p) for p in _PROGRAMS.values()}
                for k in [k for k, v in list(_LAUNCHES.items()) if id(v[1].program) not in live]:
                    _LAUNCHES.pop(k, None)
        numbers = [jnp.asarray(x) for x in jax.tree_util.tree_leaves(cfg_arrays)] + [jnp.asarray(t_max)]
        return cls(program, numbers, tuple(np.shape(all_leaves[i]) for i in program.array_at), _describe(stack))

    def run_leaves(self, lv: list) -> Array:
        """The launch velocities of the flattened `(stack, state)` `lv`, of the prepared structure."""
        p = self.program
        arrays = [lv[i] for i in p.array_at]
        for x in arrays:
            if isinstance(x, jax.core.Tracer):
                return p.nested(*arrays, *self.numbers)
        return _checked(*p.compiled(*arrays, *self.numbers))

    def __call__(self, stack: Stack, state: State) -> Array:
        """`launch(stack, state) -> (n,)` launch velocities (m/s); `ParameterError` for a stack or state of
        another structure, `SolverError` for a solve that does not end (`prepare_launch`)."""
        p = self.program
        lv, tree = jax.tree_util.tree_flatten((stack, state))
        if (tree != p.tree or tuple(_shape(lv[i]) for i in p.array_at) != self.shapes
                or [lv[i] for i in p.other_at] != p.others):
            _prepared_mismatch(stack, state, self.prepared_for)
        at = p.end_force_at
        if at is not None and not isinstance(lv[at], jax.core.Tracer) and np.asarray(lv[at]).any():
            raise ParameterError("stack", "a chain held by an end force", "a free chain: the prepared solve runs "
                                 "until the cascade ends, which a held chain never does; use simulate(..., "
                                 "until='t_max')")
        return self.run_leaves(lv)


def _shape(x) -> tuple:
    """`np.shape(x)`, in ~0.1 us for an array (~0.6 us through NumPy)."""
    shape = getattr(x, "shape", None)
    return np.shape(x) if shape is None else tuple(shape)


def _prepared_mismatch(stack, state, prepared_for: str):
    """Raise `ParameterError` for a call of `prepare_launch`'s function on a stack or state of another
    structure (its masses' and state's shapes first, then the structure)."""
    _check_one_design(stack)
    if isinstance(stack, Stack) and isinstance(state, State):
        _check_state_shape(stack, state)
    raise ParameterError("stack, state", _describe(stack) if isinstance(stack, Stack) else type(stack).__name__,
                         f"the structure prepared for: {prepared_for}")


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
    `delta` (values, rates and accelerations at the steps: interpolation error O(h^6)), over the steps
    whose two ends are both in contact (`delta > 0`): across the onset the acceleration jumps (a
    dashpot's force, largest at first touch), and the interpolant there read a hertz-dashpot contact's
    peak 12.5 % high at e = 0.3 (a review); the sample `i` itself counts."""
    best = float(fn_of_state(np.asarray(d[i]), np.asarray(dd[i])))
    for a, b in ((i - 1, i), (i, i + 1)):
        if a < 0 or b >= len(t) or t[b] <= t[a] or not (d[a] > 0 and d[b] > 0):
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


def simulate_impact(
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
    v = check_positive(impact_velocity, "impact_velocity")  # (m/s)
    m = check_positive(effective_mass, "effective_mass")  # (kg)
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


def restitution(*args, **kwargs) -> Restitution:
    """Deprecated name of :func:`simulate_impact` (it simulates; the name now says so). Warns with a
    `DeprecationWarning`; the same arguments and result."""
    import warnings

    warnings.warn("hertz_chain.restitution is renamed simulate_impact (it runs a simulation); the old name "
                  "will be removed", DeprecationWarning, stacklevel=2)
    return simulate_impact(*args, **kwargs)
