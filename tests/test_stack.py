"""The Stack system: structure, initial states, vector field (no ODE solve here)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from hertz_chain.contact import Hertz, KelvinVoigt, Tsuji
from hertz_chain.errors import ParameterError
from hertz_chain.stack import (
    STANDARD_GRAVITY,
    Stack,
    State,
    at_impact,
    dropped,
    invert_monotone,
    resting,
    stack_designs,
)

G = STANDARD_GRAVITY


def _mixed_stack(gravity=G):
    m = np.array([2.0, 1.0, 0.4, 0.1])
    laws = [Hertz(3e9), Tsuji(2e9, 0.2, 0.6), KelvinVoigt(5e7, 30.0), Hertz(1e9)]
    return Stack(m, laws, gravity=gravity)


def test_resting_stack_is_in_static_equilibrium():
    # Reference: Newton's first law: a resting stack has zero net force on every mass.
    stack = _mixed_stack()
    state = resting(stack)
    a = stack.vector_field(0.0, state.flat())[4:8]
    assert np.all(np.asarray(state.velocities) == 0)
    np.testing.assert_allclose(np.asarray(a), 0.0, atol=1e-12 * G)


def test_resting_preload_is_hertz_closed_form():
    # Reference: Hertz, F = k delta^{3/2} carrying the weight above: delta_j = (W_j/k)^{2/3}.
    m = np.array([1.0, 0.5, 0.25])
    k = 1e9
    stack = Stack(m, Hertz(k), gravity=G)
    x = np.asarray(resting(stack).positions)
    weights = G * np.array([m.sum(), m[1:].sum(), m[2:].sum()])
    delta = (weights / k) ** (2 / 3)
    np.testing.assert_allclose(x, -np.cumsum(delta), rtol=1e-13)


def test_resting_dropped_keeps_preload_and_touches_ground():
    # Reference: definition (c): mass 1 at x = 0, v = -sqrt(2 g h), overlaps = static preload.
    stack = _mixed_stack()
    h = 0.05
    s0, s1 = resting(stack), resting(stack, height=h)
    assert float(s1.positions[0]) == 0.0
    np.testing.assert_allclose(np.diff(np.asarray(s1.positions)), np.diff(np.asarray(s0.positions)), rtol=1e-14)
    np.testing.assert_allclose(np.asarray(s1.velocities), -np.sqrt(2 * G * h), rtol=1e-15)


def test_at_impact_and_dropped():
    # Reference: free fall v_ff = sqrt(2 g h) (paper Section 4); positions = cumulative gaps.
    stack = Stack([1.0, 0.5, 0.2], Hertz(1e9), gravity=G)
    gaps = [1e-3, 2e-3]
    s = at_impact(stack, 2.0, gaps)
    np.testing.assert_allclose(np.asarray(s.positions), [0.0, 1e-3, 3e-3], rtol=0, atol=1e-18)
    np.testing.assert_allclose(np.asarray(s.velocities), -2.0)
    d = dropped(stack, 0.3, gaps)
    np.testing.assert_allclose(np.asarray(d.velocities), -np.sqrt(2 * G * 0.3), rtol=1e-15)


def test_vector_field_conserves_energy_and_momentum():
    # Reference: dE/dt = grad(E) . f = 0 for the exact flow (energy audit with dissipation as a state),
    # and sum(m a) = -g sum(m) without the ground (internal forces cancel: Newton's third law).
    stack = _mixed_stack()
    rng = np.random.default_rng(1)
    x = np.array([-1e-5, -2e-5, -2.5e-5, -2.6e-5])  # every contact compressed
    v = rng.normal(size=4)
    y = jnp.asarray(np.concatenate([x, v, np.zeros(4)]))
    f = stack.vector_field(0.0, y)
    _, de = jax.jvp(stack.total_energy, (y,), (f,))
    scale = float(jnp.sum(jnp.abs(stack.masses * v * f[4:8])))
    assert abs(float(de)) <= 1e-12 * scale
    assert np.all(np.asarray(f[8:]) >= 0)  # dissipated power >= 0 on every interface

    chain = Stack([1.0, 0.7, 0.3], [Tsuji(1e9, 0.3, 0.4), Hertz(2e9)], gravity=G, ground=False)
    y = jnp.asarray([0.0, -1e-5, -1.5e-5, 1.0, -0.2, 0.4, 0, 0, 0])
    a = chain.vector_field(0.0, y)[3:6]
    assert abs(float(jnp.sum(chain.masses * a)) + G * 2.0) <= 1e-12 * 1e4


def test_total_energy_closed_form_single_and_batched():
    # Reference: E = sum(m v^2 / 2) + g sum(m x) + sum(2/5 k delta^{5/2}) (Hertz potential) + sum(D),
    # computed here with numpy; a batch of two designs with different gravity gives each its own E.
    m = np.array([1.0, 0.5, 0.2])
    x = np.array([-1e-5, -2e-5, 1e-3])  # ground and first contact compressed, top one open
    v = np.array([0.3, -0.4, 2.0])
    diss = np.array([1e-3, 2e-4, 0.0])
    y = np.concatenate([x, v, diss])

    def expected(k, g):
        delta = np.maximum(np.array([-x[0], x[0] - x[1], x[1] - x[2]]), 0.0)
        return (0.5 * np.sum(m * v**2) + g * np.sum(m * x) + np.sum(0.4 * k * delta**2.5)
                + np.sum(diss))

    designs = [(1e9, G), (3e9, 1.62)]
    stacks = [Stack(m, Hertz(k), gravity=g) for k, g in designs]
    for stack, (k, g) in zip(stacks, designs):
        np.testing.assert_allclose(float(stack.total_energy(jnp.asarray(y))), expected(k, g), rtol=1e-14)
        e = stack.energies(jnp.asarray(y))
        np.testing.assert_allclose(float(sum(e.values())), expected(k, g), rtol=1e-14)
    batch = stack_designs(stacks)
    got = batch.total_energy(jnp.asarray(np.stack([y, y])))
    np.testing.assert_allclose(np.asarray(got), [expected(k, g) for k, g in designs], rtol=1e-14)


def test_mixed_laws_are_grouped_and_match_individual_laws():
    # Reference: each interface's force equals its own law evaluated alone.
    stack = _mixed_stack()
    assert len(stack.laws) == 3  # Hertz, Tsuji, KelvinVoigt
    d = jnp.asarray([1e-5, 2e-5, 3e-6, 4e-6])
    dd = jnp.asarray([0.1, -0.2, 0.3, 0.4])
    laws = [Hertz(3e9), Tsuji(2e9, 0.2, 0.6), KelvinVoigt(5e7, 30.0), Hertz(1e9)]
    expect = [float(law.force(d[j], dd[j])) for j, law in enumerate(laws)]
    np.testing.assert_allclose(np.asarray(stack.forces(d, dd)), expect, rtol=1e-15)
    assert float(stack.law_of(1).eta) == 0.2


def test_invert_monotone_power_law():
    # Reference: closed-form inverse of k d^p.
    t = jnp.asarray([1e-3, 1.0, 1e6])
    d = invert_monotone(lambda d: 7e9 * d**1.5, t)
    np.testing.assert_allclose(np.asarray(d), (np.asarray(t) / 7e9) ** (2 / 3), rtol=1e-14)


def test_batched_designs_and_grad_through_builders():
    # Reference: d x_3 / d gap_j = 1 (positions are cumulative gaps).
    stacks = stack_designs([Stack([1.0, 0.5, 0.2], Hertz(k), gravity=0.0) for k in (1e9, 2e9)])
    assert stacks.masses.shape == (2, 3) and stacks.laws[0].k.shape == (2, 2 + 1)
    s = Stack([1.0, 0.5, 0.2], Hertz(1e9), gravity=0.0)
    grad = jax.grad(lambda g: at_impact(s, 1.0, g).positions[-1])(jnp.asarray([1e-3, 1e-3]))
    np.testing.assert_allclose(np.asarray(grad), [1.0, 1.0])


@pytest.mark.parametrize(
    "make",
    [
        lambda: Stack([1.0, -0.5], Hertz(1e9)),
        lambda: Stack(np.ones(1001), Hertz(1e9)),
        lambda: Stack([1.0], Hertz(1e9), ground=False),
        lambda: Stack([1.0, 0.5], Hertz(1e9), gravity=-1.0),
        lambda: Stack([1.0, 0.5, 0.2], [Hertz(1e9), Hertz(1e9)]),
        lambda: at_impact(Stack([1.0, 0.5], Hertz(1e9)), 1.0, [1e-3, 1e-3]),
        lambda: at_impact(Stack([1.0, 0.5], Hertz(1e9)), -1.0),
        lambda: at_impact(Stack([1.0, 0.5], Hertz(1e9)), 1.0, [-1e-3]),
        lambda: dropped(Stack([1.0, 0.5], Hertz(1e9), gravity=0.0), 1.0),
        lambda: State([0.0, 1.0], [1.0]),
    ],
)
def test_bad_parameters_raise_parameter_error(make):
    with pytest.raises(ParameterError):
        make()


def test_lists_of_traced_numbers_build_stacks_and_states():
    """A differentiable stack written as a list (`Stack([m1, m], ...)` under `jax.grad`) and a state of traced
    velocities under `jax.jit`: the input checks look at concrete numbers only (d sum(masses) / dm = 1)."""
    import hertz_chain as hc

    law = hc.Hertz(1e9)
    assert jax.grad(lambda m: hc.Stack([1.0, m], law).masses.sum())(0.3) == 1.0
    np.testing.assert_array_equal(jax.jit(lambda v: hc.State([0.0, 0.01], [v, v]).velocities)(-1.0), [-1.0, -1.0])
