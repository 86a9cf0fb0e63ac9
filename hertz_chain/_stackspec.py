"""The stack file's vocabulary and its validated form: bounds, accepted keys, and the frozen `StackSpec`.

`hertz_chain.stackfile` is the entry (`load_stack_file`, `parse_stack`); the section readers are
`hertz_chain._stacksections`. This module holds what both of them and every reader of a spec share:
the bounds of the "Physical ranges and sizes" section of docs/stack-files.md, the keys each section
accepts, and the spec dataclasses (plain SI floats, strings and tuples; no pint objects, no JAX).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .registry import CHI_MAPS as _CHI_MAP_ROWS
from .registry import LAWS
from .registry import SOLVERS as _SOLVER_ROWS
from .units import _UNITS


# ---- bounds (the "Physical ranges and sizes" section of docs/stack-files.md)
MAX_STEPS = 10_000_000
"""Largest `solver.max_steps`: the solver keeps buffers of `max_steps` rows."""
MAX_RUN_MEMORY = 4 * 2**30
"""Largest step history a stack file may ask for (bytes, `run_memory`): 4 GiB."""


def run_memory(n: int, max_steps: int) -> int:
    """Bytes of the step history `simulate` keeps for `n` masses and `max_steps` steps: the scaled state
    (`3n` physical, `n` onset proxies, one flag) and the time of every step, float64, plus the
    derived quantities of the used rows (positions, velocities, accelerations, overlaps, rates,
    forces, dissipation: `7n`)."""
    return 8 * (max_steps + 1) * ((4 * n + 2) + 7 * n)


MAX_OUTPUT_POINTS = 1_000_000
"""Largest `solver.n_output`, and largest `solver.t_max / solver.dt_output`."""
MIN_DT_OUTPUT = 1e-7
"""Smallest `solver.dt_output` (s) when `solver.t_max` is not given (the run's length is not known here)."""
MIN_RESTITUTION = 1e-3
"""Smallest restitution (the calibration of the contact laws supports 0.001 <= e <= 1)."""
MAX_FILE_BYTES = 10_000_000
"""Largest stack file (bytes) that `load_stack_file` reads."""
# the vocabularies: one table each in `hertz_chain.registry`
CONTACT_LAWS = tuple(LAWS)
CHI_MAPS = tuple(_CHI_MAP_ROWS)
SOLVERS = tuple(_SOLVER_ROWS)

DAMPING_LIMITS = {name: (row.damping_max, f" {_UNITS[row.damping_dimension]}" if row.damping_dimension in _UNITS
                         else "") for name, row in LAWS.items() if row.damping == "damping"}
"""Largest `damping` per law (`registry.LawRow.damping_max`): Tsuji's eta (plain), Kelvin-Voigt's c
(N s/m), the viscoelastic A (s)."""
DESIGN_KINDS = ("mvg", "met")
SHAPES = ("sphere", "flat")

_TOP_KEYS = ("title", "drop", "stack", "ground", "wall", "contact", "materials", "solver", "optimize", "sweep",
             "test", "srs", "fit")
_WALL_KEYS = ("material", "stiffness", "gap")
_SRS_KEYS = ("q", "damping", "per_octave", "band", "peak", "type")
#: Where an SRS band may lie (Hz), and its largest f_max/f_min: the filters run at 50 samples per cycle of
#: f_max and pad the record by a cycle of f_min, so the work grows as f_max/f_min (5 decades: 5e6
#: samples per frequency), and the pseudo-velocity's discretisation is checked to fs/f = 1e5 (docs).
SRS_BAND_LIMITS = (0.01, 1e7)
SRS_MAX_SPAN = 1e5
# `optimize`, `sweep`, `test` and `fit` are read by `hertz_chain.optimization`, `hertz_chain.sweeps`,
# `hertz_chain.standards` and `hertz_chain.fitting` (docs/optimize.md, docs/sweeps.md,
# docs/lab-workflow.md); simulating such a file runs its base stack
_DROP_KEYS = ("ground", "impact_velocity", "height", "gravity")
_STACK_KEYS = ("masses", "design", "gaps", "velocities", "preload", "end_force", "material", "radius", "shape")
_DESIGN_KEYS = ("kind", "n", "restitution", "bottom_mass", "top_mass", "mass_ratio")
_GROUND_KEYS = ("material", "shape", "radius")
_MATERIAL_KEYS = ("youngs_modulus", "poisson_ratio", "density", "yield_strength")
_CONTACT_KEYS = (
    "law",
    "stiffness",
    "restitution",
    "chi_map",
    "calibration_velocity",
    "alpha",
    "damping",
    "clamp",
) + tuple(dict.fromkeys(key for row in LAWS.values() for key, _ in row.params))  # e.g. thornton's yield_pressure
_SOLVER_KEYS = ("solver", "rtol", "atol", "t_max", "until", "max_steps", "n_output", "dt_output", "flight_steps",
                "land_onsets", "onset_window")


# --------------------------------------------------------------------------------------------------
# The spec: frozen dataclasses of plain SI floats, strings and tuples
# --------------------------------------------------------------------------------------------------


def _expand(value: Any, count: int, what: str) -> tuple:
    """A single value repeated `count` times, or a tuple checked to have `count` entries."""
    if isinstance(value, tuple):
        if len(value) != count:
            raise ValueError(f"{what} has {len(value)} entries, expected {count}")
        return value
    return (value,) * count


@dataclass(frozen=True)
class MaterialSpec:
    """A material defined in the file (`[materials.NAME]`).

    `youngs_modulus` in Pa, `poisson_ratio` dimensionless, `density` in kg/m³ (or `None`),
    `yield_strength` in Pa (or `None`).
    """

    name: str
    youngs_modulus: float
    poisson_ratio: float
    density: float | None = None
    yield_strength: float | None = None


@dataclass(frozen=True)
class DesignSpec:
    """An MVG (seed paper Eq 15) or MET (Eq 25) design, left for the rigid module to compute.

    `n` is `None` for `"optimal"`. Masses in kg; `mass_ratio` is R = m_n/m_1. For MVG all three of
    `bottom_mass`, `top_mass`, `mass_ratio` are filled in (two given, the third derived); for MET
    with an integer `n` exactly one of `bottom_mass`/`top_mass` is set and `mass_ratio` is `None`.
    """

    kind: str
    n: int | None
    restitution: float
    bottom_mass: float | None = None
    top_mass: float | None = None
    mass_ratio: float | None = None
    #: False where `restitution` was not given and is `contact.restitution`'s (the design follows it)
    restitution_given: bool = True


@dataclass(frozen=True)
class StackSectionSpec:
    """The `[stack]` section: the masses and their per-body properties (formerly `BodiesSpec`).

    Exactly one of `masses` (kg, bottom first) and `design` is set. Per-body and per-gap values are
    a single value (the same for all; always so when the number of masses is not known yet) or a
    tuple with one entry per mass (per gap for `gaps`, n−1 entries); use the `*_list(n)` methods to
    get tuples. `gaps` in m; `velocities` in m/s, upward-positive, or `None`; `end_force` in N (a
    constant force on the top mass toward mass 1; `preload` then defaults to true); `radius` in m
    (`inf` for a flat face) or `None`; `shape` `"sphere"`/`"flat"` or `None`; `material` names or
    `None`.
    """

    masses: tuple[float, ...] | None
    design: DesignSpec | None
    gaps: float | tuple[float, ...]
    velocities: tuple[float, ...] | None = None
    preload: bool = False
    material: str | tuple[str, ...] | None = None
    radius: float | tuple[float, ...] | None = None
    shape: str | tuple[str, ...] | None = None
    end_force: float = 0.0

    @property
    def n(self) -> int | None:
        """The number of masses, or `None` while an `"optimal"` design leaves it open."""
        if self.masses is not None:
            return len(self.masses)
        return self.design.n if self.design is not None else None

    def gap_list(self, n: int) -> tuple[float, ...]:
        """The n−1 gaps (m) between masses j and j+1, j = 1..n−1."""
        return _expand(self.gaps, n - 1, "stack.gaps")

    def radius_list(self, n: int) -> tuple[float, ...] | None:
        """The n cap radii (m; `inf` = flat), or `None` when no geometry was given."""
        return None if self.radius is None else _expand(self.radius, n, "stack.radius")

    def shape_list(self, n: int) -> tuple[str, ...] | None:
        """The n shapes, or `None` when no geometry was given."""
        return None if self.shape is None else _expand(self.shape, n, "stack.shape")

    def material_list(self, n: int) -> tuple[str, ...] | None:
        """The n material names, or `None` when no material was given."""
        return None if self.material is None else _expand(self.material, n, "stack.material")


@dataclass(frozen=True)
class DropSpec:
    """`[drop]`: `gravity` in m/s² (≥ 0, acting downward); `impact_velocity` in m/s, the positive
    downward speed at first ground contact (`None` when `stack.velocities` sets the state, or
    without a ground); `height` in m when the file gave one (`impact_velocity` = √(2 g h))."""

    gravity: float
    impact_velocity: float | None = None
    height: float | None = None


@dataclass(frozen=True)
class GroundSpec:
    """`[ground]`: `material` name (`None`: rigid), `shape`, `radius` in m (`inf` when flat)."""

    material: str | None = None
    shape: str = "flat"
    radius: float = math.inf


@dataclass(frozen=True)
class ContactSpec:
    """One resolved contact law (defaults and inheritance already applied), SI units.

    `stiffness` is N/m^1.5 for the Hertzian laws and N/m for `kelvin-voigt`; `None` means "compute
    it from materials and geometry". Damping is one of `restitution` (with `chi_map` and an optional
    `calibration_velocity` in m/s), `alpha` (s/m, hunt-crossley) or `damping` (tsuji η, plain;
    kelvin-voigt c, N s/m; viscoelastic A, s); all `None` for `hertz`. `source` is the dotted key of
    the section that defined it (for error messages at build time).
    """

    law: str
    stiffness: float | None = None
    restitution: float | None = None
    chi_map: str | None = None
    calibration_velocity: float | None = None
    alpha: float | None = None
    damping: float | None = None
    clamp: bool = True
    source: str = "contact"
    params: tuple[tuple[str, float], ...] = ()  # the law's further keys (`registry.LawRow.params`), in SI


@dataclass(frozen=True)
class ContactsSpec:
    """The contact of every interface: `default` (`[contact]`), `ground` (interface 0: the
    `[contact.ground]` override or the default; `None` without a ground) and `overrides`, pairs
    `(j, ContactSpec)` sorted by j, from `[[contact.interface]]`."""

    default: ContactSpec
    ground: ContactSpec | None = None
    overrides: tuple[tuple[int, ContactSpec], ...] = ()

    def interface(self, j: int) -> ContactSpec:
        """The contact of interface `j` (0 = ground–mass 1, j = mass j – mass j+1)."""
        if j == 0:
            if self.ground is None:
                raise ValueError("this stack has no ground, so no interface 0")
            return self.ground
        for index, spec in self.overrides:
            if index == j:
                return spec
        return self.default


@dataclass(frozen=True)
class SolverSpec:
    """`[solver]`; `None` leaves the simulator's default. `t_max`, `dt_output` in s."""

    solver: str = "tsit5"
    rtol: float | None = None
    atol: float | None = None
    t_max: float | None = None
    max_steps: int | None = None
    n_output: int | None = None
    dt_output: float | None = None
    until: str = "cascade"
    flight_steps: bool = True  # `Tolerances.flight_steps`: long steps through free flights
    land_onsets: bool = True  # `Tolerances.land_onsets`: contact onsets met by a step end, stepped in s
    onset_window: float | None = None  # `Tolerances.onset_window` (contact times), None: its default


@dataclass(frozen=True)
class SRSSpec:
    """`[srs]`: how the report's SRS of the top pulse is computed (`hertz_chain.spectrum.SRSOptions`).
    `band` in Hz, or None for the default band."""

    q: float = 10.0
    per_octave: int = 12
    band: tuple[float, float] | None = None
    peak: str = "abs"
    type: str = "acceleration"


@dataclass(frozen=True)
class WallSpec:
    """`[wall]`: a rigid flat wall beyond the top mass (the far end of a chain between two walls), whose
    contact with the top mass is elastic Hertz: `stiffness` in N/m^1.5, or `None` to compute it from
    `material` (the wall's) and the top mass's material and radius; `gap` in m between the top mass and
    the wall at the start (`None`: touching, or with `stack.end_force` the precompressed equilibrium)."""

    material: str | None = None
    stiffness: float | None = None
    gap: float | None = None


@dataclass(frozen=True)
class StackSpec:
    """A whole stack file, validated, in SI units. `ground` is `None` for a chain without ground."""

    drop: DropSpec
    stack: StackSectionSpec
    contact: ContactsSpec
    ground: GroundSpec | None = GroundSpec()
    solver: SolverSpec = SolverSpec()
    materials: tuple[MaterialSpec, ...] = ()
    title: str | None = None
    source: str | None = None
    srs: SRSSpec = SRSSpec()
    wall: WallSpec | None = None

    @property
    def n(self) -> int | None:
        """Number of masses (`None` for an `"optimal"` design, decided by the rigid module)."""
        return self.stack.n

    @property
    def has_ground(self) -> bool:
        return self.ground is not None

    def contact_for(self, j: int) -> ContactSpec:
        """The contact law of interface `j` (see `ContactsSpec.interface`)."""
        return self.contact.interface(j)

    def material(self, name: str) -> MaterialSpec | None:
        """The material `name` if the file defines it in `[materials]`, else `None`."""
        for m in self.materials:
            if m.name == name:
                return m
        return None

    def initial_velocities(self, n: int | None = None) -> tuple[float, ...]:
        """Upward-positive initial velocities (m/s): `stack.velocities`, or −impact_velocity for
        every mass of a dropped stack. `n` is needed only when the spec leaves it open."""
        if self.stack.velocities is not None:
            return self.stack.velocities
        n = self.n if n is None else n
        if n is None:
            raise ValueError("the number of masses is not known yet: pass n")
        return (-float(self.drop.impact_velocity),) * n


