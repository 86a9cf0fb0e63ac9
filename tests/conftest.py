"""Test configuration: float64 everywhere, as in the library (hertz_chain._config)."""

import os

os.environ.setdefault("HERTZ_CHAIN_NO_CACHE", "1")  # tests measure nothing from a warm disk cache
# two CPU devices on every machine, so that simulate_batch's split over devices is always exercised
os.environ.setdefault("HERTZ_CHAIN_CPU_DEVICES", "2")

import jax

jax.config.update("jax_enable_x64", True)
