"""Compiled baselines of project issue 22: what an expert user would pick instead of hertz_chain.

The same equations as the library (a stack of masses with Hertz or clamped Tsuji contacts, the scaled
state `[x, v, D]` of `hertz_chain.simulation`'s docstring, g = 0, the benchmark cases of `cases.py`), written
as a numba `@njit` right-hand side, checked against the library's own scaled vector field at random states
(to 1e-12), and integrated by

- scipy `solve_ivp` (DOP853, LSODA, Radau) with the numba right-hand side (and a numba Jacobian for the
  implicit methods);
- numbalsoda (compiled LSODA with a numba cfunc), when it installs from the registry (it ships as source
  only and must build its C++ core: `NUMBALSODA` says whether it did);
- a plain numba Tsit5 loop with the library's step-size controller (diffrax's `PIDController` with
  `pcoeff = 0.4`, `icoeff = 0.3`, the library's first and largest steps, the same RMS error norm, the
  flight bound), the compiled-code floor. It does not land contact onsets on step ends
  (`Tolerances.land_onsets`, on by default in the library): at the same rtol it takes more steps (15-25 %
  at 1e-10) and, across an onset, can be less accurate; so the single solves are compared at matched
  accuracy, and the cost per step is reported beside them (`per_step_us_at_1e-10`). At rtol 1e-10 it gives
  the library's launch velocity to ~1e-9.

Every method runs to the reference solution's end time (`t_final` of a tight library solve: with g = 0
every velocity is constant after it, so the top mass's velocity there is its launch velocity, as in
`methods.ScipyCase`). The matched-accuracy rule is `methods.find_matched` at a relative error of 1e-7
on the top launch velocity. `python benchmarks/baselines.py --output benchmarks/baselines.md` (part of
`make bench`); `--quick` for one case.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit, prange
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cases  # noqa: E402
from methods import (  # noqa: E402
    MAX_STEP, DiffraxCase, fine_grid, find_matched, interleaved_medians, median_time, rel_err, steps_budget,
)

import hertz_chain as hc  # noqa: E402
from hertz_chain._scaling import FieldArgs  # noqa: E402
from hertz_chain.simulation import _scaled_field, _scales  # noqa: E402

MATCH = 1e-7
FIRST_STEP = hc.Tolerances().first_step  # scaled units, the library default


# ============================================================================ the equations, in numba
@njit(cache=True)
def field_factors(m, scale, T):
    """The field's per-solve divisors as factors (`field_into`'s `fac`, `(5, n)`): rows `T v_s / x_s`,
    `T / (m v_s)`, `T / D_s` per mass, `1 / F_s` per interface (`F_s = m*_j V^2 / L`), and `1 / L` (row 4,
    entry 0). Computed once per solve, as the library's `FieldArgs.of` does: a division costs several
    multiplications, so the floor gets the same saving."""
    n = m.shape[0]
    fac = np.zeros((5, n))
    for i in range(n):
        fac[0, i] = T * scale[n + i] / scale[i]
        fac[1, i] = T / (m[i] * scale[n + i])
        fac[2, i] = T / scale[2 * n + i]
        mu = m[0] if i == 0 else m[i - 1] * m[i] / (m[i - 1] + m[i])
        fac[3, i] = scale[0] / (mu * scale[n] * scale[n])
    fac[4, 0] = 1.0 / scale[0]
    return fac


@njit(cache=True)
def field_into(out, f, fel, dd, ys, m, k, c, ground, scale, fac):
    """The scaled vector field of a stack (`hertz_chain._solve._scaled_field`) written into `out`, for a
    state of `3n` entries `[x, v, D]` or, with the library's onset proxies (`Tolerances.resolve_onsets`,
    its default), `4n` entries `[x, v, D, z]` with `z_j' = sqrt(max(delta_j, 0) / L) + sqrt(F_j / F_s)`,
    `F_s = m*_j V^2 / L`: Hertz `k d^1.5`
    plus Tsuji damping `c d^0.25 d'` (c = eta sqrt(m_eff k); 0 for Hertz), clamped >= 0. `f`, `fel`, `dd`
    are scratch arrays of length n; `fac`: `field_factors`. The flag entry of the library's state (no
    dynamics) is left out."""
    n = m.shape[0]
    proxy = ys.shape[0] == 4 * n
    for j in range(n):
        if j == 0:
            d = -ys[0] * scale[0] if ground else 0.0
            r = -ys[n] * scale[n] if ground else 0.0
        else:
            d = ys[j - 1] * scale[j - 1] - ys[j] * scale[j]
            r = ys[n + j - 1] * scale[n + j - 1] - ys[n + j] * scale[n + j]
        dd[j] = r
        f[j] = 0.0
        fel[j] = 0.0
        if d > 0.0:
            el = k[j] * d * math.sqrt(d)
            fj = el + c[j] * math.sqrt(math.sqrt(d)) * r
            fel[j] = el
            f[j] = fj if fj > 0.0 else 0.0
        if proxy:
            on = ground or j > 0
            out[3 * n + j] = (math.sqrt((d if d > 0.0 else 0.0) * fac[4, 0] + 1e-300)
                              + math.sqrt(f[j] * fac[3, j] + 1e-300)) if on else 0.0
    for i in range(n):
        above = f[i + 1] if i + 1 < n else 0.0
        out[i] = ys[n + i] * fac[0, i]
        out[n + i] = (f[i] - above) * fac[1, i]
        out[2 * n + i] = (f[i] - fel[i]) * dd[i] * fac[2, i]


@njit(cache=True)
def field(ys, m, k, c, ground, scale, T):
    """`field_into` returning a new array (for scipy and the checks)."""
    n = m.shape[0]
    out = np.empty(ys.shape[0])
    field_into(out, np.empty(n), np.empty(n), np.empty(n), ys, m, k, c, ground, scale, field_factors(m, scale, T))
    return out


@njit(cache=True)
def jacobian(ys, m, k, c, ground, scale, T):
    """Central differences of `field` (the implicit methods' Jacobian; step 1e-7 of the scaled state)."""
    n3 = ys.shape[0]
    J = np.empty((n3, n3))
    for i in range(n3):
        h = 1e-7 * max(1.0, abs(ys[i]))
        yp = ys.copy()
        ym = ys.copy()
        yp[i] += h
        ym[i] -= h
        J[:, i] = (field(yp, m, k, c, ground, scale, T) - field(ym, m, k, c, ground, scale, T)) / (2 * h)
    return J


def _tableau():
    """Tsit5 (Tsitouras 2011) as diffrax holds it (`diffrax.Tsit5.tableau`): the stage matrix `A` (7 x 7,
    row 6 = the solution weights, as the method's last stage is the new state), `B` and the error
    weights `E`."""
    import diffrax as dfx

    tab = dfx.Tsit5.tableau
    A = np.zeros((7, 7))
    for i, row in enumerate(tab.a_lower):
        A[i + 1, : len(row)] = np.asarray(row, dtype=float)
    return A, np.asarray(tab.b_sol, dtype=float), np.asarray(tab.b_error, dtype=float)


_A, _B, _E = _tableau()


FLIGHT_FRACTION = hc.Tolerances().flight_fraction


@njit(cache=True)
def flight_limit(y, n, ground, scale, T, max_step):
    """The library's largest step (`hertz_chain._solver.flight_limit`) for these cases (no gravity, no end
    force, no wall: free masses keep their velocities): `max(max_step, f * min_j (-delta_j / delta_dot_j))`
    over the closing gaps while every interface is open, else `max_step`."""
    tmin = math.inf
    for j in range(n):
        if j == 0 and not ground:
            continue
        if j == 0:
            d, r = -y[0] * scale[0], -y[n] * scale[n]
        else:
            d = y[j - 1] * scale[j - 1] - y[j] * scale[j]
            r = y[n + j - 1] * scale[n + j - 1] - y[n + j] * scale[n + j]
        if d >= 0.0:
            return max_step
        if r > 0.0:
            tmin = min(tmin, -d / r)
    return max(max_step, FLIGHT_FRACTION * tmin / T)


@njit(cache=True)
def tsit5(y0, t1, rtol, atol, max_step, first_step, m, k, c, ground, scale, T, A, B, E):
    """Integrate the scaled field from 0 to `t1` with Tsit5 and the library's controller: diffrax's
    `PIDController(pcoeff=0.4, icoeff=0.3)` (error order 5, as diffrax gives Tsit5;
    safety 0.9, an accepted step never shrinks the next, a rejected one shrinks it by 0.2 to 0.9, the
    previous accepted inverse error in the P term), the next step at most `flight_limit` of the state it
    starts from (`Tolerances.flight_steps`), and first step `first_step`; RMS error norm over the
    library's state, which carries one more (flag) entry without error. No allocation in the loop.
    Returns `(y, steps, accepted)`."""
    n3 = y0.shape[0]
    n = m.shape[0]
    y = y0.copy()
    yn = np.empty(n3)
    ys = np.empty(n3)
    K = np.empty((7, n3))
    f, fel, dd = np.empty(n), np.empty(n), np.empty(n)
    fac = field_factors(m, scale, T)
    field_into(K[0], f, fel, dd, y, m, k, c, ground, scale, fac)
    t = 0.0
    h = first_step
    prev_inv = 1.0
    steps = 0
    accepted = 0
    while t < t1:
        ht = min(h, t1 - t)
        for s in range(1, 7):
            for i in range(n3):
                acc = y[i]
                for r in range(s):
                    acc += ht * A[s, r] * K[r, i]
                ys[i] = acc
            field_into(K[s], f, fel, dd, ys, m, k, c, ground, scale, fac)
        total = 0.0
        for i in range(n3):
            ynew = y[i]
            err = 0.0
            for r in range(7):
                ynew += ht * B[r] * K[r, i]
                err += ht * E[r] * K[r, i]
            yn[i] = ynew
            sc = atol + rtol * max(abs(y[i]), abs(ynew))
            total += (err / sc) ** 2
        norm = math.sqrt(total / (n3 + 1))
        steps += 1
        keep = norm < 1.0
        inv = math.inf if norm == 0.0 else 1.0 / norm
        factor = 0.9 * inv ** (0.7 / 5.0) * prev_inv ** (-0.4 / 5.0)
        lo, hi = (1.0, 10.0) if keep else (0.2, 0.9)
        factor = min(max(factor, lo), hi)
        if inv == 0.0 or math.isinf(inv):
            inv = 1.0
        h = ht * factor
        if keep:
            t += ht
            y[:] = yn
            K[0, :] = K[6, :]
            accepted += 1
            prev_inv = inv
        h = min(h, flight_limit(y, n, ground, scale, T, max_step))
    return y, steps, accepted


@njit(parallel=True, cache=True)
def tsit5_batch(Y0, T1, rtol, atol, max_step, first_step, M, K, C, S, T, A, B, E):
    """`tsit5` over designs in parallel (numba `prange`, one thread per core): row `d` of every array is
    design `d`. Returns the top mass's scaled final velocity and the step count of every design."""
    nd, n = M.shape
    top = np.empty(nd)
    steps = np.empty(nd, np.int64)
    for d in prange(nd):
        y, s, _ = tsit5(Y0[d], T1[d], rtol, atol, max_step, first_step, M[d], K[d], C[d], True, S[d], T[d], A, B, E)
        top[d] = y[2 * n - 1]
        steps[d] = s
    return top, steps


def batched(quick: bool, designs: int = 1024) -> dict:
    """Throughput on many designs of one structure at matched accuracy: `hc.simulate_batch(save_steps=False)`
    (vmapped, split over the CPU devices) against `tsit5_batch` (numba, `prange` over designs), five-mass
    gapped Tsuji stacks whose interior masses are the MVG masses times a random factor in [0.8, 1.2]. The
    reference is the library's batch at rtol = atol = 1e-13; each method runs at the loosest rtol of a
    ladder whose LARGEST relative error of the top launch velocity over the designs is <= `MATCH` and stays
    so at the next tighter rtol (`find_matched`: an equal rtol favoured the library, whose onset landing the
    numba loop lacks: at 1e-9 its worst design was 3e-6 off, the library's 2e-8); every numba design runs to
    the reference's end time for it. Times are medians after compilation, the two in alternation."""
    import jax

    designs = 128 if quick else designs
    rng = np.random.default_rng(1)
    regime = cases.REGIMES["gapped-tsuji"]
    base = cases.masses(5)
    stacks, states, args = [], [], []
    for _ in range(designs):
        m = base.copy()
        m[1:-1] *= rng.uniform(0.8, 1.2, 3)
        stack = hc.Stack(m, cases.laws(regime, m), gravity=0.0)
        state = hc.at_impact(stack, cases.V_IMPACT, regime.gap)
        stacks.append(stack)
        states.append(state)
        meff = cases.effective_masses(m)
        kk = np.full(5, cases.K_STEEL)
        eta = np.array([float(stack.law_of(j).eta) for j in range(5)])
        sc = _scales(stack, state)
        args.append((m, kk, eta * np.sqrt(meff * kk), np.asarray(sc.vector(5), dtype=float), float(sc.time),
                     float(sc.velocity), np.asarray(state.flat(), dtype=float)))
    batch_stack = hc.stack_designs(stacks)
    batch_state = jax.tree.map(lambda *x: np.stack(x), *states)

    def lib_at(rtol):
        tol = hc.Tolerances(rtol=rtol, atol=rtol)
        return lambda: jax.block_until_ready(hc.simulate_batch(batch_stack, batch_state, tolerances=tol,
                                                               save_steps=False, max_steps=65536))

    ref = lib_at(1e-13)()
    ref_top = np.asarray(ref.launch_velocities)[:, -1]
    t_end = np.asarray(ref.t_final)
    M, K, C, S, T, V, Y = (np.stack([a[i] for a in args]) for i in range(7))
    Y0 = np.concatenate([Y / S, np.zeros((designs, 5))], axis=1)  # with the onset proxies, as the library
    S_p = np.concatenate([S, np.ones((designs, 5))], axis=1)[:, : 3 * 5]
    T1 = t_end / T

    def nb_at(rtol):
        return lambda: tsit5_batch(Y0, T1, rtol, rtol, MAX_STEP, FIRST_STEP, M, K, C, S_p, T, _A, _B, _E)

    memo: dict = {}

    def getter(kind):
        def get(rtol):
            if (kind, rtol) not in memo:
                if kind == "library":
                    sol = lib_at(rtol)()
                    top, steps, ok = np.asarray(sol.launch_velocities)[:, -1], np.asarray(sol.num_steps), \
                        bool(np.all(sol.ok))
                else:
                    top, steps = nb_at(rtol)()
                    top, ok = top * V, True
                err = np.abs(top - ref_top) / np.abs(ref_top)
                memo[(kind, rtol)] = dict(ok=ok, err=float(np.max(err)), median_err=float(np.median(err)),
                                          steps=float(np.mean(steps)), rtol=rtol)
            return memo[(kind, rtol)]
        return get

    grid = fine_grid(1e-6, 1e-12)
    rows = {kind: find_matched(getter(kind), grid, MATCH) for kind in ("library", "numba")}
    out = dict(designs=designs, match=MATCH, devices=len(jax.devices()), threads=_numba_threads(),
               equal_rtol_1e_9={kind: getter(kind)(1e-9) for kind in ("library", "numba")})
    if rows["library"] is None or rows["numba"] is None:
        return dict(out, ok=False, rows=rows)
    times = interleaved_medians({"library": lib_at(rows["library"]["rtol"]), "numba": nb_at(rows["numba"]["rtol"])},
                                3 if quick else 7, budget_s=120.0)
    for kind in rows:
        rows[kind]["ms_per_design"] = 1e3 * times[kind] / designs
    return dict(out, ok=True, rows=rows, ratio=times["library"] / times["numba"])


def _numba_threads() -> int:
    import numba

    return int(numba.get_num_threads())


# ============================================================================ the JAX floor
def jax_tsit5_solver():
    """The numba loop's algorithm (`tsit5`: Tsit5, the library's PI controller and flight bound, the RMS
    norm) as a bare `jax.lax.while_loop` over the library's own scaled field (`_scaled_field`, onset
    proxies and flag entry included), jitted once: the fastest a JAX program of this algorithm runs on
    the CPU, without diffrax's loop, the contact tracking or the stopping event (it runs to `t1`, as the
    numba loop does). Returns `solve(y0, t1, rtol, args) -> (y, steps, accepted)`."""
    import jax
    import jax.numpy as jnp

    from hertz_chain._solver import flight_limit

    A, B, E = (jnp.asarray(a) for a in (_A, _B, _E))
    C = jnp.asarray(np.sum(_A, axis=1))
    tol0 = hc.Tolerances()

    @jax.jit
    def solve(y0, t1, rtol, args):
        f = lambda t, y: _scaled_field(t, y, args)  # noqa: E731
        m = y0.shape[0]

        def body(c):
            t, y, k0, h, prev_inv, steps, acc = c
            ht = jnp.minimum(h, t1 - t)
            ks = [k0]
            for st in range(1, 7):
                yi = y + ht * sum(A[st, r] * ks[r] for r in range(st))
                ks.append(f(t + C[st] * ht, yi))
            yn = y + ht * sum(B[r] * ks[r] for r in range(7))
            err = ht * sum(E[r] * ks[r] for r in range(7))
            sc = rtol + rtol * jnp.maximum(jnp.abs(y), jnp.abs(yn))
            norm = jnp.sqrt(jnp.sum((err / sc) ** 2) / m)
            keep = norm < 1.0
            inv = jnp.where(norm == 0.0, jnp.inf, 1.0 / norm)
            factor = 0.9 * inv ** (0.7 / 5.0) * prev_inv ** (-0.4 / 5.0)
            factor = jnp.clip(factor, jnp.where(keep, 1.0, 0.2), jnp.where(keep, 10.0, 0.9))
            inv = jnp.where(jnp.isinf(inv), 1.0, inv)
            y2 = jnp.where(keep, yn, y)
            h2 = jnp.minimum(ht * factor, flight_limit(args, y2, tol0.max_step, tol0.flight_fraction))
            return (jnp.where(keep, t + ht, t), y2, jnp.where(keep, ks[6], k0), h2,
                    jnp.where(keep, inv, prev_inv), steps + 1, acc + keep.astype(jnp.int32))

        init = (jnp.asarray(0.0), y0, f(0.0, y0), jnp.asarray(tol0.first_step), jnp.asarray(1.0),
                jnp.asarray(0, jnp.int32), jnp.asarray(0, jnp.int32))
        out = jax.lax.while_loop(lambda c: c[0] < t1, body, init)
        return out[1], out[5], out[6]

    return solve


# ============================================================================ one case
class Case:
    """The numba equations of one benchmark case (`cases.build`) and its library reference."""

    def __init__(self, n: int, regime: str):
        self.n, self.regime = n, regime
        self.stack, self.state = cases.build(n, regime)
        reg = cases.REGIMES[regime]
        m = np.asarray(self.stack.masses, dtype=float)
        meff = cases.effective_masses(m)
        kk = np.array([reg.ground_stiffness] + [cases.K_STEEL] * (n - 1))
        if reg.law == "tsuji":
            eta = np.array([float(self.stack.law_of(j).eta) for j in range(n)])
            cc = eta * np.sqrt(meff * kk)
        else:
            cc = np.zeros(n)
        sc = _scales(self.stack, self.state)
        self.scale = np.asarray(sc.vector(n), dtype=float)
        self.T, self.V = float(sc.time), float(sc.velocity)
        self.args = (m, kk, cc, True, self.scale, self.T)
        self.y0 = np.asarray(self.state.flat(), dtype=float) / self.scale
        self.y0p = np.concatenate([self.y0, np.zeros(n)])  # with the onset proxies (the library's default)
        dc = DiffraxCase(self.stack, self.state)
        ref = dc.solve("dopri8", 1e-13, max_steps=65536)
        self.ref, self.t1 = ref["v_top"], ref["t_final"] / self.T
        self.dc = dc

    def check_field(self, samples: int = 20, seed: int = 0) -> float:
        """Largest relative difference of the numba field from the library's `_scaled_field`, with and
        without the onset proxies, at random states around the initial one."""
        rng = np.random.default_rng(seed)
        lib_args = FieldArgs(self.stack, self.scale, self.T)
        worst = 0.0
        for _ in range(samples):
            y = self.y0p + rng.normal(0, 1, self.y0p.size)
            for yy, lib_y in ((y[: 3 * self.n], y[: 3 * self.n]), (y, np.append(y, 0.0))):
                a = field(yy, *self.args)
                b = np.asarray(_scaled_field(0.0, lib_y, lib_args))[: yy.size]
                worst = max(worst, float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)))
        return worst

    def scipy(self, method: str, rtol: float) -> dict:
        f = lambda t, y: field(y, *self.args)  # noqa: E731
        kw = {"jac": lambda t, y: jacobian(y, *self.args)} if method in ("Radau", "LSODA") else {}
        t0 = time.perf_counter()
        sol = solve_ivp(f, (0.0, self.t1), self.y0, method=method, rtol=rtol, atol=rtol, max_step=MAX_STEP, **kw)
        el = time.perf_counter() - t0
        v = float(sol.y[2 * self.n - 1, -1] * self.V)
        return dict(ok=bool(sol.success), err=rel_err(v, self.ref), time=el, nfev=int(sol.nfev),
                    accepted=len(sol.t) - 1, rtol=rtol)

    def numba_tsit5(self, rtol: float) -> dict:
        """The numba loop on the library's default equations (with the onset proxies)."""
        run = lambda: tsit5(self.y0p, self.t1, rtol, rtol, MAX_STEP, FIRST_STEP, *self.args, _A, _B, _E)  # noqa: E731
        y, steps, acc = run()
        v = float(y[2 * self.n - 1] * self.V)
        return dict(ok=True, err=rel_err(v, self.ref), steps=int(steps), accepted=int(acc), rtol=rtol, v=v,
                    time=median_time(run, 9, budget_s=1.0))

    def jax_tsit5(self, rtol: float) -> dict:
        """`jax_tsit5_solver`'s bare JAX loop on the library's default equations (the JAX floor)."""
        import jax

        if not hasattr(self, "_jax_solve"):
            self._jax_solve = jax_tsit5_solver()
            # the per-solve factors of the library's own solve (`FieldArgs.of`): the same saving
            self._jax_args = FieldArgs.of(self.stack, np.asarray(self.scale), self.T)
        y0 = np.append(self.y0p, 0.0)
        run = lambda: jax.block_until_ready(self._jax_solve(y0, self.t1, rtol, self._jax_args))  # noqa: E731
        y, steps, acc = run()
        v = float(y[2 * self.n - 1] * self.V)
        return dict(ok=True, err=rel_err(v, self.ref), steps=int(steps), accepted=int(acc), rtol=rtol, v=v,
                    time=median_time(run, 9, budget_s=1.0))

    def numba_from_jax_us(self, rtol: float) -> dict:
        """The option of issue 22 "a compiled integrator called from JAX": the numba loop inside a jitted JAX
        function through `jax.pure_callback` (the host call JAX would make), timed against the same loop
        called directly; the difference is the price of the crossing per solve (us)."""
        import jax
        import jax.numpy as jnp

        def host(y0):
            y, _, _ = tsit5(np.asarray(y0), self.t1, rtol, rtol, MAX_STEP, FIRST_STEP, *self.args, _A, _B, _E)
            return y

        shape = jax.ShapeDtypeStruct(self.y0p.shape, jnp.float64)
        through = jax.jit(lambda y0: jax.pure_callback(host, shape, y0)[2 * self.n - 1])
        y0 = jnp.asarray(self.y0p)
        direct = median_time(lambda: host(self.y0p), 51, budget_s=2.0)
        called = median_time(lambda: jax.block_until_ready(through(y0)), 51, budget_s=2.0)
        return dict(direct_us=1e6 * direct, from_jax_us=1e6 * called, crossing_us=1e6 * (called - direct))

    def library(self, rtol: float) -> dict:
        """`hc.simulate` with the library's defaults but `rtol = atol` (onset proxies on, as users run)."""
        sol = hc.simulate(self.stack, self.state, tolerances=hc.Tolerances(rtol=rtol, atol=rtol), max_steps=65536,
                          throw=False)
        v = float(sol.launch_velocities[-1])
        return dict(ok=sol.ok, v_top=v, err=rel_err(v, self.ref), steps=int(sol.num_steps),
                    accepted=int(sol.num_accepted_steps), rtol=rtol)

    def call(self, kind: str, row: dict):
        """A call (that blocks) of `kind` ("library", "numba-tsit5" or "jax-tsit5") at its matched row."""
        import jax

        rtol = row["rtol"]
        if kind == "library":
            tol, ms = hc.Tolerances(rtol=rtol, atol=rtol), steps_budget(row["steps"])
            return lambda: jax.block_until_ready(hc.launch_velocity(self.stack, self.state, tolerances=tol,
                                                                    max_steps=ms))
        if kind == "numba-tsit5":
            return lambda: tsit5(self.y0p, self.t1, rtol, rtol, MAX_STEP, FIRST_STEP, *self.args, _A, _B, _E)
        self.jax_tsit5(rtol)  # compiles it, sets the solver up
        y0 = np.append(self.y0p, 0.0)
        return lambda: jax.block_until_ready(self._jax_solve(y0, self.t1, rtol, self._jax_args))


NUMBALSODA = None
try:  # noqa: SIM105
    import numbalsoda as _nbl  # type: ignore

    NUMBALSODA = _nbl
except Exception as exc:  # pragma: no cover - depends on the build
    NUMBALSODA_WHY = (f"not installed ({type(exc).__name__}): numbalsoda 0.3.4 (2022) ships as source only and its "
                      "build needs a Fortran compiler (CMake: 'No CMAKE_Fortran_COMPILER could be found' on the "
                      "benchmark machine, which has none)")
else:
    NUMBALSODA_WHY = ""


def run_case(n: int, regime: str, quick: bool) -> dict:
    c = Case(n, regime)
    out = dict(n=n, regime=regime, field_check=c.check_field(), ref=c.ref)
    grid = fine_grid(1e-5, 1e-12)
    memo: dict = {}

    def getter(kind):
        def get(rtol):
            key = (kind, rtol)
            if key not in memo:
                memo[key] = (c.library(rtol) if kind == "library" else c.numba_tsit5(rtol) if kind == "numba-tsit5"
                             else c.jax_tsit5(rtol) if kind == "jax-tsit5" else c.scipy(kind, rtol))
            return memo[key]
        return get

    rows = {}
    for kind in ("library", "numba-tsit5", "jax-tsit5", "DOP853", "LSODA", "Radau"):
        if quick and kind == "Radau":
            continue
        r = find_matched(getter(kind), grid, MATCH)
        if r is None:
            rows[kind] = dict(ok=False)
            continue
        if kind in ("DOP853", "LSODA", "Radau"):
            ts = [r["time"]] + [c.scipy(kind, r["rtol"])["time"] for _ in range(2 if quick else 4)]
            r["time"] = statistics.median(ts)
        rows[kind] = r
    # the library and the compiled loops timed again in alternation at their matched tolerances: their
    # ratios are the headline, and a shared machine's load drifts between separate timings
    calls = {k: c.call(k, rows[k]) for k in ("library", "numba-tsit5", "jax-tsit5") if rows.get(k, {}).get("rtol")}
    for k, t in interleaved_medians(calls, 5 if quick else 25, block=5).items():
        rows[k]["time"] = t
    # the floor reproduces the library's launch velocity (same algorithm, same tolerance): 1e-9 at 1e-10
    lib = c.library(1e-10)
    nb = c.numba_tsit5(1e-10)
    jx = c.jax_tsit5(1e-10)
    out["tsit5_agreement_at_1e-10"] = rel_err(nb["v"], lib["v_top"])
    out["jax_tsit5_agreement_at_1e-10"] = rel_err(jx["v"], lib["v_top"])
    out["tsit5_steps_at_1e-10"] = {"library": lib["steps"], "numba": nb["steps"], "jax": jx["steps"]}
    # cost per step at one tolerance, all three on the same run: the library's (launch_velocity, prepared
    # callable: no per-call preparation), the bare JAX loop's, numba's
    lv = hc.prepare_launch(c.stack, c.state, tolerances=hc.Tolerances(rtol=1e-10, atol=1e-10),
                           max_steps=steps_budget(lib["steps"]))
    import jax

    # the three timed in alternation (a shared machine's load falls on them alike), warm blocks as above
    t = interleaved_medians({"library": lambda: jax.block_until_ready(lv(c.stack, c.state)),
                             "jax": c.call("jax-tsit5", jx), "numba": c.call("numba-tsit5", nb)},
                            5 if quick else 15, block=5, budget_s=6.0)
    out["numba_from_jax_at_1e-10"] = c.numba_from_jax_us(1e-10)
    out["per_step_us_at_1e-10"] = {"library": 1e6 * t["library"] / lib["steps"],
                                   "jax": 1e6 * t["jax"] / jx["steps"], "numba": 1e6 * t["numba"] / nb["steps"]}
    out["rows"] = rows
    return out


def fixed_cost(quick: bool) -> dict:
    """The fixed cost per call of `launch_velocity` and of `prepare_launch`'s callable: time against
    steps over a tolerance ladder (n = 2, gapped Hertz), the intercept of the Theil-Sen line (the
    median of the pairwise slopes: one rung a load spike hit cannot tilt it).

    Each rung is a loop of calls of the same solve (warm, as in an optimiser's or a fit's loop: the
    same stack shape solved again), the median of its calls after the first; the ladder is run three
    times and each rung keeps its smallest median (a shared machine's load spikes only add). The same
    rungs called in alternation (each call after another rung's program: cold caches) give the cold
    intercept, reported beside it."""
    import jax

    stack, state = cases.build(2, "gapped-hertz")
    rtols = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
    calls, rows = {}, []
    for rtol in rtols:
        tol = hc.Tolerances(rtol=rtol, atol=rtol)
        steps = int(hc.simulate(stack, state, tolerances=tol).num_steps)
        launch = hc.prepare_launch(stack, state, tolerances=tol, max_steps=4096)
        calls[rtol] = (lambda tol=tol: jax.block_until_ready(hc.launch_velocity(stack, state, tolerances=tol,
                                                                                 max_steps=4096)),
                       lambda launch=launch: jax.block_until_ready(launch(stack, state)))
        rows.append(dict(rtol=rtol, steps=steps, launch_velocity_us=np.inf, prepared_us=np.inf))
    n = 30 if quick else 150
    for _ in range(3):
        for r in rows:
            for key, fn in zip(("launch_velocity_us", "prepared_us"), calls[r["rtol"]]):
                r[key] = min(r[key], 1e6 * median_time(fn, n, warmup=3, budget_s=1.0))
    cold = interleaved_medians({rtol: calls[rtol][1] for rtol in rtols}, 20 if quick else 100, budget_s=4.0)
    from scipy.stats import theilslopes  # a line that one rung hit by a load spike cannot tilt

    x = np.array([r["steps"] for r in rows], dtype=float)
    out = dict(rows=rows)
    for key in ("launch_velocity_us", "prepared_us"):
        slope, intercept = theilslopes(np.array([r[key] for r in rows]), x)[:2]
        out[key.replace("_us", "_fixed_us")], out[key.replace("_us", "_per_step_us")] = float(intercept), float(slope)
    slope, intercept = theilslopes(1e6 * np.array([cold[r] for r in rtols]), x)[:2]
    out["prepared_cold_fixed_us"], out["prepared_cold_per_step_us"] = float(intercept), float(slope)
    return out


def _write(data: dict, path: str | None) -> None:
    lines = ["# Compiled baselines (issue 22)", "",
             f"Generated by `benchmarks/baselines.py{' --quick' if data['quick'] else ''}` on {data['date']}, "
             f"{data['machine']}; load average at start {data['load'][0]:.2f}, at end {data['load'][1]:.2f}.", "",
             "Matched accuracy: relative error <= 1e-7 on the top launch velocity (`methods.find_matched`); "
             "times are medians of whole solves after compilation (the library and the numba and bare-JAX "
             "loops timed in alternation, `methods.interleaved_medians`, so that a shared machine's load falls on "
             "them alike: blocks of five calls of each, the last four timed, as a user's loop calls the same solve "
             "again; the first call after another program finds the caches cold). Ratio = hertz_chain `launch_velocity` "
             "(Tsit5) time / the method's time (above 1: the method is faster).", "",
             f"numbalsoda: {'used' if NUMBALSODA is not None else NUMBALSODA_WHY}.", "",
             "| case | method | rtol | steps | time (ms) | hertz_chain / method |", "|---|---|---|---|---|---|"]
    for case in data["cases"]:
        lib = case["rows"].get("library", {})
        for kind, r in case["rows"].items():
            if not r.get("ok"):
                lines.append(f"| n={case['n']} {case['regime']} | {kind} | — | — | — | not matched |")
                continue
            ratio = lib["time"] / r["time"] if lib.get("ok") else float("nan")
            steps = r.get("steps", r.get("accepted"))
            lines.append(f"| n={case['n']} {case['regime']} | {kind} | {r['rtol']:.0e} | {steps} | "
                         f"{1e3 * r['time']:.3f} | {ratio:.2f} |")
    fc = data.get("fixed_cost")
    if fc:
        lines += ["", "## Fixed cost per call", "",
                  "Two-mass gapped Hertz stack over a tolerance ladder; each rung a loop of calls of the same solve "
                  "(warm: the same stack shape solved again, as in an optimiser's loop), its median call time, the "
                  "smallest of three passes over the ladder; the fixed cost is the intercept of time against steps "
                  "(Theil-Sen line: the median of the pairwise slopes, robust to one rung a load spike hit), the cost "
                  "per step its slope (`baselines.fixed_cost`).", "",
                  "| rtol | steps | `launch_velocity` (us) | `prepare_launch` callable (us) |", "|---|---|---|---|"]
        lines += [f"| {r['rtol']:.0e} | {r['steps']} | {r['launch_velocity_us']:.0f} | {r['prepared_us']:.0f} |"
                  for r in fc["rows"]]
        lines += ["", f"Fixed cost: `launch_velocity` {fc['launch_velocity_fixed_us']:.0f} us, the prepared callable "
                  f"{fc['prepared_fixed_us']:.0f} us (target: under 50 us); per step {fc['launch_velocity_per_step_us']:.2f} "
                  f"and {fc['prepared_per_step_us']:.2f} us. Cold (the rungs' prepared callables called in "
                  f"alternation, each call after another program): {fc['prepared_cold_fixed_us']:.0f} us, per step "
                  f"{fc['prepared_cold_per_step_us']:.2f} us."]
    bt = data.get("batched")
    if bt:
        lines += ["", "## Many designs at once (matched accuracy)", "",
                  f"{bt['designs']} five-mass gapped Tsuji stacks (interior masses the MVG masses x U[0.8, 1.2]): "
                  f"`hc.simulate_batch(save_steps=False)` on {bt['devices']} CPU device(s) against the numba Tsit5 "
                  f"loop with `prange` over designs on {bt['threads']} thread(s). Each at the loosest rtol whose "
                  f"largest relative error of the top launch velocity over all designs is <= {bt['match']:.0e} "
                  "against the library's batch at 1e-13 (and stays so at the next tighter rtol); every numba "
                  "design runs to the reference's end time for it; the two timed in alternation.", ""]
        if bt.get("ok"):
            lines += ["| method | rtol | largest error | median error | mean steps | ms per design |",
                      "|---|---|---|---|---|---|"]
            for kind, label in (("library", "hertz_chain `simulate_batch`"), ("numba", "numba Tsit5, `prange`")):
                r = bt["rows"][kind]
                lines.append(f"| {label} | {r['rtol']:.0e} | {r['err']:.1e} | {r['median_err']:.1e} | "
                             f"{r['steps']:.0f} | {r['ms_per_design']:.3f} |")
            lines += ["", f"hertz_chain / numba: {bt['ratio']:.2f} (below 1: hertz_chain faster)."]
        else:
            lines.append("One of the two did not reach the accuracy on the ladder: " + ", ".join(
                f"{k}: {'no rtol' if r is None else r['rtol']}" for k, r in bt["rows"].items()))
        eq = bt["equal_rtol_1e_9"]
        lines += ["", f"At an equal rtol of 1e-9 (the comparison before 2026-11-28): largest errors "
                  f"{eq['library']['err']:.1e} (hertz_chain) and {eq['numba']['err']:.1e} (numba), mean steps "
                  f"{eq['library']['steps']:.0f} and {eq['numba']['steps']:.0f}: the numba loop does not land "
                  "onsets, so at one rtol it takes more steps and misses more."]
    # the targets, from this run where measured here
    lines += ["", "## Targets of issue 22 (this run)", "", "| target | measured | verdict |", "|---|---|---|"]
    for case in data["cases"]:
        rows = case["rows"]
        lib, nb = rows.get("library", {}), rows.get("numba-tsit5", {})
        if lib.get("ok") and nb.get("ok"):
            ratio = lib["time"] / nb["time"]
            ps = case["per_step_us_at_1e-10"]
            lines.append(f"| single n={case['n']} {case['regime']} solve within 1.5x of the numba loop | "
                         f"{ratio:.2f}x at matched accuracy ({lib['steps']} against {nb['steps']} steps); "
                         f"{ps['library'] / ps['numba']:.2f}x per step | {'met' if ratio <= 1.5 else 'not met'} |")
    if fc:
        warm, cold = fc["prepared_fixed_us"], fc["prepared_cold_fixed_us"]
        lines.append(f"| fixed cost per call of a prepared callable under 50 us | {warm:.0f} us warm (the same solve "
                     f"again), {cold:.0f} us cold (after another program) | "
                     f"{'met' if warm < 50 else 'not met'} warm, {'met' if cold < 50 else 'not met'} cold |")
    if bt and bt.get("ok"):
        lines.append(f"| batched five-mass designs at least as fast as numba `prange` | {bt['ratio']:.2f}x at matched "
                     f"accuracy | {'met' if bt['ratio'] <= 1.0 else 'not met'} |")
    lines += ["| long chains: cost per step linear in n to 1,000 | `benchmarks/long_chains.md` | see there |",
              "| gradient cost relative to a solve not growing | `benchmarks/results.md`, \"Gradient\" | see there |"]
    lines += ["", "Checks: the numba field equals the library's scaled field at random states (largest relative "
              "difference per case below); the numba Tsit5 loop gives the library's launch velocity at rtol 1e-10.", ""]
    for case in data["cases"]:
        lines.append(f"- n={case['n']} {case['regime']}: field {case['field_check']:.1e}; Tsit5 launch velocity "
                     f"{case['tsit5_agreement_at_1e-10']:.1e} apart (the bare JAX loop "
                     f"{case['jax_tsit5_agreement_at_1e-10']:.1e}); steps {case['tsit5_steps_at_1e-10']}")
    lines += ["", "## Cost per step (rtol 1e-10, the same run)", "",
              "hertz_chain through `prepare_launch`'s callable (no per-call preparation; the contact tracking, the "
              "stopping event and diffrax's loop included), the same algorithm as a bare `jax.lax.while_loop` over "
              "the library's field (`jax-tsit5`: the floor of a JAX program on this CPU), and the numba loop.", "",
              "| case | hertz_chain us/step | bare JAX loop us/step | numba us/step | hertz_chain / JAX | JAX / numba |",
              "|---|---|---|---|---|---|"]
    for case in data["cases"]:
        ps = case["per_step_us_at_1e-10"]
        lines.append(f"| n={case['n']} {case['regime']} | {ps['library']:.2f} | {ps['jax']:.2f} | {ps['numba']:.2f} | "
                     f"{ps['library'] / ps['jax']:.2f} | {ps['jax'] / ps['numba']:.2f} |")
    lines += ["", "The numba loop called from a jitted JAX function through `jax.pure_callback` (the option \"a compiled "
              "integrator called from JAX\"), rtol 1e-10, against the same loop called directly:", "",
              "| case | numba direct (us) | from JAX (us) | crossing (us per solve) |", "|---|---|---|---|"]
    for case in data["cases"]:
        cb = case["numba_from_jax_at_1e-10"]
        lines.append(f"| n={case['n']} {case['regime']} | {cb['direct_us']:.0f} | {cb['from_jax_us']:.0f} | "
                     f"{cb['crossing_us']:.0f} |")
    text = "\n".join(lines) + "\n"
    if path:
        Path(path).write_text(text)
    print(text)


def main(argv=None) -> int:
    import datetime
    import platform

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one case (n = 5, gapped Tsuji), no Radau")
    ap.add_argument("--output", help="Markdown file to write")
    ap.add_argument("--json", help="raw results (JSON)")
    args = ap.parse_args(argv)
    todo = [(5, "gapped-tsuji")] if args.quick else [(10, "gapped-hertz"), (10, "gapped-tsuji")]
    data = dict(quick=args.quick, date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="minutes"),
                machine=f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
                load=[os.getloadavg()[0], math.nan], cases=[])
    for n, regime in todo:
        print(f"case n={n} {regime} ...", flush=True)
        data["cases"].append(run_case(n, regime, args.quick))
    print("fixed cost ...", flush=True)
    data["fixed_cost"] = fixed_cost(args.quick)
    print("many designs ...", flush=True)
    data["batched"] = batched(args.quick)
    data["load"][1] = os.getloadavg()[0]
    _write(data, args.output)
    if args.json:
        Path(args.json).write_text(json.dumps(data, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
