"""Physical constants shared by every module (SI units; no heavy imports, so the CLI stays fast)."""

__all__ = ["STANDARD_GRAVITY", "G0"]

STANDARD_GRAVITY = 9.80665
"""Standard acceleration of gravity, m/s² (3rd CGPM 1901; ISO 80000-3). The default `drop.gravity`."""

G0 = STANDARD_GRAVITY
"""The unit 'g' of acceleration pulses: `a [g] = a [m/s²] / G0`."""
