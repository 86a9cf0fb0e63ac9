"""The elastic–plastic contact laws, with memory of the largest overlap: Thornton (1997) and Jackson &
Green (2005). Their shared mechanics (`_ElasticPlastic`) and both laws; `hertz_chain.contact` re-exports
them beside the elastic and viscous laws, and `make_law` builds them by name.
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
from .errors import ParameterError
from ._law_base import AbstractContactLaw, _positive, _positive_part, _require, _scalar, _stiffness, _velocity


MEMORY_SLACK, MEMORY_FLOOR = 1e-12, 1e-6
"""The loading test of a law with memory (`_ElasticPlastic.memory_rate`) allows ``delta`` below ``q`` by
``MEMORY_SLACK |q| + MEMORY_FLOOR delta_y``: ``q`` and ``delta`` take the same increments, so they part by
rounding only (~1e-16 of the positions), and a flip of the test in a stage would cost ``q`` that stage's
increment; near the onset ``|q|`` is tiny, hence the floor in the law's own yield overlap. A reload
resumes loading that much early: ``q`` then leads ``delta`` by at most the floor."""

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

    @abc.abstractmethod
    def _yield_overlap(self):
        """The overlap where plasticity starts (m): the length `memory_rate`'s slack is measured in."""

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
        """``dq/dt``: the overlap rate while ``delta`` is at its largest so far (``delta >= q`` up to the
        slack ``MEMORY_SLACK |q| + MEMORY_FLOOR delta_y``, ``delta_y`` the law's `_yield_overlap`) and growing,
        else 0.

        ``q`` starts at the initial overlap (`Stack.initial_vector`: minus the gap), so it follows
        ``delta`` through the approach and the onset alike: a Runge–Kutta step gives both the same
        increments, and no switch sits at ``delta = 0``. (It started at 0 and grew only while ``delta >
        0``: in a step across an onset its stages then took part of ``delta``'s increment, rounding
        decided which, so ``q`` left the onset above or below ``delta``, and the replayed derivative of
        the peak the unloading curve hangs from missed the onset's shift: a review measured launch-velocity
        derivatives 4x off at one design and right 1e-6 away, three of eight designs, without gravity.)"""
        delta = jnp.asarray(delta, dtype=float)
        slack = MEMORY_SLACK * jnp.abs(q) + MEMORY_FLOOR * self._yield_overlap()
        return jnp.where(delta >= q - slack, jnp.maximum(delta_dot, 0.0), 0.0)

    def dissipated_power(self, delta: ArrayLike, delta_dot: ArrayLike, q: ArrayLike | None = None) -> Array:
        """Plastic power ``-dU/ddelta* · d(delta*)/dt`` (W), ``delta* = max(q, delta)`` (0 before contact)."""
        delta = jnp.asarray(delta, dtype=float)
        q = jnp.zeros_like(delta) if q is None else q
        peak = jnp.maximum(q, delta)
        rate = jnp.where(peak > 0, jnp.where(delta > q, delta_dot, self.memory_rate(delta, delta_dot, q)), 0.0)
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

    **Memory.** ``q``, the largest overlap so far (m; from the initial overlap, negative across a gap), is
    carried in the ODE state, one per interface, with ``dq/dt = max(delta_dot, 0)`` while ``delta >= q``
    (0 otherwise; `memory_rate`); the force uses ``max(q, delta)``, so a lagging ``q`` never puts a
    loading contact on its unloading curve. The dissipated (plastic) power is
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

    field_rules: ClassVar[dict] = {"k": (0.0, True, "stiffness k"), "delta_y": (0.0, True, "yield overlap delta_y")}
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
        delta_y = R * (math.pi * p_y / (2.0 * e_star)) ** 2
        if not delta_y < R:  # a review: p_y = 2e13 Pa put delta_y at 1754 m on a 1 mm radius: pure Hertz, silently
            raise ParameterError("yield_pressure", p_y, f"below 2 E*/pi = {2 * e_star / math.pi:.4g} Pa (E* = "
                                 f"{e_star:.4g} Pa from the stiffness and the radius): above it the yield overlap "
                                 "delta_y = R (pi p_y / (2 E*))^2 exceeds the radius, and the law never yields")
        return cls(k, delta_y, clamp)

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

    def _yield_overlap(self):
        return self.delta_y

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




#: the smallest yield strain S_y/E' `JacksonGreen` takes (the material table's metals: 1.1e-3, copper C110, to 1.8e-2,
#: steel 52100)
MIN_YIELD_STRAIN = 1e-4


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
      exp(-0.82 (a/R)^{-0.7}))``. The published fit starts at ``w* = 1.9``, where it lies 0.47 % above
      Hertz; the force here switches to it where the two meet (``switch``, about ``w* = 2.006`` for
      steels: computed per law), so that the force is continuous and the energy audit closes. The
      contact radius follows the fit from 1.9 on, as published.
    - **Unloading** from the largest overlap ``delta*`` (force ``P*``, radius ``a*``): Hertz with the
      residual radius ``R_r = 4 E' a*^3 / (3 P*)`` about the residual overlap ``delta_r = delta* - 3 P* /
      (4 E' a*)``; below ``w* = 1.9``, ``R_r = R`` and ``delta_r = 0`` (elastic).

    **Arguments:** ``k`` (N/m^1.5), ``radius`` R* (m), ``yield_strength`` S_y (Pa), ``poisson_ratio`` nu (for
    ``C``; 0.3 when unknown), ``switch`` (``w*`` where the force joins the fit; by default computed, as
    `from_config` does, where every parameter is one number (also a Python number under `jit`); else
    1.9, where the fit starts, 0.47 % above Hertz: pass it where the parameters are arrays or traced).
    Raises `ParameterError` where the fit starts below Hertz (no continuous switch; `switch = 1.9`
    accepts the jump). Applied to two curved bodies with their effective ``E*`` and ``R*``, the usual approximation.
    """

    field_rules: ClassVar[dict] = {
        "k": (0.0, True, "stiffness k"),
        "radius": (0.0, True, "radius"),
        "yield_strength": (0.0, True, "yield strength"),
        "poisson_ratio": (-1.0, True, "Poisson ratio"),
        "switch": (1.9, False, "switch w*"),
    }
    name: ClassVar[str] = "jackson-green"
    gradient_note: ClassVar[str | None] = (
        "its loading curve changes form at w* = 1.9 (where the published fit's contact radius starts) and at "
        "w* = switch (about 2.006, where the force joins the fit: continuous, with a kink in its slope), which "
        "the replayed derivatives do not treat: measured from 2e-4 relative off central differences (three "
        "masses, no gravity) to a factor of 5,000 (three masses, 1 mm gaps, gravity)")
    gradient_refused: ClassVar[bool] = True
    k: Array
    radius: Array
    yield_strength: Array
    poisson_ratio: Array
    switch: Array
    clamp: bool = eqx.field(static=True, default=True)

    def __init__(self, k, radius, yield_strength, poisson_ratio=0.3, switch=None, clamp: bool = True):
        self.k = jnp.asarray(k, dtype=float)
        self.radius = jnp.asarray(radius, dtype=float)
        self.yield_strength = jnp.asarray(yield_strength, dtype=float)
        self.poisson_ratio = jnp.asarray(poisson_ratio, dtype=float)
        self.switch = jnp.asarray(1.9 if switch is None else switch, dtype=float)
        self.clamp = clamp
        raw = (k, radius, yield_strength, poisson_ratio)
        if switch is None and all(not isinstance(x, jax.core.Tracer) and np.ndim(x) == 0 for x in raw):
            # a review: the constructor's default was 1.9, where the fit lies 0.47 % above Hertz (a jump of
            # the loading force that `make_law` avoids); now the same continuous switch as `from_config`,
            # also under the caller's jit where the numbers are Python's (`ensure_compile_time_eval`: the
            # same law inside and outside), after the numbers' own checks
            with jax.ensure_compile_time_eval():
                plain = JacksonGreen(*(float(x) for x in raw), switch=1.9, clamp=clamp)  # checked (field_rules)
                found = plain._find_switch()
            if found is None:
                raise ParameterError("yield_strength", float(yield_strength), "a law whose fit meets Hertz above "
                                     "w* = 1.9 (here it starts below: the loading force would jump, and make_law "
                                     "refuses it); pass switch = 1.9 to accept the jump, or use thornton")
            self.switch = jnp.asarray(found, dtype=float)

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
        if strain < MIN_YIELD_STRAIN:
            # a review: 1e5 Pa on E' = 2.4e10 (4e-6) put the critical overlap at 1e-13 m, the solve's scales
            # at 1e82 s, and reported "no contact" with NaN; 4e-5 ran with an overlap twice the radius
            raise ParameterError("yield_strength", s_y, f"a yield strain S_y/E' = {strain:.3g} of at least "
                                 f"{MIN_YIELD_STRAIN:g} (E' = {e_star:.4g} Pa): Jackson & Green's fit is of metals "
                                 "(the table's: S_y/E' 1e-3 to 2e-2); a softer solid goes far outside it, and past its radius")
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

    def _yield_overlap(self):
        return self._scales()[2]  # w_c, the critical interference

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
