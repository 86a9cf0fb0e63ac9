"""Compile-time probe, run in a fresh subprocess by `run.py` (cold: empty cache folder; warm: the same
folder again). Prints one JSON line: import time, first call (trace + compile or cache load + run) and
second call (run only) of `simulate` and of `launch_velocity` for the 5-mass gapped Tsuji design.

The cache folder comes from the environment (`HERTZ_CHAIN_CACHE_DIR`, read by `hertz_chain._config`).
"""

from __future__ import annotations

import json
import os
import sys
import time

t0 = time.perf_counter()
import jax  # noqa: E402

import hertz_chain as hc  # noqa: E402
from hertz_chain import simulate as _sim  # noqa: E402,F401  (imports JAX, diffrax; sets the cache)

t_import = time.perf_counter() - t0
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cases  # noqa: E402

stack, state = cases.build(5, "gapped-tsuji")
tol = hc.Tolerances()  # the library default


def timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


sim = lambda: hc.simulate(stack, state, tolerances=tol)  # noqa: E731
lv = lambda: jax.block_until_ready(hc.launch_velocity(stack, state, tolerances=tol, max_steps=4096))  # noqa: E731
out = dict(
    import_s=t_import,
    simulate_first_s=timed(sim),
    simulate_second_s=timed(sim),
    launch_first_s=timed(lv),
    launch_second_s=timed(lv),
    cache_dir=jax.config.jax_compilation_cache_dir,
)
print(json.dumps(out))
