"""Runners: diffrax through the public `hertz_chain` API, and scipy `solve_ivp` on the same scaled
vector field (the library's `_scaled_field`, compiled with `jax.jit`; Jacobian by `jax.jacfwd`, compiled).

Both integrate the same dimensionless state (`hertz_chain.simulation` docstring: time in contact times
`T`, lengths in peak overlaps `L`, velocities in drop speeds `V`, energies in `E`) with the same
`rtol = atol`, the same largest step (`Tolerances.max_step = 0.5 T`) and the same RMS error norm, so a
tolerance means the same thing for every method.
"""

from __future__ import annotations

import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np
from scipy.integrate import solve_ivp
from scipy.integrate._ivp import radau as _radau, rk as _rk

import hertz_chain as hc
from hertz_chain._scaling import FieldArgs
from hertz_chain.simulation import _scaled_field, _scales  # the library's own scaled vector field

DIFFRAX_METHODS = ("tsit5", "tsit5-diffrax", "dopri8", "kvaerno5")
#: `run.py --quick` (the CI smoke run): the explicit methods only
QUICK_DIFFRAX_METHODS = ("tsit5", "dopri8")  # (CI time: plain diffrax Tsit5 and Kvaerno5 only in `make bench`)
SCIPY_METHODS = ("DOP853", "Radau", "LSODA")
MAX_STEP = hc.Tolerances().max_step  # scaled units (contact times), the library default


def interleaved_medians(fns: dict, rounds: int, warmup: int = 1, budget_s: float = 6.0, block: int = 1) -> dict:
    """Median wall time (s) of each of `fns` (name -> a call that blocks), timed in alternation: every
    round calls each in turn, so a slow spell of a shared machine falls on all of them alike and their
    ratios keep (timing them one after the other let a minute's load move a ratio by 30 %). Up to
    `rounds` rounds after `warmup`, stopping once the rounds have used `budget_s` (at least one).

    `block` > 1: every round calls each `block` times in a row and times the last `block - 1` (warm: a
    user's loop calls the same solve again; the first call after another program finds the caches cold,
    which cost the library's compiled solve 0-0.8 ms more on the benchmark machine (10 masses; ~0.15 ms
    for two) and numba's loop no more than the noise, so alternating single calls measured every library
    call cold)."""
    for _ in range(warmup):
        for fn in fns.values():
            fn()
    ts: dict = {k: [] for k in fns}
    spent, done = 0.0, 0
    while done < rounds and (spent == 0.0 or spent < budget_s):
        for k, fn in fns.items():
            for i in range(block):
                t0 = time.perf_counter()
                fn()
                dt = time.perf_counter() - t0
                if i or block == 1:
                    ts[k].append(dt)
                spent += dt
        done += 1
    return {k: statistics.median(v) for k, v in ts.items()}


def median_time(fn, repeats: int, warmup: int = 1, budget_s: float = 3.0) -> float:
    """Median wall time (s) of `fn()` (which blocks) over up to `repeats` calls after `warmup` calls;
    stops repeating once the timed calls have used `budget_s` (at least one timed call)."""
    for _ in range(warmup):
        fn()
    ts = []
    while len(ts) < repeats and (not ts or sum(ts) < budget_s):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def steps_budget(steps: int) -> int:
    """The `max_steps` used for timing a solve that took `steps` steps: the smallest of 4096, 16384,
    65536 with 25 % headroom (the cost of a solve grows with `max_steps`: its step buffers)."""
    for ms in (4096, 16384, 65536):
        if 1.25 * steps <= ms:
            return ms
    return 65536


# ============================================================================ diffrax
class DiffraxCase:
    """One design integrated by diffrax through `hertz_chain.simulation` / `launch_velocity`."""

    def __init__(self, stack, state):
        self.stack, self.state = stack, state

    def solve(self, solver: str, rtol: float, max_steps: int = 16384) -> dict:
        """Statistics and the top mass's launch velocity (`simulate`, `throw=False`)."""
        tol = hc.Tolerances(rtol=rtol, atol=rtol, resolve_onsets=False)  # the same 3n equations as scipy
        sol = hc.simulate(self.stack, self.state, solver=solver, tolerances=tol, max_steps=max_steps, throw=False)
        if sol.status == hc.Status.INCOMPLETE_MAX_STEPS:  # retry with a larger budget
            if max_steps < 65536:
                return self.solve(solver, rtol, 65536)
        return dict(
            ok=sol.ok, status=str(sol.status), v_top=float(sol.launch_velocities[-1]),
            t_final=sol.t_final, steps=sol.num_steps, accepted=sol.num_accepted_steps,
            rejected=sol.num_rejected_steps, max_steps=max_steps,
        )

    def launch_fn(self, solver: str, rtol: float, max_steps: int):
        tol = hc.Tolerances(rtol=rtol, atol=rtol, resolve_onsets=False)  # the same 3n equations as scipy
        return lambda: jax.block_until_ready(
            hc.launch_velocity(self.stack, self.state, solver=solver, tolerances=tol, max_steps=max_steps))

    def time_launch(self, solver: str, rtol: float, max_steps: int, repeats: int = 5) -> float:
        """Median time (s) of one compiled `launch_velocity` call (compilation excluded)."""
        return median_time(self.launch_fn(solver, rtol, max_steps), repeats)

    def time_simulate(self, solver: str, rtol: float, max_steps: int, repeats: int = 5) -> float:
        """Median time (s) of one `simulate` call (compiled; includes its host-side post-processing)."""
        tol = hc.Tolerances(rtol=rtol, atol=rtol, resolve_onsets=False)  # the same 3n equations as scipy
        return median_time(lambda: hc.simulate(self.stack, self.state, solver=solver, tolerances=tol,
                                               max_steps=max_steps, throw=False), repeats)


# ============================================================================ scipy
class _Timeout(Exception):
    pass


class _Counters:
    """Counts solver step attempts by wrapping scipy's per-attempt internals (DOP853: `rk_step`, one call
    per attempted step; Radau: `solve_collocation_system`, one call per attempt, Newton failures
    included). Installed around each solve and removed after it; costs ~0.2 us per attempt."""

    def __init__(self):
        self.attempts = 0

    def __enter__(self):
        self._rk, self._colloc = _rk.rk_step, _radau.solve_collocation_system

        def rk_step(*a, **k):
            self.attempts += 1
            return self._rk(*a, **k)

        def colloc(*a, **k):
            self.attempts += 1
            return self._colloc(*a, **k)

        _rk.rk_step, _radau.solve_collocation_system = rk_step, colloc
        return self

    def __exit__(self, *exc):
        _rk.rk_step, _radau.solve_collocation_system = self._rk, self._colloc
        return False


class ScipyCase:
    """The same design for `scipy.integrate.solve_ivp`: the library's scaled vector field, compiled with
    `jax.jit` (one dispatch per evaluation) and its Jacobian by `jax.jacfwd`, compiled (Radau, LSODA).

    End criterion: integrate to the reference solution's end time (`t_final` of the tight diffrax solve,
    when its cascade-complete event fired). With g = 0 every velocity is constant after that, so the top
    mass's velocity there is its launch velocity, as `launch_velocity` defines it.
    """

    def __init__(self, stack, state, t_end: float):
        n = stack.n
        sc = _scales(stack, state)
        self.n = n
        self.V = float(sc.velocity)
        self.T = float(sc.time)
        scale = sc.vector(n)
        args = FieldArgs(stack, scale, sc.time)
        self.y0 = np.asarray(state.flat() / scale, dtype=float)
        self.t1 = float(t_end) / self.T
        f = jax.jit(lambda t, y: _scaled_field(t, y, args))
        J = jax.jit(jax.jacfwd(lambda t, y: _scaled_field(t, y, args), argnums=1))
        self._f, self._J = f, J
        np.asarray(f(0.0, self.y0))
        np.asarray(J(0.0, self.y0))
        self.deadline = np.inf

    def rhs(self, t, y):
        if time.perf_counter() > self.deadline:
            raise _Timeout
        return np.asarray(self._f(t, y))

    def jac(self, t, y):
        return np.asarray(self._J(t, y))

    def rhs_call_cost(self, calls: int = 2000) -> tuple[float, float]:
        """Seconds per call of the compiled RHS and Jacobian from Python (numpy in, numpy out)."""
        y = self.y0 + 1e-3
        t0 = time.perf_counter()
        for _ in range(calls):
            self.rhs(0.1, y)
        t1 = time.perf_counter()
        for _ in range(calls // 4):
            self.jac(0.1, y)
        t2 = time.perf_counter()
        return (t1 - t0) / calls, (t2 - t1) / (calls // 4)

    def solve(self, method: str, rtol: float, cap_s: float = 30.0) -> dict:
        kw = dict(jac=self.jac) if method in ("Radau", "LSODA") else {}
        self.deadline = time.perf_counter() + cap_s
        try:
            with _Counters() as cnt:
                t0 = time.perf_counter()
                sol = solve_ivp(self.rhs, (0.0, self.t1), self.y0, method=method, rtol=rtol, atol=rtol,
                                max_step=MAX_STEP, **kw)
                elapsed = time.perf_counter() - t0
        except _Timeout:
            return dict(ok=False, status=f"> {cap_s:g} s", timeout=True, time=np.inf)
        finally:
            self.deadline = np.inf
        accepted = len(sol.t) - 1
        if method == "LSODA":  # one internal step per accepted point; LSODA does not report rejections
            attempts, rejected = accepted, None
        else:
            attempts, rejected = cnt.attempts, cnt.attempts - accepted
        return dict(
            ok=bool(sol.success), status=sol.message if not sol.success else "ok", timeout=False,
            v_top=float(sol.y[2 * self.n - 1, -1] * self.V), steps=attempts, accepted=accepted,
            rejected=rejected, nfev=int(sol.nfev), njev=int(sol.njev), nlu=int(sol.nlu), time=elapsed,
        )

    def time_solve(self, method: str, rtol: float, first: dict, repeats: int = 3, cap_s: float = 30.0) -> float:
        """Median time (s) of `repeats` solves, counting the already-measured `first` one; one solve only
        when it took more than 2 s."""
        ts = [first["time"]]
        if first["time"] < 2.0:
            for _ in range(repeats - 1):
                ts.append(self.solve(method, rtol, cap_s)["time"])
        return statistics.median(ts)


# ============================================================================ matched accuracy
def fine_grid(loosest: float = 1e-5, tightest: float = 1e-12) -> tuple[float, ...]:
    """The 1-2-5 tolerance grid from `loosest` to `tightest` (loose to tight): 1e-5, 5e-6, 2e-6, 1e-6, ..."""
    grid = [float(f"{c}e-{k}") for k in range(1, 17) for c in (5, 2, 1)]
    return tuple(r for r in grid if tightest * (1 - 1e-9) <= r <= loosest * (1 + 1e-9))


def find_matched(get, grid, match: float) -> dict | None:
    """Matched accuracy: the loosest `rtol` of `grid` (loose to tight) whose error is `<= match` and stays so
    at every tighter grid rtol down to a tenth of it (`[rtol/10, rtol)`; on a grid coarser than that, at
    the next tighter rtol; the tightest rtol of the grid on its own). A method reaches the accuracy
    reliably from there on, so one lucky tolerance does not count: scipy's Radau at 1e-6 once landed at
    1.3e-8 from the reference while 5e-7 and 2e-7 gave 4.2e-7 and 2.1e-7.

    `get(rtol)` returns that rtol's result (a dict with `ok` and `err`); it is called lazily, loose to
    tight, and only as far as the decision needs. None when no rtol qualifies."""

    def ok(r):
        return bool(r.get("ok")) and r["err"] <= match

    for i, rtol in enumerate(grid):
        if not ok(get(rtol)):
            continue
        tighter = grid[i + 1:]
        check = [q for q in tighter if q >= rtol / 10 * (1 - 1e-9)] or tighter[:1]
        if all(ok(get(q)) for q in check):
            return get(rtol)
    return None


def rel_err(v: float, ref: float) -> float:
    return abs(v - ref) / abs(ref)
