"""The units of a solve (`Scales`: time, length, velocity, energy) and the default time limit, from
the physics of the stack (`hertz_chain.simulation` module docstring, "Scaling")."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

from . import _config  # noqa: F401  (float64)
from .stack import Stack, State, invert_monotone

HERTZ_TIME = 2.94328  # t_c = 2.94328 delta_max / v (Hertz; docs/references.md, "Hertz single impact")


# ==================================================================== scales
class Scales(eqx.Module):
    """The units of the scaled state: time `T` (s), length `L` (m), velocity `V` (m/s), energy `E` (J)."""

    time: Array
    length: Array
    velocity: Array
    energy: Array

    def vector(self, n: int, memory: bool = False) -> Array:
        """The scale of every entry of the flat state `[x, v, D (, q)]` (`Stack.state_size`)."""
        parts = [jnp.full(n, self.length), jnp.full(n, self.velocity), jnp.full(n, self.energy)]
        return jnp.concatenate(parts + [jnp.full(n, self.length)] if memory else parts)


def _speed(stack: Stack, state: State) -> Array:
    """The velocity scale `V`: the largest initial speed or relative speed; for a stack released at
    rest, the speed of a fall through its whole height under gravity; 1 m/s if nothing would move."""
    x, v = state.positions, state.velocities
    mask = stack.interface_mask()
    rel = jnp.where(mask, jnp.abs(stack.overlap_rates(v)), 0.0)
    vel = jnp.maximum(jnp.max(jnp.abs(v)), jnp.max(rel))
    height = jnp.max(x) - jnp.minimum(jnp.min(x), 0.0)
    fall = jnp.sqrt(2.0 * stack.gravity * height)
    return jnp.where(vel > 0, vel, jnp.where(fall > 0, fall, 1.0))


def _peak_overlaps(stack: Stack, vel) -> Array:
    """`(n,)` peak overlap of every interface hit at `vel` (the root of `potential(delta) = m* vel^2/2`,
    Hertz: `(5 m* vel^2/(4k))^{2/5}`); inf where there is no interface."""
    mask = stack.interface_mask()
    target = 0.5 * stack.effective_masses() * vel**2
    fn = lambda d: jnp.where(mask, stack.potentials(d), d)  # noqa: E731
    return jnp.where(mask, invert_monotone(fn, jnp.where(mask, target, 1.0)), jnp.inf)


def _scales(stack: Stack, state: State) -> Scales:
    """Contact time and peak overlap of the stiffest contact at the drop speed (module docstring)."""
    stack, state = jax.lax.stop_gradient((stack, state))
    vel = _speed(stack, state)
    length = jnp.min(_peak_overlaps(stack, vel))
    return Scales(
        time=HERTZ_TIME * length / vel,
        length=length,
        velocity=vel,
        energy=0.5 * jnp.sum(stack.masses) * vel**2,
    )


def _default_t_max(stack: Stack, state: State, sc: Scales) -> Array:
    """A time limit (s) that covers the first cascade, from the physics (issue 16):

    `t_fall + 4 sum_j t_gap,j + 200 sum_j t_c,j + 4 V/g`, where `t_fall` is when mass 1 reaches the
    ground in free flight (0 without the ground or when it never does), `t_gap,j = min(s_j/V,
    sqrt(2 s_j/g))` the time to close gap `s_j` at the drop speed `V` or by falling from rest,
    `t_c,j = 2.94328 delta_max,j / V` the Hertz contact time estimate of interface `j` (its own
    effective mass; Johnson 1985, §11.1), and `4 V/g` two times of flight of a mass thrown up at `V`
    (mass 1's bounces on the ground during the cascade). The solve stops at the cascade's end, so a
    generous limit costs nothing when the cascade ends. The gaps count four times: after the first
    collisions gaps close slower than `V` (a review: three masses halving, 1 cm gaps, no gravity, stiff
    contacts: the last collision at 0.0425 s, the limit with twice the gaps 0.0414 s)."""
    stack, state = jax.lax.stop_gradient((stack, state))
    g, V = stack.gravity, sc.velocity
    x, v = state.positions, state.velocities
    x1, v1 = jnp.maximum(x[0], 0.0), v[0]
    g_safe = jnp.where(g > 0, g, 1.0)
    fall_g = (v1 + jnp.sqrt(v1**2 + 2.0 * g * x1)) / g_safe
    fall_0 = jnp.where(v1 < 0, x1 / jnp.where(v1 < 0, -v1, 1.0), 0.0)
    t_fall = jnp.where(stack.ground, jnp.where(g > 0, fall_g, fall_0), 0.0)
    gaps = jnp.maximum(jnp.diff(x), 0.0)
    t_gap = jnp.minimum(gaps / V, jnp.where(g > 0, jnp.sqrt(2.0 * gaps / g_safe), jnp.inf))
    t_c = jnp.where(stack.interface_mask(), HERTZ_TIME * _peak_overlaps(stack, V) / V, 0.0)
    flight = jnp.where(g > 0, 4.0 * V / g_safe, 0.0)
    return t_fall + 4.0 * jnp.sum(t_gap) + 200.0 * jnp.sum(t_c) + flight


def inverse_force_scale(stack: Stack, scale: Array) -> Array:
    """`(n,)` per interface `1 / F_s`, the onset proxy's force scale `F_s = m*_j V^2 / L` (`scale`: the state's
    scale vector, `Scales.vector`)."""
    return scale[0] / (stack.effective_masses() * scale[stack.n] ** 2)


class FieldArgs(eqx.Module):
    """What the scaled vector field (`_solve._scaled_field`) and the contact tracking (`_tracking`) read
    besides the state: the system, the state's scale vector (`Scales.vector`), the time scale `T` (s), and
    the scaled initial velocities `v0s` (a contact has happened once a velocity departs from free flight;
    None where no tracking runs, as in the replayed adjoint's steps), and `inv_force`, per interface the
    inverse of the onset proxy's force scale `F_s = m*_j V^2 / L` (computed once per solve; None: on the
    fly).

    `rate` (`T / scale`, per entry of the physical state), `inv_masses` (`1 / m_i`) and `inv_root_length`
    (`1 / sqrt(L)`) are the field's divisors as factors, computed once per solve (`FieldArgs.of`) rather
    than at every stage: a division costs several multiplications (measured on 128 five-mass designs,
    six stages: 109 -> 92 us Tsuji, 75 -> 58 us Hertz); None: divided on the fly, as before."""

    stack: Stack
    scale: Array
    T: Array
    v0s: Array | None = None
    inv_force: Array | None = None
    rate: Array | None = None
    inv_masses: Array | None = None
    inv_root_length: Array | None = None

    @classmethod
    def of(cls, stack: Stack, scale: Array, T: Array, v0s: Array | None = None) -> "FieldArgs":
        """The arguments of a tracked solve, with every per-solve constant of the field computed once."""
        return cls(stack, scale, T, v0s, inverse_force_scale(stack, scale), T / scale, 1.0 / stack.masses,
                   1.0 / jnp.sqrt(scale[0]))
