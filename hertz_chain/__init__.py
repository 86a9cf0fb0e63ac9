"""hertz_chain: design and simulate shock amplifiers (stacks of progressively lighter masses).

The public API, re-exported flat. Submodules hold the rest (`hertz_chain.rigid` has every closed form
of the seed paper, `hertz_chain.calibration` every restitution map, ...). See README.md for the
architecture and conventions.
"""


import importlib as _importlib
import os as _os
import sys as _sys
from typing import TYPE_CHECKING as _TYPE_CHECKING

# float64 from the import on, also for arrays a user makes before any JAX-using part of the package is
# loaded (a review: `jnp.array([...])` right after `import hertz_chain` was float32, its values already
# rounded). JAX not imported yet: its environment default (read when it is imported); imported: set now.
if "jax" in _sys.modules:
    _sys.modules["jax"].config.update("jax_enable_x64", True)
else:
    _os.environ.setdefault("JAX_ENABLE_X64", "1")


# The CPU cores as devices and inline CPU dispatch (`_config`) also when the user's first JAX array comes
# before any hertz_chain function (a review: `jax.random` samples drawn first left one device and JAX's
# asynchronous dispatch: batches 2.1x and prepared calls 1.7-3x slower, without a word). JAX imported
# already: `_config` now (cheap then); not yet: right after JAX's own import, by a one-shot import hook,
# so that `import hertz_chain` and `hertz-chain --help` still do not import JAX.
class _ConfigureAfterJax:
    """A `sys.meta_path` finder for the top-level `jax` package only: it lets the other finders find it and
    runs `hertz_chain._config` once its module has executed; it removes itself when JAX has been imported
    (not at a mere `importlib.util.find_spec("jax")`, whose spec is thrown away: a review)."""

    searching = False

    def find_spec(self, name, path=None, target=None):
        if name != "jax" or self.searching:
            return None
        import importlib.util

        self.searching = True  # the other finders' spec, not this one's again
        try:
            spec = importlib.util.find_spec("jax")
        finally:
            self.searching = False
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        loader, finder = spec.loader, self

        class _Loader:
            def create_module(self, spec):
                return loader.create_module(spec)

            def exec_module(self, module):
                loader.exec_module(module)
                if finder in _sys.meta_path:
                    _sys.meta_path.remove(finder)
                try:
                    _importlib.import_module("hertz_chain._config")
                except Exception:  # pragma: no cover  (never break the user's `import jax`)
                    pass

            def __getattr__(self, attr):  # anything else the import system or a tool asks the loader
                return getattr(loader, attr)

        spec.loader = _Loader()
        return spec


if "jax" in _sys.modules:
    _importlib.import_module("hertz_chain._config")
elif not any(isinstance(f, _ConfigureAfterJax) for f in _sys.meta_path):
    _sys.meta_path.insert(0, _ConfigureAfterJax())

# Public name -> the submodule that defines it. Resolved on first use (PEP 562), so that
# `import hertz_chain` and `hertz-chain --help` do not pay for importing JAX and diffrax.
_EXPORTS = {
    "Report": "analysis",
    "RigidComparison": "analysis",
    "analyse": "analysis",
    "independence": "analysis",
    "wave_speed": "analysis",
    "accelerometer": "analysis",
    "cfc_filter": "filters",
    "Comparison": "measured",
    "MeasuredPulse": "measured",
    "compare": "measured",
    "read_pulse_csv": "measured",
    "sprague_geers": "measured",
    "CheckResult": "standards",
    "ShockCondition": "standards",
    "check": "standards",
    "find_condition": "standards",
    "BuiltStack": "builder",
    "build": "builder",
    "CHI_MAPS": "calibration",
    "chi_from_restitution": "calibration",
    "chi_map_table": "calibration",
    "hunt_crossley_alpha": "calibration",
    "hunt_crossley_restitution": "calibration",
    "kelvin_voigt_damping_ratio": "calibration",
    "tsuji_eta": "calibration",
    "viscoelastic_restitution": "calibration",
    "LAW_NAMES": "contact",
    "AbstractContactLaw": "contact",
    "Hertz": "contact",
    "HuntCrossley": "contact",
    "KelvinVoigt": "contact",
    "Tsuji": "contact",
    "Viscoelastic": "contact",
    "HertzDashpot": "contact",
    "PowerLaw": "contact",
    "Thornton": "contact",
    "JacksonGreen": "contact",
    "make_law": "contact",
    "ContactEpisode": "episodes",
    "contact_episodes": "episodes",
    "HertzChainError": "errors",
    "GradientAccuracyWarning": "errors",
    "ParameterError": "errors",
    "SolverError": "errors",
    "StackFileError": "errors",
    "Material": "materials",
    "contact_stiffness": "materials",
    "effective_mass": "materials",
    "material": "materials",
    "material_names": "materials",
    "G0": "constants",
    "OptimizeResult": "optimization",
    "optimize": "optimization",
    "FitResult": "fitting",
    "fit": "fitting",
    "PulseMetrics": "pulse",
    "pulse_metrics": "pulse",
    "DesignComparison": "rigid",
    "StackDesign": "rigid",
    "cascade_velocities": "rigid",
    "chain_gain": "rigid",
    "design": "rigid",
    "energy_efficiencies": "rigid",
    "impact_velocities": "rigid",
    "met_design": "rigid",
    "met_gain": "rigid",
    "met_masses": "rigid",
    "mvg_design": "rigid",
    "mvg_gain": "rigid",
    "mvg_masses": "rigid",
    "mvg_optimal_n": "rigid",
    "mvg_optimal_n_pb": "rigid",
    "stack_gain": "rigid",
    "velocity_gains": "rigid",
    "RigidBatchResult": "rigid_events",
    "RigidResult": "rigid_events",
    "simulate_rigid": "rigid_events",
    "simulate_rigid_batch": "rigid_events",
    "BatchSolution": "simulation",
    "Restitution": "simulation",
    "Solution": "simulation",
    "Tolerances": "simulation",
    "Trajectory": "simulation",
    "UnrolledTsit5": "simulation",
    "launch_velocity": "simulation",
    "restitution": "simulation",
    "simulate_impact": "simulation",
    "prepare_launch": "simulation",
    "simulate": "simulation",
    "simulate_batch": "simulation",
    "ShockResponseSpectrum": "spectrum",
    "octave_frequencies": "spectrum",
    "srs": "spectrum",
    "STANDARD_GRAVITY": "constants",
    "Status": "status",
    "Stack": "stack",
    "State": "stack",
    "at_impact": "stack",
    "dropped": "stack",
    "resting": "stack",
    "precompressed": "stack",
    "stack_designs": "stack",
    "simulate_file": "workflow",
    "SweepResult": "sweeps",
    "sweep": "sweeps",
    "StackSpec": "stackfile",
    "load_stack_file": "stackfile",
    "parse_stack": "stackfile",
}

__version__ = "0.1.0"
__all__ = sorted(_EXPORTS)


#: Public names renamed in this round (CHANGELOG.md): an old name fails with the new one in its message.
_RENAMED = {"Built": "BuiltStack"}


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        if name in _RENAMED:
            raise AttributeError(f"hertz_chain.{name} is renamed {_RENAMED[name]} (CHANGELOG.md)")
        raise AttributeError(f"module 'hertz_chain' has no attribute {name!r}")
    value = getattr(_importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))


if _TYPE_CHECKING:  # the same names, spelled out for type checkers and IDEs
    from .analysis import Report, RigidComparison, accelerometer, analyse, independence
    from .builder import BuiltStack, build
    from .calibration import (
        CHI_MAPS,
        chi_from_restitution,
        chi_map_table,
        hunt_crossley_alpha,
        hunt_crossley_restitution,
        kelvin_voigt_damping_ratio,
        tsuji_eta,
        viscoelastic_restitution,
    )
    from .contact import (
        LAW_NAMES,
        AbstractContactLaw,
        Hertz,
        HertzDashpot,
        HuntCrossley,
        KelvinVoigt,
        PowerLaw,
        Thornton,
        Tsuji,
        Viscoelastic,
        make_law,
    )
    from .episodes import ContactEpisode, contact_episodes
    from .filters import cfc_filter
    from .measured import Comparison, MeasuredPulse, compare, read_pulse_csv, sprague_geers
    from .errors import GradientAccuracyWarning, HertzChainError, ParameterError, SolverError, StackFileError
    from .materials import Material, contact_stiffness, effective_mass, material, material_names
    from .constants import G0, STANDARD_GRAVITY
    from .optimization import OptimizeResult, optimize
    from .fitting import FitResult, fit
    from .pulse import PulseMetrics, pulse_metrics
    from .rigid import (
        DesignComparison,
        StackDesign,
        cascade_velocities,
        chain_gain,
        design,
        energy_efficiencies,
        impact_velocities,
        met_design,
        met_gain,
        met_masses,
        mvg_design,
        mvg_gain,
        mvg_masses,
        mvg_optimal_n,
        mvg_optimal_n_pb,
        stack_gain,
        velocity_gains,
    )
    from .rigid_events import RigidBatchResult, RigidResult, simulate_rigid, simulate_rigid_batch
    from .simulation import (
        BatchSolution,
        Restitution,
        Solution,
        Tolerances,
        Trajectory,
        UnrolledTsit5,
        launch_velocity,
        restitution,
        simulate_impact,
        prepare_launch,
        simulate,
        simulate_batch,
    )
    from .spectrum import ShockResponseSpectrum, octave_frequencies, srs
    from .standards import CheckResult, ShockCondition, check, find_condition
    from .status import Status
    from .stack import Stack, State, at_impact, dropped, resting, stack_designs
    from .stackfile import StackSpec, load_stack_file, parse_stack
    from .sweeps import SweepResult, sweep
    from .workflow import simulate_file

