"""The stack file's section readers: one `_parse_*` per TOML table, and the low-level value readers.

Each reader takes the raw TOML value of its table and returns the matching spec of
`hertz_chain._stackspec`, or raises `StackFileError` with one line naming the dotted key, the value
and what is allowed. `hertz_chain.stackfile` assembles the sections and runs the checks that need
more than one section.
"""

from __future__ import annotations

import difflib
import math
from typing import Any, Mapping

from ._stackspec import (
    _CONTACT_KEYS,
    _DESIGN_KEYS,
    _DROP_KEYS,
    _GROUND_KEYS,
    _MATERIAL_KEYS,
    _SOLVER_KEYS,
    _SRS_KEYS,
    _STACK_KEYS,
    _WALL_KEYS,
    CHI_MAPS,
    CONTACT_LAWS,
    DESIGN_KINDS,
    MAX_OUTPUT_POINTS,
    MAX_STEPS,
    MIN_DT_OUTPUT,
    MIN_RESTITUTION,
    SHAPES,
    SOLVERS,
    SRS_BAND_LIMITS,
    SRS_MAX_SPAN,
    StackSectionSpec,
    ContactSpec,
    ContactsSpec,
    DesignSpec,
    GroundSpec,
    MaterialSpec,
    SolverSpec,
    SRSSpec,
    WallSpec,
)
from .constants import MAX_MASSES, POWER_EXPONENTS, UNTIL
from .registry import LAWS
from .units import _UNITS, LIMITS, _error, _show, parse_quantity




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
            raise _error(key, f"has {len(raw)} {'entry' if len(raw) == 1 else 'entries'}, expected {count} (one per {per})")
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
        _check(POWER_EXPONENTS[0] <= exponent <= POWER_EXPONENTS[1], key, raw,
               f"must be between {POWER_EXPONENTS[0]:g} and {POWER_EXPONENTS[1]:g} (F = k delta^p)")
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
    given_e = True
    if "restitution" in t:
        e = parse_quantity(t["restitution"], "dimensionless", "stack.design.restitution")
        _check(0 < e <= 1, "stack.design.restitution", t["restitution"], "must be in (0, 1]")
    elif default_restitution is not None and 0 < default_restitution <= 1:
        e = default_restitution
        given_e = False
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
        return _check_design(DesignSpec(kind, n, e, m1, mn, None, given_e))
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
    return _check_design(DesignSpec(kind, n, e, m1, mn, R, given_e))



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


def _parse_stack(raw: Any, default_restitution: float | None) -> StackSectionSpec:
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
            raise _error("stack.velocities", f"has {len(v)} {'entry' if len(v) == 1 else 'entries'}, expected {n} (one per mass)")
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
    return StackSectionSpec(masses, design, gaps, velocities, preload, material, radius, shape, end_force)


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


def _parse_wall(raw: Any, bodies: StackSectionSpec, n: int | None) -> WallSpec:
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
            points = math.floor(t_max / dt_output * (1.0 + 1e-12)) + 1  # 0, dt, ..., t_max (`workflow`)
            _check(points <= MAX_OUTPUT_POINTS, "solver.dt_output", t["dt_output"],
                   f"{points:_} output points (t_max / dt_output + 1); at most "
                   f"{MAX_OUTPUT_POINTS:_} (raise dt_output or lower t_max)")
        else:
            _check(dt_output >= MIN_DT_OUTPUT, "solver.dt_output", t["dt_output"],
                   f"must be >= {MIN_DT_OUTPUT:g} s when solver.t_max is not given (with t_max, "
                   f"t_max / dt_output + 1 <= {MAX_OUTPUT_POINTS:_})")
    until = _choice(t["until"], "solver.until", UNTIL) if "until" in t else "cascade"
    if until == "t_max" and t_max is None:
        raise _error("solver.until", "'t_max' needs solver.t_max (the time to run to)")
    flight = _bool(t["flight_steps"], "solver.flight_steps") if "flight_steps" in t else True
    land = _bool(t["land_onsets"], "solver.land_onsets") if "land_onsets" in t else True
    window = None
    if "onset_window" in t:
        window = parse_quantity(t["onset_window"], "dimensionless", "solver.onset_window")
        _check(0 < window <= 1, "solver.onset_window", t["onset_window"], "must be in (0, 1] (contact times)")
    return SolverSpec(solver, rtol, atol, t_max, max_steps, n_output, dt_output, until, flight, land, window)


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
        lo, hi = SRS_BAND_LIMITS
        if isinstance(f, bool) or not isinstance(f, (int, float)) or not (math.isfinite(f) and lo <= f <= hi):
            raise _error(f"{where}[{i}][0]", f"{row[0]!r} is invalid: a frequency in Hz, {lo:g} to {hi:g}")
        a = row[1]
        if isinstance(a, bool) or not isinstance(a, (int, float)) or not (math.isfinite(a) and 0 < a <= 1e8):
            raise _error(f"{where}[{i}][1]", f"{row[1]!r} is invalid: a level in g, > 0")
        rows.append((float(f), float(a)))
    freqs = [r[0] for r in rows]
    if any(b <= a for a, b in zip(freqs, freqs[1:])):
        raise _error(where, "the frequencies must increase from row to row")
    if freqs[-1] / freqs[0] > SRS_MAX_SPAN:  # the SRS is computed over the table's band (as `[srs] band`)
        raise _error(where, f"{freqs[0]:g} Hz to {freqs[-1]:g} Hz is invalid: the rows span at most "
                     f"{math.log10(SRS_MAX_SPAN):g} decades (f_max/f_min <= {SRS_MAX_SPAN:g})")
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


