"""Benchmarks of `hertz-chain sweep` (project issue 20): `make bench` runs it after `run.py`.

    .venv/bin/python benchmarks/sweep.py --output benchmarks/sweep.md [--designs 20000]

Five-mass MVG stacks (m_1 = 8.4 kg, R = 0.012, Tsuji e = 0.8, k = 1e9 N/m^1.5, dropped at 1 m/s under
gravity) swept over the gap (log, 1e-6..1e-2 m) and the contact stiffness (log, 1e8..1e10 N/m^1.5):

1. **Overhead of the sweep machinery**: the same designs through bare `simulate_batch(save_steps=False)`
   of chunk-sized batches, against `sweep` end to end (design map, solve, Eq 19, Zarr writes and
   markers); both warm.
2. **Designs per second and the extrapolation to 10^6 designs** (issue 20's budget: under 10 min on 2
   cores), with the peak resident memory of the process.
3. **The 10 % durations** (`[sweep] durations = true`): the same sweep end to end with the top pulse
   streamed through the solve, warm.
4. **Local Dask workers**: designs per second with `--workers 1` and `2` (and `4`, oversubscribing a
   2-core machine), each worker one single-device process.
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import tomli_w

ROOT = Path(__file__).resolve().parents[1]


def _doc(designs: int, chunk: int) -> dict:
    side = max(2, int(round(math.sqrt(designs))))
    R = 0.012
    masses = (8.4 * R ** (np.arange(5) / 4)).tolist()
    return {"drop": {"impact_velocity": "1 m/s"}, "stack": {"masses": masses, "gaps": 0},
            "contact": {"law": "tsuji", "stiffness": "1e9 N/m^1.5", "restitution": 0.8},
            "sweep": {"chunk": chunk, "axis": [
                {"key": "stack.gaps", "space": "log", "start": "1e-6 m", "stop": "1e-2 m", "num": side},
                {"key": "contact.stiffness", "space": "log", "start": "1e8 N/m^1.5", "stop": "1e10 N/m^1.5",
                 "num": side}]}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--output", default=str(ROOT / "benchmarks" / "sweep.md"))
    ap.add_argument("--designs", type=int, default=20_000)
    ap.add_argument("--chunk", type=int, default=2048)
    ap.add_argument("--workers", default="1,2,4", help="local Dask worker counts to time ('' for none)")
    ap.add_argument("--rounds", type=int, default=2, help="times each path is timed, in turn (the fastest kept)")
    args = ap.parse_args(argv)

    import jax

    from hertz_chain.simulation import simulate_batch
    from hertz_chain.sweeps import _design_map, sweep

    tmp = Path(tempfile.mkdtemp())
    path = tmp / "sweep.toml"
    path.write_text(tomli_w.dumps(_doc(args.designs, args.chunk)))
    text = path.read_text()
    plan, dm, widths = _design_map(text, str(path))
    designs = jax.jit(jax.vmap(dm))  # as `sweep` does
    n = plan.size

    # warm both paths on one chunk
    sweep(path, tmp / "warm.zarr")
    shutil.rmtree(tmp / "warm.zarr")

    # 1. bare simulate_batch on the same chunks, with the same options, warmed on the first chunk
    def bare_chunk(c):
        X = np.repeat(plan.values(c), widths, axis=1)
        size = plan.chunk_rows * plan.row
        if len(X) < size:
            X = np.vstack([X, np.repeat(X[-1:], size - len(X), axis=0)])
        stacks, states = designs(X)
        simulate_batch(stacks, states, save_steps=False, max_steps=16_384)

    bare_chunk(0)
    doc = _doc(args.designs, args.chunk)
    doc["sweep"]["durations"] = True
    dpath = tmp / "durations.toml"
    dpath.write_text(tomli_w.dumps(doc))
    sweep(dpath, tmp / "dwarm.zarr")  # compiles the streamed solve
    load_start = os.getloadavg()[0]
    # the three paths timed in turn, `--rounds` times, the fastest of each kept: a shared machine's load
    # only adds time, and falls on all three alike within a round
    bare = full = with_durations = math.inf
    for r in range(args.rounds):
        t = time.perf_counter()
        for c in range(plan.n_chunks):
            bare_chunk(c)
        bare = min(bare, time.perf_counter() - t)
        t = time.perf_counter()
        res = sweep(path, tmp / f"run{r}.zarr")
        full = min(full, time.perf_counter() - t)
        t = time.perf_counter()
        dres = sweep(dpath, tmp / f"durations{r}.zarr")
        with_durations = min(with_durations, time.perf_counter() - t)
    load_end = os.getloadavg()[0]
    rss_gb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    import xarray as xr

    d10 = xr.open_zarr(tmp / f"durations{args.rounds - 1}.zarr", consolidated=False).top_duration_10.values

    rows = []
    for workers in [int(w) for w in args.workers.split(",") if w]:
        out = tmp / f"w{workers}.zarr"
        t = time.perf_counter()
        sweep(path, out, workers=workers)
        rows.append(f"| {workers} | {n / (time.perf_counter() - t):.0f} |")

    rate = n / full
    lines = ["# `hertz-chain sweep` benchmarks (issue 20)", "",
             f"Generated by `benchmarks/sweep.py --designs {args.designs} --chunk {args.chunk}` on "
             f"{datetime.date.today()}, {platform.machine()}, {jax.local_device_count()} JAX CPU device(s), "
             f"Python {sys.version.split()[0]}. {n} five-mass designs in {plan.n_chunks} chunks; status counts "
             f"{res.status_counts}. Load average {load_start:.2f} at the start of the timings, {load_end:.2f} at "
             f"their end.", "",
             "## Overhead of the sweep machinery (warm)", "",
             f"Each path timed {args.rounds} times in turn (bare, end to end, with durations); the fastest of "
             "each is kept.", "",
             "| path | wall (s) | designs/s |", "|---|---|---|",
             f"| bare `simulate_batch(save_steps=False)`, same chunks | {bare:.1f} | {n / bare:.0f} |",
             f"| `sweep` end to end (Zarr, markers, Eq 19) | {full:.1f} | {rate:.0f} |",
             f"| overhead | {100 * (full / bare - 1):.1f} % | |",
             f"| `sweep` with `durations = true` | {with_durations:.1f} | {n / with_durations:.0f} |",
             f"| cost of the durations | {100 * (with_durations / full - 1):.1f} % | |", "",
             f"With `durations = true`, {np.isfinite(d10).sum()} of {d10.size} designs have a 10 % duration "
             f"(status counts {dres.status_counts}).", "",
             "## Scale", "",
             f"- Extrapolated to 10^6 designs at this rate: {1e6 / rate / 60:.1f} min (issue 20's budget: 10 min).",
             f"- Peak resident memory of the process: {rss_gb:.2f} GB (budget 2 GB).", "",
             "## Local Dask workers (single-device worker processes; includes starting the cluster and each "
             "worker's compilation)", "", "| workers | designs/s |", "|---|---|", *rows, ""]
    Path(args.output).write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
