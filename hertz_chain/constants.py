"""Physical constants shared by every module (SI units; no heavy imports, so the CLI stays fast)."""

__all__ = ["STANDARD_GRAVITY", "G0", "MAX_MASSES", "INDEPENDENT_BELOW", "UNTIL", "POWER_EXPONENTS"]

STANDARD_GRAVITY = 9.80665
"""Standard acceleration of gravity, m/s² (3rd CGPM 1901; ISO 80000-3). The default `drop.gravity`."""

G0 = STANDARD_GRAVITY
"""The unit 'g' of acceleration pulses: `a [g] = a [m/s²] / G0`."""

MAX_MASSES = 1000
"""The most masses a stack may have (`Stack`, stack files, `hertz-chain design`): long granular chains
(Nesterenko; Sen; Daraio use 100-1,000 beads). Every per-step operation is linear in n (no n x n work). Defined here, free of
JAX, so that the stack-file checks and the command line refuse a larger stack before importing it."""

INDEPENDENT_BELOW = 0.01
"""Largest overlap fraction of neighbouring contacts still called "independent" (1 %): the regime of a
report (`analysis`) and of a sweep's designs (`sweep`)."""

UNTIL = ("cascade", "t_max", "launch")
"""What a run's `until` (`simulate(..., until=...)`, `solver.until`) accepts: stop at the end of the first
cascade, go on to `t_max` and report rebounds, or stop as soon as the top mass's launch is final."""

POWER_EXPONENTS = (1.0, 5.0)
"""The exponents p the power law `F = k delta^p (1 + alpha delta_dot)` takes (`make_law`, stack files):
from linear (p = 1) to p = 5, past every contact the literature fits (Hertz 1.5, conical 2, cylinders ~1)."""
