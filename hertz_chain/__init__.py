"""hertz_chain: design and simulate shock amplifiers (stacks of progressively lighter masses).

The public API is re-exported here, flat. See README.md for the architecture.
"""

from . import _config  # noqa: F401  (float64, compilation cache)
from .contact import (
    AbstractContactLaw,
    Hertz,
    HuntCrossley,
    KelvinVoigt,
    Tsuji,
    Viscoelastic,
)
from .errors import HertzChainError, ParameterError, SolverError, StackFileError

__version__ = "0.1.0"
