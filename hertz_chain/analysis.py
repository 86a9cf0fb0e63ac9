"""From a simulated stack to what its users need: a `Report`.

`analyse(solution)` extracts, from the solver's steps of a `Solution`:

- every **contact episode** of every interface, with its effective restitution
  `e_eff = -(V2 - V1)/(v2 - v1)` (paper Eq 2; `hertz_chain.episodes`);
- the **acceleration pulse** of every mass (`hertz_chain.pulse`), as an accelerometer fixed to the mass
  reads it: the contact acceleration `a + g` (zero in free fall), in m/s² and g;
- the **shock response spectrum** of the top mass's pulse (`hertz_chain.spectrum`: maximax absolute
  acceleration, Q = 10, 1/12 octave, Smallwood ramp-invariant filter, ISO 18431-4): of the top mass's
  own contact (the interface below it), over a band that covers at least 100 Hz-10 kHz and
  `[0.1/D, 20/D]` (D the pulse's 10 % duration), on the dense solution where the steps are coarse;
- the **velocity amplification**: the launch velocity of every mass over the drop speed, and the top
  mass's kinetic-energy transfer efficiency `K_n` (paper Section 2.1: its kinetic energy after the
  cascade over the stack's kinetic energy at impact);
- the **comparison with the rigid model**, three ways: Eq 19 (Eq 13 without the ground) with the
  nominal restitutions; Eq 19 with the measured `e_eff` of every interface; and the event-driven rigid
  simulator (`hertz_chain.rigid_events`) from the same initial state with the measured `e_eff`;
- an **independence measure** and a **regime** verdict: the rigid theory assumes that the contacts of
  neighbouring interfaces (which share a mass) never act at once. `independence` is the largest
  fraction of the shorter contact time during which two neighbouring interfaces are both closed
  (0 for a perfectly sequential cascade, up to 1). The regime is "independent" when it is below
  `INDEPENDENT_BELOW` and "overlapping" otherwise.

Everything here is plain numpy on the host; no JAX tracing.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from .episodes import ContactEpisode, contact_episodes, hermite_slope, parabolic_peak, refined_peak
from .errors import HertzChainError, ParameterError, SolverError
from .pulse import G0, PulseMetrics, pulse_metrics
from .rigid import as_rigid_restitution, chain_gain, stack_gain
from .rigid_events import simulate_rigid
from .spectrum import (DEFAULT_PPC, ShockResponseSpectrum, SRSOptions, _active_sample_rate, octave_frequencies,
                  resample_uniform, srs)
from .status import Status

from .constants import INDEPENDENT_BELOW  # noqa: E402  (re-exported: the regime threshold)

__all__ = ["INDEPENDENT_BELOW", "RigidComparison", "Report", "analyse", "independence", "wave_speed"]



@dataclasses.dataclass(frozen=True)
class RigidComparison:
    """Top-mass velocity gain predicted by the rigid independent-collision model, three ways.

    A gain is None when its inputs do not exist: a measured restitution is undefined for an interface
    that never opened and closed once with a positive approach speed (e.g. a touching stack whose
    masses start together), and the event-driven model needs every interface's restitution. `notes`
    says why. Under gravity the event-driven run usually stops with `SolverError` once the lower masses
    settle (rigid_events module docstring); its gain is then taken from the run up to that stop when the
    top mass was separating from its neighbour at the end, and `notes` says so.
    """

    nominal_gain: float | None
    measured_restitution_gain: float | None
    event_driven_gain: float | None
    nominal_restitution: np.ndarray | None
    measured_restitution: np.ndarray
    notes: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True)
class Report:
    """The analysis of one simulated stack (SI units unless a name says otherwise)."""

    status: Status
    drop_speed: float
    masses: np.ndarray
    ground: bool
    episodes: tuple[ContactEpisode, ...]  # the first cascade's (every gain, e_eff and pulse is from them)
    restitution: np.ndarray  # (n,) measured e_eff per interface (entry 0 = ground; NaN if undefined)
    launch_velocities: np.ndarray
    velocity_gains: np.ndarray
    top_velocity_gain: float
    top_efficiency: float
    rigid: RigidComparison
    pulses: tuple[PulseMetrics | None, ...]
    top_srs: ShockResponseSpectrum | None
    independence: float
    regime: str
    energy_error: float
    num_steps: int
    num_rejected_steps: int
    t_final: float
    cascade_end_time: float = float("nan")
    rebounds: tuple[ContactEpisode, ...] = ()  # later impacts, kept out of every headline number
    warnings: tuple[str, ...] = ()
    solution: object = dataclasses.field(repr=False, default=None)
    peak_velocities: np.ndarray | None = None  # (n,) each mass's largest upward velocity in the first cascade
    peak_velocity_times: np.ndarray | None = None  # (n,) and when (Hermite-refined with the accelerations)
    wave_speed: float = float("nan")  # contacts/s along a touching chain of >= 8 masses, + up (`wave_speed`)
    wall_peak_force: float = float("nan")  # the far wall's largest force on the top mass at the steps (N; [wall])
    title: str | None = None  # the stack file's title, where the run came from one (`simulate_file`, `run_spec`)
    source_file: str | None = None  # the stack file it was read from (`simulate_file`): the exports' provenance

    @property
    def top_pulse(self) -> PulseMetrics | None:
        return self.pulses[-1]

    def gain_error(self, which: str = "nominal_gain") -> float | None:
        """Relative error of the rigid prediction `which` against the simulated top gain."""
        rigid = getattr(self.rigid, which)
        if rigid is None:
            return None
        return (rigid - self.top_velocity_gain) / self.top_velocity_gain


def independence(episodes: list[ContactEpisode] | tuple[ContactEpisode, ...], interfaces) -> float:
    """Largest fraction of the shorter contact time during which two neighbouring interfaces
    (`j`, `j+1`, which share mass `j+1`) are both closed; 0 when the cascade is sequential.

    Only the first episode of each interface counts: the primary cascade, which is what the rigid
    theory describes (later re-contacts, e.g. masses falling back under gravity, are not part of it).
    """
    by_if: dict[int, list[tuple[float, float]]] = {}
    for ep in sorted(episodes, key=lambda ep: ep.start):
        by_if.setdefault(ep.interface, [(ep.start, ep.end)])
    worst = 0.0
    for j in interfaces:
        a, b = by_if.get(j, []), by_if.get(j + 1, [])
        if not a or not b:
            continue
        both = sum(max(0.0, min(e1, e2) - max(s1, s2)) for s1, e1 in a for s2, e2 in b)
        shorter = min(sum(e - s for s, e in a), sum(e - s for s, e in b))
        if shorter > 0:
            worst = max(worst, both / shorter)
    return float(min(worst, 1.0))


#: Approach speeds below this fraction of the drop speed are not impacts (touching masses).
MIN_APPROACH = 1e-6


def _main_restitution(episodes, n: int, v_ref: float) -> np.ndarray:
    """Per interface, `e_eff` of its strongest complete episode (largest approach speed); NaN when
    no episode approaches faster than `MIN_APPROACH * v_ref` (masses that start touching)."""
    e = np.full(n, np.nan)
    best = np.full(n, MIN_APPROACH * v_ref)
    for ep in episodes:
        if ep.complete and ep.approach_velocity > best[ep.interface]:
            best[ep.interface] = ep.approach_velocity
            e[ep.interface] = ep.restitution
    return e


def _index_ranges(indices) -> str:
    """Interface numbers for a message, runs joined: `[1, 2, 3, 4, 7]` -> "[1-4, 7]" (a long chain's
    touching beads listed every number)."""
    runs: list[list[int]] = []
    for j in indices:
        if runs and j == runs[-1][1] + 1:
            runs[-1][1] = j
        else:
            runs.append([j, j])
    return "[" + ", ".join(str(a) if a == b else f"{a}, {b}" if b == a + 1 else f"{a}-{b}" for a, b in runs) + "]"


def _rigid_comparison(sol, e_meas, e_nom, v_ref) -> RigidComparison:
    stack = sol.stack
    if stack.held:  # never flies apart: no launch, no rigid cascade to compare with
        return RigidComparison(None, None, None, None if e_nom is None else np.asarray(e_nom, dtype=float),
                               e_meas, ("a chain held by an end force or confined by a far wall: the rigid "
                                        "cascade does not apply",))
    m = np.asarray(stack.masses, dtype=float)
    n, ground = m.size, stack.ground
    x0 = np.asarray(sol.state.positions, dtype=float)
    v0 = np.asarray(sol.state.velocities, dtype=float)
    notes: list[str] = []
    first = 0 if ground else 1
    uniform_drop = ground and np.allclose(v0, v0[0]) and v0[0] < 0

    def closed_form(e):
        if ground:
            if not uniform_drop:
                return None
            return float(stack_gain(m, e, ground_restitution=e[0]))
        if not (v0[0] > 0 and np.allclose(v0[1:], 0.0)):
            return None
        return float(chain_gain(m, np.concatenate([[1.0], e[1:]])))  # entry 0 (ground) unused

    def safe(fn, label):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return fn()
        except HertzChainError as exc:
            notes.append(f"{label}: {exc}")
            return None

    nominal = None
    if e_nom is not None:
        e_nom = np.asarray(e_nom, dtype=float)
        if not np.isfinite(e_nom[first:]).all():
            notes.append("nominal: no nominal restitution for interface(s) "
                         f"{_index_ranges([j for j in range(first, n) if not np.isfinite(e_nom[j])])} (a "
                         "speed-dependent law "
                         "given by its raw parameter, or an elastic–plastic law)")
        else:
            nominal = safe(lambda: closed_form(e_nom), "nominal")
        if nominal is None and not notes:
            notes.append("nominal: Eqs 13/19 need a dropped stack (or a struck chain at rest)")
    measured = event = None
    defined = np.isfinite(e_meas[first:]).all()
    if not defined:
        bad = [j for j in range(first, n) if not np.isfinite(e_meas[j])]
        notes.append(f"measured restitution undefined for interface(s) {_index_ranges(bad)}: no single complete "
                     "contact with a positive approach speed (touching or persistently loaded)")
    else:
        e_rig = as_rigid_restitution(e_meas)  # an elastic contact's 1 + round-off is 1
        measured = safe(lambda: closed_form(e_rig), "measured")
        gaps = np.concatenate([[x0[0]], np.diff(x0)])
        gaps = np.maximum(gaps, 0.0)  # a preloaded (overlapping) stack starts touching
        e_arr = np.where(np.isfinite(e_rig), e_rig, 1.0)

        def run():
            try:
                res = simulate_rigid(m, v0, gaps, e_arr, ground_restitution=e_arr[0] if ground else None,
                                     gravity=float(stack.gravity), until="top_launch")
            except SolverError as exc:
                # The run stops once the top's launch is final; where the lower masses settle before
                # that (collapse or resting contact), it stops with an error, and the run so far still
                # holds the top mass's launch if the top mass was leaving its neighbour then.
                res = getattr(exc, "result", None)
                vf = None if res is None else res.final_velocities
                if res is None or (n > 1 and not vf[-1] > vf[-2]) or res.n_collisions == 0:
                    raise
                notes.append(f"event-driven: top launch taken from the run up to its stop ({exc})")
            return float(res.launch_velocities[-1] / v_ref)

        event = safe(run, "event-driven")
    return RigidComparison(nominal, measured, event, e_nom, e_meas, tuple(notes))


def _pulse(t, a, v, smooth=None) -> PulseMetrics | None:
    try:
        return pulse_metrics(t, a, velocity=v, smooth=smooth)
    except HertzChainError:
        return None  # e.g. a mass that never felt a contact


#: The top SRS's band always covers at least this (Hz): the shock-test standards' usual 100 Hz-10 kHz.
SRS_BAND_HZ = (100.0, 10_000.0)


def _top_srs(t, a_g, v_g, episodes, top_if, options=None) -> ShockResponseSpectrum | None:
    """The SRS of the top mass's own contact (`top_if`: the interface below it), as `options`
    (`srs.SRSOptions`; default maximax absolute acceleration, Q = 10, 1/12 octave) say, over their band
    or by default `[min(100 Hz, 0.1/D), max(10 kHz, 20/D)]` (D: the pulse's 10 % duration). `a_g`, `v_g`:
    the accelerometer's acceleration and its running integral, in g and g·s; an acceleration SRS comes
    back in g, a pseudo-velocity SRS in m/s. When the solver's steps sample the pulse more coarsely than
    50 points per cycle at the top of the band, the filter runs on the dense solution instead: the slope
    of the cubic Hermite interpolant of the velocity with the acceleration (`episodes.hermite_slope`),
    not on straight lines between steps; the band is never narrowed to what the steps resolve."""
    opts = options if options is not None else SRSOptions()
    eps = [ep for ep in episodes if ep.interface in top_if]
    if not eps:
        return None
    t0, t1 = min(ep.start for ep in eps), max(ep.end for ep in eps)
    pad = 0.05 * (t1 - t0)
    keep = (t >= t0 - pad) & (t <= t1 + pad)
    if keep.sum() < 4:
        return None
    tk, ak = t[keep], a_g[keep]
    try:
        step = 2.0 ** (1 / opts.per_octave) * (1 + 1e-12)  # one grid point at or beyond each end of the band
        if opts.band is not None:
            lo, hi = opts.band
        else:
            duration = pulse_metrics(tk, ak).duration_10
            lo, hi = min(SRS_BAND_HZ[0], 0.1 / duration), max(SRS_BAND_HZ[1], 20.0 / duration)
        freqs = octave_frequencies(lo / step, hi * step, opts.per_octave)
        t_end = float(tk[tk <= t1][-1])
        rate = DEFAULT_PPC * freqs[-1]
        if _active_sample_rate(tk, ak) < rate:  # too coarse: the dense solution, t_end kept on the grid
            tk, _, _ = resample_uniform(tk, ak, rate, anchor=t_end)
            tk = np.minimum(tk, t[keep][-1])
            ak = hermite_slope(t[keep], v_g[keep], a_g[keep], tk)
        scale = G0 if opts.kind == "pseudo-velocity" else 1.0  # pseudo-velocity from m/s² -> m/s
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return srs(tk, ak * scale, freqs, Q=opts.Q, on_coarse="ignore", pulse_end=t_end, peak=opts.peak,
                       kind=opts.kind)
    except HertzChainError:
        return None


def _nominal(e, n: int) -> np.ndarray:
    """`nominal_restitution` as `(n,)` floats (a single number for every interface), each in [0, 1] or NaN
    (none: a law without a nominal restitution, or the ground's entry without a ground); raises
    `ParameterError`."""
    allowed = f"a number in [0, 1] or {n} of them (entry 0: the ground)"
    try:
        a = np.asarray(e, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError("nominal_restitution", e, allowed) from None
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ParameterError("nominal_restitution", f"shape {a.shape}", allowed)
    if not np.all(np.isnan(a) | ((a >= 0) & (a <= 1))):
        raise ParameterError("nominal_restitution", e if a.size < 8 else "values outside [0, 1]",
                             "restitutions in [0, 1]")
    return a


def analyse(solution, *, nominal_restitution=None, tolerances: dict | None = None,
            srs_options: SRSOptions | None = None, yield_limits=()) -> Report:
    """Analyse a `hertz_chain.Solution` (see the module docstring for every quantity).

    **Arguments:**

    - `solution`: the result of `hertz_chain.simulation`.
    - `nominal_restitution`: `(n,)` the restitution each interface was designed for (entry 0 = ground;
      entry 0 ignored without the ground), or one number for all, each in [0, 1] (NaN: none), for the
      nominal rigid prediction; None skips it. Raises `ParameterError` otherwise.
    - `tolerances`: optional `{"rtol": ..., "atol": ...}` the solve used, for the warnings.
    - `srs_options`: how the top SRS is computed (`hertz_chain.spectrum.SRSOptions`; the stack file's
      `[srs]`); default maximax absolute acceleration, Q = 10, 1/12 octave, the default band.
    - `yield_limits`: `materials.YieldLimit`s of the interfaces whose materials have a yield strength
      (`BuiltStack.yield_limits`): an interface with an elastic or viscous law whose peak Hertz pressure
      (Johnson Eq. 4.24, from its largest contact force) exceeds the yield pressure `1.6 Y` gets a
      warning: the law's numbers are then an upper bound, the metal yields.

    Episodes that start after their interface's last contact of the first cascade
    (`Solution.contact_end_times`) are `rebounds`: listed on their own, kept out of the restitutions,
    the pulses, the SRS and the regime. `warnings` lists, one line each: an energy audit above 1e-6,
    a measured restitution outside [0, 1], a measured e more than 1 % from the nominal e in an
    independent cascade, tolerances looser than 1e-6.

    **Raises:** `ParameterError` for the arguments above or a solution without steps; `SolverError` (its
    `.status` the run's) for a run that failed before its first step (a batch's design whose numbers were
    invalid): there is nothing to analyse.
    """
    sol = solution
    stack = sol.stack
    st = sol.steps
    if nominal_restitution is not None:
        nominal_restitution = _nominal(nominal_restitution, int(np.size(stack.masses)))
    if st is None:
        raise ParameterError("solution", "a design without step history",
                             "a Solution with steps (simulate, or simulate_batch with save_steps=True)")
    if np.size(st.t) == 0:  # a batch's design that failed before a step (a review: numpy's "zero-size
        # array to reduction operation maximum")
        raise sol.status.error("the run", "there is no step to analyse")
    m = np.asarray(stack.masses, dtype=float)
    n, ground, g = m.size, bool(stack.ground), float(stack.gravity)
    interfaces = list(range(0 if ground else 1, n))
    a = st.accelerations
    dd_acc = np.concatenate([-a[:, :1], a[:, :-1] - a[:, 1:]], axis=1)  # overlap accelerations
    # round-off floor: touching float64 masses "overlap" by ~1e-24 m; real contacts by ~L = delta_max
    floor = 1e-9 * float(np.max(st.overlaps, initial=0.0))
    clamped = stack.clamped()
    closed = np.where(clamped, st.forces > 0, st.overlaps > 0)
    every = contact_episodes(st.t, st.overlaps, st.overlap_rates, st.forces, accelerations=dd_acc,
                             # free at the end only where the run stopped at the cascade's end (`until="cascade"`);
                             # a run to t_max (a held or resting chain) or to the top's launch may end with
                             # contacts loaded, which end there (reviews: a resting contact's 1e-9 m/s drift was
                             # extrapolated to an end at 43,378 s; a launch run's loaded contacts "ended" later,
                             # complete, with made-up separation speeds)
                             interfaces=interfaces, noise_floor=floor,
                             free_at_end=(sol.status.ok and not stack.held and sol.until == "cascade"
                                          and sol.t_final == sol.cascade_end_time),
                             closed=closed, separation=_separation(stack, st.max_overlaps))
    # an episode that starts after its interface's last contact of the first cascade is a rebound
    last_end = np.asarray(sol.contact_end_times, dtype=float)
    first = [ep for ep in every if np.isfinite(last_end[ep.interface]) and ep.start < last_end[ep.interface]]
    episodes = first if sol.status.ok else every
    rebounds = [ep for ep in every if ep not in episodes]
    v0 = np.asarray(sol.state.velocities, dtype=float)
    v_ref = float(np.max(np.abs(v0)))
    e_meas = _main_restitution(episodes, n, v_ref)
    if stack.held:  # its contacts stay loaded or are struck again: no single impact to measure e on
        e_meas = np.full(n, np.nan)
    launch = np.asarray(sol.launch_velocities, dtype=float)
    # no drop speed (a stack released at rest): no gain is defined, the launch velocities still are
    gains = launch / v_ref if v_ref > 0 else np.full(n, np.nan)
    ke0 = 0.5 * float(np.sum(m * v0**2))
    top_eff = 0.5 * m[-1] * launch[-1] ** 2 / ke0 if ke0 > 0 else float("nan")
    a_contact = a + g  # what an accelerometer on each mass reads
    v_contact = st.velocities + g * st.t[:, None]  # exact running integral of a + g

    def cut(i):  # the samples of mass i's first cascade: before its first rebound
        starts = [ep.start for ep in rebounds if ep.interface in (i, i + 1)]
        return st.t < min(starts) if starts else np.ones(st.t.shape, dtype=bool)

    def smooth(i, sel):  # the steps across which none of mass i's contacts (below, above, a wall) opens or closes
        cols = [j for j in (i, i + 1) if j < closed.shape[1]]
        shut = closed[sel][:, cols]
        if stack.wall and i == n - 1:
            shut = np.concatenate([shut, wall_closed[sel][:, None]], axis=1)
        return ~np.any(shut[1:] != shut[:-1], axis=1)

    wall_closed = (np.asarray(stack.wall_force(np.asarray(st.positions)), dtype=float) > 0) if stack.wall else None
    pulses = tuple(_pulse(st.t[cut(i)], a_contact[cut(i), i], v_contact[cut(i), i], smooth(i, cut(i)))
                   for i in range(n))
    # the top mass's own contact only: interface n - 1 (its neighbour below, or the ground when n = 1)
    top_if = {n - 1} if (n >= 2 or ground) else set()
    keep = cut(n - 1)
    top_srs = _top_srs(st.t[keep], a_contact[keep, -1] / G0, v_contact[keep, -1] / G0, episodes, top_if,
                       srs_options)
    ind = independence(episodes, interfaces)
    wall_peak = _wall_peak(stack, st)
    rigid = _rigid_comparison(sol, e_meas, nominal_restitution, v_ref)
    regime = "independent" if ind < INDEPENDENT_BELOW else "overlapping"
    peak_t, peak_v = _peak_velocities(st, sol.cascade_end_time)
    strongest: dict[int, ContactEpisode] = {}
    for ep in episodes:
        if ep.interface not in strongest or ep.peak_force > strongest[ep.interface].peak_force:
            strongest[ep.interface] = ep
    x0 = np.asarray(sol.state.positions, dtype=float)
    touching = n >= 8 and bool(np.all(np.diff(x0) <= 0))  # a granular chain: touching or precompressed beads
    speed = wave_speed([strongest[j].peak_force_time if j in strongest else np.nan for j in range(n)]) \
        if touching else float("nan")
    return Report(
        status=sol.status,
        drop_speed=v_ref,
        masses=m,
        ground=ground,
        episodes=tuple(episodes),
        restitution=e_meas,
        launch_velocities=launch,
        velocity_gains=gains,
        top_velocity_gain=float(gains[-1]),
        top_efficiency=float(top_eff),
        rigid=rigid,
        pulses=pulses,
        top_srs=top_srs,
        independence=ind,
        regime=regime,
        energy_error=float(sol.energy_error),
        num_steps=int(sol.num_steps),
        num_rejected_steps=int(sol.num_rejected_steps),
        t_final=float(sol.t_final),
        cascade_end_time=float(sol.cascade_end_time),
        rebounds=tuple(rebounds),
        warnings=tuple(_warnings(sol, e_meas, nominal_restitution, regime, tolerances)
                       + _yield_warnings(stack, strongest, yield_limits, wall_peak)),
        solution=sol,
        peak_velocities=peak_v,
        peak_velocity_times=peak_t,
        wave_speed=speed,
        wall_peak_force=wall_peak,
    )


def _wall_peak(stack, st) -> float:
    """The far wall's largest force on the top mass (N): the parabola through the largest step sample and
    its neighbours (`episodes.parabolic_peak`); NaN without a wall."""
    if not stack.wall:
        return float("nan")
    t = np.asarray(st.t, dtype=float)
    f = np.asarray(stack.wall_force(np.asarray(st.positions)), dtype=float)
    return max(parabolic_peak(t, f, 0, len(t) - 1)[1], float(f.max()))


def _yield_warnings(stack, strongest: dict, yield_limits, wall_peak: float = float("nan")) -> list[str]:
    """One line per interface whose law cannot yield (no memory) but whose peak Hertz pressure exceeds
    the yield pressure of its softer body (`materials.YieldLimit`); the far wall's contact (elastic Hertz,
    `YieldLimit.interface` -1) by its peak force `wall_peak`."""
    out = []
    for lim in yield_limits:
        if lim.interface < 0:  # the far wall
            f, label = wall_peak, "top-wall"
            if not np.isfinite(f):
                continue
        else:
            ep = strongest.get(lim.interface)
            if ep is None or type(stack.law_of(lim.interface)).has_memory:
                continue
            f = ep.peak_force_refined if np.isfinite(ep.peak_force_refined) else ep.peak_force
            label = "ground-1" if lim.interface == 0 else f"{lim.interface}-{lim.interface + 1}"
        p0 = float(lim.peak_pressure(f))
        if p0 > lim.yield_pressure:
            fix = ("the wall's elastic Hertz contact over-predicts its force (an upper bound)" if lim.interface < 0
                   else "this elastic/viscous law over-predicts forces and rebound (an upper bound); law = "
                   "\"thornton\" models the plasticity")
            out.append(f"interface {label}: peak Hertz pressure {p0 / 1e9:.3g} GPa exceeds the yield pressure "
                       f"{lim.yield_pressure / 1e9:.3g} GPa (1.6 Y) of {lim.material} by {p0 / lim.yield_pressure:.3g}x: "
                       f"the metal yields, so {fix}")
    return out


def wave_speed(peak_times) -> float:
    """The speed of a wave along the chain (contacts per second; > 0 travelling up, from mass 1 toward
    the top mass; < 0 travelling down), from the time `t_j` of the peak force of every interface `j`.

    It is the least-squares slope of `j` against `t_j` over the middle half of the interfaces that
    have a peak (from a quarter to three quarters of the way along, away from where a wave forms and
    where it reflects; Nesterenko's solitary wave takes about five beads to form), at least four of
    them, whose times must be strictly monotone in `j` (one wave passing). NaN otherwise. For a chain
    of equal spheres of diameter `D` the speed in m/s is `D` times this (the contacts are `D` apart).
    Nesterenko (2001, "Dynamics of heterogeneous materials", Springer) gives the solitary
    wave's speed `V_s ~ v_m^{1/5}` (docs/granular-chains.md)."""
    t = np.asarray(peak_times, dtype=float)
    j = np.nonzero(np.isfinite(t))[0]
    lo, hi = len(j) // 4, len(j) - len(j) // 4
    j = j[lo:hi]
    if len(j) < 4:
        return float("nan")
    dt = np.diff(t[j])
    if not (np.all(dt > 0) or np.all(dt < 0)):
        return float("nan")
    tc = t[j] - t[j].mean()
    return float(np.sum(tc * (j - j.mean())) / np.sum(tc**2))


def _peak_velocities(st, t_end) -> tuple[np.ndarray, np.ndarray]:
    """Per mass, the time and value of its largest upward velocity up to `t_end` (the end of the first
    cascade; the whole history when it did not end): the cubic Hermite interpolant of the velocity with
    the acceleration as its derivative (`episodes.refined_peak`)."""
    t = np.asarray(st.t, dtype=float)
    v, a = np.asarray(st.velocities, dtype=float), np.asarray(st.accelerations, dtype=float)
    i1 = len(t) - 1 if not np.isfinite(t_end) else max(int(np.searchsorted(t, t_end, side="right")) - 1, 0)
    out = []
    for i in range(v.shape[1]):
        top = float(np.max(v[: i1 + 1, i]))
        # the first sample at the peak: without gravity a launched mass keeps its velocity, and the time of
        # its peak is when it got there (round-off must not pick a later sample)
        k = int(np.argmax(v[: i1 + 1, i] >= top - 1e-9 * max(abs(top), 1e-300)))
        out.append(refined_peak(t, v[:, i], a[:, i], k, k))
    return np.array([o[0] for o in out]), np.array([o[1] for o in out])


#: Warnings (issue 16): an energy audit worse than this (relative to the drop energy) ...
ENERGY_WARN = 1e-6
#: ... a measured e_eff this far (relative) from the nominal e of its interface in an independent cascade ...
RESTITUTION_WARN = 0.01
#: ... and solver tolerances looser than this.
TOLERANCE_WARN = 1e-6


def _warnings(sol, e_meas, e_nom, regime, tolerances) -> list[str]:
    """One line each: what a user should know before trusting the numbers."""
    out = []
    if not np.max(np.abs(np.asarray(sol.state.velocities))) > 0:
        out.append("the stack starts at rest: no drop speed, so no gain is defined; the launch velocities "
                   "are in the JSON (launch_velocities_mps)")
    held = sol.stack.held
    if held:
        f0 = float(np.asarray(sol.stack.end_force))
        what = " and ".join(([f"an end force ({f0:g} N)"] if f0 > 0 else [])
                            + (["a far wall"] if sol.stack.wall else []))
        out.append(f"a chain held by {what} never flies apart as a whole (its contacts may open and close): its "
                   "'launch' velocities and gains are the "
                   "velocities at t_max, no e_eff is measured, and the rigid comparison does not apply")
    if np.isfinite(sol.energy_error) and sol.energy_error > ENERGY_WARN:
        out.append(f"energy audit: |E(t) - E(0)| reached {sol.energy_error:.2e} of the drop energy "
                   f"(> {ENERGY_WARN:g}): tighten solver.rtol/atol")
    for j, e in enumerate(e_meas):  # (1e-6: a review saw "1 lies outside [0, 1]" for 1.0000001)
        if np.isfinite(e) and not -1e-6 <= e <= 1.0 + 1e-6 and not held:
            out.append(f"interface {j}: measured restitution {e:.6g} lies outside [0, 1]"
                       + (" (a contact whose neighbours push during it, as inside a touching chain, can part "
                          "faster than it met)" if e > 1 else ""))
    if e_nom is not None and regime == "independent":
        for j, (em, en) in enumerate(zip(e_meas, np.asarray(e_nom, dtype=float))):
            if np.isfinite(em) and np.isfinite(en) and en > 0 and abs(em - en) > RESTITUTION_WARN * en:
                out.append(f"interface {j}: the contact law gives e = {em:.4f} where the nominal restitution is "
                           f"{en:.4f} ({(em - en) / en:+.1%}): a law calibrated to it from a stack file (its chi "
                           "map) is approximate at this speed; a law given in Python may not be calibrated to it")
    if tolerances is not None:
        loose = {k: v for k, v in tolerances.items() if v is not None and v > TOLERANCE_WARN}
        for k, v in loose.items():
            out.append(f"solver.{k} = {v:g} is looser than {TOLERANCE_WARN:g}: the launch velocities may "
                       "be off by more than 1e-6")
    return out


def _separation(stack, memory=None):
    """`separation(j, delta, delta_dot, k)` for `contact_episodes`: `Stack.separation_function` of
    interface `j` on arrays of samples (one JAX call each), with the memory `q` of sample `k` (a law with
    memory; `memory` the trajectory's `max_overlaps`)."""
    n = stack.n

    def fn(j, delta, rate, k=None):
        d = np.zeros((np.size(delta), n))
        r = np.zeros((np.size(delta), n))
        d[:, j], r[:, j] = delta, rate
        q = None if memory is None or k is None else np.broadcast_to(np.asarray(memory)[k], d.shape)
        return np.asarray(stack.separation_function(d, r, q))[:, j]

    return fn


def accelerometer(report: Report, t, mass: int = -1) -> np.ndarray:
    """What an accelerometer fixed to `mass` (default: the top mass) reads at the times `t`, in m/s²:
    the contact acceleration `a + g` (zero in free fall) of the simulated run, on the dense solution
    (the slope of the cubic Hermite interpolant of `v + g t` with `a + g` at the solver's steps,
    `episodes.hermite_slope`; exact at the steps, error O(h^3) between them).

    **Raises:** `ParameterError` for a report without its solution, or times outside the run.
    """
    sol = report.solution
    st = None if sol is None else sol.steps
    if st is None:
        raise ParameterError("report", "without its solution", "a Report from analyse() of a simulated run")
    g = float(sol.stack.gravity)
    ts = np.asarray(st.t, dtype=float)
    t = np.asarray(t, dtype=float)
    if t.size and not (ts[0] <= t.min() and t.max() <= ts[-1]):
        raise ParameterError("t", f"[{t.min():.6g}, {t.max():.6g}] s", f"times inside the run, [{ts[0]:.6g}, {ts[-1]:.6g}] s")
    v = np.asarray(st.velocities, dtype=float)[:, mass] + g * ts
    a = np.asarray(st.accelerations, dtype=float)[:, mass] + g
    return hermite_slope(ts, v, a, t)
