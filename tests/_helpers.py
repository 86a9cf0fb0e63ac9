"""Shared test helpers (not tests): tolerances and the stacks several test files use."""

import numpy as np

from hertz_chain.simulate import Tolerances
from hertz_chain.stack import STANDARD_GRAVITY

G = STANDARD_GRAVITY
TIGHT = Tolerances(rtol=1e-11, atol=1e-11)


def mvg(n, ratio=0.5):
    """A geometric stack of n masses, bottom 1 kg, each `ratio` times the one below."""
    return ratio ** np.arange(n)
