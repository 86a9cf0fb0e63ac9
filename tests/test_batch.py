"""simulate_batch: the batch equals the individual solves, a failure stays in its design, the split over devices."""

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from _helpers import G, TIGHT
from _helpers import mvg as _mvg

from hertz_chain.analysis import analyse
from hertz_chain.contact import HuntCrossley
from hertz_chain.errors import ParameterError, SolverError
from hertz_chain.simulation import simulate, simulate_batch
from hertz_chain.stack import Stack, at_impact, stack_designs
from hertz_chain.status import Status


def test_batch_equals_individual_and_isolates_failure():
    # Reference: vmap must reproduce the individual solves; a design needing more steps than max_steps
    # fails alone: with 0.6 m gaps mass 1 bounces on the ground again and again before the masses above
    # reach it (~1,550 steps at TIGHT; the two others ~670).
    m = _mvg(3)
    ks = [1e9, 3e8, 1e9]
    gaps = [1e-4, 2e-4, 0.6]
    grid = np.linspace(0.0, 1.2e-3, 25)
    stacks = [Stack(m, HuntCrossley(k, 0.05), gravity=G) for k in ks]
    states = [at_impact(s, 1.0, g) for s, g in zip(stacks, gaps)]
    batch = simulate_batch(stack_designs(stacks), jax.tree.map(lambda *x: jnp.stack(x), *states),
                           tolerances=TIGHT, max_steps=1000, ts=grid)
    assert list(batch.ok) == [True, True, False]
    assert batch.status[2] == Status.INCOMPLETE_MAX_STEPS
    for i in range(2):
        one = simulate(stacks[i], states[i], tolerances=TIGHT, max_steps=1000, ts=grid)
        # batched kernels round differently, so the step sequences drift apart: agreement is to the
        # global error of the solve (~1e-9 at rtol = atol = 1e-11), not bitwise
        assert abs(int(batch.num_steps[i]) - one.num_steps) <= 0.03 * one.num_steps
        np.testing.assert_allclose(batch.launch_velocities[i], one.launch_velocities, rtol=1e-8)  # ~ global error
        # dense output on a common grid (the step sequences drift apart by rounding of the controller)
        np.testing.assert_allclose(batch.grid["velocities"][i], one.grid.velocities, rtol=0, atol=1e-8)
        np.testing.assert_allclose(batch.design(i).grid.forces, one.grid.forces, rtol=1e-6)
    with pytest.raises(SolverError, match="max_steps"):
        simulate(stacks[2], states[2], tolerances=TIGHT, max_steps=1000)
    # Without the step history (throughput mode) the launch data are unchanged: same reference.
    lean = simulate_batch(stack_designs(stacks), jax.tree.map(lambda *x: jnp.stack(x), *states),
                          tolerances=TIGHT, max_steps=1000, save_steps=False)
    assert lean.steps is None and list(lean.ok) == [True, True, False]
    for i in range(2):
        one = simulate(stacks[i], states[i], tolerances=TIGHT, max_steps=1000)
        np.testing.assert_allclose(lean.launch_velocities[i], one.launch_velocities, rtol=1e-8)
        np.testing.assert_allclose(lean.launch_times[i], one.launch_times, rtol=1e-7)
        assert lean.design(i).steps is None
    with pytest.raises(ParameterError, match="step history"):
        analyse(lean.design(0))
    assert lean.top_duration_10 is None  # streamed only when asked for
    with pytest.raises(ParameterError, match="pulse_durations.*save_steps=False"):
        simulate_batch(stack_designs(stacks), jax.tree.map(lambda *x: jnp.stack(x), *states), pulse_durations=True)


@pytest.mark.parametrize("piece", [None, 2])
def test_batch_split_over_devices_equals_individual(piece, monkeypatch):
    # Reference: individual solves. Five designs over the two CPU devices of conftest (shard_map, the
    # last design repeated once to fill the second device, then dropped), with and without history; and
    # without it in pieces of two designs (`CPU_PIECE` = 2: 2 + 2 + 1, the last padded), one device
    # thread taking the next piece as it finishes, as a large batch on a CPU runs.
    from hertz_chain import simulation

    if jax.default_backend() != "cpu":
        pytest.skip("conftest's two CPU devices: the CPU backend only (an accelerator is one device here)")
    if piece is not None:
        monkeypatch.setattr(simulation, "CPU_PIECE", piece)
    assert jax.local_device_count() == 2
    ratios = [0.3, 0.4, 0.5, 0.6, 0.7]
    stacks = [Stack(r ** np.arange(3), HuntCrossley(1e9, 0.05), gravity=G) for r in ratios]
    states = [at_impact(s, 1.0, 1e-4) for s in stacks]
    xs = jax.tree.map(lambda *x: jnp.stack(x), *states)
    for save in (True, False) if piece is None else (False,):  # pieces: the sweeps' path
        batch = simulate_batch(stack_designs(stacks), xs, tolerances=TIGHT, max_steps=1000, save_steps=save)
        if piece is not None:
            assert batch.scales.time.shape == (5,) and (batch.steps is None) != save
        assert len(batch) == 5 and batch.ok.all()
        for i in range(5):
            one = simulate(stacks[i], states[i], tolerances=TIGHT, max_steps=1000)
            np.testing.assert_allclose(batch.launch_velocities[i], one.launch_velocities, rtol=1e-8)
            # batched kernels round differently and the step sequences drift apart (module docstring)
            assert abs(int(batch.num_steps[i]) - one.num_steps) <= 0.05 * one.num_steps
            # the audit (~1e-11 here: the solver's truncation error) is kept while solving without the
            # history, from the saved steps with it; batched rounding moves the steps, not the audit
            assert batch.energy_error[i] == pytest.approx(one.energy_error, rel=1e-3)


def test_cpu_pieces_take_the_designs_in_the_order_of_their_regime_number():
    """`simulation._regime_numbers`, the order of a CPU batch's pieces, is log(summed gaps / peak overlap
    at the drop speed): for Hertz contacts the peak overlap is (5 mu v^2 / (4 k))^(2/5) (Johnson 1985,
    §11.1), independent of the gap, so doubling every gap adds log 2 and a 32 times stiffer contact adds
    log 32^(2/5) = log 4 (the regime number Pi = gap / (t_c V) of the sweeps' regime map). The unsorting
    of the results is tested above (the five designs there come in reverse order)."""
    from hertz_chain.contact import Hertz
    from hertz_chain.simulation import _regime_numbers

    def key(k, gap):
        stack = Stack([1.0, 0.5, 0.25], Hertz(k), gravity=0.0)
        state = at_impact(stack, 1.0, gap)
        batch = jax.tree.map(lambda a: jnp.stack([a]), state)
        return float(_regime_numbers(stack_designs([stack]), batch)[0])

    base = key(1e9, 1e-3)
    # the scale is the smallest peak overlap of the interfaces: at equal k, the smaller effective mass
    mu = min(1.0 * 0.5 / 1.5, 0.5 * 0.25 / 0.75)
    overlap = (5 * mu * 1.0**2 / (4 * 1e9)) ** 0.4
    assert base == pytest.approx(np.log(2e-3 / overlap + 1e-6), rel=1e-3)
    assert key(1e9, 2e-3) - base == pytest.approx(np.log(2.0), abs=1e-6)
    assert key(32e9, 1e-3) - base == pytest.approx(np.log(4.0), abs=1e-6)


@pytest.mark.parametrize("save_steps", [False, True])
def test_designs_past_the_checks_fail_without_being_solved(save_steps):
    """Designs built with `jax.vmap` skip `Stack`'s checks: a negative, a zero and a NaN mass, and an
    infinite gap, are flagged `failed` with NaN results and no steps (a zero mass used to hold its piece
    to max_steps at t = 0), and the valid designs beside them are solved: two elastic masses at g = 0
    give paper Eq 19, v_top / v = 2 (2 / (1 + r)) - 1, to 1e-8."""
    law = HuntCrossley(1e9, 0.0)  # elastic
    M = jnp.array([[1.0, 0.3], [1.0, -0.5], [1.0, 0.0], [1.0, jnp.nan], [1.0, 0.6], [1.0, 0.5]])
    stacks = jax.vmap(lambda m: Stack(m, law, gravity=0.0))(M)
    gaps = jnp.array([0.01, 0.01, 0.01, 0.01, 0.01, jnp.inf])
    states = jax.vmap(lambda m, g: at_impact(Stack(jnp.array([1.0, 0.3]), law, gravity=0.0), 1.0, g))(M, gaps)
    b = simulate_batch(stacks, states, tolerances=TIGHT, save_steps=save_steps)
    assert b.status_code.tolist() == [0, 5, 5, 5, 0, 5]
    bad = np.array([1, 2, 3, 5])
    assert np.all(np.isnan(b.launch_velocities[bad])) and np.all(b.num_steps[bad] == 0)
    for i, r in ((0, 0.3), (4, 0.6)):
        assert b.launch_velocities[i, -1] == pytest.approx(2 * (2 / (1 + r)) - 1, rel=1e-8)
    assert np.asarray(b.stack.masses)[1, 1] == -0.5  # the designs as given
    if save_steps:  # analysing such a design: one SolverError with its status (was numpy's "zero-size array")
        with pytest.raises(SolverError, match="ended failed: .*there is no step to analyse") as info:
            analyse(b.design(1))
        assert info.value.status == Status.FAILED
    # a batch of nothing but such designs is not solved either (it ran to max_steps)
    none = simulate_batch(jax.tree.map(lambda a: a[1:4], stacks), jax.tree.map(lambda a: a[1:4], states),
                          tolerances=TIGHT, save_steps=save_steps)
    assert none.status_code.tolist() == [5, 5, 5] and np.all(none.num_steps == 0)
    assert np.all(np.isnan(none.launch_velocities))


def test_designs_whose_law_or_gravity_breaks_its_rule_fail_without_being_solved():
    """A review: a negative stiffness set past the law's check (a tolerance sample of k through
    `jax.vmap`) came back "complete" with NaN launch velocities, and a negative gravity "complete" with
    plausible numbers. The batch now checks what `launch_velocity` checks of a traced design (gravity
    finite and >= 0, each law's `field_rules`): both `failed` with NaN results and no steps; the valid
    designs beside them give paper Eq 19, v_top / v = 2 (2 / (1 + r)) - 1, to 1e-8."""
    M = jnp.array([[1.0, 0.3], [1.0, 0.3], [1.0, 0.3], [1.0, 0.5]])
    K = jnp.array([1e9, -1e9, 1e9, 1e9])
    G = jnp.array([0.0, 0.0, -9.8, 0.0])
    stacks = jax.vmap(lambda m, k, g: Stack(m, HuntCrossley(k, 0.0), gravity=g))(M, K, G)
    states = jax.vmap(lambda s: at_impact(s, 1.0, 0.01))(stacks)
    b = simulate_batch(stacks, states, tolerances=TIGHT, save_steps=False)
    assert b.status_code.tolist() == [0, 5, 5, 0]
    assert np.all(np.isnan(b.launch_velocities[1:3])) and np.all(b.num_steps[1:3] == 0)
    for i, r in ((0, 0.3), (3, 0.5)):
        assert b.launch_velocities[i, -1] == pytest.approx(2 * (2 / (1 + r)) - 1, rel=1e-8)


def test_designs_with_a_negative_end_force_or_a_wall_stiffness_of_zero_fail():
    """A second review: a negative end force set through `jax.vmap` ran "complete" (a top launch 1.94
    against 1.81), a wall stiffness of 0 ran without a wall and -1e9 to max_steps (3.7e63 m/s); `Stack`
    refuses both when they are concrete. Failed (5) now, the valid designs beside them complete."""
    M = jnp.array([[1.0, 0.5, 0.25]] * 3)
    s = jax.vmap(lambda m, f: Stack(m, HuntCrossley(1e9, 0.0), end_force=f))(M, jnp.array([5.0, -5.0, 5.0]))
    st = jax.vmap(lambda s: at_impact(s, 1.0, 0.0))(s)
    assert simulate_batch(s, st, save_steps=False, until="t_max", t_max=2e-3).status_code.tolist() == [0, 5, 0]
    s = jax.vmap(lambda m, k: Stack(m, HuntCrossley(1e9, 0.0), wall_stiffness=k, wall_position=1e-3))(
        M, jnp.array([1e9, -1e9, 0.0]))
    st = jax.vmap(lambda s: at_impact(s, 1.0, 0.0))(s)
    codes = simulate_batch(s, st, save_steps=False, until="t_max", t_max=2e-3).status_code.tolist()
    assert codes[0] in (0, 1) and codes[1:] == [5, 5]


def test_cpu_pieces_give_the_same_numbers_on_any_number_of_cores(monkeypatch):
    """A design's piece and companions do not depend on the cores (`simulation._solve_pieces`): the same
    seven designs in pieces of three, by one thread and by two, give bit-for-bit equal results (a sweep's
    Dask workers have one core each, a local run every core), and the elastic two-mass launch of paper
    Eq 19, v_top / v = 2 (2 / (1 + r)) - 1, to 1e-8."""
    from hertz_chain import simulation

    monkeypatch.setattr(simulation, "CPU_PIECE", 3)
    ratios = np.array([0.3, 0.35, 0.4, 0.5, 0.55, 0.6, 0.7])
    stacks = [Stack([1.0, r], HuntCrossley(1e9, 0.0), gravity=0.0) for r in ratios]
    states = [at_impact(s, 1.0, 0.01 * (1 + i)) for i, s in enumerate(stacks)]  # wide: independent impacts
    bs, xs = stack_designs(stacks), jax.tree.map(lambda *x: jnp.stack(x), *states)
    ts, t_max, cfg = simulation._prepare(bs, xs, None, None, "tsit5", TIGHT, 2000, None, False, "cascade")
    t_max = jnp.full(7, jnp.nan)
    one = simulation._solve_pieces(bs, xs, ts, t_max, cfg, 1)
    two = simulation._solve_pieces(bs, xs, ts, t_max, cfg, 2)
    for k in ("launch_velocities", "num_steps", "energy_error", "peak_forces", "restitutions"):
        np.testing.assert_array_equal(one[k], two[k], err_msg=k)
    np.testing.assert_allclose(one["launch_velocities"][:, -1], 2 * (2 / (1 + ratios)) - 1, rtol=1e-8)


def test_an_implicit_solver_solves_batches():
    """Kvaerno5's linear solves failed under `jax.shard_map` (a batch of 4 or more on two devices raised
    "pytree does not match out_structure"): a batch of 4 solves (on one device; larger batches in pieces,
    the same vmapped solve), each design giving the elastic two-mass launch of paper Eq 19 to 1e-7."""
    ratios = np.linspace(0.3, 0.7, 4)
    stacks = [Stack([1.0, r], HuntCrossley(1e9, 0.0), gravity=0.0) for r in ratios]
    states = [at_impact(s, 1.0, 0.01) for s in stacks]  # wide gaps: independent impacts
    args = (stack_designs(stacks), jax.tree.map(lambda *x: jnp.stack(x), *states))
    b = simulate_batch(*args, solver="kvaerno5", save_steps=False)
    assert b.ok.all()
    np.testing.assert_allclose(b.launch_velocities[:, -1], 2 * (2 / (1 + ratios)) - 1, rtol=1e-7)


def test_materialised_forces_are_the_identity_with_their_derivatives():
    """`_fusion.materialised` (a vmapped solve's forces in a kernel of their own) returns its arrays bit for
    bit under `jax.vmap`, passes derivatives through (d/dx sum(c * x) = c), and uses its dot only for rows of
    at most `MAX_WIDTH` numbers: a long chain's forces are passed through (the identity's dot would cost
    O(n^2) per stage)."""
    from hertz_chain._fusion import MAX_WIDTH, materialised

    rng = np.random.default_rng(0)
    for n in (5, MAX_WIDTH):  # a dot (2 x 5 numbers a row) and a pass-through (2 x 64 > 64)
        f, g, c = rng.normal(size=(7, n)), rng.normal(size=(7, n)), rng.normal(size=(7, n))
        a, b = jax.vmap(materialised)(f, g)
        np.testing.assert_array_equal(a, f)
        np.testing.assert_array_equal(b, g)
        grad = jax.grad(lambda x: jnp.sum(jax.vmap(materialised)(x, g)[0] * c))(f)
        np.testing.assert_array_equal(grad, c)
        tangent = jax.jvp(lambda x: jax.vmap(materialised)(x, g)[1], (f,), (c,))[1]
        np.testing.assert_array_equal(tangent, 0.0 * c)
        hlo = jax.jit(jax.vmap(materialised)).lower(f, g).compile().as_text()
        assert (" dot(" in hlo) == (2 * n <= MAX_WIDTH), n


@pytest.mark.parametrize("n", [1, 5, 16, 17])
def test_the_cascade_rules_running_sums_are_numpys_cumsum(n):
    """`_tracking._running_sums` (the cascade rule's running sums: a chain of additions under `jax.vmap`
    for at most `UNROLLED_SUMS` masses, `cumsum` otherwise and in a single solve) gives NumPy's `cumsum`
    bit for bit (same order of summation), batched, twice batched and unbatched, and the derivatives of a
    running sum (the lower-triangular matrix of ones)."""
    from hertz_chain._tracking import UNROLLED_SUMS, _running_sums

    rng = np.random.default_rng(n)
    x = rng.normal(size=(2, 9, 6, n)) * np.logspace(-8, 8, n)  # summands of very different sizes
    ref = np.cumsum(x, axis=-1)
    np.testing.assert_array_equal(jax.jit(jax.vmap(_running_sums))(x[0]), ref[0])
    np.testing.assert_array_equal(jax.jit(jax.vmap(jax.vmap(_running_sums)))(x), ref)
    np.testing.assert_array_equal(jax.jit(_running_sums)(x[0, 0]), ref[0, 0])
    tri = np.tril(np.ones((n, n)))  # d(sum_{j<=k} x_j)/dx_i = [i <= k]
    np.testing.assert_array_equal(jax.vmap(jax.jacfwd(_running_sums))(x[0, :, 0]), np.broadcast_to(tri, (9, n, n)))
    np.testing.assert_array_equal(jax.vmap(jax.jacrev(_running_sums))(x[0, :, 0]), np.broadcast_to(tri, (9, n, n)))
    hlo = jax.jit(jax.vmap(_running_sums)).lower(x[0]).compile().as_text()
    assert ("reduce-window" in hlo) == (n > UNROLLED_SUMS and n > 1), n


def test_cpu_batch_sizes_share_a_program_per_power_of_two(caplog):
    """On a CPU a batch of B designs is solved as `_bucket(B)` (the next power of two, the last design
    repeated): after a batch of 5, batches of 6 and 7 compile nothing and look nothing up in the
    persistent cache (a review: every new batch size up to 128 compiled again, ~10 s each); the padding
    is cut off (B results), and each design's launch equals its own solve to the batch's tolerance."""
    import logging

    from hertz_chain.simulation import _bucket

    assert [_bucket(b) for b in range(1, 10)] == [1, 2, 4, 4, 8, 8, 8, 8, 16] and _bucket(128) == 128
    if jax.default_backend() != "cpu":
        pytest.skip("a GPU takes the batch as it is")
    law = HuntCrossley.from_restitution(1e9, 0.83, calibration_velocity=1.0)  # a structure no other test batches

    def run(B):
        stacks = [Stack([1.0, 0.5, 0.2 + 0.01 * i], law, gravity=G) for i in range(B)]
        states = [at_impact(s, 1.0, 1e-3) for s in stacks]
        return simulate_batch(stack_designs(stacks), jax.tree.map(lambda *x: np.stack(x), *states),
                              save_steps=False), stacks, states

    solve = re.compile(r"compilation of jit\((run|_vmapped)\)|cache (hit|miss) for 'jit_(run|_vmapped)'")
    jax.config.update("jax_log_compiles", True)
    try:
        with caplog.at_level(logging.DEBUG, logger="jax"):
            run(5)
            caplog.clear()
            sols = [run(6), run(7)]
            assert not [r.message for r in caplog.records if solve.search(r.message)]
    finally:
        jax.config.update("jax_log_compiles", False)
    sol, stacks, states = sols[1]
    assert sol.launch_velocities.shape == (7, 3) and np.all(sol.status_code == 0)
    one = simulate(stacks[6], states[6])
    assert sol.launch_velocities[6, -1] == pytest.approx(float(one.launch_velocities[-1]), rel=1e-8)
