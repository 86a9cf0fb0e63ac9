"""Renderings of a `Report` and of the rigid designs: a table, JSON, NetCDF (xarray, units in the
attributes) or CSV. The workflows that produce them are `hertz_chain.workflow`.

- `summary_table(report)`, `to_dict(report)`, `to_json(report)`: what `hertz-chain simulate` prints.
- `write_output(report, path)`: `.nc` (time histories and results as an `xarray.Dataset`) or `.csv`
  (the top mass's pulse).
- `design_dict(...)`, `design_table(...)`: the rigid MVG/MET designs of `hertz-chain design`.
"""

from __future__ import annotations

import json
import math
import shlex
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .constants import G0

if TYPE_CHECKING:
    from .analysis import Report

__all__ = ["to_dict", "to_json", "summary_table", "write_output", "to_dataset", "design_dict", "design_table",
           "optimize_table"]


# ------------------------------------------------------------------------------------------ JSON
def _num(x):
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def _nums(a):
    return [_num(x) for x in np.asarray(a, dtype=float).ravel()]


def _episode_dict(ep) -> dict:
    return {
        "interface": ep.interface,
        "start_s": ep.start,
        "end_s": ep.end,
        "duration_s": ep.duration,
        "restitution": _num(ep.restitution),
        "approach_velocity_mps": ep.approach_velocity,
        "separation_velocity_mps": ep.separation_velocity,
        "max_overlap_m": ep.max_overlap,
        "peak_force_N": ep.peak_force,
        "peak_force_refined_N": _num(ep.peak_force_refined),
        "peak_force_time_s": _num(ep.peak_force_time),
        "complete": ep.complete,
    }


def _pulse_dict(pm) -> dict | None:
    if pm is None:
        return None  # a mass that felt no contact
    return {
        "peak_g": pm.peak_g,
        "time_of_peak_s": pm.time_of_peak,
        "duration_ms": pm.duration_10 * 1e3,
        "rise_time_ms": _num(pm.rise_time * 1e3),
        "delta_v_mps": pm.delta_v_main,
        "equivalent_half_sine_ms": pm.equivalent_half_sine_duration * 1e3,
        "n_pulses": pm.n_pulses,
    }


def _srs_dict(srs) -> dict:
    """The top SRS: what it is (`type`, `peak`, `Q`, `units`) and its spectra; an acceleration SRS also
    under the historical keys `maximax_g`, `primary_g`, `residual_g`."""
    unit = "g" if srs.kind == "acceleration" else "m/s"
    out = {"type": srs.kind, "peak": srs.peak, "Q": srs.Q, "units": unit,
           "frequencies_Hz": _nums(srs.frequencies_Hz), "maximax": _nums(srs.maximax),
           "primary": _nums(srs.primary), "residual": _nums(srs.residual)}
    if srs.kind == "acceleration":
        out.update(maximax_g=out["maximax"], primary_g=out["primary"], residual_g=out["residual"])
    return out


def to_dict(report: Report) -> dict:
    """The report as plain JSON-ready data (SI units; `null` for undefined values)."""
    top = report.top_pulse
    rigid = report.rigid
    srs = report.top_srs
    status = report.status
    return {
        "model": model_label(report),
        "status": status.text,
        "status_code": int(status),
        "partial": not status.ok,  # the headline numbers are not valid (incomplete, no contact, failed)
        "hint": status.hint(),
        "warnings": list(report.warnings),
        "cascade_end_s": _num(report.cascade_end_time),
        "drop_speed_mps": _num(report.drop_speed),
        "masses_kg": _nums(report.masses),
        "top_velocity_gain": _num(report.top_velocity_gain),
        "velocity_gains": _nums(report.velocity_gains),
        "launch_velocities_mps": _nums(report.launch_velocities),
        "peak_velocities_mps": None if report.peak_velocities is None else _nums(report.peak_velocities),
        "peak_velocity_times_s": None if report.peak_velocity_times is None else _nums(report.peak_velocity_times),
        "wave_speed_per_s": _num(report.wave_speed),
        "wall_peak_force_N": _num(report.wall_peak_force),
        "top_efficiency": _num(report.top_efficiency),
        "rigid": {
            "nominal_gain": _num(rigid.nominal_gain),
            "measured_restitution_gain": _num(rigid.measured_restitution_gain),
            "event_driven_gain": _num(rigid.event_driven_gain),
            "nominal_restitution": None if rigid.nominal_restitution is None else _nums(rigid.nominal_restitution),
            "measured_restitution": _nums(rigid.measured_restitution),
            "notes": list(rigid.notes),
        },
        "contacts": [_episode_dict(ep) for ep in report.episodes],
        "rebounds": [_episode_dict(ep) for ep in report.rebounds],
        "top_pulse": _pulse_dict(top),
        "pulses": [_pulse_dict(pm) for pm in report.pulses],  # every mass, bottom first
        "top_srs": None if srs is None else _srs_dict(srs),
        "independence": _num(report.independence),
        "regime": report.regime,
        "energy_error": _num(report.energy_error),
        "steps": {"total": report.num_steps, "rejected": report.num_rejected_steps},
        "t_final_s": _num(report.t_final),
    }


def to_json(obj) -> str:
    """JSON text of a `Report` (or of any JSON-ready dict or list)."""
    data = obj if isinstance(obj, (dict, list)) else to_dict(obj)
    return json.dumps(data, indent=2)


# ------------------------------------------------------------------------------------------ table
def _fmt(x, spec=".4f"):
    if x is None:
        return "—"
    x = float(x)
    return "—" if not math.isfinite(x) else format(x, spec)


def signed_percent(rel: float) -> str:
    """`rel` as a signed percentage to two decimals, `+0.00%` (never `-0.00%`) where it rounds to zero."""
    return f"{0.0 if abs(rel) < 5e-5 else rel:+.2%}"


def _err(rigid, sim):
    if rigid is None or sim is None or not (math.isfinite(rigid) and math.isfinite(sim)) or sim <= 0:
        return ""  # no comparison with an undefined or non-positive (partial) gain
    return f"  ({signed_percent((rigid - sim) / sim)} vs compliant)"


def model_label(report: Report) -> str:
    """The model that was run, named by its contact laws: "compliant (tsuji)", "compliant (hertz,
    kelvin-voigt)" (the laws' configuration names, `registry.LAWS`, in the order of the interfaces)."""
    sol = report.solution
    if sol is None:
        return "compliant"
    names = []
    for idx, law in sorted(zip(sol.stack.groups, sol.stack.laws), key=lambda p: p[0][0]):
        if law.name not in names:
            names.append(law.name)
    return f"compliant ({', '.join(names)})"


# a long chain's table: its first and last rows (the wave's start and the launch); --json has every row
_TABLE_HEAD, _TABLE_TAIL = 10, 10
_MASSES_LISTED = 12


def _shown_rows(n: int) -> range | set:
    """The rows of the per-mass table the text report prints: all up to `_TABLE_HEAD + _TABLE_TAIL + 5`
    masses, else the first `_TABLE_HEAD` and the last `_TABLE_TAIL`."""
    if n <= _TABLE_HEAD + _TABLE_TAIL + 5:
        return range(n)
    return set(range(_TABLE_HEAD)) | set(range(n - _TABLE_TAIL, n))


def _masses_text(masses) -> str:
    """The masses for the report's header: every one up to `_MASSES_LISTED`, "0.01 kg each" where all are
    equal, else the first and last three (a 1,000-bead chain made a 9,000-character line)."""
    m = [float(x) for x in masses]
    if len(m) > 1 and all(x == m[0] for x in m):
        return f"{m[0]:.4g} kg each"
    if len(m) <= _MASSES_LISTED:
        return f"{', '.join(f'{x:.4g}' for x in m)} kg"
    return f"{', '.join(f'{x:.4g}' for x in m[:3])}, ..., {', '.join(f'{x:.4g}' for x in m[-3:])} kg"


def summary_table(report: Report, title: str | None = None) -> str:
    """A readable summary: gains (the compliant model that was run, `model_label`, against the rigid
    theory), e_eff per contact, the top pulse, the regime."""
    r = report
    lines = []
    if title:
        lines += [title, "=" * len(title)]
    lines.append(f"status: {r.status.text}   t_final = {_fmt(r.t_final * 1e3, '.4g')} ms   steps = "
                 f"{r.num_steps} ({r.num_rejected_steps} rejected)   energy error = {_fmt(r.energy_error, '.2e')}")
    if not r.status.ok:
        done = math.isfinite(r.cascade_end_time)
        lines.append(f"PARTIAL RESULTS ({r.status.text}): {r.status.hint()}; "
                     + ("the first cascade did end, so its gains below are final; the run after it is cut short"
                        if done else "the gains below are not those of a finished cascade"))
    if math.isfinite(r.cascade_end_time):
        lines.append(f"first cascade ended at {r.cascade_end_time * 1e3:.4g} ms")
    held = bool(r.solution.stack.held)  # an end force or a far wall: no launch, the velocities at t_max
    # a stack falls onto the ground at its drop speed; a chain (no ground, or held) is struck at its striker's
    speed = "drop speed" if r.ground and not held else "striker speed"
    lines.append(f"{speed} {r.drop_speed:.4g} m/s, {len(r.masses)} mass{'es' if len(r.masses) != 1 else ''} "
                 f"({_masses_text(r.masses)})")
    lines.append("")
    lines.append("top-mass velocity at t_max over the striker speed (a held chain has no launch)" if held
                 else "top-mass velocity gain G_n = V_n / v_ff" if speed == "drop speed"
                 else "top-mass velocity gain G_n = V_n / v_0 (v_0 the striker speed)")
    lines.append(f"  {model_label(r):<40}{_fmt(r.top_velocity_gain)}")
    if not held:  # no rigid cascade for a chain that never flies apart (its note says so)
        lines.append(f"  rigid, Eq 19 with nominal e             {_fmt(r.rigid.nominal_gain)}"
                     f"{_err(r.rigid.nominal_gain, r.top_velocity_gain)}")
        lines.append(f"  rigid, Eq 19 with measured e_eff        {_fmt(r.rigid.measured_restitution_gain)}"
                     f"{_err(r.rigid.measured_restitution_gain, r.top_velocity_gain)}")
        lines.append(f"  rigid, event-driven with measured e_eff {_fmt(r.rigid.event_driven_gain)}"
                     f"{_err(r.rigid.event_driven_gain, r.top_velocity_gain)}")
    for note in r.rigid.notes:
        lines.append(f"  note: {note}")
    if not held:
        lines.append(f"  energy transfer to the top mass K_n = {_fmt(r.top_efficiency)}")
    lines.append("")
    lines.append("mass  gain     | interface  e_nominal  e_eff    episodes")
    nominal = r.rigid.nominal_restitution
    first = 0 if r.ground else 1
    shown = _shown_rows(len(r.velocity_gains))
    for i, gain in enumerate(r.velocity_gains):
        if i not in shown:
            if i == _TABLE_HEAD:
                lines.append(f"   ...  ({len(r.velocity_gains) - len(shown)} masses {_TABLE_HEAD + 1}-"
                             f"{len(r.velocity_gains) - _TABLE_TAIL} left out; --json lists every mass)")
            continue
        j = i  # interface below mass i+1
        count = sum(ep.interface == j for ep in r.episodes)
        label = "ground-1" if j == 0 else f"{j}-{j + 1}"
        e_nom = None if nominal is None or j < first else float(nominal[j])
        e_eff = float(r.restitution[j]) if j >= first else None
        right = f"{label:<10} {_fmt(e_nom, '.4f'):>9}  {_fmt(e_eff, '.4f'):>7}  {count:>4}" if j >= first else \
            "(no ground: mass 1 has no interface below it)"
        lines.append(f"{i + 1:>4}  {_fmt(float(gain), '.4f'):>7}  | {right}")
    # "up" is away from mass 1: toward the lighter end of a horizontal chain (no ground or no gravity)
    up = "upward > 0" if r.ground and float(r.solution.stack.gravity) > 0 else "> 0 away from mass 1"
    lines.append(f"  gain: the mass's velocity at t_max ({up}) over the striker speed" if held else
                 f"  gain: the mass's launch velocity (when its last push of the first cascade ended; {up}) over "
                 f"the {speed}")
    lines.append("  e_eff: separation over approach speed of the interface's main contact; episodes: its contacts "
                 + ("up to t_max" if held else "in the first cascade"))
    lines.append("")
    top = r.top_pulse
    if top is not None:
        lines.append(f"top pulse: peak {top.peak_g:,.0f} g at {top.time_of_peak * 1e3:.4g} ms, "
                     f"duration (10%) {top.duration_10 * 1e3:.4g} ms, "
                     + ("rise not measured (no rising edge in the record), " if not np.isfinite(top.rise_time) else
                        f"rise {top.rise_time * 1e3:.3g} ms, ")
                     + f"ΔV {top.delta_v_main:.4g} m/s, equivalent half-sine {top.equivalent_half_sine_duration * 1e3:.4g} ms, "
                     f"{top.n_pulses} pulse(s)")
    if r.top_srs is not None:
        s_ = r.top_srs
        k = int(np.argmax(s_.maximax))
        what = "" if (s_.kind, s_.peak) == ("acceleration", "abs") else f", {s_.kind}, {s_.peak}"
        value = f"{s_.maximax[k]:,.0f} g" if s_.kind == "acceleration" else f"{s_.maximax[k]:.4g} m/s"
        lines.append(f"top SRS (Q = {s_.Q:g}{what}): max {value} at {s_.frequencies_Hz[k]:,.0f} Hz")
    lines.append(f"regime: {r.regime} (neighbouring contacts overlap {r.independence:.1%} of the "
                 "shorter contact time" + (")" if held else "; the rigid theory assumes 0%)"))
    if np.isfinite(r.wall_peak_force):
        lines.append(f"far wall: peak force {r.wall_peak_force:,.6g} N on the top mass")
    if np.isfinite(r.wave_speed):
        way = "up, toward the top mass" if r.wave_speed > 0 else "down, toward mass 1"
        lines.append(f"wave: {abs(r.wave_speed):,.6g} contacts/s {way} (peak-force times of the middle half of "
                     "the chain; x bead diameter = m/s)")
    if r.rebounds:
        lines.append("")
        lines.append(f"rebounds after the first cascade (kept out of the gains): {len(r.rebounds)}")
        for ep in r.rebounds[:10]:
            label = "ground-1" if ep.interface == 0 else f"{ep.interface}-{ep.interface + 1}"
            end = (f"separation {_fmt(ep.separation_velocity, '.4g')} m/s" if ep.complete
                   else "still in contact at the end of the run")
            lines.append(f"  t = {ep.start * 1e3:.4g} ms  {label:<9} approach {ep.approach_velocity:.4g} m/s, {end}")
        if len(r.rebounds) > 10:
            lines.append(f"  ... and {len(r.rebounds) - 10} more (--json lists them all)")
    for w in r.warnings:
        lines.append(f"warning: {w}")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------ files
def _history(report: Report):
    """The time history to export: the uniform grid the stack file asked for (`solver.dt_output` /
    `solver.n_output`: samples of the dense solution) when there is one, else the solver's steps."""
    sol = report.solution
    grid = getattr(sol, "grid", None)
    if grid is not None:
        keep = np.isfinite(grid.positions).all(axis=-1)
        import dataclasses as _dc

        return _dc.replace(grid, **{f.name: getattr(grid, f.name)[keep] for f in _dc.fields(grid)
                                    if getattr(grid, f.name) is not None}), "uniform grid of the dense solution"
    return sol.steps, "the solver's adaptive steps"


def _metadata(meta: dict | None, report: Report | None = None) -> dict:
    """Provenance of an export: title, input file, package version, date and command. `meta`'s `title`
    and `source_file` where given, else the report's own (`Report.title`, `Report.source_file`: a report
    of `simulate_file` exported from Python carried neither)."""
    import datetime
    import sys

    from . import __version__

    own = {} if report is None else {"title": getattr(report, "title", None),
                                     "source_file": getattr(report, "source_file", None)}
    meta = {**own, **{k: v for k, v in dict(meta or {}).items() if v is not None}}
    now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    # shlex.join: a review found `--set solver.t_max="10 ms"` recorded as `--set solver.t_max=10 ms`, which
    # does not run again
    argv0 = Path(sys.argv[0]) if sys.argv and sys.argv[0] else Path()
    if "hertz-chain" in argv0.name:
        command = shlex.join(["hertz-chain", *sys.argv[1:]])
    elif argv0.parent.name == "hertz_chain" and argv0.name in ("__main__.py", "cli.py"):  # python -m hertz_chain
        command = shlex.join(["python", "-m", "hertz_chain", *sys.argv[1:]])
    else:
        command = "hertz_chain"
    out = {"title": meta.get("title") or "hertz_chain simulation", "source_file": meta.get("source_file") or "",
           "version": f"hertz_chain {__version__}", "history": f"{now} {command}"}
    # the input as it was read (a review: a bare file name, no way to tell later which stack a file came
    # from; the sweep stores already keep theirs): its SHA-256, for a check against a copy
    source = Path(out["source_file"]) if out["source_file"] else None
    if source is not None and source.is_file():
        import hashlib

        try:
            out["source_file_sha256"] = hashlib.sha256(source.read_bytes()).hexdigest()
            out["source_file"] = str(source.resolve())
        except OSError:
            pass
    return out


def _one_line(text: str) -> str:
    """A value for a one-line header (the CSV's `#` lines): line breaks as the two characters `\\n`, so that
    a title or file name with a newline cannot end the comment (a review: the second line of a title was
    read as the CSV's header)."""
    return str(text).replace("\r\n", "\\n").replace("\n", "\\n").replace("\r", "\\n")


_ACC_G = "in units of standard gravity g0 = 9.80665 m s-2"


def to_dataset(report: Report, meta: dict | None = None):
    """Time histories and results as a CF-1.10 `xarray.Dataset` (UDUNITS units, `long_name` on every
    variable, `standard_name` where CF has one, and the provenance in the global attributes). The time
    history is the file's uniform output grid when it asks for one, else the solver's steps (the
    `time_sampling` attribute says which). Accelerations in g are ratios to standard gravity (units
    `1`); the SRS is in m s-2."""
    import xarray as xr

    st, sampling = _history(report)
    n = len(report.masses)
    mass = np.arange(1, n + 1)
    interface = np.arange(n)
    g = float(report.solution.stack.gravity)
    a_g = (st.accelerations + g) / G0
    data = {
        "position": (("time", "mass"), st.positions, {"units": "m", "long_name": "position of the mass (upward)"}),
        "velocity": (("time", "mass"), st.velocities, {"units": "m s-1", "long_name": "velocity of the mass (upward)"}),
        "acceleration": (("time", "mass"), st.accelerations,
                         {"units": "m s-2", "long_name": "kinematic acceleration d2x/dt2 of the mass (upward; -g in free fall)"}),
        "accelerometer": (("time", "mass"), st.accelerations + g,
                          {"units": "m s-2", "long_name": "accelerometer reading a + g (upward; 0 in free fall)"}),
        "accelerometer_g": (("time", "mass"), a_g,
                           {"units": "1", "long_name": f"accelerometer reading (a + g) {_ACC_G}"}),
        "overlap": (("time", "interface"), st.overlaps,
                    {"units": "m", "long_name": "overlap of the interface (> 0 compression)"}),
        "force": (("time", "interface"), st.forces, {"units": "N", "long_name": "contact force of the interface"}),
        "dissipated": (("time", "interface"), st.dissipated,
                       {"units": "J", "long_name": "energy dissipated in the interface so far"}),
        "energy": (("time",), st.energy, {"units": "J", "long_name": "kinetic + gravitational + elastic + dissipated energy"}),
        **({"wall_force": (("time",), np.asarray(report.solution.stack.wall_force(np.asarray(st.positions))),
                           {"units": "N", "long_name": "force of the far wall on the top mass ([wall])"})}
           if report.solution.stack.wall else {}),
        "mass_kg": (("mass",), report.masses, {"units": "kg", "long_name": "mass"}),
        "launch_velocity": (("mass",), report.launch_velocities,
                            {"units": "m s-1", "long_name": "velocity when the mass's last contact of the cascade ended"}),
        "velocity_gain": (("mass",), report.velocity_gains,
                          {"units": "1", "long_name": "launch velocity over the drop speed"}),
        "restitution_measured": (("interface",), report.restitution,
                                 {"units": "1", "long_name": "effective restitution of the interface's main impact"}),
    }
    if report.peak_velocities is not None:
        data["peak_velocity"] = (("mass",), report.peak_velocities,
                                 {"units": "m s-1", "long_name": "largest upward velocity in the first cascade"})
        data["peak_velocity_time"] = (("mass",), report.peak_velocity_times,
                                      {"units": "s", "long_name": "time of the largest upward velocity"})
    strongest = {}  # per interface, the first-cascade episode with the largest force
    for ep in report.episodes:
        if ep.interface not in strongest or ep.peak_force > strongest[ep.interface].peak_force:
            strongest[ep.interface] = ep
    data["peak_force"] = (("interface",), [strongest[j].peak_force if j in strongest else np.nan for j in range(n)],
                          {"units": "N", "long_name": "largest contact force at the solver's steps in the first cascade "
                           "(the exported force history's maximum when it is sampled at the steps)"})
    data["peak_force_time"] = (("interface",),
                               [strongest[j].peak_force_time if j in strongest else np.nan for j in range(n)],
                               {"units": "s", "long_name": "time of the refined peak (parabola through the samples)"})
    # the value at that time (a review: the file paired the sampled maximum with the refined peak's time;
    # the JSON's peak_force_refined_N)
    data["peak_force_refined"] = (("interface",),
                                  [strongest[j].peak_force_refined if j in strongest else np.nan for j in range(n)],
                                  {"units": "N", "long_name": "largest contact force in the first cascade, refined "
                                   "between the solver's steps (parabola through the samples; at peak_force_time)"})
    pulse_fields = (("pulse_peak_g", "peak_g", "1", f"peak of the mass's main pulse {_ACC_G} (refined between "
                     "the solver's samples: up to ~1e-4 above the saved series' maximum)"),
                    ("pulse_duration", "duration_10", "s", "width of the main pulse between its 10 % points"),
                    ("pulse_rise_time", "rise_time", "s", "10 % to 90 % rise time of the main pulse"),
                    ("pulse_delta_v", "delta_v_main", "m s-1", "velocity change the accelerometer records over "
                     "the main pulse: the integral of a + g (under gravity more than the mass's own change by g "
                     "times the pulse's length)"),
                    ("pulse_half_sine_duration", "equivalent_half_sine_duration", "s",
                     "duration of the half-sine with the same peak and velocity change"))
    for name, field, unit, long in pulse_fields:  # every mass's main pulse; NaN for a mass without contact
        values = [np.nan if pm is None else float(getattr(pm, field)) for pm in report.pulses]
        data[name] = (("mass",), np.asarray(values), {"units": unit, "long_name": long})
    if report.rigid.nominal_restitution is not None:
        data["restitution_nominal"] = (("interface",), report.rigid.nominal_restitution,
                                       {"units": "1", "long_name": "restitution the interface was designed for"})
    coords = {"time": ("time", st.t, {"units": "s", "standard_name": "time", "long_name": "time since impact",
                                      "axis": "T"}),
              "mass": ("mass", mass, {"units": "1", "long_name": "mass number, bottom = 1"}),
              "interface": ("interface", interface,
                            {"units": "1", "long_name": "interface number: 0 = ground-mass 1, j = mass j-mass j+1"})}
    if report.top_srs is not None:
        s = report.top_srs
        coords["frequency"] = ("frequency", s.frequencies_Hz, {"units": "Hz", "long_name": "natural frequency"})
        acc = s.kind == "acceleration"
        for part in ("maximax", "primary", "residual"):
            data[f"srs_{part}"] = (("frequency",), getattr(s, part) * (G0 if acc else 1.0),
                                   {"units": "m s-2" if acc else "m s-1", "Q": s.Q, "peak": s.peak,
                                    "long_name": f"{part} shock response spectrum of the top mass's pulse "
                                                 f"({'absolute acceleration' if acc else 'pseudo-velocity'}, "
                                                 f"peak {s.peak}, Q = {s.Q:g})"})
    attrs = {k: (int(v) if isinstance(v, bool) else v) for k, v in to_dict(report).items()
             if isinstance(v, (str, int, float)) and v is not None}
    attrs["rigid_json"] = json.dumps(to_dict(report)["rigid"])
    # the analysis's warnings (an energy audit, loose tolerances, ...), one per line: the list was dropped
    # with the other non-scalar entries (a review: a file from a run with a failed audit looked clean)
    attrs["warnings"] = "\n".join(report.warnings)  # "" when there are none
    attrs["hertz_chain_conventions"] = ("SI units; masses numbered from the bottom; interface 0 = ground-mass 1, "
                                        "interface j = mass j - mass j+1")
    attrs["time_sampling"] = sampling
    attrs["standard_gravity_m_s2"] = G0
    attrs.update(_metadata(meta, report))
    attrs["Conventions"] = "CF-1.10"
    attrs["source"] = f"{attrs['version']}, {model_label(report)} model"
    return xr.Dataset(data, coords=coords, attrs=attrs)


def write_output(report: Report, path: str | Path, meta: dict | None = None) -> None:
    """Write `.nc` (the CF `to_dataset`, compressed) or `.csv` (time, the top mass's accelerometer in
    m/s² and in g, its velocity), the history on the file's uniform grid when it asks for one.
    `meta`: `title` and `source_file` for the provenance (default: the report's own, which
    `simulate_file` sets; `analyse`'s report has none). The CSV starts with `#` comment lines: the
    title, the input file, the version, the date, the run's status (with `PARTIAL RESULTS` where the run
    did not complete), its warnings, the units and the sampling.

    An existing file at `path` is replaced, as `xarray.Dataset.to_netcdf` does (the command line's
    `--output` refuses one without `--force`).

    **Raises:** `OutputPathError` for a suffix other than `.nc` or `.csv` (it wrote CSV text into any
    other name, e.g. `out.json`)."""
    path = Path(path)
    if path.suffix.lower() not in (".nc", ".csv"):
        from .errors import OutputPathError

        raise OutputPathError("path", str(path), "a .nc (NetCDF) or .csv file (report.to_json for JSON)")
    if path.suffix.lower() == ".nc":
        ds = to_dataset(report, meta)
        encoding = {name: {"zlib": True, "complevel": 4} for name in ds.data_vars
                    if np.issubdtype(ds[name].dtype, np.number)}
        ds.to_netcdf(path, engine="h5netcdf", encoding=encoding)
    else:
        st, sampling = _history(report)
        stack = report.solution.stack
        a = st.accelerations[:, -1] + float(stack.gravity)
        columns = [st.t, a, a / G0, st.velocities[:, -1]]
        names, described = "time_s,accelerometer_mps2,accelerometer_g,velocity_mps", ""
        if stack.wall:  # a chain between two walls: the far wall's force on the top mass too
            columns.append(np.asarray(stack.wall_force(np.asarray(st.positions))))
            names, described = names + ",wall_force_N", "; force of the far wall on it (N)"
        table = np.column_stack(columns)
        m = _metadata(meta, report)
        status = report.status
        head = [f"{m['title']}", f"input file: {m['source_file'] or '(none)'}"
                + (f" (sha256 {m['source_file_sha256']})" if m.get("source_file_sha256") else ""), f"written by {m['version']}; {m['history']}",
                f"status: {status.text}" + ("" if status.ok else f" (PARTIAL RESULTS: {status.hint()})"),
                *(f"warning: {w}" for w in report.warnings),
                f"top mass (mass {len(report.masses)}), {model_label(report)} model; time sampling: {sampling}",
                "columns: time (s); accelerometer a + g (m/s^2); the same in g (9.80665 m/s^2); velocity (m/s, upward)"
                + described]
        with open(path, "w", encoding="utf-8") as f:
            f.writelines(f"# {_one_line(line)}\n" for line in head)
            f.write(names + "\n")
            np.savetxt(f, table, delimiter=",")


# ------------------------------------------------------------------------------------------ design


def _design_dict(d) -> dict:
    return {"kind": d.kind, "n": d.n, "masses": list(map(float, d.masses)),
            "mass_ratios": list(map(float, d.ratios)), "velocity_gain": float(d.gain),
            "energy_efficiency": float(d.efficiency), "total_mass": float(d.total_mass)}


def design_dict(cmp) -> dict:
    """JSON-ready design comparison: `mvg`, `met` (each `n`, `masses`, `velocity_gain`,
    `energy_efficiency`, `total_mass`) and `mvg_over_met` (the ratios of Figs 13–15 and 18)."""
    return {"mass_ratio": cmp.R, "restitution": cmp.mvg.restitution,
            "mass_unit": "kg" if cmp.mvg.masses[0] != 1.0 else "m1",
            "mvg": _design_dict(cmp.mvg), "met": _design_dict(cmp.met),
            "mvg_over_met": {"velocity_gain": cmp.gain_ratio, "energy_efficiency": cmp.efficiency_ratio,
                             "total_mass": cmp.mass_ratio},
            "note": _end_mass_note(cmp)}


def design_table(cmp) -> str:
    """The two designs side by side, masses bottom first, and their MVG/MET ratios."""
    mvg, met = cmp.mvg, cmp.met
    unit = "kg" if mvg.masses[0] != 1.0 else "m_1"
    rows = [("number of masses n", f"{mvg.n:d}", f"{met.n:d}", "—"),
            ("velocity gain G = V_n/v_ff", f"{mvg.gain:.4f}", f"{met.gain:.4f}", f"{cmp.gain_ratio:.4f}"),
            ("energy efficiency K_n", f"{mvg.efficiency:.4f}", f"{met.efficiency:.4f}",
             f"{cmp.efficiency_ratio:.4f}"),
            (f"total mass M [{unit}]", f"{mvg.total_mass:.4g}", f"{met.total_mass:.4g}", f"{cmp.mass_ratio:.4f}"),
            ("mass ratio m_n/m_1", f"{mvg.mass_ratio:.4g}", f"{met.mass_ratio:.4g}", "—")]
    w = [max(len(r[i]) for r in rows + [("", "MVG (Eq 15)", "MET (Eq 25)", "MVG/MET")]) for i in range(4)]
    head = ("", "MVG (Eq 15)", "MET (Eq 25)", "MVG/MET")
    fmt = lambda r: f"{r[0]:<{w[0]}}  {r[1]:>{w[1]}}  {r[2]:>{w[2]}}  {r[3]:>{w[3]}}"
    lines = [f"Optimal stacks for R = {cmp.R:.6g}, e = {mvg.restitution:.6g} (seed paper Section 5)", "",
             fmt(head), "-" * (sum(w) + 6), *map(fmt, rows), "",
             f"masses [{unit}], bottom first:",
             "  MVG: " + ", ".join(f"{m:.5g}" for m in mvg.masses),
             "  MET: " + ", ".join(f"{m:.5g}" for m in met.masses),
             "",
             "MVG/MET ratios are the quantities of the paper's Figs 13 (G), 14 (K) and 15/18 (M)."]
    note = _end_mass_note(cmp)
    if note:
        lines.append("note: " + note)
    if mvg.gain <= 0:  # a review: -R 0.5 -e 0.001 printed G = -0.3320 and ratios of -331.67 without a word
        lines.append(f"note: the MVG gain G = {mvg.gain:.4g} <= 0: with e = {mvg.restitution:.6g} the top mass is not "
                     "launched upward (V_n = G v_ff), so the stack amplifies nothing and Eq 20's picture of "
                     "independent collisions no longer holds (the top mass meets the one below again)")
    return "\n".join(lines)


def _end_mass_note(cmp) -> str | None:
    """A sentence when the two designs end at different top masses (the MET design's n is an integer,
    so its top mass only approximates the one asked for): their ratios then compare unequal stacks."""
    a, b = float(cmp.mvg.masses[-1]), float(cmp.met.masses[-1])
    if abs(a - b) <= 1e-6 * max(abs(a), abs(b)):
        return None
    return (f"the designs end at different top masses (MVG {a:.5g}, MET {b:.5g}, {100 * (b / a - 1):+.2f} %): "
            "the MVG/MET ratios compare stacks with unequal top masses")


def optimize_table(result) -> str:
    """An `optimize.OptimizeResult` as text: the best stack against the start and the paper's designs,
    the varied values and the convergence."""
    c = result.convergence
    budget = c.get("limits", {}).get("total_mass", {}).get("limit")
    top = float(result.masses[-1])

    def row(name, rep, why=None):
        if rep is None:
            return f"  {name:<22} (could not be simulated{': ' + why if why else ''})"
        tp = rep.top_pulse
        pulse = "" if tp is None else f"   peak {tp.peak / G0:9.4g} g, half-sine {tp.equivalent_half_sine_duration * 1e3:.4g} ms"
        # a review: a rigid design over the mass budget, or ending at another top mass (MET), read as a
        # better stack than the optimum without a word
        m = np.asarray(rep.masses, dtype=float)
        unlike = [f"top mass {m[-1]:.4g} kg" if abs(m[-1] - top) > 1e-6 * top else "",
                  f"{m.sum():.4g} kg, over the {budget:.4g} kg budget" if budget and m.sum() > budget * (1 + 1e-9) else ""]
        unlike = "; ".join(u for u in unlike if u)
        return f"  {name:<22} gain {rep.top_velocity_gain:.6f}{pulse}" + (f"   ({unlike})" if unlike else "")

    value = (f"gain {-result.objective_value:.9g}" if result.objective == "gain"
             else f"objective {result.objective_value:.9g}")
    lines = [f"Optimised stack ({result.objective}, n = {result.n}): {result.status.text}; {value}", "",
             "masses [kg], bottom first: " + ", ".join(f"{m:.6g}" for m in result.masses), "",
             "varied:"]
    lines += [f"  {k} = {v:.9g}" for k, v in result.variables.items()]
    lines += ["", "compared under the same contacts:", row("optimum", result.report), row("start (the file)", result.start)]
    notes = getattr(result, "rigid_design_notes", {})
    lines += [row(f"{k.upper()} (n = {len(v.masses)})" if v is not None else k.upper(), v, notes.get(k))
              for k, v in result.rigid_designs.items()]
    pg = c.get("projected_gradient_norm")
    lines += ["", f"convergence: {c['method']}, {c['iterations']} iterations, starts: {c['starts_agree']}, "
              f"{result.evaluations} evaluations, {result.seconds:.1f} s",
              f"  projected-gradient norm {pg:.3g}" if pg is not None and pg == pg else
              "  (derivative-free)" if c.get("gradient") is None else
              f"  gradient: {c['gradient']} (no projected-gradient norm under limits or a mass budget)",
              "  active bounds: " + (", ".join(c["active_bounds"]) or "none")]
    lines += [f"  note: {note}" for note in c.get("start_outside_bounds", ())]
    if c.get("limits"):
        unit = {"total_mass": " kg", "max_peak_g": " g", "max_peak_force": " N"}
        lines.append("  limits: " + ", ".join(f"{k} {v['limit']:.6g}{unit.get(k, '')}: {v['value']:.6g}{unit.get(k, '')} "
                                             f"({v['state']})" for k, v in c["limits"].items()))
    if "srs_max_error_db" in c:
        lines.append(f"  SRS: largest miss {c['srs_max_error_db']:.2f} dB "
                     f"({'within' if c['srs_within_tolerance'] else 'outside'} the tolerance band)")
    if "pulse_misses" in c:
        pm = c["pulse_misses"]
        lines.append(f"  pulse: peak g {100 * pm['peak_g']:+.3g} %, duration {100 * pm['duration']:+.3g} % against the "
                     "target" + ("" if c["pulse_target_met"] else
                                 " (NOT MET: the bounds or limits keep the target out of reach; this is the "
                                 "closest pulse within them)"))
    if c.get("why"):
        lines.append(f"  {c['why']}")
    return "\n".join(lines)


def compare_table(c) -> str:
    """Model against measurement (`hertz_chain.measured.Comparison`) as a text table."""
    d = c.to_dict()
    rows = [("peak", "g", "peak_g"), ("duration (10 %)", "ms", "duration_10_ms"),
            ("equiv. half-sine", "ms", "equivalent_half_sine_ms"), ("rise time", "ms", "rise_time_ms"),
            ("velocity change", "m/s", "delta_v_mps")]
    out = [f"measured: {c.source}" + (f" (CFC {c.cfc})" if c.cfc else " (unfiltered)")
           + f"; model shifted {c.shift * 1e3:+.5g} ms ({c.alignment})",
           f"{'':<18} {'measured':>12} {'model':>12} {'model/meas - 1':>15}"]
    for label, unit, key in rows:
        m, x, r = d["measured"][key], d["model"][key], d["relative_difference"][key]
        m, x = ("—" if v is None else f"{v:.5g}" for v in (m, x))  # None: not measured (a rise cut by the record)
        out.append(f"{label + ' (' + unit + ')':<18} {m:>12} {x:>12} {'' if r is None else f'{100 * r:+.2f} %':>15}")
    sg = d["sprague_geers"]
    out.append(f"Sprague-Geers: magnitude {sg['magnitude']:+.4f}, phase {sg['phase']:.4f}, comprehensive "
               f"{sg['comprehensive']:.4f}")
    s = d["srs"]
    out.append(f"SRS ({s['peak']} {s['type']}, Q = {s['q']:g}, {c.srs_frequencies_Hz[0]:.4g}-{c.srs_frequencies_Hz[-1]:.4g} Hz): largest difference "
               f"{d['srs']['max_abs_difference_dB']:.2f} dB")
    return "\n".join(out)
