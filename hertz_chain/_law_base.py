"""The base of every contact law: `AbstractContactLaw` (the interface `Stack` and the solvers call), the
masking helper that keeps fractional powers differentiable where a contact is open, and the argument
checks the laws' constructors share. The conventions are those of `hertz_chain.contact`, which holds the
laws and re-exports this base.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from . import _config  # noqa: F401  (float64)
from .errors import ParameterError, check_non_negative, check_positive


def _positive_part(delta: ArrayLike) -> tuple[Array, Array]:
    """Return ``(mask, delta_safe)``: ``delta_safe`` is 1 where ``delta <= 0``.

    The double-``where`` trick (jax-md): fractional powers of ``delta_safe`` have finite gradients
    everywhere, and the final ``where(mask, ..., 0)`` removes them where the contact is open.
    """
    delta = jnp.asarray(delta)
    mask = delta > 0
    return mask, jnp.where(mask, delta, 1.0)


class AbstractContactLaw(eqx.Module):
    """A normal contact law ``F(delta, delta_dot)``; see the module docstring for conventions."""

    clamp: eqx.AbstractVar[bool]
    name: ClassVar[str] = ""
    has_memory: ClassVar[bool] = False
    """A law with memory (elastic–plastic) keeps one internal variable per interface, its largest overlap
    so far `q`, in the ODE state; its `force`, `elastic_force` and `potential` take `q` as a third
    argument, and it defines `memory_rate` and `dissipated_power` (`Thornton`)."""
    #: where the replayed derivatives (`hertz_chain._adjoint`) are known to be less accurate than the solve
    #: through this law, and why (warned, `GradientAccuracyWarning`, when such a derivative is traced); None
    gradient_note: ClassVar[str | None] = None
    #: derivatives through this law are refused (`ParameterError` when traced; the note says why)
    gradient_refused: ClassVar[bool] = False
    #: the constructor's checks, per field: `(lowest, strict, what)`: finite and `> lowest` (`strict`) or
    #: `>= lowest`; checked by `__check_init__` wherever the value is concrete (a traced value, under
    #: `jit`, `vmap` or `grad`, cannot be: the solve reports what it does instead)
    field_rules: ClassVar[dict[str, tuple[float, bool, str]]] = {}

    def __check_init__(self):
        """The law's own numbers, as built by its constructor (not only by `make_law`): a review found
        `Hertz(-1e9)` ran to "no contact" with NaN launch velocities, `Hertz(nan)` to 65,536 steps and
        "raise max_steps", and `Tsuji(1e9, -0.5, 1.0)` created energy (e = 1.57)."""
        for field, (lowest, strict, what) in self.field_rules.items():
            _check_field(field, getattr(self, field), lowest, strict, what, type(self).__name__)

    @abc.abstractmethod
    def elastic_force(self, delta: ArrayLike) -> Array:
        """Conservative part of the force; zero for ``delta <= 0``."""

    @abc.abstractmethod
    def potential(self, delta: ArrayLike) -> Array:
        """Elastic energy ``∫_0^delta elastic_force``; zero for ``delta <= 0``."""

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        """Dissipative part of the unclamped force; zero for ``delta <= 0``."""
        return jnp.zeros_like(jnp.asarray(delta, dtype=float))

    def force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        """Total normal force, zero for ``delta <= 0``, and ``>= 0`` when ``clamp``."""
        f = self.elastic_force(delta) + self.damping_force(delta, delta_dot)
        if self.clamp:
            f = jnp.maximum(f, 0.0)
        return f

    def dissipated_power(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        """Power dissipated by the contact (W): ``(force - elastic_force) delta_dot``."""
        return (self.force(delta, delta_dot) - self.elastic_force(delta)) * delta_dot

    def separation(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        """A function ``> 0`` exactly while the contact pushes, ``<= 0`` once it is open
        (`Stack.separation_function`): the unclamped force over the secant stiffness with the clamp,
        the overlap without it."""
        delta = jnp.asarray(delta, dtype=float)
        el = self.elastic_force(delta)
        fu = el + self.damping_force(delta, delta_dot)
        ok = (delta > 0) & (el > 0) & self.clamp
        return jnp.where(ok, fu * delta / jnp.where(ok, el, 1.0), delta)

    @classmethod
    def dimensionless_damping(cls, restitution: float, *, chi_map: str = "exact", clamp: bool = True) -> float:
        """The law's dimensionless damping for the restitution ``e`` (concrete; scipy, cached): the
        number that, with the interface's stiffness, effective mass and calibration speed, fixes the
        law's damping parameter (`from_dimensionless`). Every law calibrated to a restitution defines it
        (optimize, sweep and fit rebuild its contacts from it, `_design.DesignMap`); elastic laws and laws
        with memory are never asked.

        **Raises** `NotImplementedError` for a law that does not define it (it returned 0, and a new law
        ran undamped in a sweep)."""
        raise NotImplementedError(f"{cls.__name__}.dimensionless_damping: a law calibrated to a restitution "
                                  "defines it and from_dimensionless (docs/developers.md, 'Adding a contact law')")

    @classmethod
    def from_dimensionless(cls, k, d, *, effective_mass, calibration_velocity, clamp: bool = True):
        """The law from its stiffness ``k`` and dimensionless damping ``d`` (`dimensionless_damping`):
        JAX-traceable and differentiable in every argument, so that a design's contacts follow its
        masses (`hertz_chain.optimization`). ``calibration_velocity`` is used by the speed-dependent laws.

        **Raises** `NotImplementedError` for a law that does not define it (as `dimensionless_damping`)."""
        raise NotImplementedError(f"{cls.__name__}.from_dimensionless: a law calibrated to a restitution "
                                  "defines it and dimensionless_damping (docs/developers.md, 'Adding a contact "
                                  "law')")

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """Coefficient of restitution of an isolated impact at ``impact_velocity`` (m/s).

        Concrete (non-traced) values only: computed with scipy by `hertz_chain.calibration`.
        ``effective_mass`` (kg) is needed by the laws whose restitution depends on it.
        Returns a float, or a NumPy array broadcast over the law's parameters and the velocity.
        """
        raise NotImplementedError  # pragma: no cover


def _check_field(field: str, value, lowest: float, strict: bool, what: str, law: str) -> None:
    """`ParameterError` unless every entry of a concrete `value` is finite and `> lowest` (`strict`) or
    `>= lowest`; a traced value passes (its numbers are not known here)."""
    if isinstance(value, jax.core.Tracer):
        return
    a = np.asarray(value, dtype=float)
    ok = np.isfinite(a) & ((a > lowest) if strict else (a >= lowest))
    if not np.all(ok):
        bad = a if a.ndim == 0 else a[~ok].ravel()[0]
        where = "" if a.ndim == 0 else f" (an entry of {field}, shape {a.shape})"
        raise ParameterError(field, float(bad), f"{law}'s {what} must be finite and {'>' if strict else '>='} "
                             f"{lowest:g}{where}")


def _scalar(a):
    a = np.asarray(a, dtype=float)
    return float(a) if a.ndim == 0 else a


_positive = check_positive
_nonnegative = check_non_negative


def _stiffness(k) -> float:
    return _positive(k, "stiffness")


def _velocity(v) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if a.size == 0 or np.any(~np.isfinite(a)) or np.any(a <= 0):
        raise ParameterError("impact_velocity", v, "finite and > 0 (m/s, approach speed)")
    return a


def _require(value, name: str, law: str):
    if value is None:
        raise ParameterError(name, None, f"required by the {law!r} law")
    return value


