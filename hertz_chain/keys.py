"""The key vocabulary: how a stack-file key and an index name one number of a design.

Stack files, `[[optimize.vary]]` (`hertz_chain.optimization`) and, later, sweep axes and `--set KEY=VALUE`
name a parameter the same way: a dotted stack-file key and, for the per-body keys, an index

- `stack.masses`: mass numbers, 1 at the bottom to n at the top;
- `stack.gaps`: gap numbers, gap j between mass j and mass j+1 (1..n-1);
- `contact.stiffness`, `contact.restitution`: interface numbers, 0 = ground–mass 1, j = mass j – mass
  j+1 (a per-interface override, as `[[contact.interface]]` and `[contact.ground]` are in a file);
- `drop.impact_velocity`, `drop.height`: no index.

`KEYS` is the table (one row per key: its dimension, what its index counts, whether the search runs
in log space); `resolve` turns a key and an index into `Slot`s and refuses, in one line naming the
key, the value and what is allowed, an unknown key or an index out of range. Plain Python: the
command line reads it while checking a file, before JAX is imported.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass

from ._stackspec import MIN_RESTITUTION
from .errors import StackFileError
from .units import LIMITS

__all__ = ["KeyRow", "KEYS", "Slot", "resolve", "read_entry", "read_bounds", "dimension", "allowed_values",
           "valid_values", "check_values", "check_design_follows"]


@dataclass(frozen=True)
class KeyRow:
    """One numeric stack-file key that a design may vary.

    `dimension`: a `stackfile` dimension name (`"stiffness"`: the interface's law decides, N/m^1.5 or
    N/m); `over`: what its index counts (`"mass"`, `"gap"`, `"interface"`, or `None` for a scalar);
    `log`: searched in log space (a positive scale quantity spanning decades); `positive`: > 0 (else
    >= 0); `lower`, `upper`: the smallest and largest values allowed (inclusive)."""

    key: str
    dimension: str
    over: str | None
    log: bool = False
    positive: bool = True
    upper: float | None = None
    lower: float | None = None


KEYS: dict[str, KeyRow] = {row.key: row for row in (
    KeyRow("stack.masses", "mass", "mass", log=True),
    KeyRow("stack.gaps", "length", "gap", positive=False),
    KeyRow("contact.stiffness", "stiffness", "interface", log=True),
    KeyRow("contact.restitution", "dimensionless", "interface", upper=1.0, lower=MIN_RESTITUTION),
    KeyRow("drop.impact_velocity", "velocity", None),
    KeyRow("drop.height", "length", None),
)}
"""The keys a design may vary, by dotted name (see `KeyRow`)."""


@dataclass(frozen=True, order=True)
class Slot:
    """One number of a design: `key` and `index` (None for a scalar key), as in `KEYS`."""

    key: str
    index: int | None = None

    @property
    def position(self) -> int | None:
        """The 0-based position in the key's array: mass and gap numbers count from 1, interfaces from
        0 (the ground)."""
        if self.index is None:
            return None
        return self.index if KEYS[self.key].over == "interface" else self.index - 1

    @property
    def label(self) -> str:
        """`stack.masses[2]`, `drop.impact_velocity`."""
        return self.key if self.index is None else f"{self.key}[{self.index}]"


def _allowed(over: str, n: int, ground: bool) -> range:
    if over == "mass":
        return range(1, n + 1)
    if over == "gap":
        return range(1, n)
    return range(0 if ground else 1, n)


def resolve(key: object, index: object, *, n: int, ground: bool, where: str = "key",
            default: tuple[int, ...] | None = None) -> tuple[Slot, ...]:
    """The slots named by `key` and `index` in a stack of `n` masses (with or without the ground).

    **Arguments:** `key`, a name of `KEYS`; `index`, an int, a list of ints or None (every entry, or
    `default` when given); `where`, the dotted path for messages.

    **Returns** a tuple of `Slot`s, in the order given. **Raises** `StackFileError` (one line) for an
    unknown key, an index on a scalar key, an index out of range or repeated.
    """
    if not isinstance(key, str) or key not in KEYS:
        close = difflib.get_close_matches(str(key), list(KEYS), n=1, cutoff=0.6)
        hint = f"did you mean '{close[0]}'?" if close else f"allowed: {', '.join(KEYS)}"
        raise StackFileError(f"{where}: {key!r} is not a key a design can vary; {hint}")
    row = KEYS[key]
    if row.over is None:
        if index is not None:
            raise StackFileError(f"{where}: {key} is a single number; give no index")
        return (Slot(key),)
    allowed = _allowed(row.over, n, ground)
    if index is None:
        index = list(default) if default is not None else list(allowed)
    items = index if isinstance(index, list) else [index]
    if not items:
        raise StackFileError(f"{where}.index: empty; give {row.over} numbers {allowed.start}..{allowed.stop - 1}")
    seen = []
    for i in items:
        if isinstance(i, bool) or not isinstance(i, int):
            raise StackFileError(f"{where}.index: {i!r} is invalid: an integer {row.over} number (or a list of them)")
        if i not in allowed:
            what = f"{row.over} numbers {allowed.start}..{allowed.stop - 1}" if len(allowed) else f"no {row.over}s"
            extra = " (interface 0 is the ground, which this stack has not)" if row.over == "interface" and i == 0 else ""
            raise StackFileError(f"{where}.index: {i!r} is out of range for {key} of this {n}-mass stack; "
                                 f"allowed: {what}{extra}")
        if i in seen:
            raise StackFileError(f"{where}.index: {i} is given twice")
        seen.append(i)
    return tuple(Slot(key, i) for i in seen)


def read_entry(item: object, where: str, allowed: tuple[str, ...], example: str) -> dict:
    """Check one `[[optimize.vary]]` / `[[sweep.axis]]` table: a table, only `allowed` keys, a `key`.
    Raises `StackFileError` (one line)."""
    if not isinstance(item, dict):
        raise StackFileError(f"{where}: expected a table, got {item!r}")
    for k in item:
        if k not in allowed:
            raise StackFileError(f"{where}.{k}: unknown key; allowed: {', '.join(allowed)}")
    if "key" not in item:
        raise StackFileError(f"{where}.key: missing; the stack-file key, e.g. '{example}'")
    return item


def dimension(spec, key: str, index: object, where: str = "key") -> str:
    """The `stackfile` dimension of `key` in the file `spec` (`quantity_of`)."""
    return quantity_of(spec, key, index, where)[0]


def check_design_follows(spec, key: str, index, where: str) -> None:
    """Refuse a sweep axis on `contact.restitution` of every interface (`index` None) where the file's
    `[stack.design]` takes its restitution from it and its masses depend on it (an MET design, Eq 25; an
    optimal n, Eqs 22-24): `simulate --set contact.restitution=...` redesigns the masses for each e, a
    vectorised design cannot, and would keep those of the file's e. One interface's e (`index`) leaves
    the design as it is, in `simulate` too; optimize and fit keep the masses fixed by design (a fitted or
    optimised stack's masses are written out). **Raises** `StackFileError` (one line, at `where`)."""
    d = getattr(spec.stack, "design", None)
    if (key != "contact.restitution" or index is not None or d is None or d.restitution_given
            or (d.kind != "met" and d.n is not None)):
        return
    how = "an MET design's masses follow from e (Eq 25)" if d.kind == "met" else \
        "the optimal number of masses follows from e (Eqs 22-24)"
    raise StackFileError(f"{where}: contact.restitution cannot vary here: [stack.design] takes its restitution "
                         f"from it, and {how}; the masses would stay those of e = {d.restitution:g} while "
                         "simulate --set redesigns them. Give stack.design.restitution (the masses then stay "
                         "fixed while the contacts' e varies), or run one file per e")


def quantity_of(spec, key: str, index: object, where: str = "key") -> tuple[str, float | None]:
    """The `stackfile` dimension of `key` in the file `spec` and, for a power law's stiffness (N/m^p), its
    exponent p (else None). A stiffness is N/m^1.5, N/m or N/m^p by the law of the interfaces named,
    which must agree. **Raises** `StackFileError` (one line, at `where`) for interfaces whose laws take
    the stiffness in different units (give `index` naming interfaces of one)."""
    from .registry import LAWS

    dim = KEYS[key].dimension
    if dim != "stiffness":
        return dim, None
    if spec.n is None:  # the number of masses is left open (`optimize.n`): the first interface named
        idx = index if isinstance(index, list) else [index]
        interfaces = [next((i for i in idx if isinstance(i, int) and not isinstance(i, bool)), 1)]
    else:
        interfaces = [slot.index for slot in resolve(key, index, n=spec.n, ground=spec.has_ground, where=where)]
    kinds: dict = {}
    for j in interfaces:
        contact = spec.contact_for(j)
        unit = LAWS[contact.law].stiffness
        p = dict(contact.params).get("exponent") if unit == "power_stiffness" else None
        kinds.setdefault((unit, p), []).append(f"{contact.law} at {j}")
    if len(kinds) > 1:
        shown = "; ".join(f"{_STIFFNESS_UNIT.get(u, u).replace('p', f'{p:g}') if p else _STIFFNESS_UNIT.get(u, u)}"
                          f" for {', '.join(where_)}" for (u, p), where_ in kinds.items())
        raise StackFileError(f"{where}: {key} names interfaces whose laws take the stiffness in different units "
                             f"({shown}); give index = [...] naming interfaces of one unit")
    ((unit, p),) = kinds
    return unit, p


_STIFFNESS_UNIT = {"hertz_stiffness": "N/m^1.5", "linear_stiffness": "N/m", "power_stiffness": "N/m^p"}


def read_bounds(raw: object, dim: str, where: str, exponent: float | None = None) -> tuple[float, float]:
    """`[lower, upper]` with units -> SI floats, lower < upper (`exponent`: a power law's p, for its
    stiffness in N/m^p). Raises `StackFileError`."""
    from .units import parse_quantity

    if raw is None:
        raise StackFileError(f"{where}: missing; give [lower, upper] with units")
    if not isinstance(raw, list) or len(raw) != 2:
        raise StackFileError(f"{where}: {raw!r} is invalid: two values [lower, upper] with units")
    lo, hi = (parse_quantity(b, dim, where, exponent=exponent) for b in raw)
    if not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
        raise StackFileError(f"{where}: {raw!r} is invalid: the lower bound must be below the upper")
    return lo, hi


def allowed_values(key: str, gravity: float | None = None) -> str:
    """What `key` may be, for messages: `> 0`, `>= 0`, `>= 0.001 and <= 1`; a drop height's limit
    with `gravity` (m/s²)."""
    row = KEYS[key]
    base = f">= {row.lower:g}" if row.lower is not None else "> 0" if row.positive else ">= 0"
    if key == "drop.height" and gravity:
        v_max = LIMITS["velocity"][1]
        return (f"{base} and at most {v_max ** 2 / (2 * gravity):.6g} m (a fall from it reaches at most {v_max:g} "
                f"m/s, sqrt(2 g h))")
    return base + (f" and <= {row.upper:g}" if row.upper is not None else "")


def valid_values(key: str, values, gravity: float | None = None):
    """Elementwise: whether `values` (SI, a number or a numpy array) are allowed for `key` (`KeyRow`:
    finite, > 0 or >= 0, within `lower` and `upper`; a drop height, with `gravity` (m/s²), no higher
    than a fall reaching the largest speed a stack file takes, as `drop.height` itself)."""
    import numpy as np

    row = KEYS[key]
    v = np.asarray(values, dtype=float)
    ok = np.isfinite(v) & ((v > 0) if row.positive else (v >= 0))
    if row.upper is not None:
        ok &= v <= row.upper
    if row.lower is not None:
        ok &= v >= row.lower
    if key == "drop.height" and gravity:
        ok &= np.sqrt(2.0 * gravity * np.where(ok, v, 0.0)) <= LIMITS["velocity"][1]
    return ok


def check_values(key: str, values, where: str, shown=None, gravity: float | None = None) -> None:
    """Raise `StackFileError` (one line) unless every value is allowed for `key` (`valid_values`)."""
    import numpy as np

    ok = valid_values(key, values, gravity)
    if not np.all(ok):
        bad = np.asarray(values, dtype=float).reshape(-1)[~ok.reshape(-1)][0]
        raise StackFileError(f"{where}: {shown if shown is not None else repr(float(bad))} is invalid: {key} must be "
                             f"{allowed_values(key, gravity)}")
