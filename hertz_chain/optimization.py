"""Design by the compliant model: the stack that maximises the launch gain, or that gives a target pulse.

`optimize(path)` reads a stack file with an `[optimize]` section (docs/optimize.md), searches the
design space it names with the compliant simulator, and returns an `OptimizeResult`: the best stack,
its exact analysis, the starting stack's, the paper's MVG and MET designs for the same end masses
simulated under the same contacts, and how the search converged. `OptimizeResult.document()` is the
optimum as a stack file (without `[optimize]`) that `hertz-chain simulate` runs and that reproduces the
reported numbers (they are computed from it).

**Variables.** `[[optimize.vary]]` names stack-file keys by the key vocabulary of `hertz_chain.keys`
(`stack.masses` by mass number, `stack.gaps` by gap number, `contact.stiffness`/`contact.restitution`
by interface number with 0 = ground, `drop.impact_velocity`, `drop.height`), each with bounds in
units. The search runs on `u` in the unit box: `x = lo (hi/lo)^u` for the scale keys (masses,
stiffnesses: `keys.KeyRow.log`), `x = lo + u (hi - lo)` otherwise. With `n = [...]`, every number of
masses is optimised from masses spaced geometrically between the file's end masses, and the best wins.

**Methods.**

- *Launch gain* (no peak limit): gradients of the top launch velocity by the replayed reverse mode of
  `simulation.launch_velocity` through the differentiable design map (`hertz_chain._design`), and scipy's
  bounded quasi-Newton L-BFGS-B (SLSQP when a total-mass budget adds a linear constraint). Not
  optimistix: its quasi-Newton methods are unconstrained, and a reparametrisation onto the box can only
  approach a bound, while touching stacks often have their optimum on one.
- *Pulse targets and peak limits* (`objective = "pulse"`, `max_peak_g`, `max_peak_force`): the peak g
  and the duration are computed as the exact post-processor does (`pulse.pulse_metrics` on the solver's
  steps over the first cascade, with the exact velocity), which makes them smooth in the design: ΔV is
  the exact velocity change, the peak is refined between the steps on the velocity's cubic Hermite
  interpolant, and the equivalent half-sine duration is `pi dV / (2 peak)`. Their derivatives are
  batched central differences (the `2d + 1` designs of a stencil in one `simulate_batch` with the step
  histories), and SLSQP handles the bounds and the constraints. The reported values are the exact
  post-processor's on the written file.
- *SRS targets* (`objective = "srs"`): an SRS is a maximum over each oscillator's response; the search
  is scipy's derivative-free, bound- and constraint-aware COBYQA (Ragonneau & Zhang 2023) on it.
- *Global*: a scrambled Sobol pre-screen (`scipy.stats.qmc`, seeded) of `screen` designs evaluated in
  one compiled, vmapped `simulate_batch`; the best `starts - 1` of them and the file's own stack start
  the local searches. The result says whether the starts agree.
- *Starts in lockstep*: with batched central differences, the local searches run together, one scipy
  search per start in its own thread, and every round of their objective calls is one batched
  `simulate_batch` of all their stencils (`_searches`). The reverse mode takes one design at a time
  (under `vmap` its replay runs every kind of step for every step), so its starts run one by one.

Raises `StackFileError` (one line naming the key, the value and what is allowed) for a bad
`[optimize]` section: an unknown key to vary, an index out of range, bounds in the wrong order or units,
an infeasible mass budget.
"""

from __future__ import annotations

import dataclasses
import enum
import math
import re
import time
from pathlib import Path
from typing import Any

import numpy as np

from .errors import StackFileError
from .keys import KEYS, Slot, check_values, quantity_of, read_bounds, read_entry, resolve
from .stackfile import StackSpec, parse_srs_table, parse_stack
from .units import parse_quantity
from .status import Status

__all__ = ["OptimizeStatus", "OptimizeSpec", "VarySpec", "OptimizeResult", "optimize", "read_optimize_file",
           "OBJECTIVES", "prepare"]

OBJECTIVES = ("gain", "pulse", "srs")
"""`gain`: maximise the top mass's launch gain; `pulse`: hit a target top pulse (peak g and duration);
`srs`: fit the top pulse's shock response spectrum to a target table, within ±`srs_tolerance_db`."""

DURATIONS = ("half-sine", "10%")
"""How a pulse's duration is read: the equivalent half-sine duration `pi dV / (2 peak)`, or between the
10 % points (`hertz_chain.pulse`)."""

_OPTIMIZE_KEYS = ("objective", "n", "starts", "screen", "seed", "max_iterations", "total_mass", "fix_ends",
                  "max_peak_g", "max_peak_force", "target_peak_g", "target_duration", "duration", "target_srs",
                  "srs_tolerance_db", "srs_q", "vary")
_VARY_KEYS = ("key", "index", "bounds")
MAX_STARTS = 64
PG_TOLERANCE = 1e-4
"""A local search has converged where the projected gradient (unit box) is below this, relative."""
MAX_SCREEN = 4096


class OptimizeStatus(enum.IntEnum):
    """How a search ended; `exit_code` is the command line's."""

    CONVERGED = 0
    NOT_CONVERGED = 1
    FAILED = 2

    @property
    def text(self) -> str:
        return {0: "converged", 1: "not converged", 2: "failed"}[int(self)]

    @property
    def exit_code(self) -> int:
        return {0: 0, 1: 3, 2: 5}[int(self)]

    @property
    def ok(self) -> bool:
        return self is OptimizeStatus.CONVERGED


@dataclasses.dataclass(frozen=True)
class VarySpec:
    """One `[[optimize.vary]]` entry: `key`, `index` (as written; None = the default indices) and the
    bounds in SI units."""

    key: str
    index: Any
    bounds: tuple[float, float]
    where: str


@dataclasses.dataclass(frozen=True)
class OptimizeSpec:
    """The `[optimize]` section, validated, in SI units (docs/optimize.md)."""

    objective: str = "gain"
    vary: tuple[VarySpec, ...] = ()
    n: tuple[int, ...] | None = None
    starts: int = 4
    screen: int = 64
    seed: int = 0
    max_iterations: int = 200
    total_mass: float | None = None
    fix_ends: bool = True
    max_peak_g: float | None = None
    max_peak_force: float | None = None
    target_peak_g: float | None = None
    target_srs: tuple[tuple[float, float], ...] | None = None
    srs_tolerance_db: float = 3.0
    srs_q: float = 10.0
    target_duration: float | None = None
    duration: str = "half-sine"

    @property
    def needs_pulse(self) -> bool:
        return self.objective in ("pulse", "srs") or self.max_peak_g is not None or self.max_peak_force is not None


# ------------------------------------------------------------------------------------------ parsing
def _err(key: str, problem: str) -> StackFileError:
    return StackFileError(f"{key}: {problem}")


def _int(raw, key, lo, hi) -> int:
    if isinstance(raw, bool) or not isinstance(raw, int) or not lo <= raw <= hi:
        raise _err(key, f"{raw!r} is invalid: an integer from {lo} to {hi}")
    return raw


def _positive(raw, key, dim) -> float:
    value = parse_quantity(raw, dim, key)
    if not (math.isfinite(value) and value > 0):
        raise _err(key, f"{raw!r} is invalid: must be > 0")
    return value


def _parse_srs(raw: dict) -> dict:
    """`target_srs` (rows `[frequency, level]`: Hz and g, or quantities), `srs_tolerance_db`, `srs_q`."""
    rows = parse_srs_table(raw.get("target_srs"), "optimize.target_srs")
    out = {"target_srs": tuple(rows)}
    if "srs_tolerance_db" in raw:
        out["srs_tolerance_db"] = _positive(raw["srs_tolerance_db"], "optimize.srs_tolerance_db", "dimensionless")
    if "srs_q" in raw:
        q = _positive(raw["srs_q"], "optimize.srs_q", "dimensionless")
        if not 0.5 < q <= 1000:
            raise _err("optimize.srs_q", f"{raw['srs_q']!r} is invalid: Q between 0.5 and 1000")
        out["srs_q"] = q
    return out


def parse_optimize(raw: Any, spec: StackSpec) -> OptimizeSpec:
    """Validate an `[optimize]` table against the stack file `spec` (see docs/optimize.md)."""
    from .constants import MAX_MASSES

    if not isinstance(raw, dict):
        raise _err("optimize", f"expected a table ([optimize]), got {raw!r}")
    for k in raw:
        if k not in _OPTIMIZE_KEYS:
            import difflib

            close = difflib.get_close_matches(str(k), _OPTIMIZE_KEYS, n=1, cutoff=0.6)
            raise _err(f"optimize.{k}", "unknown key; " + (f"did you mean '{close[0]}'?" if close else
                                                          f"allowed: {', '.join(_OPTIMIZE_KEYS)}"))
    out: dict[str, Any] = {}
    objective = raw.get("objective", "gain")
    if objective not in OBJECTIVES:
        raise _err("optimize.objective", f"{objective!r} is invalid; allowed: {', '.join(OBJECTIVES)}")
    out["objective"] = objective
    if "n" in raw:
        ns = raw["n"] if isinstance(raw["n"], list) else [raw["n"]]
        if not ns:
            raise _err("optimize.n", "empty; give numbers of masses, e.g. n = [4, 8]")
        lo = 2 if spec.has_ground else 3
        out["n"] = tuple(_int(v, "optimize.n", lo, MAX_MASSES) for v in ns)
        if len(set(out["n"])) != len(out["n"]):
            raise _err("optimize.n", f"{ns!r} repeats a number of masses")
        for key in ("radius", "material", "shape"):
            if isinstance(getattr(spec.stack, key), tuple):
                raise _err("optimize.n", f"stack.{key} is given per mass; with optimize.n give one value for all")
        if isinstance(spec.stack.gaps, tuple):  # a review: numpy's "stack.gaps has 2 entries, expected 3"
            raise _err("optimize.n", "stack.gaps is given per gap; with optimize.n give one gap for all")
        if spec.stack.velocities is not None:
            raise _err("optimize.n", "a chain started from stack.velocities has a fixed number of masses")
        if spec.contact.overrides:
            raise _err("optimize.n", "[[contact.interface]] overrides name interfaces of one stack; "
                       "with optimize.n use [contact] (and [contact.ground]) only")
    for key, lo, hi in (("starts", 1, MAX_STARTS), ("screen", 0, MAX_SCREEN), ("seed", 0, 2**31 - 1),
                        ("max_iterations", 1, 100_000)):
        if key in raw:
            out[key] = _int(raw[key], f"optimize.{key}", lo, hi)
    if "fix_ends" in raw:
        if not isinstance(raw["fix_ends"], bool):
            raise _err("optimize.fix_ends", f"{raw['fix_ends']!r} is invalid: true or false")
        out["fix_ends"] = raw["fix_ends"]
    if "total_mass" in raw:
        out["total_mass"] = _positive(raw["total_mass"], "optimize.total_mass", "mass")
    if "max_peak_force" in raw:
        out["max_peak_force"] = _positive(raw["max_peak_force"], "optimize.max_peak_force", "force")
    for key in ("max_peak_g", "target_peak_g"):
        if key in raw:
            if isinstance(raw[key], str):  # "1500 g" would read as grams
                raise _err(f"optimize.{key}", f"{raw[key]!r} is invalid: a plain number of g (standard gravity, "
                           "9.80665 m/s^2), e.g. 1500")
            out[key] = _positive(raw[key], f"optimize.{key}", "dimensionless")
    if "target_duration" in raw:
        out["target_duration"] = _positive(raw["target_duration"], "optimize.target_duration", "time")
    if "duration" in raw:
        if raw["duration"] not in DURATIONS:
            raise _err("optimize.duration", f"{raw['duration']!r} is invalid; allowed: {', '.join(DURATIONS)}")
        out["duration"] = raw["duration"]
    if objective == "srs":
        out.update(_parse_srs(raw))
    else:
        for key in ("target_srs", "srs_tolerance_db", "srs_q"):
            if key in raw:
                raise _err(f"optimize.{key}", "used only with objective = 'srs'")
    if objective == "pulse":
        for key in ("target_peak_g", "target_duration"):
            if key not in out:
                raise _err(f"optimize.{key}", "missing; objective = 'pulse' needs target_peak_g and target_duration")
    else:
        for key in ("target_peak_g", "target_duration", "duration"):
            if key in raw:
                raise _err(f"optimize.{key}", "used only with objective = 'pulse'")
    vary = raw.get("vary")
    if vary is not None and not isinstance(vary, list):
        raise _err("optimize.vary", f"{vary!r} is invalid: give [[optimize.vary]] tables, each with a key and bounds")
    if not isinstance(vary, list) or not vary:
        raise _err("optimize.vary", "missing; give at least one [[optimize.vary]] with a key and bounds")
    entries = []
    for i, item in enumerate(vary):
        where = f"optimize.vary[{i}]"
        read_entry(item, where, _VARY_KEYS, "stack.masses")
        key = item["key"]
        resolve(key, None, n=3, ground=True, where=f"{where}.key")  # known key (indices checked per n)
        row = KEYS[key]
        dim, p = quantity_of(spec, key, item.get("index"), where)
        lo, hi = read_bounds(item.get("bounds"), dim, f"{where}.bounds", p)
        check_values(key, [lo, hi], f"{where}.bounds", shown=repr(item["bounds"]), gravity=spec.drop.gravity)
        if out.get("n") and "index" in item and row.over in ("mass", "gap"):
            raise _err(f"{where}.index", "with optimize.n give no index: the interior masses (or every gap) vary")
        entries.append(VarySpec(key, item.get("index"), (lo, hi), where))
    keys = [e.key for e in entries]
    for key in set(keys):
        if keys.count(key) > 1 and any(e.index is None for e in entries if e.key == key):
            raise _err("optimize.vary", f"{key} is varied twice; give disjoint index lists")
    out["vary"] = tuple(entries)
    return OptimizeSpec(**out)


def read_optimize_file(path: str | Path) -> tuple[StackSpec, OptimizeSpec, dict]:
    """Read a stack file with an `[optimize]` section: `(spec, problem, document)`; `document` is the
    parsed TOML without `[optimize]` (what `--write` starts from). Raises `StackFileError`."""
    import tomllib

    from .stackfile import load_stack_file

    spec = load_stack_file(path)  # every check of an ordinary stack file, with the file name
    doc = tomllib.loads(Path(path).read_text(encoding="utf-8-sig"))
    if "optimize" not in doc:
        raise StackFileError(f"{path}: optimize: missing; give an [optimize] section (docs/optimize.md)")
    raw = doc.pop("optimize")
    try:
        problem = parse_optimize(raw, spec)
    except StackFileError as exc:  # (once: a message from building the stack may name the file already)
        text = str(exc)
        raise StackFileError(text if text.startswith(f"{path}: ") else f"{path}: {text}") from None
    return spec, problem, doc


# ------------------------------------------------------------------------------------------ one n
@dataclasses.dataclass
class _Space:
    """The search space of one number of masses: the design map, the slots and their bounds."""

    n: int
    spec: StackSpec
    doc: dict
    slots: tuple[Slot, ...]
    lo: np.ndarray
    hi: np.ndarray
    log: np.ndarray
    dm: Any

    def to_x(self, u):
        import jax.numpy as jnp

        u = jnp.clip(u, 0.0, 1.0)
        lin = self.lo + u * (self.hi - self.lo)
        # the log branch only where it applies (elsewhere 1 ** u): a bound of 0 on a linear slot (a gap) made
        # it 0 * inf ** u, whose NaN reached the gradient through `where` (the search stopped at its start)
        log = self.log & (self.lo > 0)
        lo, hi = (np.where(log, b, 1.0) for b in (self.lo, self.hi))
        return jnp.where(log, lo * (hi / lo) ** u, lin)

    def to_u(self, x) -> np.ndarray:
        x = np.clip(np.asarray(x, dtype=float), self.lo, self.hi)
        with np.errstate(divide="ignore", invalid="ignore"):
            lg = np.log(x / self.lo) / np.log(self.hi / self.lo)
        return np.clip(np.where(self.log & (self.lo > 0), lg, (x - self.lo) / (self.hi - self.lo)), 0.0, 1.0)


def _start_masses(spec: StackSpec, n: int) -> np.ndarray:
    from .builder import design_masses

    m = design_masses(spec)
    if n == m.size:
        return m
    return m[0] * (m[-1] / m[0]) ** (np.arange(n) / (n - 1))


def _space(spec: StackSpec, doc: dict, problem: OptimizeSpec, n: int) -> _Space:
    from ._design import DesignMap, with_masses

    spec_n = with_masses(spec, _start_masses(spec, n))
    ground = spec.has_ground
    slots, lo, hi = [], [], []
    for v in problem.vary:
        default = None
        if v.key == "stack.masses" and problem.fix_ends:
            default = tuple(range(2, n))
            if not default:
                raise _err(f"{v.where}.key", f"a {n}-mass stack has no interior mass to vary with fix_ends = true")
        got = resolve(v.key, v.index, n=n, ground=ground, where=v.where, default=default)
        if v.key == "stack.masses" and problem.fix_ends:
            ends = [s.index for s in got if s.index in (1, n)]
            if ends:
                raise _err(f"{v.where}.index", f"mass {ends[0]} is an end mass, held fixed (fix_ends = true, as in "
                           "the paper); set optimize.fix_ends = false to vary it")
        for s in got:
            if s in slots:
                raise _err(f"{v.where}.index", f"{s.label} is varied twice")
            slots.append(s)
            lo.append(v.bounds[0])
            hi.append(v.bounds[1])
    slots = tuple(slots)
    dm = DesignMap(spec_n, slots)
    log = np.array([KEYS[s.key].log for s in slots])
    lo_a, hi_a = np.array(lo), np.array(hi)
    if problem.total_mass is not None:
        m = np.asarray(dm.base["stack.masses"], dtype=float).copy()
        for s, low in zip(slots, lo_a):
            if s.key == "stack.masses":
                m[s.position] = low
        if m.sum() > problem.total_mass:
            raise _err("optimize.total_mass", f"{problem.total_mass:g} kg is infeasible for n = {n}: the fixed "
                       f"masses and the lower bounds of the varied ones already weigh {m.sum():.6g} kg")
    return _Space(n, spec_n, doc, slots, lo_a, hi_a, log, dm)


# ------------------------------------------------------------------------------------------ objectives
#: a pulse target is met when the peak g and the duration are each within this fraction of their targets
#: (the search itself reaches ~1e-5); otherwise the result says by how much it misses (`pulse_misses`):
#: limits on the peak or the mass, or the bounds, can make a target unreachable, and the search then
#: converges to the closest pulse it can reach
PULSE_TARGET_TOLERANCE = 1e-3


def _objective(p: OptimizeSpec, mt: dict) -> float:
    """The value minimised on the exact path: the negative gain (with peak limits); the sum of the squared
    relative misses of the peak and the duration (`pulse`); the mean squared SRS error in units of the
    tolerance band (`srs`: 1 = every frequency on the band's edge)."""
    if p.objective == "pulse":
        return (mt["peak_g"] / p.target_peak_g - 1.0) ** 2 + (mt["duration"] / p.target_duration - 1.0) ** 2
    if p.objective == "srs":
        return float(np.mean((mt["srs_error_db"] / p.srs_tolerance_db) ** 2))
    return -mt["gain"]



def _parabola_max(t: np.ndarray, y: np.ndarray) -> float:
    """The largest value of the samples `y` `(steps, k)` at times `t`, refined between the steps by the
    parabola through the largest sample and its two neighbours (smooth in the design as the steps move,
    error O(dt^3) against O(dt^2) for the bare maximum); the bare maximum at the record's ends."""
    i, j = np.unravel_index(int(np.argmax(y)), y.shape)
    top = float(y[i, j])
    if not 0 < i < len(t) - 1:
        return top
    (t0, t1, t2), (y0, y1, y2) = t[i - 1 : i + 2], y[i - 1 : i + 2, j]
    # the interpolant is y1 + b (s - t1) + c (s - t1)^2: its vertex is y1 - b^2 / (4 c)
    d01, d12 = (y1 - y0) / (t1 - t0), (y2 - y1) / (t2 - t1)
    c = (d12 - d01) / (t2 - t0)
    if not c < 0:
        return top
    b = d01 + c * (t1 - t0)  # slope at t1
    return max(top, float(y1 - b * b / (4 * c)))


class _Evaluator:
    """The objective and constraints of one `_Space`, compiled once and reused for every start.

    `width`: how many designs one batched evaluation takes at most (the number of local searches run
    in lockstep, `_searches`; 1 for the reverse mode). The central differences pad a batch of `k`
    designs to the next power of two (at most `width`) by repeating the first: at most
    `log2(width) + 1` compiled shapes, and little work wasted as the searches finish one by one."""

    def __init__(self, space: _Space, problem: OptimizeSpec, width: int = 1):
        import jax

        self.space, self.problem = space, problem
        self.count = 0
        self._designs = self._last = None
        self.g = space.dm.gravity
        from .registry import LAWS

        self.gradient = ("reverse mode" if all(LAWS[cs.law].smooth_onset for cs in space.dm.contacts.values())
                         else "batched central differences")
        # the reverse mode takes one design at a time: under `vmap` the replay's `lax.switch` between its
        # kinds of step becomes a select that runs all four for every step (measured: the six-mass search
        # of benchmarks/optimize.md took 187 s with its eight starts vmapped, against ~30 s)
        self.width = max(int(width), 1) if self.gradient != "reverse mode" else 1
        if not problem.needs_pulse and self.gradient == "reverse mode":
            from .simulation import launch_velocity

            def neg_gain(u):
                x = space.to_x(u)
                stack, state = space.dm(x)
                return -launch_velocity(stack, state, until="launch")[-1] / space.dm.drop_speed(x)

            one = jax.jit(jax.value_and_grad(neg_gain))
            self._vg = lambda U: jax.tree.map(lambda a: a[None], one(U[0]))
        elif not problem.needs_pulse:
            self._vg = self._central_differences
        self._mass = jax.jit(jax.value_and_grad(lambda u: self._total_mass(u)))

    #: step of the central differences in the unit box. The adaptive solves (rtol = 1e-11) make the
    #: objective noisy at ~1e-9 relative; at the MVG optimum of the six-mass gapped Tsuji stack the
    #: gradient (zero there) came out ~1e-3 with a step of 1e-5, 6e-5 with 1e-4 and 1e-5 with 1e-3
    #: (truncation O(h^2) stays below that)
    FD_STEP = 1e-3

    def _central_differences(self, U):
        """The negative gains at the rows of `U` `(k, d)` and their central-difference gradients:
        the `k (2d + 1)` designs in one compiled, batched solve (`simulate_batch`); each stencil is
        kept inside the box. A row whose stencil did not complete gets NaN."""
        from .simulation import Tolerances, simulate_batch

        k, d = U.shape
        h = self.FD_STEP
        C = np.clip(U, h, 1.0 - h)
        rows = np.concatenate([U[:, None, :], C[:, None, :] + h * np.eye(d), C[:, None, :] - h * np.eye(d)], axis=1)
        stacks, states, speed = self._design_batch(rows.reshape(k * (2 * d + 1), d))
        sol = simulate_batch(stacks, states, save_steps=False, max_steps=16_384, until="launch",
                             tolerances=Tolerances(rtol=1e-11, atol=1e-11, resolve_onsets=True))
        speed = np.asarray(speed) if not self.space.dm.chain else self.space.dm.drop_speed(None)
        f = np.where(sol.ok, -sol.launch_velocities[:, -1] / speed, np.nan).reshape(k, 2 * d + 1)
        return f[:, 0], (f[:, 1 : d + 1] - f[:, d + 1 :]) / (2 * h)

    def _design_batch(self, U):
        """`(stacks, states, drop speeds)` of the rows of `U` (unit box), batched; compiled once."""
        import jax
        import jax.numpy as jnp

        if self._designs is None:
            sp = self.space
            self._designs = jax.jit(lambda U: (*jax.vmap(lambda u: sp.dm(sp.to_x(u)))(U),
                                               jax.vmap(lambda u: sp.dm.drop_speed(sp.to_x(u)))(U)
                                               if not sp.dm.chain else jnp.ones(U.shape[0])))
        return self._designs(U)

    def _total_mass(self, u):
        return self.space.dm.fields(self.space.to_x(u))["stack.masses"].sum()

    # gradient path -----------------------------------------------------------------------
    def values_and_grads(self, U) -> tuple[np.ndarray, np.ndarray]:
        """The objective and its gradient at each row of `U` `(k, d)`, `k <= width`, in one batched
        call (padded as the class docstring says). A design the solver cannot finish gets a large value
        and no slope (the line search backs off); when a batch raises, its rows are evaluated one by one
        so that only the failing design is marked."""
        U = np.asarray(U, dtype=float).reshape(-1, len(self.space.slots))
        k = len(U)
        self.count += k

        def batch(rows):
            size = min(self.width, 1 << (len(rows) - 1).bit_length())
            padded = np.concatenate([rows, np.repeat(rows[:1], size - len(rows), axis=0)])
            v, g = self._vg(padded)
            return np.array(v, dtype=float)[: len(rows)], np.array(g, dtype=float)[: len(rows)]

        try:
            v, g = batch(U)
        except Exception:  # a failed solve raises for the whole batch (`launch_velocity`): find which
            v, g = np.full(k, np.nan), np.full(U.shape, np.nan)
            for i in range(k):
                try:
                    v[i : i + 1], g[i : i + 1] = batch(U[i : i + 1])
                except Exception:
                    pass
        bad = ~(np.isfinite(v) & np.all(np.isfinite(g), axis=1))
        v[bad], g[bad] = 1e3, 0.0
        return v, g

    def value_and_grad(self, u):
        """`values_and_grads` of one design: `(value, gradient)`."""
        v, g = self.values_and_grads(np.asarray(u, dtype=float)[None, :])
        return float(v[0]), g[0]

    # exact path ----------------------------------------------------------------------------
    def metrics(self, u, count: bool = True) -> dict:
        """The exact metrics of the design at `u` from one solve with its step history."""
        from .simulation import simulate

        self.count += count
        x = np.asarray(self.space.to_x(np.asarray(u, dtype=float)))
        stack, state = self.space.dm(x)
        opts = dict(self.space.dm.built.simulate_options, throw=False)
        sol = simulate(stack, state, **opts)
        gain = float(sol.launch_velocities[-1]) / float(self.space.dm.drop_speed(x))
        st = sol.steps
        if st is None or not sol.status.ok:
            return {"ok": False, "gain": gain}
        return self._pulse_of(gain, sol.cascade_end_time, st.t, st.accelerations, st.velocities, st.forces)

    def _pulse_of(self, gain, cascade_end, t, acc, vel, forces) -> dict:
        """The metrics of one solved design from its step history: the top pulse over the first cascade
        by `pulse.pulse_metrics` with the exact velocity (ΔV exact, the peak refined between the steps
        on the velocity's cubic Hermite interpolant: both smooth in the design)."""
        from .pulse import pulse_metrics

        out = {"ok": True, "gain": float(gain)}
        keep = np.isfinite(t)
        if np.isfinite(cascade_end):
            keep &= t <= cascade_end
        t = t[keep]
        a = acc[keep, -1] + self.g
        v = vel[keep, -1] + self.g * t
        try:
            pm = pulse_metrics(t, a, velocity=v)
        except Exception:
            return out | {"ok": False}
        dur = pm.equivalent_half_sine_duration if self.problem.duration == "half-sine" else pm.duration_10
        out.update(peak_g=pm.peak / 9.80665, duration=dur, peak_force=_parabola_max(t, forces[keep]))
        if self.problem.objective == "srs":
            out["srs_error_db"] = self.srs_error_db(t, a / 9.80665)
        return out

    def metrics_batch(self, U) -> list[dict]:
        """`metrics` of every row of `U` `(k, d)` from compiled, batched solves with the step histories
        (`simulate_batch`), each post-processed as `metrics` does: in pieces of a stencil's `2d + 1`
        designs (the last padded), so that one shape compiles."""

        from .simulation import simulate_batch

        U = np.asarray(U, dtype=float)
        size = 2 * len(self.space.slots) + 1  # one compiled shape: a stencil's; more rows go in pieces
        if len(U) > size:
            return [mt for i in range(0, len(U), size) for mt in self.metrics_batch(U[i : i + size])]
        k = len(U)
        U = np.concatenate([U, np.repeat(U[:1], size - k, axis=0)])
        stacks, states, speed = self._design_batch(U)
        opts = dict(self.space.dm.built.simulate_options)
        opts.setdefault("max_steps", 16_384)
        sol = simulate_batch(stacks, states, save_steps=True, **opts)
        speed = np.asarray(speed) if not self.space.dm.chain else np.full(len(U), self.space.dm.drop_speed(None))
        st = sol.steps
        # a design that did not finish in the batch's step budget is solved alone, as `metrics` (and the
        # final report) would: with `simulate`'s own budget
        return [self._pulse_of(sol.launch_velocities[b, -1] / speed[b], sol.cascade_end_time[b], st["t"][b],
                               st["accelerations"][b], st["velocities"][b], st["forces"][b])
                if sol.ok[b] else self.metrics(U[b], count=False) for b in range(k)]

    def _pulse_values(self, mt: dict) -> np.ndarray:
        """`[objective, constraints...]` of one design's metrics (constraints >= 0 where feasible)."""
        p = self.problem
        if not mt["ok"]:
            return np.array([1e3] + [-1.0] * self.n_constraints)
        out = [_objective(p, mt)]
        if p.max_peak_g is not None:
            out.append(1.0 - mt["peak_g"] / p.max_peak_g)
        if p.max_peak_force is not None:
            out.append(1.0 - mt["peak_force"] / p.max_peak_force)
        return np.array(out)

    @property
    def n_constraints(self) -> int:
        return (self.problem.max_peak_g is not None) + (self.problem.max_peak_force is not None)

    def pulse_gradient(self, u) -> tuple[np.ndarray, np.ndarray]:
        """`(values, jacobian)` of `[objective, constraints...]` at `u` by central differences of the exact
        post-processor, the `2d + 1` designs in one batched solve (`metrics_batch`; step `FD_STEP`
        in the unit box, the stencil kept inside it); cached for the last point (SLSQP asks for the
        objective, the constraints and their derivatives at one point separately)."""
        u = np.asarray(u, dtype=float)
        key = u.tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        self.count += 1
        d, h = len(u), self.FD_STEP
        c = np.clip(u, h, 1.0 - h)
        rows = np.vstack([u[None, :], c + h * np.eye(d), c - h * np.eye(d)])
        mts = self.metrics_batch(rows)
        vals = np.array([self._pulse_values(mt) for mt in mts])
        ok = np.array([mt["ok"] for mt in mts])
        plus, minus = vals[1 : d + 1], vals[d + 1 :]
        # a neighbour that failed: the one-sided difference from the other side and the centre (the
        # centre's distance to it is not h where the stencil was moved inside the box); both: no slope
        up, down = ok[1 : d + 1, None], ok[d + 1 :, None]
        dc = (c - u)[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):  # the branches not taken may divide by zero
            jac = np.where(up & down, (plus - minus) / (2 * h),
                           np.where(up, (plus - vals[0]) / (h + dc), np.where(down, (vals[0] - minus) / (h - dc), 0.0)))
        jac = np.where(ok[0] & np.isfinite(jac), jac, 0.0).T
        self._last = (key, (vals[0], jac))
        return vals[0], jac

    def srs_frequencies(self) -> tuple[np.ndarray, np.ndarray]:
        """The natural frequencies of the SRS fit (1/12 octave across the target table, at most 120)
        and the target there (log-log interpolation of the table), g."""
        f_t, a_t = (np.array(c) for c in zip(*self.problem.target_srs))
        count = min(120, max(2, int(np.ceil(12 * np.log2(f_t[-1] / f_t[0]))) + 1))
        f = np.geomspace(f_t[0], f_t[-1], count)
        return f, np.exp(np.interp(np.log(f), np.log(f_t), np.log(a_t)))

    def srs_error_db(self, t, a_g) -> np.ndarray:
        """`20 log10(SRS / target)` of the top pulse at `srs_frequencies` (maximax, Q = `srs_q`)."""
        import warnings

        from .spectrum import srs

        f, target = self.srs_frequencies()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            s = srs(t, a_g, f, Q=self.problem.srs_q, on_coarse="ignore")
        return 20.0 * np.log10(np.maximum(s.maximax, 1e-300) / target)

    def pulse_objective(self, u) -> float:
        """The objective of the design at `u` from one solve (the derivative-free SRS path)."""
        return float(self._pulse_values(self.metrics(u))[0])

    def pulse_constraints(self, u) -> np.ndarray:
        """Constraint values >= 0 where feasible (relative margins), from one solve."""
        return self._pulse_values(self.metrics(u))[1:]


def _screen(space: _Space, ev: _Evaluator, problem: OptimizeSpec) -> np.ndarray:
    """The Sobol pre-screen: the unit-box points sorted best first (batched, compiled solves; on the pulse
    path the points that break a limit come after the feasible ones, least violation first)."""
    import jax
    from scipy.stats import qmc

    d = len(space.slots)
    if problem.screen == 0 or d == 0:
        return np.zeros((0, d))
    U = qmc.Sobol(d, scramble=True, seed=problem.seed).random(problem.screen)
    if problem.needs_pulse:  # the exact post-processor on every point's history, batched in pieces
        ev.count += len(U)
        rows = np.array([ev._pulse_values(mt) for mt in ev.metrics_batch(U)])
        violation = np.sum(np.maximum(-rows[:, 1:], 0.0), axis=1)
        vals = np.where(violation > 0, 1e6 + violation, rows[:, 0])  # feasible first, then least violation
    else:
        from .simulation import simulate_batch

        X = jax.vmap(space.to_x)(U)
        stacks, states = jax.vmap(space.dm)(X)
        opts = {k: v for k, v in space.dm.built.simulate_options.items() if k in ("solver", "tolerances", "t_max")}
        sol = simulate_batch(stacks, states, save_steps=False, max_steps=16_384, until="launch", **opts)
        ev.count += len(U)
        speed = np.asarray(jax.vmap(space.dm.drop_speed)(X)) if not space.dm.chain else space.dm.drop_speed(None)
        vals = np.where(sol.ok, -sol.launch_velocities[:, -1] / speed, np.inf)
    if problem.total_mass is not None:
        masses = np.array([float(ev._mass(u)[0]) for u in U]) if d else np.zeros(0)
        vals = np.where(masses <= problem.total_mass, vals, np.inf)
    order = np.argsort(vals)
    return U[order][np.isfinite(vals[order])]


@dataclasses.dataclass
class _Run:
    u: np.ndarray
    value: float
    iterations: int
    message: str
    success: bool
    history: list
    evaluations: int = 0
    violation: float = 0.0


_LIMIT_TOLERANCE = 1e-6
"""A search point meets a limit (`max_peak_g`, `max_peak_force`, `total_mass`) within this, relative."""


def _violation(ev: _Evaluator, u: np.ndarray) -> float:
    """How far the design at `u` breaks the limits: the sum of the relative excesses (0 when it meets
    them). Peak limits from the exact post-processor (`metrics`); the mass budget from the design."""
    p = ev.problem
    out = 0.0
    if p.total_mass is not None:
        out += max(float(ev._mass(u)[0]) / p.total_mass - 1.0, 0.0)
    if ev.n_constraints:
        mt = ev.metrics(u, count=False)
        out += float(np.sum(np.maximum(-ev._pulse_values(mt)[1:], 0.0))) if mt["ok"] else math.inf
    return out


def _local(space: _Space, ev: _Evaluator, problem: OptimizeSpec, u0: np.ndarray, fun=None) -> _Run:
    """One local search from `u0`; `fun(u) -> (value, gradient)` on the gradient path (default
    `ev.value_and_grad`)."""
    from scipy.optimize import Bounds, NonlinearConstraint, minimize

    fun = fun or ev.value_and_grad
    d = len(u0)
    bounds = Bounds(np.zeros(d), np.ones(d))
    history: list[float] = []
    cons = []
    if problem.total_mass is not None:
        if problem.objective == "srs":
            cons.append(NonlinearConstraint(lambda u: float(ev._mass(u)[0]), -np.inf, problem.total_mass))
        else:
            cons.append({"type": "ineq", "fun": lambda u: problem.total_mass - float(ev._mass(u)[0]),
                         "jac": lambda u: -np.asarray(ev._mass(u)[1])})
    if problem.needs_pulse and problem.objective != "srs":
        # peak, duration and peak force as smooth functions of the design (`_Evaluator._pulse_of`), their
        # derivatives by batched central differences; SLSQP for the bounds and the constraints
        if ev.n_constraints:
            cons.append({"type": "ineq", "fun": lambda u: ev.pulse_gradient(u)[0][1:],
                         "jac": lambda u: ev.pulse_gradient(u)[1][1:]})
        res = minimize(lambda u: float(ev.pulse_gradient(u)[0][0]), u0, jac=lambda u: ev.pulse_gradient(u)[1][0],
                       method="SLSQP", bounds=bounds, constraints=cons,
                       callback=lambda intermediate_result: history.append(float(intermediate_result.fun)),
                       # the objective's noise (the adaptive solves, ~1e-10 relative) bounds the precision
                       options={"maxiter": problem.max_iterations, "ftol": 1e-9})
    elif problem.needs_pulse:
        if problem.max_peak_g is not None or problem.max_peak_force is not None:
            cons.append(NonlinearConstraint(ev.pulse_constraints, 0.0, np.inf))
        res = minimize(ev.pulse_objective, u0, method="COBYQA", bounds=bounds, constraints=cons,
                       callback=lambda intermediate_result: history.append(float(intermediate_result.fun)),
                       options={"maxiter": problem.max_iterations, "initial_tr_radius": 0.1,
                                "final_tr_radius": 1e-8})
    else:
        def record(intermediate_result):  # the objective at each iterate, as scipy reports it (no new solve)
            history.append(float(intermediate_result.fun))

        if cons:
            res = minimize(fun, u0, jac=True, method="SLSQP", bounds=bounds, constraints=cons,
                           callback=record, options={"maxiter": problem.max_iterations, "ftol": 1e-14})
        else:
            # stop at the gradient's own accuracy: ~1e-9 relative by reverse mode, ~1e-5 by the batched
            # central differences (their noise, `_Evaluator.FD_STEP`); beyond it a line search only fails,
            # and each failure costs up to `maxls` evaluations
            gtol = 1e-9 if ev.gradient == "reverse mode" else 1e-6
            res = minimize(fun, u0, jac=True, method="L-BFGS-B", bounds=bounds, callback=record,
                           options={"maxiter": problem.max_iterations, "ftol": 1e-13, "gtol": gtol,
                                    "maxls": 20})
    return _Run(np.clip(res.x, 0, 1), float(res.fun), int(getattr(res, "nit", 0)), str(res.message),
                bool(res.success), history, int(getattr(res, "nfev", 0)))


class _Lockstep:
    """Gathers the objective calls of several local searches, each in its own thread, into one batched
    evaluation (`_Evaluator.values_and_grads`): the serving thread waits until every live search has
    asked for its next point, evaluates them together and hands each its result."""

    def __init__(self, ev: _Evaluator, size: int):
        import threading

        self.ev, self.live = ev, size
        self.pending: dict[int, np.ndarray] = {}
        self.results: dict[int, tuple] = {}
        self.closed = False
        self.cv = threading.Condition()

    def function(self, i: int):
        def fun(u):
            with self.cv:
                self.pending[i] = np.array(u, dtype=float)
                self.cv.notify_all()
                self.cv.wait_for(lambda: i in self.results or self.closed)
                if i not in self.results:  # the serving loop stopped (it raised): end this search too
                    raise RuntimeError("the batched evaluation of the starts stopped")
                return self.results.pop(i)
        return fun

    def finished(self) -> None:
        with self.cv:
            self.live -= 1
            self.cv.notify_all()

    def serve(self) -> None:
        """Serve rounds until every search has finished. If a round raises, every waiting search is
        released with an error (`closed`) before the exception propagates: no thread is left waiting."""
        try:
            while True:
                with self.cv:
                    self.cv.wait_for(lambda: self.live == 0 or len(self.pending) == self.live)
                    if self.live == 0:
                        return
                    batch, self.pending = self.pending, {}
                keys = sorted(batch)
                v, g = self.ev.values_and_grads(np.stack([batch[i] for i in keys]))
                with self.cv:
                    self.results.update({i: (float(v[j]), g[j]) for j, i in enumerate(keys)})
                    self.cv.notify_all()
        finally:
            with self.cv:
                self.closed = True
                self.cv.notify_all()


def _searches(space: _Space, ev: _Evaluator, problem: OptimizeSpec, starts: list) -> list[_Run]:
    """The local searches from every start. On the gradient path they run in lockstep: one scipy search
    per start in its own thread, every round of their objective calls one batched, compiled evaluation
    (`_Lockstep`), so `k` starts cost about one batched solve per iteration instead of `k` batched
    stencils. Only the gain path with batched central differences runs in lockstep; the reverse mode
    (one design at a time, `_Evaluator`), the pulse path (SLSQP asks for values, constraints and their
    derivatives separately; one stencil with histories per point) and the SRS path (COBYQA) run their
    starts one after another."""
    import threading

    if problem.needs_pulse or len(starts) < 2 or ev.width < 2:
        return [_local(space, ev, problem, u) for u in starts]
    lock = _Lockstep(ev, len(starts))
    runs: list = [None] * len(starts)
    errors: list = []

    def work(i, u0):
        try:
            runs[i] = _local(space, ev, problem, u0, fun=lock.function(i))
        except BaseException as exc:  # re-raised by the serving thread below
            errors.append(exc)
        finally:
            lock.finished()

    threads = [threading.Thread(target=work, args=(i, u), daemon=True) for i, u in enumerate(starts)]
    for t in threads:
        t.start()
    try:
        lock.serve()
    finally:
        for t in threads:
            t.join()
    if errors:
        raise errors[0]
    return runs


# ------------------------------------------------------------------------------------------ result
@dataclasses.dataclass(frozen=True)
class OptimizeResult:
    """The outcome of `optimize` (SI units).

    `status` (`OptimizeStatus`), `objective`, `objective_value` (the exact post-processor's at the best
    point: the negative gain, or the squared relative misses of the pulse), `variables` (label -> value),
    `report` (the `analysis.Report` of the best stack, simulated from `document()`), `start` and
    `rigid_designs` (name -> Report, the paper's MVG and MET stacks with the same end masses and contacts),
    `convergence` (per start: iterations, value, message, projected-gradient norm, active bounds;
    `starts_agree`; `history` of the best start), `evaluations` and `seconds`.
    """

    status: OptimizeStatus
    objective: str
    objective_value: float
    n: int
    variables: dict
    report: Any
    start: Any
    rigid_designs: dict
    convergence: dict
    evaluations: int
    seconds: float
    doc: dict = dataclasses.field(repr=False, default_factory=dict)
    source: str | None = None
    gaps: tuple[float, ...] = ()
    #: name -> why a design of `rigid_designs` could not be simulated (its value there is None)
    rigid_design_notes: dict = dataclasses.field(default_factory=dict)

    @property
    def masses(self) -> np.ndarray:
        return np.asarray(self.report.masses)

    @property
    def top_velocity_gain(self) -> float:
        return float(self.report.top_velocity_gain)

    def document(self) -> str:
        """The optimum as a stack file (TOML, without `[optimize]`)."""
        import tomli_w

        miss = self.convergence.get("pulse_misses")
        unmet = ("" if miss is None or self.convergence.get("pulse_target_met") else
                 f", pulse target NOT MET (peak g {100 * miss['peak_g']:+.3g} %, duration {100 * miss['duration']:+.3g} %)")
        head = (f"# Written by hertz-chain optimize{' from ' + self.source if self.source else ''}: objective "
                f"{self.objective!r}, status {self.status.text}{unmet}, top velocity gain {self.top_velocity_gain:.9g}.\n"
                "# Plain numbers are SI units (kg, m, N/m^1.5 or N/m, m/s).\n")
        return head + tomli_w.dumps(self.doc)

    def to_dict(self) -> dict:
        from .report import to_dict as report_dict

        def brief(rep):
            if rep is None:
                return None
            tp = rep.top_pulse
            return {"status": rep.status.text, "top_velocity_gain": rep.top_velocity_gain, "n": len(rep.masses),
                    "masses": rep.masses.tolist(),
                    "top_peak_g": None if tp is None else tp.peak / 9.80665,
                    "top_equivalent_half_sine_duration": None if tp is None else tp.equivalent_half_sine_duration}

        rep = report_dict(self.report)
        return {
            "status": self.status.text,
            "objective": self.objective,
            "objective_value": self.objective_value,
            "top_velocity_gain": self.top_velocity_gain,
            "n": self.n,
            "masses": self.masses.tolist(),
            "gaps": self._gaps(),
            "variables": self.variables,
            "top_pulse": rep.get("pulses", [None])[-1] if isinstance(rep.get("pulses"), list) else None,
            "start": brief(self.start),
            "rigid_designs": {k: brief(v) for k, v in self.rigid_designs.items()},
            "rigid_design_notes": dict(self.rigid_design_notes),
            "convergence": self.convergence,
            "evaluations": self.evaluations,
            "seconds": self.seconds,
        }

    def _gaps(self) -> list:
        """The n - 1 gaps (m) of the best stack."""
        return list(self.gaps)


def _set_interface(doc: dict, j: int, key: str, value: float) -> None:
    contact = doc.setdefault("contact", {})
    if j == 0:
        contact.setdefault("ground", {})[key] = value
        return
    entries = contact.setdefault("interface", [])
    for e in entries:
        idx = e.get("index")
        if idx == j:
            e[key] = value
            return
        if isinstance(idx, list) and j in idx:
            rest = [i for i in idx if i != j]
            e["index"] = rest if len(rest) > 1 else rest[0]
            entries.append({**e, "index": j, key: value})
            return
    entries.append({"index": j, key: value})


def _document(space: _Space, x: np.ndarray) -> dict:
    """The stack file of the design `x` (a copy of the file's document with the values written in)."""
    import copy

    doc = copy.deepcopy(space.doc)
    f = {k: np.asarray(v) for k, v in space.dm.fields(x).items()}
    stack = doc.setdefault("stack", {})
    varied = {(s.key, s.position) for s in space.slots}

    def entries(key, raw):
        # the user's own entries where they are not varied (units kept), the varied ones in the user's unit
        values = [float(v) for v in f[key]]
        if isinstance(raw, list) and len(raw) != len(values) or raw is None:
            return values
        raw = raw if isinstance(raw, list) else [raw] * len(values)
        return [_in_users_unit(r, v, KEYS[key].dimension) if (key, i) in varied else r
                for i, (r, v) in enumerate(zip(raw, values))]

    same_n = "design" not in stack and space.n == len(space.dm.base["stack.masses"])
    stack["masses"] = entries("stack.masses", stack.get("masses") if same_n else None)
    stack.pop("design", None)
    if any(s.key == "stack.gaps" for s in space.slots) or not same_n:
        stack["gaps"] = entries("stack.gaps", stack.get("gaps") if same_n else None)
    for s, v in zip(space.slots, x):
        if s.key in ("contact.stiffness", "contact.restitution"):
            _set_interface(doc, s.index, s.key.split(".")[1], float(v))
        elif s.key.startswith("drop."):
            drop = doc.setdefault("drop", {})
            name = s.key.split(".")[1]
            raw = drop.get(name)
            drop.pop("height", None)
            drop.pop("impact_velocity", None)
            drop[name] = _in_users_unit(raw, float(v), KEYS[s.key].dimension)
    return doc


def _in_users_unit(raw, value: float, dimension: str):
    """`value` (SI) in the unit of the user's entry `raw` (`"400 g"` -> `"316.228 g"`), or the plain SI
    number where `raw` was one or has no unit that converts."""
    from .units import parse_quantity

    match = re.fullmatch(r"\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*(\S.*?)\s*", raw) if isinstance(raw, str) else None
    if match is None:
        return value
    try:
        factor = parse_quantity(f"1 {match.group(1)}", dimension)
    except Exception:  # a unit this dimension does not take: SI
        return value
    return f"{value / factor:.15g} {match.group(1)}"


def _projected_gradient(ev: _Evaluator, u: np.ndarray) -> float:
    """The projected gradient's norm in the unit box (NaN where constraints other than the bounds
    apply, or on the derivative-free SRS path)."""
    p = ev.problem
    if p.objective == "srs" or ev.n_constraints or p.total_mass is not None:
        return math.nan
    g = ev.pulse_gradient(u)[1][0] if p.needs_pulse else ev.value_and_grad(u)[1]
    return float(np.linalg.norm(u - np.clip(u - g, 0.0, 1.0), ord=np.inf))


def _rigid_designs(space: _Space, best_masses: np.ndarray) -> tuple[dict, dict]:
    """The paper's MVG (Eq 15) and MET (Eq 25) stacks with the optimum's end masses, simulated under the
    same contacts (the file's, with the masses replaced): `(reports, notes)`, a report None where the design
    could not be simulated and the note says why."""
    from ._design import with_masses
    from .rigid import met_design, mvg_masses
    from .workflow import run_spec

    e = space.spec.contact.default.restitution
    m1, mn, n = float(best_masses[0]), float(best_masses[-1]), len(best_masses)
    out, notes = {}, {}
    if n < 2 or not mn < m1 or space.dm.chain:
        return out, notes
    designs = {"mvg": mvg_masses(mn / m1, n, m1)}
    if e is not None and e < 1:
        try:
            designs["met"] = np.asarray(met_design(mn / m1, e, m1=m1).masses)
        except Exception:
            pass
    for name, masses in designs.items():
        try:
            out[name] = run_spec(with_masses(space.spec, masses))
        except Exception as exc:  # e.g. the file's per-gap list does not fit the design's number of masses
            out[name], notes[name] = None, f"{len(masses)} masses: {exc}"
    return out, notes


def prepare(path: str | Path):
    """Every check of an optimisation file before any solve: `(spec, problem, spaces)`, one search
    space per number of masses. Raises `StackFileError` (one line)."""
    from .builder import design_masses

    spec, problem, doc = read_optimize_file(path)
    ns = problem.n or (len(design_masses(spec)),)
    try:
        return spec, problem, [_space(spec, doc, problem, n) for n in ns]
    except StackFileError as exc:  # (once: a message from building the stack may name the file already)
        text = str(exc)
        raise StackFileError(text if text.startswith(f"{path}: ") else f"{path}: {text}") from None


def optimize(path: str | Path) -> OptimizeResult:
    """Optimise the stack of the stack file `path` as its `[optimize]` section asks (module docstring).

    **Returns** an `OptimizeResult`. **Raises** `StackFileError` for a bad file or `[optimize]` section
    (one line), before any simulation; `SolverError` when the file's own stack does not complete (its
    `status` on the error).
    """
    from .workflow import run_spec

    t0 = time.perf_counter()
    spec, problem, spaces = prepare(path)
    # the file's own run first: a design judged by a run its solver settings cut short means nothing (a
    # review: with t_max inside the cascade, 22 s of search ended "failed" with gains of -1); a gapped stack
    # without gravity may stop at t_max by design (its best design is written with until = "launch", below)
    start = run_spec(spec)
    ended = start
    if start.status is Status.INCOMPLETE_T_MAX and spaces[0].dm.gravity <= 0:
        import copy

        doc = copy.deepcopy(spaces[0].doc)
        doc.setdefault("solver", {})["until"] = "launch"
        ended = run_spec(parse_stack(doc, source=str(path)))  # did the top's launch end before t_max?
    if not ended.status.ok:
        raise ended.status.error(f"{path}: the file's own stack", "the optimiser compares complete runs")
    ns = [sp.n for sp in spaces]
    best = None
    evaluators = []
    per_n: dict = {}  # the best of every number of masses tried (search values, before the exact re-run)
    for space in spaces:
        ev = _Evaluator(space, problem, width=problem.starts)
        u_file = space.to_u(space.dm.values())
        screened = _screen(space, ev, problem)
        starts = [u_file] + list(screened[: max(problem.starts - 1, 0)])
        runs = _searches(space, ev, problem, starts)
        evaluators.append(ev)
        for r in runs:  # a start that ends beyond a limit ranks after every start that meets them
            r.violation = _violation(ev, r.u)
        runs.sort(key=lambda r: (r.violation > _LIMIT_TOLERANCE, r.violation if r.violation > _LIMIT_TOLERANCE
                                 else 0.0, r.value))
        top = runs[0]
        per_n[str(space.n)] = {"objective_value": top.value, "starts": len(runs),
                               "masses": np.asarray(space.dm.fields(space.to_x(top.u))["stack.masses"]).tolist()}
        if best is None or (top.violation > _LIMIT_TOLERANCE, top.value) < (best[1][0].violation > _LIMIT_TOLERANCE,
                                                                           best[1][0].value):
            best = (space, runs, ev)
    space, runs, ev = best
    top = runs[0]
    x = np.asarray(space.to_x(top.u))
    doc_best = _document(space, x)
    report = run_spec(parse_stack(doc_best, source=str(path)))
    if report.status is Status.INCOMPLETE_T_MAX and space.dm.gravity <= 0:
        # the lower masses of a gapped stack without gravity may go on colliding long after the top's
        # launch is final: the written file stops there (`solver.until = "launch"`)
        doc_best.setdefault("solver", {})["until"] = "launch"
        report = run_spec(parse_stack(doc_best, source=str(path)))
    rigid, rigid_notes = _rigid_designs(space, np.asarray(report.masses))
    pg = _projected_gradient(ev, top.u)  # NaN on the derivative-free path (None in the JSON)
    agree = sum(abs(r.value - top.value) <= 1e-6 * max(abs(top.value), 1e-2) for r in runs)
    active = [s.label + (" (lower)" if ui <= 1e-9 else " (upper)") for s, ui in zip(space.slots, top.u)
              if ui <= 1e-9 or ui >= 1 - 1e-9]
    extra = {}
    if problem.objective == "gain":
        value = -report.top_velocity_gain
    else:
        mt = ev.metrics(top.u)
        value = _objective(problem, mt) if mt["ok"] else math.inf
        if problem.objective == "pulse" and mt["ok"]:
            misses = {"peak_g": mt["peak_g"] / problem.target_peak_g - 1.0,
                      "duration": mt["duration"] / problem.target_duration - 1.0}
            extra = {"pulse_misses": {k: float(v) for k, v in misses.items()},
                     "pulse_target_met": bool(max(abs(v) for v in misses.values()) <= PULSE_TARGET_TOLERANCE)}
        if problem.objective == "srs" and mt["ok"]:
            err = mt["srs_error_db"]
            extra = {"srs_max_error_db": float(np.max(np.abs(err))),
                     "srs_within_tolerance": bool(np.max(np.abs(err)) <= problem.srs_tolerance_db)}
    # every limit at the best point: its value and whether it binds (within 1e-3 of it) or is broken
    limits = {}
    if ev.n_constraints or problem.total_mass is not None:
        ml = ev.metrics(top.u, count=False) if ev.n_constraints else {"ok": False}
        for name, lim, val in (("max_peak_g", problem.max_peak_g, ml.get("peak_g") if ml["ok"] else None),
                               ("max_peak_force", problem.max_peak_force, ml.get("peak_force") if ml["ok"] else None),
                               ("total_mass", problem.total_mass,
                                float(ev._mass(top.u)[0]) if problem.total_mass is not None else None)):
            if lim is not None and val is not None:
                limits[name] = {"limit": float(lim), "value": float(val),
                                "state": ("broken" if val > lim * (1 + _LIMIT_TOLERANCE) else
                                          "active" if val >= lim * (1 - 1e-3) else "inactive")}
    # a line search that can make no more progress at a point whose projected gradient vanishes (to the
    # gradient's own accuracy, ~1e-6 relative) has converged too (L-BFGS-B reports it as "ABNORMAL")
    stationary = math.isfinite(pg) and pg <= PG_TOLERANCE * max(1.0, abs(top.value))
    status = OptimizeStatus.CONVERGED if (top.success or stationary) else OptimizeStatus.NOT_CONVERGED
    message = str(top.message).strip().rstrip(":")
    if message.upper().startswith("ABNORMAL"):  # scipy's L-BFGS-B says only "ABNORMAL: " (a review)
        message = ("the line search made no progress (L-BFGS-B: ABNORMAL) with the projected gradient still at "
                   f"{pg:.3g}: the objective or its gradient is not smooth or accurate enough there; tighter "
                   "[solver] tolerances, other bounds or more starts may help")
    why = "" if status.ok else f"the search stopped: {message}"
    if top.violation > _LIMIT_TOLERANCE:
        status = OptimizeStatus.NOT_CONVERGED
        broken = ", ".join(f"{k} {v['value']:.6g} over {v['limit']:.6g}" for k, v in limits.items()
                           if v["state"] == "broken")
        why = (f"no start found a design within the limits: the best breaks them by {top.violation:.3g} "
               f"(relative excess over the limit{': ' + broken if broken else ''})")
    if extra.get("srs_within_tolerance") is False:
        status = OptimizeStatus.NOT_CONVERGED
        why = (f"the best SRS found misses the target by up to {extra['srs_max_error_db']:.2f} dB, beyond "
               f"±{problem.srs_tolerance_db:g} dB")
    if not report.status.ok or not math.isfinite(value):
        status = OptimizeStatus.FAILED
        why = f"the best design could not be simulated ({report.status.text})"
    # the file's values outside their bounds: the search starts from the nearest bound (a review: silent)
    file_values = np.asarray(space.dm.values(), dtype=float)
    outside = [f"{sl.label} = {v:.6g} (the file's) lies outside its bounds [{lo:.6g}, {hi:.6g}] (SI units): "
               "the search started from the nearest bound"
               for sl, v, lo, hi in zip(space.slots, file_values, space.lo, space.hi) if not lo <= v <= hi]
    convergence = {
        "start_outside_bounds": outside,
        "method": ("COBYQA" if problem.objective == "srs" else
                   "SLSQP" if problem.total_mass or problem.needs_pulse else "L-BFGS-B"),
        "gradient": (None if problem.objective == "srs" else
                     "batched central differences" if problem.needs_pulse else ev.gradient),
        "starts": [{"value": r.value, "iterations": r.iterations, "evaluations": r.evaluations,
                    "limit_excess": r.violation,
                    "message": r.message, "success": r.success} for r in runs],
        "starts_agree": f"{agree} of {len(runs)} within 1e-6 (relative, at least 1e-8 absolute) of the best",
        "iterations": top.iterations,
        "projected_gradient_norm": pg if math.isfinite(pg) else None,
        "active_bounds": active,
        "limits": limits,
        "history": top.history,
        "n_tried": list(ns),
        "per_n": per_n,
        "why": why,
        **extra,
    }
    return OptimizeResult(
        status=status, objective=problem.objective, objective_value=float(value), n=space.n,
        variables={s.label: float(v) for s, v in zip(space.slots, x)}, report=report, start=start,
        rigid_designs=rigid, rigid_design_notes=rigid_notes, convergence=convergence, evaluations=sum(e.count for e in evaluators),
        seconds=time.perf_counter() - t0, doc=doc_best, source=str(path),
        gaps=tuple(float(g) for g in np.asarray(space.dm.fields(x)["stack.gaps"])),
    )
