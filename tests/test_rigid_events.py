"""Event-driven rigid simulator (hertz_chain.rigid_events.simulate_rigid).

References: the seed paper's Eq 13 (horizontal chain) and Eq 19 (dropped stack), each evaluated
independently here as a sequence of 2x2 linear solves of Eqs 1–2; momentum and energy conservation
(closed forms); free fall under gravity (closed form); McNamara & Young (1992) for the inelastic
collapse of three bodies in a line (e < 7 − 4√3 ≈ 0.072).
"""

import math

import numpy as np
import pytest

from hertz_chain import rigid
from hertz_chain.errors import ParameterError, SolverError
from hertz_chain.rigid_events import simulate_rigid

RNG = np.random.default_rng(7)


def _two_body(m1, m2, v1, v2, e):
    """Eqs 1–2 (momentum, restitution) as a 2x2 linear system for (V1, V2)."""
    a = np.array([[m1, m2], [-1.0, 1.0]])
    b = np.array([m1 * v1 + m2 * v2, -e * (v2 - v1)])
    return np.linalg.solve(a, b)


def _eq13_by_hand(m, e):
    v = 1.0
    for k in range(1, len(m)):  # m_k moving at v strikes m_{k+1} at rest
        v = _two_body(m[k - 1], m[k], v, 0.0, e[k])[1]
    return v


def _eq19_by_hand(m, e, e0):
    v = e0  # v_ff = 1: mass 1 leaves the ground at e0, every mass above still falls at -1
    for k in range(1, len(m)):
        v = _two_body(m[k - 1], m[k], v, -1.0, e[k])[1]
    return v


def _random_decreasing(n):
    return np.sort(RNG.uniform(0.05, 5.0, n))[::-1] * RNG.uniform(0.2, 0.6) ** np.arange(n)


def test_sequential_single_collisions_equal_eq13_and_eq19():
    # Issue 2: "the event-driven simulator equals Eq 13 and Eq 19 to 1e-12 when collisions are
    # sequential and single". Mass ratios below ~0.6 per step and equal gaps, gravity 0.
    checked13 = checked19 = 0
    for _ in range(30):
        n = int(RNG.integers(2, 9))
        m = _random_decreasing(n)
        e = RNG.uniform(0.3, 1.0, n)
        gaps = np.r_[0.0, np.full(n - 1, 1e-2)]
        chain = simulate_rigid(m, np.r_[1.0, np.zeros(n - 1)], gaps, e)
        # the top is struck exactly once (single), by the interfaces in order (sequential)
        top_hits = chain.collisions["interface"] == n - 1
        assert top_hits.sum() == 1
        assert chain.launch_velocities[-1] == pytest.approx(_eq13_by_hand(m, e), rel=1e-12)
        assert chain.gain == pytest.approx(rigid.chain_gain(m, e), rel=1e-12)
        checked13 += 1
        stack = simulate_rigid(m, -np.ones(n), gaps, e, ground_restitution=e[0])
        if (stack.collisions["interface"] == n - 1).sum() == 1:
            assert stack.gain == pytest.approx(_eq19_by_hand(m, e, e[0]), rel=1e-12)
            assert stack.gain == pytest.approx(rigid.stack_gain(m, e), rel=1e-12)
            checked19 += 1
    assert checked13 == 30 and checked19 >= 25


def test_paper_mvg6_and_met10_designs():
    # Fig 17 / Eq 20: the optimal MVG stack (R = 0.012, e = 0.8, n = 6) gains 5.0407 (docs/references.md);
    # Eq 29: the ten-mass MET stack gains sum 0.8^k = 3.5705 and leaves the lower masses at rest.
    m = rigid.mvg_masses(0.012, 6, 8.4)
    r = simulate_rigid(m, -np.ones(6), np.r_[0.0, np.full(5, 1e-2)], 0.8, ground_restitution=0.8)
    assert r.gain == pytest.approx(_eq19_by_hand(m, np.full(6, 0.8), 0.8), rel=1e-12)
    assert r.gain == pytest.approx(5.0407, abs=1e-4)
    m = rigid.met_masses(0.8, 10)
    r = simulate_rigid(m, -np.ones(10), np.r_[0.0, np.full(9, 1e-2)], 0.8, ground_restitution=0.8)
    assert r.gain == pytest.approx(sum(0.8**k for k in range(1, 11)), rel=1e-12)
    assert r.n_collisions == 10  # one impact per interface: nobody else moves afterwards
    np.testing.assert_allclose(r.final_velocities[:-1], 0.0, atol=1e-14)


def test_secondary_collisions_beat_eq19_for_equal_masses():
    # Three equal masses, e = 0.9, dropped with 1 cm gaps. Eq 19 assumes each mass is struck once.
    # Here mass 2 keeps a small upward speed after striking mass 3 (equal masses, e < 1: its share is
    # (1-e)/2 of the closing speed) while mass 1, which struck the ground again, catches up with it and
    # pushes it into the top mass a second and a third time. The top mass leaves faster than Eq 19 says.
    m, e = np.ones(3), 0.9
    r = simulate_rigid(m, -np.ones(3), [0.0, 1e-2, 1e-2], e, ground_restitution=e)
    eq19 = _eq19_by_hand(m, np.full(3, e), e)
    # by hand, equal masses: V = (v_a + v_b)/2 + e (v_a - v_b)/2; 0.9 -> 0.805 -> 0.71475
    assert eq19 == pytest.approx(0.71475, rel=1e-12)
    c = r.collisions
    top = np.flatnonzero(c["interface"] == 2)
    assert len(top) == 3  # struck three times
    assert c["after"][top[0], 1] == pytest.approx(eq19, rel=1e-12)  # first strike = Eq 19
    assert r.gain > eq19 * 1.03
    # every logged event obeys Eqs 1-2, and each mass's velocity carries over between its events
    last = -np.ones(3)
    for t, k, before, after in zip(c["time"], c["interface"], c["before"], c["after"]):
        if k == 0:
            assert before[1] == last[0] and after[1] == pytest.approx(-e * before[1], rel=1e-15)
            last[0] = after[1]
        else:
            assert tuple(before) == (last[k - 1], last[k])
            np.testing.assert_allclose(after, _two_body(1.0, 1.0, *before, e), rtol=1e-13, atol=1e-15)
            last[k - 1], last[k] = after
    assert np.all(np.diff(c["time"]) >= 0)
    np.testing.assert_array_equal(r.final_velocities, last)
    # stop rule: nothing approaches any more
    assert np.all(np.diff(r.final_velocities) >= 0) and r.final_velocities[0] >= 0


def test_conservation_in_a_horizontal_chain_with_recollisions():
    # No ground, no gravity: total momentum is conserved exactly; elastic impacts conserve energy.
    for _ in range(20):
        n = int(RNG.integers(2, 8))
        m = RNG.uniform(0.1, 3.0, n)
        v = RNG.uniform(-1, 1, n)
        gaps = np.r_[0.0, RNG.uniform(0, 0.05, n - 1)]
        for e in (1.0, 0.7):
            r = simulate_rigid(m, v, gaps, e)
            assert m @ r.final_velocities == pytest.approx(m @ v, abs=1e-13 * np.abs(m) @ np.abs(v) + 1e-15)
            ke0, ke1 = 0.5 * m @ v**2, 0.5 * m @ r.final_velocities**2
            if e == 1.0:
                assert ke1 == pytest.approx(ke0, rel=1e-12)
            else:
                assert ke1 <= ke0 * (1 + 1e-12)
            assert np.all(np.diff(r.final_velocities) >= -1e-12 * np.max(np.abs(v)))


def test_simultaneous_contacts_follow_the_lowest_interface_first_rule():
    # Newton's cradle, three equal touching elastic balls, the first moving at 1: binary impacts in
    # interface order (1-2, then 2-3) give (0, 0, 1) exactly by Eqs 1-2.
    r = simulate_rigid(np.ones(3), [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], 1.0)
    np.testing.assert_array_equal(r.collisions["interface"], [1, 2])
    np.testing.assert_allclose(r.final_velocities, [0.0, 0.0, 1.0], atol=1e-15)
    # Two equal balls hit a middle one at the same instant (equal gaps): rule 1-2 first, then 2-3,
    # then 1-2 again. By hand: (1,0,-1) -> (0,1,-1) -> (0,-1,1) -> (-1,0,1).
    r = simulate_rigid(np.ones(3), [1.0, 0.0, -1.0], [0.0, 0.1, 0.1], 1.0)
    np.testing.assert_array_equal(r.collisions["interface"], [1, 2, 1])
    assert r.collisions["time"][0] == r.collisions["time"][1] == pytest.approx(0.1, rel=1e-15)
    np.testing.assert_allclose(r.final_velocities, [-1.0, 0.0, 1.0], atol=1e-15)


def test_free_fall_and_ground_bounce_under_gravity():
    # One mass dropped from rest at h: impact at sqrt(2h/g) with speed sqrt(2gh), rebound e0 times that.
    h, g, e0 = 0.05, 9.80665, 0.6
    r = simulate_rigid([2.0], [0.0], [h], 1.0, ground_restitution=e0, gravity=g)
    # released from rest the run still runs (issue 16): it falls, lands and bounces once
    assert r.n_collisions == 1
    assert r.collisions["time"][0] == pytest.approx(math.sqrt(2 * h / g), rel=1e-12)
    assert r.launch_velocities[0] == pytest.approx(e0 * math.sqrt(2 * g * h), rel=1e-12)
    # separating from the start with nothing to meet (no gravity): no contact, no collision
    r = simulate_rigid([2.0, 1.0], [0.1, 0.2], [0.0, 0.01], 1.0, ground_restitution=e0, gravity=0.0)
    assert r.n_collisions == 0
    r = simulate_rigid([2.0], [-1e-9], [h], 1.0, ground_restitution=e0, gravity=g)
    v_imp = math.sqrt(1e-18 + 2 * g * h)
    assert r.collisions["time"][0] == pytest.approx((v_imp - 1e-9) / g, rel=1e-12)
    assert r.launch_velocities[0] == pytest.approx(e0 * v_imp, rel=1e-12)
    # gravity cancels in the relative motion: two masses in free fall hit after gap/closing speed
    r = simulate_rigid([1.0, 0.5], [-1.0, -3.0], [10.0, 0.02], 1.0, ground_restitution=0.5, gravity=g)
    assert r.collisions["interface"][0] == 1 and r.collisions["time"][0] == pytest.approx(0.01, rel=1e-12)


def test_inelastic_collapse_stops_with_a_clear_error():
    # McNamara & Young (1992): a ball between two others closing on it collapses (infinitely many
    # impacts in finite time) for e < 7 - 4 sqrt(3) = 0.0718. The run must stop, not hang.
    collapse = dict(masses=np.ones(3), velocities=[1.0, 0.0, -1.0], gaps=[0.0, 0.1, 0.2])
    with pytest.raises(SolverError, match="max_collisions = 20") as info:
        simulate_rigid(**collapse, restitution=0.05, max_collisions=20)
    assert info.value.result.n_collisions == 20  # the run so far is kept on the error
    # With the default limit the relative speeds shrink geometrically until they fall below the
    # documented round-off floor (1e-12 of the largest initial speed): the clump moves at the centre
    # of mass velocity (0 here) and the run ends in finite time.
    r = simulate_rigid(**collapse, restitution=0.05)
    assert r.n_collisions > 20
    np.testing.assert_allclose(r.final_velocities, 0.0, atol=1e-12)
    # above the threshold the same start ends after a few impacts with the bodies flying apart
    r = simulate_rigid(**collapse, restitution=0.2)
    assert r.n_collisions < 10 and np.all(np.diff(r.final_velocities) > 1e-3)
    # a finite time limit stops a run too, and names the limit: the contact would come at t = 1 s
    with pytest.raises(SolverError, match="t_max"):
        simulate_rigid(np.ones(2), [1.0, 0.0], [0.0, 1.0], 1.0, t_max=0.5)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(masses=[1.0, -1.0]), "masses"),
        (dict(masses=[1.0, np.nan]), "masses"),
        (dict(velocities=[1.0]), "velocities"),
        (dict(gaps=[0.0, -0.1]), "gaps"),
        (dict(restitution=1.2), "restitution"),
        (dict(restitution=-0.1), "restitution"),
        (dict(ground_restitution=-0.5), "ground_restitution"),
        (dict(gravity=-9.8), "gravity"),
        (dict(max_collisions=0), "max_collisions"),
    ],
)
def test_bad_input_names_the_parameter(kwargs, name):
    args = dict(masses=[1.0, 0.5], velocities=[-1.0, -1.0], gaps=[0.0, 0.01], restitution=0.8,
                ground_restitution=0.8)
    args.update(kwargs)
    with pytest.raises(ParameterError, match=name):
        simulate_rigid(**args)


def test_active_ground_is_allowed():
    # Eq 19 with e_{1,0} > 1 ('active ground', text after Eq 19)
    m = rigid.mvg_masses(0.05, 4)
    r = simulate_rigid(m, -np.ones(4), np.r_[0.0, np.full(3, 1e-2)], 0.8, ground_restitution=1.5)
    assert r.gain == pytest.approx(_eq19_by_hand(m, np.full(4, 0.8), 1.5), rel=1e-12)


def test_perfectly_plastic_impact_sticks():
    """e = 0 (Eq 2 with V2 = V1): a 3 kg mass at 2 m/s strikes a 1 kg mass at rest 1 cm away; momentum
    (Eq 1) gives both 1.5 m/s, and the pair then moves together, never approaching: one impact."""
    r = simulate_rigid([3.0, 1.0], [2.0, 0.0], [0.0, 0.01], 0.0)  # no ground: gaps[0] unused
    assert r.n_collisions == 1
    np.testing.assert_allclose(r.final_velocities, [1.5, 1.5], rtol=1e-15)


@pytest.mark.parametrize("until", ["separated", "top_launch"])
@pytest.mark.parametrize("n", [1, 3, 5])
def test_batch_runs_every_stack_as_simulate_rigid_does(n, until):
    """`simulate_rigid_batch` against `simulate_rigid` run on each stack alone (the reference, itself
    checked above against Eqs 13/19 and the closed forms): random stacks with and without a ground,
    with and without gravity, touching and gapped interfaces, plastic to elastic pairs, an active ground;
    every launch velocity and time, final velocity and impact count identical (the same arithmetic), and
    every end where `simulate_rigid` raises `SolverError` (resting contact, the impact cap) given as the
    outcome, with the run up to there; both run until the system separates, or until the top's launch is
    final."""
    from hertz_chain.rigid_events import (MAX_COLLISIONS, RESTING_CONTACT, SEPARATED, TOP_LAUNCHED,
                                          simulate_rigid_batch)

    rng = np.random.default_rng(11 + n)
    seen = set()
    for ground in (True, False):
        for g in (0.0, 9.80665):
            B = 80
            m = np.sort(np.exp(rng.uniform(-3, 0, (B, n))), axis=1)[:, ::-1].copy()
            v = np.full((B, n), -rng.uniform(0.5, 5, (B, 1))) if ground else \
                np.concatenate([rng.uniform(0.5, 5, (B, 1)), np.zeros((B, n - 1))], axis=1)
            gaps = np.where(rng.uniform(size=(B, n)) < 0.3, 0.0, 10 ** rng.uniform(-6, -2, (B, n)))
            e = np.where(rng.uniform(size=(B, n)) < 0.2, 1.0, rng.uniform(0, 1, (B, n)))
            e0 = rng.uniform(0.2, 1.2, B) if ground else None
            res = simulate_rigid_batch(m, v, gaps, e, e0, g, max_collisions=300, until=until)
            for i in range(B):
                try:
                    ref, code = simulate_rigid(m[i], v[i], gaps[i], e[i], None if e0 is None else e0[i], g,
                                               max_collisions=300, until=until), SEPARATED
                except SolverError as exc:
                    ref = exc.result
                    code = MAX_COLLISIONS if "max_collisions" in str(exc) else RESTING_CONTACT
                if code == SEPARATED and ref.n_collisions == 0:
                    code = 1  # NO_CONTACT
                if code == SEPARATED and int(res.outcome[i]) == TOP_LAUNCHED:
                    code = TOP_LAUNCHED  # simulate_rigid returns normally there
                seen.add(code)
                assert int(res.outcome[i]) == code
                assert int(res.n_collisions[i]) == ref.n_collisions
                np.testing.assert_array_equal(res.launch_velocities[i], ref.launch_velocities)
                np.testing.assert_array_equal(res.launch_times[i], ref.launch_times)
                np.testing.assert_array_equal(res.final_velocities[i], ref.final_velocities)
                if code in (SEPARATED, TOP_LAUNCHED):  # the stack's RigidResult.gain, identical
                    assert res.gains[i] == ref.gain
    np.testing.assert_array_equal(res.initial_velocities, v)
    if n == 5:  # the early ends were exercised
        assert {SEPARATED, MAX_COLLISIONS, RESTING_CONTACT} <= seen if until == "separated" else TOP_LAUNCHED in seen


def test_a_run_until_the_top_launch_gives_the_full_runs_top_launch_in_fewer_impacts():
    """Dropped five-mass MVG stacks (paper Eq 15, R = 0.05 and 0.2) under gravity, gaps 1 um to 1 cm, e from
    0.5 to 1: stopping once the top's launch is final (past its apex, or out of the lower masses' reach by
    their energy) gives the top launch velocity and time of the full run (the reference: the run until
    the system separates) exactly, wherever the full run separates, in fewer impacts."""
    from hertz_chain.rigid_events import SEPARATED, TOP_LAUNCHED, simulate_rigid_batch

    rng = np.random.default_rng(3)
    B, n = 256, 5
    for R in (0.05, 0.2):
        m = np.tile(rigid.mvg_masses(R, n), (B, 1))
        gaps = np.tile(10 ** rng.uniform(-6, -2, (B, 1)), (1, n))
        gaps[:, 0] = 0.0
        v = np.full((B, n), -2.0)
        e = np.repeat(rng.choice([0.5, 0.8, 0.95, 1.0], (B, 1)), n, axis=1)
        full = simulate_rigid_batch(m, v, gaps, e, e[:, 0], 9.80665)
        top = simulate_rigid_batch(m, v, gaps, e, e[:, 0], 9.80665, until="top_launch")
        sep = full.outcome == SEPARATED
        assert sep.sum() > B // 2 and np.sum(top.outcome == TOP_LAUNCHED) > B // 10
        np.testing.assert_array_equal(top.launch_velocities[sep, -1], full.launch_velocities[sep, -1])
        np.testing.assert_array_equal(top.launch_times[sep, -1], full.launch_times[sep, -1])
        assert np.all(top.n_collisions <= full.n_collisions)


def test_batch_top_launch_follows_the_reports_rule_for_runs_that_stop_early():
    """A run that stops (impact cap) keeps the top's launch only while the top leaves its neighbour, as
    the report's rigid comparison does (`analysis`): McNamara & Young's collapsing three-body line
    (e = 0.05 < 7 - 4 sqrt 3), whose impacts alternate 1-2, 2-3 (the 1-2 gap closes first): stopped
    after 19 impacts (the last 1-2, so 2 closes on 3) it keeps no launch; after 20 (the last 2-3) it
    keeps the top's velocity after that impact. A two-mass drop that separates keeps its launch, Eq 19
    (e0 = 1, e = 1, r = 1/2: G = 2 (2/1.5) - 1 = 5/3)."""
    from hertz_chain.rigid_events import MAX_COLLISIONS, simulate_rigid_batch

    for cap in (19, 20):
        line = simulate_rigid_batch([[1.0, 1.0, 1.0]], [[1.0, 0.0, -1.0]], [[0.0, 0.1, 0.2]],
                                    [[1.0, 0.05, 0.05]], max_collisions=cap)
        assert int(line.outcome[0]) == MAX_COLLISIONS and int(line.n_collisions[0]) == cap
        vf = line.final_velocities[0]
        if cap == 19:
            assert vf[2] < vf[1] and np.isnan(line.top_launch_velocities[0])
        else:
            assert vf[2] > vf[1] and line.top_launch_velocities[0] == vf[2]
    drop = simulate_rigid_batch([[1.0, 0.5]], [[-1.0, -1.0]], [[0.0, 0.0]], [[1.0, 1.0]], [1.0])
    assert drop.top_launch_velocities[0] == pytest.approx(5.0 / 3.0, rel=1e-14)


def test_batch_bad_input_names_the_parameter():
    from hertz_chain.rigid_events import simulate_rigid_batch

    with pytest.raises(ParameterError, match="restitution"):
        simulate_rigid_batch([[1.0, 0.5]], [[-1.0, -1.0]], [[0.0, 0.0]], [[1.0, 1.2]], [1.0])
    with pytest.raises(ParameterError, match="gaps"):
        simulate_rigid_batch([[1.0, 0.5]], [[-1.0, -1.0]], [[0.0]], [[1.0, 1.0]], [1.0])
