"""Simulating stacks with diffrax: closed forms, published values, invariants, batching, gradients."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import beta

from hertz_chain.status import Status
from hertz_chain.analysis import analyse
from hertz_chain.contact import Hertz, HuntCrossley, KelvinVoigt, Tsuji
from hertz_chain.errors import ParameterError, SolverError
from hertz_chain.simulate import (
    Tolerances,
    launch_velocity,
    restitution,
    simulate,
    simulate_batch,
)
from hertz_chain.stack import STANDARD_GRAVITY, Stack, State, at_impact, resting, stack_designs

G = STANDARD_GRAVITY
TIGHT = Tolerances(rtol=1e-11, atol=1e-11)

# Hertz impact constant: t_c = (4/5) B(2/5, 1/2) delta_max / v = 2.9432752 delta_max / v (closed form of
# t_c = 2 int_0^dmax d(delta)/sqrt(v^2 - 4 k delta^{5/2}/(5 m)); docs/references.md quotes 2.94328).
HERTZ_TC = 0.8 * beta(0.4, 0.5)


def _mvg(n, ratio=0.5):
    return ratio ** np.arange(n)


def test_single_hertz_impact_closed_forms():
    # Reference: Hertz (1882) impact, Johnson "Contact Mechanics" §11.1: delta_max = (5 m v^2/(4k))^{2/5},
    # t_c = 2.9432752 delta_max / v, F_max = k delta_max^{3/2}, e = 1.
    m, k, v = 0.3, 2e9, 1.7
    r = restitution(Hertz(k), v, m)
    d_max = (5 * m * v**2 / (4 * k)) ** 0.4
    assert r.max_overlap == pytest.approx(d_max, rel=1e-7)
    assert r.contact_time == pytest.approx(HERTZ_TC * d_max / v, rel=1e-7)
    assert r.max_force == pytest.approx(k * d_max**1.5, rel=1e-7)
    assert r.e == pytest.approx(1.0, rel=1e-8)


@pytest.mark.parametrize("e", [0.3, 0.8])
def test_unclamped_contact_ends_when_overlap_closes(e):
    # Without the no-tension clamp the contact pulls until delta = 0, so the measured restitution is
    # the law's exact unclamped map. Linear spring-dashpot: e = exp(-zeta pi / sqrt(1 - zeta^2)),
    # contact time pi / (omega_n sqrt(1 - zeta^2)) (damped half period); Tsuji: the same in rescaled
    # time with zeta = eta / sqrt(5) (docs/references.md: exact without the clamp).
    m, k, v = 0.2, 3e6, 1.3
    zeta = -np.log(e) / np.sqrt(np.pi**2 + np.log(e) ** 2)
    kv = restitution(KelvinVoigt(k, 2 * zeta * np.sqrt(m * k), clamp=False), v, m)
    assert kv.e == pytest.approx(np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2)), abs=1e-8)
    assert kv.contact_time == pytest.approx(np.pi / (np.sqrt(k / m) * np.sqrt(1 - zeta**2)), rel=1e-8)
    eta = -np.sqrt(5) * np.log(e) / np.sqrt(np.pi**2 + np.log(e) ** 2)
    ts = restitution(Tsuji(3e9, eta, m, clamp=False), v, m)
    assert ts.e == pytest.approx(e, abs=1e-7)
    # with the clamp the same eta dissipates less (docs/references.md: 0.808 for a 0.8 target)
    if e == 0.8:
        assert restitution(Tsuji(3e9, eta, m), v, m).e == pytest.approx(0.808, abs=5e-4)


def test_newtons_cradle_published_velocities_momentum_energy():
    # Reference: Herrmann & Seitz (1982), Hinch & Saint-Jean (1999): three equal touching Hertz spheres,
    # first at v0 = 1: final velocities (-0.07095, 0.07640, 0.99455).
    stack = Stack([1.0, 1.0, 1.0], Hertz(1.0), gravity=0.0, ground=False)
    sol = simulate(stack, State([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), tolerances=TIGHT)
    assert sol.status == Status.COMPLETE
    np.testing.assert_allclose(sol.final_velocities, [-0.07095, 0.07640, 0.99455], atol=5e-6)
    # momentum (Newton's third law, no ground, no gravity) to 1e-10 at every step
    p = sol.steps.velocities @ np.ones(3)
    np.testing.assert_allclose(p, 1.0, rtol=0, atol=1e-10)
    # elastic: energy conserved to 1e-8 relative (energy audit)
    assert sol.energy_error < 1e-8
    assert np.all(np.isfinite(sol.steps.t)) and sol.steps.t[0] == 0.0


def test_dense_output_matches_scipy():
    # Reference: independent integration with scipy's DOP853 at rtol 1e-12 (Hertz cradle, touching).
    stack = Stack([1.0, 0.6, 0.3], Hertz(1.0), gravity=0.0, ground=False)
    ts = np.linspace(0.0, 6.0, 13)
    sol = simulate(stack, State([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), tolerances=TIGHT, ts=ts, t_max=200.0)
    m = np.array([1.0, 0.6, 0.3])

    def rhs(t, y):
        x, v = y[:3], y[3:]
        d = np.maximum(x[:-1] - x[1:], 0.0)
        f = np.concatenate([[0.0], d**1.5])
        above = np.concatenate([f[1:], [0.0]])
        return np.concatenate([v, (f - above) / m])

    ref = solve_ivp(rhs, (0, 6.0), [0, 0, 0, 1.0, 0, 0], method="DOP853", rtol=1e-12, atol=1e-14, t_eval=ts)
    live = ts <= sol.t_final  # after the cascade is complete the solve stops: NaN there, not inf
    assert live.sum() >= 6 and np.all(np.isnan(sol.grid.positions[~live]))
    np.testing.assert_allclose(sol.grid.positions[live], ref.y[:3].T[live], atol=1e-8)
    np.testing.assert_allclose(sol.grid.velocities[live], ref.y[3:].T[live], atol=1e-8)


def test_rigid_limit_eq19_and_event_driven():
    # Reference: paper Eq 19, G_n = (1+e_10) prod_k (1+e_k,k-1)/(1+r_k,k-1) - 1, with each interface's
    # restitution measured by `restitution` (Tsuji: e independent of speed), and the event-driven rigid
    # simulator hertz_chain.rigid_events.simulate_rigid; gaps large enough to separate the contacts.
    n = 4
    m = _mvg(n)
    mstar = np.concatenate([[m[0]], m[:-1] * m[1:] / (m[:-1] + m[1:])])
    k = np.array([2e8, 1.5e8, 1e8, 8e7])
    eta = np.array([0.10, 0.15, 0.20, 0.12])
    laws = [Tsuji(k[j], eta[j], mstar[j]) for j in range(n)]
    v, gap = 1.0, 0.02
    stack = Stack(m, laws, gravity=0.0)
    sol = simulate(stack, at_impact(stack, v, gap), tolerances=TIGHT)
    # approach speeds of the rigid cascade (paper Eqs 1-2) to measure each e where it acts
    e, up = [], None
    for j in range(n):
        u = v if j == 0 else up + v
        ej = restitution(laws[j], u, mstar[j], tolerances=TIGHT).e
        e.append(ej)
        if j == 0:
            up = ej * v
        else:  # mass j+1 (index j) at -v hit by mass j (index j-1) moving up at `up`
            r = m[j] / m[j - 1]
            up = (up * (1 + ej) + (-v) * (r - ej)) / (1 + r)  # paper Eqs 1-2, upper mass after impact
    g19 = (1 + e[0]) * np.prod([(1 + e[j]) / (1 + m[j] / m[j - 1]) for j in range(1, n)]) - 1
    assert sol.launch_velocities[-1] / v == pytest.approx(g19, rel=1e-6)
    assert up / v == pytest.approx(g19, rel=1e-12)  # the cascade above is Eq 19 itself
    rigid_events = pytest.importorskip("hertz_chain.rigid_events")
    rig = rigid_events.simulate_rigid(m, -v * np.ones(n), np.r_[0.0, gap * np.ones(n - 1)], np.array(e),
                                      ground_restitution=e[0], gravity=0.0)
    assert sol.launch_velocities[-1] == pytest.approx(rig.launch_velocities[-1], rel=1e-6)


def test_launch_velocity_corrects_free_flight_under_gravity():
    # Reference: energy conservation for an elastic ball bouncing on the ground under gravity: it leaves
    # the ground (x = 0, no elastic energy) at exactly the impact speed; afterwards v = v_launch - g t.
    stack = Stack([0.2], Hertz(5e8), gravity=G)
    sol = simulate(stack, at_impact(stack, 1.3), tolerances=TIGHT)
    assert sol.status == Status.COMPLETE
    assert sol.launch_velocities[0] == pytest.approx(1.3, rel=1e-9)
    # Carried on to t_max = 0.2 s (until="t_max": it flies 0.265 s, so no rebound), the ball's velocity
    # falls by g (t - t_end) while its launch velocity stays the one at the contact's end.
    long = simulate(stack, at_impact(stack, 1.3), tolerances=TIGHT, until="t_max", t_max=0.2)
    assert long.status == Status.COMPLETE and long.t_final == pytest.approx(0.2, rel=1e-12)
    assert long.launch_velocities[0] == pytest.approx(1.3, rel=1e-9)
    assert long.final_velocities[0] == pytest.approx(1.3 - G * (0.2 - long.launch_times[0]), rel=1e-9)


def test_energy_audit_closes_with_damping_and_gravity():
    # Reference: energy balance: kinetic + gravitational + elastic + dissipated = initial energy.
    n = 5
    m = _mvg(n)
    mstar = np.concatenate([[m[0]], m[:-1] * m[1:] / (m[:-1] + m[1:])])
    stack = Stack(m, [Tsuji(1e9, 0.2, ms) for ms in mstar], gravity=G)
    sol = simulate(stack, at_impact(stack, 2.0, 1e-4), tolerances=TIGHT)
    assert sol.energy_error < 1e-8
    diss = sol.steps.dissipated
    assert diss[-1].sum() > 1e-3 * 0.5 * m.sum() * 4.0  # damping did dissipate
    assert np.all(np.diff(diss, axis=0) >= -1e-15)  # dissipated energy never decreases
    # The audit is kept while solving (no step history needed). Reference: the same balance recomputed
    # here in numpy at every saved step: sum m v^2/2 + sum m g x + sum 2/5 k delta^{5/2} + D, maximum
    # deviation over the steps, in units of the drop energy sum(m) V^2/2 (V = 2 m/s).
    st = sol.steps
    x, v = st.positions, st.velocities
    delta = np.concatenate([-x[:, :1], x[:, :-1] - x[:, 1:]], axis=1)
    e = (0.5 * (m * v**2).sum(1) + G * (m * x).sum(1) + (0.4 * 1e9 * np.clip(delta, 0, None) ** 2.5).sum(1)
         + diss.sum(1))
    audit = np.max(np.abs(e - e[0])) / (0.5 * m.sum() * 2.0**2)
    assert sol.energy_error == pytest.approx(audit, rel=1e-6, abs=1e-15)


def test_step_history_independent_of_the_step_budget():
    # Reference: the same solve. The step sequence does not depend on max_steps (only the buffers do),
    # and the post-processing runs on the rows used, so the trajectory and the audit are bitwise equal;
    # every accepted step and t0 is one row.
    m = _mvg(4)
    stack = Stack(m, HuntCrossley(1e9, 0.1), gravity=G)
    state = at_impact(stack, 1.0, 1e-4)
    small, big = (simulate(stack, state, max_steps=ms) for ms in (2000, 65536))
    assert small.num_accepted_steps == big.num_accepted_steps
    assert small.steps.t.shape == (small.num_accepted_steps + 1,)
    for name in ("t", "positions", "velocities", "forces", "energy"):
        np.testing.assert_array_equal(getattr(small.steps, name), getattr(big.steps, name))
    assert small.energy_error == big.energy_error


def test_resting_stack_stays_at_rest():
    # Reference: static equilibrium: a resting stack (state c, h = 0) has zero acceleration at t = 0.
    stack = Stack(_mvg(4), Hertz(1e9), gravity=G)
    sol = simulate(stack, resting(stack), tolerances=TIGHT, t_max=1e-3, max_steps=2000, until="t_max")
    # bound to the ground from the start: the cascade is over at once, and nothing happens after it
    assert sol.status == Status.COMPLETE and sol.t_final == pytest.approx(1e-3, rel=1e-12)
    assert np.all(sol.launch_velocities == 0.0) or np.all(np.abs(sol.launch_velocities) < 1e-9)
    np.testing.assert_allclose(sol.steps.accelerations[0], 0.0, atol=1e-9 * G)
    np.testing.assert_allclose(sol.steps.velocities[-1], 0.0, atol=1e-9)


def test_convergence_with_tolerance():
    # Reference: self-convergence against a Dopri8 solve at rtol = atol = 1e-12 (an independent solver).
    stack = Stack(_mvg(5), Hertz(1e9), gravity=G)
    s0 = at_impact(stack, 1.0, 1e-4)
    ref = simulate(stack, s0, solver="dopri8", tolerances=Tolerances(1e-12, 1e-12)).launch_velocities[-1]
    errs = [abs(simulate(stack, s0, tolerances=Tolerances(t, t)).launch_velocities[-1] / ref - 1)
            for t in (1e-6, 1e-8, 1e-10)]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-7


def test_unrolled_tsit5_equals_diffrax_tsit5():
    # Reference: diffrax's own Tsit5 (same tableau, stages in a loop): one step of a nonlinear system
    # agrees to rounding in the solution, the error estimate and the dense output; a fixed-step solve too.
    import diffrax as dfx

    from hertz_chain.simulate import UnrolledTsit5

    term = dfx.ODETerm(lambda t, y, a: jnp.stack([y[1], -jnp.sin(y[0]) - a * y[1] * jnp.abs(y[1]) + jnp.cos(3 * t)]))
    y0, args, t0, t1 = jnp.array([0.3, -1.2]), 0.7, 0.1, 0.35
    out = []
    for solver in (UnrolledTsit5(), dfx.Tsit5()):
        state = solver.init(term, t0, t1, y0, args)
        y1, err, dense, _, _ = solver.step(term, t0, t1, y0, args, state, False)
        mid = solver.interpolation_cls(t0=t0, t1=t1, **dense).evaluate(0.2)
        out.append((y1, err, mid))
    for a, b in zip(*out):  # atol: rounding of sums of O(1) stage values (the error estimate cancels)
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-15)
    sols = [dfx.diffeqsolve(term, s, 0.0, 5.0, 0.01, y0, args=args, stepsize_controller=dfx.ConstantStepSize(),
                            saveat=dfx.SaveAt(ts=jnp.linspace(0, 5, 11))).ys for s in (UnrolledTsit5(), dfx.Tsit5())]
    np.testing.assert_allclose(sols[0], sols[1], rtol=1e-11, atol=1e-13)


def test_kvaerno5_newton_fix():
    # Reference: diffrax 0.7.2's VeryChord stops after two iterations (diffrax PR #754); a Chord root
    # finder with a proper termination test must need fewer rejected steps, and agree with Tsit5.
    stack = Stack(_mvg(3), Hertz(1e9), gravity=G)
    s0 = at_impact(stack, 1.0, 1e-4)
    tol = Tolerances(1e-8, 1e-8)
    explicit = simulate(stack, s0, tolerances=tol)
    fixed = simulate(stack, s0, solver="kvaerno5", tolerances=tol)
    stock = simulate(stack, s0, solver="kvaerno5-stock", tolerances=tol)
    assert fixed.num_rejected_steps < stock.num_rejected_steps / 2
    assert fixed.num_steps < stock.num_steps
    # both within their own global error (~100 x tol, see test_convergence_with_tolerance)
    np.testing.assert_allclose(fixed.launch_velocities, explicit.launch_velocities, rtol=1e-5)


def test_batch_equals_individual_and_isolates_failure():
    # Reference: vmap must reproduce the individual solves; a design needing more steps than max_steps
    # (0.6 m gaps at 0.5 contact times per step) fails alone.
    m = _mvg(3)
    ks = [1e9, 3e8, 1e9]
    gaps = [1e-4, 2e-4, 0.6]
    grid = np.linspace(0.0, 1.2e-3, 25)
    stacks = [Stack(m, HuntCrossley(k, 0.05), gravity=G) for k in ks]
    states = [at_impact(s, 1.0, g) for s, g in zip(stacks, gaps)]
    batch = simulate_batch(stack_designs(stacks), jax.tree.map(lambda *x: jnp.stack(x), *states),
                           tolerances=TIGHT, max_steps=3000, ts=grid)
    assert list(batch.ok) == [True, True, False]
    assert batch.status[2] == Status.INCOMPLETE_MAX_STEPS
    for i in range(2):
        one = simulate(stacks[i], states[i], tolerances=TIGHT, max_steps=3000, ts=grid)
        # batched kernels round differently, so the step sequences drift apart: agreement is to the
        # global error of the solve (~1e-9 at rtol = atol = 1e-11), not bitwise
        assert abs(int(batch.num_steps[i]) - one.num_steps) <= 0.03 * one.num_steps
        np.testing.assert_allclose(batch.launch_velocities[i], one.launch_velocities, rtol=1e-8)  # ~ global error
        # dense output on a common grid (the step sequences drift apart by rounding of the controller)
        np.testing.assert_allclose(batch.grid["velocities"][i], one.grid.velocities, rtol=0, atol=1e-8)
        np.testing.assert_allclose(batch.design(i).grid.forces, one.grid.forces, rtol=1e-6)
    with pytest.raises(SolverError, match="max_steps"):
        simulate(stacks[2], states[2], tolerances=TIGHT, max_steps=3000)
    # Without the step history (throughput mode) the launch data are unchanged: same reference.
    lean = simulate_batch(stack_designs(stacks), jax.tree.map(lambda *x: jnp.stack(x), *states),
                          tolerances=TIGHT, max_steps=3000, save_steps=False)
    assert lean.steps is None and list(lean.ok) == [True, True, False]
    for i in range(2):
        one = simulate(stacks[i], states[i], tolerances=TIGHT, max_steps=3000)
        np.testing.assert_allclose(lean.launch_velocities[i], one.launch_velocities, rtol=1e-8)
        np.testing.assert_allclose(lean.launch_times[i], one.launch_times, rtol=1e-7)
        assert lean.design(i).steps is None
    with pytest.raises(ParameterError, match="step history"):
        analyse(lean.design(0))


def test_batch_split_over_devices_equals_individual():
    # Reference: individual solves. Five designs over the two CPU devices of conftest (shard_map, the
    # last design repeated once to fill the second device, then dropped), with and without history.
    assert jax.local_device_count() == 2
    ratios = [0.3, 0.4, 0.5, 0.6, 0.7]
    stacks = [Stack(r ** np.arange(3), HuntCrossley(1e9, 0.05), gravity=G) for r in ratios]
    states = [at_impact(s, 1.0, 1e-4) for s in stacks]
    xs = jax.tree.map(lambda *x: jnp.stack(x), *states)
    for save in (True, False):
        batch = simulate_batch(stack_designs(stacks), xs, tolerances=TIGHT, max_steps=3000, save_steps=save)
        assert len(batch) == 5 and batch.ok.all()
        for i in range(5):
            one = simulate(stacks[i], states[i], tolerances=TIGHT, max_steps=3000)
            np.testing.assert_allclose(batch.launch_velocities[i], one.launch_velocities, rtol=1e-8)
            # batched kernels round differently and the step sequences drift apart (module docstring)
            assert abs(int(batch.num_steps[i]) - one.num_steps) <= 0.05 * one.num_steps
            # the audit (~1e-11 here: the solver's truncation error) is kept while solving without the
            # history, from the saved steps with it; batched rounding moves the steps, not the audit
            assert batch.energy_error[i] == pytest.approx(one.energy_error, rel=1e-3)


def _hc_top(theta, tol, adjoint="forward", solver="tsit5"):
    # top launch velocity of a 3-mass Hunt–Crossley stack with gravity and gaps, as a function of
    # theta = (masses, gaps, stiffness k / 1e8, damping alpha)
    m, gaps, k, alpha = theta[0:3], theta[3:5], theta[5:8] * 1e8, theta[8:11]
    stack = Stack(m, HuntCrossley(k, alpha), gravity=G)
    return launch_velocity(stack, at_impact(stack, 1.0, gaps), adjoint=adjoint, solver=solver,
                           tolerances=Tolerances(tol, tol, resolve_onsets=True))[-1]


THETA = jnp.asarray([1.0, 0.5, 0.25, 2e-3, 1e-3, 2.0, 1.5, 1.0, 0.1, 0.15, 0.2])


def test_gradient_matches_finite_differences():
    # Reference: central finite differences of the same model at rtol = atol = 1e-12 (step 1e-4 relative):
    # d(top launch velocity)/d(masses, gaps, stiffness k, damping alpha), Hunt–Crossley, with gravity;
    # forward mode (jacfwd) and reverse mode (jax.grad, the replayed discrete adjoint) alike.
    forward = np.asarray(jax.jacfwd(lambda th: _hc_top(th, 1e-11))(THETA))
    reverse = np.asarray(jax.grad(lambda th: _hc_top(th, 1e-11, "reverse"))(THETA))
    fd = np.empty_like(forward)
    for i in range(THETA.size):
        h = 1e-4 * float(THETA[i])
        step = jnp.zeros_like(THETA).at[i].set(h)
        fd[i] = (_hc_top(THETA + step, 1e-12) - _hc_top(THETA - step, 1e-12)) / (2 * h)
    # relative error per parameter, in the natural unit of that parameter (|dv/dln(theta)| scale)
    scale = np.maximum(np.abs(fd), 1e-2 * np.max(np.abs(fd * np.asarray(THETA))) / np.abs(np.asarray(THETA)))
    # the discrete derivative is accurate to the solve's tolerance, not better: at 1e-11 the two modes
    # (different step sequences) are within 2e-4 (measured 2e-5 forward, 1.6e-4 reverse, for a gap), and
    # they converge with the tolerance: at 1e-12 both are within 1e-5 of the differences
    assert np.max(np.abs(forward - fd) / scale) <= 2e-4
    assert np.max(np.abs(reverse - fd) / scale) <= 2e-4
    reverse_12 = np.asarray(jax.grad(lambda th: _hc_top(th, 1e-12, "reverse"))(THETA))
    assert np.max(np.abs(reverse_12 - fd) / scale) <= 1e-5


@pytest.mark.parametrize("solver", ["tsit5", "dopri8"])
def test_reverse_replay_equals_diffrax_checkpointed_adjoint(solver):
    # Reference: diffrax's own reverse mode through the solver loop (RecursiveCheckpointAdjoint, which
    # differentiates every accepted step with the step sizes frozen by its controller): the replayed
    # adjoint is the same discrete derivative, so they agree to rounding (1e-12 of the largest component).
    # Gravity makes the launch velocity depend on the contacts' recorded points; gaps enter through y0.
    import diffrax as dfx

    replay = np.asarray(jax.grad(lambda th: _hc_top(th, 1e-10, "reverse", solver))(THETA))
    diffrax_rev = np.asarray(jax.grad(lambda th: _hc_top(
        th, 1e-10, dfx.RecursiveCheckpointAdjoint(checkpoints=4096), solver))(THETA))
    assert np.all(np.isfinite(replay)) and np.max(np.abs(replay)) > 0
    np.testing.assert_allclose(replay, diffrax_rev, rtol=0, atol=1e-12 * np.max(np.abs(diffrax_rev)))


def test_reverse_gradient_batched_equals_diffrax_adjoint_batched():
    # Reference: diffrax's RecursiveCheckpointAdjoint under the same vmap (vmap must not mix the designs'
    # step sequences). Against the unbatched gradients both differ by ~2e-5: batched arithmetic rounds
    # differently, the controller takes other steps, and the discrete derivative moves within its error.
    import diffrax as dfx

    thetas = jnp.stack([THETA, THETA * jnp.asarray([1.0, 0.8, 0.5] + [1.0] * 8)])
    replay = np.asarray(jax.vmap(jax.grad(lambda th: _hc_top(th, 1e-10, "reverse")))(thetas))
    diffrax_rev = np.asarray(jax.vmap(jax.grad(lambda th: _hc_top(
        th, 1e-10, dfx.RecursiveCheckpointAdjoint(checkpoints=4096))))(thetas))
    assert np.max(np.abs(replay[0] - replay[1])) > 1e-3  # two different designs
    np.testing.assert_allclose(replay, diffrax_rev, rtol=0, atol=1e-12 * np.max(np.abs(diffrax_rev)))


def test_bad_options_raise_parameter_error():
    stack = Stack([1.0, 0.5], Hertz(1e9), gravity=G)
    s0 = at_impact(stack, 1.0)
    with pytest.raises(ParameterError):
        simulate(stack, s0, solver="euler")
    with pytest.raises(ParameterError):
        simulate(stack, s0, t_max=-1.0)
    with pytest.raises(ParameterError):
        simulate(stack, s0, ts=[0.0, 2.0], t_max=1.0)
    with pytest.raises(ParameterError):
        Tolerances(rtol=0.0)
    with pytest.raises(ParameterError):
        restitution(Hertz(1e9), -1.0, 1.0)
