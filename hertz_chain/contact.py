"""Normal contact-force laws, as JAX-traceable, differentiable `eqx.Module`s.

Conventions (SI units throughout):

* ``delta`` is the overlap (interpenetration) of the two bodies: ``delta > 0`` means compression.
  ``delta_dot`` is its rate: positive while the bodies approach.
* The force ``F`` is the repulsive normal force, pushing the bodies apart when ``F > 0``.
* No adhesion: ``F = 0`` for ``delta <= 0``. By default (``clamp=True``) the force is also clamped to
  ``F >= 0`` so that a damped contact never pulls (the bodies separate where ``F`` reaches zero);
  ``clamp=False`` keeps the raw law.
* Each class has a ``name`` (the configuration name used in stack files) and a
  ``restitution_at(impact_velocity, effective_mass=None)`` method that reports the coefficient of
  restitution of an isolated impact (concrete numbers only; it calls scipy, see
  `hertz_chain.calibration`). The damped laws have ``from_restitution`` constructors, and
  `make_law` builds any law by name, as the stack-file reader does.
* Every field that holds a number is an array leaf (traced), so ``jax.vmap`` and ``jax.grad`` work
  over stiffness, damping and effective mass. ``clamp`` is static.

Energy bookkeeping: ``potential(delta)`` is the elastic energy stored by the conservative part
``elastic_force``; everything else in ``force`` is dissipative, so the dissipated power of a contact
is ``(force - elastic_force) * delta_dot``.
"""

from __future__ import annotations

import abc
import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from . import _config  # noqa: F401  (float64)
from . import calibration as _cal
from . import registry as _registry
from .errors import ParameterError, check_non_negative, check_positive

__all__ = [
    "AbstractContactLaw",
    "Hertz",
    "HuntCrossley",
    "Tsuji",
    "KelvinVoigt",
    "Viscoelastic",
    "HertzDashpot",
    "PowerLaw",
    "Thornton",
    "JacksonGreen",
    "LAW_NAMES",
    "make_law",
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
    name: ClassVar[str] = ""
    has_memory: ClassVar[bool] = False
    """A law with memory (elastic–plastic) keeps one internal variable per interface, its largest overlap
    so far `q`, in the ODE state; its `force`, `elastic_force` and `potential` take `q` as a third
    argument, and it defines `memory_rate` and `dissipated_power` (`Thornton`)."""

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
        law's damping parameter (`from_dimensionless`). 0 for an elastic law."""
        return 0.0

    @classmethod
    def from_dimensionless(cls, k, d, *, effective_mass, calibration_velocity, clamp: bool = True):
        """The law from its stiffness ``k`` and dimensionless damping ``d`` (`dimensionless_damping`):
        JAX-traceable and differentiable in every argument, so that a design's contacts follow its
        masses (`hertz_chain.optimization`). ``calibration_velocity`` is used by the speed-dependent laws."""
        raise NotImplementedError  # pragma: no cover

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """Coefficient of restitution of an isolated impact at ``impact_velocity`` (m/s).

        Concrete (non-traced) values only: computed with scipy by `hertz_chain.calibration`.
        ``effective_mass`` (kg) is needed by the laws whose restitution depends on it.
        Returns a float, or a NumPy array broadcast over the law's parameters and the velocity.
        """
        raise NotImplementedError  # pragma: no cover


class _HertzianElastic(AbstractContactLaw):
    """Shared elastic part ``k delta^{3/2}`` (Hertz 1882), with ``k = (4/3) E* sqrt(R*)``."""

    k: eqx.AbstractVar[Array]

    def elastic_force(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        # d*sqrt(d), not d**1.5: XLA lowers a fractional power to exp/log, several times slower.
        return jnp.where(mask, self.k * d * jnp.sqrt(d), 0.0)

    def potential(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, 0.4 * self.k * d * d * jnp.sqrt(d), 0.0)


class Hertz(_HertzianElastic):
    """Elastic Hertz contact, ``F = k delta^{3/2}`` (Hertz 1882). Restitution 1.

    **Arguments:** ``k``, stiffness in N/m^1.5.
    """

    name: ClassVar[str] = "hertz"
    k: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.clamp = clamp

    @classmethod
    def from_config(cls, k, *, restitution=None, damping=None, effective_mass=None, calibration_velocity=None,
                    chi_map="exact", clamp=True) -> "Hertz":
        """`make_law`'s constructor (`hertz_chain.registry.LAWS`): elastic, so only `restitution = 1`."""
        if restitution is not None and restitution != 1.0:
            raise ParameterError("restitution", restitution, "'hertz' is elastic (e = 1); use a damped law for e < 1")
        return cls(_stiffness(k), clamp)

    @classmethod
    def from_dimensionless(cls, k, d, *, effective_mass, calibration_velocity, clamp=True) -> "Hertz":
        """``Hertz(k)`` (``d`` is 0)."""
        return cls(k, clamp)

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """Always 1 (elastic)."""
        v = _velocity(impact_velocity)
        out = np.ones(np.broadcast_shapes(v.shape, np.shape(self.k)))
        return _scalar(out)


class HuntCrossley(_HertzianElastic):
    """Hunt–Crossley hysteretic damping, ``F = k delta^{3/2} (1 + alpha delta_dot)``.

    Hunt & Crossley (1975), J. Appl. Mech. 42, 440. ``alpha`` in s/m. With ``alpha`` fixed, the
    restitution falls as the impact velocity rises (``alpha = chi(e) / v_c`` reproduces ``e`` at the
    calibration velocity ``v_c`` only): ``restitution_at(v)`` gives the exact ``e(chi = alpha v)``
    (Carvalho & Martins 2019, Mech. Mach. Theory 139, 1; see `hertz_chain.calibration`).

    **The force never becomes tensile** along the isolated-impact trajectory started at
    ``delta = 0``, ``delta_dot = v > 0``, so the clamp never acts and the exact map holds with and
    without it. Proof: ``u = 1 + alpha delta_dot`` obeys
    ``du/dt = alpha delta_ddot = -(alpha k/m) delta^{3/2} u``, hence
    ``u(t) = (1 + alpha v) exp(-(alpha k/m) ∫_0^t delta^{3/2} ds) > 0`` and
    ``F = k delta^{3/2} u >= 0`` (checked numerically in ``tests/test_calibration.py``). In a
    stack, where the interface is also driven by its neighbours, the clamp can still act.
    """

    name: ClassVar[str] = "hunt-crossley"
    k: Array
    alpha: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, alpha: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.alpha = jnp.asarray(alpha, dtype=float)
        self.clamp = clamp

    @classmethod
    def from_restitution(
        cls,
        k: ArrayLike,
        restitution: float,
        calibration_velocity: float,
        chi_map: str = "exact",
        clamp: bool = True,
    ) -> "HuntCrossley":
        """``alpha = chi(e)/v_c`` with ``chi`` from the named map (`calibration.CHI_MAPS`)."""
        k = _stiffness(k)
        return cls(k, _cal.hunt_crossley_alpha(restitution, calibration_velocity, chi_map), clamp)

    @classmethod
    def from_config(cls, k, *, restitution=None, damping=None, effective_mass=None, calibration_velocity=None,
                    chi_map="exact", clamp=True) -> "HuntCrossley":
        """`make_law`'s constructor: ``alpha = damping``, or calibrated to ``restitution`` at
        ``calibration_velocity`` with ``chi_map``."""
        if restitution is None:
            return cls(_stiffness(k), damping, clamp)
        v = _positive(_require(calibration_velocity, "calibration_velocity", cls.name), "calibration_velocity")
        return cls.from_restitution(k, restitution, v, chi_map, clamp)

    @classmethod
    def dimensionless_damping(cls, restitution, *, chi_map="exact", clamp=True) -> float:
        """``chi(e)`` from the named map (`calibration.chi_from_restitution`)."""
        return _cal.chi_from_restitution(restitution, chi_map)

    @classmethod
    def from_dimensionless(cls, k, d, *, effective_mass, calibration_velocity, clamp=True) -> "HuntCrossley":
        """``alpha = chi / v_c``."""
        return cls(k, d / calibration_velocity, clamp)

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """Exact ``e(chi = alpha v)``; independent of ``k``, ``m*`` and the clamp."""
        return _cal.hunt_crossley_restitution(np.asarray(self.alpha), _velocity(impact_velocity))

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        return self.elastic_force(delta) * self.alpha * delta_dot


class Tsuji(_HertzianElastic):
    """Tsuji et al. (1992) non-linear spring–dashpot,
    ``F = k delta^{3/2} + eta sqrt(m_eff k) delta^{1/4} delta_dot``.

    Tsuji, Tanaka & Ishida (1992), Powder Technol. 71, 239. Its restitution does not depend on the
    impact velocity. ``m_eff`` is the effective mass ``m1 m2 / (m1 + m2)`` of the interface (kg).

    Without the clamp, ``eta = -sqrt(5) ln e / sqrt(pi^2 + ln^2 e)`` is exact; with the clamp
    (default) ``from_restitution`` calibrates ``eta`` numerically. (With ``u = delta^{5/4}`` and a
    rescaled time the law is exactly the linear spring-dashpot with ``zeta = eta/sqrt(5)``, clamped
    or not; see `hertz_chain.calibration`.)
    """

    name: ClassVar[str] = "tsuji"
    k: Array
    eta: Array
    m_eff: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, eta: ArrayLike, m_eff: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.eta = jnp.asarray(eta, dtype=float)
        self.m_eff = jnp.asarray(m_eff, dtype=float)
        self.clamp = clamp

    @classmethod
    def from_restitution(
        cls, k: ArrayLike, restitution: float, m_eff: ArrayLike, clamp: bool = True
    ) -> "Tsuji":
        """``eta(e, clamp)`` from `calibration.tsuji_eta` (exact unclamped, numerical clamped)."""
        k, m = _stiffness(k), _positive(m_eff, "effective_mass")
        return cls(k, _cal.tsuji_eta(restitution, clamp), m, clamp)

    @classmethod
    def from_config(cls, k, *, restitution=None, damping=None, effective_mass=None, calibration_velocity=None,
                    chi_map="exact", clamp=True) -> "Tsuji":
        """`make_law`'s constructor: ``eta = damping``, or calibrated to ``restitution``; the
        ``effective_mass`` is always needed (it is part of the law)."""
        m = _positive(_require(effective_mass, "effective_mass", cls.name), "effective_mass")
        if restitution is None:
            return cls(_stiffness(k), damping, m, clamp)
        return cls.from_restitution(k, restitution, m, clamp)

    @classmethod
    def dimensionless_damping(cls, restitution, *, chi_map="exact", clamp=True) -> float:
        """``eta(e, clamp)`` (`calibration.tsuji_eta`)."""
        return _cal.tsuji_eta(restitution, clamp)

    @classmethod
    def from_dimensionless(cls, k, d, *, effective_mass, calibration_velocity, clamp=True) -> "Tsuji":
        """``Tsuji(k, eta = d, m_eff)``."""
        return cls(k, d, effective_mass, clamp)

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """Restitution for ``eta`` (the same at every impact speed)."""
        v = _velocity(impact_velocity)
        eta, _ = np.broadcast_arrays(np.asarray(self.eta, dtype=float), v)
        return _scalar(np.vectorize(lambda h: _cal.tsuji_restitution(h, self.clamp))(eta))

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        c = self.eta * jnp.sqrt(self.m_eff * self.k)
        return jnp.where(mask, c * jnp.sqrt(jnp.sqrt(d)) * delta_dot, 0.0)


class KelvinVoigt(AbstractContactLaw):
    """Linear spring–dashpot, ``F = k delta + c delta_dot`` (k in N/m, c in N s/m).

    ``c = 2 zeta sqrt(m_eff k)``. Without the clamp ``zeta = -ln e / sqrt(pi^2 + ln^2 e)`` is exact;
    with the clamp (default) the bodies separate at ``F = 0`` while ``delta > 0`` and that ``zeta``
    gives a larger ``e`` (Schwager & Pöschel 2007, Granular Matter 9, 465): ``from_restitution``
    calibrates ``zeta`` numerically. Its restitution does not depend on the impact velocity.
    """

    name: ClassVar[str] = "kelvin-voigt"
    k: Array
    c: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, c: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.c = jnp.asarray(c, dtype=float)
        self.clamp = clamp

    @classmethod
    def from_restitution(
        cls, k: ArrayLike, restitution: float, m_eff: ArrayLike, clamp: bool = True
    ) -> "KelvinVoigt":
        """``c = 2 zeta(e, clamp) sqrt(m_eff k)`` (`calibration.kelvin_voigt_damping_ratio`)."""
        k, m = _stiffness(k), _positive(m_eff, "effective_mass")
        zeta = _cal.kelvin_voigt_damping_ratio(restitution, clamp)
        return cls(k, 2.0 * zeta * np.sqrt(m * k), clamp)

    @classmethod
    def from_config(cls, k, *, restitution=None, damping=None, effective_mass=None, calibration_velocity=None,
                    chi_map="exact", clamp=True) -> "KelvinVoigt":
        """`make_law`'s constructor: ``c = damping``, or calibrated to ``restitution`` (needs
        ``effective_mass``)."""
        if restitution is None:
            return cls(_stiffness(k), damping, clamp)
        m = _positive(_require(effective_mass, "effective_mass", cls.name), "effective_mass")
        return cls.from_restitution(k, restitution, m, clamp)

    @classmethod
    def dimensionless_damping(cls, restitution, *, chi_map="exact", clamp=True) -> float:
        """``zeta(e, clamp)`` (`calibration.kelvin_voigt_damping_ratio`)."""
        return _cal.kelvin_voigt_damping_ratio(restitution, clamp)

    @classmethod
    def from_dimensionless(cls, k, d, *, effective_mass, calibration_velocity, clamp=True) -> "KelvinVoigt":
        """``c = 2 zeta sqrt(m_eff k)``."""
        return cls(k, 2.0 * d * jnp.sqrt(effective_mass * k), clamp)

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """Restitution for ``zeta = c / (2 sqrt(m_eff k))`` (the same at every impact speed)."""
        v = _velocity(impact_velocity)
        m = _positive(_require(effective_mass, "effective_mass", self.name), "effective_mass")
        zeta = np.asarray(self.c, dtype=float) / (2.0 * np.sqrt(m * np.asarray(self.k, dtype=float)))
        zeta, _ = np.broadcast_arrays(zeta, v)
        return _scalar(np.vectorize(lambda z: _cal.kelvin_voigt_restitution(z, self.clamp))(zeta))

    def elastic_force(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, self.k * d, 0.0)

    def potential(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, 0.5 * self.k * d**2, 0.0)

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        mask, _ = _positive_part(delta)
        return jnp.where(mask, self.c * delta_dot, 0.0)


class _SpeedAndMassCalibrated(_HertzianElastic):
    """A Hertzian law with one damping parameter whose restitution depends on the impact speed and the
    effective mass (`Viscoelastic`, `HertzDashpot`): `make_law` builds it from its raw parameter, or
    calibrates it with its `from_restitution(k, e, m_eff, v_c, clamp)`."""

    @classmethod
    def from_config(cls, k, *, restitution=None, damping=None, effective_mass=None, calibration_velocity=None,
                    chi_map="exact", clamp=True):
        """`make_law`'s constructor: the raw ``damping``, or calibrated to ``restitution`` at
        ``calibration_velocity`` (needs ``effective_mass``)."""
        if restitution is None:
            return cls(_stiffness(k), damping, clamp)
        m = _positive(_require(effective_mass, "effective_mass", cls.name), "effective_mass")
        v = _positive(_require(calibration_velocity, "calibration_velocity", cls.name), "calibration_velocity")
        return cls.from_restitution(k, restitution, m, v, clamp)


class Viscoelastic(_SpeedAndMassCalibrated):
    """Viscoelastic Hertz contact, ``F = k (delta^{3/2} + (3/2) A sqrt(delta) delta_dot)``.

    Brilliantov, Spahn, Hertzsch & Pöschel (1996), Phys. Rev. E 53, 5382. ``A`` (s) is the
    dissipative material constant; restitution falls with impact velocity as
    ``e = 1 - 1.15344 xi + 0.79826 xi^2 - ...``, ``xi = (3/2) A (k/m_eff)^{2/5} v^{1/5}``
    (Ramírez et al. 1999, Phys. Rev. E 60, 4465). The exact ``e(xi, clamp)`` has no closed form: it
    is computed numerically (`hertz_chain.calibration.viscoelastic_restitution`).
    """

    name: ClassVar[str] = "viscoelastic"
    k: Array
    A: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, A: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.A = jnp.asarray(A, dtype=float)
        self.clamp = clamp

    @classmethod
    def from_restitution(
        cls,
        k: ArrayLike,
        restitution: float,
        m_eff: ArrayLike,
        calibration_velocity: float,
        clamp: bool = True,
    ) -> "Viscoelastic":
        """``A`` such that the impact at ``calibration_velocity`` has restitution ``e``."""
        k, m = _stiffness(k), _positive(m_eff, "effective_mass")
        v = _positive(calibration_velocity, "calibration_velocity")
        xi = _cal.viscoelastic_xi(restitution, clamp)
        return cls(k, _cal.viscoelastic_A_from_xi(xi, k, m, v), clamp)

    @classmethod
    def dimensionless_damping(cls, restitution, *, chi_map="exact", clamp=True) -> float:
        """``xi(e, clamp)`` (`calibration.viscoelastic_xi`)."""
        return _cal.viscoelastic_xi(restitution, clamp)

    @classmethod
    def from_dimensionless(cls, k, d, *, effective_mass, calibration_velocity, clamp=True) -> "Viscoelastic":
        """``A = xi / ((3/2) (k/m_eff)^{2/5} v_c^{1/5})`` (Ramírez et al. 1999)."""
        return cls(k, d / (1.5 * (k / effective_mass) ** 0.4 * calibration_velocity**0.2), clamp)

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """``e(xi)`` with ``xi = (3/2) A (k/m_eff)^{2/5} v^{1/5}``; falls as ``v`` rises."""
        v = _velocity(impact_velocity)
        m = _positive(_require(effective_mass, "effective_mass", self.name), "effective_mass")
        k = np.asarray(self.k, dtype=float)
        xi = 1.5 * np.asarray(self.A, dtype=float) * (k / m) ** 0.4 * v**0.2
        return _scalar(np.vectorize(lambda x: _cal.viscoelastic_restitution(x, self.clamp))(xi))

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, 1.5 * self.k * self.A * jnp.sqrt(d) * delta_dot, 0.0)


class HertzDashpot(_SpeedAndMassCalibrated):
    """Hertz with a linear dashpot, ``F = k delta^{3/2} + gamma delta_dot`` (gamma in N s/m): the model
    of dissipative granular chains of Rosas, Romero, Nesterenko & Lindenberg (2007), "Observation of
    two-wave structure in strongly nonlinear dissipative granular chains", Phys. Rev. Lett. 99, 164301.

    The dashpot acts from the first touch, so the force jumps to ``gamma v`` at contact (a rough onset for
    the solver and for gradients: `registry.LawRow.smooth_onset` is False). Its restitution depends on
    the impact speed and the effective mass: in Hertz units it is a function of
    ``zeta = gamma m*^{-3/5} k^{-2/5} v^{-1/5}`` alone (`calibration.hertz_dashpot_zeta`), so with
    ``gamma`` fixed ``e`` *rises* with the impact speed (the opposite of Hunt–Crossley and the
    viscoelastic law). ``from_restitution`` calibrates ``gamma`` at one speed.
    """

    name: ClassVar[str] = "hertz-dashpot"
    k: Array
    gamma: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, gamma: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.gamma = jnp.asarray(gamma, dtype=float)
        self.clamp = clamp

    @classmethod
    def from_restitution(cls, k, restitution: float, m_eff, calibration_velocity: float,
                         clamp: bool = True) -> "HertzDashpot":
        """``gamma = zeta(e) m*^{3/5} k^{2/5} v_c^{1/5}``, so that the impact at ``v_c`` has restitution e."""
        k, m = _stiffness(k), _positive(m_eff, "effective_mass")
        v = _positive(calibration_velocity, "calibration_velocity")
        return cls(k, _cal.hertz_dashpot_zeta(restitution, clamp) * m**0.6 * k**0.4 * v**0.2, clamp)

    @classmethod
    def dimensionless_damping(cls, restitution, *, chi_map="exact", clamp=True) -> float:
        """``zeta(e, clamp)`` (`calibration.hertz_dashpot_zeta`)."""
        return _cal.hertz_dashpot_zeta(restitution, clamp)

    @classmethod
    def from_dimensionless(cls, k, d, *, effective_mass, calibration_velocity, clamp=True) -> "HertzDashpot":
        """``gamma = zeta m*^{3/5} k^{2/5} v_c^{1/5}``."""
        return cls(k, d * effective_mass**0.6 * k**0.4 * calibration_velocity**0.2, clamp)

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """``e(zeta)`` with ``zeta = gamma m*^{-3/5} k^{-2/5} v^{-1/5}``; rises with ``v``."""
        v = _velocity(impact_velocity)
        m = _positive(_require(effective_mass, "effective_mass", self.name), "effective_mass")
        zeta = np.asarray(self.gamma, dtype=float) * m**-0.6 * np.asarray(self.k, dtype=float) ** -0.4 * v**-0.2
        return _scalar(np.vectorize(lambda z: _cal.hertz_dashpot_restitution(z, self.clamp))(zeta))

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        mask, _ = _positive_part(delta)
        return jnp.where(mask, self.gamma * delta_dot, 0.0)


class PowerLaw(AbstractContactLaw):
    """A power law with Hunt–Crossley damping of the same exponent, ``F = k delta^p (1 + alpha delta_dot)``
    (``p >= 1``; ``alpha = 0``: elastic). ``p = 3/2`` is Hertz (``HuntCrossley``), ``p = 1`` the linear
    spring, other ``p`` model conforming or rough contacts and the general granular-chain laws (Nesterenko
    2001, Ch. 1). ``k`` in N/m^p.

    The restitution depends on ``chi = alpha v`` alone, whatever ``p`` and ``k``: the exact map of
    Carvalho & Martins (2019), Mech. Mach. Theory 139, 1, holds for any exponent
    (`calibration.restitution_from_chi`), so ``from_config`` calibrates ``alpha = chi(e) / v_c`` exactly.
    """

    name: ClassVar[str] = "power"
    k: Array
    p: Array
    alpha: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, p: ArrayLike, alpha: ArrayLike = 0.0, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.p = jnp.asarray(p, dtype=float)
        self.alpha = jnp.asarray(alpha, dtype=float)
        self.clamp = clamp

    @classmethod
    def from_config(cls, k, *, restitution=None, damping=None, effective_mass=None, calibration_velocity=None,
                    chi_map="exact", clamp=True, exponent=None) -> "PowerLaw":
        """`make_law`'s constructor: ``exponent`` p, and ``alpha = damping`` or calibrated to
        ``restitution`` at ``calibration_velocity`` with ``chi_map``."""
        p = float(_require(exponent, "exponent", cls.name))
        if not (math.isfinite(p) and p >= 1.0):
            raise ParameterError("exponent", exponent, "a finite number >= 1")
        if restitution is None:
            return cls(_stiffness(k), p, damping, clamp)
        v = _positive(_require(calibration_velocity, "calibration_velocity", cls.name), "calibration_velocity")
        return cls(_stiffness(k), p, _cal.hunt_crossley_alpha(restitution, v, chi_map), clamp)

    def elastic_force(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, self.k * jnp.power(d, self.p), 0.0)

    def potential(self, delta: ArrayLike) -> Array:
        mask, d = _positive_part(delta)
        return jnp.where(mask, self.k * jnp.power(d, self.p + 1.0) / (self.p + 1.0), 0.0)

    def damping_force(self, delta: ArrayLike, delta_dot: ArrayLike) -> Array:
        return self.elastic_force(delta) * self.alpha * delta_dot

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """Exact ``e(chi = alpha v)`` (any ``p``, ``k``, ``m*``)."""
        return _cal.hunt_crossley_restitution(np.asarray(self.alpha), _velocity(impact_velocity))


class _ElasticPlastic(AbstractContactLaw):
    """Shared mechanics of the elastic–plastic laws with memory (`Thornton`, `JacksonGreen`): loading
    while the overlap is the largest so far (``q``, carried in the ODE state), elastic Hertz unloading
    ``F = k_u (delta - delta_p)^{3/2}`` from it, the recoverable energy ``(2/5) k_u (delta - delta_p)^{5/2}``
    and the plastic power ``-dU/ddelta* · d(delta*)/dt``. A subclass gives ``_unloading(peak) -> (k_u,
    delta_p)``, whose unloading curve passes through the loading curve at the peak."""

    has_memory: ClassVar[bool] = True

    @abc.abstractmethod
    def _unloading(self, peak):
        """``(k_u, delta_p)`` of the unloading curve from the largest overlap ``peak``."""

    def _peak(self, delta, q):
        delta = jnp.asarray(delta, dtype=float)
        return delta if q is None else jnp.maximum(q, delta)

    def elastic_force(self, delta: ArrayLike, q: ArrayLike | None = None) -> Array:
        """The force: on the loading curve while ``delta >= q``, else on the unloading curve."""
        k_u, dp = self._unloading(self._peak(delta, q))
        mask, s = _positive_part(jnp.asarray(delta, dtype=float) - dp)
        return jnp.where(mask, k_u * s * jnp.sqrt(s), 0.0)

    def _energy(self, delta, peak):
        k_u, dp = self._unloading(peak)
        mask, s = _positive_part(jnp.asarray(delta, dtype=float) - dp)
        return jnp.where(mask, 0.4 * k_u * s * s * jnp.sqrt(s), 0.0)

    def potential(self, delta: ArrayLike, q: ArrayLike | None = None) -> Array:
        """Recoverable elastic energy ``(2/5) k_u (delta - delta_p)^{5/2}`` (J)."""
        return self._energy(delta, self._peak(delta, q))

    def force(self, delta: ArrayLike, delta_dot: ArrayLike, q: ArrayLike | None = None) -> Array:
        return self.elastic_force(delta, q)

    def memory_rate(self, delta: ArrayLike, delta_dot: ArrayLike, q: ArrayLike) -> Array:
        """``dq/dt``: the overlap rate while loading (``delta >= q``, approaching), else 0."""
        delta = jnp.asarray(delta, dtype=float)
        return jnp.where((delta > 0) & (delta >= q), jnp.maximum(delta_dot, 0.0), 0.0)

    def dissipated_power(self, delta: ArrayLike, delta_dot: ArrayLike, q: ArrayLike | None = None) -> Array:
        """Plastic power ``-dU/ddelta* · d(delta*)/dt`` (W), ``delta* = max(q, delta)``."""
        delta = jnp.asarray(delta, dtype=float)
        q = jnp.zeros_like(delta) if q is None else q
        peak = jnp.maximum(q, delta)
        rate = jnp.where(delta > q, delta_dot, self.memory_rate(delta, delta_dot, q))
        # through the peak only (not `potential`, whose max(q, delta) would share the derivative at a tie)
        _, dU = jax.jvp(lambda p: self._energy(delta, p), (peak,), (rate,))
        return -dU

    def separation(self, delta: ArrayLike, delta_dot: ArrayLike, q: ArrayLike | None = None) -> Array:
        """``delta - delta_p``: the contact is open once the overlap is back at the permanent one."""
        _, dp = self._unloading(self._peak(delta, q))
        return jnp.asarray(delta, dtype=float) - dp


class Thornton(_ElasticPlastic):
    """Elastic–perfectly plastic contact of Thornton (1997), "Coefficient of restitution for collinear
    collisions of elastic-perfectly plastic spheres", J. Appl. Mech. 64, 383.

    - **Loading**, while the overlap ``delta`` is the largest so far: Hertz, ``F = k delta^{3/2}``, up to
      the yield overlap ``delta_y``, where the peak contact pressure reaches the limiting pressure ``p_y``
      (``delta_y = R (pi p_y / (2 E*))^2``); beyond it the linear plastic branch
      ``F = F_y + pi p_y R (delta - delta_y)`` with ``F_y = k delta_y^{3/2}``. With ``k = (4/3) E* sqrt(R)``
      its slope is ``pi p_y R = (3/2) k sqrt(delta_y)``, so the law depends on ``k`` and ``delta_y`` only.
    - **Unloading** from the largest overlap ``delta*`` (force ``F*``): elastic Hertz with the enlarged
      radius ``R_p = 4 E* a_p^3 / (3 F*)``, ``a_p^2 = R delta*`` (Thornton's ``(2F* + F_y)/(2 pi p_y)``),
      about the permanent overlap ``delta_p = delta* - a_p^2 / R_p``: ``F = k_u (delta - delta_p)^{3/2}``
      with ``k_u = k sqrt(R_p / R) = k sqrt(k delta*^{3/2} / F*)`` and ``delta_p = delta* - F* / (k
      sqrt(delta*))``. Reloading follows the unloading curve up to ``delta*``, then the plastic branch.

    **Memory.** ``q``, the largest overlap so far (m), is carried in the ODE state, one per interface, with
    ``dq/dt = max(delta_dot, 0)`` while ``delta >= q`` (0 otherwise); the force uses ``max(q, delta)``, so a
    lagging ``q`` never puts a loading contact on its unloading curve. The dissipated (plastic) power is
    ``-dU/ddelta* · d(delta*)/dt``, ``U`` the recoverable energy ``(2/5) k_u (delta - delta_p)^{5/2}``, so
    the energy audit closes.

    **Restitution** (`restitution_at`, exact for this law): ``e = 1`` up to the yield velocity
    ``V_y = sqrt(4 k delta_y^{5/2} / (5 m*))`` (Johnson 1985, Contact Mechanics, Section 11.3:
    ``rho V_y^2 / Y = 26 (Y/E*)^4`` for a sphere on a flat with ``p_y = 1.6 Y``), and above it Thornton's
    closed form ``e = sqrt(6 sqrt(3)/5) sqrt(1 - r^2/6) [r / (r + 2 sqrt(6/5 - r^2/5))]^{1/4}``,
    ``r = V_y / V_i``.

    **Arguments:** ``k`` (N/m^1.5), ``delta_y`` (m); `from_yield_pressure` takes ``p_y`` and the effective
    radius ``R`` instead. The force is never tensile (``clamp`` has no effect; kept for the common API).
    """

    name: ClassVar[str] = "thornton"
    has_memory: ClassVar[bool] = True
    k: Array
    delta_y: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k: ArrayLike, delta_y: ArrayLike, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.delta_y = jnp.asarray(delta_y, dtype=float)
        self.clamp = clamp

    @classmethod
    def from_yield_pressure(cls, k, yield_pressure, effective_radius, clamp: bool = True) -> "Thornton":
        """``delta_y = R (pi p_y / (2 E*))^2`` with ``E* = 3 k / (4 sqrt(R))`` (Hertz)."""
        k, p_y = _stiffness(k), _positive(yield_pressure, "yield_pressure")
        R = _positive(effective_radius, "effective_radius")
        e_star = 0.75 * k / math.sqrt(R)
        return cls(k, R * (math.pi * p_y / (2.0 * e_star)) ** 2, clamp)

    @classmethod
    def from_config(cls, k, *, restitution=None, damping=None, effective_mass=None, calibration_velocity=None,
                    chi_map="exact", clamp=True, yield_pressure=None, effective_radius=None) -> "Thornton":
        """`make_law`'s constructor: ``yield_pressure`` (Pa) and the interface's ``effective_radius`` (m)."""
        if restitution is not None:
            raise ParameterError("restitution", restitution, "not a parameter of 'thornton': its restitution "
                                 "follows from yield_pressure and the impact speed")
        p_y = _require(yield_pressure, "yield_pressure", cls.name)
        R = _require(effective_radius, "effective_radius (stack.radius)", cls.name)
        return cls.from_yield_pressure(k, p_y, R, clamp)

    def _unloading(self, peak):
        """``(k_u, delta_p)`` of the unloading curve from the largest overlap ``peak``."""
        mask, dm = _positive_part(peak)
        dy = self.delta_y
        sdy, sdm = jnp.sqrt(dy), jnp.sqrt(dm)
        plastic = mask & (dm > dy)
        fstar = jnp.where(plastic, self.k * dy * sdy + 1.5 * self.k * sdy * (dm - dy), self.k * dm * sdm)
        k_u = jnp.where(plastic, self.k * jnp.sqrt(self.k * dm * sdm / fstar), self.k)
        delta_p = jnp.where(plastic, dm - fstar / (self.k * sdm), 0.0)
        return k_u, delta_p

    def yield_velocity(self, effective_mass: ArrayLike):
        """Johnson's yield velocity ``V_y = sqrt(4 k delta_y^{5/2} / (5 m*))`` (m/s): the impact speed at
        which the loading reaches ``delta_y``."""
        m = np.asarray(effective_mass, dtype=float)
        k, dy = np.asarray(self.k, dtype=float), np.asarray(self.delta_y, dtype=float)
        return _scalar(np.sqrt(0.8 * k * dy**2.5 / m))

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """Thornton's closed form (class docstring); 1 at or below the yield velocity."""
        v = _velocity(impact_velocity)
        m = _positive(_require(effective_mass, "effective_mass", self.name), "effective_mass")
        r = np.minimum(np.asarray(self.yield_velocity(m)) / v, 1.0)
        e = (math.sqrt(6 * math.sqrt(3) / 5) * np.sqrt(1 - r**2 / 6)
             * (r / (r + 2 * np.sqrt(6 / 5 - r**2 / 5))) ** 0.25)
        return _scalar(np.where(r >= 1.0, 1.0, e))




class JacksonGreen(_ElasticPlastic):
    """Elastic–plastic sphere contact of Jackson & Green (2005), "A finite element study of elasto-plastic
    hemispherical contact against a rigid flat", J. Tribol. 127, 343 (loading), with elastic Hertz
    unloading that keeps the contact radius reached (as in Thornton 1997 and Jackson, Green & Marghitu
    2010, "Predicting the coefficient of restitution of impacting elastic-perfectly plastic spheres",
    Nonlinear Dyn. 60, 217). Equations in docs/references.md, "Elastic-plastic contact".

    With ``E' = 3k / (4 sqrt(R))`` (``k = (4/3) E' sqrt(R)``), ``C = 1.295 exp(0.736 nu)``, the critical
    interference ``w_c = R (pi C S_y / (2 E'))^2``, the critical load ``P_c = k w_c^{3/2}`` and ``w* =
    delta / w_c``:

    - **Loading:** Hertz ``P = k delta^{3/2}``; for ``w* >= 1.9`` the FE fit ``P / P_c = exp(-w*^{5/12} / 4)
      w*^{3/2} + (4 H_G / (C S_y)) (1 - exp(-w*^{5/9} / 25)) w*``, with the contact radius ``a = sqrt(R
      delta) (w*/1.9)^{B/2}``, ``B = 0.14 exp(23 S_y / E')``, and the hardness ``H_G / S_y = 2.84 (1 -
      exp(-0.82 (a/R)^{-0.7}))``. The published fit starts at ``w* = 1.9``, where it lies 0.5 % above
      Hertz; the force here switches to it where the two meet (``switch``, about ``w* = 2.006`` for
      steels: computed per law), so that the force is continuous and the energy audit closes. The
      contact radius follows the fit from 1.9 on, as published.
    - **Unloading** from the largest overlap ``delta*`` (force ``P*``, radius ``a*``): Hertz with the
      residual radius ``R_r = 4 E' a*^3 / (3 P*)`` about the residual overlap ``delta_r = delta* - 3 P* /
      (4 E' a*)``; below ``w* = 1.9``, ``R_r = R`` and ``delta_r = 0`` (elastic).

    **Arguments:** ``k`` (N/m^1.5), ``radius`` R* (m), ``yield_strength`` S_y (Pa), ``poisson_ratio`` nu (for
    ``C``; 0.3 when unknown), ``switch`` (``w*`` where the force joins the fit; `from_config` computes
    it). Applied to two curved bodies with their effective ``E*`` and ``R*``, the usual approximation.
    """

    name: ClassVar[str] = "jackson-green"
    k: Array
    radius: Array
    yield_strength: Array
    poisson_ratio: Array
    switch: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k, radius, yield_strength, poisson_ratio=0.3, switch=1.9, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.radius = jnp.asarray(radius, dtype=float)
        self.yield_strength = jnp.asarray(yield_strength, dtype=float)
        self.poisson_ratio = jnp.asarray(poisson_ratio, dtype=float)
        self.switch = jnp.asarray(switch, dtype=float)
        self.clamp = clamp

    @classmethod
    def from_config(cls, k, *, restitution=None, damping=None, effective_mass=None, calibration_velocity=None,
                    chi_map="exact", clamp=True, yield_strength=None, effective_radius=None,
                    poisson_ratio=None) -> "JacksonGreen":
        """`make_law`'s constructor: ``yield_strength`` (Pa), the interface's ``effective_radius`` (m) and
        ``poisson_ratio`` (default 0.3); the switch to the fit is found here (scipy)."""
        if restitution is not None:
            raise ParameterError("restitution", restitution, "not a parameter of 'jackson-green': its restitution "
                                 "follows from yield_strength and the impact speed")
        k = _stiffness(k)
        s_y = _positive(_require(yield_strength, "yield_strength", cls.name), "yield_strength")
        R = _positive(_require(effective_radius, "effective_radius (stack.radius)", cls.name), "effective_radius")
        nu = 0.3 if poisson_ratio is None else float(poisson_ratio)
        if not -1.0 < nu <= 0.5:
            raise ParameterError("poisson_ratio", nu, "in (-1, 0.5]")
        law = cls(k, R, s_y, nu, 1.9, clamp)
        e_star = 0.75 * k / math.sqrt(R)
        strain = s_y / e_star
        if strain >= 1.0 or law._find_switch() is None:
            raise ParameterError("yield_strength", s_y, f"well below E' = {e_star:.4g} Pa: at the yield strain "
                                 f"S_y/E' = {strain:.3g} Jackson & Green's fit starts below Hertz (at 1.9 w_c), "
                                 "outside the metals' range it was fitted on; use thornton, or a smaller yield_strength")
        return cls(k, R, s_y, nu, law._find_switch(), clamp)

    # ---------------------------------------------------------------- the published fit
    def _scales(self):
        e = 0.75 * self.k / jnp.sqrt(self.radius)
        c = 1.295 * jnp.exp(0.736 * self.poisson_ratio)
        w_c = self.radius * (jnp.pi * c * self.yield_strength / (2.0 * e)) ** 2
        return e, c, w_c, self.k * w_c * jnp.sqrt(w_c)

    def _fit(self, dm):
        """``(P_fit, a)`` of the Jackson–Green fit at overlaps ``dm > 0`` (the radius by the fit from 1.9
        on, Hertz's below)."""
        e, c, w_c, p_c = self._scales()
        ws = dm / w_c
        big = ws >= 1.9
        b = 0.14 * jnp.exp(23.0 * self.yield_strength / e)
        a = jnp.sqrt(self.radius * dm) * jnp.where(big, jnp.where(big, ws, 1.9) / 1.9, 1.0) ** (0.5 * b)
        hg = 2.84 * (1.0 - jnp.exp(-0.82 * (a / self.radius) ** -0.7))
        p = p_c * (jnp.exp(-0.25 * ws ** (5.0 / 12.0)) * ws**1.5
                   + 4.0 * hg / c * (1.0 - jnp.exp(-(ws ** (5.0 / 9.0)) / 25.0)) * ws)
        return p, a

    def _find_switch(self) -> float | None:
        """The first ``w* >= 1.9`` where the fit meets Hertz; None when it starts below Hertz (a force jump)."""
        from scipy.optimize import brentq

        _, _, w_c, _ = (float(x) for x in self._scales())

        def gap(ws):
            return float(self._fit(jnp.asarray(ws * w_c))[0]) - float(self.k) * (ws * w_c) ** 1.5

        g = gap(1.9)
        if not np.isfinite(g) or g <= 0:
            return None
        return brentq(gap, 1.9, 100.0, xtol=1e-14, rtol=1e-14)

    def loading_force(self, delta: ArrayLike) -> Array:
        """The loading curve ``P(delta)`` (N): Hertz below ``switch``, the fit above."""
        mask, dm = _positive_part(jnp.asarray(delta, dtype=float))
        _, _, w_c, _ = self._scales()
        p_fit, _ = self._fit(dm)
        return jnp.where(mask, jnp.where(dm / w_c >= self.switch, p_fit, self.k * dm * jnp.sqrt(dm)), 0.0)

    def _unloading(self, peak):
        mask, dm = _positive_part(peak)
        e, _, w_c, _ = self._scales()
        _, a = self._fit(dm)
        p = self.loading_force(dm)
        plastic = mask & (dm / w_c >= 1.9)
        k_u = jnp.where(plastic, (4.0 / 3.0) * e * jnp.sqrt(4.0 * e * a**3 / (3.0 * p)), self.k)
        delta_r = jnp.where(plastic, dm - 3.0 * p / (4.0 * e * a), 0.0)
        return k_u, delta_r

    def yield_velocity(self, effective_mass: ArrayLike):
        """The impact speed whose Hertz loading reaches the critical interference: ``m* V_c^2 / 2 = (2/5)
        P_c w_c`` (m/s)."""
        m = np.asarray(effective_mass, dtype=float)
        _, _, w_c, p_c = (np.asarray(x, dtype=float) for x in self._scales())
        return _scalar(np.sqrt(0.8 * p_c * w_c / m))

    def restitution_at(self, impact_velocity: ArrayLike, effective_mass: ArrayLike | None = None):
        """``e = sqrt(U* / (m* v^2 / 2))`` of an isolated impact: the loading work ``∫ P`` reaches the
        impact energy at ``delta*`` (closed-form Hertz part, 96-point Gauss-Legendre on the fit, brentq),
        ``U*`` the energy the unloading curve returns."""
        from scipy.optimize import brentq

        m = _positive(_require(effective_mass, "effective_mass", self.name), "effective_mass")
        _, _, w_c, _ = (float(x) for x in self._scales())
        k, w_s = float(self.k), float(self.switch) * w_c
        nodes, weights = np.polynomial.legendre.leggauss(96)
        fit = jax.jit(lambda x: self._fit(x)[0])

        def work(d):
            """Loading work to `d`: Hertz's (2/5) k d^{5/2} to the switch, Gauss-Legendre on the smooth fit after."""
            if d <= w_s:
                return 0.4 * k * d**2.5
            x = 0.5 * (d - w_s) * nodes + 0.5 * (d + w_s)
            return 0.4 * k * w_s**2.5 + 0.5 * (d - w_s) * float(np.dot(weights, np.asarray(fit(jnp.asarray(x)))))

        out = []
        for v in np.atleast_1d(_velocity(impact_velocity)):
            energy = 0.5 * m * v * v
            hi = (energy / k * 2.5) ** 0.4
            while work(hi) < energy:
                hi *= 2.0
            d_star = brentq(lambda d: work(d) - energy, 0.0, hi, xtol=1e-16, rtol=1e-14)
            out.append(math.sqrt(float(self._energy(d_star, d_star)) / energy))
        return _scalar(np.reshape(out, np.shape(impact_velocity)))


# --------------------------------------------------------------------------------------------------
# validation helpers (concrete values only) and the factory used by the stack-file reader

LAW_NAMES: tuple[str, ...] = tuple(_registry.LAWS)
"""Configuration names of the contact laws, as used in stack files and by `make_law`
(`hertz_chain.registry.LAWS`)."""

_LAW_CLASSES = {name: globals()[row.cls] for name, row in _registry.LAWS.items()}


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


def make_law(
    name: str,
    *,
    stiffness: float,
    restitution: float | None = None,
    effective_mass: float | None = None,
    calibration_velocity: float | None = None,
    chi_map: str | None = "exact",
    alpha: float | None = None,
    eta: float | None = None,
    damping: float | None = None,
    A: float | None = None,
    clamp: bool = True,
    yield_pressure: float | None = None,
    effective_radius: float | None = None,
    exponent: float | None = None,
    yield_strength: float | None = None,
    poisson_ratio: float | None = None,
) -> AbstractContactLaw:
    """Build a contact law from its configuration name (the one factory of the stack-file reader).

    **Arguments** (SI units; all but ``name`` keyword-only):

    - ``name``: one of `LAW_NAMES` (`registry.LAWS`): ``"hertz"``, ``"hunt-crossley"``, ``"tsuji"``,
      ``"kelvin-voigt"``, ``"viscoelastic"``, ``"hertz-dashpot"``, ``"power"``, ``"thornton"``,
      ``"jackson-green"``.
    - ``stiffness``: ``k`` > 0, N/m^1.5 (Hertzian laws) or N/m (``kelvin-voigt``).
    - Damping, **either** ``restitution`` ``e`` in (0, 1] **or** the law's own parameter:

      | law | own parameter | with ``restitution`` also needs |
      | --- | --- | --- |
      | ``hertz`` | none (``restitution`` may only be 1) | — |
      | ``hunt-crossley`` | ``alpha`` (s/m) | ``calibration_velocity``; ``chi_map`` (default ``"exact"``) |
      | ``tsuji`` | ``eta`` or ``damping`` (= eta) | ``effective_mass`` (always needed) |
      | ``kelvin-voigt`` | ``damping`` (= c, N s/m) | ``effective_mass`` |
      | ``viscoelastic`` | ``A`` or ``damping`` (= A, s) | ``effective_mass``, ``calibration_velocity`` |
      | ``hertz-dashpot`` | ``damping`` (= gamma, N s/m) | ``effective_mass``, ``calibration_velocity`` |
      | ``power`` | ``alpha`` (s/m); always ``exponent`` p >= 1 (stiffness in N/m^p) | ``calibration_velocity``; ``chi_map`` |
      | ``thornton`` | ``yield_pressure`` (Pa) and ``effective_radius`` (m); no ``restitution`` | — |
      | ``jackson-green`` | ``yield_strength`` (Pa), ``effective_radius`` (m), optional ``poisson_ratio``; no ``restitution`` | — |

      ``e`` is reproduced exactly (to ~1e-11) in the isolated impact, with or without the clamp
      (see `hertz_chain.calibration`); for ``hunt-crossley`` and ``viscoelastic`` only at the
      calibration velocity, since their ``e`` falls as the impact speed rises.
    - ``chi_map``: Hunt–Crossley map name (`calibration.CHI_MAPS`); ``None`` means ``"exact"``.
    - ``clamp``: clamp the force at ``F >= 0`` (default ``True``).

    ``effective_mass`` and ``calibration_velocity`` are context values and are ignored by laws that do
    not use them; a law-specific parameter given to another law is an error.

    **Raises** `ParameterError` naming the offending parameter.
    """
    if not isinstance(name, str) or name.strip().lower() not in _LAW_CLASSES:
        raise ParameterError("law", name, f"one of {list(LAW_NAMES)}")
    law = name.strip().lower()
    row = _registry.LAWS[law]
    k = _stiffness(stiffness)
    if not isinstance(clamp, (bool, np.bool_)):
        raise ParameterError("clamp", clamp, "true or false")
    clamp = bool(clamp)
    chi_map = "exact" if chi_map is None else chi_map
    if chi_map not in _cal.CHI_MAPS:
        raise ParameterError("chi_map", chi_map, f"one of {sorted(_cal.CHI_MAPS)}")
    if not row.chi_map and chi_map != "exact":
        raise ParameterError("chi_map", chi_map, f"only used by laws that take one, not by {law!r}")

    # the law's own damping parameter, under any of its accepted keywords (`registry.LawRow.keywords`)
    own = row.keywords
    given = {"alpha": alpha, "eta": eta, "damping": damping, "A": A}
    for key, value in given.items():
        if value is not None and key not in own:
            raise ParameterError(key, value, f"not a parameter of the {law!r} law"
                                 + (f" (it takes {' or '.join(own)})" if own else " (elastic)"))
    own_given = [(key, given[key]) for key in own if given[key] is not None]
    if len(own_given) > 1:
        raise ParameterError(own_given[1][0], own_given[1][1], f"give only one of {' / '.join(own)}")
    e = _cal.check_restitution(restitution) if restitution is not None else None
    if e is not None and own_given:
        raise ParameterError(own_given[0][0], own_given[0][1],
                             "give either restitution or the law's own damping parameter, not both")
    extra = {"yield_pressure": yield_pressure, "effective_radius": effective_radius, "exponent": exponent,
             "yield_strength": yield_strength, "poisson_ratio": poisson_ratio}
    wanted = ({key for key, _ in row.params} | ({"effective_radius"} if row.needs_radius else set())
              | set(row.context))
    for key, value in extra.items():
        if value is not None and key not in wanted and key != "effective_radius":
            raise ParameterError(key, value, f"not a parameter of the {law!r} law")
    if row.memory and e is not None:
        raise ParameterError("restitution", restitution, f"not a parameter of the {law!r} law: its restitution "
                             "follows from its own parameters and the impact speed")
    if row.damping is not None and e is None and not own_given:
        raise ParameterError("restitution", None, f"the {law!r} law needs restitution or {' / '.join(own)}")
    param = _nonnegative(own_given[0][1], own_given[0][0]) if own_given else None
    kwargs = {key: extra[key] for key in wanted}
    return _LAW_CLASSES[law].from_config(k, restitution=e, damping=param, effective_mass=effective_mass,
                                         calibration_velocity=calibration_velocity, chi_map=chi_map,
                                         clamp=clamp, **kwargs)
