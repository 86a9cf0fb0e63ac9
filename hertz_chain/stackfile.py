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
from pathlib import Path
from typing import Mapping

from ._stackspec import (  # the spec and its bounds are part of this module's interface (__all__)
    _TOP_KEYS,
    CHI_MAPS,
    CONTACT_LAWS,
    DAMPING_LIMITS,
    DESIGN_KINDS,
    MAX_FILE_BYTES,
    MAX_OUTPUT_POINTS,
    MAX_RUN_MEMORY,
    MAX_STEPS,
    MIN_DT_OUTPUT,
    MIN_RESTITUTION,
    SHAPES,
    SOLVERS,
    StackSectionSpec,
    ContactSpec,
    ContactsSpec,
    DesignSpec,
    DropSpec,
    GroundSpec,
    MaterialSpec,
    SolverSpec,
    SRSSpec,
    StackSpec,
    run_memory,
)
from ._stacksections import (
    _check,
    _join,
    _non_negative,
    _parse_contact,
    _parse_drop,
    _parse_ground,
    _parse_materials,
    _parse_solver,
    _parse_srs,
    _parse_stack,
    _parse_wall,
    _table,
    parse_srs_table,
)
from .constants import MAX_MASSES, STANDARD_GRAVITY
from .errors import StackFileError
from .registry import LAWS
from .units import LIMITS, MAX_QUANTITY_LENGTH, _error, _show, parse_quantity  # noqa: F401  (re-exported)

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
    "StackSectionSpec",
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
    if bodies.preload and ground is None:  # a review: ran, the unsupported chain flying apart in free fall
        raise _error("stack.preload", "true needs drop.ground = true: a static preload is the chain's weight "
                     "(and end force) held by the ground, and a chain without it has no static equilibrium")

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
    if wall is not None and ground is None:  # a review: run, then called "held" by the analysis while the
        # beads left the wall (a chain between two walls is the ground's and the wall's)
        raise _error("wall", "needs drop.ground = true: [wall] closes a chain between the ground at mass 1 and "
                     "a far wall at the top mass")
    if (bodies.end_force > 0 or wall is not None) and solver.until != "t_max":
        what = "stack.end_force" if bodies.end_force > 0 else "[wall]"
        raise _error("solver.until", f"'{solver.until}' with {what}: a chain held by an end force or a wall "
                     "never flies apart; set solver.until = \"t_max\" and solver.t_max")
    if solver.max_steps is not None and n is not None:
        need = run_memory(n, solver.max_steps)
        _check(need <= MAX_RUN_MEMORY, "solver.max_steps", solver.max_steps,
               f"a run of {n} masses would keep {need / 2**30:.1f} GiB of step history; at most "
               f"{MAX_RUN_MEMORY / 2**30:g} GiB (lower max_steps)")
    # every material that is used (a stiffness computed from it, or caps with a radius: the yield limits) is
    # in the table or the file's [materials] (a review: an unknown stack.material read "material =
    # 'unobtanium' is invalid", without its key); with every stiffness given and no radius a name is a
    # label only, as before (a second review)
    from .materials import _key, material_names

    own = {m.name for m in materials}
    table = {_key(name) for name in material_names()}
    used = bodies.shape is not None or any(spec.stiffness is None for spec, _ in sections)
    wall_used = wall is not None and (wall.stiffness is None or bodies.shape is not None)
    named = [("stack.material", bodies.material if used else None),
             ("ground.material", ground.material if ground and used else None),
             ("wall.material", wall.material if wall_used else None)]
    for key, value in named:
        for name in (value if isinstance(value, tuple) else (value,)):
            if name is not None and name not in own and _key(name) not in table:
                close = difflib.get_close_matches(_key(name), sorted(table | own), n=1)
                raise _error(key, f"{name!r} is unknown; the table's materials ({', '.join(material_names())}) or a "
                             "[materials.NAME] of the file" + (f"; did you mean {close[0]!r}?" if close else ""))
    drop_spec = DropSpec(gravity, impact_velocity, height)
    srs = _parse_srs(top["srs"]) if "srs" in top else SRSSpec()
    return StackSpec(drop_spec, bodies, contacts, ground, solver, materials, title, srs=srs, wall=wall)


def _check_curved(contacts: ContactsSpec, bodies: StackSectionSpec, ground, overrides, n) -> None:
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


def _toml_error(exc: Exception, text: str) -> str:
    """tomllib's message with the line it points at quoted (its "Cannot overwrite a value (at line 5,
    column 10)" names no key: a review found a duplicated key hard to find)."""
    msg = str(exc)
    found = re.search(r"at line (\d+), column \d+", msg)
    lines = text.splitlines()
    if found and 1 <= int(found.group(1)) <= len(lines):
        line = lines[int(found.group(1)) - 1].strip()
        if line:
            msg += f": {_show(line[:80] + ('...' if len(line) > 80 else ''))}"
    return msg


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
            err = _error(None, f"{prefix}invalid TOML: {_toml_error(exc, data)}")
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

        text = text.removeprefix("\ufeff")
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise _error(None, f"{path}: invalid TOML: {_toml_error(exc, text)}") from None
        return parse_stack(apply_overrides(data, overrides), source=f"{path} (with --set)")
    return parse_stack(text, source=str(path))
