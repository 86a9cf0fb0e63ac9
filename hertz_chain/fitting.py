"""Calibrate contacts to a measured pulse by least squares (`hertz-chain fit`, `hc.fit`).

A lab that has dropped its shock amplifier once has a measured pulse; the contact parameters it does
not know (a pad's stiffness, an interface's restitution) are the ones that make the model's top pulse
match that measurement. :func:`fit` finds them:

- **What varies:** the stack file's `[[fit.vary]]` tables (`key`, `index`, `bounds` with units: the
  key vocabulary of `hertz_chain.keys`, as `[[optimize.vary]]`), or the command line's `--vary KEY`
  (`contact.stiffness[1]`, `contact.restitution[0]`, ...: interface numbers, 0 = ground), which for a
  stiffness searches two decades either side of the file's value and for a restitution `[0.05, 1]`.
  The time shift between the model's clock and the record's is always fitted too.
- **The residual:** the model's top accelerometer (`a + g`, the dense solution:
  `episodes.hermite_slope`), shifted by `tau`, minus the measured record, in g, at every sample of the
  record (prepared as `measured.compare` prepares it: uniform, positive-going; both through the same
  CFC filter when `cfc` is given). Outside the run the model reads zero (free flight).
- **The solver:** `scipy.optimize.least_squares` (trust-region reflective, bounds), in the search
  coordinates `theta` (log of a stiffness, the restitution itself, the shift in units of the measured
  pulse's 10 % width). Its Jacobian is by central differences of complete solves (`rtol = atol =
  1e-11`, steps 1e-4 in `theta`), not by JAX's reverse mode: differentiating the solver's accepted
  steps is wrong at contact onsets for Tsuji, Kelvin–Voigt and viscoelastic contacts (measured in
  docs/optimize.md), and a fit needs the whole residual's Jacobian, which the 2p + 1 solves give at
  once; the shift's column needs no new solve.
- **Standard errors** from the Jacobian at the optimum, as for any nonlinear least-squares estimate
  with independent errors of equal variance (e.g. Seber & Wild, "Nonlinear Regression", 1989, §2.1):
  `cov = s² (JᵀJ)⁻¹`, `s² = Σ r² / (N − p)`, `N` samples, `p` parameters (shift included); a
  parameter searched in log space gets `x · SE(log x)`. The errors of neighbouring samples of a filtered
  or oversampled record are correlated, which makes these standard errors too small: the result says
  so when a CFC was applied.

The fitted stack is written as a stack file (`document`, `--write`) that `hertz-chain simulate` runs
as it stands.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import time
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from .constants import G0
from .errors import ParameterError, SolverError, StackFileError
from .keys import KEYS, Slot, check_values, quantity_of, read_bounds, read_entry, resolve
from .status import Status

__all__ = ["FIT_KEYS", "FitParameter", "FitResult", "parse_vary_option", "read_fit_file", "fit"]

#: how much worse (Sprague-Geers C, a fraction) the fitted stack may match the record than the file's before
#: the fit is called POOR
POOR_FIT_C = 1e-4
#: how many times the record's own noise (its standard deviation before the pulse, `measured.quiet_start`)
#: the rms residual may be before the fit is called POOR: a model that explains the record leaves its noise
#: (ratio ~1; linear resampling of the record lowers the quiet part's by up to sqrt(2))
NOISE_RATIO = 2.0
#: Keys of a stack file's `[fit]` section (`[[fit.vary]]` tables hold `key`, `index`, `bounds`).
FIT_KEYS = ("vary", "max_evaluations")
_VARY_KEYS = ("key", "index", "bounds")
#: The keys `--vary` takes without bounds, and how their default bounds follow from the file's value.
DEFAULT_BOUNDS = {"contact.stiffness": "two decades either side of the file's value",
                  "contact.restitution": "[0.05, 1]"}
#: Relative step of the central differences in the search coordinates.
FD_STEP = 1e-4


@dataclasses.dataclass(frozen=True)
class FitParameter:
    """One fitted number: `label` (`contact.stiffness[1]`), SI `unit`, the file's `start`, the fitted
    `value` and its `standard_error`, the `bounds`, and whether it ended on one."""

    label: str
    unit: str
    start: float
    value: float
    standard_error: float
    bounds: tuple[float, float]
    at_bound: bool

    def to_dict(self) -> dict:
        """JSON-ready: a standard error that is not finite (a parameter the record does not move) is None
        (`null`; `Infinity` is not JSON)."""
        d = dataclasses.asdict(self)
        d["standard_error"] = _finite_or_none(self.standard_error)
        return d


def _finite_or_none(x):
    return float(x) if math.isfinite(x) else None


@dataclasses.dataclass(frozen=True)
class FitResult:
    """The outcome of :func:`fit` (module docstring).

    | field | meaning |
    |---|---|
    | `parameters` | the fitted `FitParameter`s, in the order given |
    | `shift`, `shift_standard_error` | the model's time shift onto the record (s) |
    | `rms_residual_g` | root-mean-square residual at the optimum (g) |
    | `samples`, `dof` | samples of the record used; `samples − parameters − 1` |
    | `correlation` | correlation matrix of the parameters (shift last) |
    | `status`, `message`, `evaluations` | `optimize.OptimizeStatus`, scipy's message, solves of the stack |
    | `start`, `fitted` | `measured.Comparison` of the file's stack and of the fitted one |
    | `document` | the fitted stack file (TOML text) |
    """

    parameters: tuple[FitParameter, ...]
    shift: float
    shift_standard_error: float
    rms_residual_g: float
    samples: int
    dof: int
    correlation: np.ndarray
    status: Any
    message: str
    evaluations: int
    seconds: float
    start: Any
    fitted: Any
    document: str
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        """JSON-ready summary (SI units)."""
        sg = lambda c: dict(zip(("magnitude", "phase", "comprehensive"), c.sprague_geers))  # noqa: E731
        return {
            "status": self.status.text, "message": self.message,
            "parameters": [p.to_dict() for p in self.parameters],
            "shift_s": self.shift, "shift_standard_error_s": self.shift_standard_error,
            "rms_residual_g": self.rms_residual_g, "samples": self.samples, "dof": self.dof,
            "poor_fit": self.poor,
            "correlation": [[_finite_or_none(c) for c in row] for row in np.asarray(self.correlation, dtype=float)],
            "evaluations": self.evaluations, "seconds": self.seconds,
            "sprague_geers": {"start": sg(self.start), "fitted": sg(self.fitted)},
            "peak_g": {"measured": self.fitted.measured_metrics.peak_g, "start": self.start.model_metrics.peak_g,
                       "fitted": self.fitted.model_metrics.peak_g},
            "notes": list(self.notes),
        }

    @property
    def poor(self) -> bool:
        """True when a note says the fit is poor (worse than the start, a residual over twice the record's
        noise or 10 % of the peak, or a standard error not below its value)."""
        return any(n.startswith("POOR FIT") for n in self.notes)

    def table(self) -> str:
        """The result as a text table."""
        out = [f"fit: {self.status.text} after {self.evaluations} solves ({self.seconds:.1f} s); "
               f"{self.samples} samples, rms residual {self.rms_residual_g:.4g} g",
               f"{'parameter':<26} {'start':>12} {'fitted':>12} {'std. error':>11}  unit"]
        for p in self.parameters:
            flag = "  (at a bound)" if p.at_bound else ""
            out.append(f"{p.label:<26} {p.start:>12.6g} {p.value:>12.6g} {p.standard_error:>11.3g}  {p.unit}{flag}")
        out.append(f"{'time shift':<26} {'':>12} {self.shift * 1e3:>12.6g} {self.shift_standard_error * 1e3:>11.3g}  ms")
        s, f = self.start.sprague_geers, self.fitted.sprague_geers
        out.append(f"Sprague-Geers comprehensive error: start {s[2]:.4f} -> fitted {f[2]:.4f}; peak: measured "
                   f"{self.fitted.measured_metrics.peak_g:.5g} g, start {self.start.model_metrics.peak_g:.5g} g, "
                   f"fitted {self.fitted.model_metrics.peak_g:.5g} g")
        out.extend(f"note: {n}" for n in self.notes)
        return "\n".join(out)


# ------------------------------------------------------------------------------------------ input
@dataclasses.dataclass(frozen=True)
class _Vary:
    key: str
    index: Any
    bounds: tuple[float, float] | None
    where: str


def parse_vary_option(text: str) -> _Vary:
    """`--vary KEY` or `--vary KEY[INDEX]` (`contact.stiffness[1]`): default bounds (`DEFAULT_BOUNDS`).
    Raises `StackFileError` (one line)."""
    import re

    m = re.fullmatch(r"\s*([A-Za-z_.]+)\s*(?:\[\s*(\d+)\s*\])?\s*", str(text))
    if not m:
        raise StackFileError(f"--vary {text!r}: expected KEY or KEY[INDEX], e.g. contact.stiffness[1]")
    key, idx = m.group(1), (int(m.group(2)) if m.group(2) is not None else None)
    resolve(key, None, n=3, ground=True, where=f"--vary {text}")  # a known key
    if key not in DEFAULT_BOUNDS:
        raise StackFileError(f"--vary {text}: {key} has no default bounds; give it in a [[fit.vary]] table with "
                             f"bounds (--vary takes {', '.join(DEFAULT_BOUNDS)})")
    return _Vary(key, idx, None, f"--vary {text}")


def _parse_fit(raw: Any, spec) -> tuple[list[_Vary], int]:
    if not isinstance(raw, dict):
        raise StackFileError(f"fit: expected a table ([fit]), got {raw!r}")
    for k in raw:
        if k not in FIT_KEYS:
            raise StackFileError(f"fit.{k}: unknown key; allowed: {', '.join(FIT_KEYS)}")
    entries = []
    vary = raw.get("vary", [])
    if not isinstance(vary, list):
        raise StackFileError(f"fit.vary: {vary!r} is invalid: give [[fit.vary]] tables, each with a key")
    for i, item in enumerate(vary):
        where = f"fit.vary[{i}]"
        read_entry(item, where, _VARY_KEYS, "contact.stiffness")
        key = item["key"]
        resolve(key, None, n=3, ground=True, where=f"{where}.key")
        bounds = None
        if "bounds" in item:
            dim, p = quantity_of(spec, key, item.get("index"), where)
            bounds = read_bounds(item["bounds"], dim, f"{where}.bounds", p)
            check_values(key, list(bounds), f"{where}.bounds", shown=repr(item["bounds"]), gravity=spec.drop.gravity)
        elif key not in DEFAULT_BOUNDS:
            raise StackFileError(f"{where}.bounds: missing; {key} has no default bounds (give [lower, upper] "
                                 "with units)")
        entries.append(_Vary(key, item.get("index"), bounds, where))
    max_eval = raw.get("max_evaluations", 200)
    if isinstance(max_eval, bool) or not isinstance(max_eval, int) or not 1 <= max_eval <= 10_000:
        raise StackFileError(f"fit.max_evaluations: {max_eval!r} is invalid: an integer from 1 to 10000")
    return entries, max_eval


def read_fit_file(path, vary_options=(), overrides=None):
    """Every check of a fit before any solve: `(spec, document, slots, bounds, max_evaluations)`.
    `vary_options`: the command line's `--vary` strings (they replace the file's `[[fit.vary]]`).
    Raises `StackFileError` (one line naming the file or the option)."""
    from .stackfile import apply_overrides, load_stack_file

    spec = load_stack_file(path, overrides)
    doc = apply_overrides(tomllib.loads(Path(path).read_text(encoding="utf-8-sig")), overrides)
    raw = doc.pop("fit", {})
    try:
        entries, max_eval = _parse_fit(raw, spec)
    except StackFileError as exc:
        raise StackFileError(f"{path}: {exc}") from None
    if vary_options:
        entries = [parse_vary_option(v) for v in vary_options]
    if not entries:
        raise StackFileError(f"{path}: fit.vary: nothing to fit; give --vary KEY[INDEX] (e.g. --vary "
                             "contact.stiffness[0]) or [[fit.vary]] tables")
    n, ground = spec.n, spec.has_ground
    slots, bounds = [], []
    for v in entries:
        try:
            got = resolve(v.key, v.index, n=n, ground=ground, where=v.where)
        except StackFileError as exc:
            raise StackFileError(f"{path}: {exc}" if v.where.startswith("fit") else str(exc)) from None
        for s in got:
            if s in slots:
                raise StackFileError(f"{v.where}: {s.label} is varied twice")
            slots.append(s)
            bounds.append(v.bounds)
    return spec, doc, tuple(slots), bounds, max_eval


def _default_bounds(slot: Slot, start: float) -> tuple[float, float]:
    if slot.key == "contact.stiffness":
        return start / 100.0, start * 100.0
    return 0.05, 1.0


def _unit(spec, slot: Slot) -> str:
    from .registry import LAWS

    if slot.key == "contact.stiffness":
        dim = LAWS[spec.contact_for(slot.index).law].stiffness
        return {"linear_stiffness": "N/m", "hertz_stiffness": "N/m^1.5"}.get(dim, "N/m^p")
    return {"contact.restitution": "1", "stack.masses": "kg", "stack.gaps": "m", "drop.impact_velocity": "m/s",
            "drop.height": "m"}[slot.key]


# ------------------------------------------------------------------------------------------ the fit
class _Model:
    """The residual of a design `x` (SI values of the slots) and a shift, on the record's grid."""

    def __init__(self, spec, slots, t, measured, cfc):
        from ._design import DesignMap

        self.dm = DesignMap(spec, slots, section="fit.vary")
        self.opts = dict(self.dm.built.simulate_options, throw=False,
                         tolerances=_tight(self.dm.built.simulate_options.get("tolerances")))
        self.g = float(self.dm.gravity)
        self.t, self.measured, self.cfc = t, measured, cfc
        self.evaluations = 0

    def solve(self, x):
        """`(t_steps, v + g t, a + g)` of the top mass for the design `x`; raises on a failed run."""
        from .simulation import simulate

        self.evaluations += 1
        stack, state = self.dm(np.asarray(x, dtype=float))
        sol = simulate(stack, state, **self.opts)
        st = sol.steps
        if st is None or not sol.status.ok:
            tol = self.opts["tolerances"]  # the fit's own, tighter than a file's usual (`_tight`)
            raise sol.status.error(f"the run of the design {np.asarray(x).tolist()}",
                                   f"a fit needs complete runs (its solves run at rtol = {tol.rtol:g}, atol = "
                                   f"{tol.atol:g}, whatever the file's: raise solver.max_steps for them)"
                                   if sol.status is Status.INCOMPLETE_MAX_STEPS else "a fit needs complete runs")
        ts = np.asarray(st.t, dtype=float)
        keep = np.isfinite(ts)
        ts = ts[keep]
        return ts, np.asarray(st.velocities, dtype=float)[keep, -1] + self.g * ts, \
            np.asarray(st.accelerations, dtype=float)[keep, -1] + self.g

    def model(self, run, shift):
        """The model's accelerometer (m/s²) on the record's grid, shifted by `shift`, filtered alike."""
        from .episodes import hermite_slope
        from .filters import cfc_filter

        ts, v, a = run
        tt = self.t - shift
        inside = (tt >= ts[0]) & (tt <= ts[-1])
        out = np.zeros_like(tt)
        out[inside] = hermite_slope(ts, v, a, tt[inside])
        return cfc_filter(self.t, out, self.cfc) if self.cfc is not None else out

    def residual(self, run, shift):
        return (self.model(run, shift) - self.measured) / G0


def _tight(tol):
    """Tolerances for the fit's solves: at most 1e-11 (central differences with step 1e-4 need the
    solve's own noise well below 1e-8)."""
    from .simulation import Tolerances

    if tol is None:
        return Tolerances(rtol=1e-11, atol=1e-11)
    return dataclasses.replace(tol, rtol=min(tol.rtol, 1e-11), atol=min(tol.atol, 1e-11))


def fit(path, measured, vary=(), *, cfc: int | None = None, align: str = "xcorr", overrides=None,
        max_evaluations: int | None = None) -> FitResult:
    """Fit the varied parameters of the stack file `path` to the `measured` pulse (module docstring).

    **Arguments:**

    - `path`: a stack file; its `[fit]` section (optional) lists `[[fit.vary]]` tables.
    - `measured`: a `measured.MeasuredPulse` (`read_pulse_csv`) or the path of a CSV it reads.
    - `vary`: `--vary` strings (`"contact.stiffness[1]"`), replacing the file's `[[fit.vary]]`.
    - `cfc`: filter the record and the model alike (60, 180, 600, 1000).
    - `align`: how the starting shift is found (`measured.align_shift`: xcorr, onset, none).
    - `overrides`: `KEY=VALUE` strings, as `--set`.
    - `max_evaluations`: cap on scipy's residual evaluations, each with its Jacobian (2p + 1 solves for
      p parameters; default the file's `fit.max_evaluations`, 200).

    **Returns** a :class:`FitResult`. **Raises** `StackFileError` / `ParameterError` for bad input
    (before any solve), `SolverError` when the file's own stack cannot be simulated.
    """
    from scipy.optimize import least_squares

    from .filters import CFC_CLASSES, cfc_filter
    from .measured import ALIGNMENTS, compare, prepare_record, quiet_start, read_pulse_csv
    from .optimization import OptimizeStatus, _set_interface
    from .workflow import run_spec, srs_options

    t0 = time.perf_counter()
    if cfc is not None and cfc not in CFC_CLASSES:
        raise ParameterError("cfc", cfc, f"one of {', '.join(map(str, CFC_CLASSES))}")
    if align not in ALIGNMENTS:
        raise ParameterError("align", align, f"one of {', '.join(ALIGNMENTS)}")
    spec, doc, slots, bounds, max_eval = read_fit_file(path, vary, overrides)
    if max_evaluations is not None:
        max_eval = int(max_evaluations)
    if isinstance(measured, (str, Path)):
        measured = read_pulse_csv(measured)

    t, m, notes = prepare_record(measured, cfc)
    if cfc is not None:
        m = cfc_filter(t, m, cfc)
    try:
        model = _Model(spec, slots, t, m, cfc)  # the design map: no solve yet
    except StackFileError as exc:
        msg = str(exc).replace("optimize.vary", "fit.vary")
        raise StackFileError(msg if msg.startswith(str(path)) or msg.startswith(Path(path).name) else f"{path}: {msg}") from None
    x0 = np.asarray(model.dm.values(), dtype=float)
    lo, hi = [], []
    for s, b, x in zip(slots, bounds, x0):
        b = b if b is not None else _default_bounds(s, float(x))
        if not b[0] <= x <= b[1]:
            raise StackFileError(f"{path}: {s.label}: the file's value {x:.6g} lies outside the bounds "
                                 f"[{b[0]:.6g}, {b[1]:.6g}]")
        lo.append(b[0])
        hi.append(b[1])
    lo_a, hi_a = np.array(lo), np.array(hi)
    start_report = run_spec(spec)
    if not start_report.status.ok:  # a fit compares whole pulses (a review: a traceback, exit 1)
        raise start_report.status.error(f"{path}: the file's own stack", "a fit needs complete runs")
    opts = srs_options(spec)
    start = compare(start_report, measured, cfc=cfc, align=align, srs_options=opts)
    log = np.array([KEYS[s.key].log for s in slots])
    width = start.measured_metrics.duration_10  # the shift's unit in the search

    def to_x(theta):
        p = theta[:-1]
        return np.where(log, np.exp(p), p), theta[-1] * width

    def to_theta(x, shift):
        return np.append(np.where(log, np.log(x), x), shift / width)

    th_lo = np.append(np.where(log, np.log(lo_a), lo_a), -np.inf)
    th_hi = np.append(np.where(log, np.log(hi_a), hi_a), np.inf)
    cache: dict = {}
    best: dict = {}  # the lowest cost among the points whose solves (and Jacobian's) all finished

    def residual_and_jacobian(theta):
        key = tuple(np.round(theta, 15))
        if key in cache:
            return cache[key]
        x, shift = to_x(theta)
        run = model.solve(x)
        r = model.residual(run, shift)
        J = np.empty((r.size, theta.size))
        for j in range(theta.size - 1):  # central differences of complete solves, kept inside the bounds
            h = FD_STEP * max(1.0, abs(theta[j]) if not log[j] else 1.0)
            up, dn = theta.copy(), theta.copy()
            up[j], dn[j] = min(theta[j] + h, th_hi[j]), max(theta[j] - h, th_lo[j])
            ru = model.residual(model.solve(to_x(up)[0]), shift)
            rd = model.residual(model.solve(to_x(dn)[0]), shift)
            J[:, j] = (ru - rd) / (up[j] - dn[j])
        hs = FD_STEP
        J[:, -1] = (model.residual(run, shift + hs * width) - model.residual(run, shift - hs * width)) / (2 * hs)
        cache.clear()
        cache[key] = (r, J)
        best["finished"] = best.get("finished", 0) + 1
        if "cost" not in best or float(r @ r) < best["cost"]:
            best.update(cost=float(r @ r), theta=np.array(theta))
        return r, J

    theta0 = to_theta(x0, start.shift)
    status, message = OptimizeStatus.CONVERGED, ""
    try:
        res = least_squares(lambda th: residual_and_jacobian(th)[0], theta0,
                            jac=lambda th: residual_and_jacobian(th)[1], bounds=(th_lo, th_hi), method="trf",
                            x_scale="jac", max_nfev=max_eval, ftol=1e-8, xtol=1e-8, gtol=1e-8)
        theta, message = res.x, str(res.message)
        if res.status <= 0:
            status = OptimizeStatus.NOT_CONVERGED if res.status == 0 else OptimizeStatus.FAILED
    except SolverError as exc:  # a design the solver cannot finish: the best point reached (a review: the
        # start was reported, and written as "fitted", after a failure part-way)
        status, message = OptimizeStatus.FAILED, str(exc)
        theta = best.get("theta", theta0)
        if "theta" in best and not np.array_equal(theta, theta0):
            message += "; the best point reached is reported"
        elif best.get("finished", 0) > 1:
            message += "; no finished point was better than the start: the start is reported"
        else:
            message += "; no point beyond the start finished: the start is reported"
    r, J = residual_and_jacobian(theta)
    N, p = r.size, theta.size
    dof = N - p
    s2 = float(r @ r) / max(dof, 1)
    cov = s2 * np.linalg.pinv(J.T @ J)
    se_theta = np.sqrt(np.clip(np.diag(cov), 0, None))
    # a parameter the residual does not move at all (a zero Jacobian column): pinv gives it a standard error of 0,
    # which would read as perfectly determined; it is not determined at all
    col = np.linalg.norm(J, axis=0)
    se_theta = np.where(col <= 1e-12 * max(float(col.max()), 1e-300), np.inf, se_theta)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se_theta, se_theta)
    corr[~np.isfinite(se_theta), :] = np.nan  # an undetermined parameter: no correlation (not 0)
    corr[:, ~np.isfinite(se_theta)] = np.nan
    x, shift = to_x(theta)
    se_x = np.where(log, x * se_theta[:-1], se_theta[:-1])
    params = []
    for s, x_i, x0_i, se, l_, h_ in zip(slots, x, x0, se_x, lo_a, hi_a):
        at = bool(np.isclose(x_i, l_, rtol=1e-6) or np.isclose(x_i, h_, rtol=1e-6))
        params.append(FitParameter(s.label, _unit(spec, s), float(x0_i), float(x_i), float(se), (float(l_), float(h_)),
                                   at))
    if cfc is not None:
        notes.append(f"the CFC {cfc} filter correlates neighbouring samples: the standard errors assume "
                     "independent errors and are too small")
    if any("resampled" in n for n in notes):
        notes.append("the record was resampled: its interpolation error counts as noise, and neighbouring "
                     "residuals are correlated; the standard errors assume independent errors and are too small")
    for q in params:
        if not q.standard_error < abs(q.value):
            notes.append(f"POOR FIT: {q.label}'s standard error ({q.standard_error:.3g}) is not below its value "
                         f"({q.value:.6g}): the record does not determine it")
    if any(q.at_bound for q in params):
        notes.append("a parameter ended on its bound: its standard error is not meaningful there")

    # the fitted stack file, re-simulated from its own text (what `hertz-chain simulate` would run)
    out = copy.deepcopy(doc)
    for s, v in zip(slots, x):
        if s.key in ("contact.stiffness", "contact.restitution"):
            unit = _unit(spec, s)
            _set_interface(out, s.index, s.key.split(".")[1], float(v) if unit == "1" else f"{float(v)!r} {unit}")
        elif s.key == "stack.masses" or s.key == "stack.gaps":
            arr = np.asarray(model.dm.fields(x)[s.key], dtype=float)
            out.setdefault("stack", {})[s.key.split(".")[1]] = [float(a) for a in arr]
            out["stack"].pop("design", None)
        else:
            drop = out.setdefault("drop", {})
            drop.pop("height", None)
            drop.pop("impact_velocity", None)
            drop[s.key.split(".")[1]] = f"{float(v)!r} {_unit(spec, s)}"
    import tomli_w

    from .stackfile import parse_stack

    text = tomli_w.dumps(out)
    fitted_report = run_spec(parse_stack(tomllib.loads(text)))
    fitted = compare(fitted_report, measured, cfc=cfc, shift=float(shift), srs_options=opts)
    rms = float(math.sqrt(float(r @ r) / N))
    peak = fitted.measured_metrics.peak_g
    # worse by more than a lab could see (C is a fraction: 1e-4 = 0.01 %); a fit that starts at the answer
    # moves C by round-off (1.7720e-7 -> 1.7732e-7 was called POOR FIT)
    if fitted.sprague_geers[2] > start.sprague_geers[2] + POOR_FIT_C:
        notes.append(f"POOR FIT: the fitted stack matches the record worse than the file's (Sprague-Geers C "
                     f"{start.sprague_geers[2]:.4f} -> {fitted.sprague_geers[2]:.4f}): check the units, the "
                     "varied parameters and their bounds")
    # against the record's own noise, its standard deviation before the pulse (a review: a fit whose bounds
    # excluded the truth left 4.5 times the noise, 4 % of the peak, and passed for a calibration)
    _, noise, quiet = quiet_start(t, m)
    if np.isfinite(noise) and noise > 1e-6 * float(np.max(np.abs(m))) and rms * G0 > NOISE_RATIO * noise:
        notes.append(f"POOR FIT: the rms residual ({rms:.4g} g) is {rms * G0 / noise:.3g} times the record's noise "
                     f"({noise / G0:.4g} g, the standard deviation of its {quiet} samples before the pulse): the "
                     "model leaves a systematic misfit (check the fixed parameters, the bounds, the units)")
    if rms > 0.1 * peak:
        notes.append(f"POOR FIT: the rms residual ({rms:.4g} g) is {100 * rms / peak:.0f} % of the measured peak "
                     f"({peak:.5g} g): the model does not reproduce the record (check the units, the varied "
                     "parameters, the stack)")
    head = ("# fitted by hertz-chain fit\n" if status.ok else
            f"# hertz-chain fit {status.text}: the best point reached, NOT a converged fit (not a calibration)\n")
    return FitResult(tuple(params), float(shift), float(se_theta[-1] * width), rms, N,
                     dof, corr, status, message, model.evaluations, time.perf_counter() - t0, start, fitted,
                     head + text, tuple(notes))
