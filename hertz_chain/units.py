"""Quantities with units at the edge of the package: pint strings (`"1 cm"`, `"1e9 N/m^1.5"`) or bare
SI numbers -> SI floats of a named dimension, with the bounds every stack-file value must respect.

:func:`parse_quantity` is the one converter (stack files, `--set`, `[[optimize.vary]]` bounds, sweep
axes, `[test]`, the command line's `--bottom-mass`); `LIMITS` the physical ranges per dimension
(docs/stack-files.md, "Physical ranges and sizes"); errors are `StackFileError` naming the key. pint is
imported on first use and its parsed definitions are cached on disk (`_ureg`).
"""

from __future__ import annotations

import math
import os
import re
from functools import lru_cache
from typing import Any, Mapping

from .errors import StackFileError

__all__ = ["MAX_QUANTITY_LENGTH", "LIMITS", "UNIT_SYMBOLS", "DIMENSIONS", "parse_quantity"]

MAX_QUANTITY_LENGTH = 200
"""Longest quantity string (characters) handed to pint."""
_MAX_EXPONENT = 100.0  # largest |exponent| of a power in a quantity string ("m^1.5", "10**3 kg")

LIMITS = {
    "mass": (1e-12, 1e6),
    "length": (0.0, 1e10),
    "time": (0.0, 1e4),
    "velocity": (0.0, 1e4),
    "acceleration": (0.0, 1e4),
    "pressure": (0.0, 1e13),
    "density": (0.0, 1e5),
    "hertz_stiffness": (0.0, 1e15),
    "linear_stiffness": (0.0, 1e15),
    "power_stiffness": (0.0, 1e18),
    "viscous_damping": (0.0, 1e9),
    "inverse_velocity": (0.0, 1e6),
    "force": (0.0, 1e12),
    "frequency": (0.0, 1e9),
}
"""Dimension -> (smallest non-zero magnitude, largest magnitude), SI. A magnitude outside is an error
naming the key; 0 is left to each key's own sign rule (a mass must still be > 0)."""

_UNITS = {"mass": "kg", "length": "m", "time": "s", "velocity": "m/s", "acceleration": "m/s^2",
          "pressure": "Pa", "density": "kg/m^3", "hertz_stiffness": "N/m^1.5", "linear_stiffness": "N/m",
          "power_stiffness": "N/m^p",
          "viscous_damping": "N s/m", "inverse_velocity": "s/m", "force": "N", "frequency": "Hz"}

UNIT_SYMBOLS = _UNITS
"""Dimension -> the SI unit written in messages."""

# dimension name -> (a unit of that dimension, how the error message describes it)
_DIMENSIONS = {
    "dimensionless": ("dimensionless", "a plain number (e.g. 0.8)"),
    "length": ("m", "a length (e.g. '1 cm')"),
    "mass": ("kg", "a mass (e.g. '1 kg')"),
    "time": ("s", "a time (e.g. '1 us')"),
    "frequency": ("Hz", "a frequency (e.g. '1 kHz')"),
    "velocity": ("m/s", "a velocity (e.g. '1 m/s')"),
    "acceleration": ("m/s^2", "an acceleration (e.g. '9.81 m/s^2')"),
    "force": ("N", "a force (e.g. '10 kN')"),
    "pressure": ("Pa", "a pressure (e.g. '200 GPa')"),
    "density": ("kg/m^3", "a density (e.g. '7850 kg/m^3')"),
    "hertz_stiffness": ("N/m^1.5", "a Hertzian stiffness in N/m^1.5 (e.g. '1e9 N/m^1.5')"),
    "linear_stiffness": ("N/m", "a linear stiffness in N/m (e.g. '5e7 N/m')"),
    "viscous_damping": ("N*s/m", "a damping coefficient in N s/m (e.g. '50 N*s/m')"),
    "inverse_velocity": ("s/m", "an inverse velocity in s/m (e.g. '0.3 s/m')"),
    "power_stiffness": ("N/m^p", "a stiffness in N/m^p, p the law's exponent (e.g. '1e8 N/m^1.2' for p = 1.2)"),
}
DIMENSIONS = _DIMENSIONS


def _error(key: str | None, problem: str) -> StackFileError:
    problem = " ".join(str(problem).splitlines())
    exc = StackFileError(f"{key}: {problem}" if key else problem)
    exc.key, exc.problem = key, problem
    return exc


def _show(raw: Any) -> str:
    """How a raw value is quoted in messages: '1 kg' for strings, 3.5 for numbers."""
    return repr(raw) if isinstance(raw, str) else str(raw)


@lru_cache(maxsize=1)
def _ureg():
    """The one shared pint UnitRegistry, created on first use (pint is slow to import).

    pint parses its definitions file on every start (0.13 s, a twentieth of a warm `hertz-chain
    simulate`); with `cache_folder` it keeps the parsed result on disk, keyed by the file's content, and
    later starts take 0.02 s. The folder sits next to the JAX cache (`hertz_chain._cache.cache_dir("pint")`:
    `~/.cache/hertz_chain/pint`, or `$HERTZ_CHAIN_CACHE_DIR/pint`); `HERTZ_CHAIN_NO_CACHE=1` turns it off,
    and a folder that cannot be used falls back to no cache."""
    import pint

    from ._cache import cache_dir

    folder = cache_dir("pint")
    if folder is not None:
        try:
            os.makedirs(folder, exist_ok=True)
            return pint.UnitRegistry(cache_folder=folder)
        except Exception:  # an unwritable or damaged cache must never stop a run: parse afresh
            pass
    return pint.UnitRegistry()


@lru_cache(maxsize=None)
def _dimensionality(dim: str):
    return _ureg().Quantity(1, _DIMENSIONS[dim][0]).dimensionality


def parse_quantity(raw: Any, dim: str, key: str = "value", *, allow_inf: bool = False,
                   exponent: float | None = None) -> float:
    """Convert `raw` (a pint string such as `"1 cm"`, a bare SI number, or a pint Quantity) to an
    SI float of dimension `dim` (a key of the dimension table: `"length"`, `"mass"`, `"time"`,
    `"velocity"`, `"acceleration"`, `"pressure"`, `"density"`, `"hertz_stiffness"`,
    `"linear_stiffness"`, `"viscous_damping"`, `"inverse_velocity"`, `"dimensionless"`).

    `"power_stiffness"` (N/m^p) needs the law's `exponent` p.

    Raises `StackFileError` naming `key` for the wrong dimension, an unparseable string, a
    non-number or a non-finite value (`inf` is allowed with `allow_inf`).
    """
    desc = _DIMENSIONS[dim][1]
    if isinstance(raw, bool):
        raise _error(key, f"expected {desc}, got a boolean ({str(raw).lower()})")
    if isinstance(raw, (int, float)):
        value = float(raw)
    elif isinstance(raw, str) or hasattr(raw, "dimensionality"):
        if isinstance(raw, str):
            if not raw.strip():
                raise _error(key, f"empty string; expected {desc}")
            _screen(raw, key, desc)
            try:
                q = _ureg().Quantity(raw)
            except Exception as exc:  # pint raises many types (UndefinedUnitError, TokenError, ...)
                reason = str(exc).strip() if "not defined" in str(exc) else "not a number with units"
                raise _error(key, f"cannot parse {raw!r} as a quantity ({reason}); expected {desc}") from None
        else:
            q = raw
        if not hasattr(q, "dimensionality"):  # a string such as "3" parses to a plain number
            value = q
        elif str(q.units) == "dimensionless":  # no units at all ("0.5"): SI, like a bare number
            value = q.magnitude
        elif q.dimensionality != (_dimensionality(dim) if dim != "power_stiffness"
                                  else _ureg().Quantity(1, f"N/m**{exponent!r}").dimensionality):
            shown = _show(raw) if isinstance(raw, str) else repr(str(q))
            raise _error(key, f"{shown} has units of {q.units}, expected {desc}")
        else:
            value = q.to_base_units().magnitude if dim != "dimensionless" else q.to("dimensionless").magnitude
        try:
            value = float(value)
        except OverflowError:
            raise _error(key, f"{_show(raw)} is not a finite number") from None
        except (TypeError, ValueError):
            raise _error(key, f"cannot convert {_show(raw)} to a number; expected {desc}") from None
    else:
        if isinstance(raw, (list, tuple)):
            kind = "a list"
        else:
            kind = "a table" if isinstance(raw, Mapping) else type(raw).__name__
        raise _error(key, f"expected {desc}, got {kind}")
    if math.isnan(value) or (math.isinf(value) and not allow_inf):
        raise _error(key, f"{_show(raw)} is not a finite number")
    if dim in LIMITS and math.isfinite(value):
        lo, hi = LIMITS[dim]
        if abs(value) > hi or (value != 0 and abs(value) < lo):
            shown = _show(raw) if not isinstance(raw, (int, float)) else f"{value:g} {_UNITS[dim]}"
            where = f"between {lo:g} and {hi:g}" if lo else f"at most {hi:g}"
            raise _error(key, f"{shown} is out of range: the magnitude must be {where} {_UNITS[dim]}")
    return value


_POWER = re.compile(r"\*\*|\^")
_EXPONENT = re.compile(r"\s*\(?\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(?:/\s*(\d+)\s*)?\)?")


def _screen(raw: str, key: str, desc: str) -> None:
    """Refuse quantity strings that pint would take ages (or all memory) to evaluate: over
    `MAX_QUANTITY_LENGTH` characters, or a power whose exponent is not a plain number of magnitude at
    most 100 (`"10**10**10 kg"` asks Python for a number with ten billion digits)."""
    if len(raw) > MAX_QUANTITY_LENGTH:
        raise _error(key, f"a quantity string of {len(raw)} characters is too long (at most "
                          f"{MAX_QUANTITY_LENGTH}); expected {desc}")
    for match in _POWER.finditer(raw):
        m = _EXPONENT.match(raw, match.end())
        ok = m is not None
        if ok:
            try:
                exponent = float(m.group(1)) / (float(m.group(2)) if m.group(2) else 1.0)
            except (ValueError, ZeroDivisionError):
                ok = False
            else:
                rest = raw[m.end():].lstrip()
                ok = abs(exponent) <= _MAX_EXPONENT and not rest.startswith(("**", "^"))
        if not ok:
            raise _error(key, f"cannot parse {raw!r} as a quantity (a power needs a plain exponent of "
                              f"magnitude at most {_MAX_EXPONENT:g}); expected {desc}")
