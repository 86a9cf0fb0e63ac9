"""Exceptions raised by hertz_chain.

Every user-facing error is a subclass of :class:`HertzChainError`, so the command line can catch one
type and print a single line. Messages name the parameter, the offending value and what is allowed.
"""

from __future__ import annotations

import math

__all__ = [
    "HertzChainError",
    "ParameterError",
    "StackFileError",
    "SolverError",
    "OutputPathError",
    "GradientAccuracyWarning",
    "check_parameter",
    "check_number",
    "check_positive",
    "check_non_negative",
]


class HertzChainError(Exception):
    """Base class of every error that hertz_chain raises on purpose."""


class ParameterError(HertzChainError, ValueError):
    """A parameter is out of its allowed range or of the wrong kind."""

    def __init__(self, name: str, value: object, allowed: str):
        value = _plain(value)
        self.name, self.value, self.allowed = name, value, allowed
        super().__init__(f"{name} = {value!r} is invalid: {allowed}")


def _plain(value: object) -> object:
    """A NumPy/JAX scalar as the Python number it holds (so that messages read `0.5`, not
    `np.float64(0.5)`); anything else unchanged."""
    if getattr(value, "shape", None) == () and hasattr(value, "item"):
        try:
            return value.item()
        except Exception:  # a traced value: leave it
            return value
    return value


class StackFileError(HertzChainError, ValueError):
    """A stack file (TOML) is malformed, has unknown keys, missing fields or wrong units."""


class OutputPathError(HertzChainError, ValueError):
    """An output file (`--output`, `--plot`) cannot be written where it was asked for: a missing or
    unwritable folder, a name too long or with an unknown extension, or an existing file (without
    `--force`). The message names the option (`key`), the path and what is allowed."""

    def __init__(self, key: str, path: object, problem: str):
        self.key, self.path, self.problem = key, path, problem
        super().__init__(" ".join(f"{key} {path}: {problem}".splitlines()))


class SolverError(HertzChainError, RuntimeError):
    """The ODE solver failed (max steps, non-finite state, ...). The message carries a hint."""


class GradientAccuracyWarning(UserWarning):
    """A derivative is computed where it is known to be less accurate than the solve: through a contact
    law with a `gradient_note` that does not refuse derivatives (`gradient_refused`: Jackson–Green's, whose
    loading curve jumps at the start of its published fit, are refused). Warned when such a derivative is
    traced (once per compilation)."""


def check_parameter(ok: bool, name: str, value: object, allowed: str) -> None:
    """Raise :class:`ParameterError` unless ``ok``.

    ``ok`` must be a concrete Python/NumPy boolean (validation happens outside JAX tracing).
    """
    if not bool(ok):
        raise ParameterError(name, value, allowed)


# ------------------------------------------------------------------ the one home of plain-number checks
# (quantities with units are parsed and range-checked by `hertz_chain.units`; these take plain SI numbers)
def _traced(value: object) -> bool:
    """Whether ``value`` is a JAX tracer (without importing JAX: the command line reads this module first)."""
    return any(c.__name__ == "Tracer" for c in type(value).__mro__)


TRACED = ("a concrete number: this builder reads configuration values; to differentiate with respect to a "
          "contact parameter, construct the law class directly (e.g. hertz_chain.Hertz(k), Tsuji(k, eta, m_eff))")


def check_number(value: object, name: str) -> float:
    """``float(value)``, or :class:`ParameterError` naming ``name`` for a non-number or NaN (or a JAX
    tracer: the builders that take plain numbers are not differentiable, `TRACED`)."""
    if _traced(value):
        raise ParameterError(name, "a traced value", TRACED)
    if isinstance(value, (str, bytes)):  # float("1e9") would pass, where arrays of strings are refused
        raise ParameterError(name, value, "a number (SI units; quantities with units go in a stack file)")
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(name, value, "a number") from None
    if math.isnan(v):
        raise ParameterError(name, value, "a number (not NaN)")
    return v


def check_positive(value: object, name: str, allow_inf: bool = False) -> float:
    """``float(value)`` if finite and > 0 (or ``inf`` with ``allow_inf``), else :class:`ParameterError`."""
    v = check_number(value, name)
    if not (v > 0.0 and (allow_inf or math.isfinite(v))):
        raise ParameterError(name, value, "a finite number > 0" + (" (inf for a flat)" if allow_inf else ""))
    return v


def check_non_negative(value: object, name: str) -> float:
    """``float(value)`` if finite and >= 0, else :class:`ParameterError`."""
    v = check_number(value, name)
    if not (math.isfinite(v) and v >= 0.0):
        raise ParameterError(name, value, "a finite number >= 0")
    return v
