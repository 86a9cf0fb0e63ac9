"""The default solver, measured as users run it: Tsit5 against Dopri8 through `prepare_launch`.

`run.py`'s solver table compares diffrax methods on the scipy-comparable equations (no onset landing, g = 0)
and in one process section after another; its verdict on Tsit5 against Dopri8 moved between runs (Tsit5
fastest in all five regimes on 2026-11-23, Dopri8 in three of five on 2026-11-28). This study asks the
question the default answers, under the library's own defaults: onsets landed on step ends, the
cascade-end rule, and gravity on as well as off.

For every case (the five regimes of `cases.py`, n = 5 and 10, g = 0 and 9.80665 m/s^2):

- reference: `launch_velocity` with Dopri8 at rtol = atol = 1e-13;
- each solver's error on the top launch velocity over the 1-2-5 rtol grid (1e-5 to 1e-12), and its
  matched rtol (`methods.find_matched`, relative error 1e-7, kept a decade tighter);
- the two solvers timed in alternation (`methods.interleaved_medians`, blocks of 5, the last 4 timed), at
  their matched rtols and at the default rtol = atol = 1e-10, each a compiled `prepare_launch` callable.

`python benchmarks/solver_choice.py --output benchmarks/solver_choice.md` (part of `make bench`); `--quick`
for one case.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cases  # noqa: E402
from methods import fine_grid, find_matched, interleaved_medians, rel_err  # noqa: E402

import hertz_chain as hc  # noqa: E402

MATCH = 1e-7
SOLVERS = ("tsit5", "dopri8")
DEFAULT_RTOL = hc.Tolerances().rtol


def run_case(n: int, regime: str, gravity: float, grid, budget_s: float) -> dict:
    stack, state = cases.build(n, regime, gravity=gravity)
    ref = float(hc.launch_velocity(stack, state, solver="dopri8", tolerances=hc.Tolerances(rtol=1e-13, atol=1e-13),
                                   max_steps=1_000_000)[-1])
    out = dict(n=n, regime=regime, gravity=gravity, v_ref=ref, solvers={})
    fns = {}
    for solver in SOLVERS:
        cache: dict = {}

        def get(rtol, solver=solver, cache=cache):
            if rtol not in cache:
                tol = hc.Tolerances(rtol=rtol, atol=rtol)
                try:
                    fn = hc.prepare_launch(stack, state, solver=solver, tolerances=tol)
                    v = float(fn(stack, state)[-1])
                    cache[rtol] = dict(rtol=rtol, ok=True, err=rel_err(v, ref), fn=fn)
                except hc.SolverError as exc:
                    cache[rtol] = dict(rtol=rtol, ok=False, err=float("inf"), why=str(exc)[:80])
            return cache[rtol]

        matched = find_matched(get, grid, MATCH)
        default = get(DEFAULT_RTOL)
        out["solvers"][solver] = dict(
            errors={f"{r:.0e}": cache[r]["err"] for r in grid if r in cache},
            matched_rtol=None if matched is None else matched["rtol"],
            err_matched=None if matched is None else matched["err"],
            err_default=default["err"])
        if matched is not None:
            fns[f"{solver}@matched"] = (lambda f=matched["fn"]: f(stack, state).block_until_ready())
        fns[f"{solver}@default"] = (lambda f=default["fn"]: f(stack, state).block_until_ready())
    times = interleaved_medians(fns, rounds=40, warmup=1, budget_s=budget_s, block=5)
    for solver in SOLVERS:
        s = out["solvers"][solver]
        s["ms_matched"] = 1e3 * times[f"{solver}@matched"] if f"{solver}@matched" in times else None
        s["ms_default"] = 1e3 * times[f"{solver}@default"]
    return out


def write(results: list, path: Path, meta: dict) -> None:
    L = ["# The default solver: Tsit5 against Dopri8, as users run them", "",
         f"`benchmarks/solver_choice.py`, {meta['date']}, {meta['machine']}, load {meta['load']}: "
         "`prepare_launch` with the library's defaults (onsets landed on step ends, the cascade-end rule), "
         "the five regimes of `cases.py` (MVG, R = 0.012, 1 m/s, k = 1e9 N/m^1.5, gaps 0.1 mm), with and "
         "without gravity. Reference: Dopri8 at rtol = atol = 1e-13. **matched**: the loosest rtol of the 1-2-5 "
         "grid whose error on the top launch velocity is <= 1e-7 and stays so a decade tighter; times are "
         "medians of warm calls in alternation (blocks of 5, the last 4 timed).", "",
         "| regime | g | n | Tsit5 rtol* | Tsit5 ms* | Dopri8 rtol* | Dopri8 ms* | Dopri8/Tsit5 * | "
         "Tsit5 err@1e-10 | Dopri8 err@1e-10 | Tsit5 ms@1e-10 | Dopri8 ms@1e-10 |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        t, d = r["solvers"]["tsit5"], r["solvers"]["dopri8"]
        ratio = (d["ms_matched"] / t["ms_matched"]) if t["ms_matched"] and d["ms_matched"] else None
        f = lambda x, p=".0e": "-" if x is None else format(x, p)  # noqa: E731
        L.append(f"| {r['regime']} | {r['gravity']:g} | {r['n']} | {f(t['matched_rtol'])} | {f(t['ms_matched'], '.2f')} | "
                 f"{f(d['matched_rtol'])} | {f(d['ms_matched'], '.2f')} | {f(ratio, '.2f')} | "
                 f"{t['err_default']:.1e} | {d['err_default']:.1e} | {t['ms_default']:.2f} | {d['ms_default']:.2f} |")
    tot = {s: sum(r["solvers"][s]["ms_matched"] or float("inf") for r in results) for s in SOLVERS}
    wins = sum(1 for r in results if (r["solvers"]["dopri8"]["ms_matched"] or float("inf"))
               < (r["solvers"]["tsit5"]["ms_matched"] or float("inf")))
    miss = {s: sum(1 for r in results if r["solvers"][s]["err_default"] > MATCH) for s in SOLVERS}
    at_default = {s: sum(r["solvers"][s]["ms_default"] for r in results) for s in SOLVERS}
    worst = {s: max(r["solvers"][s]["err_default"] for r in results) for s in SOLVERS}
    L += ["", f"Summed at matched accuracy: Tsit5 {tot['tsit5']:.1f} ms, Dopri8 {tot['dopri8']:.1f} ms; Dopri8 faster "
          f"in {wins} of {len(results)} cases. At the default 1e-10, the top launch velocity misses 1e-7 in "
          f"{miss['tsit5']} of {len(results)} cases with Tsit5 (worst {worst['tsit5']:.1e}) and {miss['dopri8']} with "
          f"Dopri8 (worst {worst['dopri8']:.1e}); summed there, Tsit5 {at_default['tsit5']:.1f} ms, Dopri8 "
          f"{at_default['dopri8']:.1f} ms.", ""]
    path.write_text("\n".join(L) + "\n", encoding="utf-8")
    path.with_suffix(".json").write_text(json.dumps(dict(meta=meta, results=results), indent=1), encoding="utf-8")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--output", type=Path, default=Path(__file__).resolve().parent / "solver_choice.md")
    ap.add_argument("--quick", action="store_true", help="one case (gapped Hertz, n = 5, with gravity)")
    args = ap.parse_args()
    grid = fine_grid(1e-5, 1e-12)
    todo = ([("gapped-hertz", 5, 9.80665)] if args.quick else
            [(reg, n, g) for reg in cases.REGIMES for g in (0.0, 9.80665) for n in (5, 10)])
    results = []
    t0 = time.time()
    for regime, n, g in todo:
        results.append(run_case(n, regime, g, grid, budget_s=1.0 if args.quick else 4.0))
        r = results[-1]["solvers"]
        print(f"{regime} g={g:g} n={n}: tsit5 {r['tsit5']['matched_rtol']} {r['tsit5']['ms_matched']} ms, "
              f"dopri8 {r['dopri8']['matched_rtol']} {r['dopri8']['ms_matched']} ms ({time.time() - t0:.0f} s)",
              flush=True)
    meta = dict(date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), machine=f"{os.cpu_count()} CPU cores",
                load=" / ".join(f"{x:.2f}" for x in os.getloadavg()), seconds=round(time.time() - t0, 1),
                quick=args.quick)
    write(results, args.output, meta)


if __name__ == "__main__":
    main()
