"""Stack files: TOML with units → a validated, declarative `StackSpec`.

`load_stack_file(path)` reads a file and `parse_stack(text_or_dict)` takes TOML text or a parsed
`dict`; both return a frozen `StackSpec` of plain SI floats, strings and tuples (no pint objects, no
JAX). Every problem raises `StackFileError` with one line naming the dotted key and the problem. The
user manual of the format, every key with its units, default and bounds, is `docs/stack-files.md`
(`tests/test_stackfile.py` checks that every key this parser accepts is documented there); the
vocabularies (laws, chi maps, solvers) are the tables of `hertz_chain.registry`.

Conventions (`notes/CONVENTIONS.md`): masses bottom first; interface 0 is ground–mass 1, interface
*j* is mass *j* – mass *j+1*; SI units inside, pint only here at the edge.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from .constants import MAX_MASSES, STANDARD_GRAVITY
from .errors import StackFileError
from .units import _UNITS, LIMITS, MAX_QUANTITY_LENGTH, _error, _show, parse_quantity  # noqa: F401  (re-exported)
from .registry import CHI_MAPS as _CHI_MAP_ROWS
from .registry import LAWS
from .registry import SOLVERS as _SOLVER_ROWS

__all__ = [
    "parse_srs_table",
    "STANDARD_GRAVITY",
    "MAX_MASSES",
    "MAX_STEPS",
    "MAX_OUTPUT_POINTS",
    "MIN_DT_OUTPUT",
    "MIN_RESTITUTION",
    "MAX_QUANTITY_LENGTH",
    "MAX_FILE_BYTES",
    "LIMITS",
    "DAMPING_LIMITS",
    "CONTACT_LAWS",
    "CHI_MAPS",
    "SOLVERS",
    "DESIGN_KINDS",
    "SHAPES",
    "MaterialSpec",
    "DesignSpec",
    "BodiesSpec",
    "DropSpec",
    "GroundSpec",
    "ContactSpec",
    "ContactsSpec",
    "SolverSpec",
    "StackSpec",
    "load_stack_file",
    "parse_stack",
    "parse_quantity",
]


# ---- bounds (the "Physical ranges and sizes" section of docs/stack-files.md)
MAX_STEPS = 10_000_000
"""Largest `solver.max_steps`: the solver keeps buffers of `max_steps` rows."""
MAX_RUN_MEMORY = 4 * 2**30
"""Largest step history a stack file may ask for (bytes, `run_memory`): 4 GiB."""


def run_memory(n: int, max_steps: int) -> int:
    """Bytes of the step history `simulate` keeps for `n` masses and `max_steps` steps: the scaled state
    (`3n` physical, `n` onset proxies, one flag) and the time of every step, float64, plus the
    derived quantities of the used rows (positions, velocities, accelerations, overlaps, rates,
    forces, dissipation: `7n`)."""
    return 8 * (max_steps + 1) * ((4 * n + 2) + 7 * n)


MAX_OUTPUT_POINTS = 1_000_000
"""Largest `solver.n_output`, and largest `solver.t_max / solver.dt_output`."""
MIN_DT_OUTPUT = 1e-7
"""Smallest `solver.dt_output` (s) when `solver.t_max` is not given (the run's length is not known here)."""
MIN_RESTITUTION = 1e-3
"""Smallest restitution (the calibration of the contact laws supports 0.001 <= e <= 1)."""
MAX_FILE_BYTES = 10_000_000
"""Largest stack file (bytes) that `load_stack_file` reads."""
# the vocabularies: one table each in `hertz_chain.registry`
CONTACT_LAWS = tuple(LAWS)
CHI_MAPS = tuple(_CHI_MAP_ROWS)
SOLVERS = tuple(_SOLVER_ROWS)

DAMPING_LIMITS = {name: (row.damping_max, f" {_UNITS[row.damping_dimension]}" if row.damping_dimension in _UNITS
                         else "") for name, row in LAWS.items() if row.damping == "damping"}
"""Largest `damping` per law (`registry.LawRow.damping_max`): Tsuji's eta (plain), Kelvin-Voigt's c
(N s/m), the viscoelastic A (s)."""
DESIGN_KINDS = ("mvg", "met")
SHAPES = ("sphere", "flat")

_TOP_KEYS = ("title", "drop", "stack", "ground", "wall", "contact", "materials", "solver", "optimize", "sweep",
             "test", "srs", "fit")
_WALL_KEYS = ("material", "stiffness", "gap")
_SRS_KEYS = ("q", "damping", "per_octave", "band", "peak", "type")
#: Where an SRS band may lie (Hz), and its largest f_max/f_min: the filters run at 50 samples per cycle of
#: f_max and pad the record by a cycle of f_min, so the work grows as f_max/f_min (5 decades: 5e6
#: samples per frequency), and the pseudo-velocity's discretisation is checked to fs/f = 1e5 (docs).
SRS_BAND_LIMITS = (0.01, 1e7)
SRS_MAX_SPAN = 1e5
# `optimize`, `sweep`, `test` and `fit` are read by `hertz_chain.optimize`, `hertz_chain.sweep`,
# `hertz_chain.standards` and `hertz_chain.fit` (docs/optimize.md, docs/sweeps.md,
# docs/lab-workflow.md); simulating such a file runs its base stack
_DROP_KEYS = ("ground", "impact_velocity", "height", "gravity")
_STACK_KEYS = ("masses", "design", "gaps", "velocities", "preload", "end_force", "material", "radius", "shape")
_DESIGN_KEYS = ("kind", "n", "restitution", "bottom_mass", "top_mass", "mass_ratio")
_GROUND_KEYS = ("material", "shape", "radius")
_MATERIAL_KEYS = ("youngs_modulus", "poisson_ratio", "density", "yield_strength")
_CONTACT_KEYS = (
    "law",
    "stiffness",
    "restitution",
    "chi_map",
    "calibration_velocity",
    "alpha",
    "damping",
    "clamp",
) + tuple(dict.fromkeys(key for row in LAWS.values() for key, _ in row.params))  # e.g. thornton's yield_pressure
_SOLVER_KEYS = ("solver", "rtol", "atol", "t_max", "until", "max_steps", "n_output", "dt_output")
#: `solver.until`: stop when the first cascade ends, or go on to `t_max` and report rebounds.
UNTIL = ("cascade", "t_max", "launch")


# --------------------------------------------------------------------------------------------------
# The spec: frozen dataclasses of plain SI floats, strings and tuples
# --------------------------------------------------------------------------------------------------


def _expand(value: Any, count: int, what: str) -> tuple:
    """A single value repeated `count` times, or a tuple checked to have `count` entries."""
    if isinstance(value, tuple):
        if len(value) != count:
            raise ValueError(f"{what} has {len(value)} entries, expected {count}")
        return value
    return (value,) * count


@dataclass(frozen=True)
class MaterialSpec:
    """A material defined in the file (`[materials.NAME]`).

    `youngs_modulus` in Pa, `poisson_ratio` dimensionless, `density` in kg/m³ (or `None`),
    `yield_strength` in Pa (or `None`).
    """

    name: str
    youngs_modulus: float
    poisson_ratio: float
    density: float | None = None
    yield_strength: float | None = None


@dataclass(frozen=True)
class DesignSpec:
    """An MVG (seed paper Eq 15) or MET (Eq 25) design, left for the rigid module to compute.

    `n` is `None` for `"optimal"`. Masses in kg; `mass_ratio` is R = m_n/m_1. For MVG all three of
    `bottom_mass`, `top_mass`, `mass_ratio` are filled in (two given, the third derived); for MET
    with an integer `n` exactly one of `bottom_mass`/`top_mass` is set and `mass_ratio` is `None`.
    """

    kind: str
    n: int | None
    restitution: float
    bottom_mass: float | None = None
    top_mass: float | None = None
    mass_ratio: float | None = None


@dataclass(frozen=True)
class BodiesSpec:
    """The masses and their per-body properties (`[stack]`).

    Exactly one of `masses` (kg, bottom first) and `design` is set. Per-body and per-gap values are
    a single value (the same for all; always so when the number of masses is not known yet) or a
    tuple with one entry per mass (per gap for `gaps`, n−1 entries); use the `*_list(n)` methods to
    get tuples. `gaps` in m; `velocities` in m/s, upward-positive, or `None`; `end_force` in N (a
    constant force on the top mass toward mass 1; `preload` then defaults to true); `radius` in m
    (`inf` for a flat face) or `None`; `shape` `"sphere"`/`"flat"` or `None`; `material` names or
    `None`.
    """

    masses: tuple[float, ...] | None
    design: DesignSpec | None
    gaps: float | tuple[float, ...]
    velocities: tuple[float, ...] | None = None
    preload: bool = False
    material: str | tuple[str, ...] | None = None
    radius: float | tuple[float, ...] | None = None
    shape: str | tuple[str, ...] | None = None
    end_force: float = 0.0

    @property
    def n(self) -> int | None:
        """The number of masses, or `None` while an `"optimal"` design leaves it open."""
        if self.masses is not None:
            return len(self.masses)
        return self.design.n if self.design is not None else None

    def gap_list(self, n: int) -> tuple[float, ...]:
        """The n−1 gaps (m) between masses j and j+1, j = 1..n−1."""
        return _expand(self.gaps, n - 1, "stack.gaps")

    def radius_list(self, n: int) -> tuple[float, ...] | None:
        """The n cap radii (m; `inf` = flat), or `None` when no geometry was given."""
        return None if self.radius is None else _expand(self.radius, n, "stack.radius")

    def shape_list(self, n: int) -> tuple[str, ...] | None:
        """The n shapes, or `None` when no geometry was given."""
        return None if self.shape is None else _expand(self.shape, n, "stack.shape")

    def material_list(self, n: int) -> tuple[str, ...] | None:
        """The n material names, or `None` when no material was given."""
        return None if self.material is None else _expand(self.material, n, "stack.material")


@dataclass(frozen=True)
class DropSpec:
    """`[drop]`: `gravity` in m/s² (≥ 0, acting downward); `impact_velocity` in m/s, the positive
    downward speed at first ground contact (`None` when `stack.velocities` sets the state, or
    without a ground); `height` in m when the file gave one (`impact_velocity` = √(2 g h))."""

    gravity: float
    impact_velocity: float | None = None
    height: float | None = None


@dataclass(frozen=True)
class GroundSpec:
    """`[ground]`: `material` name (`None`: rigid), `shape`, `radius` in m (`inf` when flat)."""

    material: str | None = None
    shape: str = "flat"
    radius: float = math.inf


@dataclass(frozen=True)
class ContactSpec:
    """One resolved contact law (defaults and inheritance already applied), SI units.

    `stiffness` is N/m^1.5 for the Hertzian laws and N/m for `kelvin-voigt`; `None` means "compute
    it from materials and geometry". Damping is one of `restitution` (with `chi_map` and an optional
    `calibration_velocity` in m/s), `alpha` (s/m, hunt-crossley) or `damping` (tsuji η, plain;
    kelvin-voigt c, N s/m; viscoelastic A, s); all `None` for `hertz`. `source` is the dotted key of
    the section that defined it (for error messages at build time).
    """

    law: str
    stiffness: float | None = None
    restitution: float | None = None
    chi_map: str | None = None
    calibration_velocity: float | None = None
    alpha: float | None = None
    damping: float | None = None
    clamp: bool = True
    source: str = "contact"
    params: tuple[tuple[str, float], ...] = ()  # the law's further keys (`registry.LawRow.params`), in SI


@dataclass(frozen=True)
class ContactsSpec:
    """The contact of every interface: `default` (`[contact]`), `ground` (interface 0: the
    `[contact.ground]` override or the default; `None` without a ground) and `overrides`, pairs
    `(j, ContactSpec)` sorted by j, from `[[contact.interface]]`."""

    default: ContactSpec
    ground: ContactSpec | None = None
    overrides: tuple[tuple[int, ContactSpec], ...] = ()

    def interface(self, j: int) -> ContactSpec:
        """The contact of interface `j` (0 = ground–mass 1, j = mass j – mass j+1)."""
        if j == 0:
            if self.ground is None:
                raise ValueError("this stack has no ground, so no interface 0")
            return self.ground
        for index, spec in self.overrides:
            if index == j:
                return spec
        return self.default


@dataclass(frozen=True)
class SolverSpec:
    """`[solver]`; `None` leaves the simulator's default. `t_max`, `dt_output` in s."""

    solver: str = "tsit5"
    rtol: float | None = None
    atol: float | None = None
    t_max: float | None = None
    max_steps: int | None = None
    n_output: int | None = None
    dt_output: float | None = None
    until: str = "cascade"


@dataclass(frozen=True)
class SRSSpec:
    """`[srs]`: how the report's SRS of the top pulse is computed (`hertz_chain.srs.SRSOptions`).
    `band` in Hz, or None for the default band."""

    q: float = 10.0
    per_octave: int = 12
    band: tuple[float, float] | None = None
    peak: str = "abs"
    type: str = "acceleration"


@dataclass(frozen=True)
class WallSpec:
    """`[wall]`: a rigid flat wall beyond the top mass (the far end of a chain between two walls), whose
    contact with the top mass is elastic Hertz: `stiffness` in N/m^1.5, or `None` to compute it from
    `material` (the wall's) and the top mass's material and radius; `gap` in m between the top mass and
    the wall at the start (`None`: touching, or with `stack.end_force` the precompressed equilibrium)."""

    material: str | None = None
    stiffness: float | None = None
    gap: float | None = None


@dataclass(frozen=True)
class StackSpec:
    """A whole stack file, validated, in SI units. `ground` is `None` for a chain without ground."""

    drop: DropSpec
    stack: BodiesSpec
    contact: ContactsSpec
    ground: GroundSpec | None = GroundSpec()
    solver: SolverSpec = SolverSpec()
    materials: tuple[MaterialSpec, ...] = ()
    title: str | None = None
    source: str | None = None
    srs: SRSSpec = SRSSpec()
    wall: WallSpec | None = None

    @property
    def n(self) -> int | None:
        """Number of masses (`None` for an `"optimal"` design, decided by the rigid module)."""
        return self.stack.n

    @property
    def has_ground(self) -> bool:
        return self.ground is not None

    def contact_for(self, j: int) -> ContactSpec:
        """The contact law of interface `j` (see `ContactsSpec.interface`)."""
        return self.contact.interface(j)

    def material(self, name: str) -> MaterialSpec | None:
        """The material `name` if the file defines it in `[materials]`, else `None`."""
        for m in self.materials:
            if m.name == name:
                return m
        return None

    def initial_velocities(self, n: int | None = None) -> tuple[float, ...]:
        """Upward-positive initial velocities (m/s): `stack.velocities`, or −impact_velocity for
        every mass of a dropped stack. `n` is needed only when the spec leaves it open."""
        if self.stack.velocities is not None:
            return self.stack.velocities
        n = self.n if n is None else n
        if n is None:
            raise ValueError("the number of masses is not known yet: pass n")
        return (-float(self.drop.impact_velocity),) * n


# --------------------------------------------------------------------------------------------------
# Errors and low-level readers
# --------------------------------------------------------------------------------------------------


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _table(raw: Any, path: str, allowed: tuple[str, ...]) -> dict:
    """Check that `raw` is a table with only `allowed` keys (suggesting the closest one)."""
    if not isinstance(raw, Mapping):
        raise _error(path, f"expected a table ([{path}]), got {_show(raw)}")
    for key in raw:
        if key not in allowed:
            close = difflib.get_close_matches(str(key), allowed, n=1, cutoff=0.6)
            hint = f"did you mean '{close[0]}'?" if close else f"allowed: {', '.join(allowed)}"
            raise _error(_join(path, str(key)), f"unknown key; {hint}")
    return dict(raw)


def _check(ok: bool, key: str, raw: Any, requirement: str) -> None:
    if not ok:
        raise _error(key, f"{_show(raw)} is invalid: {requirement}")


def _positive(raw: Any, key: str, dim: str, *, allow_inf: bool = False) -> float:
    value = parse_quantity(raw, dim, key, allow_inf=allow_inf)
    _check(value > 0, key, raw, "must be > 0")
    return value


def _non_negative(raw: Any, key: str, dim: str) -> float:
    value = parse_quantity(raw, dim, key)
    _check(value >= 0, key, raw, "must be >= 0")
    return value


def _choice(raw: Any, key: str, choices: tuple[str, ...]) -> str:
    if not isinstance(raw, str) or raw.strip().lower() not in choices:
        close = difflib.get_close_matches(str(raw).lower(), choices, n=1, cutoff=0.6)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise _error(key, f"{_show(raw)} is not one of {', '.join(repr(c) for c in choices)}{hint}")
    return raw.strip().lower()


def _bool(raw: Any, key: str) -> bool:
    if not isinstance(raw, bool):
        raise _error(key, f"{_show(raw)} is not a boolean; expected true or false")
    return raw


def _int(raw: Any, key: str, minimum: int, maximum: int | None = None, why: str = "") -> int:
    given = raw
    if isinstance(raw, bool) or not isinstance(raw, int):
        if isinstance(raw, float) and raw.is_integer():
            raw = int(raw)
        else:
            raise _error(key, f"{_show(raw)} is not an integer")
    _check(raw >= minimum, key, given, f"must be an integer >= {minimum}")
    if maximum is not None:
        _check(raw <= maximum, key, given, f"must be an integer between {minimum} and {maximum:_}{why}")
    return raw


def _name(raw: Any, key: str) -> str:
    if not isinstance(raw, str) or not raw.strip():
        raise _error(key, f"{_show(raw)} is not a name; expected a non-empty string")
    return raw.strip()


def _per_item(raw: Any, key: str, count: int | None, reader, per: str = "mass"):
    """A single value, or a list with `count` entries (one `per` mass or gap); `reader(item,
    item_key)` converts each. A list needs a known `count` (n not left 'optimal')."""
    if isinstance(raw, (list, tuple)):
        if count is None:
            raise _error(
                key,
                "a list needs a known number of masses; with n = 'optimal' give one value for all",
            )
        if len(raw) != count:
            raise _error(key, f"has {len(raw)} entries, expected {count} (one per {per})")
        return tuple(reader(item, f"{key}[{i}]") for i, item in enumerate(raw))
    return reader(raw, key)


# --------------------------------------------------------------------------------------------------
# Sections
# --------------------------------------------------------------------------------------------------


def _parse_materials(raw: Any) -> tuple[MaterialSpec, ...]:
    if not isinstance(raw, Mapping):
        raise _error("materials", "expected tables [materials.NAME]")
    out = []
    for name, body in raw.items():
        bare = str(name).replace("_", "").replace("-", "").isalnum()  # a TOML bare key
        path = f"materials.{name}" if bare else f'materials."{name}"'
        t = _table(body, path, _MATERIAL_KEYS)
        for req in ("youngs_modulus", "poisson_ratio"):
            if req not in t:
                raise _error(_join(path, req), "missing")
        E = _positive(t["youngs_modulus"], _join(path, "youngs_modulus"), "pressure")
        nu = parse_quantity(t["poisson_ratio"], "dimensionless", _join(path, "poisson_ratio"))
        _check(-1 < nu <= 0.5, _join(path, "poisson_ratio"), t["poisson_ratio"], "must be in (-1, 0.5]")
        rho = _positive(t["density"], _join(path, "density"), "density") if "density" in t else None
        sy = _positive(t["yield_strength"], _join(path, "yield_strength"), "pressure") if "yield_strength" in t else None
        out.append(MaterialSpec(str(name), E, nu, rho, sy))
    return tuple(out)


def _parse_drop(raw: Any) -> tuple[bool, dict]:
    t = _table(raw, "drop", _DROP_KEYS)
    ground = _bool(t["ground"], "drop.ground") if "ground" in t else True
    return ground, t


def _merge_contact(default: dict, override: dict, path: str) -> dict:
    """Apply the inheritance rules of docs/stack-files.md. Values are `(raw, dotted_key)`."""
    own = {k: (v, _join(path, k)) for k, v in override.items() if k != "index"}
    default_law = default.get("law", (None,))[0]
    if "law" in own and str(own["law"][0]).strip().lower() != str(default_law).strip().lower():
        base = {k: v for k, v in default.items() if k == "clamp"}
    else:
        base = dict(default)
        if any(k in own for k in ("restitution", "alpha", "damping")):
            for k in ("restitution", "alpha", "damping"):
                base.pop(k, None)
            if "restitution" not in own:
                base.pop("chi_map", None)
                base.pop("calibration_velocity", None)
    base.update(own)
    return base


def _resolve_contact(merged: dict, label: str, *, ground: bool) -> ContactSpec:
    """Validate one merged contact section (`label` names it: `contact`, `contact.ground`, ...)."""
    if "law" not in merged:
        raise _error(_join(label, "law"), f"missing; one of {', '.join(repr(c) for c in CONTACT_LAWS)}")
    law_raw, law_key = merged["law"]
    law = _choice(law_raw, law_key, CONTACT_LAWS)
    row = LAWS[law]
    allowed = row.file_keys()
    for k, (raw, key) in merged.items():
        if k != "law" and k not in allowed:
            raise _error(key, f"not used by law {law!r}; {row.hint()}")

    def get(k):
        return merged[k] if k in merged else (None, None)

    stiffness = None
    exponent = None
    if "exponent" in merged and ("exponent", "dimensionless") in row.params:  # the power law: its stiffness unit
        raw, key = merged["exponent"]
        exponent = parse_quantity(raw, "dimensionless", key)
        _check(1.0 <= exponent <= 5.0, key, raw, "must be between 1 and 5 (F = k delta^p)")
    if "stiffness" in merged:
        raw, key = merged["stiffness"]
        if row.stiffness == "power_stiffness":
            if exponent is None:
                raise _error(_join(label, "exponent"), f"missing; law {law!r} needs exponent (a plain number)")
            stiffness = parse_quantity(raw, row.stiffness, key, exponent=exponent)
            _check(stiffness > 0, key, raw, "must be > 0")
        else:
            stiffness = _positive(raw, key, row.stiffness)
    elif not row.hertzian:
        raise _error(
            _join(label, "stiffness"),
            f"missing; {law!r} needs a stiffness in {_UNITS[row.stiffness]} (it cannot be computed from "
            "materials)",
        )

    restitution = None
    if "restitution" in merged:
        raw, key = merged["restitution"]
        restitution = parse_quantity(raw, "dimensionless", key)
        _check(0 < restitution <= 1, key, raw,
               "must be in (0, 1] (a contact law is passive; e > 1, an 'active ground', is rigid-model only)"
               if ground else "must be in (0, 1]")
        _check(restitution >= MIN_RESTITUTION, key, raw,
               f"must be >= {MIN_RESTITUTION:g} (the contact laws are calibrated for {MIN_RESTITUTION:g} <= e <= 1)")
    own = None  # the law's own damping parameter (`registry.LawRow.damping`: `alpha` or `damping`)
    if row.damping is not None and row.damping in merged:
        raw, key = merged[row.damping]
        own = _non_negative(raw, key, row.damping_dimension)
        unit = f" {_UNITS[row.damping_dimension]}" if row.damping_dimension in _UNITS else ""
        _check(own <= row.damping_max, key, raw,
               f"out of range; law {law!r} takes a {row.damping} of at most {row.damping_max:g}{unit}")
    alpha = own if row.damping == "alpha" else None
    damping = own if row.damping == "damping" else None
    chi_map = None
    if "chi_map" in merged:
        raw, key = merged["chi_map"]
        chi_map = _choice(raw, key, CHI_MAPS)
    calibration_velocity = None
    if "calibration_velocity" in merged:
        raw, key = merged["calibration_velocity"]
        calibration_velocity = _positive(raw, key, "velocity")
    clamp = _bool(*merged["clamp"]) if "clamp" in merged else True
    params = []
    for pkey, dim in row.params:  # required further keys of the law, e.g. thornton's yield_pressure
        if pkey not in merged and pkey in row.from_materials:
            continue  # from the materials' yield strengths (`build`; `_check_from_materials`)
        if pkey not in merged:
            raise _error(_join(label, pkey), f"missing; law {law!r} needs {pkey} ({_UNITS.get(dim, dim)})")
        raw, key = merged[pkey]
        params.append((pkey, exponent if pkey == "exponent" else _positive(raw, key, dim)))

    if row.damping is not None:
        given = [k for k in ("restitution", "alpha", "damping") if k in merged]
        options = f"restitution or {row.damping}"
        if not given:
            raise _error(_join(label, "restitution"), f"missing; law {law!r} needs {options}")
        if len(given) > 1:
            raise _error(
                merged[given[1]][1],
                f"conflicts with {merged[given[0]][1]}; law {law!r} takes one of {options}",
            )
        if restitution is None:
            for k in ("chi_map", "calibration_velocity"):
                if k in merged:
                    raise _error(
                        merged[k][1],
                        "only used to calibrate a restitution; remove it or give restitution",
                    )
        elif row.chi_map and chi_map is None:
            chi_map = "exact"
    return ContactSpec(
        law, stiffness, restitution, chi_map, calibration_velocity, alpha, damping, clamp, label, tuple(params)
    )


def _parse_contact(raw: Any, *, has_ground: bool) -> tuple[ContactsSpec, list]:
    if raw is None:
        raise _error("contact", "missing section [contact] (the default contact law)")
    t = _table(raw, "contact", _CONTACT_KEYS + ("ground", "interface"))
    default_raw = {k: (v, f"contact.{k}") for k, v in t.items() if k in _CONTACT_KEYS}
    default = _resolve_contact(default_raw, "contact", ground=False)

    ground = None
    if "ground" in t:
        if not has_ground:
            raise _error("contact.ground", "given but drop.ground = false (no ground contact)")
        g = _table(t["ground"], "contact.ground", _CONTACT_KEYS)
        merged = _merge_contact(default_raw, g, "contact.ground")
        ground = _resolve_contact(merged, "contact.ground", ground=True)
    elif has_ground:
        ground = _resolve_contact(default_raw, "contact", ground=True)

    overrides: list[tuple[int, ContactSpec, str]] = []
    if "interface" in t:
        entries = t["interface"]
        if isinstance(entries, Mapping):
            entries = [entries]
        if not isinstance(entries, list):
            raise _error("contact.interface", "expected [[contact.interface]] tables, each with an index")
        seen: dict[int, str] = {}
        for pos, entry in enumerate(entries):
            path = f"contact.interface[{pos}]"
            e = _table(entry, path, ("index",) + _CONTACT_KEYS)
            if "index" not in e:
                raise _error(
                    f"{path}.index",
                    "missing; the interface number j (mass j - mass j+1), or a list",
                )
            idx_raw = e["index"]
            indices = idx_raw if isinstance(idx_raw, list) else [idx_raw]
            if not indices:
                raise _error(f"{path}.index", "empty list")
            spec = _resolve_contact(_merge_contact(default_raw, e, path), path, ground=False)
            for i, item in enumerate(indices):
                ikey = f"{path}.index" if not isinstance(idx_raw, list) else f"{path}.index[{i}]"
                if isinstance(item, int) and not isinstance(item, bool) and item == 0:
                    raise _error(ikey, "interface 0 is the ground contact; set it in [contact.ground]")
                j = _int(item, ikey, 1, MAX_MASSES - 1, f" (a stack has at most {MAX_MASSES} masses)")
                if j in seen:
                    raise _error(ikey, f"interface {j} is already set by {seen[j]}")
                seen[j] = path
                overrides.append((j, spec, ikey))
    overrides.sort(key=lambda item: item[0])
    contacts = ContactsSpec(default, ground, tuple((j, s) for j, s, _ in overrides))
    return contacts, overrides


def _parse_design(raw: Any, default_restitution: float | None) -> DesignSpec:
    t = _table(raw, "stack.design", _DESIGN_KEYS)
    if "kind" not in t:
        raise _error("stack.design.kind", "missing; 'mvg' or 'met'")
    kind = _choice(t["kind"], "stack.design.kind", DESIGN_KINDS)
    n_raw = t.get("n", "optimal")
    if isinstance(n_raw, str) and n_raw.strip().lower() == "optimal":
        n = None
    elif isinstance(n_raw, str):
        raise _error("stack.design.n", f"{n_raw!r} is invalid: an integer >= 2 or 'optimal'")
    else:
        n = _int(n_raw, "stack.design.n", 2, MAX_MASSES, " (the most masses a stack may have)")
    if "restitution" in t:
        e = parse_quantity(t["restitution"], "dimensionless", "stack.design.restitution")
        _check(0 < e <= 1, "stack.design.restitution", t["restitution"], "must be in (0, 1]")
    elif default_restitution is not None and 0 < default_restitution <= 1:
        e = default_restitution
    else:
        raise _error(
            "stack.design.restitution",
            "missing; the design restitution e in (0, 1] (defaults to contact.restitution)",
        )
    m1 = _positive(t["bottom_mass"], "stack.design.bottom_mass", "mass") if "bottom_mass" in t else None
    mn = _positive(t["top_mass"], "stack.design.top_mass", "mass") if "top_mass" in t else None
    R = None
    if "mass_ratio" in t:
        R = parse_quantity(t["mass_ratio"], "dimensionless", "stack.design.mass_ratio")
        _check(0 < R < 1, "stack.design.mass_ratio", t["mass_ratio"], "R = m_n/m_1 must be in (0, 1)")
    given = [k for k in ("bottom_mass", "top_mass", "mass_ratio") if k in t]
    if kind == "met" and n is not None:
        if len(given) != 1 or "mass_ratio" in given:
            raise _error(
                "stack.design",
                f"an MET design with n = {n} needs exactly one of bottom_mass, top_mass (got "
                f"{', '.join(given) or 'none'}); its mass ratios follow from e (Eq 25)",
            )
        return _check_design(DesignSpec(kind, n, e, m1, mn, None))
    if len(given) != 2:
        raise _error(
            "stack.design",
            f"give two of bottom_mass, top_mass, mass_ratio (got {', '.join(given) or 'none'})",
        )
    if R is None:
        _check(mn < m1, "stack.design.top_mass", t["top_mass"], "must be lighter than bottom_mass")
        R = mn / m1
    elif m1 is None:
        m1 = mn / R
    else:
        mn = m1 * R
    return _check_design(DesignSpec(kind, n, e, m1, mn, R))



def _optimal_n(count, what: str, d) -> int:
    """`count(R, e, n_limit=MAX_MASSES)` (the rigid model's optimal number of masses), or one line
    naming `stack.design.n` when that stack would have more than `MAX_MASSES` masses."""
    from .errors import ParameterError

    try:
        return int(count(d.mass_ratio, d.restitution, n_limit=MAX_MASSES))
    except ParameterError as exc:
        if exc.name != "n_limit":
            raise
        raise _error("stack.design.n", f"'optimal' is invalid here: the {what} for R = {d.mass_ratio:.6g}, "
                     f"e = {d.restitution:.6g} has more than {MAX_MASSES} masses (the most a stack may "
                     "have); give an integer n") from None

def _check_design(d: DesignSpec) -> DesignSpec:
    """The design's masses exist and lie in the mass range; an 'optimal' n is at most MAX_MASSES.

    Uses the rigid model's closed forms (numpy, scipy; no JAX). A problem names the key that decides it."""
    import numpy as np

    from .errors import ParameterError
    from . import rigid

    lo, hi = LIMITS["mass"]
    try:
        with np.errstate(all="ignore"):
            if d.n is None and d.kind == "mvg":
                n = _optimal_n(rigid.mvg_optimal_n, "optimal MVG stack", d)
                masses = rigid.mvg_masses(d.mass_ratio, n, d.bottom_mass)
            elif d.kind == "met":
                if d.n is None:
                    n = _optimal_n(rigid.met_n_for_ratio, "MET chain", d)
                    m1 = d.bottom_mass if d.bottom_mass is not None else d.top_mass / d.mass_ratio
                else:
                    n = d.n
                    m1 = d.bottom_mass if d.bottom_mass is not None else d.top_mass / float(
                        rigid.met_mass_ratio(d.restitution, n))
                masses = rigid.met_masses(d.restitution, n, m1)
            else:
                masses = rigid.mvg_masses(d.mass_ratio, d.n, d.bottom_mass)
            masses = np.asarray(masses, dtype=float)
    except ParameterError as exc:
        key = {"e": "stack.design.restitution", "R": "stack.design.mass_ratio"}.get(exc.name, "stack.design")
        raise _error(key, f"{exc}") from None
    bad = ~np.isfinite(masses) | (masses < lo) | (masses > hi)
    if bad.any():
        i = int(np.argmax(bad))
        raise _error("stack.design", f"mass {i + 1} of this {d.kind.upper()} design is {masses[i]:.4g} kg; every "
                     f"mass must be between {lo:g} and {hi:g} kg (change bottom_mass, top_mass, mass_ratio or n)")
    return d


def _parse_stack(raw: Any, default_restitution: float | None) -> BodiesSpec:
    if raw is None:
        raise _error("stack", "missing section [stack] (masses and gaps)")
    t = _table(raw, "stack", _STACK_KEYS)
    if "masses" in t and "design" in t:
        raise _error(
            "stack.design",
            "conflicts with stack.masses; give explicit masses or a design, not both",
        )
    masses = design = None
    if "masses" in t:
        m = t["masses"]
        if not isinstance(m, (list, tuple)):
            raise _error("stack.masses", f"expected a list of masses (bottom first), got {_show(m)}")
        if len(m) < 1:
            raise _error("stack.masses", "is empty; a stack needs at least 1 mass (2 without the ground)")
        if len(m) > MAX_MASSES:
            raise _error("stack.masses", f"has {len(m)} entries; a stack has at most {MAX_MASSES} masses")
        masses = tuple(_positive(x, f"stack.masses[{i}]", "mass") for i, x in enumerate(m))
    elif "design" in t:
        design = _parse_design(t["design"], default_restitution)
    else:
        raise _error("stack.masses", "missing; give stack.masses (bottom first) or a [stack.design] section")
    n = len(masses) if masses is not None else design.n

    if "gaps" not in t and n == 1:  # one mass: there is no gap to give
        t = dict(t, gaps=())
    if "gaps" not in t:
        raise _error(
            "stack.gaps",
            "missing; the gap between neighbouring masses (0 = touching), one value or a list of "
            "n-1",
        )
    n_gaps = None if n is None else n - 1
    gaps = _per_item(t["gaps"], "stack.gaps", n_gaps, lambda x, k: _non_negative(x, k, "length"), "gap")

    velocities = None
    if "velocities" in t:
        v = t["velocities"]
        if not isinstance(v, (list, tuple)):
            raise _error("stack.velocities", f"expected a list of n initial velocities, got {_show(v)}")
        if n is None:
            raise _error("stack.velocities", "needs a known number of masses; give stack.design.n")
        if len(v) != n:
            raise _error("stack.velocities", f"has {len(v)} entries, expected {n} (one per mass)")
        velocities = tuple(parse_quantity(x, "velocity", f"stack.velocities[{i}]") for i, x in enumerate(v))

    end_force = _non_negative(t["end_force"], "stack.end_force", "force") if "end_force" in t else 0.0
    touching = all(g == 0 for g in (gaps if isinstance(gaps, tuple) else (gaps,)))
    # an end force precompresses the chain: it starts in static equilibrium unless the file says otherwise
    preload = _bool(t["preload"], "stack.preload") if "preload" in t else (end_force > 0 and touching)
    if preload and not touching:
        raise _error("stack.preload", "needs touching masses (stack.gaps = 0)")

    material = _per_item(t["material"], "stack.material", n, _name) if "material" in t else None
    radius = None
    if "radius" in t:
        radius = _per_item(
            t["radius"], "stack.radius", n, lambda x, k: _positive(x, k, "length", allow_inf=True)
        )
    shape = None
    if "shape" in t:
        shape = _per_item(t["shape"], "stack.shape", n, lambda x, k: _choice(x, k, SHAPES))
    shape, radius = _geometry(shape, radius, t, "stack")
    return BodiesSpec(masses, design, gaps, velocities, preload, material, radius, shape, end_force)


def _geometry(shape, radius, t: Mapping, path: str):
    """Reconcile `shape` and `radius` (single values or tuples): flat ⇔ radius inf."""
    if shape is None and radius is None:
        return None, None
    if shape is None:  # derived from the radius
        def kind(r: float) -> str:
            return "flat" if math.isinf(r) else "sphere"

        shape = tuple(kind(r) for r in radius) if isinstance(radius, tuple) else kind(radius)
        return shape, radius
    shapes = shape if isinstance(shape, tuple) else None
    if radius is None:
        if any(s == "sphere" for s in (shapes or (shape,))):
            raise _error(_join(path, "radius"), "missing; a spherical cap needs its radius of curvature")
        return shape, (tuple(math.inf for _ in shapes) if shapes else math.inf)
    if shapes is None and not isinstance(radius, tuple):
        if shape == "flat" and not math.isinf(radius):
            raise _error(
                _join(path, "radius"),
                f"{_show(t['radius'])} is invalid: a flat face has no radius (omit it or use inf)",
            )
        if shape == "sphere" and math.isinf(radius):
            raise _error(_join(path, "radius"), "inf is invalid: a sphere needs a finite radius")
        return shape, radius
    count = len(shapes) if shapes else len(radius)
    shapes = shapes or (shape,) * count
    radii = radius if isinstance(radius, tuple) else (radius,) * count
    out = []
    for i, (s, r) in enumerate(zip(shapes, radii)):
        rkey = f"{path}.radius[{i}]" if isinstance(radius, tuple) else f"{path}.radius"
        if s == "flat":
            r = math.inf if not isinstance(radius, tuple) else r
            if not math.isinf(r):
                raise _error(
                    rkey,
                    f"{_show(t['radius'][i])} is invalid: mass {i + 1} is flat ({path}.shape), use "
                    "inf",
                )
        elif math.isinf(r):
            raise _error(rkey, f"inf is invalid: mass {i + 1} is a sphere and needs a finite radius")
        out.append(r)
    return shapes, tuple(out)


def _parse_ground(raw: Any) -> GroundSpec:
    t = _table(raw, "ground", _GROUND_KEYS)
    material = _name(t["material"], "ground.material") if "material" in t else None
    shape = _choice(t["shape"], "ground.shape", SHAPES) if "shape" in t else None
    radius = _positive(t["radius"], "ground.radius", "length", allow_inf=True) if "radius" in t else None
    if shape is None:
        shape = "flat" if radius is None or math.isinf(radius) else "sphere"
    shape, radius = _geometry(shape, radius, t, "ground")
    return GroundSpec(material, shape, radius)


def _parse_wall(raw: Any, bodies: BodiesSpec, n: int | None) -> WallSpec:
    t = _table(raw, "wall", _WALL_KEYS)
    material = _name(t["material"], "wall.material") if "material" in t else None
    stiffness = _positive(t["stiffness"], "wall.stiffness", "hertz_stiffness") if "stiffness" in t else None
    if material is not None and stiffness is not None:
        raise _error("wall.material", "conflicts with wall.stiffness; give one (the stiffness, or the wall's "
                     "material to compute it)")
    if stiffness is None:
        if material is None:
            raise _error("wall.stiffness", "missing; give the Hertz stiffness of the top mass on the wall, or "
                         "wall.material with stack.material and stack.radius")
        top_mat, top_r = (v if v is None or not isinstance(v, tuple) else v[-1] for v in (bodies.material, bodies.radius))
        if top_mat is None or top_r is None:
            raise _error("wall.material", "needs stack.material and stack.radius (the top mass's) to compute "
                         "the wall's stiffness; or give wall.stiffness")
        if math.isinf(top_r):
            raise _error("wall.material", "the top mass is flat (stack.radius = inf) and so is the wall: flat on "
                         "flat is not Hertzian; give the top mass a finite radius or wall.stiffness")
    gap = None
    if "gap" in t:
        if bodies.end_force > 0:
            raise _error("wall.gap", "not used with stack.end_force: the wall is placed where it carries the "
                         "end force (the precompressed equilibrium)")
        gap = _non_negative(t["gap"], "wall.gap", "length")
    return WallSpec(material, stiffness, gap)


def _parse_solver(raw: Any) -> SolverSpec:
    t = _table(raw, "solver", _SOLVER_KEYS)
    solver = _choice(t["solver"], "solver.solver", SOLVERS) if "solver" in t else "tsit5"
    rtol = atol = t_max = dt_output = None
    max_steps = n_output = None
    if "rtol" in t:
        rtol = parse_quantity(t["rtol"], "dimensionless", "solver.rtol")
        _check(0 < rtol < 1, "solver.rtol", t["rtol"], "must be in (0, 1)")
    if "atol" in t:
        atol = _positive(t["atol"], "solver.atol", "dimensionless")
    if "t_max" in t:
        t_max = _positive(t["t_max"], "solver.t_max", "time")
    if "max_steps" in t:
        max_steps = _int(t["max_steps"], "solver.max_steps", 1, MAX_STEPS)
    if "n_output" in t and "dt_output" in t:
        raise _error("solver.dt_output", "conflicts with solver.n_output; give one of them")
    if "n_output" in t:
        n_output = _int(t["n_output"], "solver.n_output", 2, MAX_OUTPUT_POINTS, " output points")
    if "dt_output" in t:
        dt_output = _positive(t["dt_output"], "solver.dt_output", "time")
        if t_max is not None:
            _check(t_max / dt_output <= MAX_OUTPUT_POINTS, "solver.dt_output", t["dt_output"],
                   f"t_max / dt_output = {t_max / dt_output:.4g} output points; at most "
                   f"{MAX_OUTPUT_POINTS:_} (raise dt_output or lower t_max)")
        else:
            _check(dt_output >= MIN_DT_OUTPUT, "solver.dt_output", t["dt_output"],
                   f"must be >= {MIN_DT_OUTPUT:g} s when solver.t_max is not given (with t_max, "
                   f"t_max / dt_output <= {MAX_OUTPUT_POINTS:_})")
    until = _choice(t["until"], "solver.until", UNTIL) if "until" in t else "cascade"
    if until == "t_max" and t_max is None:
        raise _error("solver.until", "'t_max' needs solver.t_max (the time to run to)")
    return SolverSpec(solver, rtol, atol, t_max, max_steps, n_output, dt_output, until)


def parse_srs_table(table: Any, where: str) -> tuple[tuple[float, float], ...]:
    """An SRS given as a table: rows `[frequency, level]` (Hz or a quantity such as `"1 kHz"`; g as a
    plain number), at least two, frequencies increasing. Used by `[optimize] target_srs` and
    `[test] srs`. Raises `StackFileError` naming `where` and the row."""
    if not isinstance(table, list) or len(table) < 2:
        raise _error(where, "missing or too short; give rows [frequency, level], e.g. [[100, 50], [\"1 kHz\", 1500]] "
                     "(Hz and g), at least two")
    rows = []
    for i, row in enumerate(table):
        if not isinstance(row, list) or len(row) != 2:
            raise _error(f"{where}[{i}]", f"{row!r} is invalid: a row [frequency, level]")
        f = parse_quantity(row[0], "frequency", f"{where}[{i}][0]") if isinstance(row[0], str) else row[0]
        if isinstance(f, bool) or not isinstance(f, (int, float)) or not (math.isfinite(f) and 1e-3 <= f <= 1e6):
            raise _error(f"{where}[{i}][0]", f"{row[0]!r} is invalid: a frequency in Hz, 1e-3 to 1e6")
        a = row[1]
        if isinstance(a, bool) or not isinstance(a, (int, float)) or not (math.isfinite(a) and 0 < a <= 1e8):
            raise _error(f"{where}[{i}][1]", f"{row[1]!r} is invalid: a level in g, > 0")
        rows.append((float(f), float(a)))
    freqs = [r[0] for r in rows]
    if any(b <= a for a, b in zip(freqs, freqs[1:])):
        raise _error(where, "the frequencies must increase from row to row")
    return tuple(rows)


def _parse_srs(raw: Any) -> SRSSpec:
    t = _table(raw, "srs", _SRS_KEYS)
    if "q" in t and "damping" in t:
        raise _error("srs.damping", "conflicts with srs.q; give one of them (Q = 1/(2 damping))")
    q = 10.0
    if "q" in t:
        q = _positive(t["q"], "srs.q", "dimensionless")
        _check(q > 0.5, "srs.q", t["q"], "must be > 0.5 (an underdamped oscillator), e.g. 10")
    if "damping" in t:
        z = _positive(t["damping"], "srs.damping", "dimensionless")
        _check(z < 1, "srs.damping", t["damping"], "must be in (0, 1) (the damping ratio, e.g. 0.05)")
        q = 1.0 / (2.0 * z)
    per_octave = _int(t["per_octave"], "srs.per_octave", 1, 48) if "per_octave" in t else 12
    band = None
    if "band" in t:
        b = t["band"]
        if not (isinstance(b, list) and len(b) == 2):
            raise _error("srs.band", f"{_show(b)} is not a pair [f_min, f_max], e.g. [\"100 Hz\", \"10 kHz\"]")
        lo = _positive(b[0], "srs.band[0]", "frequency")
        hi = _positive(b[1], "srs.band[1]", "frequency")
        _check(lo < hi, "srs.band", b, "needs f_min < f_max")
        _check(SRS_BAND_LIMITS[0] <= lo and hi <= SRS_BAND_LIMITS[1] and hi / lo <= SRS_MAX_SPAN, "srs.band", b,
               f"must lie within [{SRS_BAND_LIMITS[0]:g} Hz, {SRS_BAND_LIMITS[1]:g} Hz] and span at most "
               f"{math.log10(SRS_MAX_SPAN):g} decades (f_max/f_min <= {SRS_MAX_SPAN:g})")
        band = (lo, hi)
    peak = _choice(t["peak"], "srs.peak", ("abs", "pos", "neg")) if "peak" in t else "abs"
    kind = _choice(t["type"], "srs.type", ("acceleration", "pseudo-velocity")) if "type" in t else "acceleration"
    return SRSSpec(q, per_octave, band, peak, kind)


# --------------------------------------------------------------------------------------------------
# The whole file
# --------------------------------------------------------------------------------------------------


def _build(data: Mapping) -> StackSpec:
    top = _table(data, "", _TOP_KEYS)
    title = None
    if "title" in top:
        if not isinstance(top["title"], str):
            raise _error("title", f"{_show(top['title'])} is not a string")
        title = top["title"]
    materials = _parse_materials(top["materials"]) if "materials" in top else ()
    has_ground, drop = _parse_drop(top.get("drop", {}))
    contacts, overrides = _parse_contact(top.get("contact"), has_ground=has_ground)
    bodies = _parse_stack(top.get("stack"), contacts.default.restitution)
    n = bodies.n
    if n == 1 and not has_ground:
        raise _error("stack.masses", "has 1 entry but drop.ground = false; a chain without the ground needs "
                     "at least 2 masses (one mass needs the ground to hit)")

    # --- the drop and the initial state
    gravity = None
    if "gravity" in drop:
        gravity = parse_quantity(drop["gravity"], "acceleration", "drop.gravity")
        _check(
            gravity >= 0, "drop.gravity", drop["gravity"],
            "must be >= 0 (the magnitude of the downward gravity)",
        )
    impact_velocity = height = None
    if has_ground:
        gravity = STANDARD_GRAVITY if gravity is None else gravity
        given = [k for k in ("impact_velocity", "height") if k in drop]
        if len(given) == 2:
            raise _error("drop.height", "conflicts with drop.impact_velocity; give one of them")
        if given and bodies.velocities is not None:
            raise _error("stack.velocities", f"conflicts with drop.{given[0]}; give one initial state")
        if not given and bodies.velocities is None:
            raise _error(
                "drop.impact_velocity",
                "missing; give drop.impact_velocity or drop.height (or stack.velocities)",
            )
        if "impact_velocity" in drop:
            impact_velocity = _non_negative(drop["impact_velocity"], "drop.impact_velocity", "velocity")
        elif "height" in drop:
            height = _non_negative(drop["height"], "drop.height", "length")
            if gravity == 0:
                raise _error(
                    "drop.height",
                    "a drop height needs gravity, but drop.gravity = 0; give drop.impact_velocity "
                    "instead",
                )
            impact_velocity = math.sqrt(2.0 * gravity * height)
            v_max = LIMITS["velocity"][1]
            _check(impact_velocity <= v_max, "drop.height", drop["height"],
                   f"a fall from it reaches {impact_velocity:.4g} m/s; at most {v_max:g} m/s (sqrt(2 g h))")
        if "ground" in top:
            ground = _parse_ground(top["ground"])
        else:
            ground = GroundSpec()
    else:
        gravity = 0.0 if gravity is None else gravity
        for k in ("impact_velocity", "height"):
            if k in drop:
                raise _error(
                    f"drop.{k}",
                    "not used without a ground (drop.ground = false); give stack.velocities",
                )
        if "ground" in top:
            raise _error("ground", "given but drop.ground = false")
        if bodies.velocities is None:
            raise _error(
                "stack.velocities",
                "missing; a chain without ground (drop.ground = false) needs the initial "
                "velocities",
            )
        ground = None
    if bodies.preload and gravity == 0 and bodies.end_force == 0:
        raise _error("stack.preload", "a static preload needs gravity or stack.end_force, but drop.gravity = 0 "
                     "and there is no end force")
    if bodies.end_force > 0:
        if ground is None:
            raise _error("stack.end_force", f"{bodies.end_force:g} N needs drop.ground = true (a wall at mass 1 "
                         "that holds the chain against it)")

    # --- interface numbers against the number of masses
    if n is not None:
        for j, _, key in overrides:
            if j > n - 1:
                raise _error(key, f"{j} is invalid: a stack of {n} masses has interfaces 1..{n - 1}")

    # --- stiffness from materials and geometry where none is given
    sections = [(contacts.default, "contact")] + [(s, s.source) for _, s, _ in overrides]
    if ground is not None:
        sections.append((contacts.ground, contacts.ground.source))
    for spec, label in sections:
        if spec.stiffness is not None:
            continue
        if bodies.material is None:
            raise _error(
                _join(label, "stiffness"),
                "missing; give a stiffness, or stack.material and stack.radius to compute it",
            )
        if bodies.shape is None:
            raise _error(
                "stack.radius",
                f"missing; {label} has no stiffness, so it is computed from materials and the "
                "caps' radii",
            )
    _check_curved(contacts, bodies, ground, overrides, n)
    for spec_, label in sections:
        row = LAWS[spec_.law]
        given = {k for k, _ in spec_.params}
        for pkey in row.from_materials:
            if pkey not in given and bodies.material is None:
                raise _error(_join(label, pkey), f"missing; law {spec_.law!r} needs {pkey}, or stack.material "
                             "with a yield strength (the softer body's Y gives it)")

    solver = _parse_solver(top["solver"]) if "solver" in top else SolverSpec()
    wall = _parse_wall(top["wall"], bodies, n) if "wall" in top else None
    if (bodies.end_force > 0 or wall is not None) and solver.until != "t_max":
        what = "stack.end_force" if bodies.end_force > 0 else "[wall]"
        raise _error("solver.until", f"'{solver.until}' with {what}: a chain held by an end force or a wall "
                     "never flies apart; set solver.until = \"t_max\" and solver.t_max")
    if solver.max_steps is not None and n is not None:
        need = run_memory(n, solver.max_steps)
        _check(need <= MAX_RUN_MEMORY, "solver.max_steps", solver.max_steps,
               f"a run of {n} masses would keep {need / 2**30:.1f} GiB of step history; at most "
               f"{MAX_RUN_MEMORY / 2**30:g} GiB (lower max_steps)")
    drop_spec = DropSpec(gravity, impact_velocity, height)
    srs = _parse_srs(top["srs"]) if "srs" in top else SRSSpec()
    return StackSpec(drop_spec, bodies, contacts, ground, solver, materials, title, srs=srs, wall=wall)


def _check_curved(contacts: ContactsSpec, bodies: BodiesSpec, ground, overrides, n) -> None:
    """Hertz contact needs at least one curved face: reject flat-on-flat where stiffness is computed."""
    if bodies.shape is None:
        return
    if n is None:  # an 'optimal' design: one shape for all masses
        if bodies.shape == "flat":
            for spec in [contacts.default] + [s for _, s, _ in overrides]:
                if spec.stiffness is None:
                    raise _error(
                        _join(spec.source, "stiffness"),
                        "missing, and the masses are flat (no Hertz stiffness flat on flat); give "
                        "one or a radius",
                    )
        count = 1
    else:
        count = n
    shapes = bodies.shape_list(max(count, 1))
    computed = ground is not None and contacts.ground.stiffness is None
    if computed and ground.shape == "flat" and shapes[0] == "flat":
        raise _error(
            _join(contacts.ground.source, "stiffness"),
            "missing, and the flat ground on the flat mass 1 has no Hertz stiffness; give one or "
            "a radius",
        )
    for j in range(1, count):
        spec = contacts.interface(j)
        if spec.stiffness is None and shapes[j - 1] == "flat" and shapes[j] == "flat":
            raise _error(
                _join(spec.source, "stiffness"),
                f"missing, and interface {j} is flat on flat (no Hertz stiffness); give one or a "
                "radius",
            )


def parse_stack(data: Mapping | str, *, source: str | None = None) -> StackSpec:
    """Validate a stack description — TOML text or an already-parsed `dict` (whose values may also
    be pint Quantities) — into a `StackSpec`. `source` (a file name) prefixes error messages.

    Raises `StackFileError` (one line, naming the dotted key) on any problem.
    """
    prefix = f"{source}: " if source else ""
    if isinstance(data, str):
        import tomllib

        data = data.removeprefix("\ufeff")  # a UTF-8 byte-order mark (Windows editors write one)
        try:
            data = tomllib.loads(data)
        except tomllib.TOMLDecodeError as exc:
            err = _error(None, f"{prefix}invalid TOML: {exc}")
            raise err from None
        except RecursionError:
            raise _error(None, f"{prefix}invalid TOML: arrays or tables nested too deeply") from None
    elif not isinstance(data, Mapping):
        raise _error(None, f"{prefix}expected TOML text or a dict, got {type(data).__name__}")
    try:
        spec = _build(data)
    except StackFileError as exc:
        if not prefix:
            raise
        err = StackFileError(f"{prefix}{exc}")
        err.key, err.problem = getattr(exc, "key", None), getattr(exc, "problem", str(exc))
        raise err from None
    if source is not None:
        spec = dataclasses.replace(spec, source=source)
    return spec


def apply_overrides(data: Mapping, overrides) -> dict:
    """A copy of the parsed stack file `data` with `KEY=VALUE` overrides set (the command line's
    `--set`): `KEY` a dotted path into the file's tables (`drop.height`, `contact.restitution`,
    `solver.rtol`), `VALUE` a TOML value (`0.7`, `"30 cm"`, `[1, 0.5]`, `true`) or, when it is not one,
    the text itself (`30 cm`). Sections and keys are created as needed; a key that says the same as
    another of the file (`srs.q` / `srs.damping`, `drop.height` / `drop.impact_velocity`,
    `solver.dt_output` / `solver.n_output`) replaces it, unless both are set; the stack-file checks
    then judge the result as they would the file.

    **Raises:** `StackFileError` (`--set ...`) for a malformed override or a key that crosses a value.
    """
    import copy
    import tomllib

    out = copy.deepcopy(dict(data))
    set_keys: set[str] = set()
    for item in overrides or ():
        key, sep, raw = str(item).partition("=")
        key = key.strip()
        parts = key.split(".")
        if not sep or not key or not all(re.fullmatch(r"[A-Za-z0-9_\-]+", p_) for p_ in parts):
            raise _error(None, f"--set {item!r}: expected KEY=VALUE with a dotted key, e.g. drop.height=\"30 cm\"")
        try:
            value = tomllib.loads(f"v = {raw.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = raw.strip()  # plain text: a quantity such as 30 cm
        node = out
        for i, p_ in enumerate(parts[:-1]):
            nxt = node.setdefault(p_, {})
            if not isinstance(nxt, dict):
                raise _error(None, f"--set {key}: {'.'.join(parts[: i + 1])} is a value, not a section")
            node = nxt
        node[parts[-1]] = value
        for other in _ALTERNATIVES.get(key, ()):  # --set srs.q replaces the file's srs.damping, ...
            sec, _, name = other.rpartition(".")
            table = out.get(sec) if sec else out
            if isinstance(table, dict) and name in table and other not in set_keys:
                del table[name]
        set_keys.add(key)
    return out


#: Keys that say the same thing another way: a `--set` of one replaces the file's other.
_ALTERNATIVES = {
    "srs.q": ("srs.damping",), "srs.damping": ("srs.q",),
    "solver.dt_output": ("solver.n_output",), "solver.n_output": ("solver.dt_output",),
    "drop.height": ("drop.impact_velocity",), "drop.impact_velocity": ("drop.height",),
}


def load_stack_file(path: str | Path, overrides=None) -> StackSpec:
    """Read and validate a stack file (TOML with units); the format is docs/stack-files.md.
    `overrides`: `KEY=VALUE` strings applied before the checks (`apply_overrides`); an error caused by
    one names the key as the file would."""
    path = Path(path)
    try:
        if path.is_dir():
            raise _error(None, f"{path}: is a folder, not a stack file")
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise _error(None, f"{path}: {size} bytes is too large for a stack file (at most {MAX_FILE_BYTES:_})")
        text = path.read_text(encoding="utf-8-sig")  # a leading byte-order mark is dropped
    except StackFileError:
        raise
    except FileNotFoundError:
        raise _error(None, f"{path}: no such stack file") from None
    except UnicodeDecodeError:
        raise _error(None, f"{path}: not a UTF-8 text file") from None
    except OSError as exc:
        raise _error(None, f"{path}: cannot read it ({exc.strerror or exc})") from None
    except ValueError as exc:  # e.g. a NUL byte in the path
        raise _error(None, f"{_show(str(path))}: not a usable path ({exc})") from None
    if overrides:
        import tomllib

        try:
            data = tomllib.loads(text.removeprefix("\ufeff"))
        except tomllib.TOMLDecodeError as exc:
            raise _error(None, f"{path}: invalid TOML: {exc}") from None
        return parse_stack(apply_overrides(data, overrides), source=f"{path} (with --set)")
    return parse_stack(text, source=str(path))
