"""The compiled solve behind `hertz_chain.simulation`: the scaled vector field, the one call to
`diffrax.diffeqsolve`, its outputs, the step history's post-processing, and the batched and sharded
solves."""

from __future__ import annotations

import dataclasses
import functools

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import _config  # float64; SOLVE_COMPILER_OPTIONS
from ._export import cached_jit
from ._law_base import _positive_part
from ._scaling import FieldArgs, Scales, _default_t_max, _scales, inverse_force_scale
from ._solver import UNROLL_MAX_STATE, UnrolledERK, _SolveConfig
from ._tracking import (
    PEAK_FORCE,
    T_FIRST_IN,
    T_FIRST_OUT,
    T_IN,
    V_LOWER_AFTER,
    V_LOWER_BEFORE,
    V_UPPER_AFTER,
    V_UPPER_BEFORE,
    _cascade_complete,
    _end_of_contacts,
    _pulse_duration,
    _launch,
    _Tracked,
)
from .stack import Stack, State
from .status import Status

def _scaled_field(t, ys, args):
    """The scaled vector field of the solver's state `[x, v, D (3n) (, q (n), a law with memory) | z (n,
    with resolve_onsets) | over]`.

    `over` (the last entry) is no variable of the motion: its derivative is zero, and `_Tracked` writes
    the cascade-over flag of `_cascade_over` into it after every step, so that the stopping event reads
    one number instead of evaluating the rule again. A state of exactly the physical size
    (`Stack.state_size`: the replayed adjoint's physical part) gets the physical derivatives only."""
    stack, scale, T = args.stack, args.scale, args.T
    n3 = scale.shape[0]
    y = ys[:n3] * scale
    # the divisors as factors where the solve computed them once (`FieldArgs.rate`, ...)
    rate = T / scale if args.rate is None else args.rate
    if ys.shape[0] <= n3 + 1:  # no onset proxies
        dy = stack.vector_field_and_forces(t * T, y, args.inv_masses)[0] * rate
        return dy if ys.shape[0] == n3 else jnp.concatenate([dy, jnp.zeros(1, dy.dtype)])
    dy, f = stack.vector_field_and_forces(t * T, y, args.inv_masses)
    dy = dy * rate
    # onset proxy (`Tolerances.resolve_onsets`): z_j' = sqrt(delta_j+ / L) + sqrt(F_j / F_s), F_s = m*_j V^2 / L,
    # whose local error is O(h^1.5) wherever a contact closes (the kink of F ~ delta^{3/2}; the steeper rise
    # of a damped law) and wherever a clamped contact lets go (its force's kink at F = 0), so the step
    # controller resolves both to the tolerance (docs/solver-defaults.md, "Default tolerances")
    # sqrt(delta+ / L) as sqrt(delta_safe) / sqrt(L), with the laws' own `_positive_part` of the SI overlap:
    # the same operations on the same overlap as the Hertzian laws' `sqrt(delta)`, which XLA then computes
    # once for both (one square root fewer per interface and stage); finite derivatives (double `where`)
    mask, d_safe = _positive_part(stack.overlaps(stack.split(y)[0]))
    inv_f = args.inv_force if args.inv_force is not None else inverse_force_scale(stack, scale)
    # (a law's force is zero for delta <= 0; `maximum` drops an unclamped law's tension)
    root = jnp.where(mask, jnp.sqrt(d_safe), 0.0)
    root = root / jnp.sqrt(scale[0]) if args.inv_root_length is None else root * args.inv_root_length
    z = root + jnp.sqrt(jnp.maximum(f, 0.0) * inv_f + 1e-300)
    return jnp.concatenate([dy, z * stack.interface_mask(), jnp.zeros(1, dy.dtype)])


def _derived(stack: Stack, y):
    """Physical quantities of SI states `(..., 3n)` (a stack of states row by row: the laws see one
    state's `(n,)` interfaces at a time, with no implicit broadcasting)."""
    if y.ndim > 1:
        return jax.vmap(lambda row: _derived(stack, row))(y)
    x, v, diss = stack.split(y)
    q = stack.memory(y)
    d, dd = stack.overlaps(x), stack.overlap_rates(v)
    f = stack.forces(d, dd, q)
    out = dict(
        positions=x, velocities=v, accelerations=stack.accelerations(f, x), overlaps=d,
        overlap_rates=dd, forces=f, dissipated=diss, energy=stack.total_energy(y),
    )
    if q is not None:  # the memory starts at the initial overlap (`Stack.initial_vector`): 0 before a contact
        out["max_overlaps"] = jnp.maximum(q, 0.0)
    return out


def _setup(stack: Stack, state: State, t_max, cfg: _SolveConfig):
    """Scales, the scaled initial state and the scaled end time of a solve."""
    n = stack.n
    sc = _scales(stack, state)
    scale = sc.vector(n, stack.has_memory)
    y0 = stack.initial_vector(state)
    t1 = jnp.where(jnp.isnan(t_max), _default_t_max(stack, state, sc), t_max)
    proxies = jnp.zeros(n if cfg.tolerances.resolve_onsets else 0)
    y0s = jnp.concatenate([y0 / scale, proxies, jnp.zeros(1)])  # `_scaled_field`: [x v D | z | over]
    return sc, scale, y0s, t1 / sc.time


def _lands_onsets(cfg: _SolveConfig, y0s) -> bool:
    """Whether a solve lands its onsets and steps through them in `s` (`Tolerances.land_onsets`): only
    with an unrolled solver (`UnrolledERK`) that writes out the step (a state of at most `UNROLL_MAX_STATE`
    entries)."""
    return (cfg.tolerances.land_onsets and isinstance(cfg.solver, UnrolledERK)
            and y0s.shape[0] <= UNROLL_MAX_STATE)


def _diffeqsolve(stack: Stack, y0s, t1s, scale, T, ts_s, cfg: _SolveConfig, history: bool, audit: bool,
                 land: bool = True):
    """The one call to `diffrax.diffeqsolve` (scaled state and time). Saves, in `sol.ys`/`sol.ts` in
    this order: the accepted steps with `t0` (if `history`), the times `ts_s` (if given), `t1`. `land`:
    whether onsets may be landed (`_lands_onsets`; False for the replayed adjoint, whose replay takes its
    own steps at onsets)."""
    onsets = land and _lands_onsets(cfg, y0s)
    solver = (dataclasses.replace(cfg.solver, onsets=True, window=cfg.tolerances.onset_window) if onsets
              else cfg.solver)
    subs = []
    if history:
        subs.append(dfx.SubSaveAt(t0=True, steps=True))
    if ts_s is not None:
        subs.append(dfx.SubSaveAt(ts=ts_s))
    subs.append(dfx.SubSaveAt(t1=True))
    return dfx.diffeqsolve(
        dfx.ODETerm(_scaled_field),
        _Tracked.around(solver, cfg.adjoint, audit=audit, launch=cfg.until == "launch", durations=cfg.durations),
        t0=0.0,
        t1=t1s,
        dt0=None,  # the controller's `first_step` (`FlightController.init`)
        y0=y0s,
        args=FieldArgs.of(stack, scale, T, y0s[stack.n : 2 * stack.n]),
        saveat=dfx.SaveAt(subs=subs, solver_state=True),
        stepsize_controller=cfg.tolerances.controller(onsets=onsets),
        event=dfx.Event(_cascade_complete) if cfg.until != "t_max" else None,
        max_steps=cfg.max_steps,
        adjoint=cfg.adjoint,
        throw=False,
    )


def _solve_record(sol) -> dict:
    """What every solve reports: final scaled time and state, the contacts' bookkeeping, status, steps.

    The status (`hertz_chain.status.Status`): the event (the cascade is over) or, with `until="t_max"`,
    an accepted point where it was over: complete (with rebounds if a contact closed after it); else
    `t_max` or `max_steps` first: incomplete, or no contact if nothing ever touched; a non-finite state
    is checked in `_launch_outputs`."""
    c = sol.solver_state[1]
    over, rebounds = c.cascade[0] > 0, c.cascade[1] > 0
    touched = jnp.any(c.rows[:, T_IN] >= 0)
    done = jnp.where(rebounds, Status.COMPLETE_WITH_REBOUNDS, Status.COMPLETE)
    # the step budget running out is incomplete even after the cascade ended (with until="t_max": the
    # rebounds up to t_max were asked for; the launch data are still those of the cascade)
    status = jnp.where(
        sol.result == dfx.RESULTS.max_steps_reached, Status.INCOMPLETE_MAX_STEPS,
        jnp.where((sol.result == dfx.RESULTS.event_occurred) | over, done,
                  jnp.where(sol.result == dfx.RESULTS.successful,
                            jnp.where(touched, Status.INCOMPLETE_T_MAX, Status.NO_CONTACT), Status.FAILED)),
    )
    return dict(t_fin=sol.ts[-1][-1], y_fin=sol.ys[-1][-1], contacts=c, status=status,
                num_steps=sol.stats["num_steps"], num_accepted_steps=sol.stats["num_accepted_steps"],
                num_rejected_steps=sol.stats["num_rejected_steps"])


def _launch_outputs(stack: Stack, sc: Scales, scale, core: dict, until: str = "cascade") -> dict:
    """Launch data (in SI) from a solve's `_solve_record` (`_end_of_contacts`, `_launch`). A mass still pushed
    when the cascade ended (mass 1 resting on the ground) is given its velocity then: the final state
    of a solve stopped by the event (`until="cascade"`; it carries the reverse-mode cotangent), the
    velocities kept in `_Contacts.cascade` otherwise."""
    n, n3 = stack.n, stack.state_size
    t_fin = core["t_fin"] * sc.time
    y_fin = core["y_fin"][:n3] * scale
    v_fin = stack.split(y_fin)[1]
    c = core["contacts"]
    over = c.cascade[0] > 0
    t_c, v_c = t_fin, v_fin
    if until == "t_max":
        t_c = jnp.where(over, c.cascade[2] * sc.time, t_fin)
        v_c = jnp.where(over, c.cascade[5:] * scale[n : 2 * n], v_fin)
    t_end_if = _end_of_contacts(stack, c, sc.time, t_c, sc.velocity)
    t_end, v_launch = _launch(stack, c, sc.time, t_end_if, t_c, v_c)
    status = core["status"]
    # a chain held by an end force or a wall never flies apart: its run ends at t_max by design
    # (until="t_max"), and its "launch" velocities are the velocities there
    held = (stack.end_force > 0) | stack.wall
    status = jnp.where((status == Status.INCOMPLETE_T_MAX) & held, Status.COMPLETE, status)
    v_launch = jnp.where(held, v_fin, v_launch)
    t_end = jnp.where(held, t_fin, t_end)
    status = jnp.where(jnp.all(jnp.isfinite(y_fin)) | (status == Status.INCOMPLETE_MAX_STEPS), status,
                       Status.FAILED)
    # a run that ended with a non-finite launch velocity of a mass that was launched (parameters outside
    # what the laws allow, e.g. a negative mass set past `Stack`'s checks) failed: its headline results
    # are not valid (a mass never pushed has no launch, NaN with a NaN launch time, by design: `_launch`)
    # and so did a run of masses no stack may have (not finite and > 0; set past `Stack`'s checks)
    ended = (status == Status.COMPLETE) | (status == Status.COMPLETE_WITH_REBOUNDS)
    broken = jnp.any(jnp.isfinite(t_end) & ~jnp.isfinite(v_launch))
    broken |= ~jnp.all(jnp.isfinite(stack.masses) & (stack.masses > 0))
    status = jnp.where(ended & broken, Status.FAILED, status)
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


def _solve_impl(stack: Stack, state: State, ts, t_max, cfg: _SolveConfig, launch_only: bool = False):
    """One solve's outputs (`_launch_outputs`) and, unless `launch_only` (`launch_velocity`'s path: no energy
    audit, no step history, no grid), the scales, the step history or the audit's results, and the grid."""
    n3 = stack.state_size
    sc, scale, y0s, t1s = _setup(stack, state, t_max, cfg)
    sol = _diffeqsolve(stack, y0s, t1s, scale, sc.time, None if ts is None else ts / sc.time, cfg,
                       history=cfg.save_steps, audit=not launch_only and not cfg.save_steps)
    contacts = sol.solver_state[1]
    out = _launch_outputs(stack, sc, scale, _solve_record(sol), cfg.until)
    if launch_only:
        return out
    out["scales"] = sc
    if cfg.save_steps:  # derived quantities and the energy audit: `_history`, on the rows actually used
        out["history"] = (sol.ys[0][:, :n3], sol.ts[0])
    else:
        out["energy_error"] = contacts.energy[1] / sc.energy
        out["peak_forces"], out["impact_velocities"] = contacts.peaks[PEAK_FORCE], contacts.peaks[V_UPPER_BEFORE]
        # restitution of the interface's first contact: separation over approach speed, both in free flight
        # (relative speeds unchanged by gravity between two falling bodies); NaN without a finished contact
        pk = contacts.peaks
        approach, release = pk[V_LOWER_BEFORE] - pk[V_UPPER_BEFORE], pk[V_UPPER_AFTER] - pk[V_LOWER_AFTER]
        ok = jnp.isfinite(release) & (approach > 1e-12 * sc.velocity)
        out["restitutions"] = jnp.where(ok, release / jnp.where(ok, approach, 1.0), jnp.nan)
        # the first contact of every interface, [first point in it, first point after it] (s; step-resolved)
        out["first_contacts"] = jnp.stack([pk[T_FIRST_IN], pk[T_FIRST_OUT]], axis=-1) * sc.time
        # the top pulse's 10 % duration at the steps (NaN: no pulse, not ended, or a rising edge too long to follow)
        if contacts.pulse is not None:
            duration, rise = _pulse_duration(*contacts.pulse, pk[PEAK_FORCE, -1])
            out["top_duration_10"], out["top_rise_time"] = duration * sc.time, rise * sc.time
    if ts is not None:
        grid = _derived(stack, sol.ys[int(cfg.save_steps)][:, :n3] * scale[None, :])
        grid["t"] = ts
        out["grid"] = grid
    return out


def _solve_plain(stack: Stack, state: State, ts, t_max, cfg: _SolveConfig) -> dict:
    """`_solve_impl` with `Scales` as a dict: only dicts, tuples and arrays, which `jax.export` can keep."""
    out = dict(_solve_impl(stack, state, ts, t_max, cfg))
    out["scales"] = {f.name: getattr(out["scales"], f.name) for f in dataclasses.fields(Scales)}
    return out


# a traced solve is kept on disk where that is exact (`_export`)
_solve = cached_jit(_solve_plain, "simulate._solve", _config.solve_compiler_options)


def _history_impl(stack: Stack, history, sc: Scales, rows: int):
    """Physical quantities and the energy audit of the first `rows` points of a saved step history
    (scaled; points after the solve's end are inf)."""
    ys, ts = history
    steps = _derived(stack, ys[:rows] * sc.vector(stack.n, stack.has_memory)[None, :])
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
