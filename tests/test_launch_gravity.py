"""Launch velocities under gravity (issue 16) against an independent scipy reference.

The reference, `cascade_reference`, integrates the same equations as `hertz_chain.stack.Stack`
(`m_i a_i = F_{i-1} - F_i - m_i g`, `F_j = k_j delta^{3/2} + c_j delta^{1/4} delta_dot` on a closed
contact, Hertz: `c_j = 0`, Tsuji: `c_j = eta sqrt(m*_j k_j)`) with scipy's DOP853 and none of
hertz_chain's solver code. It integrates piecewise, as a hybrid system: between two events the set of
closed contacts is fixed and the right-hand side is smooth, so the integrator restarts at every contact
onset and release (where the force is not smooth) instead of stepping across them. Events (located by
scipy's root finder on the dense output):

- a contact closes: `delta` rises through 0, or, at `delta > 0` after a clamped release, the unclamped
  force rises through 0;
- a contact opens: its force returns to zero (`F / delta^{1/4} = k delta^{5/4} + c delta_dot` falls
  through 0: the clamp's release for Tsuji, `delta = 0` for Hertz);
- mass 1 becomes bound to the ground: `m_1 v_1^2/2 + P_0(delta_0) - m_1 g delta_0` falls through 0;
- the top mass passes the apex of its free flight after its last push (its velocity falls through 0).

The cascade-end rule (issue 16) is checked after every event: something has touched, every contact
between masses is open and no neighbours approach (`v_{j+1} >= v_j`), and mass 1 is off the ground with
`v_1 >= 0` or bound to it with `delta_0 > 0`. A mass's launch velocity is its velocity when the force of
its last contact (below or above) returned to zero before the cascade ended. The top mass's launch is
frozen at its apex if the apex comes before the end (hertz_chain's rule: its landing back is a
rebound). The state is `[x_1, s_1..s_{n-1}, v_1..v_n, D]` with the gaps `s_j = x_{j+1} - x_j`
integrated directly, so that overlaps of 1e-5 m are not differences of positions of 0.1 m; `D` is the
dissipated energy, for the energy audit.

Self-checks of the reference (`test_reference_*`): closed forms (single Hertz impact e = 1; elastic
bounce under gravity leaves at the impact speed; Tsuji e = 0.8 of the calibration; two-mass rigid limit,
paper Eqs 1-2), energy conservation, and convergence in rtol.

Compile budget: three structures (3 Hertz, 3 Tsuji, 6 Tsuji, with the ground; one more for the extreme
mass ratio and the single mass), one set of tolerances (`TIGHT`: traced, no recompile).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import hertz_chain as hc
from hertz_chain.status import Status

G = 9.80665  # standard gravity (m/s^2)
K = 1e9  # contact stiffness (N/m^1.5)
E = 0.8  # restitution of the Tsuji contacts
TIGHT = hc.Tolerances(rtol=1e-11, atol=1e-11)
REF_RTOL = 1e-12


# ==================================================================== the independent reference
@dataclasses.dataclass(frozen=True)
class Reference:
    status: str  # "complete", "t_max" (no end before t_max) or "no contact"
    t_end: float  # cascade end (s), or t_max
    launch: np.ndarray  # (n,) launch velocity of every mass (m/s), NaN if never pushed
    t_launch: np.ndarray  # (n,) when its last push ended (s)
    top_frozen: bool  # the top mass passed its apex before the end
    top_rebound: bool  # ... and touched the stack again before the end
    events: int
    energy_drift: float  # |E(t_end) - E(0)| (J), dissipated energy included


def law_parameters(masses, law: str):
    """`(k, c)` per interface (ground first) for the Hertz or the clamped Tsuji law with e = 0.8.

    Only the calibrated `eta(e)` is taken from hertz_chain (`hc.tsuji_eta`, not under test here); the
    forces are computed by the reference itself."""
    m = np.asarray(masses, float)
    meff = np.concatenate([m[:1], m[:-1] * m[1:] / (m[:-1] + m[1:])])
    k = np.full(m.size, K)
    c = np.zeros(m.size) if law == "hertz" else hc.tsuji_eta(E) * np.sqrt(meff * K)
    return k, c


def cascade_reference(masses, k, c, g, x0, v0, *, t_max=5.0, rtol=REF_RTOL, max_events=5000) -> Reference:
    """The first cascade of a grounded stack, integrated by scipy's DOP853 (module docstring)."""
    m = np.asarray(masses, float)
    n = m.size
    k, c = np.asarray(k, float), np.asarray(c, float)
    x0, v0 = np.asarray(x0, float), np.asarray(v0, float)

    def overlaps(y):
        d = -np.concatenate([y[:1], y[1:n]])  # delta_0 = -x_1, delta_j = -(x_{j+1} - x_j)
        v = y[n : 2 * n]
        dd = np.concatenate([-v[:1], v[:-1] - v[1:]])
        return d, dd

    def forces(y, active):
        d, dd = overlaps(y)
        dp = np.maximum(d, 0.0)
        return np.where(active, k * dp**1.5 + c * dp**0.25 * dd, 0.0), k * dp**1.5, dd

    def rhs(t, y, active):
        f, fel, dd = forces(y, active)
        v = y[n : 2 * n]
        a = (f - np.concatenate([f[1:], [0.0]])) / m - g
        return np.concatenate([v[:1], np.diff(v), a, [np.sum((f - fel) * dd)]])

    def bound(y):  # mass 1 cannot leave the ground unless pushed (issue 16)
        d0 = -y[0]
        return 0.5 * m[0] * y[n] ** 2 + 0.4 * k[0] * max(d0, 0.0) ** 2.5 - m[0] * g * d0

    def energy(y):
        d, _ = overlaps(y)
        x = y[0] + np.concatenate([[0.0], np.cumsum(y[1:n])])
        v = y[n : 2 * n]
        return 0.5 * m @ v**2 + g * m @ x + np.sum(0.4 * k * np.maximum(d, 0.0) ** 2.5) + y[-1]

    y = np.concatenate([x0[:1], np.diff(x0), v0, [0.0]])
    e0 = energy(y)
    d, dd = overlaps(y)
    active = ((d > 0) & (k * np.maximum(d, 0) ** 1.5 + c * np.maximum(d, 0) ** 0.25 * dd > 0)) | (
        (d == 0) & (dd > 0))
    touched = bool(active.any())
    t_last = np.full(n, np.nan)
    v_last = np.full((n, n), np.nan)
    top_frozen = top_rebound = False
    armed_bound, just_bound = True, False
    t, nev, status = 0.0, 0, "t_max"
    while nev <= max_events:
        v = y[n : 2 * n]
        if touched and not active[1:].any() and np.all(np.diff(v) >= 0) and (
                (not active[0] and v[0] >= 0) or (active[0] and -y[0] > 0 and (bound(y) < 0 or just_bound))):
            status = "complete"
            break
        events, kinds = [], []
        for j in range(n):
            if active[j]:
                def ev(t, z, j=j):  # F_j / delta^{1/4}, continued oddly below delta = 0
                    d, dd = overlaps(z)
                    val = k[j] * d[j] * abs(d[j]) ** 0.25 + c[j] * dd[j]
                    return val if val != 0 else np.copysign(1e-300, dd[j])  # no root at an exact 0
                ev.direction = -1
            else:
                def ev(t, z, j=j):  # delta for delta < 0, the unclamped force above
                    d, dd = overlaps(z)
                    if d[j] == 0:  # touching: a contact starts once the force is positive, not here
                        return -1e-300
                    return d[j] if d[j] < 0 else k[j] * d[j] ** 1.5 + c[j] * d[j] ** 0.25 * dd[j]
                ev.direction = 1
            events.append(ev)
            kinds.append(("contact", j))
        if active[0] and armed_bound and bound(y) > 0:
            events.append(lambda t, z: bound(z))
            events[-1].direction = -1
            kinds.append(("bound", 0))
        if not top_frozen and not active[n - 1] and np.isfinite(t_last[n - 1]) and g > 0 and v[-1] > 0:
            events.append(lambda t, z: z[2 * n - 1])
            events[-1].direction = -1
            kinds.append(("apex", n - 1))
        for ev in events:
            ev.terminal = True
        atol = np.concatenate([np.full(n, 1e-17), np.full(n, 1e-15), [1e-15]])
        sol = solve_ivp(functools.partial(rhs, active=active.copy()), (t, t_max), y, method="DOP853",
                        rtol=rtol, atol=atol, events=events)
        if sol.status == -1:
            raise RuntimeError(sol.message)
        hit = [i for i, te in enumerate(sol.t_events) if len(te)]
        if not hit:
            y, t = sol.y[:, -1], sol.t[-1]
            status = "t_max" if touched else "no contact"
            break
        i = min(hit, key=lambda i: sol.t_events[i][0])
        t, y = sol.t_events[i][0], sol.y_events[i][0]
        kind, j = kinds[i]
        nev += 1
        armed_bound, just_bound = kind == "contact", kind == "bound"
        if kind == "apex":
            top_frozen = True
        elif kind == "contact":
            if active[j] and not (top_frozen and j == n - 1):  # a push ended
                t_last[j], v_last[j] = t, y[n : 2 * n]
            if not active[j] and top_frozen and j == n - 1:
                top_rebound = True
            active[j] = not active[j]
            touched = True
    launch, t_launch = np.full(n, np.nan), np.full(n, np.nan)
    for i in range(n):  # the last push of mass i: interface i (below) or i + 1 (above)
        ends = [(t_last[j], v_last[j][i]) for j in (i, i + 1) if j < n and np.isfinite(t_last[j])]
        if ends:
            t_launch[i], launch[i] = max(ends)
    return Reference(status, t, launch, t_launch, top_frozen, top_rebound, nev, abs(energy(y) - e0))


def _masses(n):
    return 0.4 ** np.arange(n)  # geometric, ratio 0.4, bottom 1 kg


@functools.lru_cache(maxsize=None)
def _ref_drop(n, law, gap, g=G, v=1.0, t_max=2.0, rtol=REF_RTOL) -> Reference:
    """The reference for `hc.at_impact(stack, v, gap)` of the geometric stack (cached per case)."""
    m = _masses(n)
    k, c = law_parameters(m, law)
    return cascade_reference(m, k, c, g, np.arange(n) * gap, -v * np.ones(n), t_max=t_max, rtol=rtol)


def _stack(masses, law, g=G) -> hc.Stack:
    """The hc stack with the same parameters: Hertz(K) or Tsuji(K, eta(e), m*_j) per interface (one law
    with (n,) parameters, so that every design of n masses shares a compiled solve)."""
    m = np.asarray(masses, float)
    if law == "hertz":
        return hc.Stack(m, hc.Hertz(K), gravity=g)
    meff = np.concatenate([m[:1], m[:-1] * m[1:] / (m[:-1] + m[1:])])
    return hc.Stack(m, hc.Tsuji(np.full(m.size, K), np.full(m.size, hc.tsuji_eta(E)), meff), gravity=g)


def _ends_no_later(sol, ref) -> None:
    """hertz_chain's cascade end against the reference's literal rule: its rule also ends the cascade
    when the lower masses are bound to the ground or, as a group, can never reach the masses above
    again (`hertz_chain.simulation._cascade_over`), which the literal rule implies, so it ends no later
    (within one solver step: 0.5 contact times, < 2e-4 s here) and after the top mass's launch."""
    assert sol.status.ok, sol.status
    assert sol.launch_times[-1] <= sol.cascade_end_time <= ref.t_end + 2e-4


# ==================================================================== self-checks of the reference
def test_reference_single_impacts_closed_forms():
    # Hertz, g = 0: elastic, e = 1 (Hertz 1882; Johnson 1985 §11.1), to 1e-10.
    r = cascade_reference([0.3], [2e9], [0.0], 0.0, [0.0], [-1.7])
    assert r.status == "complete" and r.events == 1
    assert r.launch[0] == pytest.approx(1.7, rel=1e-10)
    # Hertz, gravity: energy conservation, it leaves the ground (delta = 0) at the impact speed, 1e-10.
    r = cascade_reference([0.2], [5e8], [0.0], G, [0.0], [-1.3])
    assert r.launch[0] == pytest.approx(1.3, rel=1e-10)
    assert r.energy_drift < 1e-10 * 0.5 * 0.2 * 1.3**2
    # Tsuji, clamped, g = 0: the calibrated eta(0.8) gives e = 0.8 (hertz_chain.calibration; exact in
    # the isolated impact to ~1e-11) at any speed and mass.
    m = 0.3
    for v in (0.5, 2.0):
        r = cascade_reference([m], [K], [hc.tsuji_eta(E) * np.sqrt(m * K)], 0.0, [0.0], [-v])
        assert r.launch[0] == pytest.approx(E * v, rel=1e-9)


@pytest.mark.parametrize("law,e", [("hertz", 1.0), ("tsuji", E)])
def test_reference_two_mass_rigid_limit(law, e):
    # Paper Eqs 1-2 (momentum and restitution of an isolated two-body impact), g = 0, gaps large enough
    # that the impacts do not overlap: mass 1 leaves the ground at e v, hits mass 2 (at -v):
    # v2' = v2 + (1+e) m1/(m1+m2) (v1 - v2), v1' = v1 - (1+e) m2/(m1+m2) (v1 - v2) < 0; mass 1 then
    # bounces off the ground at -e v1' < v2', and the cascade ends. Exact for compliant contacts that
    # never act together, to the calibration's 1e-11.
    m = np.array([1.0, 0.4])
    k, c = law_parameters(m, law)
    r = cascade_reference(m, k, c, 0.0, [0.0, 0.01], [-1.0, -1.0])
    v1, v2 = e * 1.0, -1.0
    v2p = v2 + (1 + e) * m[0] / m.sum() * (v1 - v2)
    v1p = v1 - (1 + e) * m[1] / m.sum() * (v1 - v2)
    assert r.status == "complete"
    assert r.launch[1] == pytest.approx(v2p, rel=1e-9)
    assert r.launch[0] == pytest.approx(-e * v1p, rel=1e-9)


def test_reference_energy_and_convergence():
    # Energy: kinetic + gravitational + elastic + dissipated is constant (Hertz: dissipated = 0);
    # measured 1.6e-11 J of 0.78 J (3 masses, 1 cm, gravity).
    r = _ref_drop(3, "hertz", 0.01)
    assert r.energy_drift < 1e-10 * 0.5 * _masses(3).sum()
    # Convergence in rtol (1e-12 vs 1e-13): the top launch agrees to 1e-9 (measured 6.6e-12 Tsuji 1 cm,
    # 8.9e-12 the issue's stack, at most 3e-11 over the matrix of test 1).
    a, b = _ref_drop(3, "tsuji", 0.01), _ref_drop(3, "tsuji", 0.01, rtol=1e-13)
    assert a.launch[-1] == pytest.approx(b.launch[-1], rel=1e-9)
    assert a.t_end == pytest.approx(b.t_end, rel=1e-9)


# ==================================================================== hertz_chain against the reference
# (n, law, gap): the reference's cascade end (s) and top launch (m/s) at rtol 1e-12 (converged to <3e-11):
#   3 hertz 1mm 0.004194 / 3.0807712574; 1cm 0.200026 / 3.0060468583; 5cm 0.630425 / 2.6739384178 (apex,
#   landed back: a rebound); 3 tsuji 1mm 0.031292 / 1.9697908513; 1cm 0.179169 / 1.8829753487; 5cm
#   0.697261 / 1.4971286707 (apex, landed back); 6 hertz 1mm 0.004194 / 10.923911807; 6 tsuji 1cm
#   0.298747 / 5.1661997662. Chaotic settling (the end is not reproducible, the top launch is):
#   6 tsuji 1mm end 0.287670 (0.287674 at rtol 1e-13); 6 tsuji 5cm end 1.0306 (none before 2 s at
#   1e-13); 6 hertz 1cm and 5cm: elastic, no end before 2 s (12 s and 18 s at 1e-12, not converged).
CLEAN = [(3, "hertz", 1e-3), (3, "hertz", 1e-2), (3, "hertz", 5e-2), (3, "tsuji", 1e-3),
         (3, "tsuji", 1e-2), (6, "hertz", 1e-3), (6, "tsuji", 1e-2)]
# the issue's stack settles for 0.65 s after the top's launch: its end moves by ~1 ms with the
# integration error (its literal, unfrozen top launch differs by 2.7e-4 between rtol 1e-11 and 1e-13)
CHAOTIC_END = [(3, "tsuji", 5e-2), (6, "tsuji", 1e-3), (6, "tsuji", 5e-2)]
NO_END_BEFORE_2S = [(6, "hertz", 1e-2), (6, "hertz", 5e-2)]


def _run(n, law, gap, **kw):
    stack = _stack(_masses(n), law)
    return hc.simulate(stack, hc.at_impact(stack, 1.0, gap), tolerances=TIGHT, throw=False, **kw)


@pytest.mark.parametrize("n,law,gap", CLEAN)
def test_gapped_drop_matches_reference(n, law, gap):
    # Reference: cascade_reference (scipy DOP853, rtol 1e-12). Top launch to 1e-6 relative; the status
    # from the reference's event record; the end within one solver step of the reference's (the solve
    # checks the rule at its accepted steps: 0.5 contact times at most, < 2e-4 s here).
    ref = _ref_drop(n, law, gap)
    assert ref.status == "complete"
    sol = _run(n, law, gap)
    _ends_no_later(sol, ref)
    assert sol.launch_velocities[-1] == pytest.approx(ref.launch[-1], rel=1e-6)
    assert sol.gain == pytest.approx(ref.launch[-1] / 1.0, rel=1e-6)
    assert sol.launch_times[-1] == pytest.approx(ref.t_launch[-1], abs=1e-7)


@pytest.mark.parametrize("n,law,gap", CHAOTIC_END + NO_END_BEFORE_2S)
def test_gapped_drop_long_settling(n, law, gap):
    # Reference: cascade_reference. The top mass's launch is frozen at its apex (reproducible to 3e-11);
    # the literal end of the cascade comes after a long, chaotic settling (or not before 2 s): hertz_chain
    # must either end it (by its rule, no later) with the reference's top launch, or report an
    # incomplete run.
    # the reference is run to 0.5 s: hertz_chain's rule ends these before 0.1 s, and the reference's top
    # launch at 0.5 s agreed with hertz_chain's to 1e-6 as the one from runs to 2 s did
    ref = _ref_drop(n, law, gap, t_max=0.5)
    assert ref.launch[-1] == pytest.approx(_ref_drop(n, law, gap, t_max=0.5, rtol=1e-11).launch[-1], rel=1e-8)
    sol = _run(n, law, gap)
    if sol.status.ok:
        assert sol.launch_times[-1] <= sol.cascade_end_time <= ref.t_end + 2e-4
        assert sol.launch_velocities[-1] == pytest.approx(ref.launch[-1], rel=1e-6)
    else:
        assert sol.status in (Status.INCOMPLETE_T_MAX, Status.INCOMPLETE_MAX_STEPS), sol.status
        assert sol.t_final < ref.t_end or ref.status != "complete"


def test_free_flight_steps_end_before_any_contact_and_cost_few_steps():
    # `Tolerances.flight_steps` (docs/solver-defaults.md, "Free flights"): a step longer than `max_step`
    # contact times is taken only where every gap is open, and ends before any contact begins (the
    # exact closure times of free parabolas). The launch is the reference's (test above: 5 cm, rel 1e-6).
    # The 3-mass Tsuji stack with 5 cm gaps: its free flights (every gap open) last ~175 contact times
    # until the cascade ends, which the `max_step` bound of 0.5 contact times alone would cover in
    # >= 349 steps; with flight steps each of its ~5 flights costs some 20 (the growth after a release,
    # the approach to the next onset), less than half in all.
    sol = _run(3, "tsuji", 5e-2)
    assert sol.status.ok
    t, d, T = np.asarray(sol.steps.t), np.asarray(sol.steps.overlaps), float(sol.scales.time)
    dt, open_ = np.diff(t), np.all(d < 0, axis=1)
    long = dt > 0.5 * T * (1 + 1e-9)
    assert long.sum() > 10
    assert np.all(open_[:-1][long] & open_[1:][long])
    free = open_[:-1] & open_[1:]
    bound_alone = dt[free].sum() / (0.5 * T)  # steps the max_step bound alone would need
    assert bound_alone > 300
    assert free.sum() < bound_alone / 2
    assert sol.launch_velocities[-1] == pytest.approx(_ref_drop(3, "tsuji", 5e-2).launch[-1], rel=1e-6)


def _onset_steps(sol):
    """Per contact onset of a solve's step history (an interface open at one accepted point, closed at
    the next): the overlap at the one of those two points nearer the touch (units of L; a landed step
    ends within rounding of it, on either side) and the steps within 0.05 T after that point."""
    t, d = np.asarray(sol.steps.t), np.asarray(sol.steps.overlaps)
    T, L = float(sol.scales.time), float(sol.scales.length)
    k, j = np.nonzero((d[:-1] < 0) & (d[1:] >= 0))
    near = [kk + 1 if abs(d[kk + 1, jj]) < abs(d[kk, jj]) else kk for kk, jj in zip(k, j)]
    return [(d[m, jj] / L, int(np.sum((t > t[m]) & (t <= t[m] + 0.05 * T)))) for m, jj in zip(near, j)]


def test_onsets_are_landed_and_stepped_through_in_s():
    # `Tolerances.land_onsets` (docs/solver-defaults.md, "Onsets met"): every contact onset of the 3-mass
    # Tsuji drop with 5 cm gaps (three, each after a free flight) is met by a step end within
    # ONSET_OVERLAP = 1e-9 L of the touch (measured 2e-14..5e-14 L, either side: the parabola of free flight
    # is exact); the window after it, stepped in s = (t - t*)^{1/4}, takes fewer than half the steps of the plain solve
    # over its first 0.05 T (measured 17-31 against 44-67), and the launch is the scipy reference's
    # (DOP853 at rtol 1e-12, `cascade_reference`) to 1e-8 both ways (measured 5.6e-11 and 5.3e-11).
    from hertz_chain._solver import ONSET_OVERLAP

    ref = _ref_drop(3, "tsuji", 5e-2).launch[-1]
    stack = _stack(_masses(3), "tsuji")
    state = hc.at_impact(stack, 1.0, 5e-2)
    on = hc.simulate(stack, state, tolerances=TIGHT)
    off = hc.simulate(stack, state, tolerances=hc.Tolerances(rtol=1e-11, atol=1e-11, land_onsets=False))
    landed, plain = _onset_steps(on), _onset_steps(off)
    assert len(landed) == len(plain) == 3
    assert all(abs(d) <= ONSET_OVERLAP for d, _ in landed)
    assert all(abs(d) > 10 * ONSET_OVERLAP for d, _ in plain)  # the plain solve: 1e-7..2e-6 L before
    assert all(2 * a < b for (_, a), (_, b) in zip(landed, plain))
    assert on.num_steps < off.num_steps
    assert on.launch_velocities[-1] == pytest.approx(ref, rel=1e-8)
    assert off.launch_velocities[-1] == pytest.approx(ref, rel=1e-8)


def test_dense_output_in_an_onset_window_is_the_motion():
    # A sphere dropped at 1 m/s onto a Hertz ground (g = 0) touches at t = 0: its first 0.05 T are an onset
    # window, stepped in s. The saved grid there (the solver's dense output, mapped to s) is the overlap of
    # an independent scipy DOP853 solve (rtol 1e-13) of m x'' = -k x^{3/2} to 1e-9 L.
    from scipy.integrate import solve_ivp

    m, k, v = 0.1, 1e9, 1.0
    stack = hc.Stack([m], [hc.Hertz(k)], gravity=0.0)
    T = float(hc.simulate(stack, hc.at_impact(stack, v), t_max=1e-6).scales.time)
    L = float(hc.simulate(stack, hc.at_impact(stack, v), t_max=1e-6).scales.length)
    ts = np.linspace(0.0, 0.05 * T, 41)[1:]
    sol = hc.simulate(stack, hc.at_impact(stack, v), ts=ts, until="t_max", t_max=0.06 * T)
    ref = solve_ivp(lambda t, y: [y[1], -k / m * max(y[0], 0.0) ** 1.5], (0.0, ts[-1]), [0.0, v], t_eval=ts,
                    method="DOP853", rtol=1e-13, atol=1e-20 * L)
    got = -np.asarray(sol.grid.positions)[:, 0]
    assert np.max(np.abs(got - ref.y[0])) < 1e-9 * L


def test_closure_times_are_the_first_positive_root():
    # Reference: numpy.roots of delta + r t + a t^2 / 2 (companion-matrix eigenvalues), the smallest
    # positive real root, inf if none; random gaps, rates and accelerations of both signs, a = 0 too.
    from hertz_chain._solver import _closure_times

    rng = np.random.default_rng(7)
    delta = -10 ** rng.uniform(-6, -1, 400)
    rate = rng.normal(0, 1, 400)
    acc = np.where(rng.random(400) < 0.2, 0.0, rng.normal(0, 10, 400))
    got = np.asarray(_closure_times(delta, rate, acc))
    for dj, rj, aj, tj in zip(delta, rate, acc, got):
        roots = np.roots([aj / 2, rj, dj] if aj != 0 else [rj, dj])
        pos = [x.real for x in roots if abs(x.imag) <= 1e-12 * abs(x) and x.real > 0]
        if pos:
            assert tj == pytest.approx(min(pos), rel=1e-9)
        else:
            assert tj == np.inf


def test_the_default_time_limit_covers_slow_late_collisions_of_a_stiff_gapped_stack():
    """Three masses halving, 1 cm gaps, g = 0, stiff Hertz contacts (1e15 N/m^1.5, contacts of ~1e-5 of the
    flight times): mass 1, bounced off the ground, catches mass 2 again late, at 0.0425 s by the rigid
    event-driven model, past the default limit the gaps counted twice gave (0.0414 s: "t_max reached", a
    review). With the default limit the launch velocities are the rigid model's (elastic, e = 1) to 1e-6."""
    m = np.array([1.0, 0.5, 0.25])
    stack = hc.Stack(m, hc.make_law("hertz", stiffness=1e15), gravity=0.0)
    state = hc.at_impact(stack, 1.0, 0.01)
    rigid = hc.simulate_rigid(m, np.asarray(state.velocities), np.asarray(state.positions) - np.r_[0.0,
                              np.asarray(state.positions)[:-1]], 1.0, 1.0)
    assert rigid.final_time > 0.0414
    np.testing.assert_allclose(hc.launch_velocity(stack, state), rigid.launch_velocities, rtol=1e-6)


def test_issue_16_example_gain_and_until_t_max():
    # Issue 16: masses [1, 0.4, 0.16] kg, 5 cm gaps, 1 m/s, Tsuji 1e9 N/m^1.5, e = 0.8, standard gravity.
    # Before the fix hertz_chain reported a gain of 0.1718 (the top mass's velocity after its last
    # landing before t_max). Reference: cascade_reference, gain 1.4971286707 (the top mass is launched at
    # 0.0500 s and passes its apex before the stack settles at 0.697 s; its landing back is a rebound).
    # Literal rule without the apex freeze: 0.0297, not reproducible (2.3e-5 between rtol 1e-12/1e-13).
    ref = _ref_drop(3, "tsuji", 0.05)
    assert ref.launch[-1] == pytest.approx(1.4971286707, rel=1e-9)
    sol = _run(3, "tsuji", 0.05)
    assert sol.status.ok
    assert sol.gain == pytest.approx(ref.launch[-1], rel=1e-6)
    assert sol.gain != pytest.approx(0.1718, abs=1e-3)
    # the launch is frozen at the end: the same when the run goes on to 100x the cascade's end (rebounds)
    long = _run(3, "tsuji", 0.05, until="t_max", t_max=100 * sol.cascade_end_time, max_steps=600_000)
    assert long.status == Status.COMPLETE_WITH_REBOUNDS, long.status
    assert long.gain == pytest.approx(sol.gain, rel=1e-9)
    assert long.cascade_end_time == pytest.approx(sol.cascade_end_time, rel=1e-12)
    assert long.t_final == pytest.approx(100 * sol.cascade_end_time, rel=1e-12)
    # a step budget that covers the cascade but not the run to t_max: incomplete (the rebounds asked for
    # are cut short), the cascade's launch still the same
    short = _run(3, "tsuji", 0.05, until="t_max", t_max=100 * sol.cascade_end_time,
                 max_steps=sol.num_steps + 500)
    assert short.status == Status.INCOMPLETE_MAX_STEPS and not short.ok
    assert short.cascade_end_time == pytest.approx(sol.cascade_end_time, rel=1e-12)
    assert short.gain == pytest.approx(sol.gain, rel=1e-9)


# ==================================================================== a run must actually run
def test_resting_stack_is_not_complete_at_t0():
    # A stack resting on the ground (hc.resting): every contact between masses carries the weight above
    # it and never opens: by the literal rule the cascade never ends (the
    # reference, run 0.05 s, finds no event at all): t_max comes first. hertz_chain's rule counts masses
    # bound to the ground as at rest and may call it complete, but only after a step
    # and with nothing launched (|v| < 1e-6 m/s).
    stack = _stack(_masses(3), "tsuji")
    state = hc.resting(stack)
    k, c = law_parameters(_masses(3), "tsuji")
    ref = cascade_reference(_masses(3), k, c, G, np.asarray(state.positions), np.zeros(3), t_max=0.05)
    assert ref.status == "t_max" and ref.events == 0
    sol = hc.simulate(stack, state, tolerances=TIGHT, throw=False)
    assert sol.num_steps > 0 and sol.t_final > 0
    if sol.status.ok:
        assert sol.status == Status.COMPLETE and sol.cascade_end_time > 0
        assert np.all(np.abs(np.nan_to_num(sol.launch_velocities)) < 1e-6)
    else:
        assert sol.status == Status.INCOMPLETE_T_MAX and np.isnan(sol.cascade_end_time), sol.status


def test_stack_thrown_upward():
    # x_1 = 0, 1 cm gaps, every mass thrown up at 1 m/s: it flies 0.204 s, lands at -1 m/s and cascades.
    # Reference: cascade_reference from the same state; top launch to 1e-6.
    m, gap = _masses(3), 0.01
    stack = _stack(m, "tsuji")
    x0, v0 = np.arange(3) * gap, np.ones(3)
    k, c = law_parameters(m, "tsuji")
    ref = cascade_reference(m, k, c, G, x0, v0)
    assert ref.status == "complete" and ref.t_end > 2 / G
    sol = hc.simulate(stack, hc.State(x0, v0), tolerances=TIGHT, throw=False)
    assert sol.num_steps > 0 and sol.t_final > 2 / G
    _ends_no_later(sol, ref)
    assert sol.launch_velocities[-1] == pytest.approx(ref.launch[-1], rel=1e-6)


def test_zero_speed_drop():
    # hc.at_impact(stack, 0.0, 1 cm): mass 1 touches the ground at rest, the others fall onto it.
    # Reference: cascade_reference from the same state; top launch to 1e-6.
    m, gap = _masses(3), 0.01
    stack = _stack(m, "tsuji")
    k, c = law_parameters(m, "tsuji")
    ref = cascade_reference(m, k, c, G, np.arange(3) * gap, np.zeros(3))
    assert ref.status == "complete"
    sol = hc.simulate(stack, hc.at_impact(stack, 0.0, gap), tolerances=TIGHT, throw=False)
    assert sol.num_steps > 0 and sol.t_final > 0
    _ends_no_later(sol, ref)
    assert sol.launch_velocities[-1] == pytest.approx(ref.launch[-1], rel=1e-6)


def test_no_contact():
    # g = 0, every mass moving up, the upper ones faster: nothing ever touches (reference: no event).
    m = _masses(3)
    x0, v0 = np.array([0.0, 0.01, 0.02]), np.array([0.1, 0.2, 0.3])
    k, c = law_parameters(m, "hertz")
    ref = cascade_reference(m, k, c, 0.0, x0, v0, t_max=1.0)
    assert ref.status == "no contact" and ref.events == 0
    stack = _stack(m, "hertz", g=0.0)
    sol = hc.simulate(stack, hc.State(x0, v0), tolerances=TIGHT, throw=False)
    assert sol.status == Status.NO_CONTACT, sol.status
    assert not sol.status.ok


def test_extreme_mass_ratio_does_not_stop_mid_cascade():
    # masses [1e6, 1e-6] kg, Hertz 1e9, 0.25 m gap, 1 m/s, gravity. The heavy mass's ground contact
    # lasts 0.2 s (2.94 delta_max / v, delta_max = (5 m v^2/4k)^{2/5} = 6.9 cm), the light contact a few
    # microseconds: a t_max scaled by the shortest contact would stop mid-cascade. Reference:
    # cascade_reference (the light mass meets the heavy one while it still rises: the cascade ends there).
    m = np.array([1e6, 1e-6])
    k, c = law_parameters(m, "hertz")
    ref = cascade_reference(m, k, c, G, [0.0, 0.25], [-1.0, -1.0])
    assert ref.status == "complete"
    stack = _stack(m, "hertz")
    sol = hc.simulate(stack, hc.at_impact(stack, 1.0, 0.25), tolerances=TIGHT, throw=False)
    if sol.status.ok:
        _ends_no_later(sol, ref)
        assert sol.gain == pytest.approx(ref.launch[-1], rel=1e-6)
    else:
        assert sol.status in (Status.INCOMPLETE_T_MAX, Status.INCOMPLETE_MAX_STEPS), sol.status


# ==================================================================== gravity off: the former behaviour
@pytest.mark.parametrize("law,gap", [("hertz", 0.0), ("hertz", 1e-3), ("tsuji", 0.0), ("tsuji", 1e-2)])
def test_gravity_off_matches_reference(law, gap):
    # Reference: cascade_reference with g = 0 (touching and gapped); top launch to 1e-6, status complete.
    ref = _ref_drop(3, law, gap, g=0.0)
    assert ref.status == "complete"
    stack = _stack(_masses(3), law, g=0.0)
    sol = hc.simulate(stack, hc.at_impact(stack, 1.0, gap), tolerances=TIGHT, throw=False)
    assert sol.status == Status.COMPLETE, sol.status
    assert sol.launch_velocities[-1] == pytest.approx(ref.launch[-1], rel=1e-6)
    assert sol.gain == pytest.approx(ref.launch[-1], rel=1e-6)


# ==================================================================== a launch while a neighbour still pushes
# The paper's six-mass MVG stack (Eq 15: m_1 = 8.4 kg, m_6 = 0.1008 kg), Tsuji e = 0.8, dropped at 1 m/s
# under gravity with small gaps (the regime where the contacts overlap): an interface often opens while
# the contact below it still pushes its lower mass hard (850 N at the top's release in the first case),
# so the overlap is no straight line between the release and the first accepted point after it.
# Before the fix (`_end_of_contacts` extrapolated back linearly from that point) the launch times here were
# off by up to 5e-8 s and the launch velocities, under gravity, by up to 3.2e-7 relative even at rtol 1e-11
# (and by 4.5e-6 in batched sweeps of five-mass stacks at the default tolerances).
MVG6 = 8.4 * 0.012 ** (np.arange(6) / 5)
NEIGHBOUR_PUSHES = [(3e-5, 1.4e9), (2e-5, 4e9), (1.3e-4, 3e8)]  # (gap m, stiffness N/m^1.5)


@functools.lru_cache(maxsize=None)
def _mvg6(gap, k):
    m = MVG6
    meff = np.concatenate([m[:1], m[:-1] * m[1:] / (m[:-1] + m[1:])])
    kk = np.full(m.size, k)
    ref = cascade_reference(m, kk, hc.tsuji_eta(E) * np.sqrt(meff * kk), G, np.arange(m.size) * gap,
                            -np.ones(m.size), t_max=2.0)
    stack = hc.Stack(m, hc.Tsuji(kk, np.full(m.size, hc.tsuji_eta(E)), meff), gravity=G)
    return ref, stack, hc.at_impact(stack, 1.0, gap)


@pytest.mark.parametrize("gap,k", NEIGHBOUR_PUSHES)
def test_launch_while_a_neighbour_pushes(gap, k):
    # Reference: cascade_reference (scipy DOP853 at rtol 1e-12, every release located by its event
    # finder; converged to 2e-11 in velocity and 6e-14 s against rtol 1e-13). Every mass's launch
    # velocity and time: at rtol 1e-11 to 2e-8 relative and 5e-10 s (measured <= 5.3e-9 and 6e-11 s;
    # before the fix 3.2e-7 and 2.6e-8 s), at the default tolerances (what users run) to 1e-7 and 2e-9 s
    # (measured <= 5.5e-8 and 1.8e-10 s; before 3.9e-7 and 5e-8 s).
    ref, stack, state = _mvg6(gap, k)
    assert ref.status == "complete"
    for tol, dv, dt in ((TIGHT, 2e-8, 5e-10), (None, 1e-7, 2e-9)):
        sol = hc.simulate(stack, state, tolerances=tol)
        assert sol.status.ok
        np.testing.assert_allclose(sol.launch_velocities, ref.launch, rtol=dv)
        np.testing.assert_allclose(sol.launch_times, ref.t_launch, rtol=0, atol=dt)


def test_launch_while_a_neighbour_pushes_batched():
    # The same designs in one batched solve without a step history (`hertz-chain sweep`'s path), at the
    # default tolerances: to 1e-7 relative and 2e-9 s (measured 5.4e-8 and 3.9e-10 s; before the fix
    # 4.1e-7 and 5e-8 s).
    refs, stacks, states = zip(*(_mvg6(gap, k) for gap, k in NEIGHBOUR_PUSHES))
    sol = hc.simulate_batch(hc.stack_designs(stacks), hc.State(np.stack([s.positions for s in states]),
                                                               np.stack([s.velocities for s in states])),
                            save_steps=False)
    assert np.all(sol.ok)
    np.testing.assert_allclose(sol.launch_velocities, np.array([r.launch for r in refs]), rtol=1e-7)
    np.testing.assert_allclose(sol.launch_times, np.array([r.t_launch for r in refs]), rtol=0, atol=2e-9)


# ==================================================================== the error tail of damped laws
# Five-mass Tsuji stacks (e = 0.8, gravity, 1 m/s) that had the largest errors at the default tolerances
# among 200 random designs (docs/solver-defaults.md, "The release term"): (masses kg, k N/m^1.5, gap m).
TAIL = [([8.4, 2.492914, 1.063028, 0.27116, 0.1008], 1.775e8, 1.423e-5),
        ([8.4, 2.567626, 0.835458, 0.348791, 0.1008], 5.789e9, 1.104e-4),
        ([8.4, 3.273594, 0.809495, 0.306038, 0.1008], 1.117e8, 4.503e-6)]


@pytest.mark.parametrize("masses,k,gap", TAIL)
def test_damped_tail_at_default_tolerances(masses, k, gap):
    # Reference: cascade_reference (scipy DOP853 at rtol 1e-12, restarted at every onset and release;
    # converged to 2e-11 against rtol 1e-13). At the default tolerances every mass's launch velocity to
    # 1e-8 relative and every launch time to 1e-10 s (measured <= 3.2e-9 and 5e-12 s). With the onset
    # proxy's first term only (no release term) the errors were up to 2.5e-7 and 2.5e-9 s.
    m = np.asarray(masses)
    meff = np.concatenate([m[:1], m[:-1] * m[1:] / (m[:-1] + m[1:])])
    kk = np.full(m.size, k)
    ref = cascade_reference(m, kk, hc.tsuji_eta(E) * np.sqrt(meff * kk), G, np.arange(m.size) * gap,
                            -np.ones(m.size), t_max=2.0)
    stack = hc.Stack(m, hc.Tsuji(kk, np.full(m.size, hc.tsuji_eta(E)), meff), gravity=G)
    sol = hc.simulate(stack, hc.at_impact(stack, 1.0, gap))
    assert ref.status == "complete" and sol.status.ok
    np.testing.assert_allclose(sol.launch_velocities, ref.launch, rtol=1e-8)
    np.testing.assert_allclose(sol.launch_times, ref.t_launch, rtol=0, atol=1e-10)
