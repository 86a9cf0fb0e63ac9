"""Normal contact-force laws, as JAX-traceable, differentiable `eqx.Module`s.

Conventions (SI units throughout):

* ``delta`` is the overlap (interpenetration) of the two bodies: ``delta > 0`` means compression.
  ``delta_dot`` is its rate: positive while the bodies approach.
* The force ``F`` is the repulsive normal force, pushing the bodies apart when ``F > 0``.
* No adhesion: ``F = 0`` for ``delta <= 0``. By default (``clamp=True``) the force is also clamped to
  ``F >= 0`` so that a damped contact never pulls (the bodies separate where ``F`` reaches zero);
  ``clamp=False`` keeps the raw law.
* Every field that holds a number is an array leaf (traced), so ``jax.vmap`` and ``jax.grad`` work
  over stiffness, damping and effective mass. ``clamp`` is static.

Energy bookkeeping: ``potential(delta)`` is the elastic energy stored by the conservative part
``elastic_force``; everything else in ``force`` is dissipative, so the dissipated power of a contact
is ``(force - elastic_force) * delta_dot``.
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike

from . import _config  # noqa: F401  (float64)

__all__ = [
    "AbstractContactLaw",
    "Hertz",
    "HuntCrossley",
    "Tsuji",
    "KelvinVoigt",
    "Viscoelastic",
]


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


class _HertzianElastic(AbstractContactLaw):
    """Shared elastic part ``k delta^{3/2}`` (Hertz 1882), with ``k = (4/3) E* sqrt(R*)``."""

    k: eqx.AbstractVar[Array]

    def elastic_force(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, self.k * d**1.5, 0.0)

    def potential(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, 0.4 * self.k * d**2.5, 0.0)


class Hertz(_HertzianElastic):
    """Elastic Hertz contact, ``F = k delta^{3/2}`` (Hertz 1882). Restitution 1.

    **Arguments:** ``k``, stiffness in N/m^1.5.
    """

    k: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.clamp = clamp


class HuntCrossley(_HertzianElastic):
    """Hunt–Crossley hysteretic damping, ``F = k delta^{3/2} (1 + alpha delta_dot)``.

    Hunt & Crossley (1975), J. Appl. Mech. 42, 440. ``alpha`` in s/m. With ``alpha`` fixed, the
    restitution falls as the impact velocity rises (``alpha = chi(e) / v_c`` reproduces ``e`` at the
    calibration velocity ``v_c`` only).
    """

    k: Array
    alpha: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, alpha: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.alpha = jnp.asarray(alpha, dtype=float)
        self.clamp = clamp

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        return self.elastic_force(delta) * self.alpha * delta_dot


class Tsuji(_HertzianElastic):
    """Tsuji et al. (1992) non-linear spring–dashpot,
    ``F = k delta^{3/2} + eta sqrt(m_eff k) delta^{1/4} delta_dot``.

    Tsuji, Tanaka & Ishida (1992), Powder Technol. 71, 239. Its restitution does not depend on the
    impact velocity. ``m_eff`` is the effective mass ``m1 m2 / (m1 + m2)`` of the interface (kg).
    """

    k: Array
    eta: Array
    m_eff: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, eta: ArrayLike, m_eff: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.eta = jnp.asarray(eta, dtype=float)
        self.m_eff = jnp.asarray(m_eff, dtype=float)
        self.clamp = clamp

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        c = self.eta * jnp.sqrt(self.m_eff * self.k)
        return jnp.where(mask, c * d**0.25 * delta_dot, 0.0)


class KelvinVoigt(AbstractContactLaw):
    """Linear spring–dashpot, ``F = k delta + c delta_dot`` (k in N/m, c in N s/m)."""

    k: Array
    c: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, c: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.c = jnp.asarray(c, dtype=float)
        self.clamp = clamp

    def elastic_force(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, self.k * d, 0.0)

    def potential(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, 0.5 * self.k * d**2, 0.0)

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        mask, _ = _positive_part(delta)
        return jnp.where(mask, self.c * delta_dot, 0.0)


class Viscoelastic(_HertzianElastic):
    """Viscoelastic Hertz contact, ``F = k (delta^{3/2} + (3/2) A sqrt(delta) delta_dot)``.

    Brilliantov, Spahn, Hertzsch & Pöschel (1996), Phys. Rev. E 53, 5382. ``A`` (s) is the
    dissipative material constant; restitution falls with impact velocity as
    ``e = 1 - 1.15344 xi + 0.79826 xi^2 - ...``, ``xi = (3/2) A (k/m_eff)^{2/5} v^{1/5}``
    (Ramírez et al. 1999).
    """

    k: Array
    A: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, A: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.A = jnp.asarray(A, dtype=float)
        self.clamp = clamp

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, 1.5 * self.k * self.A * jnp.sqrt(d) * delta_dot, 0.0)
