"""Rigid-body (independent-collision) theory of velocity amplifiers: the seed paper's closed forms.

Everything here follows Sections 2–5 of the seed paper (Rodgers, Goyal, Kelly & Sheehy, *The dynamics
of multiple pair-wise collisions in a chain for designing optimal shock amplifiers*, Shock and
Vibration, 2009; `docs/references.md, "Seed paper"`), Eqs 1–30, and is plain
numpy/scipy (no JAX). Conventions (see `notes/CONVENTIONS.md`): masses are numbered from the bottom /
from the striker, `m_1` is the heaviest; pair-wise ratios are `r_{i+1,i} = m_{i+1}/m_i` (Eq 5),
`R = m_n/m_1 = prod r` (Eq 14); velocities are upward-positive.

Arrays over interfaces follow the project layout: an `(n,)` array whose entry 0 belongs to the ground
(interface 0) and entry `j` to the pair `m_j – m_{j+1}`. A scalar restitution applies to every interface.

Most functions broadcast over numpy arrays of `R` and `e` (the notebooks draw surfaces); the only Python
loops are the small searches over the integer number of masses `n` and the scalar root of Eq 23.

**Misprints in the paper** (each is re-derived in `tests/test_rigid.py`):

* Eq 8 prints `r_{2,3}`; from Eq 4 with `V_2 = 0` the condition is `g_{2,1} = (1+e)/(e − r_{2,1})`.
* Eq 23 prints the exponent `x_0/1+x_0`; stationarity of Eq 20 in `n` gives
  `1 + x_0 = (1+e)·x_0^{x_0/(1+x_0)}`.
* Eq 24 prints `(1+R)^{n*−1}`; the optimum is `G* = (1+e)^{n*}/(1+x_0)^{n*−1} − 1`, i.e. Eq 20 at the
  continuous `n*` of Eq 22 (there `R^{1/(n*−1)} = x_0`).
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np
from scipy.optimize import brentq

from .errors import ParameterError

__all__ = [
    "as_rigid_restitution",
    "ELASTIC_EXCESS",
    # two-mass impact (Section 2)
    "impact_velocities",
    "velocity_gains",
    "velocity_ratio_m1_at_rest",
    "velocity_ratio_m2_at_rest",
    "gain_target_at_rest",
    "energy_efficiencies",
    # chains and stacks with arbitrary masses
    "chain_gain",
    "stack_gain",
    "cascade_velocities",
    # MVG (Sections 3.1, 4.1)
    "mvg_ratio",
    "mvg_masses",
    "mvg_chain_gain",
    "mvg_chain_efficiency",
    "mvg_chain_gain_limit",
    "mvg_gain",
    "mvg_gain_limit",
    "mvg_efficiency",
    "mvg_total_mass",
    "mvg_optimal_n",
    "optimal_pair_ratio",
    "continuous_optimal_n",
    "continuous_optimal_gain",
    "mvg_optimal_n_pb",
    # MET (Section 4.2)
    "met_ratios",
    "met_masses",
    "met_mass_ratio",
    "met_gain",
    "met_gain_limit",
    "met_efficiency",
    "met_total_mass",
    "met_n_for_ratio",
    # design (Section 5)
    "StackDesign",
    "DesignComparison",
    "DesignRatios",
    "mvg_design",
    "met_design",
    "design",
    "design_ratios",
]

# --------------------------------------------------------------------------------------------------
# validation helpers


#: The most masses a function of this module builds an array for (`mvg_masses`, `met_masses`, the designs):
#: 10^6 masses are 8 MB; a typo such as `n = 10**10` would ask for 80 GB (the closed forms of a gain take
#: any `n`).
MAX_ARRAY_MASSES = 1_000_000


def _arr(x, name: str = "value") -> np.ndarray:
    """`x` as a float array, or a `ParameterError` naming `name` (text, lists of text, `None`, ragged
    lists: numpy's own ValueError/TypeError did not say which argument)."""
    # text is refused (numpy turns "0.012" into 0.012); anything numpy makes a float of passes: fractions,
    # decimals, None (NaN) in an unused entry such as a ground restitution's, as before (a review)
    try:
        if isinstance(x, (str, bytes)) or np.asarray(x).dtype.kind in "USV":
            raise TypeError
        return np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(name, x, "a real number (or an array of real numbers)") from None


def _scalar(x, name: str) -> float:
    """One real number (`ParameterError` for text or an array of more than one value)."""
    a = _arr(x, name)
    if a.size != 1:
        raise ParameterError(name, _show(a), "a single number (this function designs one stack)")
    return float(a.reshape(()))


def _check_finite(name: str, x: np.ndarray) -> None:
    if not np.all(np.isfinite(x)):
        raise ParameterError(name, _show(x), "must be finite (no NaN or inf)")


def _show(x):
    x = np.asarray(x)
    return x.item() if x.size == 1 else x.tolist() if x.size <= 8 else f"array of shape {x.shape}"


def _check_e(x, name: str = "e", *, allow_zero: bool = True) -> np.ndarray:
    """A pair's coefficient of restitution: `[0, 1]` (0 = perfectly plastic: the pair moves on together),
    or `(0, 1]` where a formula needs `e > 0` (the MET ratios, Eq 27, vanish at `e = 0`)."""
    x = _arr(x, name)
    _check_finite(name, x)
    ok = (x >= 0) if allow_zero else (x > 0)
    if not np.all(ok & (x <= 1)):
        allowed = "[0, 1]" if allow_zero else "(0, 1] (the MET ratios of Eq 27 vanish at e = 0)"
        raise ParameterError(name, _show(x), f"coefficient of restitution must lie in {allowed}")
    return x


def _check_ground_e(x, name: str = "ground_restitution") -> np.ndarray:
    x = _arr(x, name)
    _check_finite(name, x)
    if not np.all(x >= 0):
        raise ParameterError(
            name, _show(x), "ground restitution e_{1,0} must be >= 0 (values > 1 model an 'active ground', Eq 19)"
        )
    return x


def _check_R(x, name: str = "R") -> np.ndarray:
    x = _arr(x, name)
    _check_finite(name, x)
    if not np.all((x > 0) & (x < 1)):
        raise ParameterError(name, _show(x), "mass ratio R = m_n/m_1 must lie in (0, 1)")
    return x


def _check_positive(x, name: str) -> np.ndarray:
    x = _arr(x, name)
    _check_finite(name, x)
    if not np.all(x > 0):
        raise ParameterError(name, _show(x), "must be > 0")
    return x


def _check_n(n, name: str = "n", maximum: int = 2**53) -> np.ndarray:
    """An integer number of masses `2 <= n <= maximum` (as int64), checked before any cast (a review:
    `n = 1e20` was reported as -9223372036854775808); `maximum`: `MAX_ARRAY_MASSES` where an array of `n`
    masses is built, else 2^53 (float64's exact integers)."""
    try:
        a = np.asarray(n)
    except (TypeError, ValueError):
        a = np.asarray(None, dtype=object)
    if a.dtype.kind == "b" or a.dtype.kind not in "iu" and not (
            a.dtype.kind == "f" and np.all(np.isfinite(a)) and np.all(a == np.round(a))):
        raise ParameterError(name, _show(a) if a.dtype.kind in "iufb" else n, "number of masses must be an integer >= 2")
    if not np.all(a >= 2):
        raise ParameterError(name, _show(a), "number of masses must be an integer >= 2")
    if not np.all(a <= maximum):
        why = (f"at most {maximum:,} (the function builds an array of n masses; MAX_ARRAY_MASSES)"
               if maximum == MAX_ARRAY_MASSES else f"at most 2^53 = {maximum:,}")
        raise ParameterError(name, _show(a), f"number of masses must be an integer >= 2 and {why}")
    return a.astype(np.int64)


def _one_n(n, name: str = "n") -> int:
    """One number of masses for a function that builds an array of them (`_check_n`, at most
    `MAX_ARRAY_MASSES`)."""
    a = _check_n(n, name, maximum=MAX_ARRAY_MASSES)
    if a.size != 1:
        raise ParameterError(name, _show(a), "a single number of masses")
    return int(a.reshape(()))


def _check_g(g, name: str = "g") -> np.ndarray:
    g = _arr(g, name)
    _check_finite(name, g)
    if not np.all(g < 1):
        raise ParameterError(name, _show(g), "initial velocity ratio g = v2/v1 must be < 1 so that the masses collide")
    return g


def _interface_array(restitution, n: int, name: str) -> np.ndarray:
    """Restitution over interfaces 1..n-1 (shape (..., n-1)) from a scalar or an (..., n) array."""
    e = _arr(restitution)
    if e.ndim == 0:
        return np.broadcast_to(e, (n - 1,))
    if e.shape[-1] != n:
        raise ParameterError(
            name, _show(e), f"must be a scalar or have length n = {n} over interfaces 0..n-1 (entry 0 = ground)"
        )
    return e[..., 1:]


def _masses(masses, name: str = "masses", minimum: int = 2) -> np.ndarray:
    m = _check_positive(masses, name)
    if m.ndim == 0 or m.shape[-1] < minimum:
        raise ParameterError(name, _show(m), f"need at least {minimum} mass{'es' if minimum > 1 else ''} (last axis)")
    return m


# --------------------------------------------------------------------------------------------------
# Section 2: impact between two masses


def impact_velocities(m1, m2, v1, v2, e):
    """Post-impact velocities `(V1, V2)` of two masses (paper Eqs 1–2).

    Momentum `m1 V1 + m2 V2 = m1 v1 + m2 v2` (Eq 1) and restitution `e = −(V2 − V1)/(v2 − v1)` (Eq 2)
    give

    `V1 = v1 + m2 (1+e)(v2 − v1)/(m1 + m2)`, `V2 = v2 − m1 (1+e)(v2 − v1)/(m1 + m2)`.

    Broadcasts over arrays. `e` in [0, 1]; masses > 0. No check that the bodies approach (the
    event simulator does that).
    """
    m1, m2 = _check_positive(m1, "m1"), _check_positive(m2, "m2")
    v1, v2 = _arr(v1), _arr(v2)
    _check_finite("v1", v1)
    _check_finite("v2", v2)
    e = _check_e(e)
    dv = (1 + e) * (v2 - v1) / (m1 + m2)
    return v1 + m2 * dv, v2 - m1 * dv


def velocity_gains(r, g, e):
    """Velocity gains `(A1, A2) = (V1/v1, V2/v2)` of a two-mass impact (paper Eqs 3–4).

    `A1 = 1 + r/(1+r)·(1+e)(g − 1)` (Eq 3), `A2 = 1 − (1+e)/(1+r)·(1 − 1/g)` (Eq 4), with
    `r = m2/m1` (Eq 5) and `g = v2/v1` (Eq 6). The bodies collide only for `g < 1` (Section 2).
    `A2` is infinite for `g = 0` (target at rest); use `gain_target_at_rest` there.
    """
    r = _check_positive(r, "r")
    g = _check_g(g)
    e = _check_e(e)
    with np.errstate(divide="ignore"):
        a2 = 1 - (1 + e) / (1 + r) * (1 - 1 / g)
    return 1 + r / (1 + r) * (1 + e) * (g - 1), a2


def velocity_ratio_m1_at_rest(r, e):
    """Initial velocity ratio `g = v2/v1` for which `m1` is at rest after impact (paper Eq 7).

    From Eq 3 with `A1 = 0`: `g = (e − 1/r)/(1 + e)`.
    """
    r, e = _check_positive(r, "r"), _check_e(e)
    return (e - 1 / r) / (1 + e)


def velocity_ratio_m2_at_rest(r, e):
    """Initial velocity ratio `g = v2/v1` for which `m2` is at rest after impact (paper Eq 8, corrected).

    From Eq 4 with `A2 = 0`: `1 − 1/g = (1+r)/(1+e)`, so `g = (1 + e)/(e − r_{2,1})`.
    **Misprint:** the paper prints `r_{2,3}` in the denominator; `r_{2,1}` is meant (there is no third
    mass in the two-body problem; `tests/test_rigid.py` re-derives it with a root finder on Eq 4).
    The ratio lies in the collision range `g < 1` only when `r > e` (then `g < 0`, head-on impact);
    `r = e` has no finite solution (returns ±inf).
    """
    r, e = _check_positive(r, "r"), _check_e(e)
    with np.errstate(divide="ignore"):
        return (1 + e) / (e - r)


def gain_target_at_rest(r, e):
    """Gain `V2/v1` when `m2` starts at rest (`g = 0`): `(1 + e)/(1 + r)` (Eqs 1–2; factor of Eq 13).

    The paper's Eq 9 is the special case where `m1` is also at rest afterwards (`V1 = v2 = 0`): Eq 7
    with `g = 0` forces `r = 1/e` and then `G_2 = 1/r = e` — no amplification.
    """
    r, e = _check_positive(r, "r"), _check_e(e)
    return (1 + e) / (1 + r)


def energy_efficiencies(r, g, e):
    """Kinetic-energy transfer efficiencies `(K1, K2)` of a two-mass impact (paper Eqs 10–12).

    `K_i = (½ m_i V_i²) / (½ m1 v1² + ½ m2 v2²)`:

    `K1 = A1² / (1 + r g²)` (Eq 10), `K2 = r (g − (1+e)(g − 1)/(1+r))² / (1 + r g²)` (Eq 11).
    `K1 + K2 = 1` for `e = 1`; at `g = 0` Eq 11 reduces to `K2 = r (1+e)²/(1+r)²` (Eq 12).
    """
    r = _check_positive(r, "r")
    g = _check_g(g)
    e = _check_e(e)
    den = 1 + r * g**2
    k1 = (1 + r / (1 + r) * (1 + e) * (g - 1)) ** 2 / den
    k2 = r * (g - (1 + e) * (g - 1) / (1 + r)) ** 2 / den
    return k1, k2


# --------------------------------------------------------------------------------------------------
# Sections 3–4: chains and stacks with arbitrary masses


#: a measured pair restitution at most this far above 1 is an elastic contact's (the solver's error) and
#: counts as 1 (`as_rigid_restitution`)
ELASTIC_EXCESS = 1e-6


def as_rigid_restitution(e, first: int = 1):
    """Measured restitutions `(..., n)` over interfaces as the rigid model takes them: every pair's value
    (interfaces `first`.., entry 0 being the ground's, which may exceed 1) in `(1, 1 + ELASTIC_EXCESS]` is
    an elastic contact measured to the solver's error and becomes 1; larger values (a contact that its
    neighbour pushes apart, separating faster than it approached) are kept, for Eqs 13/19 and
    `simulate_rigid` to refuse. Returns a new float array."""
    out = np.array(e, dtype=float)
    pairs = out[..., max(first, 1):]
    pairs[(pairs > 1.0) & (pairs <= 1.0 + ELASTIC_EXCESS)] = 1.0
    return out


def chain_gain(masses, restitution):
    """Gain `G_n = V_n/v_1` of a horizontal chain struck by `m_1`, others at rest (paper Eq 13).

    `G_n = prod_{k=2}^{n} (1 + e_{k,k−1})/(1 + r_{k,k−1})`.

    `masses`: `(..., n)`; `restitution`: scalar or `(..., n)` over interfaces (entry 0, the ground, is
    unused here). Assumes each mass is struck once, in order (independent collisions).
    """
    m = _masses(masses)
    n = m.shape[-1]
    e = _check_e(_interface_array(restitution, n, "restitution"), "restitution")
    r = m[..., 1:] / m[..., :-1]
    return np.prod((1 + e) / (1 + r), axis=-1)


def stack_gain(masses, restitution, ground_restitution=None):
    """Gain `G_n = V_n/v_ff` of the top of a dropped vertical stack (paper Eq 19).

    `G_n = (1 + e_{1,0}) prod_{k=2}^{n} (1 + e_{k,k−1})/(1 + r_{k,k−1}) − 1`: in the frame falling with
    `v_ff` the stack is the horizontal chain of Eq 13 struck at `(1 + e_{1,0}) v_ff`.

    `restitution`: scalar or `(..., n)` over interfaces, entry 0 = ground; `ground_restitution`, when
    given, overrides entry 0 (and a scalar `restitution`). `e_{1,0} > 1` ('active ground') is allowed.
    One mass (`n = 1`): the ground bounce alone, `G_1 = e_{1,0}`.
    """
    m = _masses(masses, minimum=1)
    n = m.shape[-1]
    e_all = _arr(restitution, "restitution")
    e = _check_e(_interface_array(restitution, n, "restitution"), "restitution")
    if ground_restitution is None:  # entry 0 of `restitution` (its check names `restitution`, as given)
        e0 = _check_ground_e(e_all if e_all.ndim == 0 else e_all[..., 0], "restitution")
    else:
        e0 = _check_ground_e(ground_restitution)
    r = m[..., 1:] / m[..., :-1]
    return (1 + e0) * np.prod((1 + e) / (1 + r), axis=-1) - 1


def cascade_velocities(masses, restitution, ground_restitution=None, velocities=None):
    """One sequential pass of binary impacts through a chain or stack (paper Eqs 1–2, Section 4).

    Order: ground–`m_1` (if `ground_restitution` is given), then `m_1–m_2`, `m_2–m_3`, …, each pair
    resolved with Eqs 1–2 regardless of any later re-collision (the paper's independent-collision
    picture). `velocities` default: a dropped stack, all `−1` (units of `v_ff`) when there is a
    ground, else the horizontal chain `(1, 0, …, 0)`.

    Returns `(after_hit, after_pass)`, both `(..., n)`: `after_hit[i]` is the velocity of mass `i+1`
    just after it is struck from below (Fig 16's per-mass gain for `v_ff = 1`), `after_pass[i]` its
    velocity after it has struck the mass above (equal to `after_hit` for the top mass). A MET stack
    (Eq 25) leaves `after_pass` zero for all masses but the top.
    """
    m = _masses(masses, minimum=1 if ground_restitution is not None else 2)  # one mass: the ground bounce
    n = m.shape[-1]
    e = _check_e(_interface_array(restitution, n, "restitution"), "restitution")
    e = np.broadcast_to(e, m.shape[:-1] + (n - 1,))
    if velocities is None:
        v = -np.ones_like(m) if ground_restitution is not None else np.concatenate(
            [np.ones_like(m[..., :1]), np.zeros_like(m[..., 1:])], axis=-1
        )
    else:
        v = np.array(np.broadcast_to(_arr(velocities), m.shape), dtype=float)
        _check_finite("velocities", v)
    hit = np.empty_like(v)
    out = np.empty_like(v)
    cur = v[..., 0]
    if ground_restitution is not None:
        e0 = _check_ground_e(ground_restitution)
        cur = -e0 * cur
    hit[..., 0] = cur
    for k in range(n - 1):  # small loop over the chain
        va, vb = impact_velocities(m[..., k], m[..., k + 1], cur, v[..., k + 1], e[..., k])
        out[..., k] = va
        hit[..., k + 1] = vb
        cur = vb
    out[..., n - 1] = cur
    return hit, out


# --------------------------------------------------------------------------------------------------
# MVG: power-law masses (Eqs 14–24)


def mvg_ratio(R, n):
    """Common pair-wise mass ratio `r = R^{1/(n−1)}` of the MVG chain (paper Eqs 14–15)."""
    R, n = _check_R(R), _check_n(n)
    return R ** (1.0 / (n - 1))


def mvg_masses(R, n: int, m1: float = 1.0) -> np.ndarray:
    """MVG masses `m_i = m_1 R^{(i−1)/(n−1)}`, `i = 1..n` (Eq 15). Scalar `R`, `n`; returns `(n,)`."""
    R, n = _scalar(_check_R(R), "R"), _one_n(n)
    m1 = _scalar(_check_positive(m1, "m1"), "m1")
    return m1 * R ** (np.arange(n) / (n - 1))


def mvg_chain_gain(R, e, n):
    """Gain of the horizontal MVG chain `G_n = [(1+e)/(1 + R^{1/(n−1)})]^{n−1}` (paper Eq 16)."""
    x, e = mvg_ratio(R, n), _check_e(e)
    n = _check_n(n)
    return ((1 + e) / (1 + x)) ** (n - 1)


def mvg_chain_efficiency(R, e, n):
    """Energy efficiency of the horizontal MVG chain `K_n = R (1+e)^{2(n−1)}/(1 + R^{1/(n−1)})^{2(n−1)}` (Eq 17).

    `K_n = m_n V_n² / (m_1 v_1²) = R G_n²`, with Eq 16 for `G_n` (only `m_1` moves initially).
    """
    R = _check_R(R)
    return R * mvg_chain_gain(R, e, n) ** 2


def mvg_chain_gain_limit(R):
    """Elastic (`e = 1`) horizontal MVG gain for `n → ∞`: `1/√R` (paper Eq 18).

    `(1 + R^{1/m})^m = 2^m (1 + (R^{1/m} − 1)/2)^m → 2^m e^{ln R/2} = 2^m √R`, so `K_n = R G_n² → 1`.
    """
    return 1 / np.sqrt(_check_R(R))


def mvg_gain(R, e, n):
    """Gain of the dropped MVG stack `G_n = (1+e)^n/(1 + R^{1/(n−1)})^{n−1} − 1` (paper Eq 20).

    Eq 19 with `e_{1,0} = e_{k,k−1} = e` and the power-law ratios of Eq 15 (which maximise Eq 19 for
    fixed `n` and `R`, as for the horizontal chain). Broadcasts over `R`, `e`, `n`.
    """
    x, e = mvg_ratio(R, n), _check_e(e)
    n = _check_n(n)
    # (1+e)^n/(1+x)^(n-1) in log form: the two powers overflow separately for n ≳ 1000
    return np.exp(n * np.log1p(e) - (n - 1) * np.log1p(x)) - 1


def mvg_gain_limit(R):
    """Elastic (`e = 1`) MVG stack gain for `n → ∞`: `(2 − √R)/√R` (paper Eq 21); see `mvg_chain_gain_limit`."""
    s = np.sqrt(_check_R(R))
    return (2 - s) / s


def mvg_total_mass(R, n, m1=1.0):
    """Total mass of the MVG stack `M = m_1 Σ_{i=0}^{n−1} x^i = m_1 (1 − x^n)/(1 − x)`, `x = R^{1/(n−1)}` (Eq 15)."""
    R, n = _check_R(R), _check_n(n)
    # (1 - x^n)/(1 - x) with ln x = ln R/(n - 1), as expm1's: the plain form is 0/0 = NaN where x rounds to
    # 1 (R within ~1e-13 of 1, a review: mvg_total_mass(1 - 1e-15, 1000) was NaN, 1000 m_1 meant)
    ln_x = np.log(R) / (n - 1)
    return _check_positive(m1, "m1") * np.expm1(n * ln_x) / np.expm1(ln_x)


def mvg_efficiency(R, e, n):
    """Energy efficiency `K_n` of the dropped MVG stack (derived here; the paper gives no formula).

    Definition (Section 2.1, Section 5): kinetic energy of the top mass after the cascade over the
    kinetic energy of the whole stack at impact, when every mass moves at `v_ff`:

    `K_n = ½ m_n (G_n v_ff)² / (½ M v_ff²) = R G_n² / (M/m_1)`,

    with `G_n` from Eq 20 and `M/m_1 = (1 − x^n)/(1 − x)`, `x = R^{1/(n−1)}` (Eq 15). Unlike Eq 17
    (horizontal chain, only `m_1` moving) the denominator holds the whole stack.
    """
    R = _check_R(R)
    return R * mvg_gain(R, e, n) ** 2 / mvg_total_mass(R, n)


def _check_e_below_one(e) -> np.ndarray:
    e = _check_e(e)
    if np.any(e >= 1):
        raise ParameterError(
            "e", _show(e), "the optimal MVG stack needs e < 1: for e = 1 the gain of Eq 20 grows with n "
            "without bound (limit Eq 21); choose n explicitly"
        )
    return e


#: The smallest `e` of the continuous-`n` optimum (`optimal_pair_ratio`): below it the root `x_0` of Eq 23
#: lies under 1e-300, the bracket's lower end (`h(1e-300) = 6.9e-298 - ln(1 + e)`).
_E_MIN_CONTINUOUS = 1e-297


def _check_e_for_optimum(e) -> np.ndarray:
    """`e` of the continuous-`n` optimum (Eqs 22-24): `1e-297 <= e < 1` (a review: `e = 0` passed the
    check of `[0, 1)` and scipy's brentq failed with "f(a) and f(b) must have different signs")."""
    e = _check_e_below_one(e)
    if np.any(e < _E_MIN_CONTINUOUS):
        raise ParameterError("e", _show(e), "the continuous-n optimum (Eqs 22-24) needs e > 0 (as e -> 0 the "
                             "optimal pair ratio x_0 -> 0 and n* -> 1; in float64, e >= 1e-297); "
                             "mvg_optimal_n takes e = 0")
    return e


def mvg_optimal_n(R, e, *, n_limit: int = 100_000):
    """Number of masses `n_max >= 2` maximising the MVG stack gain, Eq 20, by search over integer `n`.

    Exact: with `m = n − 1` and `x = R^{1/m}` (an increasing map of `m` onto `(0, 1)`),
    `d ln(1 + G)/dx = (ln R/(x ln²x))·h(x)`, `h(x) = ln(1+x) − ln(1+e) − x ln x/(1+x)`, and
    `h'(x) = −ln x/(1+x)² > 0` on `(0, 1)`: `ln(1 + G)` is strictly unimodal in continuous `n`. So
    the search steps `n = 2, 3, …` and stops, per element, at the first `n` with `G_{n+1} <= G_n`
    (ties go to the smaller `n`). Broadcasts over `R` and `e` (`e < 1`: for `e = 1` there is no
    maximum). Returns an integer array.
    """
    R, e = np.broadcast_arrays(_check_R(R), _check_e_below_one(e))
    shape = R.shape
    Rf, ef = R.ravel(), e.ravel()
    best = np.full(Rf.size, 2, dtype=np.int64)
    g_best = np.asarray(mvg_gain(Rf, ef, 2), dtype=float)
    idx = np.arange(Rf.size)  # elements whose gain still increased at the last step
    n = 2
    while idx.size:  # small integer search over n
        n += 1
        if n > n_limit:
            raise ParameterError("n_limit", n_limit, "the MVG optimum lies beyond n_limit: raise it")
        g = mvg_gain(Rf[idx], ef[idx], n)
        up = g > g_best[idx]
        idx = idx[up]
        best[idx] = n
        g_best[idx] = g[up]
    best = best.reshape(shape)
    return best if best.ndim else int(best)


def _stationarity(x: float, e: float) -> float:
    """`h(x) = ln(1+x) − ln(1+e) − x ln x/(1+x)`: zero at the optimal pair ratio (`optimal_pair_ratio`)."""
    return np.log1p(x) - np.log1p(e) - x * np.log(x) / (1 + x)


def optimal_pair_ratio(e):
    """The optimal ratio of neighbouring masses `x_0 = m_{i+1}/m_i` of a continuous-`n` MVG chain (the
    Pöschel–Brilliantov route; formerly `pb_x0`): the root `x_0 ∈ (0, 1)` of `1 + x_0 = (1 + e)·x_0^{x_0/(1+x_0)}` (paper Eq 23, corrected).

    **Misprint:** the paper prints the exponent as `x_0/1+x_0`; the stationarity condition of Eq 20 in
    continuous `n` (with `x = R^{1/(n−1)}`) is `h(x) = ln(1+x) − ln(1+e) − x ln x/(1+x) = 0`, i.e.
    exponent `x_0/(1 + x_0)` (Pöschel & Brilliantov). `h` is strictly increasing on `(0, 1)`
    (`h' = −ln x/(1+x)²`) from `−ln(1+e)` to `ln(2/(1+e))`, so for `0 < e < 1` there is exactly one
    root inside; the degenerate roots are `x_0 = 1` for `e = 1` (`n* = ∞`) and `x_0 → 0` for `e → 0`, and
    a second root `x_0 > 1` belongs to increasing masses (`R > 1`) — the bracket `(0, 1)` avoids both.
    Solved with `scipy.optimize.brentq` per distinct `e` (`e < 1`).
    """
    e = _check_e_for_optimum(e)
    uniq, inv = np.unique(e.ravel(), return_inverse=True)
    roots = np.array([brentq(_stationarity, 1e-300, 1.0, args=(float(ei),), xtol=1e-300, rtol=4 * np.finfo(float).eps,
                             maxiter=500) for ei in uniq])
    out = roots[inv].reshape(e.shape)
    return out if out.ndim else float(out)


def continuous_optimal_n(R, e):
    """(Formerly `pb_n_star`.) Continuous optimal number of masses `n* = ln R/ln x_0 + 1` (paper Eq 22), `x_0` from Eq 23."""
    R = _check_R(R)
    return np.log(R) / np.log(optimal_pair_ratio(e)) + 1


def continuous_optimal_gain(R, e):
    """(Formerly `pb_gain_star`.) Optimal continuous-`n` gain `G* = (1+e)^{n*}/(1 + x_0)^{n*−1} − 1` (paper Eq 24, corrected).

    **Misprint:** the paper prints `(1 + R)^{n*−1}` in the denominator; `(1 + x_0)` is meant. With
    Eq 22, `R^{1/(n*−1)} = x_0`, so `G*` is Eq 20 evaluated at the continuous `n*`, i.e. the maximum of
    Eq 20 over real `n`.
    """
    R, e = _check_R(R), _check_e_for_optimum(e)
    x0 = optimal_pair_ratio(e)
    ns = np.log(R) / np.log(x0) + 1
    return np.exp(ns * np.log1p(e) - (ns - 1) * np.log1p(x0)) - 1


def mvg_optimal_n_pb(R, e):
    """`n_max` by the Pöschel–Brilliantov route (paper Eqs 22–24, corrected): the better of
    `floor(n*)` and `ceil(n*)` (both clipped to `>= 2`) by the gain at integer `n` (Eq 20; ties go to
    the smaller `n`). Agrees with `mvg_optimal_n` because Eq 20 is unimodal in `n`."""
    R, e = np.broadcast_arrays(_check_R(R), _check_e_for_optimum(e))
    ns = continuous_optimal_n(R, e)
    lo = np.maximum(np.floor(ns), 2).astype(np.int64)
    hi = np.maximum(np.ceil(ns), 2).astype(np.int64)
    out = np.where(mvg_gain(R, e, hi) > mvg_gain(R, e, lo), hi, lo)
    return out if out.ndim else int(out)


# --------------------------------------------------------------------------------------------------
# MET: maximum energy transfer stack (Eqs 25–30)


def met_ratios(e, n: int):
    """MET pair-wise mass ratios `r_{i+1,i}`, `i = 1..n−1` (paper Eqs 25–27); shape `(..., n−1)`.

    Eq 25: `r_{i+1,i} = S_i/(1 + S_{i+1})`, `S_i = Σ_{k=1}^{i} e^k`. Derivation: in a dropped stack
    `m_i` leaves with `S_i v_ff` (`S_1 = e` off the ground) and meets `m_{i+1}` falling at `−v_ff`;
    Eq 7 with `g = −1/S_i` gives `V_i = 0`, and then `V_{i+1} = e(1 + S_i) v_ff = S_{i+1} v_ff`.
    Closed forms: `i/(i+2)` for `e = 1` (Eq 26), `(e^{i+1} − e)/(e^{i+2} − 1)` for `e < 1` (Eq 27),
    tending to `e` as `i → ∞` (Eq 28). Computed from Eq 27 (Eq 26 where `e = 1`). Assumes the same
    `e` at the ground and at every pair.
    """
    e = _check_e(e, allow_zero=False)[..., None]
    n = _one_n(n)
    i = np.arange(1, n, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        inel = (e ** (i + 1) - e) / (e ** (i + 2) - 1)
    return np.where(e == 1, i / (i + 2), inel)


def met_masses(e, n: int, m1: float = 1.0) -> np.ndarray:
    """MET masses `m_i = m_1 prod_{k<i} r_{k+1,k}` (Eq 25), shape `(..., n)`."""
    r = met_ratios(e, n)
    m1 = _check_positive(m1, "m1")
    c = np.cumprod(r, axis=-1)
    return m1[..., None] * np.concatenate([np.ones_like(c[..., :1]), c], axis=-1)


def met_mass_ratio(e, n: int):
    """`R = m_n/m_1 = prod_{i=1}^{n−1} r_{i+1,i}` of the MET stack (Eqs 14, 25)."""
    return np.prod(met_ratios(e, n), axis=-1)


def met_gain(e, n):
    """MET stack gain `G_n = Σ_{k=1}^{n} e^k` (paper Eq 29); `= n` for `e = 1`."""
    e, n = _check_e(e), _check_n(n)
    with np.errstate(invalid="ignore", divide="ignore"):
        g = e * (1 - e**n) / (1 - e)
    return np.where(e == 1, n * 1.0, g)


def met_gain_limit(e):
    """MET gain for `n → ∞`: `e/(1 − e)` (paper Eq 30); `> 1` only for `e > 1/2`. Needs `e < 1`."""
    e = _check_e_below_one(e)
    return e / (1 - e)


def met_total_mass(e, n: int, m1=1.0):
    """Total mass `M = Σ m_i` of the MET stack (Eq 25)."""
    return np.sum(met_masses(e, n, m1), axis=-1)


def met_efficiency(e, n: int):
    """Energy efficiency `K_n` of the MET stack (derived here; the paper gives no formula).

    Same definition as `mvg_efficiency`: `K_n = m_n (G_n v_ff)²/(M v_ff²) = R G_n²/(M/m_1)` with
    `G_n` from Eq 29 and `R`, `M` from Eq 25. For `e = 1` all energy reaches the top: `K_n = 1`.
    """
    return met_mass_ratio(e, n) * met_gain(e, n) ** 2 / met_total_mass(e, n)


def met_n_for_ratio(R, e, *, n_limit: int = 1_000_000):
    """Number of masses `n >= 2` of the MET stack whose `R_n = prod r` (Eq 25) is closest to `R`.

    "Closest" is measured in `|ln R_n − ln R|` (mass ratios are multiplicative; Fig 12 reads them on a
    log axis); ties go to the smaller `n`. `R_n` decreases strictly with `n`, so the search stops
    once `R_n < R`. Broadcasts over `R`, `e`.
    """
    R, e = np.broadcast_arrays(_check_R(R), _check_e(e))
    lnR = np.log(R)
    best = np.full(R.shape, 2, dtype=np.int64)
    ln_rn = np.log(met_ratios(e, 2)[..., 0])  # ln R_2
    best_d = np.abs(ln_rn - lnR)
    active = ln_rn > lnR
    n = 2
    while active.any():  # small integer search over n
        n += 1
        if n > n_limit:
            raise ParameterError("n_limit", n_limit, "the MET chain for this R is longer than n_limit")
        i = n - 1.0  # ratio r_{n,n-1} is Eq 27 with i = n - 1
        r = np.where(e == 1, i / (i + 2), (e ** (i + 1) - e) / np.where(e == 1, 1.0, e ** (i + 2) - 1))
        ln_rn = ln_rn + np.log(r)
        d = np.abs(ln_rn - lnR)
        better = active & (d < best_d)
        best = np.where(better, n, best)
        best_d = np.where(better, d, best_d)
        active = active & (ln_rn > lnR)
    return best if best.ndim else int(best)


# --------------------------------------------------------------------------------------------------
# Section 5: designs


def _ro(a) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclasses.dataclass(frozen=True)
class StackDesign:
    """A vertically-stacked amplifier design (Section 5), with restitution `e` at every impact.

    * `kind`: `"MVG"` (power-law masses, Eq 15) or `"MET"` (Eq 25).
    * `masses` `(n,)`, bottom first (units of the `m1` given, or `m_1 = 1`); `ratios` `(n−1,)`:
      `r_{i+1,i}`.
    * `gain`: `G_n = V_n/v_ff` (Eq 20 or Eq 29); `efficiency`: `K_n` = kinetic energy of the top mass
      after the cascade / kinetic energy of the whole stack at impact (`mvg_efficiency`,
      `met_efficiency`); `total_mass`: `M = Σ m_i`.
    """

    kind: Literal["MVG", "MET"]
    n: int
    masses: np.ndarray
    ratios: np.ndarray
    gain: float
    efficiency: float
    total_mass: float
    restitution: float

    @property
    def mass_ratio(self) -> float:
        """`R = m_n/m_1` of this design (Eq 14)."""
        return float(self.masses[-1] / self.masses[0])


@dataclasses.dataclass(frozen=True)
class DesignComparison:
    """Optimal MVG design against the MET design for the same `R` and `e` (Figs 13–15, 18).

    Ratios are MVG/MET: `gain_ratio` (Fig 13), `efficiency_ratio` (Fig 14), `mass_ratio` (total mass,
    Fig 15). The MVG stack uses the requested `R`; the MET stack uses its own `R_n` (Eq 25) nearest
    to it, so its top mass differs slightly from the requested one.
    """

    mvg: StackDesign
    met: StackDesign
    R: float

    @property
    def gain_ratio(self) -> float:
        return self.mvg.gain / self.met.gain

    @property
    def efficiency_ratio(self) -> float:
        return self.mvg.efficiency / self.met.efficiency

    @property
    def mass_ratio(self) -> float:
        return self.mvg.total_mass / self.met.total_mass


def mvg_design(R: float, e: float, *, n: int | None = None, m1: float = 1.0) -> StackDesign:
    """MVG stack for mass ratio `R` and restitution `e` (Eqs 15, 20): `n` masses, or the optimal
    `n_max` (`mvg_optimal_n`, needs `e < 1`) when `n` is None. `K` and `M` as in `mvg_efficiency`.

    `n` and `m1` are keyword-only, as in `met_design` (until 2026-11 `mvg_design(R, e, n, m1)` and
    `met_design(R, e, m1, n)` took them positionally in opposite orders: `met_design(0.012, 0.8, 6)`
    made a ten-mass stack with `m1 = 6`).

    **Raises:** `ParameterError` for `R` outside `(0, 1)`, `e` outside `[0, 1]` (`e < 1` without `n`),
    `n` not an integer in `[2, MAX_ARRAY_MASSES]`, `m1 <= 0`, or anything that is not one real number.
    """
    R, e = _scalar(_check_R(R), "R"), _scalar(_check_e(e), "e")
    n = mvg_optimal_n(R, e) if n is None else _one_n(n)
    masses = mvg_masses(R, n, m1)
    return StackDesign(
        kind="MVG",
        n=n,
        masses=_ro(masses),
        ratios=_ro(np.full(n - 1, mvg_ratio(R, n))),
        gain=float(mvg_gain(R, e, n)),
        efficiency=float(mvg_efficiency(R, e, n)),
        total_mass=float(masses.sum()),
        restitution=e,
    )


def met_design(R: float | None, e: float, *, n: int | None = None, m1: float = 1.0) -> StackDesign:
    """MET stack for restitution `e` (Eqs 25, 29) with the `n` whose `R_n` is closest to `R`
    (`met_n_for_ratio`), or the given `n` (then `R` may be None: the MET masses follow from `e` and `n`
    alone, and its `R_n` is the design's `mass_ratio`). `K` and `M` as in `met_efficiency`.

    `n` and `m1` are keyword-only (see `mvg_design`).

    **Raises:** `ParameterError` for `R` outside `(0, 1)` (or None without `n`), `e` outside `(0, 1]`,
    `n` not an integer in `[2, MAX_ARRAY_MASSES]`, `m1 <= 0`, or anything that is not one real number.
    """
    e = _scalar(_check_e(e, allow_zero=False), "e")
    if R is None and n is None:
        raise ParameterError("R", None, "give the mass ratio R, or the number of masses n")
    if R is not None:
        R = _scalar(_check_R(R), "R")
    n = met_n_for_ratio(R, e) if n is None else _one_n(n)
    masses = met_masses(e, n, m1)
    return StackDesign(
        kind="MET",
        n=n,
        masses=_ro(masses),
        ratios=_ro(met_ratios(e, n)),
        gain=float(met_gain(e, n)),
        efficiency=float(met_efficiency(e, n)),
        total_mass=float(masses.sum()),
        restitution=e,
    )


def design(*, e: float, R: float | None = None, m1: float | None = None, mn: float | None = None) -> DesignComparison:
    """One-call design (Section 5): optimal MVG stack and MET stack, and their comparison.

    Give either `R = m_n/m_1` (with an optional bottom mass `m1` in kg; masses are in units of `m_1`
    without it) or both `m1` and `mn` (kg), and `e` in `(0, 1)`. Example: `design(R=0.012, e=0.8)`
    gives the six-mass MVG (`G = 5.04`) and the ten-mass MET (`G = 3.57`) of Figs 16–17.
    """
    if R is None:
        if m1 is None or mn is None:
            raise ParameterError("R", None, "give R, or both m1 and mn")
        m1f, mnf = _scalar(_check_positive(m1, "m1"), "m1"), _scalar(_check_positive(mn, "mn"), "mn")
        R = mnf / m1f
        if not R < 1:
            raise ParameterError("mn", mnf, f"the top mass must be lighter than m1 = {m1f!r}")
    else:
        if mn is not None:
            raise ParameterError("mn", mn, "give R or the top mass mn, not both")
        m1f = 1.0 if m1 is None else _scalar(_check_positive(m1, "m1"), "m1")
    R = _scalar(_check_R(R), "R")
    e = _scalar(_arr(e, "e"), "e")
    if not 0 < e < 1:  # one message for both designs (MET's ratios vanish at e = 0, MVG has no optimum at 1)
        raise ParameterError("e", e, "coefficient of restitution must lie in (0, 1): the MET ratios of Eq 27 "
                             "vanish at e = 0, and for e = 1 the MVG gain of Eq 20 grows with n without bound")
    return DesignComparison(mvg=mvg_design(R, e, m1=m1f), met=met_design(R, e, m1=m1f), R=R)


@dataclasses.dataclass(frozen=True)
class DesignRatios:
    """Vectorised MVG/MET comparison (Figs 13–15): arrays broadcast over `R` and `e`.

    `R` is the mass ratio the MVG stack was designed for (the requested `R`, or the MET's own `R_n`
    when `at_met_ratio=True`, as in the paper's figures).
    """

    R: np.ndarray
    n_mvg: np.ndarray
    n_met: np.ndarray
    gain: np.ndarray
    efficiency: np.ndarray
    total_mass: np.ndarray


def design_ratios(R, e, *, at_met_ratio: bool = False) -> DesignRatios:
    """MVG/MET ratios of gain, efficiency and total mass over arrays of `R` and `e` (Figs 13–15, 18).

    For each `(R, e)`: MET with `n_met = met_n_for_ratio(R, e)`; MVG optimal (`mvg_optimal_n`) for the
    requested `R`, or for the MET's `R_{n_met}` if `at_met_ratio` (Section 5: "the plotted values of R
    are dictated by the MET system"). `e < 1`.
    """
    R, e = np.broadcast_arrays(_check_R(R), _check_e_below_one(e))
    n_met = np.asarray(met_n_for_ratio(R, e))
    # MET quantities: loop over the distinct n (few), vectorised over e
    r_met = np.empty(R.shape)
    g_met = np.empty(R.shape)
    k_met = np.empty(R.shape)
    m_met = np.empty(R.shape)
    for n in np.unique(n_met):
        sel = n_met == n
        es = e[sel]
        r_met[sel] = met_mass_ratio(es, int(n))
        g_met[sel] = met_gain(es, int(n))
        k_met[sel] = met_efficiency(es, int(n))
        m_met[sel] = met_total_mass(es, int(n))
    Rm = r_met if at_met_ratio else R
    n_mvg = np.asarray(mvg_optimal_n(Rm, e))
    return DesignRatios(
        R=Rm,
        n_mvg=n_mvg,
        n_met=n_met,
        gain=mvg_gain(Rm, e, n_mvg) / g_met,
        efficiency=mvg_efficiency(Rm, e, n_mvg) / k_met,
        total_mass=mvg_total_mass(Rm, n_mvg) / m_met,
    )


#: Names renamed in this round (CHANGELOG.md): an old name fails with the new one in its message.
_RENAMED = {"pb_x0": "optimal_pair_ratio", "pb_n_star": "continuous_optimal_n", "pb_gain_star": "continuous_optimal_gain"}


def __getattr__(name: str):
    if name in _RENAMED:
        raise AttributeError(f"hertz_chain.rigid.{name} is renamed {_RENAMED[name]} (CHANGELOG.md)")
    raise AttributeError(f"module 'hertz_chain.rigid' has no attribute {name!r}")
