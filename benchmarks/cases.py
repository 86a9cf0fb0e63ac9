"""Benchmark cases: stack sizes, regimes and the designs they build (public `hertz_chain` API only).

Every case is a dropped MVG stack (paper Eq 15) with the normative example's numbers
(`examples/issue5_normative.toml`): bottom mass `m_1 = 8.4 kg`, mass ratio `R = m_n/m_1 = 0.012` for
every `n` (so the pair ratio `R^{1/(n-1)}` is 0.012, 0.33, 0.61 and 0.79 for n = 2, 5, 10, 20), impact
speed 1 m/s, no gravity (so the launch velocity of the top mass is its final velocity, and the scipy
runs need no event location), mass–mass stiffness `k = 1e9 N/m^1.5`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

import hertz_chain as hc

M1 = 8.4  # kg, bottom mass (normative example)
R_TOTAL = 0.012  # m_n / m_1 (normative example, paper's optimal six-mass design)
V_IMPACT = 1.0  # m/s
K_STEEL = 1e9  # N/m^1.5, every mass–mass contact
GAP = 1e-4  # m, "gapped" regimes (peak overlaps are 0.03–0.6 mm: contacts partly overlap in time)

SIZES = (2, 5, 10, 20)


@dataclasses.dataclass(frozen=True)
class Regime:
    name: str
    law: str  # "hertz" or "tsuji"
    restitution: float
    gap: float  # m
    ground_stiffness: float  # N/m^1.5
    description: str


REGIMES = {
    r.name: r
    for r in (
        Regime("gapped-hertz", "hertz", 1.0, GAP, K_STEEL, "elastic Hertz (e = 1), gaps 0.1 mm"),
        Regime("gapped-tsuji", "tsuji", 0.8, GAP, K_STEEL, "Tsuji, e = 0.8, gaps 0.1 mm"),
        Regime("touching", "tsuji", 0.8, 0.0, K_STEEL, "Tsuji, e = 0.8, touching (zero gaps)"),
        Regime("damped-e0.3", "tsuji", 0.3, GAP, K_STEEL, "Tsuji, heavy damping e = 0.3, gaps 0.1 mm"),
        Regime("soft-pad", "tsuji", 0.8, GAP, K_STEEL * 1e-3,
               "Tsuji, e = 0.8, gaps 0.1 mm, ground pad k = 1e6 (1e3 x softer than mass-mass)"),
    )
}


def masses(n: int, ratio: float = R_TOTAL) -> np.ndarray:
    return hc.mvg_masses(ratio, n, M1)


def effective_masses(m: np.ndarray) -> np.ndarray:
    return np.concatenate([m[:1], m[:-1] * m[1:] / (m[:-1] + m[1:])])


def laws(regime: Regime, m: np.ndarray) -> list:
    """One law per interface (interface 0 = ground–mass 1); Tsuji laws use each interface's m_eff."""
    meff = effective_masses(m)
    out = []
    for j in range(len(m)):
        k = regime.ground_stiffness if j == 0 else K_STEEL
        if regime.law == "hertz":
            out.append(hc.make_law("hertz", stiffness=k))
        else:
            out.append(hc.make_law("tsuji", stiffness=k, restitution=regime.restitution, effective_mass=meff[j]))
    return out


def build(n: int, regime: Regime | str, ratio: float = R_TOTAL, gap: float | None = None, gravity: float = 0.0):
    """`(stack, state)` of one case: at impact with the regime's gaps, g = 0 unless `gravity` (m/s^2)."""
    regime = REGIMES[regime] if isinstance(regime, str) else regime
    m = masses(n, ratio)
    stack = hc.Stack(m, laws(regime, m), gravity=gravity)
    return stack, hc.at_impact(stack, V_IMPACT, regime.gap if gap is None else gap)


def rigid_check_case(law: str, n: int = 2):
    """A case where the rigid theory (paper Eq 19) is exact up to the contact-law calibration: gaps of
    1 cm, so each contact ends long before the next starts, g = 0, restitution velocity-independent
    (Hertz: e = 1; Tsuji: e = 0.8 calibrated to ~1e-11). Returns `(stack, state, eq19_launch_velocity)`."""
    regime = Regime("rigid", law, 1.0 if law == "hertz" else 0.8, 1e-2, K_STEEL, "")
    stack, state = build(n, regime)
    gain = float(hc.stack_gain(np.asarray(stack.masses), regime.restitution))
    return stack, state, gain * V_IMPACT
