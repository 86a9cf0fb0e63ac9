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

__all__ = ["RigidResult", "simulate_rigid", "COLLISION_DTYPE"]

COLLISION_DTYPE = np.dtype(
    [("time", "f8"), ("interface", "i8"), ("before", "f8", (2,)), ("after", "f8", (2,))]
)
"""One impact: time (s), interface index, velocities `(lower, upper)` before and after (m/s).
For the ground (interface 0) the lower body is the ground, velocity 0."""

_RTOL_T = 1e-12
_RTOL_V = 1e-12


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

        For a dropped stack started at impact (`v_i = −v_ff`, `gaps[0] = 0`, or `gravity = 0`) this is
        the paper's `G_n = V_n/v_ff` (Eq 19); for a horizontal chain struck by mass 1 it is Eq 13's
        `G_n = V_n/v_1`. With gravity and `gaps[0] > 0` mass 1's impact speed differs from its initial
        speed: divide by that yourself.
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
) -> RigidResult:
    """Event-driven rigid simulation of a chain (no ground) or a dropped stack (with ground).

    Parameters (SI): `masses` `(n,)` kg, bottom first, `> 0`; `velocities` `(n,)` m/s upward-positive;
    `gaps` `(n,)` m, `>= 0`: `gaps[0]` the height of mass 1 above the ground (ignored without a
    ground), `gaps[j]` the gap between masses `j` and `j+1`; `restitution` scalar or `(n,)` over
    interfaces (entry 0 unused, see the module rules), each in `[0, 1]` (0: perfectly plastic); `ground_restitution`: None
    (no ground) or `>= 0` (may exceed 1); `gravity` `>= 0` m/s², acting downward; `t_max` s;
    `max_collisions` a positive integer.

    Each impact uses Eqs 1–2 of the seed paper (ground: `V_1 = −e_{1,0} v_1`). Contact times are exact
    (linear relative motion between masses, quadratic height of mass 1). Stops when the system
    separates (module rules); raises `SolverError` when `max_collisions` or `t_max` is reached first
    (e.g. inelastic collapse) or for a resting contact.

    With independent collisions (large, suitably chosen gaps, `gravity = 0`) the top's launch velocity
    reproduces Eq 13 (no ground) and Eq 19 (ground): see `tests/test_rigid_events.py`.
    """
    m = np.asarray(masses, dtype=float)
    if m.ndim != 1 or m.size < 1:
        raise ParameterError("masses", masses, "must be a 1-D array of at least one mass")
    n = m.size
    if not np.all(np.isfinite(m) & (m > 0)):
        raise ParameterError("masses", m.tolist(), "masses must be finite and > 0")
    v = np.array(velocities, dtype=float)
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ParameterError("velocities", velocities, f"must be {n} finite numbers (one per mass)")
    gp = np.array(gaps, dtype=float)
    if gp.shape != (n,) or not np.all(np.isfinite(gp) & (gp >= 0)):
        raise ParameterError("gaps", gaps, f"must be {n} finite numbers >= 0 (gaps[0] = height of mass 1)")
    e_arr = np.asarray(restitution, dtype=float)
    if e_arr.ndim == 0:
        e_arr = np.full(n, float(e_arr))
    if e_arr.shape != (n,):
        raise ParameterError("restitution", restitution, f"must be a scalar or {n} values over interfaces 0..n-1")
    e_pair = e_arr[1:]
    if not np.all(np.isfinite(e_pair) & (e_pair >= 0) & (e_pair <= 1)):
        raise ParameterError("restitution", e_arr.tolist(), "pair restitution must lie in [0, 1]")
    ground = ground_restitution is not None
    if ground:
        e0 = float(ground_restitution)
        if not (np.isfinite(e0) and e0 >= 0):
            raise ParameterError("ground_restitution", ground_restitution, "must be >= 0 (may exceed 1) or None")
    else:
        e0 = np.nan
        gp[0] = np.nan
    g = float(gravity)
    if not (np.isfinite(g) and g >= 0):
        raise ParameterError("gravity", gravity, "must be finite and >= 0 (acts downward)")
    t_max = float(t_max)
    if not t_max > 0:
        raise ParameterError("t_max", t_max, "must be > 0")
    if int(max_collisions) != max_collisions or max_collisions < 1:
        raise ParameterError("max_collisions", max_collisions, "must be a positive integer")
    max_collisions = int(max_collisions)

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
