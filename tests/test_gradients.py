"""Gradients of the launch velocity: finite differences, the replayed reverse mode against diffrax's adjoint."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from _helpers import G

from hertz_chain.contact import HuntCrossley
from hertz_chain.simulation import Tolerances, launch_velocity
from hertz_chain.stack import Stack, at_impact

# the elastic and damped laws' derivatives are the solve's: nothing may warn that they are approximate
pytestmark = pytest.mark.filterwarnings("error::hertz_chain.errors.GradientAccuracyWarning")


def _hc_top(theta, tol, adjoint="forward", solver="tsit5"):
    # top launch velocity of a 3-mass Hunt–Crossley stack with gravity and gaps, as a function of
    # theta = (masses, gaps, stiffness k / 1e8, damping alpha)
    m, gaps, k, alpha = theta[0:3], theta[3:5], theta[5:8] * 1e8, theta[8:11]
    stack = Stack(m, HuntCrossley(k, alpha), gravity=G)
    return launch_velocity(stack, at_impact(stack, 1.0, gaps), adjoint=adjoint, solver=solver,
                           tolerances=Tolerances(tol, tol, resolve_onsets=True))[-1]


THETA = jnp.asarray([1.0, 0.5, 0.25, 2e-3, 1e-3, 2.0, 1.5, 1.0, 0.1, 0.15, 0.2])


def _central_differences(theta):
    """The reference: central differences at rtol = atol = 1e-12 (step 1e-4 relative), and the natural
    scale of each component (|dv/dln(theta)| scale) to measure errors in."""
    fd = np.empty(theta.size)
    for i in range(theta.size):
        h = 1e-4 * float(theta[i])
        step = jnp.zeros_like(theta).at[i].set(h)
        fd[i] = (_hc_top(theta + step, 1e-12) - _hc_top(theta - step, 1e-12)) / (2 * h)
    th = np.asarray(theta)
    return fd, np.maximum(np.abs(fd), 1e-2 * np.max(np.abs(fd * th)) / np.abs(th))


def test_gradient_matches_finite_differences():
    # Reference: central finite differences of the same model at rtol = atol = 1e-12 (step 1e-4 relative):
    # d(top launch velocity)/d(masses, gaps, stiffness k, damping alpha), Hunt–Crossley, with gravity;
    # forward mode (jacfwd) and reverse mode (jax.grad, the replayed discrete adjoint) alike.
    forward = np.asarray(jax.jacfwd(lambda th: _hc_top(th, 1e-11))(THETA))
    reverse = np.asarray(jax.grad(lambda th: _hc_top(th, 1e-11, "reverse"))(THETA))
    fd, scale = _central_differences(THETA)  # relative error per parameter, in its natural unit
    # the discrete derivative is accurate to the solve's tolerance, not better: at 1e-11 the two modes
    # (different step sequences) are within 2e-4 (measured 2e-5 forward, 1.6e-4 reverse, for a gap), and
    # they converge with the tolerance: at 1e-12 both are within 1e-5 of the differences
    assert np.max(np.abs(forward - fd) / scale) <= 2e-4
    assert np.max(np.abs(reverse - fd) / scale) <= 2e-4
    reverse_12 = np.asarray(jax.grad(lambda th: _hc_top(th, 1e-12, "reverse"))(THETA))
    assert np.max(np.abs(reverse_12 - fd) / scale) <= 1e-5


def test_reverse_gradient_batched_matches_finite_differences_per_design():
    # Reference: central finite differences of each design at rtol = atol = 1e-12 (step 1e-4 relative), as
    # in the test above. Under vmap every design is replayed on its own accepted steps (vmap must not mix
    # the designs' step sequences), so each batched gradient is within the same 2e-4 (natural scale) at
    # 1e-11. (Before onsets were split out of the replayed steps, this compared the replay with diffrax's
    # RecursiveCheckpointAdjoint, then the same discrete derivative; the replay is now a better one.)
    thetas = jnp.stack([THETA, THETA * jnp.asarray([1.0, 0.8, 0.5] + [1.0] * 8)])
    replay = np.asarray(jax.vmap(jax.grad(lambda th: _hc_top(th, 1e-11, "reverse")))(thetas))
    assert np.max(np.abs(replay[0] - replay[1])) > 1e-3  # two different designs
    for theta, got in zip(thetas, replay):
        fd, scale = _central_differences(theta)
        assert np.max(np.abs(got - fd) / scale) <= 2e-4


def _tsuji_top(m, adjoint):
    # top launch velocity of a gapped 3-mass Tsuji stack under gravity (the defaults), as a function of the masses
    import hertz_chain as hc

    law = hc.make_law("tsuji", stiffness=1e9, restitution=0.8, effective_mass=0.4)
    stack = Stack(m, law)
    return launch_velocity(stack, at_impact(stack, 1.0, [2e-3, 5e-4]), adjoint=adjoint)[-1]


def test_forward_mode_of_the_reverse_mode_is_refused_in_one_line():
    """`jax.jacfwd` of `launch_velocity`'s default mode (the replayed reverse mode, a custom_vjp) names the
    option to use, `adjoint="forward"` (JAX's own words were a bare TypeError about custom_vjp), plain and
    under `jax.jit`. (Forward mode itself: tests/test_optimize.py, against central differences and the
    reverse mode for every damped law.)"""
    from hertz_chain.errors import ParameterError

    m = jnp.asarray([1.0, 0.5, 0.25])
    for transform in (jax.jacfwd, lambda f: jax.jit(jax.jacfwd(f))):
        with pytest.raises(ParameterError, match=r"^adjoint = 'reverse' is invalid: adjoint='forward' for "
                                                 r"forward-mode derivatives \(jax.jacfwd, jax.jvp\)"):
            transform(lambda x: _tsuji_top(x, "reverse"))(m)
