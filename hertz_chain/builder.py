"""From a declarative `StackSpec` (a stack file) to what the simulator needs.

`build(spec)` returns a `BuiltStack`: the `Stack` (masses, one calibrated contact law per interface,
ground, gravity), the initial `State`, the nominal restitution of every interface (for the rigid
comparison) and the solver options. It resolves, in this order:

1. **Masses**: explicit, or the paper's MVG design (Eq 15, optimal `n` by Eq 20) or MET design
   (Eq 25) through `hertz_chain.rigid`.
2. **Stiffness**: given, or Hertz's `k = (4/3) E* sqrt(R*)` from the materials and radii of the two
   bodies (`hertz_chain.materials`); the ground is rigid unless it has a material.
3. **Calibration**: each law is calibrated to its interface's restitution with its effective mass
   `m* = m_j m_{j+1}/(m_j + m_{j+1})` (`m_1` for the ground). Laws whose restitution depends on the
   impact speed (hunt-crossley, viscoelastic) are calibrated at `calibration_velocity`; when the file
   leaves it out, at the approach speed that the rigid independent-collision model predicts for that
   interface (paper Eqs 1–2 applied down the cascade, `rigid.cascade_velocities`), so that the
   nominal restitution holds where the rigid model expects the impact to happen.
4. **Initial state**: explicit velocities, a preloaded resting stack dropped at the impact speed
   (`stack.resting`; the preload is the weight above each contact plus `stack.end_force`, and a
   precompressed chain may start with explicit velocities), or the impact state with the given gaps
   (`stack.at_impact`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math

import numpy as np

from .contact import AbstractContactLaw, make_law
from .errors import ParameterError, StackFileError
from .materials import (
    Material,
    YieldLimit,
    contact_stiffness,
    effective_modulus,
    effective_radius,
    material as lookup_material,
)
from .registry import LAWS
from .rigid import cascade_velocities, met_design, met_mass_ratio, mvg_design
from .simulation import Tolerances
from .stack import Stack, State, at_impact, reduced_masses, resting
from .stackfile import ContactSpec, StackSpec

__all__ = ["BuiltStack", "build", "design_masses"]


@dataclasses.dataclass(frozen=True)
class BuiltStack:
    """A stack file resolved into simulator inputs (SI units); `build`'s result (formerly `Built`).

    `nominal_restitution` `(n,)`: the restitution each interface was specified for (entry 0 = the
    ground; NaN where a law was given by its raw damping parameter and its restitution is not a
    constant). `simulate_options`: keyword arguments for `hertz_chain.simulation`.
    """

    stack: Stack
    state: State
    masses: np.ndarray
    nominal_restitution: np.ndarray
    laws: tuple[AbstractContactLaw | None, ...]
    simulate_options: dict
    n_output: int | None = None
    dt_output: float | None = None
    title: str | None = None
    yield_limits: tuple[YieldLimit, ...] = ()


def _with_wall(spec: StackSpec, stack: Stack, state: State, laws, interfaces) -> Stack:
    """The stack with the file's far wall (`[wall]`): stiffness given or from the wall's material and the top
    mass's (a flat wall); with `stack.end_force` the wall carries it at the precompressed equilibrium of
    `state` (`stack.precompressed`; no dead load then), else it stands `wall.gap` above the top mass."""
    w, n, bodies = spec.wall, stack.n, spec.stack
    k_w = w.stiffness
    if k_w is None:
        top = _material(spec, bodies.material_list(n)[-1])
        try:
            wall = _material(spec, w.material)
        except ParameterError as exc:
            raise StackFileError(f"wall.material: {w.material!r} is unknown; {exc.allowed}, or a [materials.NAME] "
                                 "of the file") from None
        k_w = contact_stiffness(top, wall, bodies.radius_list(n)[-1], None)
    x_top = float(state.positions[-1])
    f0 = bodies.end_force
    x_w = x_top - (f0 / k_w) ** (2.0 / 3.0) if f0 > 0 else x_top + (w.gap or 0.0)
    return Stack(stack.masses, [laws[j] for j in interfaces], gravity=stack.gravity, ground=stack.ground,
                 wall_stiffness=k_w, wall_position=x_w)


#: `YieldLimit.interface` of the far wall's contact with the top mass (`[wall]`), which is no interface
WALL_INTERFACE = -1


def _pair_limit(j: int, pair, r) -> YieldLimit | None:
    """The `YieldLimit` of contact `j` between the bodies `pair` (materials, None: rigid) with the cap radii
    `r` (inf: flat), where one of them has a yield strength and one cap is curved; else None."""
    if math.isinf(r[0]) and math.isinf(r[1]):
        return None
    yielding = [mat for mat in pair if mat is not None and mat.yield_pressure is not None]
    if not yielding:
        return None
    soft = min(yielding, key=lambda mat: mat.yield_pressure)
    R1, R2 = (r[1], r[0]) if math.isinf(r[0]) else r
    return YieldLimit(j, effective_modulus(*pair), effective_radius(R1, None if math.isinf(R2) else R2),
                      soft.yield_pressure, soft.name, soft.yield_strength, soft.poisson_ratio)


def _wall_yield_limit(spec: StackSpec, n: int) -> YieldLimit | None:
    """The far wall's contact with the top mass (a flat wall): its `YieldLimit`, as `_yield_limits` for the
    interfaces (a review: a steel wall at 2.5x its yield pressure was never warned about)."""
    w, bodies = spec.wall, spec.stack
    mats, radii = bodies.material_list(n), bodies.radius_list(n)
    if w.material is None or mats is None or radii is None:
        return None
    return _pair_limit(WALL_INTERFACE, (_material(spec, mats[-1]), _material(spec, w.material)),
                       (radii[-1], math.inf))


def _yield_limits(spec: StackSpec, n: int, interfaces) -> dict[int, YieldLimit]:
    """`YieldLimit` of every interface whose two bodies have materials and radii (a rigid ground counts
    as a body that does not yield) and one of which has a yield strength."""
    mats, radii = spec.stack.material_list(n), spec.stack.radius_list(n)
    if mats is None or radii is None:
        return {}
    out = {}
    for j in interfaces:
        if j == 0:
            pair, r = (_material(spec, spec.ground.material), _material(spec, mats[0])), (spec.ground.radius, radii[0])
        else:
            pair, r = (_material(spec, mats[j - 1]), _material(spec, mats[j])), (radii[j - 1], radii[j])
        limit = _pair_limit(j, pair, r)
        if limit is not None:
            out[j] = limit
    return out


def design_masses(spec: StackSpec) -> np.ndarray:
    """Masses (kg, bottom first) of the stack: explicit, or an MVG/MET design (paper Eqs 15, 25)."""
    bodies = spec.stack
    if bodies.masses is not None:
        return np.asarray(bodies.masses, dtype=float)
    d = bodies.design
    if d.kind == "mvg":
        m1 = d.bottom_mass if d.bottom_mass is not None else d.top_mass / d.mass_ratio
        return np.asarray(mvg_design(d.mass_ratio, d.restitution, n=d.n, m1=m1).masses, dtype=float)
    if d.n is not None:  # MET with a given n and one mass
        if d.bottom_mass is not None:
            m1 = d.bottom_mass
        else:
            m1 = d.top_mass / float(met_mass_ratio(d.restitution, d.n))
        return np.asarray(met_design(None, d.restitution, n=d.n, m1=m1).masses, dtype=float)
    R = d.mass_ratio if d.mass_ratio is not None else d.top_mass / d.bottom_mass
    m1 = d.bottom_mass if d.bottom_mass is not None else d.top_mass / R
    return np.asarray(met_design(R, d.restitution, m1=m1).masses, dtype=float)


def _material(spec: StackSpec, name: str | None) -> Material | None:
    if name is None:
        return None
    inline = spec.material(name)
    if inline is not None:
        return Material(inline.name, inline.youngs_modulus, inline.poisson_ratio, inline.density,
                        yield_strength=inline.yield_strength)
    return lookup_material(name)


def _stiffness(spec: StackSpec, cs: ContactSpec, j: int, n: int) -> float:
    if cs.stiffness is not None:
        return cs.stiffness
    where = f"{cs.source}.stiffness"  # a law that is not Hertzian always has one (`stackfile` checks)
    mats, radii = spec.stack.material_list(n), spec.stack.radius_list(n)
    if mats is None or radii is None:
        raise StackFileError(f"{where}: missing; give a stiffness or stack.material and stack.radius")
    if j == 0:
        ground = spec.ground
        pair = (_material(spec, ground.material), _material(spec, mats[0]))
        r = (ground.radius, radii[0])
    else:
        pair = (_material(spec, mats[j - 1]), _material(spec, mats[j]))
        r = (radii[j - 1], radii[j])
    if math.isinf(r[0]) and math.isinf(r[1]):
        raise StackFileError(f"{where}: interface {j} is flat on flat; Hertz contact needs a curved "
                             "surface (give a finite stack.radius)")
    R1, R2 = (r[1], r[0]) if math.isinf(r[0]) else r
    return contact_stiffness(pair[0], pair[1], R1, None if math.isinf(R2) else R2)


@contextlib.contextmanager
def _section(spec: StackSpec, cs: ContactSpec, j: int):
    """Name the section of the file that set an offending value."""
    try:
        yield
    except ParameterError as exc:
        raise StackFileError(f"{spec.source + ': ' if spec.source else ''}{cs.source} "
                             f"(interface {j}): {exc}") from exc


def _effective_radius(spec: StackSpec, cs: ContactSpec, j: int, n: int) -> float:
    """The interface's effective radius R* (m) from `stack.radius` (and `ground.radius`), for a law that
    needs it (`registry.LawRow.needs_radius`: the elastic–plastic laws)."""
    radii = spec.stack.radius_list(n)
    if radii is None:
        raise StackFileError(f"{spec.source + ': ' if spec.source else ''}stack.radius: missing; law "
                             f"{cs.law!r} ({cs.source}) needs the contact radius of interface {j}")
    r = (spec.ground.radius, radii[0]) if j == 0 else (radii[j - 1], radii[j])
    if math.isinf(r[0]) and math.isinf(r[1]):
        raise StackFileError(f"{cs.source}: interface {j} is flat on flat; law {cs.law!r} needs a curved "
                             "surface (give a finite stack.radius)")
    R1, R2 = (r[1], r[0]) if math.isinf(r[0]) else r
    return effective_radius(R1, None if math.isinf(R2) else R2)


def _law(cs: ContactSpec, stiffness: float, m_eff: float, v_c: float | None,
         radius: float | None = None, limit: YieldLimit | None = None) -> AbstractContactLaw:
    params = dict(cs.params)
    row = LAWS[cs.law]
    from_materials = [key for key in row.from_materials if key not in params]
    for key in row.from_materials:  # e.g. thornton's yield_pressure from the softer body's Y
        if key not in params:
            if limit is None:
                raise StackFileError(f"{cs.source}.{key}: missing, and the interface's materials have no yield "
                                     "strength (the table gives none for cemented carbide and polymers); give "
                                     f"{key}, or yield_strength in [materials.NAME]")
            params[key] = getattr(limit, key)
    for key in row.context:  # e.g. jackson-green's Poisson ratio, the yielding body's when known
        if limit is not None:
            params[key] = getattr(limit, key)
    try:
        return make_law(cs.law, stiffness=stiffness, restitution=cs.restitution, effective_mass=m_eff,
                        calibration_velocity=v_c, chi_map=cs.chi_map, alpha=cs.alpha, damping=cs.damping,
                        clamp=cs.clamp, effective_radius=radius, **params)
    except ParameterError as exc:  # a value the file did not give: say where it came from (a review: steel
        # on polyurethane read "yield_pressure = 3248000000.0 is invalid", a key the file never set)
        if exc.name not in from_materials or limit is None:
            raise
        raise StackFileError(f"{cs.source} (interface {limit.interface}): law {cs.law!r}: the {exc.name} from "
                             f"the materials, {exc.value:.4g} Pa (1.6 x {limit.material}'s yield strength), is "
                             f"invalid: {exc.allowed}; the other body is far softer and takes the impact "
                             "elastically: give this interface an elastic or viscoelastic law, or give "
                             f"{exc.name} yourself") from None


def _nominal_e(cs: ContactSpec, stiffness: float, m_eff: float) -> float:
    """The restitution an interface is designed for: the file's, 1 for an elastic law, the one its raw
    damping parameter gives (the law's own `restitution_at`) when that does not depend on the impact
    speed (`registry.LawRow.speed_dependent`), NaN otherwise."""
    row = LAWS[cs.law]
    if row.memory:  # elastic–plastic: e follows from the impact speed (the law's `restitution_at`)
        return math.nan
    if row.elastic:
        return 1.0
    if cs.restitution is not None:
        return cs.restitution
    if row.speed_dependent:
        return math.nan
    e = float(_law(cs, stiffness, m_eff, None).restitution_at(1.0, m_eff))
    return max(0.0, e)  # an overdamped linear contact rounds to ~-1e-16


def _approach_speeds(masses, e, ground: bool, v0) -> np.ndarray:
    """Rigid-model approach speed of every interface (Eqs 1–2 down the cascade)."""
    e_fill = np.where(np.isfinite(e), e, 1.0)
    after_hit, _ = cascade_velocities(masses, e_fill, ground_restitution=e_fill[0] if ground else None,
                                      velocities=v0)
    speeds = np.empty(len(masses))
    speeds[0] = abs(v0[0]) if ground else math.nan
    # interface j: mass j (struck from below, after_hit[j-1]) approaches mass j+1 (still at v0[j])
    speeds[1:] = after_hit[:-1] - np.asarray(v0[1:])
    return speeds


def build(spec: StackSpec) -> BuiltStack:
    """Resolve a `StackSpec` into a `BuiltStack` (see the module docstring)."""
    try:
        return _build(spec)
    except ParameterError as exc:
        raise StackFileError(f"{spec.source + ': ' if spec.source else ''}{exc}") from exc


def _build(spec: StackSpec) -> BuiltStack:
    m = design_masses(spec)
    n = m.size
    ground = spec.has_ground
    g = spec.drop.gravity
    interfaces = range(0 if ground else 1, n)
    for j, _ in spec.contact.overrides:
        if not 1 <= j <= n - 1:
            raise StackFileError(f"contact.interface.index: {j} is not an interface of this "
                                 f"{n}-mass stack (allowed 1..{n - 1})")
    v0 = np.asarray(spec.initial_velocities(n), dtype=float)
    specs = {j: spec.contact_for(j) for j in interfaces}
    m_eff = np.asarray(reduced_masses(m))  # ground: m_1; pair j: the pair's reduced mass
    stiffness = {j: _stiffness(spec, cs, j, n) for j, cs in specs.items()}
    e_nom = np.full(n, math.nan)
    for j, cs in specs.items():
        with _section(spec, cs, j):
            e_nom[j] = _nominal_e(cs, stiffness[j], float(m_eff[j]))
    speeds = _approach_speeds(m, e_nom, ground, v0)
    laws: list[AbstractContactLaw | None] = [None] * n
    limits = _yield_limits(spec, n, interfaces)
    for j, cs in specs.items():
        v_c = cs.calibration_velocity
        if v_c is None and LAWS[cs.law].speed_dependent and cs.restitution is not None:
            v_c = float(speeds[j])
            if not (np.isfinite(v_c) and v_c > 0):
                raise StackFileError(f"{cs.source}.calibration_velocity: the rigid model predicts no "
                                     f"impact at interface {j}; give a calibration_velocity")
        radius = _effective_radius(spec, cs, j, n) if LAWS[cs.law].needs_radius else None
        with _section(spec, cs, j):
            laws[j] = _law(cs, stiffness[j], float(m_eff[j]), v_c, radius, limits.get(j))
    bodies = spec.stack
    stack = Stack(m, [laws[j] for j in interfaces], gravity=g, ground=ground, end_force=bodies.end_force)
    if bodies.preload:
        # static equilibrium under gravity and the end force (a precompressed chain), then either the
        # file's velocities or a drop at the impact speed with the preload kept (mass 1 just touching)
        rest = resting(stack)
        v = spec.drop.impact_velocity or 0.0
        if bodies.velocities is not None:
            state = State(rest.positions, v0)
        elif v > 0:
            state = State(rest.positions - rest.positions[0], np.full(n, -v))
        else:
            state = rest
    elif bodies.velocities is not None:
        gaps = np.asarray(bodies.gap_list(n), dtype=float)
        x = np.concatenate([[0.0], np.cumsum(gaps)])
        state = State(x, v0)
    else:
        state = at_impact(stack, spec.drop.impact_velocity, np.asarray(bodies.gap_list(n), dtype=float))
    if spec.wall is not None:
        stack = _with_wall(spec, stack, state, laws, interfaces)
        wall_limit = _wall_yield_limit(spec, n)
        if wall_limit is not None:
            limits[WALL_INTERFACE] = wall_limit
    s = spec.solver
    tol = {k: v for k, v in (("rtol", s.rtol), ("atol", s.atol)) if v is not None}
    if s.onset_window is not None:
        tol["onset_window"] = s.onset_window
    options = {"solver": s.solver,
               "tolerances": Tolerances(**tol, flight_steps=s.flight_steps, land_onsets=s.land_onsets)}
    if s.t_max is not None:
        options["t_max"] = s.t_max
    if s.max_steps is not None:
        options["max_steps"] = s.max_steps
    if s.until != "cascade":
        options["until"] = s.until
    return BuiltStack(stack=stack, state=state, masses=m, nominal_restitution=e_nom, laws=tuple(laws),
                 simulate_options=options, n_output=s.n_output, dt_output=s.dt_output, title=spec.title,
                 yield_limits=tuple(limits[j] for j in sorted(limits)))

