"""CI smoke run of the benchmark suite (`benchmarks/run.py --quick`): structure only, no timing assertions.

The quick run integrates one case (n = 2, gapped Tsuji stack) with the library's Tsit5/Dopri8 (Kvaerno5, the longest
compile, and plain diffrax Tsit5 only in `make bench`; tests/test_solvers.py runs Kvaerno5) and scipy
DOP853/Radau/LSODA on a three-rung tolerance ladder, one batch size, one gradient (without the comparisons that need another compile: `simulate()` timings,
diffrax's own reverse mode and central differences, which `make bench` and tests/test_gradients.py do),
and writes the Markdown
table and the raw JSON. Expected numbers below come from independent references: the rigid-body gain of
paper Eq 19 (exact for widely gapped contacts with velocity-independent restitution) and scipy's DOP853
on the same vector field.
"""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
METHODS = ("tsit5", "dopri8", "DOP853", "Radau", "LSODA")  # quick: no Kvaerno5, no plain diffrax Tsit5 (compiles)


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    md, js = out / "results.md", out / "results.json"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "run.py"), "--quick", "--output", str(md), "--json", str(js)],
        cwd=ROOT, env=dict(os.environ), capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return md.read_text(), json.loads(js.read_text())


def test_table_is_written(quick_run):
    md, _ = quick_run
    for section in ("## Targets", "## Single solves", "### n = 2", "## Reference checks", "## Batched throughput",
                    "## Gradient cost", "## Error ladders", "Machine:"):
        assert section in md
    for method in METHODS:
        assert f"| gapped-tsuji | {method} |" in md


def test_every_method_solved_with_finite_error(quick_run):
    _, data = quick_run
    (case,) = data["cases"]
    assert case["n"] == 2 and case["regime"] == "gapped-tsuji"
    assert case["ref"]["ok"] and case["ref"]["status"] == "complete"
    assert set(case["methods"]) == set(METHODS)
    for method, rec in case["methods"].items():
        common = [r for r in rec["ladder"] if r["rtol"] == 1e-10]
        assert common and common[0]["ok"], method
        r = common[0]
        # every solver at the library default rtol = atol = 1e-10 lands within 1e-6 of the reference
        # (measured 1e-11 .. 2e-8): a loose bound, this is a structural check, not an accuracy benchmark
        assert math.isfinite(r["err"]) and r["err"] < 1e-6, (method, r["err"])
        assert r["accepted"] > 0 and r["steps"] >= r["accepted"]
        assert math.isfinite(r["time"]) and r["time"] > 0


def test_reference_agrees_with_independent_checks(quick_run):
    _, data = quick_run
    (case,) = data["cases"]
    # scipy DOP853 at rtol 1e-12 on the same field (an independent integrator and end criterion): measured 6e-10
    assert case["ref_check_dop853"] < 1e-8
    # paper Eq 19 (rigid, independent collisions): n = 2, gaps 1 cm; exact up to the Tsuji e calibration (~1e-11)
    rigid = {r["law"]: r for r in data["rigid"]}
    assert set(rigid) == {"hertz", "tsuji"}
    for r in rigid.values():
        assert r["status"] == "complete"
        assert r["rel_diff"] < 1e-8, r


def test_batch_grad_and_targets_structure(quick_run):
    _, data = quick_run
    (row,) = data["batch"]["rows"]
    assert row["B"] == 16 and row["max_steps"] >= row["max_steps_used"]
    assert math.isfinite(row["simulate_batch_ms"]) and row["simulate_batch_ms"] > 0
    assert row["simulate_batch_lean_ms"] == row["vmap_launch_ms"] == "nan"  # quick: not run (compiles fewer)
    (g,) = data["grads"]
    assert g["n"] == 2 and g["regime"] == "gapped-hertz" and math.isfinite(g["grad_ratio"]) and g["grad_ratio"] > 0
    # quick: the central differences of a 1e-13 reference are not compiled (tests/test_gradients.py
    # checks the gradient against finite differences; `make bench` reports it)
    assert g["rev_vs_fd_rel"] == "nan"
    # quick: diffrax's own reverse mode is not compiled here; tests/test_gradients.py checks that it gives
    # the same discrete derivative (the full `make bench` reports it)
    assert g["diffrax_grad_ms"] == "nan"  # the JSON writes a non-finite number as text
    assert any("grad" in t["target"] for t in data["targets"])


def test_render_from_json_reproduces_the_table(quick_run, tmp_path):
    """`--render` rewrites the Markdown from a run's JSON without running anything: from the quick run's
    own JSON it must give back the quick run's Markdown, byte for byte (the same data, the same renderer)."""
    md, data = quick_run
    src = tmp_path / "in.json"
    src.write_text(json.dumps(data))
    out = tmp_path / "out.md"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "run.py"), "--render", str(src), "--output", str(out)],
        cwd=ROOT, env=dict(os.environ), capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert out.read_text() == md
