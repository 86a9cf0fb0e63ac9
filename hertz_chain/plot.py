"""Matplotlib figures of a `Report`: velocities, contact forces, the top pulse and its SRS."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .analysis import Report
from .pulse import G0

__all__ = ["report_figure", "plot_report", "plot_optimize", "plot_sweep", "plot_check", "plot_compare"]


def report_figure(report: Report):
    """A 2×2 figure: velocities, contact forces (and the far wall's, where a `[wall]` holds the chain), the
    top mass's pulse (g) and its SRS."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    st = report.solution.steps
    t_ms = st.t * 1e3
    n = len(report.masses)
    fig, axes = plt.subplots(2, 2, figsize=(12, 8), constrained_layout=True)
    ax = axes[0, 0]
    for i in range(n):
        ax.plot(t_ms, st.velocities[:, i], label=f"mass {i + 1}")
    # with the ground, > 0 is upward (away from it) with or without gravity (a review: a gapped stack at g = 0
    # read "> 0 away from mass 1"); a chain without the ground has no up: away from mass 1
    vertical = report.ground
    ax.set(xlabel="time (ms)", ylabel=f"velocity (m/s, {'upward' if vertical else '> 0 away from mass 1'})",
           title="Velocities")
    ax.legend(fontsize="small", ncol=2)
    ax = axes[0, 1]
    for j in range(0 if report.ground else 1, n):
        ax.plot(t_ms, st.forces[:, j] / 1e3, label="ground–1" if j == 0 else f"{j}–{j + 1}")
    if report.solution.stack.wall:  # a chain between two walls: the far wall's force on the top mass
        wall = np.asarray(report.solution.stack.wall_force(np.asarray(st.positions)))
        ax.plot(t_ms, wall / 1e3, "k--", label=f"{n}–wall")
    ax.set(xlabel="time (ms)", ylabel="contact force (kN)", title="Contact forces")
    ax.legend(fontsize="small", ncol=2)
    ax = axes[1, 0]
    a_g = (st.accelerations[:, -1] + float(report.solution.stack.gravity)) / G0
    top = report.top_pulse
    if top is not None:
        span = max(top.t_end_10 - top.t_start_10, 1e-12)
        keep = (st.t >= top.t_start_10 - span) & (st.t <= top.t_end_10 + span)
        ax.plot(t_ms[keep], a_g[keep], color="C3")
        ax.set_title(f"Top-mass pulse: {top.peak_g:,.0f} g, {top.duration_10 * 1e3:.3g} ms (10 %), "
                     f"ΔV {top.delta_v_main:.3g} m/s")
    else:
        ax.plot(t_ms, a_g, color="C3")
        ax.set_title("Top-mass acceleration")
    ax.set(xlabel="time (ms)", ylabel="accelerometer a + g (g)")
    ax = axes[1, 1]
    srs = report.top_srs
    if srs is None:  # a review: an empty panel without a word (a partial run's top mass had no pulse)
        ax.text(0.5, 0.5, "no SRS: the top mass has no complete pulse", transform=ax.transAxes, ha="center",
                va="center", color="0.4")
    if srs is not None:
        ax.loglog(srs.frequencies_Hz, srs.maximax, label={"abs": "maximax", "pos": "positive", "neg": "negative"}.get(
            getattr(srs, "peak", "abs"), "maximax"))
        ax.loglog(srs.frequencies_Hz, srs.primary, "--", label="primary")
        ax.loglog(srs.frequencies_Hz, np.maximum(srs.residual, 1e-300), ":", label="residual")
        ax.legend(fontsize="small")
        ax.set_title(f"SRS of the top pulse (Q = {srs.Q:g})")
    pv = srs is not None and getattr(srs, "kind", "acceleration") == "pseudo-velocity"
    ax.set(xlabel="natural frequency (Hz)",
           ylabel="pseudo-velocity (m/s)" if pv else "peak absolute acceleration (g)")
    # the primary cascade: up to a little after the top mass's last contact (a chain held by an end force or
    # a far wall never flies apart: its whole record, the wall's contact included)
    # (every contact of the first cascade, not only the top's: a review saw a touching stack's ground force
    # still at 4 kN at the right edge)
    top_eps = [ep for ep in report.episodes if ep.interface == n - 1]
    if top_eps and not report.solution.stack.held:
        t_end = 1e3 * max(ep.end for ep in report.episodes) * 1.15
        for ax in axes[0]:
            ax.set_xlim(0.0, t_end)
    for a in axes.flat:
        a.grid(True, which="both" if a.get_xscale() == "log" else "major", alpha=0.4)
    gain = report.top_velocity_gain
    shown = (f"{gain:.4f}" if np.isfinite(gain) else "— (no launch)") + ("" if report.status.ok else " (not final)")
    if report.solution.stack.held:  # an end force or a far wall: no launch, no rigid cascade
        title = f"Held chain: top velocity at t_max / striker speed {shown}, regime: {report.regime}"
    else:
        title = (f"Top launch gain {shown} (rigid theory: "
                 f"{'—' if report.rigid.nominal_gain is None else format(report.rigid.nominal_gain, '.4f')}), "
                 f"regime: {report.regime}")
    if not report.status.ok:  # a review: a cut-short run's figure looked finished ("gain nan")
        title = f"PARTIAL RESULTS ({report.status.text})\n{title}"
    fig.suptitle(title, color="C3" if not report.status.ok else "black")
    return fig


def plot_report(report: Report, path: str | Path) -> None:
    """Write `report_figure(report)` to `path` (PNG)."""
    import matplotlib.pyplot as plt

    fig = report_figure(report)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_optimize(result, path: str | Path) -> None:
    """The convergence of the best start (objective per iteration) and the top pulse of the optimum
    against the starting stack's and the MVG design's, as a PNG."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 4.5), constrained_layout=True)
    hist = result.convergence.get("history") or []
    if hist:  # against the final value: under limits an early, infeasible iterate can be lower than it
        last = hist[-1]
        ax0.semilogy(range(1, len(hist) + 1), np.maximum(np.abs(np.asarray(hist) - last), 1e-16), marker="o")
    ax0.set(xlabel="iteration", ylabel="|objective - final|", title=f"Convergence ({result.convergence['method']})")
    for label, rep in (("optimum", result.report), ("start", result.start),
                       ("MVG", result.rigid_designs.get("mvg"))):
        if rep is None or rep.solution is None or rep.solution.steps is None:
            continue
        st = rep.solution.steps
        g = float(rep.solution.stack.gravity)
        ax1.plot(st.t * 1e3, (st.accelerations[:, -1] + g) / G0, label=label)
    met = result.convergence.get("pulse_target_met")
    ax1.set(xlabel="time (ms)", ylabel="top mass acceleration (g)",
            title="Top pulse" + ("" if met is None else " (target met)" if met else " (target NOT met)"))
    ax1.legend()
    fig.savefig(path, dpi=120, format="png")
    plt.close(fig)


def plot_sweep(store: str | Path, path: str | Path, *, x: str, y: str | None = None,
               var: str = "top_velocity_gain") -> None:
    """A line (`x` only) or a map (`x` and `y`) of the variable `var` of a sweep store, as a PNG.

    Grid sweeps: `x` and `y` are axis dimensions; any other axis is taken at its first value (said in the
    title), and a line plot draws one line per value of the first remaining dimension. Sampled or zipped
    sweeps: `x` and `y` are sampled variables, drawn as a scatter (coloured by `var` with `y`).
    Raises `ParameterError` naming the flag for an unknown name."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    import xarray as xr

    from .errors import ParameterError

    ds = xr.open_zarr(store, consolidated=False)
    names = sorted(k for k in ds.data_vars if k != "chunk_done")
    if var not in ds.data_vars or var == "chunk_done":
        raise ParameterError("--var", var, f"one of {', '.join(names)}")
    allowed = [d for d in ds.dims if d not in ("mass", "interface", "chunk")] if "design" not in ds.dims else \
        [k for k in names if ds[k].dims == ("design",) and k not in _variable_names()]
    for flag, name in (("--x", x), ("--y", y)):
        if name is not None and name not in allowed:
            raise ParameterError(flag, name, f"one of {', '.join(allowed)}")
    if y is not None and y == x:
        raise ParameterError("--y", y, f"another key than --x (one of {', '.join(a for a in allowed if a != x)})")
    # designs that completed (status 0 or 1; -1: not run yet, in a store still being written)
    da = ds[var].where((ds["status"] >= 0) & (ds["status"] <= 1)) if var != "status" else ds[var]
    if not np.any(np.isfinite(np.asarray(da, dtype=float))):
        why = (" (the store was written without [sweep] durations = true)"
               if var in ("top_duration_10", "top_rise_time") else
               " for any completed design")
        raise ParameterError("--var", var, f"a variable with values: {var} has none{why}")
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    title = f"{var} ({da.attrs.get('long_name', '')})"

    def scale(axis_name, setter):  # log for values spanning decades (symlog when they start at zero)
        v = np.asarray(ds[axis_name], dtype=float)
        pos = v[v > 0]
        if pos.size and pos.max() / pos.min() >= 30:
            if np.all(v > 0):
                setter("log")
            elif np.all(v >= 0):
                setter("symlog", linthresh=pos.min())

    # a per-mass or per-interface variable is drawn for the top mass / the top mass's interface
    own = [d for d in da.dims if d in ("mass", "interface")]
    if own:
        da = da.isel({d: -1 for d in own})
        title += "; " + ", ".join(f"{d} {int(ds[d][-1])} (the top)" for d in own)
    if "design" in ds.dims:
        if y is None:
            ax.plot(ds[x], da, ".", ms=3)
            ax.set(xlabel=_label(ds, x), ylabel=_label(ds, var))
        else:
            sc = ax.scatter(ds[x], ds[y], c=da, s=6)
            fig.colorbar(sc, ax=ax, label=_label(ds, var))
            ax.set(xlabel=_label(ds, x), ylabel=_label(ds, y))
            scale(y, ax.set_yscale)
        scale(x, ax.set_xscale)
    else:
        rest = [d for d in da.dims if d not in (x, y)]
        fixed = rest[1:] if y is None else rest  # a line plot: one line per value of the first other axis
        if fixed:
            da = da.isel({d: 0 for d in fixed})
            title += "; at " + ", ".join(f"{d} = {float(ds[d][0]):.4g}{_unit(ds, d)}" for d in fixed if d in ds.coords)
        if y is None:
            lines = [d for d in da.dims if d != x]
            if lines:
                for k in range(da.sizes[lines[0]]):
                    ax.plot(ds[x], da.isel({lines[0]: k}), marker="o", ms=3,
                            label=f"{lines[0]} = {float(ds[lines[0]][k]):.4g}{_unit(ds, lines[0])}")
                ax.legend(fontsize="small")
            else:
                ax.plot(ds[x], da, marker="o", ms=3)
            ax.set(xlabel=_label(ds, x), ylabel=_label(ds, var))
        else:
            mesh = ax.pcolormesh(ds[x], ds[y], da.transpose(y, x), shading="nearest")
            fig.colorbar(mesh, ax=ax, label=_label(ds, var))
            ax.set(xlabel=_label(ds, x), ylabel=_label(ds, y))
            scale(y, ax.set_yscale)
        scale(x, ax.set_xscale)
    import textwrap

    ax.set_title("\n".join(textwrap.wrap(title, 90)), fontsize="small")
    ax.grid(True, which="both", alpha=0.4)
    fig.savefig(path, dpi=120, format="png")
    plt.close(fig)


def _variable_names() -> tuple[str, ...]:
    """The result variables of a sweep store (`sweeps.VARIABLES`): not sampled keys."""
    from .sweeps import VARIABLES

    return tuple(VARIABLES)


def _unit(ds, name) -> str:
    """` m` (the coordinate's `units` attribute, SI) for a legend or title value, '' without one or for 1
    (a review: legends read "stack.gaps = 1e-06")."""
    u = str(ds[name].attrs.get("units", "")) if name in ds.variables else ""
    return f" {u}" if u and u != "1" else ""


def _label(ds, name: str) -> str:
    units = ds[name].attrs.get("units", "")
    return f"{name} ({units})" if units and units != "1" else name


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def plot_check(result, path: str | Path) -> None:
    """The checked pulse inside its nominal pulse and band (`hertz_chain.standards.CheckResult`), in g
    against ms from the nominal pulse's start, with the verdict of every criterion in the legend."""
    from .standards import band_limits, nominal_pulse

    plt = _pyplot()
    spec = result.spec
    t = (result.t - result.nominal_start) * 1e3
    a_g = result.a / G0
    if a_g[np.argmax(np.abs(a_g))] < 0:
        a_g = -a_g
    # the nominal pulse and its band over the window where the band is judged, also where the record does
    # not reach (the pulse reads zero outside the record: free flight)
    w0, w1 = ((w - result.nominal_start for w in result.band_window) if result.band_window is not None
              else (0.0, 0.0))
    span = spec.duration + (spec.fall_time or 0.0)
    rel = np.union1d(result.t - result.nominal_start,
                     np.linspace(min(-0.05 * span, w0), max(1.05 * span, w1), 801))
    a_g = np.interp(rel, result.t - result.nominal_start, a_g, left=0.0, right=0.0)
    t = rel * 1e3
    nom = nominal_pulse(spec.shape, spec.peak_g, spec.duration, rel)
    if spec.srs is not None:
        fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 5), constrained_layout=True)
        _check_srs_panel(bx, result)
    else:
        fig, ax = plt.subplots(figsize=(8, 5), constrained_layout=True)
    if spec.band is not None:
        lo, hi = band_limits(spec, rel)
        judged = (rel >= w0) & (rel <= w1)
        ax.fill_between(t, lo, hi, where=judged, color="0.85", label=f"band ±{spec.band:g} A (where judged)")
    ax.plot(t, nom, "k--", lw=1, label=f"nominal {spec.shape}, {spec.peak_g:g} g, {spec.duration * 1e3:g} ms")
    ax.plot(t, a_g, color="C3", lw=1.6, label="top pulse (model)")
    for c in result.criteria:
        if c.passed is not None:
            ax.plot([], [], " ", label=f"{c.name}: {'pass' if c.passed else 'FAIL'} ({c.margin:+.3g} {c.unit})")
    ax.grid(True, alpha=0.4)
    ax.set(xlabel="time from the nominal pulse's start (ms)", ylabel="acceleration (g)",
           title=f"{spec.name}: {result.verdict}")
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.savefig(path, dpi=120, format="png")
    plt.close(fig)


def _check_srs_panel(bx, result) -> None:
    """The checked record's SRS against the required one and its dB limits (`plot_check`)."""
    import warnings

    from .spectrum import octave_frequencies, srs

    spec = result.spec
    f_t, a_t = (np.array(c) for c in zip(*spec.srs))
    f = octave_frequencies(f_t[0], f_t[-1], 12)
    req = np.exp(np.interp(np.log(f), np.log(f_t), np.log(a_t)))
    a = result.a / G0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        got = srs(result.t, a if a[np.argmax(np.abs(a))] > 0 else -a, f, Q=spec.srs_q, on_coarse="ignore").maximax
    curves = [(got, "top pulse (model)", "C3", "-"), (req, "required", "k", "--")]
    if spec.srs_tolerance_db is not None:
        lo, hi = spec.srs_tolerance_db
        curves += [(req * 10 ** (lo / 20), f"lower limit {lo:+g} dB", "0.45", ":"),
                   (req * 10 ** (hi / 20), f"upper limit {hi:+g} dB", "0.45", "-.")]
    _srs_panel(bx, f, curves)
    bx.set_ylabel(f"maximax SRS (g), Q = {spec.srs_q:g}")


def plot_fit(result, path: str | Path) -> None:
    """A fit (`hertz_chain.fitting.FitResult`): the measured pulse with the file's and the fitted model's
    (g, ms), and their SRS (log-log), the fitted values with their standard errors in the legend."""
    plt = _pyplot()
    s, f = result.start, result.fitted
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    ax.plot(f.t * 1e3, f.measured / G0, color="0.2", lw=1.0, label="measured")
    ax.plot(s.t * 1e3, s.model / G0, color="C0", lw=1.0, ls="--", label=f"start (C = {s.sprague_geers[2]:.3f})")
    ax.plot(f.t * 1e3, f.model / G0, color="C3", lw=1.4, label=f"fitted (C = {f.sprague_geers[2]:.3f})")
    for p in result.parameters:
        unit = "" if p.unit == "1" else f" {p.unit}"
        ax.plot([], [], " ", label=f"{p.label} = {p.value:.5g} ± {p.standard_error:.2g}{unit}")
    ax.grid(True, alpha=0.4)
    ax.set(xlabel="time (ms)", ylabel="acceleration (g)",
           title=f"fit: {result.status.text}, rms residual {result.rms_residual_g:.3g} g"
           + (f" (CFC {f.cfc})" if f.cfc else ""))
    ax.legend(fontsize="small")
    _srs_panel(bx, f.srs_frequencies_Hz, [(f.measured_srs, "measured", "0.2", "-"),
                                          (s.model_srs, "start", "C0", "--"), (f.model_srs, "fitted", "C3", "-")])
    fig.savefig(path, dpi=120, format="png")
    plt.close(fig)


def _srs_panel(bx, f, curves) -> None:
    """Maximax SRS curves `(values, label, colour, linestyle)` on log-log axes with a grid."""
    for values, label, colour, ls in curves:
        bx.loglog(f, values, color=colour, ls=ls, label=label)
    bx.grid(True, which="both", alpha=0.4)
    bx.set(xlabel="natural frequency (Hz)", ylabel="maximax SRS (g), Q = 10", title="Shock response spectra")
    bx.legend(fontsize="small")


def plot_compare(comparison, path: str | Path) -> None:
    """Model against measurement (`hertz_chain.measured.Comparison`): the two pulses (g, ms) and their
    SRS (log-log, decade ticks), with the Sprague–Geers errors in the title."""
    plt = _pyplot()
    c = comparison
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    ax.plot(c.t * 1e3, c.measured / G0, color="0.2", lw=1.2, label="measured")
    ax.plot(c.t * 1e3, c.model / G0, color="C3", lw=1.2, label=f"model (shifted {c.shift * 1e3:+.4g} ms)")
    ax.grid(True, alpha=0.4)
    M, P, C = c.sprague_geers
    ax.set(xlabel="time (ms)", ylabel="acceleration (g)",
           title=f"Sprague–Geers M {M:+.3f}, P {P:.3f}, C {C:.3f}" + (f" (CFC {c.cfc})" if c.cfc else ""))
    ax.legend(fontsize="small")
    _srs_panel(bx, c.srs_frequencies_Hz, [(c.measured_srs, "measured", "0.2", "-"), (c.model_srs, "model", "C3", "-")])
    s = c.to_dict()["srs"]
    bx.set_ylabel(f"{s['peak']} {s['type']} SRS ({s['units']}), Q = {s['q']:g}")
    fig.savefig(path, dpi=120, format="png")
    plt.close(fig)
