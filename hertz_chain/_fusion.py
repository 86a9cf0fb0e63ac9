"""Fusion boundaries for XLA on a CPU: `materialised`, which makes a vmapped solve compute its contact
forces once per stage.

XLA fuses the whole scaled vector field of a stage (`_solve._scaled_field`) into one loop over the
elements of its output, the concatenation `[dx, dv, dD, z, over]`. The elemental emitter generates every
fused producer anew for each output element that reads it, so an interface's force (its square roots, its
damping) is evaluated once for each of the four entries that use it (the accelerations of the two masses
it pushes, its dissipated power, its onset proxy), in the scalar loop a concatenation along the state's
entries compiles to. `jax.lax.optimization_barrier` does not separate them (XLA's CPU pipeline removes the
barriers before fusing). A dot is never fused on a CPU (an Eigen call), so a product with the identity
makes the forces one vectorised kernel of their own, read four times.

Measured on 1,024 five-mass gapped Tsuji designs (`simulate_batch(save_steps=False)`, rtol 1e-9,
alternating processes, this 2-core machine): 0.375-0.417 -> 0.313-0.361 ms per design; the sweep benchmark's
family (8,100 designs with gravity, gaps 1 um-1 cm, stiffness 1e8-1e10): 1,151-1,266 -> 1,439-1,558 designs/s.
A single solve (unbatched) is left as it is: its forces are scalars in a loop of tiny kernels, where one more
kernel per stage would cost more than the repeated arithmetic.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


@jax.custom_batching.custom_vmap
def _identity(f, g):
    return f, g


@_identity.def_vmap
def _identity_vmap(axis_size, in_batched, f, g):
    f = f if in_batched[0] else jnp.broadcast_to(f, (axis_size,) + f.shape)
    g = g if in_batched[1] else jnp.broadcast_to(g, (axis_size,) + g.shape)
    n = f.shape[-1]
    # the identity as a dot, exact for finite numbers (x * 1 + 0 + ... + 0; a non-finite force, which fails
    # the solve anyway, turns its own design's row into NaN)
    both = jnp.dot(jnp.concatenate([f, g], axis=-1), jnp.eye(2 * n, dtype=f.dtype),
                   precision=jax.lax.Precision.HIGHEST)
    return (both[..., :n], both[..., n:]), (True, True)


@jax.custom_jvp
def materialised(f, g):
    """`(f, g)` unchanged: two arrays of the same shape `(..., n)`. Under `jax.vmap`, computed by a kernel of
    their own (a dot with the identity, which XLA does not fuse) and then read by their consumers, instead
    of being recomputed inside each consumer's fused loop (module docstring). Derivatives pass through."""
    return _identity(f, g)


@materialised.defjvp
def _materialised_jvp(primals, tangents):
    return materialised(*primals), tangents
