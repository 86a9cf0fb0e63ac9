"""Measured pulses: read them, filter them, and compare them with the model (`hertz-chain compare`).

- :func:`read_pulse_csv` reads a time column and an acceleration column, with units from the header
  (`time (ms), acceleration (g)`, `t [s]; a [m/s^2]`, or a name ending in `_ms`, `_g`, ...) or from
  the caller (`time_unit=`, `accel_unit=`, the command line's `--time-unit`/`--accel-unit`).
- :func:`compare` puts the stack's top pulse and the measurement side by side: the same channel filter
  on both (a CFC of SAE J211-1 / ISO 6487, `hertz_chain.filters`), one time alignment (cross-correlation,
  the pulse onset, or none), the pulse metrics of both (`hertz_chain.pulse`), the SRS of both on one
  frequency grid (`hertz_chain.spectrum`), and the Sprague–Geers magnitude, phase and comprehensive errors.

**Sprague–Geers errors** (M. A. Sprague and T. L. Geers, "A spectral-element method for modelling
cavitation in transient fluid–structure interaction", Int. J. Numer. Meth. Eng. 60 (2004) 2467–2499;
reviewed in L. E. Schwer, "Validation metrics for response histories: perspectives and case studies",
Engineering with Computers 23 (2007) 295–309). With the measured history `m(t)` and the computed `c(t)`
over the common window, `ψ_mm = ∫m²`, `ψ_cc = ∫c²`, `ψ_mc = ∫mc`:

    M = sqrt(ψ_cc / ψ_mm) − 1,     P = arccos(ψ_mc / sqrt(ψ_mm ψ_cc)) / π,     C = sqrt(M² + P²).

`M` is the relative magnitude error (0 for equal energy, `k − 1` for `c = k·m`); `P` is in [0, 1]
(0 in phase, `φ/π` for two sines `φ` apart over whole periods); the integrals are trapezoid sums on the
measurement's grid.

**Units.** Acceleration units are read from a closed list (`ACCEL_UNITS`: g, m/s², ft/s²) rather than
through pint, because pint reads `g` as the gram; time units are s, ms and µs (`TIME_UNITS`).
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from .constants import G0
from .errors import ParameterError
from .pulse import PulseMetrics, pulse_metrics

__all__ = [
    "ACCEL_UNITS",
    "TIME_UNITS",
    "ALIGNMENTS",
    "MeasuredPulse",
    "Comparison",
    "read_pulse_csv",
    "sprague_geers",
    "align_shift",
    "compare",
    "prepare_record",
]

#: Time units of a measured record: name -> seconds.
TIME_UNITS = {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6}
#: Acceleration units of a measured record: name -> m/s² (g is standard gravity, 9.80665 m/s²).
ACCEL_UNITS = {"g": G0, "gn": G0, "g0": G0, "m/s^2": 1.0, "m/s2": 1.0, "m/s²": 1.0, "m s-2": 1.0,
               "m/s**2": 1.0, "mps2": 1.0, "ft/s^2": 0.3048, "ft/s2": 0.3048, "ft/s²": 0.3048}
#: How the model is placed in time against the measurement.
ALIGNMENTS = ("xcorr", "onset", "none")


@dataclasses.dataclass(frozen=True)
class MeasuredPulse:
    """A measured acceleration record in SI units: `t` (s, increasing), `a` (m/s²), where it came from
    (`source`) and the units it was given in."""

    t: np.ndarray
    a: np.ndarray
    source: str = ""
    time_unit: str = "s"
    accel_unit: str = "m/s^2"
    notes: tuple[str, ...] = ()

    @property
    def sample_rate(self) -> float:
        """Mean sample rate (Hz)."""
        return (self.t.size - 1) / float(self.t[-1] - self.t[0])


def _unit_of(header: str) -> str | None:
    """The unit named in a column header: `name (unit)`, `name [unit]`, or a `name_unit` suffix."""
    h = header.strip()
    m = re.search(r"[\(\[]\s*([^\)\]]+?)\s*[\)\]]\s*$", h)
    if m:
        return m.group(1).strip()
    m = re.search(r"[_\s]([A-Za-zµμ/\^\*²0-9\-]+)$", h)
    if m and (m.group(1).lower() in TIME_UNITS or m.group(1).lower() in ACCEL_UNITS):
        return m.group(1)
    return None


def _factor(unit: str, table: dict, what: str, key: str) -> float:
    u = unit.strip()
    for cand in (u, u.lower(), u.replace(" ", "")):
        if cand in table:
            return table[cand]
    raise ParameterError(key, unit, f"{'an' if what[0] in 'aeiou' else 'a'} {what} unit: {', '.join(sorted(set(table)))}")


def read_pulse_csv(path, *, time_unit: str | None = None, accel_unit: str | None = None,
                   time_column: int = 0, accel_column: int = 1) -> MeasuredPulse:
    """Read a measured pulse from a CSV (or whitespace/semicolon separated) text file.

    **Arguments:**

    - `path`: the file. Lines starting with `#` are comments. The first other line is a header when
      it is not all numbers.
    - `time_unit`, `accel_unit`: the units (`TIME_UNITS`, `ACCEL_UNITS`); override the header's.
    - `time_column`, `accel_column`: 0-based column numbers (0 and 1).

    **Returns:** a :class:`MeasuredPulse` in SI units.

    **Raises:** `ParameterError` (naming the file, the column or the unit) for a missing file, no
    units from either the header or the arguments, an unknown unit, fewer than 3 rows, a non-number
    cell, non-finite values, or times that do not increase.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise ParameterError("measured file", str(path), f"a readable file ({exc.strerror or exc})") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise ParameterError(str(path), "no data rows", "a time column and an acceleration column")
    def separator(line):
        return ";" if ";" in line else ("," if "," in line else None)

    def split(block):  # by the separator of the block's first line (a header may use another, a review)
        sep = separator(block[0]) if block else None
        return [r for r in csv.reader(io.StringIO("\n".join(block)), delimiter=sep)] if sep else \
            [ln.split() for ln in block], sep

    def numeric(cells, sep):
        try:
            [_number(c, sep) for c in cells if c.strip()]
            return True
        except ValueError:
            return False

    def is_unit(cell, table):
        try:
            _factor(cell.strip().strip("[]()"), table, "unit", "")
            return True
        except ParameterError:
            return False

    header = None
    first, first_sep = split(lines[:1])
    if not numeric(first[0], first_sep):
        header, lines = [c.strip() for c in first[0]], lines[1:]
        below, below_sep = split(lines[:1])
        if below and not numeric(below[0], below_sep) and not any(_unit_of(h) for h in header):
            cells = [c.strip() for c in below[0]]
            need_cols = max(time_column, accel_column) + 1
            if len(cells) >= need_cols and is_unit(cells[time_column], TIME_UNITS) \
                    and is_unit(cells[accel_column], ACCEL_UNITS):
                # a second header row of units under the names (`time,accel` then `ms,g` or `[ms],[g]`)
                header = [f"{h} ({u.strip('[]()')})" if u else h for h, u in zip(header, cells)] \
                    + header[len(cells):]
                lines = lines[1:]
            elif any(_unit_of(c) for c in cells):  # a title line above the real header: the header
                header, lines = cells, lines[1:]
    rows, dialect = split(lines)
    need = max(time_column, accel_column) + 1
    if header is not None and len(header) < need:
        raise ParameterError(f"{path}: columns", len(header), f"at least {need} columns")
    units = {}
    for col, given, table, what in ((time_column, time_unit, TIME_UNITS, "time"),
                                    (accel_column, accel_unit, ACCEL_UNITS, "acceleration")):
        in_header = _unit_of(header[col]) if header is not None else None
        unit = given if given is not None else in_header
        option = "--time-unit" if what == "time" else "--accel-unit"
        if given is not None and in_header is not None:
            try:
                differs = _factor(in_header, table, what, "header") != _factor(given, table, what, option)
            except ParameterError:
                differs = False  # an unreadable header unit: the option decides (checked below)
            if differs:
                raise ParameterError(f"{path}: {what} unit", given,
                                     f"the unit of column {header[col]!r} ({in_header}), or no {option} "
                                     "(the header already says it)")
        if unit is None:  # "column 1 'time' = 'no unit' is invalid: ..." (named as the user sees it)
            where = f"column {col + 1} {header[col]!r}" if header is not None else f"column {col + 1} (no header)"
            raise ParameterError(f"{path}: {what} unit of {where}", "none given",
                                 f"a unit in the header, e.g. 'time (ms), acceleration (g)', or the "
                                 f"{option} option "
                                 f"({', '.join(sorted(set(table)))})")
        units[what] = (unit, _factor(unit, table, what, f"{path}: {what} unit"))
    try:
        data = np.array([[_number(r[time_column], dialect), _number(r[accel_column], dialect)] for r in rows],
                        dtype=float)
    except (ValueError, IndexError):
        bad = next(i for i, r in enumerate(rows) if not _row_ok(r, time_column, accel_column, dialect))
        sep = {";": "';'", ",": "','", None: "spaces"}[dialect]
        raise ParameterError(f"{path}: data row {bad + 1}", (dialect or " ").join(rows[bad]),
                             f"numbers in columns {time_column + 1} and {accel_column + 1} (separated by {sep}, as "
                             "in the first data row)") from None
    if data.shape[0] < 3:
        raise ParameterError(f"{path}: data rows", data.shape[0], "at least 3 rows of finite numbers")
    if not np.all(np.isfinite(data)):
        i = int(np.argmin(np.all(np.isfinite(data), axis=1)))
        raise ParameterError(f"{path}: data row {i + 1}", ",".join(rows[i]), "finite numbers (no NaN or inf)")
    t = data[:, 0] * units["time"][1]
    if not np.all(np.diff(t) > 0):
        i = int(np.argmin(np.diff(t) > 0))
        raise ParameterError(f"{path}: time", f"row {i + 2}: {float(data[i + 1, 0])!r} after {float(data[i, 0])!r}",
                             "strictly increasing times")
    if not np.any(data[:, 1]):  # named by the file (a review: the pulse metrics' own "a = 'all zeros'")
        raise ParameterError(f"{path}: acceleration column {accel_column + 1}", "all zeros",
                             "a record with a non-zero acceleration")
    notes = ()
    ncol = len(header) if header is not None else max(len(r) for r in rows)
    if ncol > 2:
        names = (f" ({header[time_column].strip()!r}, {header[accel_column].strip()!r})" if header is not None
                 else "")
        notes = (f"{Path(path).name} has {ncol} columns: columns {time_column + 1} and {accel_column + 1}{names} "
                 "were read as time and acceleration",)
    return MeasuredPulse(t, data[:, 1] * units["acceleration"][1], str(path), units["time"][0],
                         units["acceleration"][0], notes)


def _number(cell: str, sep: str | None) -> float:
    """A cell's number; in a file separated by ';', a decimal comma (`0,5`, the spreadsheet export of many
    European labs) read as a point (a review: refused). Not where ',' separates (a quoted "1,000" may be
    a thousands separator) nor in a file separated by spaces (whose commas make it read as ','-separated)."""
    return float(cell.replace(",", ".") if sep == ";" else cell)


def _row_ok(r, i, j, sep) -> bool:
    try:
        _number(r[i], sep), _number(r[j], sep)
        return True
    except (ValueError, IndexError):
        return False


def sprague_geers(measured, computed, t=None) -> tuple[float, float, float]:
    """Sprague–Geers `(M, P, C)` of `computed` against `measured` on common samples (module docstring).

    `t` (optional): the sample times, for the trapezoid integrals on a non-uniform grid.

    **Raises:** `ParameterError` for different lengths, non-finite values, or a zero history.
    """
    m, c = np.asarray(measured, dtype=float), np.asarray(computed, dtype=float)
    if m.shape != c.shape or m.ndim != 1 or m.size < 2:
        raise ParameterError("computed", f"shape {c.shape}", f"the measured history's shape {m.shape}")
    if not (np.all(np.isfinite(m)) and np.all(np.isfinite(c))):
        raise ParameterError("measured, computed", "non-finite values", "finite histories")
    x = np.arange(m.size, dtype=float) if t is None else np.asarray(t, dtype=float)
    mm, cc, mc = (np.trapezoid(u, x) for u in (m * m, c * c, m * c))
    if not (mm > 0 and cc > 0):
        raise ParameterError("measured, computed", "a zero history", "histories with a non-zero value")
    M = float(np.sqrt(cc / mm) - 1.0)
    P = float(np.arccos(np.clip(mc / np.sqrt(mm * cc), -1.0, 1.0)) / np.pi)
    return M, P, float(np.hypot(M, P))


def align_shift(t, reference, moving, how: str = "xcorr", level: float = 0.1) -> float:
    """The time shift `τ` (s) to add to the times of `moving` so that it lines up with `reference`,
    both sampled on the same uniform grid `t`.

    - `"xcorr"`: the lag of the largest cross-correlation (`scipy.signal.correlate`), refined between
      samples by the parabola through the peak and its neighbours;
    - `"onset"`: the difference of the first upward crossings of `level` (10 %) of each one's peak
      (linear interpolation);
    - `"none"`: 0.
    """
    from scipy import signal

    if how not in ALIGNMENTS:
        raise ParameterError("align", how, f"one of {', '.join(ALIGNMENTS)}")
    if how == "none":
        return 0.0
    t = np.asarray(t, dtype=float)
    r, mv = np.asarray(reference, dtype=float), np.asarray(moving, dtype=float)
    h = (t[-1] - t[0]) / (t.size - 1)
    if how == "onset":
        def onset(y):
            s = 1.0 if y.max() >= -y.min() else -1.0
            y = s * y
            i = int(np.argmax(y >= level * y.max()))
            if i == 0:
                return t[0]
            return t[i - 1] + h * (level * y.max() - y[i - 1]) / (y[i] - y[i - 1])
        return float(onset(r) - onset(mv))
    xc = signal.correlate(r, mv, mode="full", method="fft")
    k = int(np.argmax(xc))
    lag = float(k - (mv.size - 1))
    if 0 < k < xc.size - 1:
        y0, y1, y2 = xc[k - 1], xc[k], xc[k + 1]
        den = y0 - 2 * y1 + y2
        if den < 0:
            lag += 0.5 * (y0 - y2) / den
    return lag * h


@dataclasses.dataclass(frozen=True)
class Comparison:
    """The model's top pulse against a measured pulse (`compare`). SI units; times of the measurement.

    | field | meaning |
    |---|---|
    | `t` | the common uniform grid (s): the measurement's samples over the compared window |
    | `measured`, `model` | the two accelerations on `t` (m/s²), filtered alike, the model shifted |
    | `shift` | time added to the model's clock to align it (s) |
    | `alignment`, `cfc` | how it was aligned; the CFC applied to both (None: unfiltered) |
    | `measured_metrics`, `model_metrics` | `PulseMetrics` of each |
    | `sprague_geers` | `(M, P, C)` of the model against the measurement |
    | `srs_frequencies_Hz`, `measured_srs`, `model_srs` | the SRS of each (`srs_options`; default maximax acceleration, Q = 10, g) |
    | `notes` | one line each: what was capped or assumed |
    | `partial` | the model's run did not complete (`hertz_chain.Status`: t_max or max_steps): its pulse is cut where the run stopped (a note says so) |
    """

    # arrays out of the repr (a notebook's echo printed hundreds of lines)
    t: np.ndarray = dataclasses.field(repr=False)
    measured: np.ndarray = dataclasses.field(repr=False)
    model: np.ndarray = dataclasses.field(repr=False)
    shift: float
    alignment: str
    cfc: int | None
    measured_metrics: PulseMetrics
    model_metrics: PulseMetrics
    sprague_geers: tuple[float, float, float]
    srs_frequencies_Hz: np.ndarray = dataclasses.field(repr=False)
    measured_srs: np.ndarray = dataclasses.field(repr=False)
    model_srs: np.ndarray = dataclasses.field(repr=False)
    notes: tuple[str, ...] = ()
    source: str = ""
    srs_options: Any = None  # `srs.SRSOptions` of both spectra (None: the defaults)
    partial: bool = False

    def to_dict(self) -> dict:
        """JSON-ready summary (SI units, plus g and ms where the key says so)."""
        def metrics(pm: PulseMetrics) -> dict:
            out = {"peak_g": pm.peak_g, "duration_10_ms": pm.duration_10 * 1e3,
                   "equivalent_half_sine_ms": pm.equivalent_half_sine_duration * 1e3,
                   "rise_time_ms": pm.rise_time * 1e3, "delta_v_mps": pm.delta_v_main}
            return {k: (float(v) if np.isfinite(v) else None) for k, v in out.items()}  # None: not measured
        from .spectrum import SRSOptions

        o = self.srs_options if self.srs_options is not None else SRSOptions()
        mm, cm = metrics(self.measured_metrics), metrics(self.model_metrics)
        M, P, C = self.sprague_geers
        return {
            "measured_file": self.source,
            "alignment": self.alignment,
            "shift_ms": self.shift * 1e3,
            "cfc": self.cfc,
            "measured": mm,
            "model": cm,
            "relative_difference": {k: (cm[k] - mm[k]) / mm[k] if mm[k] and cm[k] is not None else None for k in mm},
            "sprague_geers": {"magnitude": M, "phase": P, "comprehensive": C},
            "srs": {"type": o.kind, "peak": {"abs": "maximax", "pos": "positive", "neg": "negative"}[o.peak],
                    "q": o.Q, "per_octave": o.per_octave, "units": "g" if o.kind == "acceleration" else "m/s",
                    "frequencies_Hz": self.srs_frequencies_Hz.tolist(), "measured": self.measured_srs.tolist(),
                    "model": self.model_srs.tolist(),
                    "max_abs_difference_dB": float(np.max(np.abs(20 * np.log10(self.model_srs / self.measured_srs))))},
            "partial": self.partial,
            "notes": list(self.notes),
        }


QUIET_MIN_SAMPLES = 20  # fewer samples before the pulse: no estimate of the record's offset and noise


def quiet_start(t, a) -> tuple[float, float, int]:
    """The record before its pulse, the channel's own baseline: `(mean, standard deviation, count)` of the
    samples before the main pulse's 10 % start (`pulse_metrics`) less a quarter of its 10 % duration;
    `(nan, nan, count)` where fewer than `QUIET_MIN_SAMPLES` samples lie there (a record that starts at the
    impact). `a` upward-positive, as `prepare_record` returns it."""
    quiet = _quiet_samples(t, a)
    if quiet.size < QUIET_MIN_SAMPLES:
        return float("nan"), float("nan"), int(quiet.size)
    return float(quiet.mean()), float(quiet.std(ddof=1)), int(quiet.size)


def _quiet_samples(t, a) -> np.ndarray:
    """The samples of `quiet_start`."""
    t, a = np.asarray(t, dtype=float), np.asarray(a, dtype=float)
    pm = pulse_metrics(t, a)
    return a[t < pm.t_start_10 - 0.25 * pm.duration_10]


def _independent_samples(x) -> float:
    """The effective number of independent samples of a noise record, `n / tau`, `tau = 1 + 2 sum rho_k`
    over the lags whose autocorrelation `rho_k` stays positive (Geyer's initial positive sequence): a
    channel sampled above its anti-alias bandwidth has correlated neighbours, and the mean of its quiet
    start scatters by `std / sqrt(n / tau)`, not `std / sqrt(n)` (a review: with `sqrt(n)`, a band-limited
    zero-mean record was called offset in 12-15 % of seeds)."""
    x = np.asarray(x, dtype=float) - np.mean(x)
    n = x.size
    spec = np.fft.rfft(x, 2 * n)
    acf = np.fft.irfft(spec * np.conj(spec))[:n]
    if acf[0] <= 0:
        return float(n)
    rho = (acf / acf[0])[1 : max(n // 2, 2)]
    stop = int(np.argmax(rho <= 0)) if np.any(rho <= 0) else rho.size  # the first lag that is not positive
    return n / (1.0 + 2.0 * float(np.sum(rho[:stop])))


def prepare_record(measured: MeasuredPulse, cfc: int | None = None) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The measured record as :func:`compare` and `hertz_chain.fitting` use it, before any filter:
    `(t, a, notes)` on a uniform grid (a non-uniform record resampled linearly at its median step, so that
    a uniform record with missing samples keeps its own samples, or at its mean step where the median
    would make the record more than 4 times longer; a note naming any gap longer than 5 steps), with a
    negative-going record's sign flipped (a note), and a note where its quiet start (`quiet_start`) shows
    an offset. `cfc` only changes the notes' wording (the filter is applied by the caller)."""
    t = np.asarray(measured.t, dtype=float)
    h = (t[-1] - t[0]) / (t.size - 1)
    notes = list(measured.notes)
    dt = np.diff(t)
    uniform = np.max(np.abs(dt - h)) <= 1e-6 * h
    if not uniform:
        # the median step: a record on a uniform clock with samples missing keeps its own samples (a review:
        # resampled at the mean rate, 246,662 Hz for a 250 kHz record, every sample was an interpolated one)
        h_med = float(np.median(dt))
        count = int(round((t[-1] - t[0]) / h_med)) + 1
        kind = "median step" if count <= 4 * t.size else "mean step"
        if kind == "median step":
            h = (t[-1] - t[0]) / (count - 1)
        t_u = t[0] + h * np.arange(int(round((t[-1] - t[0]) / h)) + 1)
        m_u = np.interp(t_u, t, measured.a)
        notes.append(f"the measurement's times are not uniform: resampled linearly at its {kind} ({1 / h:.6g} Hz)"
                     + (" before the CFC filter" if cfc is not None else ""))
        if dt.max() > 5 * h:
            i = int(np.argmax(dt))
            notes.append(f"the measurement has a gap of {dt[i] * 1e3:.4g} ms ({dt[i] / h:.3g} steps) after "
                         f"t = {t[i] * 1e3:.6g} ms: the resampled record is a straight line across it")
        t = t_u
    else:
        m_u = np.asarray(measured.a, dtype=float)
    flipped = pulse_metrics(t, m_u).sign < 0
    if flipped:
        m_u = -m_u
        notes.append("the measured pulse is negative-going (its largest excursion is below zero): it is compared "
                     "with its sign flipped, as the model's top pulse is positive (upward acceleration)")
    # a constant offset of the channel (a review: +5 g, 0.4 % of the peak, moved a fitted e by 2.4 standard
    # errors without a word): its mean before the pulse, beyond 4 standard errors of that mean and 0.1 % of the
    # peak
    quiet = _quiet_samples(t, m_u)
    peak = float(np.max(m_u))
    if quiet.size >= QUIET_MIN_SAMPLES:
        mean, std = float(quiet.mean()), float(quiet.std(ddof=1))
        if abs(mean) > 1e-3 * peak and abs(mean) > 4 * std / np.sqrt(_independent_samples(quiet)):
            own = -mean if flipped else mean  # in the file's own sign (a review: the flipped one misled)
            notes.append(f"the record's quiet start ({quiet.size} samples before the pulse) averages "
                         f"{own / G0:.4g} g in the file ({100 * own / peak:+.2f} % of the peak), not 0: an offset "
                         "of the channel shifts the velocity change and biases a fit; subtract it (the "
                         "pre-trigger mean) first")
    return t, m_u, notes


def compare(report, measured: MeasuredPulse, *, cfc: int | None = None, align: str = "xcorr",
            shift: float | None = None, srs_options=None) -> Comparison:
    """Compare the top pulse of a simulated stack with a measured pulse.

    **Arguments:**

    - `report`: a `hertz_chain.Report` (e.g. `hc.simulate_file(path)`) whose run holds the top
      mass's pulse.
    - `measured`: a :class:`MeasuredPulse` (:func:`read_pulse_csv`).
    - `cfc`: filter both the measurement and the model by this channel frequency class (60, 180, 600,
      1000; `hertz_chain.filters.cfc_filter`), as a lab's data channel would; None: no filter.
    - `align`: `"xcorr"` (default), `"onset"` or `"none"` (`align_shift`).
    - `shift`: a time shift (s) to use as it is instead of aligning (`hertz_chain.fitting` passes its
      fitted shift); `alignment` then reads `"given"`.
    - `srs_options`: how both SRS are computed (`srs.SRSOptions`: Q, points per octave, band, peak,
      acceleration or pseudo-velocity; the stack file's `[srs]`); default maximax acceleration, Q = 10,
      1/12 octave over the default band.

    The model's accelerometer (`analysis.accelerometer`: the dense solution) is sampled on the
    measurement's grid, shifted, filtered alike; outside the run it reads zero (free flight before
    impact). The compared window is the measurement's record. The SRS grid is 1/12 octave over
    `[min(100 Hz, 0.1/D), max(10 kHz, 20/D)]` (D the measured 10 % duration), capped at a tenth of the
    measurement's sample rate, with a note saying so when capped.

    **Returns:** a :class:`Comparison`.

    A non-uniform record is resampled linearly at its median step first (`prepare_record`; a note says so,
    and names any gap longer than 5 steps); a negative-going record is compared with its sign flipped (a note says
    so); a note names a pulse that the record's window cuts, and a model run that did not complete
    (`Comparison.partial`).

    **Raises:** `ParameterError` for a report without a top pulse, a bad `cfc`/`align`, or a record
    sampled more coarsely than half the model's pulse (usually a wrong time unit).
    """
    from .analysis import accelerometer
    from .filters import cfc_filter
    from .spectrum import SRSOptions, octave_frequencies, srs_uniform

    if align not in ALIGNMENTS:
        raise ParameterError("align", align, f"one of {', '.join(ALIGNMENTS)}")
    if report.top_pulse is None:
        raise ParameterError("report", "no top pulse", "a run in which the top mass was struck")
    top = report.top_pulse
    t, m_u, notes = prepare_record(measured, cfc)
    h = (t[-1] - t[0]) / (t.size - 1)
    sol_t = np.asarray(report.solution.steps.t, dtype=float)
    h_model = top.duration_10
    if h_model < 2 * h:
        raise ParameterError(f"{measured.source or 'measured'}: sample interval", f"{h * 1e3:.6g} ms",
                             f"at most half the model's pulse ({h_model * 1e3:.4g} ms between its 10 % points; this "
                             "interval is longer): check the time unit (header or --time-unit)")

    def model_on(times):
        inside = (times >= sol_t[0]) & (times <= sol_t[-1])
        out = np.zeros_like(times)
        out[inside] = accelerometer(report, times[inside])
        return out

    # first place the model's main pulse in the middle of the record's pulse, then align finely
    meas_pm = pulse_metrics(t, m_u)
    coarse = (0.5 * (meas_pm.t_start_10 + meas_pm.t_end_10)) - 0.5 * (top.t_start_10 + top.t_end_10)
    if shift is None:
        model_raw = model_on(t - coarse)
        shift = coarse + align_shift(t, m_u, model_raw, align) if align != "none" else 0.0
    else:
        align = "given"
    model = model_on(t - shift)
    meas = m_u
    if cfc is not None:
        meas, model = cfc_filter(t, meas, cfc), cfc_filter(t, model, cfc)
    if not np.any(model):
        raise ParameterError(f"{measured.source or 'measured'}: time window",
                             f"[{t[0] * 1e3:.6g}, {t[-1] * 1e3:.6g}] ms",
                             f"a record that holds the model's pulse ({top.duration_10 * 1e3:.4g} ms between its 10 % "
                             "points; the model reads zero on this window): check the time unit (header or --time-unit)"
                             + (" or the alignment (the model's clock starts at impact: --align xcorr or onset, "
                                "in the Python API a shift)" if align in ("none", "given") else ""))
    raw_pm = meas_pm
    raw_peak = raw_pm.peak_g
    meas_pm, model_pm = pulse_metrics(t, meas), pulse_metrics(t, model)
    if cfc is not None and meas_pm.peak_g < 0.9 * raw_peak:  # a review: CFC 1000 took a 65 us pulse's peak
        # from 26,130 g to 5,050 g without a word (right, as filtering, but rarely what was meant)
        notes.append(f"the CFC {cfc} filter lowers the measured peak by {100 * (1 - meas_pm.peak_g / raw_peak):.0f} % "
                     f"({raw_peak:.5g} g -> {meas_pm.peak_g:.5g} g): a pulse of {raw_pm.duration_10 * 1e3:.3g} ms is "
                     f"short for a channel flat to {cfc} Hz; a higher class, or none, keeps it")
    ratio = meas_pm.duration_10 / top.duration_10
    if not 0.1 <= ratio <= 10:
        notes.append(f"the measured pulse lasts {ratio:.3g} times the model's ({meas_pm.duration_10 * 1e3:.4g} ms "
                     f"against {top.duration_10 * 1e3:.4g} ms between 10 % points): check the time unit")
    # g written as m/s^2 or the reverse: the velocity change (the area, whatever the shape) off by 9.81 (a
    # review: +874 % peak and velocity change without a word, where a wrong time unit is noted)
    # both the velocity change and the peak (a wrong drop height moves the peak as v^1.2, the change as v)
    dv_ratio = meas_pm.delta_v_main / model_pm.delta_v_main if model_pm.delta_v_main > 0 else math.nan
    pk_ratio = meas_pm.peak_g / model_pm.peak_g if model_pm.peak_g > 0 else math.nan
    for factor, said, meant in ((G0, "g", "m/s^2"), (1 / G0, "m/s^2", "g")):
        if abs(dv_ratio / factor - 1) < 0.15 and abs(pk_ratio / factor - 1) < 0.15:
            notes.append(f"the measured velocity change is {dv_ratio:.3g} times the model's, close to {factor:.4g} "
                         f"(the ratio of g to m/s^2): check the acceleration unit (a record in {meant} read as "
                         f"{said}? header or --accel-unit)")
    for who, pm in (("measured", meas_pm), ("model's", model_pm)):
        if pm.truncated:
            notes.append(f"the record's window cuts the {who} pulse: its duration and velocity change are measured "
                         "to the window's edge")
    partial = not report.status.ok
    if partial:  # a review: a cut model pulse was compared as if whole, exit 0
        notes.append(f"the model's run did not complete ({report.status.text}): its pulse is cut at "
                     f"{report.t_final * 1e3:.4g} ms; {report.status.hint()}")
    M, P, C = sprague_geers(meas, model, t)
    D = meas_pm.duration_10
    opts = srs_options if srs_options is not None else SRSOptions()
    step = 2.0 ** (1 / opts.per_octave) * (1 + 1e-12)
    if opts.band is not None:
        f_lo, f_hi = opts.band[0] / step, opts.band[1] * step
    else:
        f_lo, f_hi = min(100.0, 0.1 / D) / step, max(1e4, 20.0 / D) * step
    cap = 0.1 / h
    if f_hi / step > cap * (1 + 1e-12):
        notes.append(f"SRS band capped at {cap:.6g} Hz (a tenth of the measurement's {1 / h:.6g} Hz sample rate), "
                     f"below the {f_hi / step:.6g} Hz asked for")
    f_hi = min(f_hi, cap)
    freqs = octave_frequencies(f_lo, f_hi, opts.per_octave)
    unit = G0 if opts.kind == "acceleration" else 1.0  # g; a pseudo-velocity from m/s² is in m/s
    kw = dict(peak=opts.peak, kind=opts.kind)
    s_meas = srs_uniform(meas / unit, 1.0 / h, freqs, opts.Q, **kw)
    s_model = srs_uniform(model / unit, 1.0 / h, freqs, opts.Q, **kw)
    return Comparison(t, meas, model, float(shift), align, cfc, meas_pm, model_pm, (M, P, C), freqs,
                      s_meas.maximax, s_model.maximax, tuple(notes), measured.source, opts, partial)
