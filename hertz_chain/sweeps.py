"""Parameter sweeps: `hertz-chain sweep FILE.toml --output OUT.zarr` and `sweep(path, output)`.

A stack file with `[sweep]` and `[[sweep.axis]]` tables (docs/sweeps.md) names the axes by the key
vocabulary of `hertz_chain.keys` (the same keys and indices as `[[optimize.vary]]`). The designs are
evaluated in chunks, each chunk one compiled, vmapped `simulate_batch(save_steps=False)` of the
differentiable design map (`hertz_chain._design.DesignMap`), locally or on a Dask cluster, and written
into an xarray Dataset in a Zarr store as they finish.

**Layout.** A grid sweep (`combine = "product"`, the default) has one dimension per axis, named by the
axis label (`contact.stiffness`, `stack.masses[2]`), with coordinates in SI; the work chunks are slabs
along the first axis (whole rows of the others), so each chunk is one rectangular region. Zipped axes
and sampled designs (`sample = "sobol"`, `"lhs"`, `"montecarlo"`) have one `design` dimension, the
sampled values as variables.

**Survives a kill.** A chunk's results are written first, then its marker: element `c` of the store's
`chunk_done` array (int8, one uncompressed one-byte Zarr chunk per element, so its file either holds the
byte 1 or is missing or empty). A run of the same command on an existing store computes only the chunks
without a marker (a chunk killed mid-write has none, and is written again whole), so nothing is lost or
done twice and the final store equals an uninterrupted run's. The store records the SHA-256 of the stack file's sweep-relevant content; a different file or
spec is refused in one line.

Variables (per design): `status` (`hertz_chain.status.Status` codes), `top_velocity_gain`,
`velocity_gains` (per mass), `rigid_gain` (paper Eq 19 with the nominal restitutions),
`rigid_gain_measured` (Eq 19 with the measured restitutions), `rigid_gain_event_driven` (the design's
event-driven rigid cascade with them, `rigid_events.simulate_rigid_batch`) and
`rigid_deficit` (`top_velocity_gain / rigid_gain - 1`; NaN where `rigid_gain` <= 0), `energy_error`, `num_steps`, `t_final`, and the
top pulse without a step history (`BatchSolution.peak_forces`, `impact_velocities`: running values kept
by the solver): `peak_force` per interface (N), `top_peak_g` (the top interface's peak force over the
top mass, in g: the accelerometer's peak), `top_delta_v` (the accelerometer's velocity change:
launch velocity minus the velocity just before the top's first contact, plus g times the time between, m/s), `top_equivalent_half_sine` (`π ΔV / (2 a_peak)`, s) and, with
`[sweep] durations = true`, `top_duration_10` and `top_rise_time` (`simulate_batch(pulse_durations=True)`),
and `restitution`
per interface (its first contact's separation over approach speed, paper Eq 2, read at the steps around
it in free flight: exact between two falling bodies, within g h of the step against the ground; NaN
without a finished contact). The peaks are the
largest values at the solver's accepted steps: low by O(h²) of the step (about 2e-4 relative at the
default tolerance; `hertz-chain simulate` of one design refines them).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from .constants import INDEPENDENT_BELOW
from .errors import StackFileError
from .keys import Slot, check_design_follows, check_values, quantity_of, read_bounds, read_entry, resolve, valid_values
from .stackfile import StackSpec, load_stack_file
from .units import parse_quantity

__all__ = ["SweepSpec", "AxisSpec", "SweepResult", "read_sweep_file", "check", "sweep", "recorded_rate", "COMBINE",
           "SAMPLES"]

COMBINE = ("product", "zip")
SAMPLES = ("sobol", "lhs", "montecarlo")
DISTRIBUTIONS = ("normal", "uniform")
_SWEEP_KEYS = ("combine", "sample", "samples", "seed", "chunk", "durations", "axis")
_AXIS_KEYS = ("key", "index", "values", "space", "start", "stop", "num", "bounds", "distribution", "std")
MAX_DESIGNS = 100_000_000
#: the sampled designs of a random sweep are drawn once per process when they are at most this many
#: numbers (256 MB); larger sets are drawn again for every chunk, so that memory stays bounded
SAMPLES_KEPT = 32_000_000
UNRUN = "not simulated (a sampled value outside what its key allows)"
"""`SweepResult.status_counts`' key for the designs a sample put outside a key's range (status `failed`,
no step)."""
VARIABLES = {  # name -> (units, long name)
    "status": ("1", "run status code (hertz_chain.status.Status: 0 complete, 1 with rebounds, 2-3 incomplete, "
               "4 no contact, 5 failed)"),
    "top_velocity_gain": ("1", "launch velocity of the top mass over the drop speed"),
    "velocity_gains": ("1", "launch velocity of each mass over the drop speed"),
    "rigid_gain": ("1", "rigid independent-collision gain, seed paper Eq 19, nominal restitutions (NaN where a law "
                   "has none: a speed-dependent raw damping, a plastic law)"),
    "rigid_deficit": ("1", "top_velocity_gain / rigid_gain - 1 (NaN where rigid_gain is not positive: Eq 19 "
                      "then leaves the top mass moving down, a design whose cascade the independent-collision "
                      "model does not describe)"),
    "rigid_gain_measured": ("1", "rigid independent-collision gain, seed paper Eq 19, with each interface's measured "
                            "restitution (NaN unless every interface has one)"),
    "rigid_gain_event_driven": ("1", "top launch velocity of the event-driven rigid cascade (the design's gaps, "
                                "velocities and gravity; each interface's measured restitution) over the drop speed "
                                "(NaN unless every interface has a restitution and the run gives a launch)"),
    "energy_error": ("1", "largest relative energy-audit error"),
    "num_steps": ("1", "solver steps"),
    "t_final": ("s", "end time of the run"),
    "peak_force": ("N", "largest contact force of the interface in the first cascade (at the solver's steps)"),
    "top_peak_g": ("1", "peak of the top mass's accelerometer (a + g), in units of standard gravity (9.80665 m s-2)"),
    "top_delta_v": ("m s-1", "velocity change of the top mass's accelerometer (a + g integrated): its launch velocity "
                    "minus its velocity before its first contact, plus g times the time between"),
    "top_equivalent_half_sine": ("s", "duration of the half-sine with the top pulse's peak and velocity change"),
    "top_duration_10": ("s", "duration of the top pulse between its 10 % points, at the solver's steps (NaN unless "
                        "[sweep] durations = true)"),
    "top_rise_time": ("s", "rise time of the top pulse from 10 % to 90 % of its peak, at the solver's steps (NaN unless "
                      "[sweep] durations = true)"),
    "restitution": ("1", "effective restitution of the interface's first contact: separation over approach speed"),
    "overlap_fraction": ("1", "largest fraction of the shorter first contact during which two neighbouring "
                         "interfaces are both closed (0: sequential; step-resolved)"),
    "regime": ("1", "0 independent (overlap_fraction < 0.01, the rigid theory's assumption), 1 overlapping"),
}
#: the extra dimension of a per-mass or per-interface variable
_EXTRA_DIM = {"velocity_gains": "mass", "peak_force": "interface", "restitution": "interface"}


@dataclasses.dataclass(frozen=True)
class AxisSpec:
    """One `[[sweep.axis]]`: its slots (one value shared by all the slots of the axis), its values (SI;
    grid axes), or its sampling (`bounds`, or `distribution` with `std` around the file's value)."""

    key: str
    index: Any
    values: tuple[float, ...] | None
    bounds: tuple[float, float] | None
    distribution: str | None
    std: float | None
    where: str

    @property
    def label(self) -> str:
        if self.index is None:
            return self.key
        idx = self.index if isinstance(self.index, list) else [self.index]
        return f"{self.key}[{','.join(str(i) for i in idx)}]"


@dataclasses.dataclass(frozen=True)
class SweepSpec:
    """`[sweep]`, validated (docs/sweeps.md)."""

    axes: tuple[AxisSpec, ...]
    combine: str = "product"
    sample: str | None = None
    samples: int = 0
    seed: int = 0
    #: designs per work chunk: 2048 ran 13-15 % faster than 1024 on the sweep benchmark's family (32,761
    #: designs, 2 cores, 2026-11-27): fewer chunks to set up and write, and the regime order
    #: (`simulation._regime_numbers`) sorts more designs at once into like pieces
    chunk: int = 2048
    durations: bool = False


def _err(key: str, problem: str) -> StackFileError:
    return StackFileError(f"{key}: {problem}")


def _parse_axis(item: Any, i: int, spec: StackSpec, sample: str | None) -> AxisSpec:
    where = f"sweep.axis[{i}]"
    read_entry(item, where, _AXIS_KEYS, "stack.gaps")
    key, index = item["key"], item.get("index")
    n = spec.n or 3
    resolve(key, index, n=n, ground=spec.has_ground, where=where)  # the key and its indices
    check_design_follows(spec, key, index, f"{where}.key")
    dim, p = quantity_of(spec, key, index, where)
    q = lambda raw, k: parse_quantity(raw, dim, f"{where}.{k}", exponent=p)  # noqa: E731
    # the keys of this kind of axis only (a key that does not apply would be silently ignored)
    if sample is None:
        mode, own = "a grid axis", ("values", "space", "start", "stop", "num")
    elif sample in ("sobol", "lhs"):
        mode, own = f"sample = '{sample}'", ("bounds",)
    elif item.get("distribution", "normal") == "normal":
        mode, own = "a normal Monte-Carlo axis", ("distribution", "std")
    else:
        mode, own = "a uniform Monte-Carlo axis", ("distribution", "bounds")
    for k in item:
        if k not in ("key", "index") + own:
            raise _err(f"{where}.{k}", f"not used by {mode}; its keys: key, index, {', '.join(own)}")
    values = bounds = distribution = std = None
    if sample is None:
        if "values" in item:
            if any(k in item for k in ("space", "start", "stop", "num")):
                raise _err(f"{where}.values", "give values, or space with start, stop and num, not both")
            raw = item["values"]
            if not isinstance(raw, list) or not raw:
                raise _err(f"{where}.values", f"{raw!r} is invalid: a non-empty list of values with units")
            values = tuple(q(v, "values") for v in raw)
            check_values(key, values, f"{where}.values", gravity=spec.drop.gravity)
            if len(set(values)) != len(values):
                raise _err(f"{where}.values", f"{raw!r} repeats a value; give each value once")
        else:
            for k in ("start", "stop", "num"):
                if k not in item:
                    raise _err(f"{where}.{k}", "missing; give values = [...], or space, start, stop and num")
            space = item.get("space", "linear")
            if space not in ("linear", "log"):
                raise _err(f"{where}.space", f"{space!r} is invalid; allowed: linear, log")
            num = item["num"]
            if isinstance(num, bool) or not isinstance(num, int) or not 1 <= num <= 10_000_000:
                raise _err(f"{where}.num", f"{num!r} is invalid: an integer from 1 to 10000000")
            a, b = q(item["start"], "start"), q(item["stop"], "stop")
            if num == 1 and a != b:
                raise _err(f"{where}.num", "1 takes start only; give num >= 2, or values = [start]")
            if num > 1 and a == b:
                raise _err(f"{where}.stop", f"{item['stop']!r} equals start; give a range, or values = [start]")
            if space == "log" and not (a > 0 and b > 0):
                raise _err(f"{where}.start", "a log axis needs start and stop > 0")
            values = tuple((np.geomspace(a, b, num) if space == "log" else np.linspace(a, b, num)).tolist())
            check_values(key, [a], f"{where}.start", gravity=spec.drop.gravity)
            check_values(key, [b], f"{where}.stop", gravity=spec.drop.gravity)
    elif sample in ("sobol", "lhs"):
        bounds = read_bounds(item.get("bounds"), dim, f"{where}.bounds", p)
        check_values(key, bounds, f"{where}.bounds", shown=repr(item["bounds"]), gravity=spec.drop.gravity)
    else:  # montecarlo
        distribution = item.get("distribution", "normal")
        if distribution not in DISTRIBUTIONS:
            raise _err(f"{where}.distribution", f"{distribution!r} is invalid; allowed: {', '.join(DISTRIBUTIONS)}")
        if distribution == "normal":
            if "std" not in item:
                raise _err(f"{where}.std", "missing; a normal tolerance needs its standard deviation (with units)")
            std = q(item["std"], "std")
            if not std > 0:
                raise _err(f"{where}.std", f"{item['std']!r} is invalid: must be > 0")
        else:
            bounds = read_bounds(item.get("bounds"), dim, f"{where}.bounds", p)
            check_values(key, bounds, f"{where}.bounds", shown=repr(item["bounds"]), gravity=spec.drop.gravity)
    return AxisSpec(key, index, values, bounds, distribution, std, where)


def parse_sweep(raw: Any, spec: StackSpec) -> SweepSpec:
    """Validate a `[sweep]` table against the stack file `spec`."""
    if not isinstance(raw, dict):
        raise _err("sweep", f"expected a table ([sweep]), got {raw!r}")
    for k in raw:
        if k not in _SWEEP_KEYS:
            raise _err(f"sweep.{k}", f"unknown key; allowed: {', '.join(_SWEEP_KEYS)}")
    out: dict[str, Any] = {}
    combine = raw.get("combine", "product")
    if combine not in COMBINE:
        raise _err("sweep.combine", f"{combine!r} is invalid; allowed: {', '.join(COMBINE)}")
    out["combine"] = combine
    sample = raw.get("sample")
    if sample is not None and sample not in SAMPLES:
        raise _err("sweep.sample", f"{sample!r} is invalid; allowed: {', '.join(SAMPLES)}")
    out["sample"] = sample
    for k, lo, hi in (("samples", 1, MAX_DESIGNS), ("seed", 0, 2**31 - 1), ("chunk", 1, 1_000_000)):
        if k in raw:
            v = raw[k]
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise _err(f"sweep.{k}", f"{v!r} is invalid: an integer from {lo} to {hi}")
            out[k] = v
    if "durations" in raw:
        if not isinstance(raw["durations"], bool):
            raise _err("sweep.durations", f"{raw['durations']!r} is invalid: true or false")
        out["durations"] = raw["durations"]
    if sample is not None and "combine" in raw:
        raise _err("sweep.combine", f"used only with grid axes; sample = '{sample}' draws its designs together")
    if sample is not None and "samples" not in out:
        raise _err("sweep.samples", f"missing; sample = '{sample}' needs the number of samples")
    if sample is None and "samples" in out:
        raise _err("sweep.samples", "used only with sample = 'sobol', 'lhs' or 'montecarlo'")
    axes = raw.get("axis")
    if not isinstance(axes, list) or not axes:
        raise _err("sweep.axis", "missing; give at least one [[sweep.axis]] with a key")
    parsed = tuple(_parse_axis(a, i, spec, sample) for i, a in enumerate(axes))
    labels = [a.label for a in parsed]
    if len(set(labels)) != len(labels):
        raise _err("sweep.axis", f"an axis is given twice ({labels})")
    if sample is None and combine == "zip" and len({len(a.values) for a in parsed}) > 1:
        raise _err("sweep.combine", "zipped axes need the same number of values: "
                   + ", ".join(f"{a.label}: {len(a.values)}" for a in parsed))
    out["axes"] = parsed
    spec_ = SweepSpec(**out)
    if _count(spec_) > MAX_DESIGNS:
        raise _err("sweep.axis", f"{_count(spec_)} designs; at most {MAX_DESIGNS}")
    return spec_


def _count(s: SweepSpec) -> int:
    if s.sample is not None:
        return s.samples
    if s.combine == "zip":
        return len(s.axes[0].values)
    return math.prod(len(a.values) for a in s.axes)


def read_sweep_file(path: str | Path) -> tuple[StackSpec, SweepSpec, str]:
    """`(spec, sweep, text)` of a stack file with a `[sweep]` section. Raises `StackFileError`."""
    import tomllib

    spec = load_stack_file(path)
    text = Path(path).read_text(encoding="utf-8-sig")
    doc = tomllib.loads(text)
    if "sweep" not in doc:
        raise StackFileError(f"{path}: sweep: missing; give a [sweep] section with [[sweep.axis]] (docs/sweeps.md)")
    if spec.stack.masses is None and spec.n is None:
        raise StackFileError(f"{path}: stack.design: an 'optimal' design leaves n open; a sweep needs a fixed n")
    try:
        return spec, parse_sweep(doc["sweep"], spec), text
    except StackFileError as exc:
        raise StackFileError(f"{path}: {exc}") from None


# ------------------------------------------------------------------------------------------ the plan
@dataclasses.dataclass
class _Plan:
    """The designs of a sweep: the slots of every axis, the grid shape (or one `design` dimension),
    the chunks and how to produce the values of a chunk without holding them all."""

    spec: StackSpec
    sweep: SweepSpec
    slots: tuple[tuple[Slot, ...], ...]  # per axis
    shape: tuple[int, ...]
    dims: tuple[str, ...]
    chunk_rows: int  # along the first dimension
    base: np.ndarray  # the file's value of every axis
    _drawn: list = dataclasses.field(default_factory=list, repr=False, compare=False)  # `_samples`, kept

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    @property
    def row(self) -> int:
        return math.prod(self.shape[1:])

    @property
    def n_chunks(self) -> int:
        return -(-self.shape[0] // self.chunk_rows)

    def region(self, c: int) -> slice:
        return slice(c * self.chunk_rows, min((c + 1) * self.chunk_rows, self.shape[0]))

    def values(self, c: int) -> np.ndarray:
        """`(designs, axes)` SI values of chunk `c`, in the store's C order."""
        r = self.region(c)
        s = self.sweep
        if s.sample is None and s.combine == "product":
            idx = np.indices((r.stop - r.start,) + self.shape[1:]).reshape(len(self.shape), -1).T
            idx[:, 0] += r.start
            return np.column_stack([np.asarray(a.values)[idx[:, k]] for k, a in enumerate(s.axes)])
        if s.sample is None:
            return np.column_stack([np.asarray(a.values)[r] for a in s.axes])
        if self._drawn:
            return self._drawn[0][r]
        U = self._samples()
        if U.size <= SAMPLES_KEPT:  # drawn once per process (redrawing all of them for every chunk cost
            self._drawn.append(U)   # 0.1-0.14 s per chunk at 10^6 samples)
        return U[r]

    def _samples(self) -> np.ndarray:
        """Every sampled design `(samples, axes)`, drawn from the seed (the same on every call)."""
        from scipy.stats import qmc

        s = self.sweep
        d = len(s.axes)
        if s.sample == "sobol":
            import warnings

            with warnings.catch_warnings():  # a count that is not a power of 2 is allowed (docs/sweeps.md)
                warnings.simplefilter("ignore", UserWarning)
                U = qmc.Sobol(d, scramble=True, seed=s.seed).random(s.samples)
        elif s.sample == "lhs":
            U = qmc.LatinHypercube(d, seed=s.seed).random(s.samples)
        else:
            rng = np.random.default_rng(s.seed)
            out = np.empty((s.samples, d))
            for k, a in enumerate(s.axes):
                if a.distribution == "normal":
                    out[:, k] = self.base[k] + a.std * rng.standard_normal(s.samples)
                else:
                    out[:, k] = rng.uniform(*a.bounds, s.samples)
            return out
        lo = np.array([a.bounds[0] for a in s.axes])
        hi = np.array([a.bounds[1] for a in s.axes])
        return lo + U * (hi - lo)


def _plan(spec: StackSpec, sweep: SweepSpec, n: int) -> _Plan:
    slots = tuple(resolve(a.key, a.index, n=n, ground=spec.has_ground, where=a.where) for a in sweep.axes)
    seen: dict = {}
    for a, axis in zip(sweep.axes, slots):
        for sl in axis:
            if sl in seen:
                raise _err(f"{a.where}.index", f"{sl.label} is set by {seen[sl]} too; give the axes disjoint indices")
            seen[sl] = a.where
    if sweep.sample is None and sweep.combine == "product":
        shape = tuple(len(a.values) for a in sweep.axes)
        dims = tuple(a.label for a in sweep.axes)
    else:
        shape, dims = (_count(sweep),), ("design",)
    row = math.prod(shape[1:])
    rows = max(1, sweep.chunk // max(row, 1))
    return _Plan(spec, sweep, slots, shape, dims, rows, np.zeros(len(sweep.axes)))


# ------------------------------------------------------------------------------------------ evaluation
_CACHE: dict[str, Any] = {}


def _design_map(text: str, source: str | None):
    """The design map and slot layout of a sweep file, built once per process (workers reuse it)."""
    import tomllib

    import jax

    from ._design import DesignMap, with_masses
    from .builder import design_masses
    from .stackfile import parse_stack

    key = hashlib.sha256(text.encode()).hexdigest()
    if key not in _CACHE:
        doc = tomllib.loads(text)
        spec = parse_stack(doc, source=source)
        sw = parse_sweep(doc["sweep"], spec)
        spec = with_masses(spec, design_masses(spec))
        plan = _plan(spec, sw, spec.n)
        flat = tuple(s for axis in plan.slots for s in axis)
        dm = DesignMap(spec, flat, section="sweep.axis")
        base = dm.values()
        pos, k = [], 0
        for axis in plan.slots:
            pos.append(k)
            k += len(axis)
        plan.base = base[pos]
        _CACHE[key] = (plan, dm, [len(a) for a in plan.slots])
        _CACHE[key + "jit"] = (jax.jit(jax.vmap(dm)), jax.jit(jax.vmap(dm.fields)))
    return _CACHE[key]


def _evaluate(text: str, source: str | None, c: int, rows: int | None = None) -> dict:
    """The results of chunk `c` (numpy arrays, one entry per design of the chunk); `rows`: the store's chunk
    size along the first dimension, where it differs from the file's (`_store_layout`)."""
    from .rigid import as_rigid_restitution, stack_gain
    from .simulation import simulate_batch

    plan, dm, widths = _design_map(text, source)
    plan = _with_rows(plan, rows)
    designs, fields_of = _CACHE[hashlib.sha256(text.encode()).hexdigest() + "jit"]  # compiled once per process
    V = plan.values(c)
    # a sampled value outside what its key allows (a Monte-Carlo tail: a negative gap or mass) is not
    # simulated: its design is reported failed (grid values and bounds were checked before the run)
    valid = np.all([valid_values(a.key, V[:, k], dm.gravity) for k, a in enumerate(plan.sweep.axes)], axis=0)
    X = np.repeat(np.where(valid[:, None], V, plan.base[None, :]), widths, axis=1)  # an axis sets its slots
    B = X.shape[0]
    size = plan.chunk_rows * plan.row  # pad to the full chunk: one compiled shape for every chunk
    if B < size:
        X = np.vstack([X, np.repeat(X[-1:], size - B, axis=0)])
    stacks, states = designs(X)
    opts = {k: v for k, v in dm.built.simulate_options.items() if k in ("solver", "tolerances", "t_max", "until")}
    sol = simulate_batch(stacks, states, save_steps=False, max_steps=dm.built.simulate_options.get("max_steps", 16_384),
                         pulse_durations=plan.sweep.durations, _pieces=True, **opts)
    fields = fields_of(X)
    speed = np.asarray(fields["drop.impact_velocity"]) if not dm.chain else \
        np.full(len(X), dm.drop_speed(None))
    gains = sol.launch_velocities / speed[:, None]
    masses = np.asarray(fields["stack.masses"])
    e = np.asarray(fields["contact.restitution"])
    # paper Eq 19 with the nominal restitutions (elastic laws: 1); NaN where a law has none (a raw damping whose e
    # depends on the speed, a plastic law)
    rigid = np.full(len(X), np.nan)
    nominal = np.all(np.isfinite(e[:, 0 if dm.ground else 1 :]), axis=1) & dm.ground
    if np.any(nominal):
        rigid[nominal] = stack_gain(masses[nominal], e[nominal])
    rigid_measured = np.full(len(X), np.nan)
    e_meas = np.asarray(sol.restitutions, dtype=float)
    e_rig = as_rigid_restitution(e_meas)  # an elastic contact's 1 + round-off is 1; the ground's may exceed 1
    # as the report: a pair measured above 1 (a contact its neighbour pushes apart) has no rigid gain
    rigid_ok = np.all(np.isfinite(e_rig[:, 0 if dm.ground else 1:]), axis=1) & np.all(e_rig[:, 1:] <= 1.0, axis=1)
    have = rigid_ok & dm.ground
    if np.any(have):
        rigid_measured[have] = stack_gain(masses[have], e_rig[have])
    rigid_event = _event_driven_gains(masses, states, stacks, e_rig, rigid_ok, dm.ground, speed)
    from .constants import G0

    # the top mass has one contact: the interface below it; a top never struck has no pulse (NaN, as the
    # report's `top_pulse` is None; a review: 0 g, and regime "independent", for a run stopped by t_max)
    struck = np.isfinite(sol.first_contacts[:, -1, 0])
    peak_a = np.where(struck, sol.peak_forces[:, -1] / masses[:, -1], np.nan)
    # the accelerometer's velocity change (a + g integrated, as the report's pulse): the top's velocity
    # change plus g times the time from its first contact to its launch (its first point in contact is
    # within one onset step, ~1e-7 of the contact time, of the onset)
    g = np.broadcast_to(np.asarray(stacks.gravity, dtype=float), (len(X),))
    dv = (sol.launch_velocities[:, -1] - sol.impact_velocities[:, -1]
          + g * (sol.launch_times[:, -1] - sol.first_contacts[:, -1, 0]))
    with np.errstate(divide="ignore", invalid="ignore"):
        eq_hs = np.where(peak_a > 0, np.pi * dv / (2.0 * peak_a), np.nan)
    overlap = overlap_fractions(sol.first_contacts, sol.t_final, dm.ground)
    out = {"status": sol.status_code.astype(np.int8), "top_velocity_gain": gains[:, -1], "velocity_gains": gains,
           "rigid_gain": rigid, "rigid_deficit": rigid_deficit(gains[:, -1], rigid), "rigid_gain_measured": rigid_measured,
           "rigid_gain_event_driven": rigid_event, "energy_error": sol.energy_error,
           "num_steps": sol.num_steps.astype(np.int64), "t_final": sol.t_final,
           "peak_force": sol.peak_forces, "top_peak_g": peak_a / G0, "top_delta_v": dv, "top_equivalent_half_sine": eq_hs,
           "top_duration_10": sol.top_duration_10 if plan.sweep.durations else np.full(len(X), np.nan),
           "top_rise_time": sol.top_rise_time if plan.sweep.durations else np.full(len(X), np.nan),
           "restitution": sol.restitutions, "overlap_fraction": overlap,
           "regime": np.where(struck, overlap >= INDEPENDENT_BELOW, -1).astype(np.int8)}
    if plan.dims == ("design",):
        out["values"] = V
    out = {k: np.asarray(v)[:B] for k, v in out.items()}
    if not np.all(valid):
        from .status import Status

        out["status"] = np.where(valid, out["status"], np.int8(Status.FAILED)).astype(np.int8)
        for k in ("top_velocity_gain", "velocity_gains", "rigid_gain", "rigid_deficit", "rigid_gain_measured",
                  "rigid_gain_event_driven", "energy_error", "t_final",
                  "peak_force", "top_peak_g", "top_delta_v", "top_equivalent_half_sine", "top_duration_10", "top_rise_time",
                  "restitution", "overlap_fraction"):
            out[k] = np.where(valid.reshape((-1,) + (1,) * (out[k].ndim - 1)), out[k], np.nan)
        out["num_steps"] = np.where(valid, out["num_steps"], 0)
        out["regime"] = np.where(valid, out["regime"], -1).astype(np.int8)
    return out


#: impacts after which a design's event-driven rigid run stops (the report's allows 100,000; run until
#: the top's launch is final, five-mass stacks took at most 363, and a batch iteration costs ~0.2 ms)
RIGID_MAX_IMPACTS = 1000


def _event_driven_gains(masses, states, stacks, e_rig, have, ground: bool, speed) -> np.ndarray:
    """The event-driven rigid cascade of the designs `have` (`rigid_events.simulate_rigid_batch`) as the
    report's rigid comparison runs it (`analysis`): the design's initial gaps (overlaps clipped to
    touching), velocities and gravity, each interface's measured restitution `e_rig`
    (`rigid.as_rigid_restitution`); the top's launch over `speed`, NaN elsewhere and where the run gives no
    launch."""
    from .rigid_events import simulate_rigid_batch

    B, n = masses.shape
    out = np.full(B, np.nan)
    if not np.any(have):
        return out
    x0 = np.asarray(states.positions, dtype=float)[have]
    v0 = np.asarray(states.velocities, dtype=float)[have]
    gaps = np.maximum(np.concatenate([x0[:, :1], np.diff(x0, axis=1)], axis=1), 0.0)
    e = np.where(np.isfinite(e_rig[have]), e_rig[have], 1.0)
    g = np.broadcast_to(np.asarray(stacks.gravity, dtype=float), (B,))[have]
    res = simulate_rigid_batch(masses[have], v0, gaps, e, e[:, 0] if ground else None, g,
                               max_collisions=RIGID_MAX_IMPACTS, until="top_launch")
    out[have] = res.top_launch_velocities / speed[have]
    return out


# ------------------------------------------------------------------------------------------ the store
def _fingerprint(text: str) -> str:
    """The sweep's identity: a hash of the parsed stack file (its keys and values; comments, blank lines and
    the order of tables do not change it). A store made before the nineteenth session (2026-11-27) holds the hash of the raw text,
    which `_check_store` accepts too."""
    import tomllib

    try:
        canonical = json.dumps(tomllib.loads(text), sort_keys=True, default=str)
    except tomllib.TOMLDecodeError:
        canonical = text
    return hashlib.sha256(canonical.encode()).hexdigest()


def _create_store(path: Path, plan: _Plan, text: str, source: str | None) -> None:
    """The store's layout, coordinates and attributes (no results yet)."""
    import datetime
    import tomllib

    import xarray as xr

    from . import __version__

    n = plan.spec.n
    dims = plan.dims
    shape = plan.shape
    chunks = (plan.chunk_rows,) + shape[1:]
    data = {}
    for name, (units, long_name) in VARIABLES.items():
        extra = (_EXTRA_DIM[name],) if name in _EXTRA_DIM else ()
        shp = shape + ((n,) if extra else ())
        dtype = np.int8 if name in ("status", "regime") else (np.int64 if name == "num_steps" else np.float64)
        fill = -1 if dtype is not np.float64 else np.nan
        import dask.array as da

        data[name] = xr.Variable(dims + extra, da.full(shp, fill, dtype=dtype, chunks=chunks + ((n,) if extra else ())),
                                 attrs={"units": units, "long_name": long_name})
    coords = {}
    if dims != ("design",):
        for a in plan.sweep.axes:
            coords[a.label] = xr.Variable((a.label,), np.asarray(a.values),
                                          attrs={"units": _units(plan.spec, a), "long_name": f"stack-file key {a.label}"})
    else:
        import dask.array as da

        for a in plan.sweep.axes:
            data[a.label] = xr.Variable(("design",), da.full(shape, np.nan, chunks=chunks),
                                        attrs={"units": _units(plan.spec, a), "long_name":
                                               f"{'sampled' if plan.sweep.sample else 'swept (zipped)'} {a.label}"})
    coords["mass"] = xr.Variable(("mass",), np.arange(1, n + 1), attrs={"long_name": "mass number, 1 = bottom"})
    coords["interface"] = xr.Variable(("interface",), np.arange(n),
                                      attrs={"long_name": "interface number: 0 = ground-mass 1, j = mass j-mass j+1"})
    from .status import Status

    data["status"].attrs.update(flag_values=np.array([-1] + [int(x) for x in Status], np.int8),
                                flag_meanings=" ".join(["not_run"] + [x.text.replace(":", "").replace(" ", "_")
                                                                      for x in Status]))
    data["regime"].attrs.update(flag_values=np.array([-1, 0, 1], np.int8),
                                flag_meanings="undetermined independent overlapping")
    data["chunk_done"] = xr.Variable(("chunk",), np.zeros(plan.n_chunks, np.int8),
                                     attrs={"units": "1", "long_name": "1 where the work chunk's results are written"})
    import importlib.metadata as md

    versions = {p: md.version(p) for p in ("jax", "diffrax", "equinox", "numpy", "scipy", "xarray", "zarr")}
    ds = xr.Dataset(data, coords=coords, attrs={
        "title": "hertz_chain sweep", "Conventions": "CF-1.10", "source": f"hertz_chain {__version__}",
        "history": f"{datetime.datetime.now(datetime.timezone.utc).isoformat()} hertz-chain sweep {source or ''}",
        "stack_file": text, "stack_file_sha256": _fingerprint(text), "versions": json.dumps(versions),
        "stack_title": str(tomllib.loads(text).get("title", "")),
        "chunk_rows": plan.chunk_rows, "n_chunks": plan.n_chunks})
    # fill values: what a design not computed yet reads (-1 for the integers, NaN for the floats; Zarr's
    # default 0 read as status "complete" and regime "independent" in a store still being written)
    encoding = {name: {"fill_value": -1} for name, v in data.items() if v.dtype.kind == "i" and name != "chunk_done"}
    encoding["chunk_done"] = {"chunks": (1,), "compressors": None, "fill_value": 0}
    ds.to_zarr(path, mode="w-", compute=False, consolidated=False, encoding=encoding)


#: CF / UDUNITS spellings of the stack files' SI units
_CF_UNITS = {"dimensionless": "1", "mass": "kg", "length": "m", "time": "s", "velocity": "m s-1",
             "acceleration": "m s-2", "hertz_stiffness": "N m-1.5", "linear_stiffness": "N m-1", "force": "N"}


def _units(spec: StackSpec, a: AxisSpec) -> str:
    dim, p = quantity_of(spec, a.key, a.index)
    return f"N m-{p:g}" if dim == "power_stiffness" else _CF_UNITS.get(dim, "1")


def _write_chunk(path: Path, plan: _Plan, c: int, res: dict) -> None:
    """Write chunk `c`'s results into its region, then its marker (atomically)."""
    r = plan.region(c)
    shape = (r.stop - r.start,) + plan.shape[1:]
    data = {name: res[name].reshape(shape + res[name].shape[1:]) for name in VARIABLES}
    if plan.dims == ("design",):
        for k, a in enumerate(plan.sweep.axes):
            data[a.label] = res["values"][:, k]
    # straight into the arrays that `_create_store` made through xarray (same dtypes; NaN and -1 as its
    # fill values): xarray's region writes re-read and checked the store's layout at every chunk, ~2x
    # the time of the writes themselves
    import zarr

    group = zarr.open_group(str(path), mode="r+")
    names = list(data)
    half = len(names) // 2
    for i, name in enumerate(names):
        if i == half:
            _fault("mid-data", c)
        arr = group[name]
        arr[r.start : r.stop] = np.asarray(data[name], dtype=arr.dtype)
    _fault("after-data", c)
    group["chunk_done"][c] = 1


def _fault(where: str, c: int) -> None:
    """Fault injection for the kill tests: `HERTZ_CHAIN_SWEEP_FAULT="after-data:3"` kills this process
    (SIGKILL) after chunk 3's results are written and before its marker; `"mid-data:3"` halfway through
    writing them; `"creating:0"` when the new store is laid out and not yet renamed to its name."""
    want = os.environ.get("HERTZ_CHAIN_SWEEP_FAULT", "")
    if want == f"{where}:{c}":
        import signal

        os.kill(os.getpid(), signal.SIGKILL)


def _done(path: Path) -> set[int]:
    """The chunks whose marker is written: the one-byte chunk files of `chunk_done` that hold 1 (Zarr v3's
    default chunk-key encoding, `chunk_done/c/<i>`; a missing or empty file is not done)."""
    folder = path / "chunk_done" / "c"
    if not folder.is_dir():
        return set()
    out = set()
    for entry in os.scandir(folder):
        if entry.name.isdigit():
            try:
                if Path(entry.path).read_bytes() == b"\x01":
                    out.add(int(entry.name))
            except OSError:
                pass
    return out


# ------------------------------------------------------------------------------------------ entry point
@dataclasses.dataclass(frozen=True)
class SweepResult:
    """What `sweep` did: the store, the number of designs and chunks, how many chunks were computed in
    this run (`computed`) and were already done (`skipped`), and the status counts of the whole store."""

    path: Path
    designs: int
    chunks: int
    computed: int
    skipped: int
    seconds: float
    status_counts: dict

    def dataset(self):
        """The store as a lazily loaded `xarray.Dataset` (`xarray.open_zarr(path, consolidated=False)`:
        the store keeps no consolidated metadata, since chunks are written as they finish, so plain
        `open_zarr` warns and then reads it the same way)."""
        import xarray as xr

        return xr.open_zarr(self.path, consolidated=False)

    def to_dict(self) -> dict:
        return {"output": str(self.path), "designs": self.designs, "chunks": self.chunks, "computed": self.computed,
                "skipped": self.skipped, "seconds": self.seconds,
                "designs_per_second": (self.designs * self.computed / max(self.chunks, 1) / max(self.seconds, 1e-9)
                                       if self.computed else None),
                "status_counts": self.status_counts}


def check(path: str | Path, output: str | Path) -> tuple[_Plan, str]:
    """Every check before a sweep runs: the file, the spec, and the output (a new store, or one written
    by this same sweep). Returns the plan and the file text. Raises `StackFileError` or
    `errors.OutputPathError` (one line)."""
    from .errors import OutputPathError

    spec, sw, text = read_sweep_file(path)
    try:
        plan = _design_map(text, str(path))[0]  # every check of the axes against the file, before any store
    except StackFileError as exc:
        raise StackFileError(f"{path}: {exc}") from None
    out = Path(output)
    if out.suffix != ".zarr":
        raise OutputPathError("output", out, "a sweep store is a folder ending in .zarr")
    try:
        exists = out.exists()
    except OSError:  # a name too long for the file system: `check_output_path` says so
        exists = False
    if exists:
        _check_store(out, text)
        plan = _with_rows(plan, _store_layout(out))
    else:  # the folder exists and is writable, the name fits (the store is made beside it, then renamed)
        from ._paths import check_output_path

        check_output_path(out, "output", (".zarr",), force=False)
    return plan, text


def _with_rows(plan: _Plan, rows: int | None) -> _Plan:
    """`plan` with chunks of `rows` along its first dimension (None: as it is)."""
    return plan if rows is None or rows == plan.chunk_rows else dataclasses.replace(plan, chunk_rows=int(rows))


def _store_layout(out: Path) -> int | None:
    """The chunk size (along the first dimension) that a store was laid out with: resuming keeps it, also
    where the default `chunk` changed since (1024 -> 2048 on 2026-11-27), which is no change to the
    file. None if the store does not say."""
    import zarr

    try:
        group = zarr.open_group(str(out), mode="r")
        rows = group.attrs.get("chunk_rows")  # written with the store (an array's own chunks are clipped to
        # its length where one chunk holds it all)
        return int(rows) if rows is not None else int(group["status"].chunks[0])
    except Exception:  # noqa: BLE001
        return None


def _check_store(out: Path, text: str) -> None:
    """`OutputPathError` unless `out` is a whole sweep store of this stack file (`_fingerprint`)."""
    from .errors import OutputPathError

    attrs = {}
    if (out / "chunk_done").is_dir():
        import zarr

        try:
            attrs = dict(zarr.open_group(str(out), mode="r").attrs)
        except Exception:  # noqa: BLE001  (any unreadable layout: not a store of ours)
            attrs = {}
    if attrs.get("title") != "hertz_chain sweep" or not all((out / v).is_dir() for v in ("status", "regime")):
        raise OutputPathError("output", out, "exists and is not a hertz_chain sweep store; choose a new name")
    if attrs.get("stack_file_sha256") not in (_fingerprint(text), hashlib.sha256(text.encode()).hexdigest()):
        raise OutputPathError("output", out, "written by a different stack file or sweep spec; resume it "
                              "with the same file, or choose a new name")


# ------------------------------------------------------------------------------------------ time estimates
def _rate_key(plan: _Plan, workers: int | None, scheduler: str | None) -> str:
    """What a sweep's designs per second depend on, as one string: the machine's JAX backend and device
    count (or the Dask workers), the number of masses, the laws and the ground, and the chunk size."""
    import jax

    from . import _config  # noqa: F401  (every CPU core a device: before JAX starts, as the sweep would)

    spec = plan.spec
    n = spec.n or 0
    laws = sorted({spec.contact_for(j).law for j in range(0 if spec.has_ground else 1, n)})
    where = (f"dask:{scheduler}" if scheduler else f"workers:{workers}" if workers
             else f"{jax.default_backend()}:{jax.local_device_count()}")
    return (f"{where}|n={n}|{','.join(laws)}|ground={spec.has_ground}|chunk={plan.chunk_rows * plan.row}"
            + ("|durations" if plan.sweep.durations else ""))


def _rates_path() -> Path | None:
    from ._cache import cache_dir

    root = cache_dir("sweeps")
    return None if root is None else Path(root) / "rates.json"


def recorded_rate(plan: _Plan, workers: int | None = None, scheduler: str | None = None) -> float | None:
    """Designs per second of the last sweep of the same structure on this machine (`_rate_key`), from
    the cache (`hertz_chain._cache`, ``sweeps/rates.json``), or None if there is none."""
    p = _rates_path()
    try:
        rate = json.loads(p.read_text()).get(_rate_key(plan, workers, scheduler)) if p is not None else None
        return float(rate["designs_per_s"]) if rate else None
    except (OSError, ValueError, TypeError, KeyError):
        return None


def _record_rate(plan: _Plan, workers, scheduler, designs_per_s: float) -> None:
    """Keep the steady rate of this run (chunks after the first, which compiles) for the next estimate;
    silently nothing when the cache is off or not writable."""
    p = _rates_path()
    if p is None or not math.isfinite(designs_per_s) or designs_per_s <= 0:
        return
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        try:
            rates = json.loads(p.read_text())
        except (OSError, ValueError):
            rates = {}
        rates[_rate_key(plan, workers, scheduler)] = {"designs_per_s": designs_per_s,
                                                      "date": time.strftime("%Y-%m-%d")}
        tmp = p.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(rates, indent=1))
        os.replace(tmp, p)
    except OSError:
        pass


def sweep(path: str | Path, output: str | Path, *, workers: int | None = None, scheduler: str | None = None,
          progress: bool = False, on_chunk=None) -> SweepResult:
    """Run the sweep of the stack file `path` into the Zarr store `output` (module docstring).

    **Arguments:** `workers`: run the chunks on a local Dask cluster of that many worker processes;
    `scheduler`: the address of an existing Dask scheduler (`tcp://host:port`); neither: in this process,
    every CPU core a JAX device (`simulate_batch` solves each chunk in pieces of `simulation.CPU_PIECE`
    designs, a thread per core taking the next piece; docs/sweeps.md, "Scale"). `progress`: a rich
    progress bar on stderr. `on_chunk(done, todo, seconds)`: called after every chunk written in this
    run (the command line prints a time estimate from the first).

    **Returns** a `SweepResult`. An existing store of the same sweep is resumed: only chunks without a
    marker run. **Raises** `StackFileError`/`OutputPathError` before anything runs.
    """
    from .errors import ParameterError

    t0 = time.perf_counter()
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, (int, np.integer))
                                or not 1 <= workers <= 1024):
        raise ParameterError("workers", workers, "a number of worker processes from 1 to 1024 (or None: this process)")
    if workers is not None and scheduler is not None:
        raise ParameterError("workers", workers, "None with a scheduler: give workers or scheduler, not both")
    if scheduler is not None and (not isinstance(scheduler, str) or "://" not in scheduler):
        raise ParameterError("scheduler", scheduler, "a Dask scheduler address such as tcp://host:8786")
    path, output = Path(path), Path(output)
    plan, text = check(path, output)
    client = _dask_client(workers, scheduler) if workers is not None or scheduler is not None else None
    try:
        return _sweep(path, output, plan, text, client, workers, scheduler, progress, on_chunk, t0)
    finally:
        if client is not None:
            cluster = client.cluster if workers is not None else None
            client.close()
            if cluster is not None:
                cluster.close()


#: how long `sweep` waits for a Dask scheduler to answer before refusing its address
SCHEDULER_TIMEOUT = "10s"


def _dask_client(workers, scheduler):
    """A Dask client: of a new local cluster of `workers` single-device processes, or connected to the
    scheduler at `scheduler` (`ParameterError` naming it where none answers; before any store is made)."""
    from distributed import Client, LocalCluster

    from .errors import ParameterError

    if scheduler is not None:
        try:
            return Client(scheduler, timeout=SCHEDULER_TIMEOUT)
        except (OSError, TimeoutError) as exc:
            raise ParameterError("scheduler", scheduler, f"a running Dask scheduler's address (none answered: "
                                 f"{str(exc).splitlines()[0][:120]})") from None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                           env={"HERTZ_CHAIN_CPU_DEVICES": "1"})
    return Client(cluster)


def _make_store(output: Path, plan: _Plan, text: str, source: str) -> None:
    """Create the store whole or not at all: laid out in a hidden folder beside `output`, then renamed
    to it (a kill while it is made leaves no half store under the user's name; the hidden folders of runs
    no longer alive are removed). Where another run made `output` first, its store is used if it is a
    store of this sweep (`_check_store`)."""
    import shutil

    prefix = f".{output.name}.creating-"
    for old in output.parent.glob(prefix + "*"):
        try:
            os.kill(int(old.name[len(prefix):].split("-")[0]), 0)
        except ProcessLookupError:
            shutil.rmtree(old, ignore_errors=True)
        except (ValueError, OSError):
            pass
    tmp = output.with_name(f"{prefix}{os.getpid()}-{os.urandom(4).hex()}")
    try:
        _create_store(tmp, plan, text, source)
        _fault("creating", 0)
        try:
            os.rename(tmp, output)
        except OSError:
            if not output.exists():
                raise
            _check_store(output, text)  # made by another run meanwhile
    except OSError as exc:
        from .errors import OutputPathError

        raise OutputPathError("output", output, f"cannot create the store ({exc.strerror or exc})") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _sweep(path, output, plan, text, client, workers, scheduler, progress, on_chunk, t0) -> SweepResult:
    if not output.exists():
        _make_store(output, plan, text, str(path))
    done = _done(output)
    todo = [c for c in range(plan.n_chunks) if c not in done]
    counts: dict[int, int] = {}
    bar = _progress(progress, plan, todo)

    written, steady = [0], {}  # steady: the time and designs after the first chunk written (which compiles)

    def finish(c, res):
        _write_chunk(output, plan, c, res)
        written[0] += 1
        now = time.perf_counter()
        if written[0] == 1:
            steady.update(t=now, designs=0)
        else:
            steady["designs"] += len(res["status"])
        if on_chunk is not None:
            on_chunk(written[0], len(todo), now - t0)
        for code, k in zip(*np.unique(res["status"], return_counts=True)):
            counts[int(code)] = counts.get(int(code), 0) + int(k)
        if bar is not None:
            bar[0].advance(bar[1], plan.region(c).stop * plan.row - plan.region(c).start * plan.row)

    try:
        if client is None:
            for c in todo:
                finish(c, _evaluate(text, str(path), c, plan.chunk_rows))
        else:
            _run_dask(text, str(path), todo, finish, client, plan.chunk_rows)
    finally:
        if bar is not None:
            bar[0].stop()
    if steady.get("designs"):
        _record_rate(plan, workers, scheduler, steady["designs"] / (time.perf_counter() - steady["t"]))
    import zarr

    from .status import Status

    status = np.asarray(zarr.open_array(str(output / "status"), mode="r")[...]).ravel()
    # a design whose sampled value lies outside what its key allows is not simulated (`_evaluate`): failed
    # with no step; counted apart (a review: a Monte-Carlo tail read as 23 solver failures)
    unrun = (status == int(Status.FAILED)) & (
        np.asarray(zarr.open_array(str(output / "num_steps"), mode="r")[...]).ravel() == 0)
    codes, k = np.unique(status[~unrun], return_counts=True)
    store_counts = {Status(int(c)).text: int(v) for c, v in zip(codes, k) if c >= 0}
    if unrun.any():
        store_counts[UNRUN] = int(unrun.sum())
    return SweepResult(output, plan.size, plan.n_chunks, len(todo), plan.n_chunks - len(todo),
                       time.perf_counter() - t0, store_counts)


def rigid_deficit(gain, rigid) -> np.ndarray:
    """`gain / rigid - 1` (the store's `rigid_deficit`), NaN where the rigid gain (Eq 19) is not positive:
    Eq 19 then leaves the top mass moving down (a top heavier than the mass below it), and a deficit
    against it means nothing (it read gain / -0.85 - 1)."""
    gain, rigid = np.asarray(gain, dtype=float), np.asarray(rigid, dtype=float)
    with np.errstate(invalid="ignore"):
        ok = rigid > 0
    return np.where(ok, gain / np.where(ok, rigid, 1.0) - 1.0, np.nan)


def overlap_fractions(first_contacts, t_final, ground: bool) -> np.ndarray:
    """`(B,)` per design, the largest fraction of the shorter first contact during which two neighbouring
    interfaces (`j`, `j+1`, sharing mass `j+1`) are both closed: `analysis.independence` from the first
    contacts' step-resolved `[start, end]` (`BatchSolution.first_contacts`; a contact not over by the end
    of the run ends at `t_final`); 0 when no two neighbours both touched."""
    fc = np.asarray(first_contacts, dtype=float)
    on = fc[..., 0]
    off = np.where(np.isnan(fc[..., 1]) & np.isfinite(on), np.asarray(t_final, dtype=float)[:, None], fc[..., 1])
    lo = 0 if ground else 1
    a_on, a_off, b_on, b_off = on[:, lo:-1], off[:, lo:-1], on[:, lo + 1 :], off[:, lo + 1 :]
    with np.errstate(invalid="ignore", divide="ignore"):
        both = np.maximum(0.0, np.minimum(a_off, b_off) - np.maximum(a_on, b_on))
        shorter = np.minimum(a_off - a_on, b_off - b_on)
        frac = np.where(np.isfinite(both) & (shorter > 0), both / np.where(shorter > 0, shorter, 1.0), 0.0)
    return frac.max(axis=1) if frac.shape[1] else np.zeros(len(fc))


def _progress(enabled: bool, plan: _Plan, chunks):
    """A rich progress bar over the designs of the chunks `chunks` (those this run computes), or None."""
    if not enabled:
        return None
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    bar = Progress(TextColumn("sweep"), BarColumn(), MofNCompleteColumn(), TextColumn("designs"), TimeElapsedColumn(),
                   TextColumn("eta"), TimeRemainingColumn(), console=Console(stderr=True), transient=True)
    bar.start()
    task = bar.add_task("sweep", total=sum((plan.region(c).stop - plan.region(c).start) * plan.row for c in chunks))
    return bar, task


def _run_dask(text, source, todo, finish, client, rows: int) -> None:
    from distributed import as_completed

    futures = {client.submit(_evaluate, text, source, c, rows, pure=False): c for c in todo}
    for fut in as_completed(futures):
        finish(futures[fut], fut.result())
