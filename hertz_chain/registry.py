"""The vocabularies of hertz_chain, one table each: contact laws (`LAWS`), Hunt–Crossley restitution
maps (`CHI_MAPS`) and ODE solvers (`SOLVERS`), in the manner of scipy's `solve_ivp` `METHODS`.

Every entry point reads these tables: `contact.make_law`, the stack-file parser (`stackfile`), the
builder (`build`), the calibration (`calibration.CHI_MAPS`), `simulation.make_solver`, and the tests,
which run every row end to end (`tests/test_registry.py`). Adding a contact law is one class in
`hertz_chain.contact` (with a `from_config` classmethod) and one row here; adding a solver or a map is
one row.

Plain Python (no JAX, no numpy): the command line reads it while checking a stack file, before anything
heavy is imported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

__all__ = ["LawRow", "LAWS", "ChiMapRow", "CHI_MAPS", "SolverRow", "SOLVERS"]


# ==================================================================== contact laws
@dataclass(frozen=True)
class LawRow:
    """One contact law.

    - `name`: its configuration name (stack files, `make_law`); `cls`: its class in
      `hertz_chain.contact`, whose `from_config` builds it.
    - `stiffness`: the dimension of its `stiffness` (`"hertz_stiffness"`, N/m^1.5, for the Hertzian
      laws, whose stiffness can also come from materials and radii; `"linear_stiffness"`, N/m).
    - `damping`: the stack-file key of its own damping parameter (`None` for an elastic law), its
      dimension (a `stackfile` dimension name), its largest value, and how messages describe it;
      `aliases`: the other keywords `make_law` accepts for it.
    - `smooth_onset`: its force and the force's derivatives stay bounded as a contact closes (no
      `delta^(1/4)` or `sqrt(delta)` factor on the rate, no jump of a linear dashpot). Reverse mode
      (`simulation.launch_velocity`) differentiates every law accurately since onsets are split out of
      the replayed steps (2e-6 against central differences with gaps, `tests/test_optimize.py`); forward
      mode and diffrax's adjoints do not for the other laws (errors of order 1 with gaps), and
      `hertz_chain.optimization` still uses batched central differences for them. A stack whose every
      law has a smooth onset is replayed with plain steps (no split: cheaper, as accurate).
    - `speed_dependent`: its restitution changes with the impact speed, so calibrating it to a
      restitution needs a `calibration_velocity`; `needs_effective_mass`: calibrating it (or the law
      itself) needs the interface's effective mass; `chi_map`: it takes a `CHI_MAPS` entry.
    - `memory`: the law keeps an internal variable per interface in the ODE state (elastic–plastic: the
      largest overlap so far); its restitution follows from its own parameters and the impact speed, so
      it takes no `restitution`. `params`: the further stack-file keys it needs, as `(key, dimension)`
      (a `stackfile` dimension name), passed to its `from_config` by name; `needs_radius`: it needs the
      interface's effective radius (from `stack.radius`), passed as `effective_radius`.
      `from_materials`: the keys of `params` that may instead follow from the materials (`yield_pressure`:
      `p_y = 1.6 Y` of the softer of the two bodies, `materials.YIELD_PRESSURE_FACTOR`; `yield_strength`:
      that body's Y). `context`: optional values the law takes from the materials when they are known
      (`poisson_ratio`: the yielding body's), never from the file.
    """

    name: str
    cls: str
    stiffness: str = "hertz_stiffness"
    damping: str | None = None
    damping_dimension: str | None = None
    damping_max: float | None = None
    damping_label: str = ""
    aliases: tuple[str, ...] = ()
    speed_dependent: bool = False
    needs_effective_mass: bool = False
    chi_map: bool = False
    smooth_onset: bool = False
    memory: bool = False
    params: tuple[tuple[str, str], ...] = ()
    needs_radius: bool = False
    from_materials: tuple[str, ...] = ()
    context: tuple[str, ...] = ()

    @property
    def hertzian(self) -> bool:
        """Its stiffness is a Hertz stiffness (N/m^1.5), computable from materials and radii."""
        return self.stiffness == "hertz_stiffness"

    @property
    def elastic(self) -> bool:
        """Its restitution is 1 (no damping, no plasticity)."""
        return self.damping is None and not self.memory

    @property
    def keywords(self) -> tuple[str, ...]:
        """Every keyword of its damping parameter (`make_law`)."""
        return () if self.damping is None else self.aliases + (self.damping,)

    def file_keys(self) -> frozenset[str]:
        """The keys a stack-file contact section with this law may hold (besides `law`)."""
        keys = {"stiffness", "clamp"} | {key for key, _ in self.params}
        if self.damping is not None:
            keys |= {"restitution", self.damping}
        if self.chi_map:
            keys.add("chi_map")
        if self.speed_dependent:
            keys.add("calibration_velocity")
        return frozenset(keys)

    def hint(self) -> str:
        """What it takes, for error messages."""
        if self.memory:
            return f"the {self.name!r} law takes {', '.join(k for k, _ in self.params)} (no restitution)"
        if self.elastic:
            return f"the {self.name!r} law is elastic (no damping)"
        extra = " with chi_map" if self.chi_map else (" (with calibration_velocity)" if self.speed_dependent else "")
        return f"{self.name!r} takes restitution{extra} or {self.damping} ({self.damping_label})"


LAWS: dict[str, LawRow] = {row.name: row for row in (
    LawRow("hertz", "Hertz", smooth_onset=True),
    LawRow("hunt-crossley", "HuntCrossley", damping="alpha", damping_dimension="inverse_velocity",
           damping_max=1e6, damping_label="alpha, s/m", speed_dependent=True, chi_map=True,
           smooth_onset=True),
    LawRow("tsuji", "Tsuji", damping="damping", damping_dimension="dimensionless", damping_max=1e6,
           damping_label="eta", aliases=("eta",), needs_effective_mass=True),
    LawRow("kelvin-voigt", "KelvinVoigt", stiffness="linear_stiffness", damping="damping",
           damping_dimension="viscous_damping", damping_max=1e9, damping_label="c, N s/m",
           needs_effective_mass=True),
    LawRow("viscoelastic", "Viscoelastic", damping="damping", damping_dimension="time", damping_max=1.0,
           damping_label="A, s", aliases=("A",), speed_dependent=True, needs_effective_mass=True),
    LawRow("hertz-dashpot", "HertzDashpot", damping="damping", damping_dimension="viscous_damping",
           damping_max=1e9, damping_label="gamma, N s/m", speed_dependent=True, needs_effective_mass=True),
    LawRow("power", "PowerLaw", stiffness="power_stiffness", damping="alpha", damping_dimension="inverse_velocity",
           damping_max=1e6, damping_label="alpha, s/m", speed_dependent=True, chi_map=True,
           params=(("exponent", "dimensionless"),)),
    LawRow("thornton", "Thornton", memory=True, params=(("yield_pressure", "pressure"),), needs_radius=True,
           from_materials=("yield_pressure",)),
    LawRow("jackson-green", "JacksonGreen", memory=True, params=(("yield_strength", "pressure"),), needs_radius=True,
           from_materials=("yield_strength",), context=("poisson_ratio",)),
)}
"""Contact laws by configuration name (see `LawRow`)."""


# ==================================================================== Hunt–Crossley chi maps
@dataclass(frozen=True)
class ChiMapRow:
    """A map `e -> chi` for `F = k delta^{3/2} (1 + chi delta_dot / v_0)`: `formula` (plain Python;
    `None` for the exact map, which `hertz_chain.calibration` inverts numerically) and its `source`."""

    name: str
    formula: Callable[[float], float] | None
    source: str


CHI_MAPS: dict[str, ChiMapRow] = {row.name: row for row in (
    ChiMapRow("hunt-crossley", lambda e: 1.5 * (1.0 - e), "Hunt & Crossley (1975), J. Appl. Mech. 42, 440"),
    ChiMapRow("herbert-mcwhannell", lambda e: 6.0 * (1.0 - e) / ((2.0 * e - 1.0) ** 2 + 3.0),
              "Herbert & McWhannell (1977), J. Eng. Ind. 99, 513"),
    ChiMapRow("lee-wang", lambda e: 0.75 * (1.0 - e), "Lee & Wang (1983), J. Mech. Transm. Autom. Des. 105, 534"),
    ChiMapRow("lankarani-nikravesh", lambda e: 0.75 * (1.0 - e * e),
              "Lankarani & Nikravesh (1990), J. Mech. Des. 112, 369"),
    ChiMapRow("gonthier", lambda e: (1.0 - e * e) / e,
              "Gonthier, McPhee, Lange & Piedboeuf (2004), Multibody Syst. Dyn. 11, 209"),
    ChiMapRow("zhiying-qishao", lambda e: 0.75 * (1.0 - e * e) * math.exp(2.0 * (1.0 - e)),
              "Zhiying & Qishao (2006), Acta Mech. Sin. 22, 79 (as quoted by Flores et al. 2011)"),
    ChiMapRow("flores", lambda e: 8.0 * (1.0 - e) / (5.0 * e),
              "Flores, Machado, Silva & Martins (2011), Multibody Syst. Dyn. 25, 357"),
    ChiMapRow("hu-guo", lambda e: 1.5 * (1.0 - e) / e,
              "Hu & Guo (2015), Multibody Syst. Dyn. 35, 131 (the 3(1-e)/(2e) form)"),
    ChiMapRow("exact", None, "Carvalho & Martins (2019), Mech. Mach. Theory 139, 1: exact for F = K d^p (1 + chi d'/v0)"),
)}
"""Hunt–Crossley restitution maps by configuration name (see `ChiMapRow`)."""


# ==================================================================== solvers
def _diffrax(name: str) -> Callable[[Any], Any]:
    def make(tolerances):
        import diffrax

        return getattr(diffrax, name)()

    return make


def _unrolled(name):
    def make(tolerances):
        from . import _solver

        return getattr(_solver, name)()

    return make


def _kvaerno5_chord(tolerances):
    # Chord iterations (Jacobian frozen per step) stopped on a proper Cauchy test at a tenth of the
    # step controller's tolerances (measured best among Chord/Newton at 1e-2, 1e-1, 1 x tol).
    import diffrax
    import optimistix

    rf = optimistix.Chord(rtol=tolerances.rtol * 1e-1, atol=tolerances.atol * 1e-1)
    return diffrax.Kvaerno5(root_finder=rf, root_find_max_steps=10)


@dataclass(frozen=True)
class SolverRow:
    """An ODE solver: `make(tolerances)` returns the diffrax solver (it imports JAX only when called)."""

    name: str
    make: Callable[[Any], Any]
    description: str


SOLVERS: dict[str, SolverRow] = {row.name: row for row in (
    SolverRow("tsit5", _unrolled("UnrolledTsit5"), "Tsitouras 5(4) with its stages written out (the default)"),
    SolverRow("tsit5-diffrax", _diffrax("Tsit5"), "diffrax's Tsit5: the same method, its stages in a loop"),
    SolverRow("dopri5", _unrolled("UnrolledDopri5"), "Dormand–Prince 5(4), its stages written out"),
    SolverRow("dopri5-diffrax", _diffrax("Dopri5"), "diffrax's Dopri5: the same method, its stages in a loop"),
    SolverRow("dopri8", _unrolled("UnrolledDopri8"), "Dormand–Prince 8(7), its stages written out"),
    SolverRow("dopri8-diffrax", _diffrax("Dopri8"), "diffrax's Dopri8: the same method, its stages in a loop"),
    SolverRow("kvaerno5", _kvaerno5_chord, "Kvaerno5, implicit, with a Chord iteration that terminates properly"),
    SolverRow("kvaerno5-stock", _diffrax("Kvaerno5"), "diffrax 0.7.2's Kvaerno5 as shipped (VeryChord)"),
)}
"""ODE solvers by name (see `SolverRow`)."""
