r"""Restitution maps and the calibration of damped contact laws (numpy/scipy only).

A damped contact law is usually specified by a coefficient of restitution $e$, the ratio of the
separation to the approach speed in a single, isolated two-body impact. This module turns $e$ into
the damping parameter of each law in `hertz_chain.contact`, and back.

## One nondimensional problem per law

The isolated impact $m^* \ddot\delta = -F(\delta, \dot\delta)$, $\delta(0) = 0$,
$\dot\delta(0) = v$ has **one** free parameter per law once scaled. For the Hertzian laws take
$\delta = \delta^* x$, $t = (\delta^*/v)\tau$ with $\delta^* = (m^* v^2/k)^{2/5}$; for the linear law
$\delta = (v/\omega) x$, $t = \tau/\omega$, $\omega = \sqrt{k/m^*}$. Then ($' = d/d\tau$,
$x(0) = 0$, $x'(0) = 1$):

| law | nondimensional equation | parameter |
| --- | --- | --- |
| `hunt-crossley` | $x'' = -x^{3/2}(1 + \chi x')$ | $\chi = \alpha v$ |
| `tsuji` | $x'' = -x^{3/2} - \eta x^{1/4} x'$ | $\eta$ (no $v$: $e$ is speed-independent) |
| `kelvin-voigt` | $x'' = -x - 2\zeta x'$ | $\zeta = c / (2\sqrt{m^* k})$ (speed-independent) |
| `viscoelastic` | $x'' = -x^{3/2} - \xi x^{1/2} x'$ | $\xi = \tfrac32 A (k/m^*)^{2/5} v^{1/5}$ |
| `hertz-dashpot` | $x'' = -x^{3/2} - \zeta x'$ | $\zeta = \gamma\, m^{*-3/5} k^{-2/5} v^{-1/5}$ (e rises with $v$) |

so $e$ is a function of that parameter alone (and of the clamp), $e = -x'(\tau_\mathrm{sep})$.

**Separation.** Without the clamp the contact ends where $x$ returns to 0. With the no-tension clamp
$F \ge 0$ (the default) the bodies separate where the *force* reaches zero while $x > 0$: from there
on the clamped force is zero, the relative velocity stays constant and $x$ keeps decreasing freely
(the raw force only becomes more negative, so contact never resumes). The restitution is the relative
velocity at $F = 0$. For the Hertzian laws the event is taken on $F/x^{p}$ (e.g. $x^{5/4} + \eta x'$
for Tsuji), which is positive at the first touch, so it cannot fire at $\tau = 0$.

**Why scipy here.** Each map $e(\text{parameter}, \text{clamp})$ is a one-off precompute of a scalar
function of one variable: a single `scipy.integrate.solve_ivp` (DOP853, rtol 1e-12, atol 1e-15,
terminal events) per evaluation, inverted with `scipy.optimize.brentq` and cached with
`functools.lru_cache` on `(e, clamp)`, so repeated calls are instant. Nothing here is differentiated
or batched; the diffrax/JAX machinery is reserved for the stack simulator (`hertz_chain.simulation`).
The measured self-consistency of $e$ is about 1e-11 (halving rtol changes $e$ by < 1e-11).

## Closed forms used where they exist

* Hunt–Crossley: exact map of Carvalho & Martins (2019), Mech. Mach. Theory 139, 1:
  $x - \ln(1+x) = -y - \ln(1-y)$, $x = \chi$, $y = e\chi$, i.e.
  $e = [1 + W_0(-(1+\chi) e^{-(1+\chi)})]/\chi$. It holds **with and without the clamp**: along the
  trajectory $u = 1 + \chi x'$ obeys $u' = -\chi x^{3/2} u$, so
  $u(\tau) = (1+\chi)\exp(-\chi\int_0^\tau x^{3/2}) > 0$ and the force
  $x^{3/2} u$ is never tensile (the clamp never acts). Published approximate maps $\chi(e)$ are in
  `CHI_MAPS`; `chi_map_table` shows the $e$ each one really produces.
* Kelvin–Voigt without clamp: $\zeta = -\ln e / \sqrt{\pi^2 + \ln^2 e}$ (underdamped oscillator,
  exact). With clamp: Schwager & Pöschel (2007), Granular Matter 9, 465 — here calibrated numerically.
* Tsuji without clamp: $\eta = -\sqrt5 \ln e / \sqrt{\pi^2 + \ln^2 e}$, exact. Reason (derived here,
  checked in the tests): with $u = x^{5/4}$ and $d\sigma = \sqrt{5/4}\, x^{1/4} d\tau$ the Tsuji
  equation becomes exactly $u_{\sigma\sigma} + 2(\eta/\sqrt5) u_\sigma + u = 0$, and the Tsuji force
  is $x^{1/4}$ times the linear one, so **Tsuji with $\eta$ is Kelvin–Voigt with $\zeta = \eta/\sqrt5$,
  with or without the clamp**. Its clamped calibration is nevertheless integrated from its own
  equation here (the equivalence is a test, not an assumption).
* Viscoelastic: no closed form; small-$\xi$ series of Ramírez et al. (1999), Phys. Rev. E 60, 4465,
  and the Padé fit of Müller & Pöschel (2011), Phys. Rev. E 84, 021302, are provided for comparison.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import beta as _beta_fn
from scipy.special import lambertw

from . import registry as _registry
from .errors import ParameterError

__all__ = [
    "CHI_MAPS",
    "HERTZ_CONTACT_TIME_FACTOR",
    "NondimensionalImpact",
    "chi_from_restitution",
    "restitution_from_chi",
    "hunt_crossley_alpha",
    "hunt_crossley_restitution",
    "chi_map_table",
    "nondimensional_impact",
    "kelvin_voigt_damping_ratio",
    "kelvin_voigt_restitution",
    "tsuji_eta",
    "tsuji_restitution",
    "viscoelastic_xi",
    "viscoelastic_restitution",
    "viscoelastic_xi_from_A",
    "viscoelastic_A_from_xi",
    "viscoelastic_restitution_series",
    "viscoelastic_restitution_pade",
    "hertz_impact",
    "check_restitution",
]

# Smallest restitution the numerical calibration accepts (below it the damping parameter runs away
# and the single-impact integration becomes long; no design in this package needs it).
MIN_CALIBRATED_RESTITUTION = 1e-3

_RTOL = 1e-12
_ATOL = 1e-15


# --------------------------------------------------------------------------------------------------
# input checks


def check_restitution(e: float, name: str = "restitution", minimum: float = 0.0) -> float:
    """Return ``float(e)`` or raise `ParameterError` unless ``minimum < e <= 1`` (and finite; not a JAX
    tracer: `errors.TRACED`)."""
    from .errors import TRACED, _traced

    if _traced(e):
        raise ParameterError(name, "a traced value", TRACED)
    if isinstance(e, (bool, np.bool_)) or getattr(e, "dtype", None) == bool:  # True read as e = 1 (a review)
        raise ParameterError(name, e, "a number in (0, 1], not a boolean")
    try:
        ef = float(e)
    except (TypeError, ValueError):
        raise ParameterError(name, e, "a number in (0, 1]") from None
    if not (math.isfinite(ef) and 0.0 < ef <= 1.0):
        raise ParameterError(name, e, "a coefficient of restitution must lie in (0, 1]")
    if ef < minimum:
        raise ParameterError(
            name, e, f"the numerical calibration supports {minimum:g} <= e <= 1"
        )
    return ef


def _check_nonnegative(value: float, name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, value, "a finite number >= 0") from None
    if not (math.isfinite(v) and v >= 0.0):
        raise ParameterError(name, value, "a finite number >= 0")
    return v


def _check_positive(value: float, name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, value, "a finite number > 0") from None
    if not (math.isfinite(v) and v > 0.0):
        raise ParameterError(name, value, "a finite number > 0")
    return v


# --------------------------------------------------------------------------------------------------
# Hunt–Crossley: published maps chi(e) and the exact map


def _chi_exact(e: float) -> float:
    return _chi_exact_cached(float(e))


CHI_MAPS: dict[str, Callable[[float], float]] = {
    name: row.formula or _chi_exact for name, row in _registry.CHI_MAPS.items()
}
"""Maps $e \\mapsto \\chi$ for $F = k\\delta^{3/2}(1 + \\chi\\dot\\delta/v_0)$, by configuration name: the
rows of `hertz_chain.registry.CHI_MAPS` (formulas and sources), the exact map computed here."""


def restitution_from_chi(chi: float | np.ndarray) -> float | np.ndarray:
    r"""Exact restitution of the Hunt–Crossley law for $\chi = \alpha v$ (Carvalho & Martins 2019).

    $e = [1 + W_0(-(1+\chi)e^{-(1+\chi)})]/\chi$, valid for any exponent $p$ and stiffness, with and
    without the no-tension clamp (the force never becomes tensile; see the module docstring).
    For $\chi < 0.1$ the root $y = e\chi$ of the same relation is found with `brentq` in a
    cancellation-free form instead, avoiding the loss of digits near the branch point of $W_0$.
    """
    chi_arr = np.asarray(chi, dtype=float)
    if np.any(~np.isfinite(chi_arr)) or np.any(chi_arr < 0):
        raise ParameterError("chi", chi, "a finite number >= 0 (chi = alpha * impact velocity)")
    c = np.maximum(chi_arr, 1e-300)
    arg = -np.exp(np.log1p(c) - 1.0 - c)  # -(1+chi) exp(-(1+chi))
    w = lambertw(arg, 0).real
    exact = (1.0 + w) / c
    small = np.vectorize(_restitution_small_chi, otypes=[float])(np.minimum(chi_arr, 0.1))
    out = np.where(chi_arr < 0.1, small, exact)
    return float(out) if out.ndim == 0 else out


def _restitution_small_chi(x: float) -> float:
    """e(chi) for small chi: solve h(x) = h(-y), y in (0, x), scaled by x^2; e = y/x."""
    if x == 0.0:
        return 1.0
    hx = _z_minus_log1p(x)
    y = brentq(lambda y: (hx - _z_minus_log1p(-y)) / (x * x), 0.0, x, xtol=1e-300, rtol=4 * np.finfo(float).eps)
    return y / x


def _z_minus_log1p(z: float) -> float:
    """``z - ln(1 + z)`` without cancellation for small ``|z|`` (series below 0.1)."""
    if abs(z) >= 0.1:
        return z - math.log1p(z)
    total, term = 0.0, -z  # term_n = (-1)^n z^n
    for n in range(2, 40):
        term *= -z
        total += term / n
        if abs(term) < 1e-18 * abs(total):
            break
    return total


@functools.lru_cache(maxsize=4096)
def _chi_exact_cached(e: float) -> float:
    e = check_restitution(e)
    if e == 1.0:
        return 0.0

    # Solve h(x) = h(-e x), h(z) = z - ln(1+z), for x in (0, 1/e) (the root x = 0 is trivial).
    # g = [h(x) - h(-e x)] / x^2 -> (1 - e^2)/2 > 0 as x -> 0 (stable form, no cancellation),
    # and g -> -inf as x -> 1/e.
    def g(x: float) -> float:
        return (_z_minus_log1p(x) - _z_minus_log1p(-e * x)) / (x * x)

    hi = (1.0 / e) * (1.0 - 1e-16)
    if g(hi) > 0.0:
        # e below ~0.0254: the root lies within rounding of 1/e, x = (1 - s)/e with h(-e x) = s - 1 - ln s =
        # h(x), so s ~ exp(-1 - h(1/e)) < 1e-16 (a review: brentq's bracket failed, a raw ValueError)
        return (1.0 / e) * (1.0 - math.exp(-1.0 - _z_minus_log1p(1.0 / e)))
    lo = 1e-3 * (1.0 - e)
    while g(lo) <= 0.0:  # pragma: no cover - not reached for e < 1
        lo *= 0.1
    return brentq(g, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=500)


def chi_from_restitution(e: float, chi_map: str = "exact") -> float:
    r"""Hunt–Crossley damping factor $\chi(e)$ from a named map (see `CHI_MAPS`).

    `"exact"` inverts the Carvalho & Martins (2019) relation with `brentq` (cached).
    """
    if chi_map not in CHI_MAPS:
        raise ParameterError("chi_map", chi_map, f"one of {sorted(CHI_MAPS)}")
    e = check_restitution(e)
    return float(CHI_MAPS[chi_map](e))


def hunt_crossley_alpha(e: float, calibration_velocity: float, chi_map: str = "exact") -> float:
    r"""$\alpha = \chi(e)/v_c$ (s/m): the Hunt–Crossley $\alpha$ that gives $e$ at impact speed $v_c$."""
    v = _check_positive(calibration_velocity, "calibration_velocity")
    return chi_from_restitution(e, chi_map) / v


def hunt_crossley_restitution(
    alpha: float | np.ndarray, impact_velocity: float | np.ndarray
) -> float | np.ndarray:
    r"""Exact restitution $e(\chi = \alpha v)$ of the Hunt–Crossley law at impact speed $v$.

    With $\alpha$ fixed, $e$ falls as the impact speed rises. Clamp-independent (see
    `restitution_from_chi`).
    """
    a = np.asarray(alpha, dtype=float)
    v = np.asarray(impact_velocity, dtype=float)
    if np.any(~np.isfinite(a)) or np.any(a < 0):
        raise ParameterError("alpha", alpha, "a finite number >= 0 (s/m)")
    if np.any(~np.isfinite(v)) or np.any(v <= 0):
        raise ParameterError("impact_velocity", impact_velocity, "finite and > 0 (m/s)")
    return restitution_from_chi(a * v)


def chi_map_table(
    targets: tuple[float, ...] = (0.5, 0.9), maps: tuple[str, ...] | None = None
) -> dict[str, dict[float, float]]:
    r"""The restitution each published $\chi(e)$ map really produces, ``{map: {target: e}}``.

    The produced $e$ is the exact one (`restitution_from_chi`) for the map's $\chi$, so the error of a
    map is ``table[map][target] - target``. Published comparisons: Carvalho & Martins (2019);
    values for 0.5 and 0.9 are listed in ``docs/references.md``, "Restitution maps".
    """
    names = tuple(CHI_MAPS) if maps is None else maps
    table: dict[str, dict[float, float]] = {}
    for name in names:
        if name not in CHI_MAPS:
            raise ParameterError("chi_map", name, f"one of {sorted(CHI_MAPS)}")
        table[name] = {
            float(t): float(restitution_from_chi(chi_from_restitution(t, name))) for t in targets
        }
    return table


# --------------------------------------------------------------------------------------------------
# the nondimensional single impact (scipy)

_LAWS = tuple(_registry.LAWS)


@dataclass(frozen=True)
class NondimensionalImpact:
    """Result of `nondimensional_impact`, in the scaled units of the module docstring.

    ``restitution`` is $e = -x'(\\tau_\\mathrm{sep})$; ``contact_time`` is $\\tau_\\mathrm{sep}$
    (multiply by $\\delta^*/v$, or $1/\\omega$ for `kelvin-voigt`); ``max_overlap`` is
    $x_\\max$ (multiply by $\\delta^*$, or $v/\\omega$); ``separated_by_force`` tells whether the
    contact ended at $F = 0$ with $x > 0$ (clamp active) rather than at $x = 0$.
    """

    restitution: float
    contact_time: float
    max_overlap: float
    separated_by_force: bool


def _nondim_functions(law: str, p: float):
    """Return (raw force F(x, v), reduced force F/x^q used for the separation event)."""
    if law == "hertz":
        return (lambda x, v: max(x, 0.0) ** 1.5), (lambda x, v: 1.0)
    if law == "hunt-crossley":
        return (lambda x, v: max(x, 0.0) ** 1.5 * (1.0 + p * v)), (lambda x, v: 1.0 + p * v)
    if law == "tsuji":
        return (
            lambda x, v: max(x, 0.0) ** 1.5 + p * max(x, 0.0) ** 0.25 * v,
            lambda x, v: max(x, 0.0) ** 1.25 + p * v,
        )
    if law == "kelvin-voigt":
        return (lambda x, v: x + 2.0 * p * v), (lambda x, v: x + 2.0 * p * v)
    if law == "viscoelastic":
        return (
            lambda x, v: max(x, 0.0) ** 1.5 + p * math.sqrt(max(x, 0.0)) * v,
            lambda x, v: max(x, 0.0) + p * v,
        )
    if law == "hertz-dashpot":  # the linear dashpot acts from the first touch (x >= 0): F(0+) = zeta x'
        return (
            lambda x, v: max(x, 0.0) ** 1.5 + p * v if x >= 0.0 else 0.0,
            lambda x, v: max(x, 0.0) ** 1.5 + p * v,
        )
    raise ParameterError("law", law, "one of ['hertz', 'hunt-crossley', 'tsuji', 'kelvin-voigt', 'viscoelastic', "
                         "'hertz-dashpot'] (the laws with a one-parameter nondimensional impact; the others: "
                         "their restitution_at)")


def nondimensional_impact(law: str, parameter: float = 0.0, clamp: bool = True) -> NondimensionalImpact:
    r"""Integrate the nondimensional isolated impact of `law` once (scipy DOP853, rtol 1e-12).

    ``parameter`` is $\chi$, $\eta$, $\zeta$ or $\xi$ (see the module docstring; ignored for
    `hertz`). Without clamp the contact ends at $x = 0$; with clamp at $F = 0$ (or $x = 0$ if the
    force never vanishes first, as for Hertz and Hunt–Crossley). An unclamped overdamped
    Kelvin–Voigt contact never returns to $x = 0$: its restitution is reported as 0.
    """
    p = _check_nonnegative(parameter, "parameter")
    force, reduced = _nondim_functions(law, p)

    if clamp:

        def rhs(t, y):
            return (y[1], -max(force(y[0], y[1]), 0.0))
    else:

        def rhs(t, y):
            return (y[1], -force(y[0], y[1]))

    def ev_zero(t, y):
        return y[0]

    ev_zero.terminal, ev_zero.direction = True, -1

    def ev_force(t, y):
        return reduced(y[0], y[1])

    ev_force.terminal, ev_force.direction = True, -1

    def ev_top(t, y):
        return y[1]

    ev_top.terminal, ev_top.direction = False, -1

    events = [ev_zero, ev_top] + ([ev_force] if clamp else [])
    # Elastic contact time is 3.218 (Hertz) or pi (linear); heavy damping lengthens an unclamped one.
    t_end = 1e4
    sol = solve_ivp(
        rhs, (0.0, t_end), np.array([0.0, 1.0]), method="DOP853", rtol=_RTOL, atol=_ATOL,
        events=events,
    )
    if sol.status == -1:  # pragma: no cover - DOP853 does not fail on these smooth problems
        raise RuntimeError(f"single-impact integration failed: {sol.message}")
    x_max = float(sol.y_events[1][0][0]) if len(sol.y_events[1]) else float(np.max(sol.y[0]))
    if sol.status == 0:  # no separation within t_end: overdamped, unclamped
        return NondimensionalImpact(0.0, math.inf, x_max, False)
    by_force = clamp and len(sol.y_events[2]) > 0
    return NondimensionalImpact(
        restitution=float(-sol.y[1, -1]),
        contact_time=float(sol.t[-1]),
        max_overlap=x_max,
        separated_by_force=bool(by_force),
    )


def _e_of(law: str, p: float, clamp: bool) -> float:
    return nondimensional_impact(law, p, clamp).restitution


def _invert(law: str, e: float, clamp: bool, p_cap: float = math.inf) -> float:
    """Solve e(p) = e for the law's single parameter p >= 0 (e(p) decreases from 1)."""
    if e == 1.0:
        return 0.0
    lo, hi = 0.0, 1.0
    while _e_of(law, hi, clamp) > e:
        lo, hi = hi, 2.0 * hi
        if hi > p_cap or hi > 1e6:  # pragma: no cover - guarded by MIN_CALIBRATED_RESTITUTION
            raise ParameterError("restitution", e, f"not reachable by the {law} law")
    return brentq(
        lambda p: _e_of(law, p, clamp) - e, lo, hi, xtol=1e-14, rtol=4 * np.finfo(float).eps,
        maxiter=200,
    )


def _linear_ratio(e: float) -> float:
    """$-\\ln e / \\sqrt{\\pi^2 + \\ln^2 e}$ (exact for the unclamped linear oscillator)."""
    le = math.log(e)
    return -le / math.sqrt(math.pi**2 + le * le)


# --------------------------------------------------------------------------------------------------
# Kelvin–Voigt and Tsuji


@functools.lru_cache(maxsize=4096)
def _kv_zeta_cached(e: float, clamp: bool) -> float:
    if not clamp:
        return _linear_ratio(e)
    return _invert("kelvin-voigt", e, True)


def kelvin_voigt_damping_ratio(e: float, clamp: bool = True) -> float:
    r"""Damping ratio $\zeta$ of $F = k\delta + c\dot\delta$, $c = 2\zeta\sqrt{m^* k}$, giving $e$.

    Unclamped: $\zeta = -\ln e/\sqrt{\pi^2 + \ln^2 e}$ (exact). Clamped: numerical inversion of the
    nondimensional impact (Schwager & Pöschel 2007 list clamped $e$ = 0.253/0.550/0.902 for the
    unclamped $\zeta$ of 0.1/0.5/0.9). Cached on ``(e, clamp)``.
    """
    e = check_restitution(e, minimum=MIN_CALIBRATED_RESTITUTION if clamp else 0.0)
    return _kv_zeta_cached(e, bool(clamp))


def kelvin_voigt_restitution(zeta: float, clamp: bool = True) -> float:
    r"""Restitution of the linear spring–dashpot with damping ratio $\zeta$ (numerical)."""
    return _e_of("kelvin-voigt", _check_nonnegative(zeta, "zeta"), bool(clamp))


@functools.lru_cache(maxsize=4096)
def _tsuji_eta_cached(e: float, clamp: bool) -> float:
    if not clamp:
        return math.sqrt(5.0) * _linear_ratio(e)
    return _invert("tsuji", e, True)


def tsuji_eta(e: float, clamp: bool = True) -> float:
    r"""Tsuji damping coefficient $\eta$ giving restitution $e$ (independent of impact speed).

    Unclamped: $\eta = -\sqrt5\ln e/\sqrt{\pi^2+\ln^2 e}$ (exact: Tsuji is Kelvin–Voigt with
    $\zeta = \eta/\sqrt5$ in transformed variables, see the module docstring). Clamped (default):
    numerical inversion of the nondimensional Tsuji impact. Cached on ``(e, clamp)``.
    """
    e = check_restitution(e, minimum=MIN_CALIBRATED_RESTITUTION if clamp else 0.0)
    return _tsuji_eta_cached(e, bool(clamp))


def tsuji_restitution(eta: float, clamp: bool = True) -> float:
    """Restitution of the Tsuji law with coefficient ``eta`` (numerical, speed-independent)."""
    return _e_of("tsuji", _check_nonnegative(eta, "eta"), bool(clamp))


# --------------------------------------------------------------------------------------------------
# viscoelastic (Brilliantov et al. 1996)


@functools.lru_cache(maxsize=4096)
def _visco_xi_cached(e: float, clamp: bool) -> float:
    return _invert("viscoelastic", e, clamp)


def viscoelastic_xi(e: float, clamp: bool = True) -> float:
    r"""Scaled dissipation $\xi = \tfrac32 A (k/m^*)^{2/5} v^{1/5}$ giving restitution $e$.

    Numerical inversion of the nondimensional impact; cached on ``(e, clamp)``.
    """
    e = check_restitution(e, minimum=MIN_CALIBRATED_RESTITUTION)
    return _visco_xi_cached(e, bool(clamp))


def viscoelastic_restitution(xi: float, clamp: bool = True) -> float:
    r"""Restitution $e(\xi)$ of the viscoelastic law (numerical)."""
    return _e_of("viscoelastic", _check_nonnegative(xi, "xi"), bool(clamp))


def viscoelastic_xi_from_A(A: float, stiffness: float, effective_mass: float, impact_velocity: float) -> float:
    r"""$\xi = \tfrac32 A (k/m^*)^{2/5} v^{1/5}$ (Ramírez et al. 1999)."""
    k = _check_positive(stiffness, "stiffness")
    m = _check_positive(effective_mass, "effective_mass")
    v = _check_positive(impact_velocity, "impact_velocity")
    return 1.5 * _check_nonnegative(A, "A") * (k / m) ** 0.4 * v**0.2


def viscoelastic_A_from_xi(xi: float, stiffness: float, effective_mass: float, impact_velocity: float) -> float:
    r"""Inverse of `viscoelastic_xi_from_A`: $A = \xi / (\tfrac32 (k/m^*)^{2/5} v^{1/5})$ (s)."""
    k = _check_positive(stiffness, "stiffness")
    m = _check_positive(effective_mass, "effective_mass")
    v = _check_positive(impact_velocity, "impact_velocity")
    return _check_nonnegative(xi, "xi") / (1.5 * (k / m) ** 0.4 * v**0.2)


@functools.lru_cache(maxsize=4096)
def _dashpot_zeta_cached(e: float, clamp: bool) -> float:
    return _invert("hertz-dashpot", e, clamp)


def hertz_dashpot_zeta(e: float, clamp: bool = True) -> float:
    r"""Scaled dashpot $\zeta = \gamma\, m^{*-3/5} k^{-2/5} v^{-1/5}$ of Hertz with a linear dashpot,
    $F = k\delta^{3/2} + \gamma\dot\delta$ (Rosas, Romero, Nesterenko & Lindenberg 2007, Phys. Rev. Lett. 98,
    164301), giving restitution $e$ at the speed $v$. Numerical inversion; cached on ``(e, clamp)``."""
    e = check_restitution(e, minimum=MIN_CALIBRATED_RESTITUTION)
    return _dashpot_zeta_cached(e, bool(clamp))


def hertz_dashpot_restitution(zeta: float, clamp: bool = True) -> float:
    r"""Restitution $e(\zeta)$ of Hertz with a linear dashpot (numerical)."""
    return _e_of("hertz-dashpot", _check_nonnegative(zeta, "zeta"), bool(clamp))


def hertz_dashpot_zeta_from_gamma(gamma: float, stiffness: float, effective_mass: float,
                                  impact_velocity: float) -> float:
    r"""$\zeta = \gamma\, m^{*-3/5} k^{-2/5} v^{-1/5}$: the dashpot's weight grows as the impact slows."""
    k = _check_positive(stiffness, "stiffness")
    m = _check_positive(effective_mass, "effective_mass")
    v = _check_positive(impact_velocity, "impact_velocity")
    return _check_nonnegative(gamma, "gamma") * m**-0.6 * k**-0.4 * v**-0.2


def viscoelastic_restitution_series(xi: float | np.ndarray) -> float | np.ndarray:
    r"""Ramírez et al. (1999) small-$\xi$ series $e = 1 - 1.15344\xi + 0.79826\xi^2$ of the unclamped law
    (tension allowed), error $O(\xi^3)$ against it (6.1e-7 at $\xi = 0.01$, 6.4e-5 at 0.05); against the
    clamped law (the default) it is off by about $\xi^{2.2}$ (2.0e-6 and 7.3e-5: `viscoelastic_restitution`)."""
    xi = np.asarray(xi, dtype=float)
    out = 1.0 - 1.15344 * xi + 0.79826 * xi**2
    return float(out) if out.ndim == 0 else out


def viscoelastic_restitution_pade(xi: float | np.ndarray) -> float | np.ndarray:
    r"""Müller & Pöschel (2011) Padé fit of the clamped viscoelastic $e(\xi)$, $s = \sqrt\xi$.

    $e = (1 + 1.07232s + 0.574198s^2 + 0.141552s^3)/(1 + 1.07232s + 1.72765s^2 + 1.37842s^3 +
    1.19449s^4 + 0.467273s^5 + 0.235585s^6)$. A fit, not exact: see the tests for its measured error.
    """
    s = np.sqrt(np.asarray(xi, dtype=float))
    num = 1 + 1.07232 * s + 0.574198 * s**2 + 0.141552 * s**3
    den = 1 + 1.07232 * s + 1.72765 * s**2 + 1.37842 * s**3 + 1.19449 * s**4 + 0.467273 * s**5 + 0.235585 * s**6
    out = num / den
    return float(out) if out.ndim == 0 else out


# --------------------------------------------------------------------------------------------------
# Hertz closed form

HERTZ_CONTACT_TIME_FACTOR: float = 0.8 * float(_beta_fn(0.4, 0.5))
r"""$t_c v/\delta_\max = \tfrac45 B(\tfrac25, \tfrac12) = 2.94328\ldots$ for the elastic Hertz impact
(Johnson 1985, *Contact Mechanics*, §11.4; Landau & Lifshitz, *Theory of Elasticity*, §9)."""


def hertz_impact(effective_mass: float, stiffness: float, impact_velocity: float) -> dict[str, float]:
    r"""Closed-form elastic Hertz impact (Johnson 1985, §11.4).

    $\delta_\max = (5 m^* v^2 / (4k))^{2/5}$, $t_c = 2.94328\,\delta_\max/v$,
    $F_\max = k\delta_\max^{3/2}$. Returns ``{"max_overlap", "contact_time", "max_force"}``.
    """
    m = _check_positive(effective_mass, "effective_mass")
    k = _check_positive(stiffness, "stiffness")
    v = _check_positive(impact_velocity, "impact_velocity")
    d = (1.25 * m * v * v / k) ** 0.4
    return {"max_overlap": d, "contact_time": HERTZ_CONTACT_TIME_FACTOR * d / v, "max_force": k * d**1.5}
