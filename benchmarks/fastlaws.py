"""Ablation only (not used for the headline numbers): the library's Hertz and Tsuji laws with the
fractional powers written as square roots, `d^1.5 = d sqrt(d)`, `d^2.5 = d^2 sqrt(d)`,
`d^0.25 = sqrt(sqrt(d))`. Same equations (to rounding); XLA lowers `x ** 1.5` to a general `pow`
(exp/log), several times slower than `sqrt`, and the vector field evaluates these powers for every
interface at every stage. Used to measure what that change in `hertz_chain/contact.py` would buy.
"""

from __future__ import annotations

import jax.numpy as jnp

import hertz_chain as hc
from hertz_chain.contact import _positive_part


class SqrtHertz(hc.Hertz):
    def elastic_force(self, delta):
        mask, d = _positive_part(delta)
        return jnp.where(mask, self.k * d * jnp.sqrt(d), 0.0)

    def potential(self, delta):
        mask, d = _positive_part(delta)
        return jnp.where(mask, 0.4 * self.k * d * d * jnp.sqrt(d), 0.0)


class SqrtTsuji(hc.Tsuji):
    def elastic_force(self, delta):
        mask, d = _positive_part(delta)
        return jnp.where(mask, self.k * d * jnp.sqrt(d), 0.0)

    def potential(self, delta):
        mask, d = _positive_part(delta)
        return jnp.where(mask, 0.4 * self.k * d * d * jnp.sqrt(d), 0.0)

    def damping_force(self, delta, delta_dot):
        mask, d = _positive_part(delta)
        c = self.eta * jnp.sqrt(self.m_eff * self.k)
        return jnp.where(mask, c * jnp.sqrt(jnp.sqrt(d)) * delta_dot, 0.0)


def sqrt_version(stack):
    """The same stack with every Hertz/Tsuji law replaced by its square-root twin (same parameters)."""
    laws = []
    for j in stack.interfaces:
        law = stack.law_of(j)
        if isinstance(law, hc.Tsuji):
            laws.append(SqrtTsuji(law.k, law.eta, law.m_eff, law.clamp))
        elif isinstance(law, hc.Hertz):
            laws.append(SqrtHertz(law.k, law.clamp))
        else:
            raise TypeError(type(law))
    return hc.Stack(stack.masses, laws, gravity=stack.gravity, ground=stack.ground)
