"""Test configuration: float64 everywhere, as in the library (hertz_chain._config), and no implicit rank
promotion (`jax_numpy_rank_promotion = "raise"`, as diffrax tests itself).

The on-disk caches are on, as for users (`hertz_chain._cache`), but in a fresh folder for this test session
only: nothing is read from an earlier run or from the user's own cache, and compiles are shared between
the two pytest-xdist workers and the command-line and notebook subprocesses of the session (it halves
the suite's compile time). The folder is made by the first process that loads this file (the xdist
controller); the workers and subprocesses inherit it through the environment. Set
`HERTZ_CHAIN_NO_CACHE=1` to run the whole suite without any cache.
"""

import atexit
import os
import shutil
import tempfile

if not os.environ.get("HERTZ_CHAIN_NO_CACHE") and not os.environ.get("HERTZ_CHAIN_TEST_CACHE"):
    _session_cache = tempfile.mkdtemp(prefix="hertz-chain-test-cache-")
    os.environ["HERTZ_CHAIN_TEST_CACHE"] = _session_cache
    os.environ["HERTZ_CHAIN_CACHE_DIR"] = _session_cache
    atexit.register(shutil.rmtree, _session_cache, ignore_errors=True)
# two CPU devices on every machine, so that simulate_batch's split over devices is always exercised
os.environ.setdefault("HERTZ_CHAIN_CPU_DEVICES", "2")
# diffrax's strict setting: an implicit broadcast of arrays of different ranks is an error, here and in
# the command-line and notebook subprocesses (which inherit it, and so share the compile cache)
os.environ.setdefault("JAX_NUMPY_RANK_PROMOTION", "raise")

import jax

jax.config.update("jax_enable_x64", True)
