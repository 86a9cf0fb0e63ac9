"""The results of `hertz_chain.simulation`: `Trajectory`, `Solution`, `BatchSolution`."""

from __future__ import annotations

import dataclasses

import jax
import numpy as np

from ._scaling import Scales
from .stack import Stack, State
from .status import Status

# ==================================================================== results
@dataclasses.dataclass(frozen=True)
class Trajectory:
    """Samples of a solution (numpy, SI units). Shapes: `t (T,)`; mass arrays `(T, n)`; interface
    arrays `(T, n)` (entry 0 = ground; 0 without the ground).

    - `t` (s); `positions` (m), `velocities` (m/s), `accelerations` (m/s²) of the masses, upward;
    - `overlaps` (m, > 0 compression), `overlap_rates` (m/s, > 0 approaching), `forces` (N) and
      `dissipated` (J, cumulative) of the interfaces;
    - `energy` (J): kinetic + gravitational + elastic + dissipated, constant in an exact solution;
    - `max_overlaps` (m): the largest overlap of every interface so far, for a stack with an
      elastic–plastic law (`Stack.memory`); None otherwise.
    """

    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    overlaps: np.ndarray
    overlap_rates: np.ndarray
    forces: np.ndarray
    dissipated: np.ndarray
    energy: np.ndarray
    max_overlaps: np.ndarray | None = None

    @classmethod
    def _from(cls, d: dict, trim: bool) -> Trajectory:
        arrs = {k: np.asarray(v) for k, v in d.items()}
        if trim:
            keep = np.isfinite(arrs["t"])
            arrs = {k: v[keep] for k, v in arrs.items()}
        else:  # grid points after the solve stopped: NaN, not inf
            alive = np.isfinite(arrs["positions"]).all(axis=-1)
            arrs = {k: (v if k == "t" else np.where(alive.reshape(alive.shape + (1,) * (v.ndim - 1)), v, np.nan))
                    for k, v in arrs.items()}
        return cls(**{f.name: arrs[f.name] for f in dataclasses.fields(cls) if f.name in arrs})


@dataclasses.dataclass(frozen=True)
class Solution:
    """The result of `simulate` (numpy arrays, SI units).

    - `status`: a `Status` (`hertz_chain.status`: complete, complete with rebounds, incomplete, no
      contact, failed); `status_code` its integer. The launch data are valid when `ok`.
    - `cascade_end_time` (s): when the first cascade ended (`_cascade_over`), NaN if it did not.
    - `t_final` (s): when the solve stopped.
    - `launch_velocities` `(n,)` (m/s): the velocity of every mass when its last contact ended (NaN for
      a mass that was never in contact); `launch_times` `(n,)` (s): when that was.
    - `final_velocities` `(n,)` (m/s) at `t_final`; `contact_end_times` `(n,)` (s): end of the last
      contact of every interface.
    - `num_steps`, `num_accepted_steps`, `num_rejected_steps`: solver statistics.
    - `energy_error`: max over the steps of `|E(t) - E(0)| / E_scale` (the energy audit;
      `E_scale = sum(m) V^2/2`, the drop kinetic energy).
    - `steps`: `Trajectory` at the solver's steps (including t = 0; None for a design of
      `simulate_batch(..., save_steps=False)`); `grid`: `Trajectory` on the
      requested `ts` (NaN after `t_final`), or None.
    - `scales`: the `Scales` used; `stack`, `state`: the design and the initial state; `until`: what the
      run was to end at (`"cascade"`, `"t_max"`, `"launch"`).
    """

    status: Status
    status_code: int
    t_final: float
    cascade_end_time: float
    launch_velocities: np.ndarray
    launch_times: np.ndarray
    final_velocities: np.ndarray
    contact_end_times: np.ndarray
    num_steps: int
    num_accepted_steps: int
    num_rejected_steps: int
    energy_error: float
    steps: Trajectory
    grid: Trajectory | None
    scales: Scales
    stack: Stack
    state: State
    until: str = "cascade"  # what the run was to end at (`simulate(..., until=...)`)

    @property
    def ok(self) -> bool:
        return self.status.ok

    @property
    def gain(self) -> float:
        """Velocity gain of the top mass, `V_n / v_ff` (paper Eq 19's `G_n`), `v_ff = V` scale."""
        return float(self.launch_velocities[-1] / self.scales.velocity)


@dataclasses.dataclass(frozen=True)
class BatchSolution:
    """The result of `simulate_batch`: every field of `Solution` with a leading design axis `B`.

    `status_code (B,)`, `ok (B,)`, `t_final`, `launch_velocities (B, n)`, ..., `steps`/`grid`
    (padded with NaN after each design's end; `steps` is None with `save_steps=False`). `design(i)` returns design `i` as a trimmed `Solution`.
    Without a step history (`save_steps=False`) also `peak_forces (B, n)`: each interface's largest
    contact force at the accepted points of the first cascade (N; low by O(h^2) of the step), and
    `impact_velocities (B, n)`: the upper body's velocity at the last accepted point before the
    interface's first contact (m/s, upward > 0); `restitutions (B, n)`: each interface's first
    contact's separation over approach speed (paper Eq 2), both read at the accepted points just around
    it, in free flight, where gravity leaves the relative speed of two falling bodies unchanged (against
    the fixed ground it changes by up to g h within a step h; a neighbour's contact acting within that
    step also shifts it); NaN without a finished contact; `first_contacts (B, n, 2)`: the first accepted
    points in and after each interface's first contact (s; within a step of its start and end; NaN
    without one); `top_duration_10 (B,)`: the top mass's pulse duration between its 10 % points
    (`pulse.pulse_metrics`'s `duration_10` on the accelerometer sampled at the accepted points of the
    first cascade, streamed through the solve; NaN without a pulse, for a pulse still above 10 % at the
    end, or a rising edge too long for the 256 slots kept), and `top_rise_time (B,)`, its 10 % to 90 % rise
    (`rise_time`; NaN alike), both only with `pulse_durations=True`; all None with a step history (analyse
    a design instead).
    """

    status_code: np.ndarray
    t_final: np.ndarray
    cascade_end_time: np.ndarray
    launch_velocities: np.ndarray
    launch_times: np.ndarray
    final_velocities: np.ndarray
    contact_end_times: np.ndarray
    num_steps: np.ndarray
    num_accepted_steps: np.ndarray
    num_rejected_steps: np.ndarray
    energy_error: np.ndarray
    steps: dict
    grid: dict | None
    scales: Scales
    stack: Stack
    state: State
    peak_forces: np.ndarray | None = None
    impact_velocities: np.ndarray | None = None
    restitutions: np.ndarray | None = None
    first_contacts: np.ndarray | None = None
    top_duration_10: np.ndarray | None = None
    top_rise_time: np.ndarray | None = None
    until: str = "cascade"  # what the runs were to end at (`simulate_batch(..., until=...)`)

    @property
    def ok(self) -> np.ndarray:
        return (self.status_code == Status.COMPLETE) | (self.status_code == Status.COMPLETE_WITH_REBOUNDS)

    @property
    def status(self) -> list[Status]:
        return [Status(int(c)) for c in self.status_code]

    def __len__(self) -> int:
        return len(self.status_code)

    def design(self, i: int) -> Solution:
        pick = lambda tree: jax.tree.map(lambda a: a[i], tree)  # noqa: E731
        return _to_solution(
            {k: getattr(self, k)[i] for k in _SCALAR_KEYS} | dict(
                steps=None if self.steps is None else pick(self.steps),
                grid=None if self.grid is None else pick(self.grid),
                scales=pick(self.scales)),
            pick(self.stack), pick(self.state), self.until)


_SCALAR_KEYS = ("status_code", "t_final", "cascade_end_time", "launch_velocities", "launch_times", "final_velocities",
                "contact_end_times", "num_steps", "num_accepted_steps", "num_rejected_steps", "energy_error")


def _to_solution(out: dict, stack, state, until: str = "cascade") -> Solution:
    code = int(out["status_code"])
    return Solution(
        status=Status(code), status_code=code, t_final=float(out["t_final"]),
        cascade_end_time=float(out["cascade_end_time"]),
        launch_velocities=np.asarray(out["launch_velocities"]),
        launch_times=np.asarray(out["launch_times"]),
        final_velocities=np.asarray(out["final_velocities"]),
        contact_end_times=np.asarray(out["contact_end_times"]),
        num_steps=int(out["num_steps"]), num_accepted_steps=int(out["num_accepted_steps"]),
        num_rejected_steps=int(out["num_rejected_steps"]), energy_error=float(out["energy_error"]),
        steps=None if out.get("steps") is None else Trajectory._from(out["steps"], trim=True),
        grid=None if out.get("grid") is None else Trajectory._from(out["grid"], trim=False),
        scales=out["scales"], stack=stack, state=state, until=until,
    )
