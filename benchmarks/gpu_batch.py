"""Batched throughput on whatever device JAX sees (issues 20 and 22, "GPU"): `simulate_batch(save_steps=False)`
on 10^3 .. 10^5 five-mass designs in one call each, as `hertz-chain sweep` runs a chunk.

    python benchmarks/gpu_batch.py --output benchmarks/gpu.md --json benchmarks/gpu.json
    python benchmarks/gpu_batch.py --sizes 256 --cpu-reference 0      # a CPU smoke run, seconds

Two design families, each built by the sweep's own design map (`sweeps._design_map`: one vmapped, compiled
call turns a table of values into batched stacks, no Python loop over designs):

- **baseline**: the batched case of `baselines.py` (issue 22): five-mass gapped Tsuji stacks (MVG masses of
  `cases.py`, m_1 = 8.4 kg, R = 0.012, interior masses x U[0.8, 1.2]), gaps 0.1 mm, k = 1e9 N/m^1.5,
  e = 0.8, dropped at 1 m/s, g = 0, rtol = atol = 1e-9;
- **sweep**: the designs of `sweep.py` (issue 20): the same MVG stack under gravity with gaps log-uniform in
  [1e-6, 1e-2] m and k log-uniform in [1e8, 1e10] N/m^1.5 (library tolerances): under `vmap` every design
  of a call runs until the slowest is done, so the spread of step counts costs here.

Each size is compiled once (first call, reported) and timed on a second call. With `--cpu-reference B`
the same script runs, in a subprocess on the CPU backend (every core a device), the first B designs of each
family: their top launch velocities are compared with the accelerator's (largest relative difference) and
their throughput is reported beside it, so both numbers come from one machine.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
MASSES = (8.4 * 0.012 ** (np.arange(5) / 4)).tolist()  # cases.masses(5): MVG, R = 0.012

DOCS = {
    "baseline": f"""
[drop]
impact_velocity = "1 m/s"
gravity = 0
[stack]
masses = {MASSES}
gaps = "0.1 mm"
[contact]
law = "tsuji"
stiffness = "1e9 N/m^1.5"
restitution = 0.8
[solver]
rtol = 1e-9
atol = 1e-9
[[sweep.axis]]
key = "stack.masses"
index = [2]
values = ["1 kg", "2 kg"]
[[sweep.axis]]
key = "stack.masses"
index = [3]
values = ["1 kg", "2 kg"]
[[sweep.axis]]
key = "stack.masses"
index = [4]
values = ["1 kg", "2 kg"]
""",
    "sweep": f"""
[drop]
impact_velocity = "1 m/s"
[stack]
masses = {MASSES}
gaps = 0
[contact]
law = "tsuji"
stiffness = "1e9 N/m^1.5"
restitution = 0.8
[[sweep.axis]]
key = "stack.gaps"
values = ["1e-6 m", "1e-2 m"]
[[sweep.axis]]
key = "contact.stiffness"
values = ["1e8 N/m^1.5", "1e10 N/m^1.5"]
""",
}


def values(family: str, B: int) -> np.ndarray:
    """The axis values (SI) of B designs of a family, the same for every B prefix (seeded)."""
    rng = np.random.default_rng(0)
    u = rng.uniform(size=(B, 3))
    if family == "baseline":
        return np.asarray(MASSES)[1:4] * (0.8 + 0.4 * u)
    return np.stack([10 ** (-6 + 4 * u[:, 0]), 10 ** (8 + 2 * u[:, 1])], axis=1)


def run_family(family: str, sizes: list[int]) -> list[dict]:
    """Compile and time `simulate_batch` on each size; returns one row per size."""
    import jax

    from hertz_chain.simulation import simulate_batch
    from hertz_chain.sweeps import _design_map

    text = DOCS[family]
    plan, dm, widths = _design_map(text, f"<{family}>")
    designs = jax.jit(jax.vmap(dm))
    opts = {k: v for k, v in dm.built.simulate_options.items() if k in ("solver", "tolerances", "t_max", "until")}
    rows = []
    for B in sizes:
        X = np.repeat(values(family, B), widths, axis=1)

        def call():
            stacks, states = designs(X)
            return simulate_batch(stacks, states, save_steps=False, max_steps=16_384, **opts)

        t = time.perf_counter()
        sol = call()
        first = time.perf_counter() - t
        t = time.perf_counter()
        sol = call()
        warm = time.perf_counter() - t
        steps = np.asarray(sol.num_steps)
        top = np.asarray(sol.launch_velocities)[:, -1]
        rows.append(dict(family=family, designs=B, first_call_s=first, warm_s=warm, designs_per_s=B / warm,
                         us_per_design=1e6 * warm / B, mean_steps=float(steps.mean()), max_steps=int(steps.max()),
                         ok=int(np.sum(np.asarray(sol.status_code) == 0)), top=top.tolist() if B <= 4096 else None))
        print(f"{family} B={B}: first call {first:.1f} s, warm {warm:.3f} s, {B / warm:.0f} designs/s, "
              f"steps mean {steps.mean():.0f} max {steps.max()}, ok {rows[-1]['ok']}/{B}", flush=True)
    return rows


def tight_reference(family: str, B: int) -> list[float]:
    """The top launch velocities of the first B designs of a family at rtol = atol = 1e-13 (the accuracy
    reference for both backends' default-tolerance results)."""
    import jax

    import hertz_chain as hc
    from hertz_chain.simulation import simulate_batch
    from hertz_chain.sweeps import _design_map

    plan, dm, widths = _design_map(DOCS[family], f"<{family}>")
    stacks, states = jax.jit(jax.vmap(dm))(np.repeat(values(family, B), widths, axis=1))
    opts = {k: v for k, v in dm.built.simulate_options.items() if k in ("t_max", "until")}
    sol = simulate_batch(stacks, states, save_steps=False, max_steps=65_536,
                         tolerances=hc.Tolerances(rtol=1e-13, atol=1e-13), **opts)
    return np.asarray(sol.launch_velocities)[:, -1].tolist()


def run_sweep(designs: int, chunk: int) -> dict:
    """`hc.sweep` end to end (design map, solve, Eq 19, Zarr writes and markers) on the grid of `sweep.py`
    (gap x stiffness, five masses, gravity), warmed on a two-chunk sweep of the same chunk size."""
    import shutil
    import tempfile

    import tomli_w

    import hertz_chain as hc
    from sweep import _doc  # benchmarks/sweep.py

    tmp = Path(tempfile.mkdtemp())
    warm, big = tmp / "warm.toml", tmp / "big.toml"
    warm.write_text(tomli_w.dumps(_doc(2 * chunk, chunk)))
    big.write_text(tomli_w.dumps(_doc(designs, chunk)))
    t = time.perf_counter()
    hc.sweep(warm, tmp / "warm.zarr")
    first = time.perf_counter() - t
    t = time.perf_counter()
    res = hc.sweep(big, tmp / "big.zarr")
    wall = time.perf_counter() - t
    import resource

    out = dict(designs=int(sum(res.status_counts.values())), chunk=chunk, warm_up_s=first, wall_s=wall,
               designs_per_s=sum(res.status_counts.values()) / wall, status=dict(res.status_counts),
               peak_rss_gb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20)
    shutil.rmtree(tmp, ignore_errors=True)
    print(f"sweep end to end: {out}", flush=True)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1000,10000,100000")
    ap.add_argument("--families", default="baseline,sweep")
    ap.add_argument("--cpu-reference", type=int, default=2048, help="designs run on the CPU backend (0: none)")
    ap.add_argument("--output", help="Markdown file to write")
    ap.add_argument("--json", help="raw results (JSON)")
    ap.add_argument("--sweep", type=int, default=0, help="also run `hc.sweep` end to end on this many designs")
    ap.add_argument("--sweep-chunk", type=int, default=65536)
    ap.add_argument("--rows-only", action="store_true", help=argparse.SUPPRESS)  # the CPU subprocess
    args = ap.parse_args(argv)
    sizes = [int(s) for s in args.sizes.split(",")]
    families = args.families.split(",")

    import jax

    if args.rows_only:
        print(json.dumps([r for f in families for r in run_family(f, sizes)]))
        return 0
    dev = jax.devices()[0]
    import diffrax
    import equinox

    data = dict(date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="minutes"),
                device=f"{dev.platform}: {getattr(dev, 'device_kind', '')}", devices=jax.local_device_count(),
                host=f"{platform.machine()}, {os.cpu_count()} cores",
                versions=dict(jax=jax.__version__, diffrax=diffrax.__version__, equinox=equinox.__version__),
                rows=[r for f in families for r in run_family(f, sizes)], cpu=[], sweep=None)
    data["reference"] = {f: tight_reference(f, min(1000, min(sizes))) for f in families}
    if args.sweep:
        try:
            data["sweep"] = run_sweep(args.sweep, args.sweep_chunk)
        except Exception as exc:  # noqa: BLE001  (a missing Zarr/Dask on the accelerator machine: say so)
            print(f"sweep end to end not run: {type(exc).__name__}: {exc}", flush=True)
    if args.cpu_reference:
        env = dict(os.environ, JAX_PLATFORMS="cpu")
        out = subprocess.run([sys.executable, __file__, "--rows-only", "--sizes", str(args.cpu_reference),
                              "--families", args.families], env=env, capture_output=True, text=True, timeout=900)
        try:
            data["cpu"] = json.loads(out.stdout.strip().splitlines()[-1])
        except (ValueError, IndexError):
            print("CPU reference failed:", out.stderr[-2000:], flush=True)
        for c in data["cpu"]:
            acc = next((r for r in data["rows"] if r["family"] == c["family"] and r["top"] is not None), None)
            if acc is not None and c["top"] is not None:
                k = min(len(acc["top"]), len(c["top"]))
                a, b = np.asarray(acc["top"][:k]), np.asarray(c["top"][:k])
                c["agreement"] = float(np.max(np.abs(a - b) / np.abs(b)))
                c["agreement_designs"] = k
    _write(data, args.output)
    if args.json:
        Path(args.json).write_text(json.dumps(data, indent=1))
    return 0


def _write(data: dict, path: str | None) -> None:
    lines = ["# Batched throughput on an accelerator (issues 20 and 22)", "",
             f"Generated by `benchmarks/gpu_batch.py` on {data['date']}: device {data['device']} "
             f"({data['devices']} JAX device(s)), host {data['host']}; jax {data['versions']['jax']}, diffrax "
             f"{data['versions']['diffrax']}, equinox {data['versions']['equinox']}.", "",
             "`simulate_batch(save_steps=False)` on B designs in one call (designs built by the sweep's design "
             "map); first call includes compilation; warm = the second call.", "",
             "| family | B | first call (s) | warm (s) | designs/s | us/design | mean steps | max steps | ok |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in data["rows"]:
        lines.append(f"| {r['family']} | {r['designs']} | {r['first_call_s']:.1f} | {r['warm_s']:.3f} | "
                     f"{r['designs_per_s']:.0f} | {r['us_per_design']:.2f} | {r['mean_steps']:.0f} | "
                     f"{r['max_steps']} | {r['ok']}/{r['designs']} |")
    if data["cpu"]:
        lines += ["", f"The same designs on the same machine's CPU backend ({data['host']}, every core a JAX device):",
                  "", "| family | B | warm (s) | designs/s | top launch velocity vs the accelerator |",
                  "|---|---|---|---|---|"]
        for c in data["cpu"]:
            agree = f"{c['agreement']:.1e} (largest relative difference, {c['agreement_designs']} designs)" \
                if "agreement" in c else "—"
            lines.append(f"| {c['family']} | {c['designs']} | {c['warm_s']:.3f} | {c['designs_per_s']:.0f} | {agree} |")
    ref = data.get("reference") or {}
    if ref:
        lines += ["", "Accuracy of the top launch velocity against the same designs at rtol = atol = 1e-13 on the "
                  "accelerator (relative error; maximum / median over the designs compared), each at its family's "
                  "tolerances (baseline rtol = atol = 1e-9, sweep the library's default 1e-10):", "",
                  "| family | designs | accelerator | CPU backend |",
                  "|---|---|---|---|"]
        for f, r in ref.items():
            r = np.asarray(r)
            acc = next((x for x in data["rows"] if x["family"] == f and x["top"] is not None), None)
            cpu = next((x for x in data["cpu"] if x["family"] == f and x["top"] is not None), None)

            def err(x):
                if x is None:
                    return "—"
                k = min(len(r), len(x["top"]))
                e = np.abs(np.asarray(x["top"][:k]) / r[:k] - 1)
                return f"{e.max():.1e} / {np.median(e):.1e} ({k})"

            lines.append(f"| {f} | {len(r)} | {err(acc)} | {err(cpu)} |")
    sw = data.get("sweep")
    if sw:
        lines += ["", f"`hc.sweep` end to end (`sweep.py`'s gap x stiffness grid, Zarr store, chunk {sw['chunk']}): "
                  f"{sw['designs']} designs in {sw['wall_s']:.1f} s, {sw['designs_per_s']:.0f} designs/s "
                  f"(after a {sw['warm_up_s']:.1f} s warm-up sweep that compiled the chunk); peak resident memory "
                  f"{sw['peak_rss_gb']:.2f} GB; statuses {sw['status']}."]
    text = "\n".join(lines) + "\n"
    if path:
        Path(path).write_text(text)
    print(text, flush=True)


if __name__ == "__main__":
    sys.exit(main())
