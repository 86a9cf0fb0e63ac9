"""Benchmark suite of project issue 6: `make bench` (full, ~10-15 min on 2 cores) or `--quick` (CI smoke).

    .venv/bin/python benchmarks/run.py --output benchmarks/results.md [--json benchmarks/results.json]
    .venv/bin/python benchmarks/run.py --quick --output /tmp/bench.md --json /tmp/bench.json

Sections: (1) single solves of every case (n x regime) by diffrax Tsit5/Dopri8/Kvaerno5 and scipy
DOP853/Radau/LSODA over a tolerance ladder, against a tight reference, with the matched-accuracy
comparison; (2) reference checks (an independent integrator; the rigid Eq 19 limit); (3) batched
throughput; (4) gradient cost; (5) compile time cold/warm and
the CLI. See benchmarks/README.md for what every column means. Timings: `time.perf_counter`, results
blocked with `jax.block_until_ready`, median of repeats, compilation excluded unless stated.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

# One XLA CPU device per core, so that a batch can be split across both cores (section 3). Single
# solves run on device 0 as usual. Must be set before JAX is imported.
_NDEV = max(1, min(os.cpu_count() or 1, 8))
if "xla_force_host_platform_device_count" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") +
                               f" --xla_force_host_platform_device_count={_NDEV}").strip()

import diffrax as dfx  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)

import hertz_chain as hc  # noqa: E402

import cases  # noqa: E402
from methods import (  # noqa: E402
    DIFFRAX_METHODS, QUICK_DIFFRAX_METHODS, SCIPY_METHODS, DiffraxCase, ScipyCase, find_matched, fine_grid, interleaved_medians,
    median_time, rel_err,
    steps_budget,
)

MATCH = 1e-7  # "matched accuracy": launch velocity within 1e-7 relative of the reference
REF_RTOL = 1e-13
COMMON_RTOL = 1e-10  # the library default rtol = atol (Tolerances())
LADDER = tuple(10.0**-k for k in range(5, 13))  # 1e-5 .. 1e-12: every method's error table
GRID = fine_grid(LADDER[0], LADDER[-1])  # 1-2-5 steps: where matched accuracy is searched
SCIPY_CAP_S = 30.0


def log(*a):
    print(*a, file=sys.stderr, flush=True)


# ============================================================================ (1) solver comparison
def run_case(n: int, regime: str, ladder, grid, quick: bool) -> dict:
    """One case: the reference, then every method on the decade `ladder` (diffrax: every rung; scipy: down
    to the common rtol) and on the finer `grid` as far as `find_matched` needs; times at the matched and
    the common rtol."""
    t_case = time.perf_counter()
    stack, state = cases.build(n, regime)
    dc = DiffraxCase(stack, state)
    ref = dc.solve("dopri8", REF_RTOL)
    ref_rtol = REF_RTOL
    if not ref["ok"]:
        ref, ref_rtol = dc.solve("dopri8", 1e-12), 1e-12
    v_ref = ref["v_top"]
    out = dict(n=n, regime=regime, ref=dict(ref, rtol=ref_rtol, solver="dopri8"), methods={})
    reps = 3 if quick else 9

    def runner(solve):
        """A cached `get(rtol)` for `find_matched`; past a timed-out rtol, tighter ones are not run."""
        cache = {}

        def get(rtol):
            if rtol not in cache:
                if any(r.get("timeout") for q, r in cache.items() if q > rtol):
                    return dict(ok=False, skipped=True, err=math.inf)  # tighter costs more: not run
                r = solve(rtol)
                r.update(rtol=rtol, err=rel_err(r["v_top"], v_ref) if r["ok"] else math.inf)
                cache[rtol] = r
            return cache[rtol]

        return get, cache

    def rungs_of(cache):
        return [cache[q] for q in sorted(cache, reverse=True)]

    # quick (CI smoke): no Kvaerno5, whose implicit solver is the longest compile (tests/test_solvers.py and
    # tests/test_registry.py run it); `make bench` times every method
    for solver in (QUICK_DIFFRAX_METHODS if quick else DIFFRAX_METHODS):
        get, cache = runner(lambda rtol: dc.solve(solver, rtol))
        for rtol in ladder:
            get(rtol)
        m = find_matched(get, grid, MATCH)
        rungs = rungs_of(cache)
        for r in rungs:  # timed where the tables report a time: the matched and the common rtol
            if r["ok"] and (r is m or r["rtol"] == COMMON_RTOL):
                r["timing_max_steps"] = ms = steps_budget(r["steps"])
                # a few-ms solve on a shared machine: bursts of 1.5x are common, so more repeats
                # (capped by median_time's 3 s budget) than for the 0.1-1 s scipy solves
                r["time"] = dc.time_launch(solver, r["rtol"], ms, reps if quick else 25)
                if r["rtol"] == COMMON_RTOL and not quick:  # quick: no second compile per method
                    r["time_simulate"] = dc.time_simulate(solver, r["rtol"], r["max_steps"], reps)
        out["methods"][solver] = dict(kind="diffrax", ladder=rungs, matched=m)

    sp = ScipyCase(stack, state, ref["t_final"])
    out["rhs_call_us"], out["jac_call_us"] = (1e6 * c for c in sp.rhs_call_cost(500 if quick else 2000))
    for method in SCIPY_METHODS:
        get, cache = runner(lambda rtol: sp.solve(method, rtol, SCIPY_CAP_S))
        for rtol in ladder:
            if rtol >= COMMON_RTOL:
                get(rtol)
        m = find_matched(get, grid, MATCH)
        rungs = rungs_of(cache)
        for r in rungs:  # repeats only where the tables report a time
            if r.get("ok") and (r is m or r["rtol"] == COMMON_RTOL):
                r["time"] = sp.time_solve(method, r["rtol"], r, repeats=2 if quick else 3, cap_s=SCIPY_CAP_S)
        out["methods"][method] = dict(kind="scipy", ladder=rungs, matched=m)

    # independent check of the reference: scipy DOP853 at 1e-12 on the same field, ending at t_final
    chk = sp.solve("DOP853", 1e-12, SCIPY_CAP_S)
    out["ref_check_dop853"] = rel_err(chk["v_top"], v_ref) if chk.get("ok") else None
    out["ref_check_tsit5"] = out["methods"]["tsit5"]["ladder"][-1]["err"]  # tsit5 at the tightest rung
    out["wall_s"] = time.perf_counter() - t_case
    return out


def rigid_checks() -> list[dict]:
    """Rigid Eq 19 limit: widely gapped n = 2 stacks, where the compliant solution must reproduce the
    independent-collision gain (Hertz e = 1; Tsuji e = 0.8, calibrated)."""
    out = []
    for law in ("hertz", "tsuji"):
        stack, state, v_eq19 = cases.rigid_check_case(law)
        ref = DiffraxCase(stack, state).solve("dopri8", REF_RTOL)
        out.append(dict(law=law, n=2, v_ref=ref["v_top"], v_eq19=v_eq19, status=ref["status"],
                        rel_diff=rel_err(ref["v_top"], v_eq19)))
    return out


# ============================================================================ (3) batches
def _designs(B: int, n: int = 5, seed: int = 0):
    """B designs of one structure: gapped-tsuji regime, mass ratio R log-uniform in [0.01, 0.1]."""
    rng = np.random.default_rng(seed)
    ratios = 10 ** rng.uniform(-2, -1, B)
    built = [cases.build(n, "gapped-tsuji", ratio=R) for R in ratios]
    stacks = hc.stack_designs([b[0] for b in built])
    states = jax.tree.map(lambda *x: jnp.stack(x), *[b[1] for b in built])
    return stacks, states


def batch_bench(sizes, quick: bool) -> dict:
    tol = hc.Tolerances()  # the library default (rtol = atol = 1e-10, onset proxy on)
    big_s, big_x = _designs(max(sizes))
    pilot = hc.simulate_batch(big_s, big_x, tolerances=tol, max_steps=4096)
    # smallest power of 2 with headroom (quick: the pilot's own budget, so that nothing compiles again)
    ms = 4096 if quick else 1 << int(math.ceil(math.log2(1.25 * int(pilot.num_steps.max()))))
    ndev = jax.local_device_count()
    rows = []

    def lv_vmap(stacks, states):
        return jax.vmap(lambda s, x: hc.launch_velocity(s, x, tolerances=tol, max_steps=ms))(stacks, states)

    jit_vmap = jax.jit(lv_vmap)
    pmapped = jax.pmap(lv_vmap)
    split = lambda tree: jax.tree.map(lambda a: a.reshape((ndev, -1) + a.shape[1:]), tree)  # noqa: E731
    for B in sizes:
        stacks = jax.tree.map(lambda a: a[:B], big_s)
        states = jax.tree.map(lambda a: a[:B], big_x)
        reps = 3 if quick else 5
        row = dict(B=B, max_steps=ms, mean_steps=float(np.mean(pilot.num_steps[:B])),
                   max_steps_used=int(np.max(pilot.num_steps[:B])))
        t = median_time(lambda: hc.simulate_batch(stacks, states, tolerances=tol, max_steps=ms), reps)
        row["simulate_batch_ms"] = 1e3 * t / B
        if not quick:  # one more compile; the quick smoke run checks the structure only
            t = median_time(lambda: hc.simulate_batch(stacks, states, tolerances=tol, max_steps=ms, save_steps=False),
                            reps)
            row["simulate_batch_lean_ms"] = 1e3 * t / B
        else:
            row["simulate_batch_lean_ms"] = math.nan
        row["vmap_launch_ms"] = (math.nan if quick else  # quick: one compile fewer (CI time)
                                 1e3 * median_time(lambda: jax.block_until_ready(jit_vmap(stacks, states)), reps) / B)
        if ndev > 1 and B % ndev == 0 and not quick:
            ss, xs = split(stacks), split(states)
            row["pmap_launch_ms"] = 1e3 * median_time(lambda: jax.block_until_ready(pmapped(ss, xs)), reps) / B
        rows.append(row)
        log(f"  batch B={B}: {row}")
    return dict(n=5, regime="gapped-tsuji, R in [0.01, 0.1]", rtol=tol.rtol, devices=ndev, rows=rows)


# ============================================================================ (4) gradients
def grad_bench(sizes, quick: bool) -> list[dict]:
    """`jax.grad` of the top launch velocity w.r.t. all masses vs one forward solve, both compiled
    (`jax.jit`), with `launch_velocity`'s defaults (rtol = atol = 1e-11, resolve_onsets). Accuracy
    against central differences of a reference solve at rtol = atol = 1e-13 (h = 1e-4 m_i: the
    reference's error over h is ~1e-8, so the differences measure the gradient, not the noise)."""
    rows = []
    # quick: the Hertz stack only (its gradient compiles in ~4 s, Tsuji's in ~12-16 s; tests/test_gradients.py
    # differentiates Tsuji)
    regimes = ("gapped-hertz",) if quick else ("gapped-tsuji", "gapped-hertz")
    for regime in regimes:
        for n in sizes:
            stack, state = cases.build(n, regime)
            laws, gaps = [stack.law_of(j) for j in stack.interfaces], np.diff(np.asarray(state.positions))
            tol = hc.Tolerances(rtol=1e-11, atol=1e-11, resolve_onsets=True)
            ref_tol = hc.Tolerances(rtol=1e-13, atol=1e-13, resolve_onsets=True)
            probe = hc.simulate(stack, state, tolerances=tol, max_steps=65536)
            ms = 1 << int(math.ceil(math.log2(1.25 * probe.num_steps)))  # checkpoints = max_steps: keep it tight

            def top(m, adjoint="reverse", tol=tol, ms=ms):
                s = hc.Stack(m, laws, gravity=0.0)
                return hc.launch_velocity(s, hc.at_impact(s, cases.V_IMPACT, gaps), tolerances=tol,
                                          max_steps=ms, adjoint=adjoint)[-1]

            m0 = jnp.asarray(stack.masses)
            fwd = jax.jit(top)
            ref = jax.jit(lambda m: top(m, "forward", ref_tol, 65536))
            grad = jax.jit(jax.grad(top))
            # diffrax's own reverse mode through the solver loop, a checkpoint at every step (the
            # library's previous default): the same discrete derivative as the replayed adjoint
            grad_dfx = jax.jit(jax.grad(lambda m: top(m, dfx.RecursiveCheckpointAdjoint(checkpoints=ms))))
            jacf = jax.jit(jax.jacfwd(lambda m: top(m, "forward")))
            reps = 3 if quick else 9
            t_c = time.perf_counter(); jax.block_until_ready(grad(m0)); c_grad = time.perf_counter() - t_c  # noqa: E702
            calls = {"fwd": lambda: jax.block_until_ready(fwd(m0)), "grad": lambda: jax.block_until_ready(grad(m0))}
            if not quick:  # quick: no second gradient compile (tests/test_gradients.py compares the modes)
                calls |= {"dfx": lambda: jax.block_until_ready(grad_dfx(m0)),
                          "jacf": lambda: jax.block_until_ready(jacf(m0))}
            # in alternation, in warm blocks (`interleaved_medians`): a slow spell falls on all of them alike
            med = interleaved_medians(calls, reps, block=1 if quick else 3, budget_s=3.0 if quick else 12.0)
            t_fwd, t_grad = med["fwd"], med["grad"]
            t_dfx, t_jacf = med.get("dfx", math.nan), med.get("jacf", math.nan)
            g_r = np.asarray(grad(m0))
            g_d = g_r * math.nan if quick else np.asarray(grad_dfx(m0))
            g_f = g_r * math.nan if quick else np.asarray(jacf(m0))
            fd = []  # central differences of the reference solve (independent check of the accuracy)
            for i in range(0 if quick else n):  # quick: not compiled (tests/test_gradients.py checks it)
                h = 1e-4 * float(m0[i])
                e = jnp.zeros(n).at[i].set(h)
                fd.append((float(ref(m0 + e)) - float(ref(m0 - e))) / (2 * h))
            fd = np.asarray(fd) if fd else g_r * math.nan
            scale = np.max(np.abs(fd)) if not quick else np.max(np.abs(g_r))
            rows.append(dict(regime=regime, n=n, steps=probe.num_steps, max_steps=ms, forward_ms=1e3 * t_fwd,
                             grad_ms=1e3 * t_grad, jacfwd_ms=1e3 * t_jacf, grad_ratio=t_grad / t_fwd,
                             diffrax_grad_ms=1e3 * t_dfx, diffrax_grad_ratio=t_dfx / t_fwd,
                             rev_vs_diffrax_rel=float(np.max(np.abs(g_r - g_d)) / np.max(np.abs(g_d))),
                             jacfwd_ratio=t_jacf / t_fwd, grad_compile_s=c_grad,
                             rev_vs_fwd_rel=float(np.max(np.abs(g_r - g_f)) / scale),
                             rev_vs_fd_rel=float(np.max(np.abs(g_r - fd)) / scale),
                             fwd_vs_fd_rel=float(np.max(np.abs(g_f - fd)) / scale)))
            log(f"  grad {regime} n={n}: {rows[-1]}")
    return rows


# ============================================================================ (5) compile, CLI
def _clean_env(**extra):
    env = {k: v for k, v in os.environ.items() if k not in ("HERTZ_CHAIN_NO_CACHE", "XLA_FLAGS", "EQX_ON_ERROR")}
    env.update(extra)
    return env


def _on_disk(root: str) -> tuple[bool, bool]:
    """(the compiled solve is in the compilation cache, the traced solve is in `_export`'s folder), for the
    cache root `root` (`HERTZ_CHAIN_CACHE_DIR`; JAX's cache is its `jax/` subfolder, `hertz_chain._cache`)."""
    folder = os.path.join(root, "jax")
    if not os.path.isdir(folder):
        return False, False
    compiled = any(f.startswith(("jit__solve", "jit_simulate__solve")) for f in os.listdir(folder))
    export = os.path.join(folder, "export")
    traced = os.path.isdir(export) and any(f.endswith(".jaxexport") for f in os.listdir(export))
    return compiled, traced


def compile_and_cli(quick: bool) -> dict:
    py = sys.executable
    cli = os.path.join(os.path.dirname(py), "hertz-chain")
    demo = os.path.join(ROOT, "examples", "issue5_normative.toml")
    out = dict(probe={}, cli={})

    def wall(cmd, env):
        t = time.perf_counter()
        p = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True, timeout=300)
        return time.perf_counter() - t, p

    variants = [] if quick else [("default", {}), ("EQX_ON_ERROR=nan", {"EQX_ON_ERROR": "nan"})]
    for label, extra in variants:
        tmp = tempfile.mkdtemp(prefix="hc-bench-cache-")
        try:
            env = _clean_env(HERTZ_CHAIN_CACHE_DIR=tmp, **extra)
            rec = {}
            for phase in ("cold", "warm"):
                _, p = wall([py, os.path.join(HERE, "probe_compile.py")], env)
                if p.returncode != 0:
                    raise RuntimeError(p.stderr[-2000:])
                rec[phase] = json.loads(p.stdout.strip().splitlines()[-1])
            rec["cache_files"] = len(os.listdir(os.path.join(tmp, "jax")))
            rec["solve_cached"], rec["solve_exported"] = _on_disk(tmp)
            out["probe"][label] = rec
            log(f"  compile probe [{label}]: {rec}")
            if not quick and os.path.exists(cli):
                tmp2 = tempfile.mkdtemp(prefix="hc-bench-cli-")
                env2 = _clean_env(HERTZ_CHAIN_CACHE_DIR=tmp2, **extra)
                t_cold, p = wall([cli, "simulate", demo], env2)
                ok = p.returncode == 0
                warm = [wall([cli, "simulate", demo], env2)[0] for _ in range(3)]
                compiled, traced = _on_disk(tmp2)
                out["cli"][label] = dict(cold_s=t_cold, warm_s=statistics.median(warm), warm_all=warm, ok=ok,
                                         solve_cached=compiled, solve_exported=traced)
                shutil.rmtree(tmp2, ignore_errors=True)
                log(f"  cli [{label}]: {out['cli'][label]}")
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    if os.path.exists(cli):
        out["help_s"] = statistics.median([wall([cli, "--help"], _clean_env())[0] for _ in range(3 if quick else 5)])
    return out


# ============================================================================ summaries
def _present(*tables) -> list[str]:
    """The diffrax methods (in `DIFFRAX_METHODS` order) that every one of `tables` (dicts keyed by method)
    has: all four in `make bench`, three in the quick smoke run."""
    return [m for m in DIFFRAX_METHODS if all(m in t for t in tables)]


def _best_diffrax(res):
    best = None
    for solver in _present(res["methods"]):
        m = res["methods"][solver]["matched"]
        if m is not None and (best is None or m["time"] < best[1]["time"]):
            best = (solver, m)
    return best


def targets(results, batch, grads, comp) -> list[dict]:
    rows = []
    for res in results:
        if res["n"] != 10:
            continue
        best = _best_diffrax(res)
        for scipy_m, goal in (("DOP853", 15.0), ("Radau", 50.0)):
            m = res["methods"][scipy_m]["matched"]
            last = res["methods"][scipy_m]["ladder"][-1]
            if best is None:
                val, note = None, "no diffrax method reached 1e-7"
            elif m is None:
                val = None
                note = f"{scipy_m} never reached 1e-7" + (" (timed out)" if last.get("timeout") else "")
            else:
                val = m["time"] / best[1]["time"]
                note = f"{best[0]} @ {best[1]['rtol']:.0e} vs {scipy_m} @ {m['rtol']:.0e}"
            rows.append(dict(target=f"10-mass solve vs {scipy_m} at matched accuracy ({res['regime']})",
                             goal=f">= {goal:g}x", value=None if val is None else f"{val:.1f}x",
                             met=None if val is None else val >= goal, note=note))
    if batch:
        big = max(batch["rows"], key=lambda r: r["B"])
        val = big["simulate_batch_lean_ms"]
        rows.append(dict(target=f"batched 5-mass designs, B = {max(x['B'] for x in batch['rows'])}",
                         goal="<= 0.5 ms/design", value=f"{val:.3f} ms", met=val <= 0.5,
                         note=f"simulate_batch(save_steps=False) over {batch['devices']} devices "
                              f"(with the step history: {big['simulate_batch_ms']:.3f} ms)"))
    for g in grads or []:
        rows.append(dict(target=f"jax.grad of top launch velocity w.r.t. {g['n']} masses ({g.get('regime', 'gapped-tsuji')})",
                         goal="<= 5x one solve", value=f"{g['grad_ratio']:.1f}x", met=g["grad_ratio"] <= 5,
                         note=f"{g['grad_ms']:.1f} ms vs {g['forward_ms']:.1f} ms (both jitted); forward mode "
                              f"(jax.jacfwd) {g['jacfwd_ratio']:.1f}x, see 'Gradient cost'"))
    for label, c in (comp or {}).get("cli", {}).items():
        rows.append(dict(target=f"warm `hertz-chain simulate` of the demo [{label}]", goal="< 5 s",
                         value=f"{c['warm_s']:.2f} s", met=c["warm_s"] < 5.0 and c["ok"],
                         note=f"solve cached on disk: {c['solve_cached']}"))
    return rows


def recommend(results) -> list[dict]:
    """Per regime: the diffrax method with the smallest total time at matched accuracy over all n."""
    out = []
    for regime in sorted({r["regime"] for r in results}, key=list(cases.REGIMES).index):
        per = {}
        for solver in _present(*(res["methods"] for res in results)):
            tot, rt, ok = 0.0, [], True
            for res in results:
                if res["regime"] != regime:
                    continue
                m = res["methods"][solver]["matched"]
                if m is None:
                    ok = False
                    rt.append(f"n={res['n']}: -")
                    continue
                tot += m["time"]
                rt.append(f"n={res['n']}: {m['rtol']:.0e}")
            per[solver] = (tot if ok else math.inf, rt)
        best = min(per, key=lambda s: per[s][0])
        out.append(dict(regime=regime, best=best, total_ms=1e3 * per[best][0], rtols=per[best][1],
                        others={s: 1e3 * v[0] for s, v in per.items()}))
    return out


# ============================================================================ markdown
def _f(x, fmt="{:.2f}", none="-"):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return none
    return fmt.format(x)


def _e(x):
    return _f(x, "{:.1e}")


def _steps(r):
    if not r or not r.get("ok"):
        return "-"
    rej = "n/a" if r.get("rejected") is None else r["rejected"]
    return f"{r['steps']} ({r['accepted']}/{rej})"


def _time_ms(r):
    if r is None:
        return "-"
    if r.get("timeout"):
        return f"> {SCIPY_CAP_S:g} s"
    return _f(1e3 * r["time"]) if "time" in r and r.get("ok") else "-"


def machine() -> dict:
    model = "?"
    try:
        for line in subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines():
            if line.startswith("Model name"):
                model = line.split(":", 1)[1].strip()
    except OSError:
        pass
    import diffrax
    import equinox
    import jaxlib
    import scipy

    return dict(cpu=model, cores=os.cpu_count(), xla_devices=jax.local_device_count(), python=platform.python_version(),
                jax=jax.__version__, jaxlib=jaxlib.__version__, diffrax=diffrax.__version__,
                equinox=equinox.__version__, scipy=scipy.__version__, numpy=np.__version__,
                date=datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
                loadavg_start=os.getloadavg()[0])


def markdown(data: dict) -> str:
    L = []
    mc = data["machine"]
    L += ["# hertz_chain benchmarks", "",
          f"Generated by `benchmarks/run.py{' --quick' if data['quick'] else ''}` on {mc['date']} "
          f"(total {data['wall_s'] / 60:.1f} min). Column meanings and how to rerun: `benchmarks/README.md`.", "",
          f"Machine: {mc['cpu']}, {mc['cores']} cores ({mc['xla_devices']} XLA CPU devices), load average at start "
          f"{mc['loadavg_start']:.2f} (timings are noisy: other work shared the machine; compare ratios within this run). "
          f"Python {mc['python']}, jax {mc['jax']}, jaxlib {mc['jaxlib']}, diffrax {mc['diffrax']}, equinox "
          f"{mc['equinox']}, scipy {mc['scipy']}, numpy {mc['numpy']}." + (
              f" Batches: {mc['batch_rerun']}." if mc.get("batch_rerun") else "") + (
              f" Gradients: {mc['grads_rerun']}." if mc.get("grads_rerun") else ""), ""]

    L += ["## Targets", "", "| target | goal | measured | met | how |", "|---|---|---|---|---|"]
    for t in data["targets"]:
        met = "n/a" if t["met"] is None else ("yes" if t["met"] else "**no**")
        L.append(f"| {t['target']} | {t['goal']} | {t['value'] or '-'} | {met} | {t['note']} |")
    L.append("")

    if data["recommend"]:
        dfx_cols = [r["others"] for r in data["recommend"]]
        L += ["## Suggested diffrax solver per regime", "",
              "Fastest diffrax method at matched accuracy (launch velocity within 1e-7), summed over n; the matched "
              "rtol = atol per n. Other columns: the same sum for each method "
              "(ms; `inf` = missed 1e-7 for some n).", "",
              "| regime | best | total ms | rtol needed | " + " | ".join(_present(*dfx_cols)) + " |",
              "|---|---|---|---|" + "---|" * len(_present(*dfx_cols))]
        for r in data["recommend"]:
            L.append(f"| {r['regime']} | {r['best']} | {r['total_ms']:.1f} | {', '.join(r['rtols'])} | "
                     + " | ".join(_f(r["others"][s], "{:.1f}", "inf") for s in _present(*dfx_cols)) + " |")
        L.append("")

    L += ["## Single solves", "",
          "Per case: reference = diffrax Dopri8 at rtol = atol = 1e-13 (scaled units). **matched** (`*`): the loosest rtol "
          "of the 1-2-5 grid whose error is <= 1e-7 and stays so at every grid rtol down to a tenth of it; time there; `x DOP853` = DOP853's matched time over "
          "this method's. **@1e-10**: every method at the library default rtol = atol = 1e-10 (diffrax without the onset proxy, the same equations as scipy). diffrax times are compiled "
          "`launch_velocity` calls; `simulate()` adds the user-facing host-side post-processing. steps = attempted "
          "(accepted/rejected). scipy: jitted JAX RHS (+ jitted `jax.jacfwd` Jacobian for Radau/LSODA), "
          "one dispatch per evaluation.", ""]
    for n in sorted({r["n"] for r in data["cases"]}):
        L += [f"### n = {n}", "",
              "| regime | method | rtol* | time* ms | err* | steps* | x DOP853 | time@1e-10 ms | simulate() ms | err@1e-10 | steps@1e-10 |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
        for res in data["cases"]:
            if res["n"] != n:
                continue
            dop = res["methods"]["DOP853"]["matched"]
            for meth, rec in res["methods"].items():
                m = rec["matched"]
                c = next((r for r in rec["ladder"] if r["rtol"] == COMMON_RTOL), None)
                last = rec["ladder"][-1]
                if m is None:
                    rt = "timed out" if last.get("timeout") else "not reached"
                else:
                    rt = f"{m['rtol']:.0e}"
                ratio = dop["time"] / m["time"] if (m is not None and dop is not None) else None
                L.append(f"| {res['regime']} | {meth} | {rt} | {_time_ms(m)} | {_e(m['err'] if m else None)} | "
                         f"{_steps(m)} | {_f(ratio, '{:.1f}')} | {_time_ms(c) if c else ('> cap' if last.get('timeout') else '-')} | "
                         f"{_f(1e3 * c['time_simulate']) if c and 'time_simulate' in c else ''} | "
                         f"{_e(c['err'] if c and c.get('ok') else None)} | {_steps(c)} |")
        L.append("")

    L += ["## Reference checks", "",
          f"`tsit5@{data['ladder'][-1]:.0e}`, `DOP853@1e-12`: relative difference of the top launch velocity from the reference (another "
          "diffrax method; scipy's DOP853 on the same field ending at the reference's `t_final`). RHS/Jacobian call: "
          "cost of one jitted evaluation called from Python (what scipy pays per evaluation).", "",
          f"| n | regime | v_ref (m/s) | ref steps | t_final (ms) | tsit5@{data['ladder'][-1]:.0e} | DOP853@1e-12 | RHS call us | Jacobian call us | case wall s |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for res in data["cases"]:
        ref = res["ref"]
        L.append(f"| {res['n']} | {res['regime']} | {ref['v_top']:.10g} | {ref['steps']} | {1e3 * ref['t_final']:.3f} | "
                 f"{_e(res['ref_check_tsit5'])} | {_e(res['ref_check_dop853'])} | {res['rhs_call_us']:.1f} | "
                 f"{res['jac_call_us']:.1f} | {res['wall_s']:.0f} |")
    L += ["", "Rigid limit (paper Eq 19, independent collisions): n = 2, gaps 1 cm, g = 0; reference vs "
          "`stack_gain(masses, e) * v`:", "", "| law | v_ref (m/s) | Eq 19 (m/s) | rel. diff |", "|---|---|---|---|"]
    for r in data["rigid"]:
        L.append(f"| {r['law']} | {r['v_ref']:.12g} | {r['v_eq19']:.12g} | {r['rel_diff']:.1e} |")
    L.append("")

    b = data.get("batch")
    if b:
        L += ["## Batched throughput", "",
              f"{b['n']}-mass designs ({b['regime']}), rtol = atol = {b['rtol']:g}, max_steps = {b['rows'][0]['max_steps']} "
              f"(a power of two with 25 % headroom over the slowest design). ms per design (batch time / B); "
              f"designs/s = B / batch time. "
              f"`simulate_batch`: the library's batched entry point, which splits up to 128 designs over the "
              f"{b['devices']} XLA CPU devices (one per core; from B >= 2 x devices) and solves more in pieces of "
              f"128, a thread per core taking the next piece, with the step history (default) "
              f"and without (`save_steps=False`: launch data and energy audit only); `vmap`: "
              f"`jax.jit(jax.vmap(launch_velocity))` on one device; `pmap`: the same split over the devices "
              f"with `jax.pmap`.", "",
              "| B | mean steps | simulate_batch ms/design | designs/s | simulate_batch, save_steps=False ms/design | designs/s "
              "| vmap (1 device) ms/design | pmap ms/design |",
              "|---|---|---|---|---|---|---|---|"]

        def per_s(ms):
            return _f(None if ms is None or not ms > 0 else 1e3 / ms, "{:.0f}")

        for r in b["rows"]:
            lean = r.get("simulate_batch_lean_ms")
            L.append(f"| {r['B']} | {r['mean_steps']:.0f} | {r['simulate_batch_ms']:.3f} | "
                     f"{per_s(r['simulate_batch_ms'])} | {_f(lean, '{:.3f}')} | {per_s(lean)} | "
                     f"{r['vmap_launch_ms']:.3f} | {_f(r.get('pmap_launch_ms'), '{:.3f}')} |")
        L.append("")

    if data.get("grads"):
        L += ["## Gradient cost", "",
              "`launch_velocity` defaults (rtol = atol = 1e-11, `resolve_onsets=True`). forward: "
              "`jax.jit` of the top launch velocity as a function of the masses; grad: `jax.jit(jax.grad(...))` "
              "(reverse mode, `launch_velocity`'s replayed discrete adjoint); diffrax grad: the same with "
              "`adjoint=diffrax.RecursiveCheckpointAdjoint(checkpoints=max_steps)` (reverse mode through the solver "
              "loop); rev vs diffrax: max |difference| / max |diffrax gradient| (the same discrete derivative until 2026-11-26; since then the replay splits contact onsets and releases out of its steps, so they differ by diffrax's error at onsets); "
              "jacfwd: `adjoint=\"forward\"` with `jax.jacfwd`. "
              "rev vs fwd, rev / fwd vs FD: max |difference| / max |FD gradient|, FD = central differences "
              "(h = 1e-4 m_i) of a reference solve at rtol = atol = 1e-13. The solver controls the error of the "
              "solution, not of its derivative: Tsuji's `delta^{1/4}` damping has an unbounded derivative at "
              "contact onset, so its gradient converges more slowly than Hertz's as the tolerance is tightened.", "",
              "| regime | n | steps | max_steps | forward ms | grad ms | grad / forward | diffrax grad ms | diffrax grad / forward | rev vs diffrax | jacfwd ms | jacfwd / forward | grad compile s | rev vs fwd | rev vs FD | fwd vs FD |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for g in data["grads"]:
            L.append(f"| {g.get('regime', 'gapped-tsuji')} | {g['n']} | {g['steps']} | {g['max_steps']} | {g['forward_ms']:.2f} | {g['grad_ms']:.2f} | "
                     f"{g['grad_ratio']:.2f} | {_f(g.get('diffrax_grad_ms'), '{:.2f}')} | {_f(g.get('diffrax_grad_ratio'), '{:.2f}')} | "
                     f"{_f(g.get('rev_vs_diffrax_rel'), '{:.1e}')} | {g['jacfwd_ms']:.2f} | {g['jacfwd_ratio']:.2f} | {g['grad_compile_s']:.1f} | "
                     f"{g['rev_vs_fwd_rel']:.1e} | {g['rev_vs_fd_rel']:.1e} | {g.get('fwd_vs_fd_rel', float('nan')):.1e} |")
        L.append("")

    c = data.get("compile")
    if c:
        L += ["## Compile time and the CLI", ""]
    if c and c["probe"]:
        L += ["Subprocesses (`benchmarks/probe_compile.py`): cold = empty `HERTZ_CHAIN_CACHE_DIR`, warm = the same folder "
              "again. first = trace + compile (or cache load) + run; second = run only. 5-mass gapped Tsuji, default tolerances. "
              "compiled / traced on disk: the solve's entry in JAX's compilation cache / its `jax.export` module "
              "(`hertz_chain._export`, which skips the trace; under either `EQX_ON_ERROR`).", "",
              "| env | phase | import s | simulate first s | simulate second s | launch_velocity first s | launch second s | compiled on disk | traced on disk |",
              "|---|---|---|---|---|---|---|---|---|"]
        for label, rec in c["probe"].items():
            for ph in ("cold", "warm"):
                p = rec[ph]
                L.append(f"| {label} | {ph} | {p['import_s']:.2f} | {p['simulate_first_s']:.2f} | {p['simulate_second_s']:.3f} | "
                         f"{p['launch_first_s']:.2f} | {p['launch_second_s']:.3f} | {rec['solve_cached']} | "
                         f"{rec.get('solve_exported', '-')} |")
    if c:
        if c.get("cli"):
            L += ["", "`hertz-chain simulate examples/issue5_normative.toml` wall time (s), fresh cache folder:", "",
                  "| env | cold | warm (median of 3) | compiled on disk | traced on disk |", "|---|---|---|---|---|"]
            for label, r in c["cli"].items():
                L.append(f"| {label} | {r['cold_s']:.2f} | {r['warm_s']:.2f} | {r['solve_cached']} | "
                         f"{r.get('solve_exported', '-')} |")
        if "help_s" in c:
            L += ["", f"`hertz-chain --help`: {c['help_s']:.2f} s (median)."]
        L.append("")

    L += ["## Error ladders", "",
          "Relative error of the top launch velocity per decade rtol = atol, and the time (ms) where measured (at the "
          "matched and the common rtol; scipy: median of repeats there). `> cap`: a scipy run "
          f"stopped after {SCIPY_CAP_S:g} s; blank: not run (scipy runs the decades down to 1e-10 and the rtols the "
          "matched-accuracy search needs). The 2x and 5x rtols of that search are in the JSON (`ladder` of each method).", "",
          "| n | regime | method | " + " | ".join(f"{r:.0e}" for r in data["ladder"]) + " |",
          "|---|---|---|" + "---|" * len(data["ladder"])]
    for res in data["cases"]:
        for meth, rec in res["methods"].items():
            by_rtol = {r["rtol"]: r for r in rec["ladder"]}
            cells = []
            for q in data["ladder"]:
                r = by_rtol.get(q)
                if r is None:
                    cells.append("")
                elif r.get("timeout"):
                    cells.append("> cap")
                elif not r.get("ok"):
                    cells.append("fail")
                else:
                    cells.append(f"{r['err']:.0e}" + (f" / {_time_ms(r)}" if "time" in r else ""))
            L.append(f"| {res['n']} | {res['regime']} | {meth} | " + " | ".join(cells) + " |")
    L.append("")
    return "\n".join(L)


# ============================================================================ main
def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(x) else str(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def _from_json(x):
    """Inverse of `_jsonable` for the non-finite floats it writes as strings ("nan", "inf", "-inf")."""
    if isinstance(x, dict):
        return {k: _from_json(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_from_json(v) for v in x]
    if x in ("nan", "inf", "-inf"):
        return float(x)
    return x


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--output", default=os.path.join(HERE, "results.md"), help="Markdown table to write.")
    ap.add_argument("--json", default=None, help="Also write the raw results as JSON.")
    ap.add_argument("--quick", action="store_true", help="CI smoke run: n = 2, one regime, one batch size, no CLI.")
    ap.add_argument("--sizes", default=None, help="Comma-separated n (default 2,5,10,20).")
    ap.add_argument("--regimes", default=None, help=f"Comma-separated regimes (default all: {','.join(cases.REGIMES)}).")
    ap.add_argument("--skip", default="", help="Comma-separated sections to skip: batch,grad,compile.")
    ap.add_argument("--render", default=None, metavar="JSON",
                    help="Rewrite the Markdown (and targets) from a previous run's JSON; runs nothing.")
    args = ap.parse_args(argv)
    if args.render:
        with open(args.render) as fh:
            data = _from_json(json.load(fh))
        data["targets"] = targets(data["cases"], data.get("batch"), data.get("grads"), data.get("compile"))
        data["recommend"] = recommend(data["cases"])
        _write(data, args.output, args.json if args.json != args.render else None)
        log(f"rendered {args.output} from {args.render}")
        return 0
    t0 = time.perf_counter()
    quick = args.quick
    sizes = [int(s) for s in args.sizes.split(",")] if args.sizes else ([2] if quick else list(cases.SIZES))
    regimes = args.regimes.split(",") if args.regimes else (["gapped-tsuji"] if quick else list(cases.REGIMES))
    ladder = (1e-6, 1e-8, 1e-10) if quick else LADDER
    grid = ladder if quick else GRID
    skip = set(filter(None, args.skip.split(",")))
    data = dict(quick=quick, machine=machine(), ladder=list(ladder), grid=list(grid), match=MATCH)
    log(f"machine: {data['machine']}")

    data["cases"] = []
    for n in sizes:
        for regime in regimes:
            log(f"case n={n} {regime} ...")
            res = run_case(n, regime, ladder, grid, quick)
            data["cases"].append(res)
            log(f"  done in {res['wall_s']:.0f} s; matched: " + ", ".join(
                f"{k}={v['matched']['rtol']:.0e}" if v["matched"] else f"{k}=-" for k, v in res["methods"].items()))
    data["section_s"] = {"cases": time.perf_counter() - t0}

    def section(name, fn):
        t = time.perf_counter()
        data[name] = fn()
        data["section_s"][name] = time.perf_counter() - t
        log(f"section {name}: {data['section_s'][name]:.0f} s")

    section("rigid", rigid_checks)
    section("batch", lambda: None if "batch" in skip else batch_bench([16] if quick else [1, 16, 256, 1024], quick))
    section("grads", lambda: None if "grad" in skip else grad_bench([2] if quick else [5, 10], quick))
    section("compile", lambda: None if "compile" in skip else compile_and_cli(quick))
    data["targets"] = targets(data["cases"], data["batch"], data["grads"], data["compile"])
    data["recommend"] = recommend(data["cases"])
    data["wall_s"] = time.perf_counter() - t0
    _write(data, args.output, args.json)
    log(f"wrote {args.output} in {data['wall_s']:.0f} s")
    return 0


def _write(data, output, json_path) -> None:
    md = markdown(data)
    os.makedirs(os.path.dirname(os.path.abspath(output)), exist_ok=True)
    with open(output, "w") as fh:
        fh.write(md)
    if json_path:
        with open(json_path, "w") as fh:
            json.dump(_jsonable(data), fh, indent=1)


if __name__ == "__main__":
    sys.exit(main())
