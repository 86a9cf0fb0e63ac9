"""The workflows behind the command line: run a stack file, the rigid designs, the demo.

- `run_spec(spec)` / `simulate_file(path)`: stack file → `BuiltStack` → `simulate` → `analyse` → `Report`
  (a run that did not complete returns its partial `Report`: read `Report.status`).
- `design_report(...)`: the rigid MVG/MET designs of `hertz-chain design`.
- `demo()`: the paper's optimal six-mass MVG stack, gapped and touching, against the rigid theory.

What they produce is shown by `hertz_chain.report` (table, JSON, NetCDF, CSV).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .report import model_label, signed_percent, summary_table
from .stackfile import StackSpec, load_stack_file

if TYPE_CHECKING:  # the simulator stack (JAX) is imported only when a simulation runs
    from .analysis import Report

__all__ = ["run_spec", "simulate_file", "design_report", "demo"]

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


# ------------------------------------------------------------------------------------------ running
def run_spec(spec: StackSpec) -> Report:
    """Build, simulate and analyse a stack spec. A dense output grid is added when the file asks
    for one (`solver.n_output` / `solver.dt_output`)."""
    from .analysis import analyse
    from .builder import build
    from .simulation import simulate

    built = build(spec)
    options = dict(built.simulate_options, throw=False)  # the status says how it ended (partial results)
    sol = simulate(built.stack, built.state, **options)
    if built.n_output or built.dt_output:
        if built.dt_output:
            # every multiple of dt up to t_final, t_final itself where it is one (to round-off: 0.3 ms / 1 us
            # is 299.99999..., and np.arange dropped the last sample, a review)
            k = int(np.floor(sol.t_final / built.dt_output * (1.0 + 1e-12)))
            ts = np.minimum(np.arange(k + 1) * built.dt_output, sol.t_final)
        else:
            ts = np.linspace(0.0, sol.t_final, built.n_output)
        sol = simulate(built.stack, built.state, ts=ts, **dict(options, t_max=sol.t_final))
    tol = {k: built.simulate_options["tolerances"].__getattribute__(k) for k in ("rtol", "atol")} \
        if built.simulate_options.get("tolerances") is not None else None
    report = analyse(sol, nominal_restitution=built.nominal_restitution, tolerances=tol,
                     srs_options=srs_options(spec), yield_limits=built.yield_limits)
    return dataclasses.replace(report, title=spec.title)


def srs_options(spec: StackSpec):
    """The `srs.SRSOptions` of a stack file's `[srs]` section."""
    from .spectrum import SRSOptions

    o = spec.srs
    return SRSOptions(Q=o.q, per_octave=o.per_octave, band=o.band, peak=o.peak, kind=o.type)


def simulate_file(path: str | Path) -> Report:
    """Read, simulate and analyse a stack file. The report keeps the file's title and path
    (`Report.title`, `Report.source_file`), which `report.write_output` records."""
    return dataclasses.replace(run_spec(load_stack_file(path)), source_file=str(Path(path).resolve()))


def design_report(*, ratio=None, m1=None, mn=None, e):
    """The paper's optimal MVG and MET designs for (R, e), (R, m_1, e) or (m_1, m_n, e) (`rigid.design`)."""
    from .errors import ParameterError
    from .rigid import design

    if ratio is None and (m1 is None or mn is None):
        raise ParameterError("mass-ratio", ratio, "give --mass-ratio R, or both --bottom-mass and --top-mass")
    return design(R=ratio, m1=m1, mn=mn, e=e)


# ------------------------------------------------------------------------------------------ demo
def demo() -> str:
    """Simulate `examples/mvg6_gapped.toml` and `examples/mvg6_touching.toml` (the paper's optimal
    six-mass MVG stack for R = 0.012, e = 0.8) and show how far each is from the rigid theory."""
    out = []
    reports = {}
    for name in ("mvg6_gapped", "mvg6_touching"):
        path = EXAMPLES / f"{name}.toml"
        spec = load_stack_file(path)
        reports[name] = rep = run_spec(spec)
        out.append(summary_table(rep, title=f"{spec.title}  [{path.name}]"))
        out.append("")
    g, t = reports["mvg6_gapped"], reports["mvg6_touching"]
    rigid = g.rigid.nominal_gain
    out.append("Summary: rigid theory (paper Eq 20/19) predicts G = "
               f"{rigid:.4f} for this stack.")
    out.append(f"  gapped  : {model_label(g)} G = {g.top_velocity_gain:.4f} ({signed_percent((g.top_velocity_gain - rigid) / rigid)}), "
               f"regime {g.regime}")
    out.append(f"  touching: {model_label(t)} G = {t.top_velocity_gain:.4f} ({signed_percent((t.top_velocity_gain - rigid) / rigid)}), "
               f"regime {t.regime}: a touching stack gets far less than the theory promises")
    return "\n".join(out)
