"""Derivatives by replaying the accepted steps: `_replayed_solve`, reverse mode, a discrete adjoint over
the saved accepted states, and `_forward_replayed_solve`, forward mode, the same discrete derivative swept
forward (`hertz_chain.simulation` module docstring, "Gradients")."""

from __future__ import annotations

import warnings

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import _config  # noqa: F401  (float64)
from ._scaling import FieldArgs
from ._solve import _diffeqsolve, _scaled_field, _solve_record
from ._solver import UnrolledERK, _SolveConfig
from ._tracking import DELTA_OUT, T_IN, T_OUT
from .errors import GradientAccuracyWarning, ParameterError
from .registry import SOLVERS

# ==================================================================== reverse mode: replay the accepted steps
# Onsets and releases in the replay (`_Replay`; docs/solver-defaults.md, "Onsets and releases in the replay"). Where a contact closes inside a step,
# the replay splits the step `_ONSET_OVERLAP` (in units of the overlap scale) either side of the onset: far
# above the rounding of an overlap (~1e-13), far below anything the motion resolves. Within `_ONSET_WINDOW`
# (units of the contact time T) after the latest onset `t*`, steps are replayed in
# `s = (t - t*)^(1/_ONSET_POWER)`, each as `_ONSET_SUBSTEPS` solver steps: a damped law's force rises as
# `delta^(1/4)` (Tsuji) or `delta^(1/2)` from the onset, so the motion and its sensitivity are singular in
# `t` there but power series in `s`, and the forward solve's steps, chosen for the motion, are too coarse
# for the sensitivity there. Where a clamped contact's unclamped force changes sign while it overlaps (the
# kink of its force), the step is split where it is zero.
_ONSET_OVERLAP = 1e-11
_ONSET_POWER = 4
_ONSET_WINDOW = 1e-4  # docs/solver-defaults.md: 1e-3 until 2026-11-26, the same accuracy, ~12 % slower
_ONSET_SUBSTEPS = 4
_ONSET_MIN_RATE = 1e-3  # in units of the velocity scale (scaled overlap per scaled time)


def _s_field(s, y, args):
    """The scaled vector field in `s = (t - t*)^(1/p)`: `dy/ds = p s^(p-1) f(t* + s^p, y)`."""
    field_args, t_star = args
    p = _ONSET_POWER
    return p * s ** (p - 1) * _scaled_field(t_star + s**p, y, field_args)


class _Replay(eqx.Module):
    """One accepted step of the forward solve, replayed as a differentiable map of the design, the state
    and the latest onset time `t*` (scaled; `-inf` before the first onset): `(y, t*) -> (y', t*')`.
    Four kinds of step (`vjp`), chosen from the forward solve's states at the step's ends:

    - plain: the solver's step, as diffrax's discrete adjoint replays it;
    - within `_ONSET_WINDOW` of the latest onset: `_ONSET_SUBSTEPS` solver steps in
      `s = (t - t*)^(1/4)` (`in_s`);
    - an onset (a contact open at the step's start and closed at its end, approaching faster than
      `_ONSET_MIN_RATE`): three pieces that each see the contact in one state, so that the discrete
      derivative is that of the motion with its onset (a force that jumps or rises steeply where the
      contact closes; the saltation of the sensitivity):
      1. the solver's step to where the overlap is `-_ONSET_OVERLAP` (none if the step starts closer to
         the onset than that), predicted linearly from the overlap and its rate at the step's start (the
         onset proxy keeps such steps short, ~1e-7 T, so the prediction is off by ~1e-14, far below
         `_ONSET_OVERLAP`); it moves with the design;
      2. an Euler step with the derivative at its start (open) to `+_ONSET_OVERLAP`: the overlap is linear
         in the positions, so it lands there exactly; its length, `2 _ONSET_OVERLAP` over the closing
         speed, is ~1e-11 T; the onset `t*'` (overlap 0) is on it;
      3. the rest of the step in `s = (t - t*')^(1/4)` (every stage sees the contact closed);
      only the first contact to close in a step is split out (two onsets in one accepted step are rare);
    - a release (a clamped contact's unclamped force changes sign while it overlaps: the kink of its
      force at `F = 0`): two solver steps that meet where that force is zero, found by one secant step
      from the linear guess (its derivative is the implicit function theorem's).

    - a turn (a law with memory, `memory`: a contact whose overlap rate changes sign from loading to
      unloading inside the step, the kink of an elastic–plastic force where the stiffer unloading curve
      takes over): two solver steps that meet where the overlap rate is zero, found as a release's split.

    `split`: whether the onsets, windows and releases apply at all. Where every law's onset is smooth
    (`registry.LawRow.smooth_onset`: Hertz, Hunt–Crossley) every step is plain, releases of a clamped
    contact included: the solver's steps resolve them (within 1e-6 of central differences,
    `benchmarks/optimize.md`) and the gradient costs what it did before the split (`_smooth_onsets`).
    """

    stack_static: object
    scale: jax.Array
    T: jax.Array
    solver: object
    mask: jax.Array
    clamped: jax.Array
    n: int = eqx.field(static=True)
    split: bool = eqx.field(static=True, default=True)
    memory: bool = eqx.field(static=True, default=False)

    def _args(self, dyn):
        return FieldArgs.of(eqx.combine(dyn, self.stack_static), self.scale, self.T)  # the divisors as factors

    def _overlaps(self, y):
        """Scaled overlaps (in units of the overlap scale, the positions' scale) of a scaled state, or
        their rates from a scaled derivative (`Stack.overlaps`: linear in the positions)."""
        return self.stack_static.overlaps(y[: self.n])

    def _solver_step(self, term, y, a, b, args, rolled: str | None = None):
        """The new state of one step of the forward solve's solver; `rolled` (a diffrax `scan_kind`): the
        same method with its stages in diffrax's loop (`_rolled`)."""
        solver = self.solver if rolled is None else _rolled(self.solver, rolled)
        return solver.step(term, a, b, y, args, solver.init(term, a, b, y, args), False)[0]

    def in_s(self, dyn, y, sa, sb, t_star, rolled: str | None = None):
        """`_ONSET_SUBSTEPS` solver steps in `s` from `sa` to `sb` (`_s_field`)."""
        args, term = (self._args(dyn), t_star), dfx.ODETerm(_s_field)
        ds = (sb - sa) / _ONSET_SUBSTEPS
        return jax.lax.fori_loop(
            0, _ONSET_SUBSTEPS, lambda i, y: self._solver_step(term, y, sa + i * ds, sa + (i + 1) * ds, args, rolled),
            y)

    def approach(self, dyn, y, t):
        """Every interface's scaled overlap and its rate at a state (`(2, n)`)."""
        return jnp.stack([self._overlaps(y), self._overlaps(_scaled_field(t, y, self._args(dyn)))])

    def onset(self, dyn, y0, t0, t1, t_star, j, rolled: str | None = None):
        """The step `t0 -> t1` in which contact `j` closes: `(y', t*')` (class docstring)."""
        eps, h = _ONSET_OVERLAP, t1 - t0
        d0, rate0 = self.approach(dyn, y0, t0)[:, j]
        tau_a = jnp.where(d0 < -eps, jnp.clip((-eps - d0) / jnp.where(rate0 > 0, rate0, 1.0), 0.0, h), 0.0)
        ya = self._solver_step(dfx.ODETerm(_scaled_field), y0, t0, t0 + tau_a, self._args(dyn), rolled)
        f = _scaled_field(t0 + tau_a, ya, self._args(dyn))
        rate = self._overlaps(f)[j]  # the closing interface's scaled overlap rate (> 0)
        rate = jnp.where(rate > 0, rate, 1.0)
        da = self._overlaps(ya)[j]
        tau_star = tau_a - da / rate  # the onset, from t0
        tau_b = jnp.minimum(tau_a + (eps - da) / rate, h)
        yb = ya + (tau_b - tau_a) * f
        sa = jnp.maximum(tau_b - tau_star, 0.0) ** (1.0 / _ONSET_POWER)
        sb = jnp.maximum(h - tau_star, 0.0) ** (1.0 / _ONSET_POWER)
        new_star = t0 + tau_star
        return self.in_s(dyn, yb, sa, sb, new_star, rolled), new_star

    def closing(self, y0, y1, h):
        """Whether a contact closes between two accepted states of the forward solve `h` apart (open at
        the first, closed at the second, approaching at more than `_ONSET_MIN_RATE`: a gentler closing
        is smooth enough for the plain step) and the first to close, by a linear guess."""
        d0, d1 = self._overlaps(y0), self._overlaps(y1)
        closes = self.mask & (d0 <= 0) & (d1 > 0) & (d1 - d0 > _ONSET_MIN_RATE * h)
        frac = jnp.where(closes, d0 / jnp.where(closes, d0 - d1, 1.0), jnp.inf)
        return jnp.any(closes), jnp.argmin(frac)

    def classify(self, dyn, ts, ys, N):
        """Every step's kind (class docstring), without gradients, vectorised over the history (no loop):
        `(kind, j, jr, t*, F)`, per step `k = 1..len(ts) - 1` at index `k - 1`: the kind (0 plain, 1 in
        the window, 2 onset, 3 release), the contact that closes and the one that lets go, the latest
        onset time at the step's start (`-inf` before the first; the primal `t*` the reverse sweep
        linearises at: `onset`'s prediction from the step's start, the same to third order in the step),
        and every row's unclamped forces."""
        dyn = jax.lax.stop_gradient(dyn)
        y0, y1, t0, t1 = ys[:-1], ys[1:], ts[:-1], ts[1:]
        steps = jnp.arange(1, ts.shape[0]) <= N
        closes, j = jax.vmap(self.closing)(y0, y1, t1 - t0)
        closes &= steps & self.split  # onsets, windows and releases: only where a law's onset is not smooth

        def onset_at(y, t, t_end, jj):
            d, rate = self.approach(dyn, y, t)[:, jj]
            return jnp.clip(t + jnp.where(d < 0, -d / jnp.where(rate > 0, rate, 1.0), 0.0), t, t_end)

        onsets = jnp.where(closes, jax.vmap(onset_at)(y0, jnp.where(steps, t0, 0.0), jnp.where(steps, t1, 0.0), j),
                           -jnp.inf)
        # each onset lies in its own step (clipped there), so they only move forward in time: the latest
        # before step k is a running maximum over the steps before it
        star = jnp.concatenate([jnp.full(1, -jnp.inf), jax.lax.cummax(onsets)[:-1]])
        window = jnp.isfinite(star) & (t0 - star < _ONSET_WINDOW) & self.split
        finite = jnp.where(jnp.isfinite(ys), ys, 0.0)
        F = jax.vmap(lambda y: jnp.stack([self.unclamped(dyn, y), self.rates(y)]))(finite)
        d = jax.vmap(self._overlaps)(ys)
        inside = self.mask[None, :] & (d[:-1] > 0) & (d[1:] > 0) & steps[:, None]
        kink = inside & self.clamped[None, :] & (jnp.sign(F[:-1, 0]) * jnp.sign(F[1:, 0]) < 0) & self.split
        kind = jnp.where(closes, 2, jnp.where(window, 1, jnp.where(jnp.any(kink, axis=1), 3, 0)))
        jr = jnp.argmax(kink, axis=1)
        if self.memory:  # a contact with memory turns from loading to unloading (its rate changes sign)
            turn = inside & (F[:-1, 1] > 0) & (F[1:, 1] < 0)
            kind = jnp.where((kind == 0) & jnp.any(turn, axis=1), 4, kind)
            jr = jnp.where(kind == 4, jnp.argmax(turn, axis=1), jr)
        return kind, j, jr, star, F

    def _branches(self, t0, t1, kind, j, jr, f0, f1, rolled: str | None) -> list:
        """The replays `(dyn, y, t*) -> (y', t*')` of the step `t0 -> t1`, one per kind this replay has
        (class docstring: the window, onset and release with `split`, the turn with `memory`, a release and
        a turn in one branch; `_index` maps a kind to its position): `kind`, `j`, `jr`, `f0`, `f1` from
        `classify`; `rolled`: the `scan_kind` of the onsets' and the kinks' steps (`_rolled`), the
        rarest kinds, for the laws with memory (`vjp`, `jvp`): written out, with a memory law's field,
        they made most of the compiled derivative (Thornton's gradient compiled in ~31 s, ~16 s rolled);
        for the other laws they stay written out (rolled, a Tsuji gradient ran 13-17 % slower in
        `benchmarks/run.py`), as do the windows' steps."""

        def plain(d, y, ts):
            return self._solver_step(dfx.ODETerm(_scaled_field), y, t0, t1, self._args(d)), ts

        def in_window(d, y, ts):
            sa, sb = (jnp.maximum(t - ts, 0.0) ** (1.0 / _ONSET_POWER) for t in (t0, t1))
            return self.in_s(d, y, sa, sb, ts), ts  # written out: the most frequent of the rare kinds

        def onset(d, y, ts):
            return self.onset(d, y, t0, t1, ts, j, rolled)

        def kink(d, y, ts):
            # a release: split where the unclamped force is zero (the clamp's kink); a turn: a contact with
            # memory turns from loading to unloading where its overlap rate is zero (the kink of its force: the
            # unloading curve is stiffer), split there the same way (one branch: one compiled copy)
            if not self.memory:
                return split_where(d, y, ts, lambda d, y: self.unclamped(d, y)[jr], f0[0, jr], f1[0, jr])
            if not self.split:
                return split_where(d, y, ts, lambda d, y: self.rates(y)[jr], f0[1, jr], f1[1, jr])
            row = jnp.where(kind == 4, 1, 0)
            g = lambda d, y: jnp.where(row == 1, self.rates(y)[jr], self.unclamped(d, y)[jr])  # noqa: E731
            return split_where(d, y, ts, g, f0[row, jr], f1[row, jr])

        def split_where(d, y, ts, g, g0, g1):
            # two solver steps that meet where `g` (linear between the step's ends, `g0`, `g1`) is zero, by one
            # secant step from the linear guess, whose derivative is the implicit function theorem's (the
            # slope is the step's, without gradient)
            term, args, h = dfx.ODETerm(_scaled_field), self._args(d), t1 - t0
            slope = jax.lax.stop_gradient(g1 - g0)
            th0 = jax.lax.stop_gradient(jnp.clip(g0 / -slope, 0.0, 1.0))
            th = th0 - g(d, self._solver_step(term, y, t0, t0 + th0 * h, args, rolled)) / slope
            ta = t0 + jnp.clip(th, 0.0, 1.0) * h
            ya = self._solver_step(term, y, t0, ta, args, rolled)
            return self._solver_step(term, ya, ta, t1, args, rolled), ts

        return [plain] + ([in_window, onset] if self.split else []) + ([kink] if self.split or self.memory else [])

    def _index(self, kind):
        """The position in `_branches` of a step of kind `kind` (0 plain, 1 in an onset window, 2 onset,
        3 release, 4 turn; the last two one branch)."""
        return jnp.minimum(kind, 3) if self.split else jnp.where(kind == 4, 1, 0)

    def vjp(self, cotangents, dyn, y0, t_star, t0, t1, kind, j, jr, f0, f1):
        """The step's vector-Jacobian product: `cotangents = (lambda_y, lambda_t*)` of `(y', t*')` to those
        of `(dyn, y0, t*)`. The kind of step (class docstring) comes from `classify`, outside the
        differentiation, so a plain step costs what it did before onsets were treated; `f0`, `f1`: the
        unclamped forces and the overlap rates at the step's ends (`(2, n)`, from `classify`)."""
        fns = self._branches(t0, t1, kind, j, jr, f0, f1, "checkpointed" if self.memory else None)
        if len(fns) == 1:
            return jax.vjp(fns[0], dyn, y0, t_star)[1](cotangents)
        return jax.lax.switch(self._index(kind), [lambda fn=fn: jax.vjp(fn, dyn, y0, t_star)[1](cotangents)
                                                  for fn in fns])

    def jvp(self, tangents, dyn, y0, t_star, t0, t1, kind, j, jr, f0, f1):
        """The step's Jacobian-vector product: `tangents = (dyn_dot, y_dot, t*_dot)` of `(dyn, y0, t*)` to
        those of `(y', t*')` (the forward counterpart of `vjp`: the same replays)."""
        fns = self._branches(t0, t1, kind, j, jr, f0, f1, "lax" if self.memory else None)
        if len(fns) == 1:
            return jax.jvp(fns[0], (dyn, y0, t_star), tangents)[1]
        return jax.lax.switch(self._index(kind), [lambda fn=fn: jax.jvp(fn, (dyn, y0, t_star), tangents)[1]
                                                  for fn in fns])

    def rates(self, y):
        """Every interface's scaled overlap rate at a scaled state (in units of the velocity scale)."""
        return self._overlaps(y[self.n : 2 * self.n])

    def unclamped(self, dyn, y):
        """Every interface's unclamped force (`Stack.unclamped_forces`, N) at a scaled state."""
        stack = eqx.combine(dyn, self.stack_static)
        Y = y * self.scale
        x, v, _ = stack.split(Y)
        return stack.unclamped_forces(stack.overlaps(x), stack.overlap_rates(v), stack.memory(Y))


def _rolled(solver, scan_kind: str):
    """diffrax's own solver of an `UnrolledERK`'s method (`stock`: its stages in a loop, so that the
    compiled program holds one copy of the vector field per step rather than one per stage), with
    `scan_kind` (`"checkpointed"` for reverse mode, `"lax"` for forward mode); any other solver itself.
    The same arithmetic to rounding."""
    return solver.stock(scan_kind=scan_kind) if isinstance(solver, UnrolledERK) else solver


def _smooth_onsets(stack) -> bool:
    """Whether every contact law of `stack` has a smooth onset (`registry.LawRow.smooth_onset`; the far
    wall's contact is elastic Hertz)."""
    from .registry import LAWS

    smooth = {row.cls for row in LAWS.values() if row.smooth_onset}
    return all(type(law).__name__ in smooth for law in stack.laws)


@eqx.filter_custom_vjp
def _replayed_solve(diff, t1s, scale, T, cfg: _SolveConfig) -> dict:
    """`_solve_record` of the solve from `diff = (stack, y0s)`, differentiable in reverse mode by a discrete
    adjoint over the accepted steps (`_replay_bwd`). Undifferentiated, it is the lean solve, landing its
    onsets (`Tolerances.land_onsets`); differentiated, the solve does not land them (the replay takes its own
    steps at onsets), so its value can differ from the undifferentiated one within the tolerance."""
    stack, y0s = diff
    return _solve_record(_diffeqsolve(stack, y0s, t1s, scale, T, None, cfg, history=False, audit=False))


def _history(diff, t1s, scale, T, cfg: _SolveConfig):
    """The solve with its history of accepted steps, not landing onsets (the replay takes its own steps
    there): `(core, (ts, ys, idx, valid))`, `core` its `_solve_record`; per interface, `idx` the history
    index of the point recorded in `_Contacts.rows` (the first accepted point after its last contact),
    found by its time (the same float), and `valid` whether there is one."""
    stack, y0s = diff
    sol = _diffeqsolve(stack, y0s, t1s, scale, T, None, cfg, history=True, audit=False, land=False)
    core = _solve_record(sol)
    c = core["contacts"]
    match = sol.ts[0][None, :] == c.rows[:, T_OUT : T_OUT + 1]
    idx, valid = jnp.argmax(match, axis=1), (c.rows[:, T_IN] >= 0) & ~c.now & jnp.any(match, axis=1)
    return core, (sol.ts[0], sol.ys[0], idx, valid)


def _replay_of(stack, scale, T, cfg: _SolveConfig):
    """`(dyn, replay)`: the differentiable part of `stack` and its `_Replay`. Warns
    (`GradientAccuracyWarning`, when the derivative is traced) for a law with a `gradient_note`; raises
    `ParameterError` for a law with `gradient_refused` (Jackson–Green) and for an implicit solver."""
    if not isinstance(cfg.solver, (UnrolledERK, dfx.AbstractERK)):
        # an implicit step replayed inside a derivative: its Newton iteration differentiated as it runs
        name = type(cfg.solver).__name__  # its name in `registry.SOLVERS` where it has one ('kvaerno5')
        name = name.lower() if name.lower() in SOLVERS else name
        raise ParameterError("solver", name, "an explicit Runge-Kutta solver (e.g. tsit5, dopri5, dopri8) for "
                             "derivatives: through kvaerno5 a review measured 13-19 % "
                             "off central differences (viscoelastic, 1 mm gaps, gravity) and its forward mode fails")
    for law in {type(law): law for law in stack.laws}.values():
        if law.gradient_refused:
            raise ParameterError("contact law", law.name, f"derivatives through it are refused: {law.gradient_note}; "
                                 "take central differences of solves instead")
        if law.gradient_note:
            warnings.warn(f"derivatives through the {law.name} contact law: {law.gradient_note}; check them "
                          "against differences", GradientAccuracyWarning, stacklevel=2)
    dyn, static = eqx.partition(stack, eqx.is_inexact_array)
    return dyn, _Replay(static, scale, T, cfg.solver, stack.interface_mask(), jnp.asarray(stack.clamped()),
                        stack.n, split=not _smooth_onsets(stack), memory=stack.has_memory)


def _kinds(replay: _Replay, dyn, hist_t, ys, N):
    """`replay.classify`, or every step plain where nothing is split."""
    if replay.split or replay.memory:
        return replay.classify(dyn, hist_t, ys, N)
    zeros = jnp.zeros(hist_t.shape[0] - 1, int)
    return zeros, zeros, zeros, jnp.full(hist_t.shape[0] - 1, -jnp.inf), jnp.zeros((hist_t.shape[0], 2, replay.n))


def _at_rows(stack, scale, n3):
    """The state-dependent columns of `_Contacts.rows` (overlap, its rate, the lower and upper bodies'
    velocities, and with a law with memory its memory: columns `DELTA_OUT` on) of each interface `j` at the
    scaled state `Y[j]` (linear in it). The memory reaches the launch through the contact's end time
    (`_end_of_contacts`), and that through gravity (`v + g (t_r - t_end)`)."""

    def at_rows(Y):
        Y = Y[:, :n3] * scale[None, :]
        x, v, _ = stack.split(Y)
        v_lo = jnp.concatenate([jnp.zeros(1, v.dtype), jnp.diagonal(v, offset=-1)])
        cols = (jnp.diagonal(stack.overlaps(x)), jnp.diagonal(stack.overlap_rates(v)), v_lo, jnp.diagonal(v))
        return cols + ((jnp.diagonal(stack.memory(Y)),) if stack.has_memory else ())

    return at_rows


@_replayed_solve.def_fwd
def _replay_fwd(perturbed, diff, t1s, scale, T, cfg: _SolveConfig):
    del perturbed
    return _history(diff, t1s, scale, T, cfg)


@_replayed_solve.def_bwd
def _replay_bwd(residuals, g, perturbed, diff, t1s, scale, T, cfg: _SolveConfig):
    """Reverse sweep over the accepted steps `y_k = Phi(y_{k-1}; t_{k-1}, t_k, stack)`: with the step
    times frozen (as diffrax's controller does in reverse mode: it stops gradients through the step size),
    `lambda_{k-1} = (dPhi/dy)^T lambda_k + (cotangent of y_{k-1})` and `stack_bar += (dPhi/dstack)^T
    lambda_k`, each step's vector-Jacobian product by `jax.vjp` of its replay (`_Replay`: the solver's
    own step, or, where a contact closes or a clamped contact lets go inside it or an onset is recent, the
    step in pieces that see how those move; the latest onset time `t*` is carried with `lambda`). The
    outputs that depend on the state are the final state and, per interface, the overlap, its rate and
    the two bodies' velocities at the first accepted point after the last contact (`_Contacts.rows`);
    the step times carry no gradient."""
    del perturbed
    hist_t, hist_y, idx, valid = residuals
    stack, y0s = diff
    n3 = stack.state_size
    N = jnp.sum(jnp.isfinite(hist_t)) - 1  # accepted steps: rows 0..N of the history are finite
    ct_hist = jnp.zeros_like(hist_y)
    if g["y_fin"] is not None:
        ct_hist = ct_hist.at[N].add(g["y_fin"])
    rows_ct = g["contacts"].rows
    if rows_ct is not None:  # overlap, rate, velocities (memory) at the recorded point: linear in that state
        _, vjp = jax.vjp(_at_rows(stack, scale, n3), hist_y[idx])
        (ct_Y,) = vjp(tuple(rows_ct[:, c] for c in range(DELTA_OUT, rows_ct.shape[1])))
        ct_hist = ct_hist.at[idx].add(jnp.where(valid[:, None], ct_Y, 0.0))
    dyn, replay = _replay_of(stack, scale, T, cfg)
    # The onset proxies (`resolve_onsets`, entries state_size:) feed nothing back into the motion and no output
    # depends on them: replay the physical equations only (the same arithmetic, component by component).
    ct_hist, ys = ct_hist[:, :n3], hist_y[:, :n3]
    kinds, js, jrs, stars, F = _kinds(replay, dyn, hist_t, ys, N)

    def body(i, carry):
        lam, lam_star, acc = carry
        k = N - i
        g_dyn, g_y, g_star = replay.vjp((lam, lam_star), dyn, ys[k - 1], stars[k - 1], hist_t[k - 1], hist_t[k],
                                        kinds[k - 1], js[k - 1], jrs[k - 1], F[k - 1], F[k])
        return g_y + ct_hist[k - 1], g_star, jax.tree.map(jnp.add, acc, g_dyn)

    lam, _, acc = jax.lax.fori_loop(0, N, body, (ct_hist[N], jnp.zeros(()), jax.tree.map(jnp.zeros_like, dyn)))
    return acc, jnp.zeros_like(y0s).at[:n3].set(lam)


# ==================================================================== forward mode: replay the accepted steps
@eqx.filter_custom_jvp
def _forward_replayed_solve(diff, t1s, scale, T, cfg: _SolveConfig) -> dict:
    """`_solve_record` of the solve from `diff = (stack, y0s)`, differentiable in forward mode
    (`jax.jvp`, `jax.jacfwd`; `launch_velocity(adjoint="forward")`) by replaying the accepted steps
    forward (`_forward_jvp`): the tangent of the same discrete solve as the reverse mode's
    (`_replayed_solve`), onsets and releases split out of the steps as there. Undifferentiated, the lean
    solve."""
    stack, y0s = diff
    return _solve_record(_diffeqsolve(stack, y0s, t1s, scale, T, None, cfg, history=False, audit=False))


@_forward_replayed_solve.def_jvp
def _forward_jvp(primals, tangents):
    """Forward sweep over the accepted steps `y_k = Phi(y_{k-1}; t_{k-1}, t_k, stack)` with the step times
    frozen (as `_replay_bwd`): `y_dot_k = (dPhi/dy) y_dot_{k-1} + (dPhi/dstack) stack_dot`, each step's
    Jacobian-vector product by `jax.jvp` of its replay (`_Replay.jvp`; the latest onset time `t*` is
    carried with the tangent). The outputs' tangents are those the reverse mode's cotangents reach: the
    final state's physical part, and per interface the overlap, its rate and the two bodies' velocities
    at the first accepted point after its last contact; every other output has a zero tangent (the step
    times, the statuses and counts carry no derivative)."""
    diff, t1s, scale, T, cfg = primals
    (t_stack, t_y0s) = tangents[0]
    stack, y0s = diff
    core, (hist_t, hist_y, idx, valid) = _history(diff, t1s, scale, T, cfg)
    n3 = stack.state_size
    N = jnp.sum(jnp.isfinite(hist_t)) - 1  # accepted steps: rows 0..N of the history are finite
    dyn, replay = _replay_of(stack, scale, T, cfg)
    # a parameter that is not differentiated has no tangent (None): a zero one
    t_dyn = jax.tree.map(lambda p, t: jnp.zeros_like(p) if t is None else t, dyn,
                         eqx.filter(t_stack, eqx.is_array) if t_stack is not None else jax.tree.map(lambda _: None, dyn),
                         is_leaf=lambda x: x is None)
    ty0 = jnp.zeros(n3, y0s.dtype) if t_y0s is None else t_y0s[:n3]
    ys = hist_y[:, :n3]
    kinds, js, jrs, stars, F = _kinds(replay, dyn, hist_t, ys, N)
    at_idx = jnp.where((idx == 0)[:, None], ty0[None, :], 0.0)  # each interface's recorded point's tangent

    def body(k, carry):
        ty, tstar, at_idx = carry
        ty, tstar = replay.jvp((t_dyn, ty, tstar), dyn, ys[k - 1], stars[k - 1], hist_t[k - 1], hist_t[k],
                               kinds[k - 1], js[k - 1], jrs[k - 1], F[k - 1], F[k])
        return ty, tstar, jnp.where((idx == k)[:, None], ty[None, :], at_idx)

    ty, _, at_idx = jax.lax.fori_loop(1, N + 1, body, (ty0, jnp.zeros(()), at_idx))
    t_core = jax.tree.map(lambda x: jnp.zeros_like(x) if jnp.issubdtype(x.dtype, jnp.inexact)
                          else np.zeros(x.shape, jax.dtypes.float0), core)
    t_core["y_fin"] = jnp.zeros_like(core["y_fin"]).at[:n3].set(ty)
    _, cols = jax.jvp(_at_rows(stack, scale, n3), (hist_y[idx][:, :n3],), (at_idx,))
    rows = t_core["contacts"].rows
    for c, col in zip(range(DELTA_OUT, rows.shape[1]), cols):
        rows = rows.at[:, c].set(jnp.where(valid, col, 0.0))
    t_core["contacts"] = eqx.tree_at(lambda c: c.rows, t_core["contacts"], rows)
    return core, t_core
