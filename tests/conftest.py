"""Test configuration: float64 everywhere, as in the library (hertz_chain._config)."""

import os

os.environ.setdefault("HERTZ_CHAIN_NO_CACHE", "1")  # tests measure nothing from a warm disk cache

import jax

jax.config.update("jax_enable_x64", True)
