"""Shock-test conditions and the check of a pulse against them (`hertz-chain check`).

**The table.** `hertz_chain/data/shock_standards.csv` holds one nominal pulse per test condition
(JESD22-B110 A–H, MIL-STD-883 Method 2002 A–G, MIL-STD-810H Method 516.8 Procedure I sawtooth pulses),
each row with its document, edition, clause and where its numbers were read (`source`, and
`source_level`: primary, secondary, or secondary-unverified). :func:`conditions` reads it;
:func:`find_condition` looks a name up (`"JESD22-B110 B"`, `"MIL-STD-883 2002 B"`: case, spaces and
hyphens do not matter). Tolerances are in the table only where the source gave them; otherwise the
stack file's `[test]` section gives them (:class:`TestSpec`). docs/lab-workflow.md lists what is there,
what is not, and why.

**Nominal pulses** (`A` the peak, `D` the duration, time from the start of the pulse):

| shape | a(t) on [0, D] | ΔV | 10 % width |
|---|---|---|---|
| half-sine | `A sin(πt/D)` | `2AD/π` | `(1 − 2 asin(0.1)/π) D = 0.93623 D` |
| sawtooth (terminal peak) | `A t/D`, then 0 | `AD/2` | `0.9 D` |
| trapezoid | rise and fall over `D/10` each | `0.9 AD` | `0.98 D` |

**The check** (:func:`check_pulse`) compares like with like: the pulse's peak with `A`; its width between
its 10 % points with the nominal pulse's own 10 % width (so a perfect half-sine of duration `D` passes
exactly); its velocity change over the main lobe with the nominal ΔV; and, when a band is given, the pulse
against the nominal pulse ± `band`·A over the nominal pulse's support joined with the pulse's main lobe,
the nominal pulse placed where the smallest margin is largest. Each criterion reports its value, the
allowed range and the margin (the distance to the nearer limit, in the criterion's unit, negative when
it fails). Without a tolerance a criterion is reported, not judged (`passed` None).

**The SRS criterion** (`[test] srs`, a table of `[frequency, level]` rows in Hz and g, with
`srs_tolerance_db` and `srs_q`): the maximax absolute-acceleration SRS of the checked record at 1/12
octave across the table (and at its rows), against the table interpolated log-log; the criterion's
value is the deviation (dB) at the worst point and its margin the distance to the nearer limit there.
"""

from __future__ import annotations

import csv
import dataclasses
import difflib
import functools
import math
import re
from pathlib import Path

import numpy as np

from .constants import G0
from .errors import ParameterError
from .pulse import pulse_metrics

__all__ = [
    "SHAPES",
    "ShockCondition",
    "TestSpec",
    "Criterion",
    "CheckResult",
    "conditions",
    "find_condition",
    "nominal_pulse",
    "nominal_delta_v",
    "nominal_width_10",
    "check_pulse",
    "standards_table",
    "TEST_KEYS",
    "parse_test",
    "check",
]

STANDARDS_CSV = Path(__file__).resolve().parent / "data" / "shock_standards.csv"

#: Nominal pulse shapes: name -> (ΔV / (A·D), 10 % width / D).
#: Default fall allowance of a terminal-peak sawtooth's band, as a fraction of its duration D: the
#: nominal pulse drops vertically at D, a real one cannot; the band's upper limit falls from the peak to
#: zero over `fall_time` (hertz_chain's choice, stated in every check that uses it; `test.fall_time`).
DEFAULT_FALL = 0.1

#: The band is judged from `before · D` ahead of the nominal pulse to `after · D` past its end (and over
#: the pulse's own 10 % span): the standards' tolerance figures monitor the pulse some time before and
#: after it, so that ringing, an undershoot or a second hit there fails. hertz_chain's default, not a
#: number read in a standard (`test.band_window`, in multiples of D; set it from your standard's figure).
DEFAULT_BAND_WINDOW = (0.4, 0.4)

#: How the duration criterion reads the pulse (`test.duration_reference`): `"nominal-width"` (default)
#: compares the width between the pulse's own 10 % points with the nominal pulse's 10 % width (a perfect
#: pulse of duration D passes with its full margin); `"D"` compares the width between the points at 10 % of
#: the *specified* peak with D itself, as standards that define the duration so read it.
DURATION_REFERENCES = ("nominal-width", "D")

SHAPES = {
    "half-sine": (2.0 / math.pi, 1.0 - 2.0 * math.asin(0.1) / math.pi),
    "sawtooth": (0.5, 0.9),
    "trapezoid": (0.9, 0.98),
}


@dataclasses.dataclass(frozen=True)
class ShockCondition:
    """One row of the table (SI units; tolerances in percent, None where the source gives none)."""

    standard: str
    condition: str
    document: str
    edition: str
    clause: str
    shape: str
    peak_g: float
    duration: float  # s
    delta_v: float | None  # m/s, as tabulated (None if the source gives none)
    peak_tolerance: tuple[float, float] | None
    duration_tolerance: tuple[float, float] | None
    velocity_tolerance: tuple[float, float] | None
    source: str
    source_level: str

    @property
    def name(self) -> str:
        return f"{self.standard} {self.condition}"


def _norm(name: str) -> str:
    return re.sub(r"[\s\-_.]+", "", str(name)).lower()


def _tol(low: str, high: str) -> tuple[float, float] | None:
    if not low.strip() and not high.strip():
        return None
    return (float(low), float(high))


@functools.lru_cache(maxsize=1)
def conditions() -> tuple[ShockCondition, ...]:
    """Every row of `data/shock_standards.csv`, in file order."""
    lines = [ln for ln in STANDARDS_CSV.read_text(encoding="utf-8").splitlines() if not ln.startswith("#")]
    rows = []
    by_key: dict[tuple[str, str], str] = {}
    for r in csv.DictReader(lines):
        vt = r["velocity_tol_pct"].strip()
        m = re.match(r"as row ([^;,]+)(.*)", r["source"])
        if m and (r["standard"], m.group(1).strip()) in by_key:  # "as row A; ...": row A's source, then the rest
            r["source"] = by_key[(r["standard"], m.group(1).strip())] + m.group(2)
        by_key[(r["standard"], r["condition"])] = r["source"]
        rows.append(ShockCondition(
            standard=r["standard"], condition=r["condition"], document=r["document"], edition=r["edition"],
            clause=r["clause"], shape=r["shape"], peak_g=float(r["peak_g"]), duration=float(r["duration_ms"]) * 1e-3,
            delta_v=float(r["delta_v_mps"]) if r["delta_v_mps"].strip() else None,
            peak_tolerance=_tol(r["peak_tol_low_pct"], r["peak_tol_high_pct"]),
            duration_tolerance=_tol(r["duration_tol_low_pct"], r["duration_tol_high_pct"]),
            velocity_tolerance=(-float(vt), float(vt)) if vt else None,
            source=r["source"], source_level=r["source_level"],
        ))
    return tuple(rows)


def find_condition(name: str) -> ShockCondition:
    """The row named `name` (`"<standard> <condition>"`, e.g. `"JESD22-B110 B"`).

    **Raises:** `ParameterError` naming the closest names when there is no such row.
    """
    key = _norm(name)
    table = {_norm(c.name): c for c in conditions()}
    if key in table:
        return table[key]
    documents = sorted({c.standard for c in conditions()})
    same = [d for d in documents if key.startswith(_norm(d.split()[0]))]  # "MIL-STD-883 B" is of MIL-STD-883 2002
    if not same:  # no suggestion from another document: its levels differ (a review: JESD22-B104 C was
        # offered B110 C, 100 g / 2 ms for 3000 g / 0.3 ms)
        raise ParameterError("standard", name, f"not a document of the table (it has {', '.join(documents)}); "
                             "give the pulse in the [test] section instead: shape, peak_g, duration and their "
                             "tolerances (docs/lab-workflow.md; hertz-chain check --standard list)")
    names = [c.name for c in conditions() if c.standard in same]
    close = difflib.get_close_matches(str(name), names, n=3, cutoff=0.5)
    hint = f"did you mean {', '.join(repr(c) for c in close)}? " if close else ""
    raise ParameterError("standard", name, f"{hint}a condition of the table (hertz-chain check --standard list)")


def standards_table() -> str:
    """The table as text: name, shape, peak, duration, tolerances and the source level."""
    def tol(t):
        return "-" if t is None else f"{t[0]:+g}/{t[1]:+g} %"
    lines = [f"{'condition':<44} {'shape':<10} {'peak g':>8} {'ms':>6}  {'peak tol':<12} {'dur. tol':<12} source"]
    for c in conditions():
        lines.append(f"{c.name:<44} {c.shape:<10} {c.peak_g:>8g} {c.duration * 1e3:>6g}  {tol(c.peak_tolerance):<12} "
                     f"{tol(c.duration_tolerance):<12} {c.source_level}")
    lines.append("tolerances marked '-' are not in the sources read; give them in the stack file's [test] section "
                 "(docs/lab-workflow.md)")
    return "\n".join(lines)


def _check_shape(shape: str) -> str:
    if shape not in SHAPES:
        raise ParameterError("shape", shape, f"one of {', '.join(SHAPES)}")
    return shape


def nominal_pulse(shape: str, peak: float, duration: float, t) -> np.ndarray:
    """The nominal pulse `a(t)` (units of `peak`), `t` from its start (s); zero outside `[0, D]` (module
    docstring's table)."""
    _check_shape(shape)
    t = np.asarray(t, dtype=float)
    s = t / duration
    inside = (s >= 0) & (s <= 1)
    if shape == "half-sine":
        y = np.sin(np.pi * np.clip(s, 0, 1))
    elif shape == "sawtooth":
        y = np.clip(s, 0, 1)
    else:
        y = np.clip(np.minimum(s, 1 - s) / 0.1, 0, 1)
    return np.where(inside, peak * y, 0.0)


def band_limits(spec: TestSpec, t) -> tuple[np.ndarray, np.ndarray]:
    """The band's lower and upper limits (units of `spec.peak_g`, g) at `t` (s from the nominal pulse's
    start): the nominal pulse ± `band`·A, where a terminal-peak sawtooth's upper limit falls linearly
    from its peak to zero over `spec.fall_time` after `D` (the fall allowance) while its lower limit
    drops at `D`."""
    t = np.asarray(t, dtype=float)
    nom = nominal_pulse(spec.shape, spec.peak_g, spec.duration, t)
    upper = nom
    if spec.shape == "sawtooth" and spec.fall_time:
        s = (t - spec.duration) / spec.fall_time
        upper = np.maximum(nom, np.where((s >= 0) & (s <= 1), spec.peak_g * (1.0 - np.clip(s, 0, 1)), 0.0))
    b = spec.band * spec.peak_g
    return nom - b, upper + b


def nominal_delta_v(shape: str, peak: float, duration: float) -> float:
    """Velocity change of the nominal pulse (`peak` in m/s², `duration` in s)."""
    return SHAPES[_check_shape(shape)][0] * peak * duration


def nominal_width_10(shape: str, duration: float) -> float:
    """Width of the nominal pulse between its 10 % points."""
    return SHAPES[_check_shape(shape)][1] * duration


@dataclasses.dataclass(frozen=True)
class TestSpec:
    """What a pulse is checked against: a nominal pulse and tolerances (percent of nominal), the band's
    half-width as a fraction of the peak, and where each came from. `from_condition` fills it from a
    table row; the stack file's `[test]` section overrides any field."""

    __test__ = False  # not a pytest class

    name: str
    shape: str
    peak_g: float
    duration: float
    peak_tolerance: tuple[float, float] | None = None
    duration_tolerance: tuple[float, float] | None = None
    velocity_tolerance: tuple[float, float] | None = None
    band: float | None = None
    source: str = ""
    fall_time: float | None = None
    srs: tuple[tuple[float, float], ...] | None = None  # required SRS: rows (Hz, g)
    srs_tolerance_db: tuple[float, float] | None = None  # (below, above) in dB
    srs_q: float = 10.0
    band_window: tuple[float, float] = DEFAULT_BAND_WINDOW  # judged before / after the nominal pulse, in D
    duration_reference: str = "nominal-width"  # DURATION_REFERENCES

    def __post_init__(self):
        if self.duration_reference not in DURATION_REFERENCES:
            from .errors import ParameterError

            raise ParameterError("duration_reference", self.duration_reference, f"one of {', '.join(DURATION_REFERENCES)}")
        if self.fall_time is None and self.shape == "sawtooth":
            object.__setattr__(self, "fall_time", DEFAULT_FALL * self.duration)

    @classmethod
    def from_condition(cls, c: ShockCondition, **overrides) -> TestSpec:
        """The row's nominal pulse and tolerances, with `overrides` (any field). When the overrides change
        the nominal pulse itself (shape, peak_g or duration), the name says so: `"MIL-STD-883 2002 B,
        modified: peak_g 1000"`."""
        spec = cls(c.name, c.shape, c.peak_g, c.duration, c.peak_tolerance, c.duration_tolerance,
                   c.velocity_tolerance, None, f"{c.document}, {c.clause} ({c.source_level}: {c.source})")
        over = {k: v for k, v in overrides.items() if v is not None}
        changed = [f"{k} {over[k] * 1e3:g} ms" if k == "duration" else f"{k} {over[k]:g}" if k == "peak_g"
                   else f"{k} {over[k]}" for k in ("shape", "peak_g", "duration")
                   if k in over and over[k] != getattr(spec, k)]
        if changed:
            over["name"] = f"{c.name}, modified: {', '.join(changed)}"
        if "shape" in over and over["shape"] != "sawtooth" and "fall_time" not in over:
            over["fall_time"] = None
        elif "duration" in over and spec.shape == "sawtooth" and "fall_time" not in over:
            over["fall_time"] = DEFAULT_FALL * over["duration"]
        return dataclasses.replace(spec, **over)


@dataclasses.dataclass(frozen=True)
class Criterion:
    """One line of a check: `value` against `nominal` with the allowed `[low, high]` (None: not judged)."""

    name: str
    unit: str
    value: float
    nominal: float
    low: float | None
    high: float | None
    margin: float | None
    passed: bool | None

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class CheckResult:
    """The outcome of :func:`check_pulse`: the criteria, whether every judged one passed, the shift of
    the nominal pulse (s, from the record's time origin) and the spec."""

    spec: TestSpec
    criteria: tuple[Criterion, ...]
    nominal_start: float
    notes: tuple[str, ...] = ()
    t: np.ndarray | None = dataclasses.field(default=None, repr=False)  # the checked record (s)
    a: np.ndarray | None = dataclasses.field(default=None, repr=False)  # and its samples (m/s²)
    band_window: tuple[float, float] | None = None  # where the band was judged (s, the record's times)

    @property
    def passed(self) -> bool | None:
        """True when every judged criterion passed, False when one failed, None when nothing was judged
        (no tolerance and no band given)."""
        judged = [c.passed for c in self.criteria if c.passed is not None]
        return all(judged) if judged else None

    @property
    def verdict(self) -> str:
        """`"PASS"`, `"FAIL"` or `"NOT JUDGED"`."""
        return {True: "PASS", False: "FAIL", None: "NOT JUDGED"}[self.passed]

    def to_dict(self) -> dict:
        return {"condition": self.spec.name, "shape": self.spec.shape, "nominal_peak_g": self.spec.peak_g,
                "nominal_duration_ms": self.spec.duration * 1e3, "source": self.spec.source,
                "passed": self.passed, "verdict": self.verdict.lower(), "nominal_start_s": self.nominal_start,
                "band_window_s": None if self.band_window is None else list(self.band_window),
                "criteria": [c.to_dict() for c in self.criteria], "notes": list(self.notes)}

    def table(self) -> str:
        out = [f"check against {self.spec.name} ({self.spec.shape}, {self.spec.peak_g:g} g, "
               f"{self.spec.duration * 1e3:g} ms)"]
        for c in self.criteria:
            rng = "not judged (no tolerance)" if c.passed is None else f"allowed [{c.low:.5g}, {c.high:.5g}]"
            verdict = "" if c.passed is None else ("PASS" if c.passed else "FAIL")
            margin = "" if c.margin is None else f" margin {c.margin:+.4g} {c.unit}"
            nominal = "" if c.name in ("band", "SRS") else f" (nominal {c.nominal:.5g})"
            what = {"band": "largest excursion", "SRS": "deviation"}.get(c.name, "")
            out.append(f"  {c.name:<20} {what + ' ' if what else ''}{c.value:.5g} {c.unit}{nominal} {rng}{margin} "
                       f"{verdict}".rstrip())
        out.append(f"result: {self.verdict}" + (" (no tolerance given: add test.peak_tolerance, "
                                                 "duration_tolerance, velocity_tolerance, band, or srs with "
                                                 "srs_tolerance_db)"
                                                 if self.passed is None else ""))
        out.extend(f"note: {n}" for n in self.notes)
        return "\n".join(out)


def _duration_criterion(t, a, pm, spec: TestSpec) -> Criterion:
    """The duration criterion as `spec.duration_reference` reads it (`DURATION_REFERENCES`): the pulse's
    own 10 % width against the nominal pulse's, or the width at 10 % of the specified peak against D
    (zero where the pulse never reaches that level)."""
    if spec.duration_reference == "nominal-width":
        return _judge("duration (10 %)", "ms", pm.duration_10 * 1e3,
                      nominal_width_10(spec.shape, spec.duration) * 1e3, spec.duration_tolerance)
    level = 0.1 * spec.peak_g / pm.peak_g  # 10 % of the specified peak, as a fraction of the pulse's own
    width = pulse_metrics(t, a, duration_level=level).duration_10 if level < 1 else 0.0
    return _judge("duration (10 % of A)", "ms", width * 1e3, spec.duration * 1e3, spec.duration_tolerance)


def _judge(name, unit, value, nominal, tol) -> Criterion:
    if tol is None:
        return Criterion(name, unit, float(value), float(nominal), None, None, None, None)
    lo, hi = nominal * (1 + tol[0] / 100), nominal * (1 + tol[1] / 100)
    margin = min(value - lo, hi - value)
    return Criterion(name, unit, float(value), float(nominal), float(lo), float(hi), float(margin), bool(margin >= 0))


#: even points over the nominal pulse's support at which `band_margin` also evaluates the band
BAND_POINTS = 401


def band_window(spec: TestSpec, centre_start: float, lobe: tuple[float, float]) -> tuple[float, float]:
    """The times (s) over which the band is judged: from `band_window[0] · D` before the nominal pulse
    to `band_window[1] · D` after its end (`D`, plus a sawtooth's `fall_time`), the nominal pulse placed
    with its 10 % points centred on the pulse's (`centre_start`, before the band's own placement, so that
    the window is the record's, not moved by the placement), joined with the pulse's main lobe `lobe`."""
    before, after = spec.band_window
    end = centre_start + spec.duration + (spec.fall_time or 0.0)
    return min(centre_start - before * spec.duration, lobe[0]), max(end + after * spec.duration, lobe[1])


def band_margin(t, a_g, spec: TestSpec, start: float, window: tuple[float, float]) -> float:
    """Smallest distance (g) of the pulse inside its band (:func:`band_limits`), negative where it leaves
    it, over `window` (:func:`band_window`) joined with the nominal pulse's support `[start, start + D
    (+ fall_time)]`, for the nominal pulse starting at `start` (the pulse `a_g` in g, linear between
    samples, sampled at `t`, its first and last values held outside them). Evaluated at the pulse's samples
    and at `BAND_POINTS` even points over that span: the band's own shape counts between samples, and
    where the nominal pulse reaches past the record (the record stops at the cascade's end)."""
    t0 = min(window[0], start)
    t1 = max(window[1], start + spec.duration + (spec.fall_time or 0.0))
    inside = (t >= t0) & (t <= t1)
    tt = np.union1d(t[inside], np.linspace(t0, t1, BAND_POINTS))
    aa = np.interp(tt, t, a_g)
    lo, hi = band_limits(spec, tt - start)
    return float(np.min(np.minimum(hi - aa, aa - lo)))


def check_pulse(t, a, spec: TestSpec) -> CheckResult:
    """Check the pulse `a(t)` (m/s², samples linear between them) against `spec` (module docstring).

    **Returns:** a :class:`CheckResult`: peak (g), width at 10 % (ms), velocity change (m/s) and, with
    `spec.band`, the band (g).

    **Raises:** `ParameterError` for a record `pulse_metrics` refuses.
    """
    from scipy.optimize import minimize_scalar

    t, a = np.asarray(t, dtype=float), np.asarray(a, dtype=float)
    pm = pulse_metrics(t, a)
    a_g = pm.sign * a / G0
    peak_nom = spec.peak_g * G0
    crit = [
        _judge("peak", "g", pm.peak_g, spec.peak_g, spec.peak_tolerance),
        _duration_criterion(t, a, pm, spec),
        _judge("velocity change", "m/s", abs(pm.delta_v_main), nominal_delta_v(spec.shape, peak_nom, spec.duration),
               spec.velocity_tolerance),
    ]
    notes = []
    # the nominal pulse starts where its 10 % points centre on the pulse's (refined to the best band fit)
    w = nominal_width_10(spec.shape, spec.duration)
    lead = {"half-sine": math.asin(0.1) / math.pi, "sawtooth": 0.1, "trapezoid": 0.01}[spec.shape] * spec.duration
    start = 0.5 * (pm.t_start_10 + pm.t_end_10) - (lead + 0.5 * w)
    if spec.band is not None:
        window = band_window(spec, start, (pm.t_start_10, pm.t_end_10))
        span = 0.5 * spec.duration
        grid = start + np.linspace(-span, span, 201)
        vals = [band_margin(t, a_g, spec, s, window) for s in grid]
        k = int(np.argmax(vals))
        lo_s, hi_s = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
        res = minimize_scalar(lambda s: -band_margin(t, a_g, spec, s, window), bounds=(lo_s, hi_s), method="bounded",
                              options={"xatol": 1e-6 * spec.duration})
        start = float(res.x) if -res.fun >= vals[k] else float(grid[k])
        m = band_margin(t, a_g, spec, start, window)
        crit.append(Criterion("band", "g", float(spec.band * spec.peak_g - m), 0.0, 0.0,
                              float(spec.band * spec.peak_g), float(m), bool(m >= 0)))
        w0 = min(window[0], start)
        w1 = max(window[1], start + spec.duration + (spec.fall_time or 0.0))
        window = (w0, w1)
        outside = (t < w0) | (t > w1)
        if np.any(outside) and np.max(np.abs(a_g[outside])) > spec.band * spec.peak_g:
            k = int(np.flatnonzero(outside)[np.argmax(np.abs(a_g[outside]))])
            notes.append(f"the record leaves the band outside the judged window: {a_g[k]:+.4g} g at "
                         f"{(t[k] - start) * 1e3:+.4g} ms from the nominal pulse's start, not judged (the band "
                         f"is judged from {spec.band_window[0]:g} D before the nominal pulse to "
                         f"{spec.band_window[1]:g} D after it: test.band_window)")
        if spec.shape == "sawtooth" and spec.fall_time:
            notes.append(f"the band lets the sawtooth fall from its peak to zero within {spec.fall_time * 1e3:.4g} ms "
                         f"after D (test.fall_time; default {DEFAULT_FALL:g} D, hertz_chain's allowance, not a "
                         "number of the standard)")
    if spec.srs is not None:
        c, note = srs_criterion(t, pm.sign * a, spec)
        crit.append(c)
        notes.append(note)
    if pm.truncated:
        notes.append("the record cuts the pulse: its duration and velocity change are measured to the record's end")
    return CheckResult(spec, tuple(crit), float(start), tuple(notes), t, a,
                       None if spec.band is None else (float(window[0]), float(window[1])))


# ------------------------------------------------------------------------------------------ files
#: Keys of a stack file's `[test]` section.
TEST_KEYS = ("standard", "shape", "peak_g", "duration", "peak_tolerance", "duration_tolerance",
             "duration_reference", "velocity_tolerance", "band", "band_window", "fall_time", "srs",
             "srs_tolerance_db", "srs_q")


def _tolerance(raw, key: str) -> tuple[float, float]:
    """`10` (meaning ±10 %) or `[-10, 20]` (percent below and above the nominal value)."""
    from .errors import StackFileError

    vals = raw if isinstance(raw, list) else [raw]
    if (not 1 <= len(vals) <= 2 or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in vals)
            or not all(math.isfinite(v) for v in vals)):
        raise StackFileError(f"test.{key}: {raw!r} is invalid: a percentage (10 = ±10 %) or [below, above] "
                             "in percent, e.g. [-20, 20]")
    if len(vals) == 1 and vals[0] < 0:  # a one-sided tolerance is a list; a negative ± is a typo
        raise StackFileError(f"test.{key}: {raw!r} is invalid: a percentage >= 0 (10 = ±10 %), or [below, above] "
                             "for a one-sided tolerance, e.g. [-20, 0]")
    lo, hi = (-abs(vals[0]), abs(vals[0])) if len(vals) == 1 else (float(vals[0]), float(vals[1]))
    if not (-100 < lo <= 0 <= hi):
        if len(vals) == 1:  # a single number: say so in its own terms (a review: 200 was told of lists only)
            raise StackFileError(f"test.{key}: {raw!r} is invalid: a percentage below 100 (10 = ±10 %; a value "
                                 "may not fall by 100 % or more), or [below, above] with -100 < below <= 0 <= above")
        raise StackFileError(f"test.{key}: {raw!r} is invalid: [below, above] with -100 < below <= 0 <= above (percent)")
    return (lo, hi)


def _db_tolerance(raw) -> tuple[float, float]:
    """`6` (meaning ±6 dB) or `[-3, 6]` (dB below and above the required SRS)."""
    from .errors import StackFileError

    vals = raw if isinstance(raw, list) else [raw]
    if (not 1 <= len(vals) <= 2 or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in vals)
            or not all(math.isfinite(v) for v in vals)):
        raise StackFileError(f"test.srs_tolerance_db: {raw!r} is invalid: decibels (6 = ±6 dB) or [below, above], "
                             "e.g. [-3, 6]")
    if len(vals) == 1 and vals[0] < 0:
        raise StackFileError(f"test.srs_tolerance_db: {raw!r} is invalid: decibels > 0 (6 = ±6 dB), or [below, above] "
                             "for a one-sided tolerance, e.g. [-3, 0]")
    lo, hi = (-abs(vals[0]), abs(vals[0])) if len(vals) == 1 else (float(vals[0]), float(vals[1]))
    if not (lo <= 0 <= hi and hi - lo > 0):
        raise StackFileError(f"test.srs_tolerance_db: {raw!r} is invalid: [below, above] with below <= 0 <= above")
    return (lo, hi)


def srs_criterion(t, a, spec: TestSpec) -> tuple[Criterion, str]:
    """The SRS of the record `(t, a)` (maximax absolute acceleration, Q = `spec.srs_q`) against the
    required SRS `spec.srs` (log-log between its rows, at 1/12 octave from its first to its last
    frequency): the criterion (value: the deviation in dB farthest from the allowed range's middle;
    margin: the smallest distance to a limit, dB) and a note naming the worst frequency."""
    import warnings

    from .spectrum import octave_frequencies, srs

    f_t, a_t = (np.array(c) for c in zip(*spec.srs))
    f = octave_frequencies(f_t[0], f_t[-1] * (1 + 1e-12), 12)
    f = f[(f >= f_t[0] * (1 - 1e-12)) & (f <= f_t[-1] * (1 + 1e-12))]
    f = np.unique(np.concatenate([f, f_t]))
    req = np.exp(np.interp(np.log(f), np.log(f_t), np.log(a_t)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        got = srs(np.asarray(t, dtype=float), np.asarray(a, dtype=float) / G0, f, Q=spec.srs_q,
                  on_coarse="ignore").maximax
    dev = 20.0 * np.log10(np.maximum(got, 1e-300) / req)
    if spec.srs_tolerance_db is None:
        k = int(np.argmax(np.abs(dev)))
        return (Criterion("SRS", "dB", float(dev[k]), 0.0, None, None, None, None),
                f"SRS: largest deviation {dev[k]:+.2f} dB at {f[k]:.5g} Hz (Q = {spec.srs_q:g})")
    lo, hi = spec.srs_tolerance_db
    margins = np.minimum(dev - lo, hi - dev)
    k = int(np.argmin(margins))
    return (Criterion("SRS", "dB", float(dev[k]), 0.0, float(lo), float(hi), float(margins[k]), bool(margins[k] >= 0)),
            f"SRS: worst point {dev[k]:+.2f} dB at {f[k]:.5g} Hz (Q = {spec.srs_q:g}, allowed [{lo:+g}, {hi:+g}] dB)")


def parse_test(raw, standard: str | None = None) -> TestSpec:
    """The `[test]` section of a stack file (a dict), with `standard` (the command line's `--standard`)
    taking the place of `test.standard`. A table row gives the nominal pulse and its tolerances; any
    key of the section overrides it; without a row, `shape`, `peak_g` and `duration` are needed.

    **Raises:** `StackFileError` (`test.KEY: ...`) or `ParameterError` (an unknown standard).
    """
    from .errors import StackFileError
    from .units import parse_quantity

    raw = dict(raw or {})
    unknown = sorted(set(raw) - set(TEST_KEYS))
    if unknown:
        raise StackFileError(f"test.{unknown[0]}: unknown key; allowed: {', '.join(TEST_KEYS)}")
    name = standard if standard is not None else raw.get("standard")
    over: dict = {}
    if "shape" in raw:
        if raw["shape"] not in SHAPES:
            raise StackFileError(f"test.shape: {raw['shape']!r} is invalid: one of {', '.join(SHAPES)}")
        over["shape"] = raw["shape"]
    if "peak_g" in raw:
        v = raw["peak_g"]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v > 0):
            raise StackFileError(f"test.peak_g: {v!r} is invalid: a plain number of g (standard gravity) > 0")
        over["peak_g"] = float(v)
    if "duration" in raw:
        d = parse_quantity(raw["duration"], "time", "test.duration")
        if not d > 0:
            raise StackFileError(f"test.duration: {raw['duration']!r} is invalid: a duration > 0, e.g. \"0.5 ms\"")
        over["duration"] = d
    for key in ("peak_tolerance", "duration_tolerance", "velocity_tolerance"):
        if key in raw:
            over[key] = _tolerance(raw[key], key)
    if "band" in raw:
        b = raw["band"]
        if isinstance(b, bool) or not isinstance(b, (int, float)) or not (0 < b < 1):
            raise StackFileError(f"test.band: {b!r} is invalid: the band's half-width as a fraction of the peak, "
                                 "in (0, 1), e.g. 0.2")
        over["band"] = float(b)
    if "duration_reference" in raw:
        ref = raw["duration_reference"]
        if ref not in DURATION_REFERENCES:
            raise StackFileError(f"test.duration_reference: {ref!r} is invalid; allowed: "
                                 f"{', '.join(DURATION_REFERENCES)} (the pulse's 10 % width against the nominal "
                                 "pulse's, or the width at 10 % of the specified peak against D)")
        over["duration_reference"] = ref
    if "band_window" in raw and "band" not in raw:
        raise StackFileError("test.band_window: used only with test.band (the band's half-width); give band, "
                             "e.g. 0.2, or leave band_window out")
    if "band_window" in raw:
        w = raw["band_window"]
        if (not isinstance(w, list) or len(w) != 2 or any(isinstance(v, bool) or not isinstance(v, (int, float))
                                                            or not (math.isfinite(v) and 0 <= v <= 100) for v in w)):
            raise StackFileError(f"test.band_window: {w!r} is invalid: [before, after], how long the band is judged "
                                 "before and after the nominal pulse in multiples of its duration D, each in "
                                 "[0, 100], e.g. [0.4, 0.4]")
        over["band_window"] = (float(w[0]), float(w[1]))
    if "fall_time" in raw:
        f = parse_quantity(raw["fall_time"], "time", "test.fall_time")
        if not f > 0:
            raise StackFileError(f"test.fall_time: {raw['fall_time']!r} is invalid: a duration > 0, e.g. \"0.1 ms\" "
                                 "(the terminal-peak sawtooth's fall allowance in the band)")
        over["fall_time"] = f
    if "srs" in raw:
        from .stackfile import parse_srs_table

        over["srs"] = parse_srs_table(raw["srs"], "test.srs")
    for key in ("srs_tolerance_db", "srs_q"):
        if key in raw and "srs" not in raw:
            raise StackFileError(f"test.{key}: used only with test.srs (the required SRS table)")
    if "srs_tolerance_db" in raw:
        over["srs_tolerance_db"] = _db_tolerance(raw["srs_tolerance_db"])
    if "srs_q" in raw:
        q = raw["srs_q"]
        if isinstance(q, bool) or not isinstance(q, (int, float)) or not (math.isfinite(q) and 0.5 < q <= 1000):
            raise StackFileError(f"test.srs_q: {q!r} is invalid: Q between 0.5 and 1000 (e.g. 10)")
        over["srs_q"] = float(q)
    if name is not None:
        if not isinstance(name, str):
            raise StackFileError(f"test.standard: {name!r} is invalid: a condition name, e.g. \"JESD22-B110 B\"")
        from .errors import ParameterError

        try:
            condition = find_condition(name)
        except ParameterError as exc:  # the key it came from: the file's test.standard or --standard
            key = "--standard" if standard is not None else "test.standard"
            raise StackFileError(f"{key}: {name!r} is invalid: {exc.allowed}") from None
        return TestSpec.from_condition(condition, **over)
    missing = [k for k in ("shape", "peak_g", "duration") if k not in over]
    if missing:
        raise StackFileError(f"test.{missing[0]}: missing; give test.standard (a condition of the table) or the "
                             "nominal pulse: shape, peak_g and duration")
    return TestSpec(name="user-defined", source="the stack file's [test] section", **over)


def read_test_file(path, standard: str | None = None, overrides=None) -> TestSpec:
    """The `TestSpec` of a stack file's `[test]` section (or of `standard` alone), after the `--set`
    `overrides` (`stackfile.apply_overrides`). Errors name the file."""
    import tomllib

    from .errors import StackFileError
    from .stackfile import apply_overrides

    try:
        doc = apply_overrides(tomllib.loads(Path(path).read_text(encoding="utf-8-sig")), overrides)
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise StackFileError(f"{path}: {exc}") from None
    if "test" not in doc and standard is None:
        raise StackFileError(f"{path}: test: missing; give a [test] section or --standard NAME "
                             "(hertz-chain check --standard list)")
    try:
        return parse_test(doc.get("test"), standard)
    except StackFileError as exc:
        key = str(exc).split(":", 1)[0]
        via = " (with --set)" if any(str(o).split("=", 1)[0].strip() == key for o in overrides or ()) else ""
        raise StackFileError(f"{path}: {exc}{via}") from None


MAX_RECORD = 2_000_000
"""The most samples `pulse_record` takes (16 MB of float64; a pulse 5,000 times shorter than its nominal
duration is sampled more coarsely than 400 per its own duration)."""


def pulse_record(report, spec: TestSpec, samples_per_duration: int = 400):
    """The top mass's accelerometer around its main pulse, uniformly sampled on the dense solution:
    `(t, a)` over the pulse's 10 % points widened by one nominal duration each side, or by the band's
    judged window (`band_window`, plus half a duration) where that is longer (inside the run),
    `samples_per_duration` samples per the shorter of the nominal duration and the pulse's own 10 %
    duration (a review: sampled by an 11 ms nominal alone, a 0.065 ms pulse's peak read 1.3 % low), at
    most `MAX_RECORD` samples."""
    from .analysis import accelerometer

    top = report.top_pulse
    if top is None:
        raise ParameterError("report", "no top pulse", "a run in which the top mass was struck")
    st = report.solution.steps.t
    before, after = (max(1.0, w + 0.5) for w in spec.band_window)  # (+ 0.5 D: the nominal pulse's shift)
    t0 = max(float(st[0]), top.t_start_10 - before * spec.duration)
    t1 = min(float(st[-1]), top.t_end_10 + (after + (spec.fall_time or 0.0) / spec.duration) * spec.duration)
    width = spec.duration
    if np.isfinite(top.duration_10) and top.duration_10 > 0:
        width = min(width, top.duration_10)
    n = min(max(int(samples_per_duration * (t1 - t0) / width), 200), MAX_RECORD)
    t = np.linspace(t0, t1, n + 1)
    return t, accelerometer(report, t)


def check(path, standard: str | None = None, overrides=None):
    """Simulate a stack file and check its top pulse against its `[test]` section or `standard`
    (`overrides`: `KEY=VALUE` strings, as the command line's `--set`).

    **Returns:** `(report, result)`: the `Report` of the run and the :class:`CheckResult` (which holds
    the checked record, `pulse_record`, in `t` and `a`).

    **Raises:** `StackFileError` / `ParameterError` for bad input (before anything is simulated).
    """
    from .stackfile import load_stack_file
    from .workflow import run_spec

    spec_file = load_stack_file(path, overrides)
    spec = read_test_file(path, standard, overrides)
    report = run_spec(spec_file)
    if report.top_pulse is None:
        raise ParameterError("stack", "no top pulse", "a run in which the top mass was struck")
    t, a = pulse_record(report, spec)
    return report, check_pulse(t, a, spec)
