"""Reverse mode by replaying the accepted steps: `_replayed_solve`, a discrete adjoint over the saved
accepted states (`hertz_chain.simulation` module docstring, "Gradients")."""

from __future__ import annotations

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp

from . import _config  # noqa: F401  (float64)
from ._scaling import FieldArgs
from ._solve import _diffeqsolve, _scaled_field, _solve_record
from ._solver import _SolveConfig
from ._tracking import T_IN, T_OUT

# ==================================================================== reverse mode: replay the accepted steps
@eqx.filter_custom_vjp
def _replayed_solve(diff, t1s, scale, T, cfg: _SolveConfig) -> dict:
    """`_solve_record` of the solve from `diff = (stack, y0s)`, differentiable in reverse mode by a discrete
    adjoint over the accepted steps (`_replay_bwd`). Undifferentiated, it is the lean solve."""
    stack, y0s = diff
    return _solve_record(_diffeqsolve(stack, y0s, t1s, scale, T, None, cfg, history=False, audit=False))


@_replayed_solve.def_fwd
def _replay_fwd(perturbed, diff, t1s, scale, T, cfg: _SolveConfig):
    del perturbed
    stack, y0s = diff
    sol = _diffeqsolve(stack, y0s, t1s, scale, T, None, cfg, history=True, audit=False)
    core = _solve_record(sol)
    # per interface: the history index of the point recorded in `_Contacts.rows` (the first accepted
    # point after its last contact), found by its time (the same float), and whether there is one
    c = core["contacts"]
    match = sol.ts[0][None, :] == c.rows[:, T_OUT : T_OUT + 1]
    idx, valid = jnp.argmax(match, axis=1), (c.rows[:, T_IN] >= 0) & ~c.now & jnp.any(match, axis=1)
    return core, (sol.ts[0], sol.ys[0], idx, valid)


@_replayed_solve.def_bwd
def _replay_bwd(residuals, g, perturbed, diff, t1s, scale, T, cfg: _SolveConfig):
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
    n3 = stack.state_size
    N = jnp.sum(jnp.isfinite(hist_t)) - 1  # accepted steps: rows 0..N of the history are finite
    ct_hist = jnp.zeros_like(hist_y)
    if g["y_fin"] is not None:
        ct_hist = ct_hist.at[N].add(g["y_fin"])
    rows_ct = g["contacts"].rows
    if rows_ct is not None:  # overlap, rate and velocities at the recorded point: linear in that state
        def at_rows(Y):
            x, v, _ = stack.split(Y[:, :n3] * scale[None, :])
            v_lo = jnp.concatenate([jnp.zeros(1, v.dtype), jnp.diagonal(v, offset=-1)])
            return (jnp.diagonal(stack.overlaps(x)), jnp.diagonal(stack.overlap_rates(v)), v_lo,
                    jnp.diagonal(v))

        _, vjp = jax.vjp(at_rows, hist_y[idx])
        (ct_Y,) = vjp((rows_ct[:, 2], rows_ct[:, 3], rows_ct[:, 4], rows_ct[:, 5]))
        ct_hist = ct_hist.at[idx].add(jnp.where(valid[:, None], ct_Y, 0.0))
    dyn, static = eqx.partition(stack, eqx.is_inexact_array)
    terms, solver = dfx.ODETerm(_scaled_field), cfg.solver

    def step(dyn, y, t0, t1):
        args = FieldArgs(eqx.combine(dyn, static), scale, T)
        return solver.step(terms, t0, t1, y, args, solver.init(terms, t0, t1, y, args), False)[0]

    # The onset proxies (`resolve_onsets`, entries state_size:) feed nothing back into the motion and no output
    # depends on them: replay the physical equations only (the same arithmetic, component by component).
    ct_hist = ct_hist[:, :n3]

    def body(i, carry):
        lam, acc = carry
        k = N - i
        _, vjp = jax.vjp(lambda d, y: step(d, y, hist_t[k - 1], hist_t[k]), dyn, hist_y[k - 1, :n3])
        g_dyn, g_y = vjp(lam)
        return g_y + ct_hist[k - 1], jax.tree.map(jnp.add, acc, g_dyn)

    lam, acc = jax.lax.fori_loop(0, N, body, (ct_hist[N], jax.tree.map(jnp.zeros_like, dyn)))
    return acc, jnp.zeros_like(y0s).at[:n3].set(lam)
