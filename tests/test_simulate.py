"""Simulating stacks: closed forms, published values, invariants (batches, gradients and solvers have their own files)."""

import jax
import diffrax as dfx
import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from _helpers import G, TIGHT
from _helpers import mvg as _mvg
from scipy.integrate import solve_ivp
from scipy.special import beta

import hertz_chain as hc
from hertz_chain.contact import Hertz, HuntCrossley, KelvinVoigt, Tsuji
from hertz_chain.errors import ParameterError
from hertz_chain.simulation import Tolerances, simulate, simulate_batch, simulate_impact
from hertz_chain.stack import Stack, State, at_impact, resting
from hertz_chain.status import Status

# Hertz impact constant: t_c = (4/5) B(2/5, 1/2) delta_max / v = 2.9432752 delta_max / v (closed form of
# t_c = 2 int_0^dmax d(delta)/sqrt(v^2 - 4 k delta^{5/2}/(5 m)); docs/references.md quotes 2.94328).
HERTZ_TC = 0.8 * beta(0.4, 0.5)


def test_single_hertz_impact_closed_forms():
    # Reference: Hertz (1882) impact, Johnson "Contact Mechanics" §11.1: delta_max = (5 m v^2/(4k))^{2/5},
    # t_c = 2.9432752 delta_max / v, F_max = k delta_max^{3/2}, e = 1.
    m, k, v = 0.3, 2e9, 1.7
    r = simulate_impact(Hertz(k), v, m)
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
    kv = simulate_impact(KelvinVoigt(k, 2 * zeta * np.sqrt(m * k), clamp=False), v, m)
    assert kv.e == pytest.approx(np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2)), abs=1e-8)
    assert kv.contact_time == pytest.approx(np.pi / (np.sqrt(k / m) * np.sqrt(1 - zeta**2)), rel=1e-8)
    eta = -np.sqrt(5) * np.log(e) / np.sqrt(np.pi**2 + np.log(e) ** 2)
    ts = simulate_impact(Tsuji(3e9, eta, m, clamp=False), v, m)
    assert ts.e == pytest.approx(e, abs=1e-7)
    # with the clamp the same eta dissipates less (docs/references.md: 0.808 for a 0.8 target)
    if e == 0.8:
        assert simulate_impact(Tsuji(3e9, eta, m), v, m).e == pytest.approx(0.808, abs=5e-4)


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


def test_free_chain_under_gravity_launches_as_in_free_fall():
    # Without a ground, gravity is a common free fall: in the falling frame the chain moves as at g = 0,
    # so each launch velocity plus g times its launch time is the g = 0 launch velocity. Reference: an
    # independent scipy DOP853 integration (rtol 1e-12) of the six-bead Hertz chain at g = 0, struck by
    # bead 1 at 1 m/s, run until every contact is open and no neighbours approach (the velocities are
    # then final). Until 2026-11-26 the cascade was declared over under gravity while three contacts
    # were still closed (middle launches off by up to 2.7 %).
    m = np.array([1, 0.5, 0.25, 0.125, 0.0625, 0.03])
    k = 1e9

    def rhs(t, y):
        x, v = y[:6], y[6:]
        d = np.maximum(x[:-1] - x[1:], 0.0)
        f = np.concatenate([[0.0], k * d**1.5, [0.0]])
        return np.concatenate([v, (f[:-1] - f[1:]) / m])

    y0 = np.concatenate([np.zeros(6), [1.0], np.zeros(5)])
    ref = solve_ivp(rhs, (0, 5e-3), y0, method="DOP853", rtol=1e-12, atol=1e-15).y[:, -1]
    x, v = ref[:6], ref[6:]
    assert np.all(x[:-1] < x[1:]) and np.all(np.diff(v) >= 0)  # all open, none approaching: final
    stack = Stack(m, Hertz(k), gravity=G, ground=False)
    sol = simulate(stack, State(np.zeros(6), y0[6:]), tolerances=TIGHT)
    assert sol.status == Status.COMPLETE
    assert np.all(sol.steps.overlaps[-1, 1:] <= 0)  # nothing still in contact at the end
    np.testing.assert_allclose(sol.launch_velocities + G * sol.launch_times, v, rtol=1e-7)


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
        ej = simulate_impact(laws[j], u, mstar[j], tolerances=TIGHT).e
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
    for bad in (0.0, 1.0, "0.5"):
        with pytest.raises(ParameterError, match="flight_fraction.*0 < flight_fraction < 1"):
            Tolerances(flight_fraction=bad)
    for bad in (0.0, -0.1, float("inf"), "0.05", True):
        with pytest.raises(ParameterError, match="onset_window.*finite number > 0"):
            Tolerances(onset_window=bad)
    for bad in (1, "yes", None):
        with pytest.raises(ParameterError, match="land_onsets.*True or False"):
            Tolerances(land_onsets=bad)
    with pytest.raises(ParameterError):
        simulate_impact(Hertz(1e9), -1.0, 1.0)


def test_until_launch_ends_a_gapped_stack_without_gravity_once_the_top_is_final():
    """Six masses 5 cm apart, no gravity, Tsuji e = 0.8 (speed-independent): the collisions are
    independent, so the top's launch gain is paper Eq 19, prod form with e = 0.8, written out here. The
    two bottom masses keep drifting together for seconds (mass 1 slightly faster), so the full cascade
    is not over by the default t_max; `until="launch"` stops as soon as nothing below can catch the top."""
    m = np.array([8.4, 3.47, 1.43, 0.59, 0.244, 0.1008])
    e = 0.8
    laws = [hc.make_law("tsuji", stiffness=1e9, restitution=e, effective_mass=float(me))
            for me in np.concatenate([m[:1], m[:-1] * m[1:] / (m[:-1] + m[1:])])]
    stack = hc.Stack(m, laws, gravity=0.0)
    state = hc.at_impact(stack, 1.0, 0.05)
    tol = hc.Tolerances(rtol=1e-11, atol=1e-11, resolve_onsets=True)
    r = m[1:] / m[:-1]
    eq19 = (1 + e) * np.prod((1 + e) / (1 + r)) - 1
    full = hc.simulate(stack, state, throw=False, tolerances=tol)
    assert full.status is hc.Status.INCOMPLETE_T_MAX
    sol = hc.simulate(stack, state, tolerances=tol, until="launch")
    assert sol.status is hc.Status.COMPLETE
    assert sol.t_final < 0.2 * full.t_final
    assert sol.launch_velocities[-1] == pytest.approx(eq19, rel=1e-8)
    v = hc.launch_velocity(stack, state, until="launch")
    assert float(v[-1]) == pytest.approx(eq19, rel=1e-8)


def test_restitution_is_the_deprecated_name_of_simulate_impact():
    with pytest.warns(DeprecationWarning, match="simulate_impact"):
        old = hc.restitution(Hertz(1e9), 1.0, 0.1)
    assert old == simulate_impact(Hertz(1e9), 1.0, 0.1)


def test_prepared_launch_equals_launch_velocity_and_paper_eq_19():
    """`prepare_launch` compiles once for a structure: for masses it was not prepared with it gives the
    same numbers as `launch_velocity` (bit for bit: the same compiled computation), and for widely gapped
    elastic Hertz stacks without gravity paper Eq 19 (independent collisions, e = 1) to 1e-8; another
    structure (three masses) is one clear error."""
    law = Hertz(1e9)
    tol = Tolerances(rtol=1e-11, atol=1e-11)

    def design(m, g=0.0):
        stack = Stack(jnp.asarray(m), law, gravity=g)
        return stack, at_impact(stack, 1.0, 0.01)

    launch = hc.prepare_launch(*design([1.0, 0.3]), tolerances=tol)
    for m in ([1.0, 0.3], [2.0, 0.5], [1.0, 0.9]):
        v = np.asarray(launch(*design(m)))
        np.testing.assert_array_equal(v, np.asarray(hc.launch_velocity(*design(m), tolerances=tol)))
        r = m[1] / m[0]
        assert v[-1] == pytest.approx(2 * (2 / (1 + r)) - 1, rel=1e-8)  # Eq 19, n = 2, e = 1
    with pytest.raises(ParameterError, match="structure prepared for"):
        launch(*design([1.0, 0.5, 0.2]))
    # gravity is a number of the design, not of the structure: the same compiled solve takes it
    np.testing.assert_array_equal(np.asarray(launch(*design([1.0, 0.3], g=9.81))),
                                  np.asarray(hc.launch_velocity(*design([1.0, 0.3], g=9.81), tolerances=tol)))


def test_a_repeated_launch_velocity_call_keeps_every_check(monkeypatch):
    """A repeated `launch_velocity` call of the same options on a stack of the same structure runs its
    compiled solve without preparing it again (`simulation._LAUNCHES`). It must still give each design's
    own numbers (paper Eq 19, n = 2, e = 1, widely gapped, no gravity: 1e-8), refuse what the first call
    would refuse (a held chain; a state of another length), raise for a failed solve, and read a registry
    row replaced since (its numbers equal those of the replacement solver named directly)."""
    from hertz_chain import registry

    law, tol = Hertz(1e9), Tolerances(rtol=1e-11, atol=1e-11)

    def design(m, **kw):
        stack = Stack(jnp.asarray(m), law, gravity=0.0, **kw)
        return stack, at_impact(stack, 1.0, 0.01)

    for m in ([1.0, 0.3], [2.0, 0.5], [1.0, 0.9]):  # the first call prepares, the others reuse
        r = m[1] / m[0]
        v = hc.launch_velocity(*design(m), tolerances=tol)
        assert float(v[-1]) == pytest.approx(2 * (2 / (1 + r)) - 1, rel=1e-8)  # Eq 19
    with pytest.raises(ParameterError, match="until"):  # held by an end force: the same structure
        hc.launch_velocity(*design([1.0, 0.3], end_force=5.0), tolerances=tol)
    with pytest.raises(ParameterError, match="held"):  # and a prepared function refuses it too
        hc.prepare_launch(*design([1.0, 0.3]), tolerances=tol)(*design([1.0, 0.3], end_force=5.0))
    stack, _ = design([1.0, 0.3])
    with pytest.raises(ParameterError, match=r"positions \(3,\)"):
        hc.launch_velocity(stack, State([0.0, 0.01, 0.02], [-1.0] * 3), tolerances=tol)
    bad = eqx.tree_at(lambda s: s.masses, stack, jnp.asarray([1.0, -0.3]))
    with pytest.raises(hc.SolverError, match="the cascade did not end"):
        hc.launch_velocity(bad, design([1.0, 0.3])[1], tolerances=tol)
    loose = Tolerances(rtol=1e-5, atol=1e-5)
    before = np.asarray(hc.launch_velocity(*design([1.0, 0.3]), tolerances=loose))
    monkeypatch.setitem(registry.SOLVERS, "tsit5", registry.SOLVERS["dopri5"])
    after = np.asarray(hc.launch_velocity(*design([1.0, 0.3]), tolerances=loose))
    np.testing.assert_array_equal(after, np.asarray(hc.launch_velocity(*design([1.0, 0.3]), tolerances=loose,
                                                                       solver="dopri5")))
    assert not np.array_equal(after, before)


def test_a_new_tolerance_or_an_option_written_another_way_compiles_nothing(monkeypatch):
    """The tolerances and `t_max` are arguments of the compiled launch solve, and the programs are kept by
    what is static about them (`simulation._PROGRAMS`): a new tolerance, the default tolerances written out,
    `max_steps` as a NumPy integer, a solver name in capitals, a NumPy-scalar gravity, a given `t_max` and a
    prepared launch with another `t_max` all run one compiled program per `replay` (launch_velocity's and
    prepare_launch's),
    and give paper Eq 19 (n = 2, e = 1, widely gapped, no gravity) to 1e-6 at rtol 1e-8."""
    from hertz_chain import simulation

    monkeypatch.setattr(simulation, "_PROGRAMS", {})
    monkeypatch.setattr(simulation, "_LAUNCHES", {})
    law = Hertz(1e9)
    stack = Stack(jnp.asarray([1.0, 0.3]), law, gravity=0.0)
    state = at_impact(stack, 1.0, 0.01)
    eq19 = 2 * (2 / (1 + 0.3)) - 1
    calls = [dict(tolerances=Tolerances(rtol=r, atol=r, resolve_onsets=True)) for r in (1e-8, 1e-9, 1e-10)]
    calls += [dict(tolerances=Tolerances(rtol=1e-8, atol=1e-8, resolve_onsets=True), max_steps=np.int64(16_384)),
              dict(tolerances=Tolerances(rtol=1e-8, atol=1e-8, resolve_onsets=True), solver="TSIT5"),
              dict(tolerances=Tolerances(rtol=np.float64(1e-8), atol=1e-8, resolve_onsets=True))]
    for kw in calls:
        assert float(hc.launch_velocity(stack, state, **kw)[-1]) == pytest.approx(eq19, rel=1e-6)
    g0 = eqx.tree_at(lambda s: s.gravity, stack, np.float64(0.0))
    assert float(hc.launch_velocity(g0, state, **calls[0])[-1]) == pytest.approx(eq19, rel=1e-6)
    for t_max in (0.1, 0.2):  # (the cascade ends at ~0.02 s: 1 cm gaps at 1 m/s)
        assert float(hc.launch_velocity(stack, state, t_max=t_max, **calls[0])[-1]) == pytest.approx(eq19, rel=1e-6)
    assert len(simulation._PROGRAMS) == 1
    for t_max in (0.1, 0.2):
        launch = hc.prepare_launch(stack, state, t_max=t_max, **calls[0])
        assert float(launch(stack, state)[-1]) == pytest.approx(eq19, rel=1e-6)
    assert len(simulation._PROGRAMS) == 2


def test_launch_velocity_raises_where_the_cascade_does_not_end():
    """Solver trouble is reported, never a silent number: a 1 cm gap closed at 1 m/s takes 10 ms, so a
    `t_max` of 1 us ends the solve before any contact, and `launch_velocity` and a prepared launch raise
    (the status check runs after the compiled solve, `simulation._checked`), while the same call with the
    default `t_max` returns paper Eq 19 (n = 2, e = 1) to 1e-8."""
    law, tol = Hertz(1e9), Tolerances(rtol=1e-11, atol=1e-11)
    stack = Stack(jnp.asarray([1.0, 0.3]), law, gravity=0.0)
    state = at_impact(stack, 1.0, 0.01)
    with pytest.raises(hc.SolverError, match="the cascade did not end"):
        hc.launch_velocity(stack, state, tolerances=tol, t_max=1e-6)
    launch = hc.prepare_launch(stack, state, tolerances=tol, t_max=1e-6)
    with pytest.raises(hc.SolverError, match="the cascade did not end"):
        launch(stack, state)
    # under the caller's own jit: a run-time error of the caller's program, raised when its result is read
    # (on a GPU, not before)
    with pytest.raises(Exception, match="the cascade did not end"):
        np.asarray(jax.jit(launch)(stack, state))
    v = np.asarray(hc.launch_velocity(stack, state, tolerances=tol))
    assert v[-1] == pytest.approx(2 * (2 / (1 + 0.3)) - 1, rel=1e-8)


def test_a_failed_solve_raises_through_the_callers_derivatives():
    """Under the caller's `jit`, `jax.grad` drops the primal value: a check on it alone was removed with
    it, and a failed solve (t_max of 1 us before a contact 10 ms away) gave zero gradients. Now: the
    replayed reverse mode and forward mode raise; reverse mode through a diffrax adjoint gives NaN (a
    NaN cotangent) wherever the result depends on the parameter. (Gradients of solves that end are
    checked against central differences in tests/test_gradients.py, through the same guard.)"""
    law, tol = Hertz(1e9), Tolerances(rtol=1e-8, atol=1e-8)
    state = at_impact(Stack(jnp.asarray([1.0, 0.3]), law, gravity=0.0), 1.0, 0.01)

    def top(adjoint):
        return lambda m: hc.launch_velocity(Stack(m, law, gravity=0.0), state, tolerances=tol, t_max=1e-6,
                                            max_steps=64, adjoint=adjoint)[-1]

    m = jnp.asarray([1.0, 0.3])
    with pytest.raises(Exception, match="the cascade did not end"):
        np.asarray(jax.jit(jax.grad(top("reverse")))(m))
    with pytest.raises(Exception, match="the cascade did not end"):
        np.asarray(jax.jit(jax.jacfwd(top("forward")))(m))
    # without the caller's jit the status is known at once: the SolverError says the design's numbers
    # were traced, past Stack's checks (a review: a negative mass under jax.grad read "raise max_steps")
    with pytest.raises(hc.SolverError, match="the design's numbers were traced .* masses > 0"):
        jax.grad(top("reverse"))(m)
    # (before any contact the top's velocity depends on m1 only, through the scales: d/dm2 stays an exact 0)
    g = np.asarray(jax.jit(jax.grad(top(dfx.RecursiveCheckpointAdjoint(checkpoints=64))))(m))
    assert np.isnan(g[0])


def test_a_traced_design_that_breaks_a_rule_raises_under_jit():
    """A review: a stiffness of 0 traced through the caller's `jit` gave a NaN launch velocity and, under
    `jax.grad`, a gradient of zeros, the run reported complete (the law's own check cannot see a traced
    value). Now the guard after the solve also checks the traced design's rules (masses, gravity, each law's
    `field_rules`): the same compiled gradient raises at k = 0 and is finite at k = 1e9."""
    tol = Tolerances(rtol=1e-8, atol=1e-8)

    def top(k):
        stack = Stack(jnp.asarray([1.0, 0.3]), Hertz(k), gravity=0.0)
        return hc.launch_velocity(stack, at_impact(stack, 1.0, 1e-3), tolerances=tol)[-1]

    grad = jax.jit(jax.grad(top))
    assert np.isfinite(float(grad(1e9)))
    with pytest.raises(Exception, match="the traced design breaks a rule"):
        float(grad(0.0))
    # without the caller's jit the values are known after the solve: ParameterError at once (a second review:
    # plain jax.grad of a Tsuji law with a negative eta created energy silently)
    with pytest.raises(hc.ParameterError, match="the traced design breaks one"):
        jax.grad(top)(0.0)


def test_a_traced_negative_gap_or_drop_speed_raises():
    """Noticed in a review: a negative gap traced through `at_impact` (the concrete check cannot read it)
    started the stack overlapped and ran silently. Now the traced gap and drop speed carry their rule: a
    run-time error of the compiled function under jit (the state made non-finite, caught by the guard after
    the solve), `ParameterError` at once under plain `jax.grad`."""
    tol = Tolerances(rtol=1e-8, atol=1e-8)
    stack = Stack(jnp.asarray([1.0, 0.3]), Hertz(1e9))

    def top(gap, v=1.0):
        return hc.launch_velocity(stack, at_impact(stack, v, gap), tolerances=tol)[-1]

    grad = jax.jit(jax.grad(top))
    assert np.isfinite(float(grad(1e-3)))
    with pytest.raises(Exception, match="gaps and drop speed finite and >= 0"):
        float(grad(-1e-3))
    with pytest.raises(hc.ParameterError, match=r"gaps = \[-0.001\] is invalid: finite and >= 0 \(m\) \(a traced value"):
        jax.grad(top)(-1e-3)
    with pytest.raises(Exception, match="gaps and drop speed finite and >= 0"):
        float(jax.jit(lambda v: top(1e-3, v))(-1.0))


def test_parameters_past_the_checks_fail_instead_of_returning_nan():
    """A negative mass set past `Stack`'s checks (`eqx.tree_at`, or a traced value) gives a non-finite
    launch velocity: the run is `failed` (not `complete` with NaN), and the launch functions raise."""
    law = Hertz(1e9)
    stack = Stack(jnp.asarray([1.0, 0.5, 0.25]), law)
    state = at_impact(stack, 1.0, 0.01)
    bad = eqx.tree_at(lambda s: s.masses, stack, jnp.asarray([1.0, -0.5, 0.25]))
    assert hc.simulate(bad, state, throw=False).status == Status.FAILED
    with pytest.raises(hc.SolverError, match="the cascade did not end"):
        hc.launch_velocity(bad, state)
    with pytest.raises(hc.SolverError, match="the cascade did not end"):
        hc.prepare_launch(stack, state)(bad, state)
    # a mass that is never pushed has no launch (NaN) in a run that is complete: three equal elastic masses
    # in free space, mass 1 moving up at 1 m/s onto mass 2 at rest, mass 3 moving away at 5 m/s; equal
    # masses in an elastic impact exchange their velocities (Newton's cradle), so mass 1 stops, mass 2
    # leaves at 1 m/s and never reaches mass 3
    free = Stack(jnp.ones(3), Hertz(1e9), gravity=0.0, ground=False)
    sol = hc.simulate(free, State([0.0, 0.01, 0.02], [1.0, 0.0, 5.0]), tolerances=TIGHT)
    assert sol.status == Status.COMPLETE
    assert sol.launch_velocities[0] == pytest.approx(0.0, abs=1e-8)
    assert sol.launch_velocities[1] == pytest.approx(1.0, rel=1e-8) and np.isnan(sol.launch_velocities[2])


def test_a_state_of_another_length_is_refused_by_every_entry_point():
    """A two-mass state for a three-mass stack: one `ParameterError` naming `state` and both shapes, from
    `simulate`, `launch_velocity`, `prepare_launch` and a prepared launch's call (not a raw broadcasting
    error)."""
    stack = Stack(jnp.asarray([1.0, 0.5, 0.25]), Hertz(1e9))
    good, bad = at_impact(stack, 1.0, 0.01), State([0.0, 0.01], [-1.0, -1.0])
    for call in (lambda: simulate(stack, bad), lambda: hc.launch_velocity(stack, bad),
                 lambda: hc.prepare_launch(stack, bad), lambda: hc.prepare_launch(stack, good)(stack, bad)):
        with pytest.raises(ParameterError, match=r"state = 'positions \(2,\), velocities \(2,\)'.*shape \(3,\)"):
            call()


def test_simulate_under_a_trace_says_what_to_use():
    """`simulate` and `simulate_batch` return NumPy results on the host: under `jax.grad`/`jax.jit` they
    refuse at once with one line that points at `launch_velocity` (not a JAX concretization error)."""
    law = Hertz(1e9)
    state = at_impact(Stack(jnp.asarray([1.0, 0.3]), law), 1.0)
    with pytest.raises(ParameterError, match="stack/state = 'a traced value'.*use launch_velocity"):
        jax.grad(lambda m: simulate(Stack(m, law), state).gain)(jnp.asarray([1.0, 0.3]))
    with pytest.raises(ParameterError, match="simulate_batch runs on the host"):
        jax.jit(lambda m: simulate_batch(jax.vmap(lambda mm: Stack(mm, law))(m), jax.vmap(lambda _: state)(m)).status_code)(
            jnp.ones((2, 2)))


def test_a_launch_that_did_not_end_names_its_cause():
    """Two masses, 1 cm gap, g = 0, drop speed 1 m/s: the gap alone takes 10 ms to close, so t_max = 1 ms
    ends the run at t_max and 16 steps cannot reach the cascade's end; the error says which (a review: one
    message for every cause suggested raising max_steps for a t_max)."""
    stack = hc.Stack(np.array([1.0, 0.5]), hc.Hertz(1e9), gravity=0.0)
    state = hc.at_impact(stack, 1.0, 0.01)
    with pytest.raises(hc.SolverError, match=r"the cascade did not end \(incomplete: t_max reached\): .*raise t_max"):
        hc.launch_velocity(stack, state, t_max=1e-3)
    with pytest.raises(hc.SolverError, match=r"\(incomplete: max_steps reached\): .*raise max_steps"):
        hc.launch_velocity(stack, state, max_steps=16)
