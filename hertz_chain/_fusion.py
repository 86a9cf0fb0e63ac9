"""Fusion boundaries for XLA on a CPU: `materialised`, which makes a vmapped solve compute its contact
forces once per stage.

XLA fuses the whole scaled vector field of a stage (`_solve._scaled_field`) into one loop over the
elements of its output, the concatenation `[dx, dv, dD, z, over]`. The elemental emitter generates every
fused producer anew for each output element that reads it, so an interface's force (its square roots, its
damping) is evaluated once for each of the four entries that use it (the accelerations of the two masses
it pushes, its dissipated power, its onset proxy), in the scalar loop a concatenation along the state's
entries compiles to. `jax.lax.optimization_barrier` does not separate them (XLA's CPU pipeline removes the
barriers before fusing). A dot is never fused on a CPU (an Eigen call), so a product with the identity
makes the forces one vectorised kernel of their own, read four times. The contact tracking after every
step (`_tracking._Contacts.update`) reads the forces in every column of its per-interface records, and
gets the same, and so do the stage times and weights of a step in an onset window (`_solver.UnrolledERK`:
seven of each, which XLA recomputed for each of the 21 entries of every stage's state).

Measured on 1,024 five-mass gapped Tsuji designs (`simulate_batch(save_steps=False)`, rtol 1e-9,
alternating processes, this 2-core machine): 0.375-0.417 -> 0.313-0.361 ms per design; the sweep benchmark's
family (8,100 designs with gravity, gaps 1 um-1 cm, stiffness 1e8-1e10): 1,151-1,266 -> 1,439-1,558 designs/s
for the field, and 1,356-1,468 -> 1,461-1,611 for the tracking's forces.
A single solve (unbatched) is left as it is: its forces are scalars in a loop of tiny kernels, where one more
kernel per stage would cost more than the repeated arithmetic. Long chains are left to XLA too (`MAX_WIDTH`:
a dot with the identity costs O(n^2) per row), and laws with memory (Thornton, Jackson-Green) keep their
field as it was (their tracking is materialised).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


@jax.custom_batching.custom_vmap
def _identity(*arrays):
    return arrays


#: the widest row (all arrays together) that `materialised` passes through a dot: the identity's dot costs
#: O(width^2) per row, so long chains (and arrays it was not made for) keep XLA's fusion
MAX_WIDTH = 64


@_identity.def_vmap
def _identity_vmap(axis_size, in_batched, *arrays):
    arrays = [a if b else jnp.broadcast_to(a, (axis_size,) + a.shape) for a, b in zip(arrays, in_batched)]
    n = arrays[0].shape[-1]
    if (jax.default_backend() != "cpu" or n * len(arrays) > MAX_WIDTH
            or any(a.shape != arrays[0].shape or a.dtype != arrays[0].dtype for a in arrays)
            or not jnp.issubdtype(arrays[0].dtype, jnp.floating)):
        return tuple(arrays), (True,) * len(arrays)  # measured on a CPU only; see MAX_WIDTH
    # the identity as a dot, exact for finite numbers (x * 1 + 0 + ... + 0; a non-finite force, which fails
    # the solve anyway, turns its own design's row into NaN)
    both = jnp.dot(jnp.concatenate(arrays, axis=-1), jnp.eye(n * len(arrays), dtype=arrays[0].dtype),
                   precision=jax.lax.Precision.HIGHEST)
    return tuple(both[..., i * n : (i + 1) * n] for i in range(len(arrays))), (True,) * len(arrays)


@jax.custom_jvp
def materialised(*arrays):
    """`arrays` unchanged (a tuple): float arrays of the same shape `(..., n)`. Under `jax.vmap` on a CPU,
    computed by a kernel of their own (a dot with the identity, which XLA does not fuse) and then read by
    their consumers, instead of being recomputed inside each consumer's fused loop (module docstring); only
    for rows of at most `MAX_WIDTH` numbers (all arrays together) of one float dtype, otherwise (and on
    other backends, where it was not measured) passed through as they are. Derivatives pass through."""
    return _identity(*arrays)


@materialised.defjvp
def _materialised_jvp(primals, tangents):
    return materialised(*primals), tangents
