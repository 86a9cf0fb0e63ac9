"""Event-driven simulator of rigid point masses in a chain or a dropped stack (plain numpy).

Each impact is instantaneous and binary, resolved with momentum conservation and a coefficient of
restitution (seed paper Eqs 1–2; ground: `V_1 = −e_{1,0} v_1`). Between impacts the masses fly freely
under uniform gravity `g` (may be 0): the relative motion of two masses is uniform (gravity cancels) and
the height of mass 1 above the ground is quadratic in time, so every contact time is computed in closed
form — there is no time stepping.

Layout (`notes/CONVENTIONS.md`): masses bottom first, velocities upward-positive, interface 0 =
ground–mass 1, interface `j` = mass `j` – mass `j+1` (array indices `j−1`, `j`).

**Rules (deterministic).**

* *Restitution.* `restitution` is a scalar or an `(n,)` array over interfaces 0..n−1. The ground exists
  if and only if `ground_restitution` is given; it then is the ground's restitution (it may exceed 1,
  an 'active ground', Eq 19) and entry 0 of `restitution` is never used. Pair restitutions lie in
  `[0, 1]` (0: perfectly plastic, the pair moves on together).
* *Order.* The next event is the earliest predicted contact. Contacts whose times agree within a
  relative tolerance (`1e-12`·t) count as simultaneous and the lowest interface goes first; the
  others follow as separate binary impacts at the same instant (so a touching stack, zero gaps, is
  resolved as ground–1, then 1–2, … and any re-collision at that instant).
* *Approach.* Two bodies collide only if they touch and close at a speed above `1e-12 × v_scale`
  (`v_scale` = the largest initial speed, or 1): round-off never creates spurious impacts.
* *Stopping.* The cascade is over — normal return — as soon as the system *separates* after at least
  one impact: every pair has `v_{j+1} − v_j >= 0` and, with a ground, `v_1 >= 0` or mass 1 held on the
  ground (checked after every impact, with the tolerance above) — the same rule as the compliant
  simulator's (`hertz_chain.simulation`). A stack released at rest above the ground, or thrown upward,
  is followed until it has landed and separated; where nothing ever meets the run returns at once
  with no collision ("no contact"). Later ballistic returns under gravity (mass 1 falling back to the ground after the
  cascade) are a new drop and are not followed.
* *The top mass's apex.* Under gravity, an impact on the top mass after it has passed the apex of its
  flight from its last impact (it lands again) is a rebound: it changes the velocities but no launch
  velocity (as in the compliant simulator, whose top interface is then frozen).
* *Ground support.* Mass 1 at the ground with zero velocity under gravity is held by the ground (it
  does not sink) while the bodies above move; a second body *resting* on it with zero relative
  velocity under gravity (resting contact) is outside the impulsive model and raises `SolverError`.
* *Limits.* Reaching `max_collisions` impacts, or a next impact later than `t_max`, before the system
  separates raises `SolverError` (inelastic collapse has infinitely many impacts in finite time). The
  error carries the run so far as `error.result` (a `RigidResult`), so launch velocities stay readable.
  A collapsing clump without gravity (e.g. three bodies in a line with `e < 7 − 4√3`, McNamara & Young
  1992) ends normally once its relative speeds fall below the approach floor: it then moves as one body
  at its centre-of-mass velocity.

**Gravity.** The paper neglects gravity during the impacts (Section 2). With `gravity > 0` and a
ground, the slow lower masses of a dropped stack usually fall back onto each other and onto the
ground after the cascade (gravity changes their velocities by `g·Δt` between impacts, comparable to
their post-cascade speeds) and settle: the system then never separates, and the run ends in
`SolverError` (collapse or resting contact) whose `.result` still holds the top mass's launch. For the
paper's cascade use `gravity = 0` with the impact velocity as initial velocity.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .errors import ParameterError, SolverError
from .rigid import _arr, _show

__all__ = ["RigidResult", "RigidBatchResult", "simulate_rigid", "simulate_rigid_batch", "COLLISION_DTYPE"]

COLLISION_DTYPE = np.dtype(
    [("time", "f8"), ("interface", "i8"), ("before", "f8", (2,)), ("after", "f8", (2,))]
)
"""One impact: time (s), interface index, velocities `(lower, upper)` before and after (m/s).
For the ground (interface 0) the lower body is the ground, velocity 0."""

_RTOL_T = 1e-12
_RTOL_V = 1e-12
#: what a run goes on until (`simulate_rigid`, `simulate_rigid_batch`)
UNTIL = ("separated", "top_launch")


@dataclasses.dataclass(frozen=True)
class RigidResult:
    """Result of `simulate_rigid` (SI units).

    * `collisions`: structured array (`COLLISION_DTYPE`: `time`, `interface`, `before` (2,),
      `after` (2,)), in time order.
    * `initial_velocities` `(n,)`; `final_velocities` `(n,)`: at `final_time` (time of the last impact,
      0 if none), gravity included.
    * `launch_velocities` `(n,)`: each mass's velocity just after its last impact (before gravity acts
      further); a mass that never collides keeps its initial velocity. `launch_times` `(n,)`: time of
      that last impact (0 for a mass that never collides).
    * `final_gaps` `(n,)`: `gaps[0]` = height of mass 1 above the ground (NaN without a ground), `gaps[j]`
      the gap between masses `j` and `j+1`, at `final_time`.
    * `gain` (property): the top's launch velocity over mass 1's initial speed (Eq 19's `G_n` for a
      gapped stack at g = 0; see the property).
    """

    collisions: np.ndarray
    initial_velocities: np.ndarray
    final_velocities: np.ndarray
    launch_velocities: np.ndarray
    launch_times: np.ndarray
    final_gaps: np.ndarray
    final_time: float
    n_collisions: int

    @property
    def gain(self) -> float:
        """`launch velocity of the top mass / |initial velocity of mass 1|`.

        For a dropped stack started at impact (`v_i = −v_ff`) with `gravity = 0` and independent
        collisions (gaps wide enough) this is the paper's `G_n = V_n/v_ff` (Eq 19); for a horizontal chain
        struck by mass 1 it is Eq 13's `G_n = V_n/v_1`. Under gravity it differs from Eq 19 (a review:
        the six-mass MVG stack of R = 0.012, e = 0.8 with 1 cm gaps and g = 9.81 m/s^2, `until = "top_launch"`, gives 4.8628
        against Eq 19's 5.0407: gravity slows the masses between impacts), and with `gaps[0] > 0` mass 1's
        impact speed differs from its initial speed: divide by that yourself.

        **Raises:** `ParameterError` where mass 1 starts at rest (`velocities[0] = 0`).
        """
        v1 = abs(float(self.initial_velocities[0]))
        if v1 == 0:
            raise ParameterError("velocities[0]", 0.0, "gain needs a moving mass 1 (|v_1| > 0)")
        return float(self.launch_velocities[-1]) / v1


def _ro(a) -> np.ndarray:
    a = np.array(a)
    a.setflags(write=False)
    return a


def _contact_time(s: float, u: float, a: float, vtol: float) -> float:
    """Smallest `t >= 0` at which the gap `s + u t + a t²/2` (`s >= 0`, `a <= 0`) closes with speed > vtol.

    Returns `inf` if never; `nan` for a resting contact (`s = 0`, `|u| <= vtol`, `a < 0`).
    """
    if s <= 0.0:
        if u < -vtol:
            return 0.0
        if a < 0.0:
            if abs(u) <= vtol:
                return np.nan
            return 2.0 * u / (-a)  # separating now, back later (ballistic return)
        return np.inf
    if a == 0.0:
        return s / -u if u < -vtol else np.inf
    big_a = -a
    root = np.sqrt(u * u + 2.0 * big_a * s)
    return 2.0 * s / (root - u) if u <= 0.0 else (u + root) / big_a


def _check_max_collisions(x) -> int:
    """A positive integer (`ParameterError` naming `max_collisions` for text, NaN or a fraction)."""
    try:
        ok = not isinstance(x, bool) and int(x) == x and x >= 1
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ParameterError("max_collisions", x, "a positive integer")
    return int(x)


def _first_bad(name: str, x: np.ndarray, ok: np.ndarray) -> tuple[str, float]:
    """The name and value of the first entry of `x` where `ok` is False: `("masses[3, 1]", -0.2)` (a
    review: the batch's messages read `masses = 'non-positive or non-finite'`)."""
    idx = tuple(int(i) for i in np.argwhere(~ok)[0])
    return f"{name}[{', '.join(map(str, idx))}]", float(x[idx])


def simulate_rigid(
    masses,
    velocities,
    gaps,
    restitution,
    ground_restitution=None,
    gravity=0.0,
    *,
    t_max=np.inf,
    max_collisions=100_000,
    until: str = "separated",
) -> RigidResult:
    """Event-driven rigid simulation of a chain (no ground) or a dropped stack (with ground).

    Parameters (SI): `masses` `(n,)` kg, bottom first, `> 0`; `velocities` `(n,)` m/s upward-positive;
    `gaps` `(n,)` m, `>= 0`: `gaps[0]` the height of mass 1 above the ground (ignored without a
    ground), `gaps[j]` the gap between masses `j` and `j+1`; `restitution` scalar or `(n,)` over
    interfaces (entry 0 unused, see the module rules), each in `[0, 1]` (0: perfectly plastic); `ground_restitution`: None
    (no ground) or `>= 0` (may exceed 1); `gravity` `>= 0` m/s², acting downward; `t_max` s;
    `max_collisions` a positive integer; `until`: `"separated"` (the stopping rule of the module
    docstring) or `"top_launch"`: also stop, normally, as soon as the top mass's launch velocity is final
    (under gravity, launched upward by an impact, and either its next impact would come after the apex of
    that flight, which the apex rule makes a rebound, or, on a ground with `e <= 1`, the masses below
    cannot rise to it before that apex: their energy, which only falls while the top is not hit, is less
    than `m_{n-1} g` times its height). A dropped stack's lower masses, which go on bouncing on the ground
    after the top has left (and under gravity often end in a resting contact or an inelastic collapse),
    are then not followed; the top's launch velocity and time are those of the full run.

    Each impact uses Eqs 1–2 of the seed paper (ground: `V_1 = −e_{1,0} v_1`). Contact times are exact
    (linear relative motion between masses, quadratic height of mass 1). Stops when the system
    separates (module rules); raises `SolverError` when `max_collisions` or `t_max` is reached first
    (e.g. inelastic collapse) or for a resting contact.

    With independent collisions (large, suitably chosen gaps, `gravity = 0`) the top's launch velocity
    reproduces Eq 13 (no ground) and Eq 19 (ground): see `tests/test_rigid_events.py`.
    """
    m = _arr(masses, "masses")
    if m.ndim != 1 or m.size < 1:
        raise ParameterError("masses", masses, "must be a 1-D array of at least one mass")
    n = m.size
    if not np.all(np.isfinite(m) & (m > 0)):
        raise ParameterError("masses", m.tolist(), "masses must be finite and > 0")
    v = _arr(velocities, "velocities").copy()
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ParameterError("velocities", velocities, f"must be {n} finite numbers (one per mass)")
    gp = _arr(gaps, "gaps").copy()
    if gp.shape != (n,) or not np.all(np.isfinite(gp) & (gp >= 0)):
        raise ParameterError("gaps", gaps, f"must be {n} finite numbers >= 0 (gaps[0] = height of mass 1)")
    e_arr = _arr(restitution, "restitution")
    if e_arr.ndim == 0:
        e_arr = np.full(n, float(e_arr))
    if e_arr.shape != (n,):
        raise ParameterError("restitution", restitution, f"must be a scalar or {n} values over interfaces 0..n-1")
    e_pair = e_arr[1:]
    if not np.all(np.isfinite(e_pair) & (e_pair >= 0) & (e_pair <= 1)):
        raise ParameterError("restitution", e_arr.tolist(), "pair restitution must lie in [0, 1]")
    ground = ground_restitution is not None
    if ground:
        e0 = _arr(ground_restitution, "ground_restitution")
        if e0.ndim:
            raise ParameterError("ground_restitution", _show(e0), "one number (or None: no ground)")
        e0 = float(e0)
        if not (np.isfinite(e0) and e0 >= 0):
            raise ParameterError("ground_restitution", ground_restitution, "must be >= 0 (may exceed 1) or None")
    else:
        e0 = np.nan
        gp[0] = np.nan
    g = _arr(gravity, "gravity")
    if g.ndim or not (np.isfinite(g) and g >= 0):
        raise ParameterError("gravity", _show(g), "one finite number >= 0 (acts downward)")
    g = float(g)
    t_max = _arr(t_max, "t_max")
    if t_max.ndim or not t_max > 0:
        raise ParameterError("t_max", _show(t_max), "one number > 0")
    t_max = float(t_max)
    max_collisions = _check_max_collisions(max_collisions)
    if until not in UNTIL:
        raise ParameterError("until", until, f"one of {', '.join(UNTIL)}")

    v0 = v.copy()
    vtol = _RTOL_V * (np.max(np.abs(v)) if np.any(v) else 1.0)
    launch_v = v.copy()
    launch_t = np.zeros(n)
    log: list[tuple] = []
    t = 0.0
    top_hit = False  # the top mass has had an impact (its apex is then launch_t + launch_v / g)

    def held() -> bool:
        return ground and g > 0 and gp[0] == 0.0 and abs(v[0]) <= vtol

    def result() -> RigidResult:
        coll = np.array(log, dtype=COLLISION_DTYPE) if log else np.zeros(0, dtype=COLLISION_DTYPE)
        coll.setflags(write=False)
        return RigidResult(
            collisions=coll,
            initial_velocities=_ro(v0),
            final_velocities=_ro(v),
            launch_velocities=_ro(launch_v),
            launch_times=_ro(launch_t),
            final_gaps=_ro(gp),
            final_time=float(t),
            n_collisions=len(log),
        )

    def fail(message: str) -> SolverError:
        err = SolverError(message)
        err.result = result()  # the run up to the failure: launch velocities etc. stay readable
        return err

    def separated() -> bool:
        if not log:
            return False  # nothing has happened yet: a run must run
        if n > 1 and np.any(np.diff(v) < -vtol):
            return False
        return not (ground and v[0] < -vtol)

    while not separated():
        if len(log) >= max_collisions:
            raise fail(
                f"rigid simulation: max_collisions = {max_collisions} reached at t = {t:.6g} s before the "
                f"masses separated (n = {n}, masses = {m.tolist()}); likely inelastic collapse: raise "
                "restitution or max_collisions"
            )
        hold = held()
        if hold:
            v[0] = 0.0
        # predicted contact time of every interface
        times = np.full(n, np.inf)
        if ground and not hold:
            times[0] = _contact_time(gp[0], v[0], -g, vtol)
        for j in range(1, n):  # small loop over interfaces (scalar closed forms)
            a = -g if (j == 1 and hold) else 0.0
            times[j] = _contact_time(gp[j], v[j] - v[j - 1], a, vtol)
        if np.any(np.isnan(times)):
            j = int(np.flatnonzero(np.isnan(times))[0])
            raise fail(
                f"rigid simulation: resting contact between mass {j} and mass {j + 1} under gravity at "
                f"t = {t:.6g} s after {len(log)} impacts (the lower masses have settled onto each other); "
                "the impulsive model cannot hold a resting contact, so the run stops here"
            )
        dt = float(np.min(times))
        if not np.isfinite(dt) and not log:
            break  # nothing ever meets: no contact (n_collisions == 0), the bodies fly on
        if not np.isfinite(dt):  # cannot happen while not separated; guard against hangs anyway
            raise fail(
                f"rigid simulation: bodies approach but no contact is predicted at t = {t:.6g} s after "
                f"{len(log)} impacts (velocities {v.tolist()}); report this as a bug"
            )
        if until == "top_launch" and _top_launch_final(
                m[None], v[None], np.where(np.isfinite(gp), gp, 0.0)[None], launch_v[-1:], launch_t[-1:],
                np.array([t + dt]), np.array([top_hit]), np.array([g]), np.array([e0]), ground)[0]:
            break  # the top's launch is final
        if t + dt > t_max:
            raise fail(
                f"rigid simulation: t_max = {t_max:.6g} s reached (next impact at t = {t + dt:.6g} s) after "
                f"{len(log)} impacts before the masses separated; raise t_max"
            )
        k = int(np.flatnonzero(times <= dt + _RTOL_T * (t + dt))[0])  # lowest simultaneous interface
        # advance free flight by dt
        if dt > 0:
            if n > 1:
                gp[1:] += np.diff(v) * dt
                if hold:
                    gp[1] -= 0.5 * g * dt * dt
            if ground and not hold:
                gp[0] += v[0] * dt - 0.5 * g * dt * dt
            if hold:
                v[1:] -= g * dt
            else:
                v -= g * dt
            t += dt
            np.maximum(gp, 0.0, out=gp, where=np.isfinite(gp))  # round-off only
        gp[k] = 0.0
        # resolve impact k (Eqs 1-2)
        if k == 0:
            before = (0.0, v[0])
            v[0] = -e0 * v[0]
            after = (0.0, v[0])
            launch_v[0], launch_t[0] = v[0], t
        else:
            a_, b_ = k - 1, k
            va, vb = v[a_], v[b_]
            # the top mass lands again after the apex of its flight: a rebound, no launch
            landed = (k == n - 1 and g > 0 and top_hit and launch_v[b_] > 0
                      and t > launch_t[b_] + launch_v[b_] / g)
            dv = (1.0 + e_pair[k - 1]) * (vb - va) / (m[a_] + m[b_])
            v[a_], v[b_] = va + m[b_] * dv, vb - m[a_] * dv
            before, after = (va, vb), (v[a_], v[b_])
            if not landed:
                launch_v[a_], launch_v[b_] = v[a_], v[b_]
                launch_t[a_] = launch_t[b_] = t
                top_hit = top_hit or k == n - 1
        log.append((t, k, before, after))

    return result()


# --------------------------------------------------------------------------------------------------
# many stacks at once


#: `RigidBatchResult.outcome` codes
SEPARATED, NO_CONTACT, MAX_COLLISIONS, RESTING_CONTACT, NO_PREDICTION, TOP_LAUNCHED = 0, 1, 2, 3, 4, 5


@dataclasses.dataclass(frozen=True)
class RigidBatchResult:
    """Result of `simulate_rigid_batch` (SI units), one row per stack.

    * `launch_velocities`, `launch_times`, `final_velocities` `(B, n)`: as in `RigidResult`, for each
      stack at the end of its run (the run so far where it stopped early).
    * `n_collisions` `(B,)`; `outcome` `(B,)` int8: `SEPARATED` (0, the normal end), `NO_CONTACT` (1:
      nothing ever meets), and the ends where `simulate_rigid` raises `SolverError`: `MAX_COLLISIONS`
      (2), `RESTING_CONTACT` (3), `NO_PREDICTION` (4: bodies approach with no predicted contact, a bug);
      with `until="top_launch"` also `TOP_LAUNCHED` (5: the top's launch is final, the run stopped there).
    * `initial_velocities` `(B, n)`: the velocities given.
    * `gains` `(B,)`: `top_launch_velocities / |initial velocity of mass 1|` (`RigidResult.gain` per stack,
      NaN where it has no top launch or mass 1 starts at rest).
    """

    launch_velocities: np.ndarray
    launch_times: np.ndarray
    final_velocities: np.ndarray
    n_collisions: np.ndarray
    outcome: np.ndarray
    initial_velocities: np.ndarray

    @property
    def gains(self) -> np.ndarray:
        """`(B,)`: the top mass's launch velocity over mass 1's initial speed (paper Eq 19's `G_n =
        V_n/v_ff` for a stack started at impact, as `RigidResult.gain`); NaN where `top_launch_velocities`
        is NaN or mass 1 starts at rest."""
        v1 = np.abs(self.initial_velocities[:, 0])
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(v1 > 0, self.top_launch_velocities / np.where(v1 > 0, v1, 1.0), np.nan)

    @property
    def top_launch_velocities(self) -> np.ndarray:
        """`(B,)`: the top mass's launch velocity, NaN where the run cannot give one.

        A normal end gives `launch_velocities[:, -1]`. A run that stopped early (the `SolverError` ends
        of `simulate_rigid`: under gravity the lower masses settle after the cascade) still gives it
        where the top mass had an impact and was leaving its neighbour when the run stopped
        (`v_n > v_{n-1}`), the rule of the report's rigid comparison (`analysis`); otherwise NaN.
        """
        top = self.launch_velocities[:, -1].copy()
        stopped = (self.outcome >= MAX_COLLISIONS) & (self.outcome != TOP_LAUNCHED)
        vf = self.final_velocities
        leaving = vf[:, -1] > vf[:, -2] if vf.shape[1] > 1 else np.ones(len(vf), dtype=bool)
        top[stopped & ~(leaving & (self.n_collisions > 0))] = np.nan
        return top


def _contact_times(s, u, a, vtol):
    """`_contact_time` elementwise (arrays of one shape)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        big_a = -a
        root = np.sqrt(u * u + 2.0 * big_a * np.maximum(s, 0.0))
        closed = np.where(u < -vtol, 0.0,
                          np.where(a < 0.0, np.where(np.abs(u) <= vtol, np.nan, 2.0 * u / big_a), np.inf))
        linear = np.where(u < -vtol, s / -u, np.inf)
        quad = np.where(u <= 0.0, 2.0 * s / (root - u), (u + root) / big_a)
        return np.where(s <= 0.0, closed, np.where(a == 0.0, linear, quad))


def _top_launch_final(m, v, gp, lv_top, lt_top, t_next, top_hit, g, e0, ground: bool):
    """Whether the top mass's launch velocity can no longer change (`(B, n)` rows, or one stack as 1-row
    arrays): it has had an impact that launched it upward (`lv_top > 0`) under gravity, and either the
    next impact comes after the apex of that flight (`t_next > lt_top + lv_top / g`: every impact on it
    from then on lands it, a rebound, the module's apex rule), or, on a ground that adds no energy
    (`e0 <= 1`), the masses below it cannot reach it before that apex: their energy
    `E = sum_{j<n} m_j (v_j^2 / 2 + g x_j)` (heights `x_j >= 0` above the ground) never grows while the top
    is not hit (pair and ground impacts with e <= 1 dissipate, free flight conserves it), so mass n-1
    never rises above `E / (m_{n-1} g)`, and the top, still rising to its apex, is already above that."""
    with np.errstate(divide="ignore", invalid="ignore"):
        gs = np.where(g > 0, g, 1.0)
        launched = top_hit & (g > 0) & (lv_top > 0)
        final = launched & (t_next > lt_top + lv_top / gs)
        if ground and m.shape[1] > 1:
            x = np.cumsum(gp, axis=1)  # heights above the ground
            energy = np.sum(m[:, :-1] * (0.5 * v[:, :-1] ** 2 + gs[:, None] * x[:, :-1]), axis=1)
            out_of_reach = m[:, -2] * gs * x[:, -1] > energy * (1.0 + 1e-9)
            final |= launched & (e0 <= 1.0) & (v[:, -1] > 0) & out_of_reach
    return final


def simulate_rigid_batch(masses, velocities, gaps, restitution, ground_restitution=None, gravity=0.0, *,
                         max_collisions=100_000, until: str = "separated") -> RigidBatchResult:
    """`simulate_rigid` of `B` stacks of `n` masses at once, vectorised over the stacks (plain numpy).

    **Arguments** (SI, arrays with a leading batch axis `B`): `masses`, `velocities`, `gaps` `(B, n)` as in
    `simulate_rigid`; `restitution` `(B, n)` over interfaces (entry 0 unused, pair values in `[0, 1]`);
    `ground_restitution`: None (no ground, for every stack) or `(B,)` values `>= 0`; `gravity`: a scalar
    or `(B,)`, `>= 0`; `max_collisions`: impacts after which a run stops (`MAX_COLLISIONS`); `until`:
    `"separated"` (the end of `simulate_rigid`) or `"top_launch"`: a run also ends (`TOP_LAUNCHED`) as soon
    as the top mass's launch is final (`simulate_rigid`'s `until`): a dropped stack's lower masses, which
    keep bouncing on the ground long after the top has left, are not followed. The top's launch velocity and time are those of
    `simulate_rigid`; the other masses' are those of the run so far.

    **Returns** a `RigidBatchResult`. Each stack follows exactly the rules of `simulate_rigid` (the
    module docstring: the same closed-form contact times, tie rule, approach floor, ground support,
    apex rule and stopping rule, the same arithmetic), one loop iteration per impact over the stacks
    still running; where `simulate_rigid` raises `SolverError`, the run's outcome says why and its
    state up to there is returned (no `t_max`: a sweep has none).

    **Raises:** `ParameterError` for arrays of the wrong shape or values outside those ranges.
    """
    m = _arr(masses, "masses")
    if m.ndim != 2 or m.shape[1] < 1:
        raise ParameterError("masses", m.shape, "a (B, n) array of masses, n >= 1")
    B, n = m.shape
    if not np.all(np.isfinite(m) & (m > 0)):
        raise ParameterError(*_first_bad("masses", m, np.isfinite(m) & (m > 0)), "masses must be finite and > 0")
    v = _arr(velocities, "velocities").copy()
    gp = _arr(gaps, "gaps").copy()
    e = _arr(restitution, "restitution").copy()
    if e.ndim == 0:  # one value for every interface of every stack, as `simulate_rigid` takes
        e = np.full((B, n), float(e))
    for name, x in (("velocities", v), ("gaps", gp), ("restitution", e)):
        if x.shape != (B, n):
            raise ParameterError(name, x.shape, f"a ({B}, {n}) array, one row per stack")
    if not np.all(np.isfinite(v)):
        raise ParameterError(*_first_bad("velocities", v, np.isfinite(v)), "finite velocities")
    v0 = v.copy()
    if not np.all(np.isfinite(gp) & (gp >= 0)):
        raise ParameterError(*_first_bad("gaps", gp, np.isfinite(gp) & (gp >= 0)), "finite gaps >= 0")
    pair = np.ones_like(e, dtype=bool)
    pair[:, 1:] = np.isfinite(e[:, 1:]) & (e[:, 1:] >= 0) & (e[:, 1:] <= 1)
    if not np.all(pair):
        raise ParameterError(*_first_bad("restitution", e, pair), "pair restitutions in [0, 1] (column 0, the "
                             "ground's, is ground_restitution's)")
    for name, x in (("ground_restitution", ground_restitution), ("gravity", gravity)):
        if x is not None and np.ndim(x) not in (0, 1) or np.ndim(x) == 1 and np.shape(x) != (B,):
            raise ParameterError(name, np.shape(x), f"a scalar or {B} values, one per stack")
    ground = ground_restitution is not None
    if ground:
        e0 = np.broadcast_to(_arr(ground_restitution, "ground_restitution"), (B,)).copy()
        if not np.all(np.isfinite(e0) & (e0 >= 0)):
            raise ParameterError(*_first_bad("ground_restitution", e0, np.isfinite(e0) & (e0 >= 0)),
                                 "values >= 0 (may exceed 1) or None")
    else:
        e0 = np.full(B, np.nan)
        gp[:, 0] = np.nan
    g = np.broadcast_to(_arr(gravity, "gravity"), (B,)).copy()
    if not np.all(np.isfinite(g) & (g >= 0)):
        raise ParameterError(*_first_bad("gravity", g, np.isfinite(g) & (g >= 0)), "finite values >= 0 (acts downward)")
    max_collisions = _check_max_collisions(max_collisions)
    if until not in UNTIL:
        raise ParameterError("until", until, f"one of {', '.join(UNTIL)}")

    vmax = np.max(np.abs(v), axis=1)
    vtol = _RTOL_V * np.where(vmax > 0, vmax, 1.0)
    out_lv, out_lt, out_vf = v.copy(), np.zeros((B, n)), v.copy()
    out_nc, out_code = np.zeros(B, dtype=np.int64), np.full(B, SEPARATED, dtype=np.int8)
    # the stacks still running, compacted: their index and state
    idx = np.arange(B)
    lv, lt, t = v.copy(), np.zeros((B, n)), np.zeros(B)
    top_hit, nc = np.zeros(B, dtype=bool), np.zeros(B, dtype=np.int64)
    rows = np.arange(B)
    while idx.size:
        # end the runs that separated (after an impact) or failed: write them out, keep the rest
        sep = nc > 0
        if n > 1:
            sep &= ~np.any(np.diff(v, axis=1) < -vtol[:, None], axis=1)
        if ground:
            sep &= ~(v[:, 0] < -vtol)
        cap = ~sep & (nc >= max_collisions)
        hold = ground & (g > 0) & (gp[:, 0] == 0.0) & (np.abs(v[:, 0]) <= vtol)
        vh = v.copy()
        vh[hold, 0] = 0.0
        times = np.full(v.shape, np.inf)
        if ground:
            times[:, 0] = np.where(hold, np.inf, _contact_times(gp[:, 0], vh[:, 0], -g, vtol))
        if n > 1:
            acc = np.zeros(v.shape[0:1] + (n - 1,))
            acc[:, 0] = np.where(hold, -g, 0.0)
            times[:, 1:] = _contact_times(gp[:, 1:], np.diff(vh, axis=1), acc, vtol[:, None])
        running = ~sep & ~cap
        resting = running & np.any(np.isnan(times), axis=1)
        dt = np.min(np.where(np.isnan(times), np.inf, times), axis=1)
        never = running & ~resting & ~np.isfinite(dt)
        no_contact = never & (nc == 0)
        stuck = never & (nc > 0)
        final = np.zeros_like(sep)
        if until == "top_launch":
            final = running & ~resting & ~never & _top_launch_final(m, vh, gp, lv[:, -1], lt[:, -1], t + dt, top_hit,
                                                                     g, e0, ground)
        end = sep | cap | resting | never | final
        if np.any(end):
            i = idx[end]
            out_lv[i], out_lt[i], out_nc[i] = lv[end], lt[end], nc[end]
            out_vf[i] = np.where(resting[end, None] | never[end, None], vh[end], v[end])
            out_code[i] = np.select([cap[end], resting[end], no_contact[end], stuck[end], final[end]],
                                    [MAX_COLLISIONS, RESTING_CONTACT, NO_CONTACT, NO_PREDICTION, TOP_LAUNCHED],
                                    SEPARATED)
            keep = ~end
            idx, v, vh, gp, lv, lt, t = idx[keep], v[keep], vh[keep], gp[keep], lv[keep], lt[keep], t[keep]
            top_hit, nc, hold, times, dt = top_hit[keep], nc[keep], hold[keep], times[keep], dt[keep]
            m, e, e0, g, vtol = m[keep], e[keep], e0[keep], g[keep], vtol[keep]
            if not idx.size:
                break
        v = vh
        r = rows[: idx.size]
        k = np.argmax(times <= (dt + _RTOL_T * (t + dt))[:, None], axis=1)  # the lowest simultaneous interface
        # free flight for dt
        move = dt > 0
        dtm = np.where(move, dt, 0.0)
        if n > 1:
            gp[:, 1:] = np.where(move[:, None], gp[:, 1:] + np.diff(v, axis=1) * dtm[:, None], gp[:, 1:])
            gp[:, 1] = np.where(move & hold, gp[:, 1] - 0.5 * g * dtm * dtm, gp[:, 1])
        if ground:
            gp[:, 0] = np.where(move & ~hold, gp[:, 0] + (v[:, 0] * dtm - 0.5 * g * dtm * dtm), gp[:, 0])
        fall = np.where(move[:, None], g[:, None] * dtm[:, None], 0.0)
        if n > 1:
            v[:, 1:] = v[:, 1:] - fall
        v[:, 0] = np.where(hold, v[:, 0], v[:, 0] - fall[:, 0])
        t = np.where(move, t + dtm, t)
        gp = np.where(move[:, None] & np.isfinite(gp), np.maximum(gp, 0.0), gp)
        gp[r, k] = 0.0
        # the impact at interface k (Eqs 1-2; the ground: V_1 = -e_{1,0} v_1)
        on_ground = k == 0
        a_, b_ = np.maximum(k - 1, 0), np.maximum(k, 1) if n > 1 else np.zeros_like(k)
        if n > 1:
            va, vb = v[r, a_], v[r, b_]
            landed = ((k == n - 1) & (g > 0) & top_hit & (lv[:, -1] > 0)
                      & (t > lt[:, -1] + lv[:, -1] / np.where(g > 0, g, 1.0)))
            dv = (1.0 + e[r, b_]) * (vb - va) / (m[r, a_] + m[r, b_])
            na, nb = va + m[r, b_] * dv, vb - m[r, a_] * dv
            pair = ~on_ground
            v[r[pair], a_[pair]], v[r[pair], b_[pair]] = na[pair], nb[pair]
            upd = pair & ~landed
            lv[r[upd], a_[upd]], lv[r[upd], b_[upd]] = na[upd], nb[upd]
            lt[r[upd], a_[upd]] = t[upd]
            lt[r[upd], b_[upd]] = t[upd]
            top_hit |= upd & (k == n - 1)
        if ground:
            gr = r[on_ground]
            v[gr, 0] = -e0[on_ground] * v[gr, 0]
            lv[gr, 0], lt[gr, 0] = v[gr, 0], t[on_ground]
        nc = nc + 1
    return RigidBatchResult(_ro(out_lv), _ro(out_lt), _ro(out_vf), _ro(out_nc), _ro(out_code), _ro(v0))
