"""Matplotlib figures of a `Report`: velocities, contact forces, the top pulse and its SRS."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .analysis import Report
from .pulse import G0

__all__ = ["report_figure", "plot_report", "plot_optimize"]


def report_figure(report: Report):
    """A 2×2 figure: velocities, contact forces, the top mass's pulse (g) and its SRS."""
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
    ax.set(xlabel="time (ms)", ylabel="velocity (m/s, upward)", title="Velocities")
    ax.legend(fontsize="small", ncol=2)
    ax = axes[0, 1]
    for j in range(0 if report.ground else 1, n):
        ax.plot(t_ms, st.forces[:, j], label="ground–1" if j == 0 else f"{j}–{j + 1}")
    ax.set(xlabel="time (ms)", ylabel="contact force (N)", title="Contact forces")
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
    ax.set(xlabel="time (ms)", ylabel="acceleration (g)")
    ax = axes[1, 1]
    srs = report.top_srs
    if srs is not None:
        ax.loglog(srs.frequencies_Hz, srs.maximax, label="maximax")
        ax.loglog(srs.frequencies_Hz, srs.primary, "--", label="primary")
        ax.loglog(srs.frequencies_Hz, np.maximum(srs.residual, 1e-300), ":", label="residual")
        ax.legend(fontsize="small")
        ax.set_title(f"SRS of the top pulse (Q = {srs.Q:g}, 1/12 octave)")
    ax.set(xlabel="natural frequency (Hz)", ylabel="peak absolute acceleration (g)")
    # the primary cascade: up to a little after the top mass's last contact
    top_eps = [ep for ep in report.episodes if ep.interface == n - 1]
    if top_eps:
        t_end = 1e3 * max(ep.end for ep in top_eps) * 1.15
        for ax in axes[0]:
            ax.set_xlim(0.0, t_end)
    fig.suptitle(f"Gain {report.top_velocity_gain:.4f} (rigid Eq 19: "
                 f"{'—' if report.rigid.nominal_gain is None else format(report.rigid.nominal_gain, '.4f')}), "
                 f"regime: {report.regime}")
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
    if hist:
        best = min(hist)
        ax0.semilogy(range(1, len(hist) + 1), np.maximum(np.asarray(hist) - best, 1e-16), marker="o")
    ax0.set(xlabel="iteration", ylabel="objective - best", title=f"Convergence ({result.convergence['method']})")
    for label, rep in (("optimum", result.report), ("start", result.start),
                       ("MVG", result.rigid_designs.get("mvg"))):
        if rep is None or rep.solution is None or rep.solution.steps is None:
            continue
        st = rep.solution.steps
        g = float(rep.solution.stack.gravity)
        ax1.plot(st.t * 1e3, (st.accelerations[:, -1] + g) / G0, label=label)
    ax1.set(xlabel="time (ms)", ylabel="top mass acceleration (g)", title="Top pulse")
    ax1.legend()
    fig.savefig(path, dpi=120, format="png")
    plt.close(fig)
