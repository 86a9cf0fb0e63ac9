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

import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from . import _config  # noqa: F401  (float64)
from . import calibration as _cal
from . import registry as _registry
from .constants import POWER_EXPONENTS
from .errors import ParameterError
from ._law_base import (  # noqa: F401  (the base is part of this module's interface)
    AbstractContactLaw,
    _nonnegative,
    _positive,
    _positive_part,
    _require,
    _scalar,
    _stiffness,
    _velocity,
)
from ._plastic import JacksonGreen, Thornton  # the elastic–plastic family, re-exported

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

    field_rules: ClassVar[dict] = {"k": (0.0, True, "stiffness k")}
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

    field_rules: ClassVar[dict] = {"k": (0.0, True, "stiffness k"), "alpha": (0.0, False, "damping alpha")}
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

    field_rules: ClassVar[dict] = {
        "k": (0.0, True, "stiffness k"),
        "eta": (0.0, False, "damping eta"),
        "m_eff": (0.0, True, "effective mass m_eff"),
    }
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

    field_rules: ClassVar[dict] = {"k": (0.0, True, "stiffness k"), "c": (0.0, False, "damping c")}
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

    field_rules: ClassVar[dict] = {"k": (0.0, True, "stiffness k"), "A": (0.0, False, "damping time A")}
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
    two-wave structure in strongly nonlinear dissipative granular chains", Phys. Rev. Lett. 98, 164301.

    The dashpot acts from the first touch, so the force jumps to ``gamma v`` at contact (a rough onset for
    the solver and for gradients: `registry.LawRow.smooth_onset` is False). Its restitution depends on
    the impact speed and the effective mass: in Hertz units it is a function of
    ``zeta = gamma m*^{-3/5} k^{-2/5} v^{-1/5}`` alone (`calibration.hertz_dashpot_zeta`), so with
    ``gamma`` fixed ``e`` *rises* with the impact speed (the opposite of Hunt–Crossley and the
    viscoelastic law). ``from_restitution`` calibrates ``gamma`` at one speed.
    """

    field_rules: ClassVar[dict] = {"k": (0.0, True, "stiffness k"), "gamma": (0.0, False, "damping gamma")}
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

    field_rules: ClassVar[dict] = {
        "k": (0.0, True, "stiffness k"),
        "p": (1.0, False, "exponent p"),
        "alpha": (0.0, False, "damping alpha"),
    }
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
        if isinstance(exponent, (bool, np.bool_)):  # True read as p = 1 (a review)
            raise ParameterError("exponent", exponent, "a number between 1 and 5, not a boolean")
        p = float(_require(exponent, "exponent", cls.name))
        lo, hi = POWER_EXPONENTS
        if not (math.isfinite(p) and lo <= p <= hi):  # as stack files (a review: make_law took 6, files refused it)
            raise ParameterError("exponent", exponent, f"a number between {lo:g} and {hi:g} (F = k delta^p)")
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



LAW_NAMES: tuple[str, ...] = tuple(_registry.LAWS)
"""Configuration names of the contact laws, as used in stack files and by `make_law`
(`hertz_chain.registry.LAWS`)."""

def _law_class(row: _registry.LawRow) -> type:
    """The class of a registry row, defined or imported in this module (a new law in `_plastic` is
    imported above, as Thornton is)."""
    try:
        return globals()[row.cls]
    except KeyError:
        raise ImportError(f"registry.LAWS[{row.name!r}].cls = {row.cls!r}: no such class in hertz_chain.contact; "
                          "define it there (or import it there from its own module, as Thornton from _plastic)") \
            from None


_LAW_CLASSES = {name: _law_class(row) for name, row in _registry.LAWS.items()}


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
      | ``power`` | ``alpha`` (s/m); always ``exponent`` 1 <= p <= 5 (stiffness in N/m^p) | ``calibration_velocity``; ``chi_map`` |
      | ``thornton`` | ``yield_pressure`` (Pa) and ``effective_radius`` (m); no ``restitution`` | — |
      | ``jackson-green`` | ``yield_strength`` (Pa), ``effective_radius`` (m), optional ``poisson_ratio``; no ``restitution`` | — |

      ``e`` is reproduced exactly (to ~1e-11) in the isolated impact, with or without the clamp
      (see `hertz_chain.calibration`); for the speed-dependent laws only at the calibration velocity:
      the ``e`` of ``hunt-crossley``, ``power`` and ``viscoelastic`` falls as the impact speed rises,
      that of ``hertz-dashpot`` rises (``tsuji`` and ``kelvin-voigt``: the same ``e`` at every speed).
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
    if param is not None and row.damping_max is not None and param > row.damping_max:
        # the stack files' cap (`registry.LawRow.damping_max`), so that Python and a file agree (a review:
        # Kelvin-Voigt c = 1e10 N s/m gave e = -8e-7 from a simulated impact without a word)
        label = row.damping_label or own_given[0][0]
        raise ParameterError(own_given[0][0], own_given[0][1],
                             f"at most {row.damping_max:g} ({label}) for the {law!r} law")
    kwargs = {key: extra[key] for key in wanted}
    return _LAW_CLASSES[law].from_config(k, restitution=e, damping=param, effective_mass=effective_mass,
                                         calibration_velocity=calibration_velocity, chi_map=chi_map,
                                         clamp=clamp, **kwargs)
