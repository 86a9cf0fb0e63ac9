"""Shared test helpers (not tests): tolerances, the stacks several test files use, and edited stack files."""

import copy

import numpy as np

from hertz_chain.simulation import Tolerances
from hertz_chain.stack import STANDARD_GRAVITY

G = STANDARD_GRAVITY
TIGHT = Tolerances(rtol=1e-11, atol=1e-11)


def mvg(n, ratio=0.5):
    """A geometric stack of n masses, bottom 1 kg, each `ratio` times the one below."""
    return ratio ** np.arange(n)


DELETE = object()
"""A value for `patched` that removes the key."""


def patched(data: dict, changes: dict) -> dict:
    """A deep copy of the parsed stack file `data` with dotted keys set (value `DELETE` removes the key)."""
    data = copy.deepcopy(data)
    for dotted, value in changes.items():
        *parents, last = dotted.split(".")
        node = data
        for p in parents:
            node = node.setdefault(p, {})
        if value is DELETE:
            node.pop(last, None)
        else:
            node[last] = value
    return data
