"""One place for process-wide JAX settings: float64, CPU cores as devices, the compilation cache.

Imported (for its side effects) by every module that uses JAX, before any array is created.
"""

from __future__ import annotations

import os

import jax

from ._cache import cache_dir

jax.config.update("jax_enable_x64", True)


def expose_cpu_cores() -> int | None:
    """Make every CPU core a JAX device, so that `simulate_batch` can split a batch over the cores (XLA
    runs one design loop per device on one thread). Only before JAX has started, and only when the user
    has not chosen (``XLA_FLAGS=--xla_force_host_platform_device_count``, ``jax_num_cpu_devices``);
    ``HERTZ_CHAIN_CPU_DEVICES=N`` sets the number (1: one device). No effect on GPU machines' GPUs.
    Returns the number set, or None.
    """
    try:
        from jax._src import xla_bridge

        if xla_bridge.backends_are_initialized():
            return None
    except (ImportError, AttributeError):  # pragma: no cover  (private API moved: leave JAX alone)
        return None
    if "xla_force_host_platform_device_count" in os.environ.get("XLA_FLAGS", "") \
            or jax.config.jax_num_cpu_devices != -1:
        return None
    want = os.environ.get("HERTZ_CHAIN_CPU_DEVICES", "")
    try:
        n = int(want) if want else len(os.sched_getaffinity(0))
    except (ValueError, AttributeError):
        n = os.cpu_count() or 1
    n = max(1, min(n, 64))
    jax.config.update("jax_num_cpu_devices", n)
    return n

CACHE_DIR: str | None = None
"""The compilation cache folder in use (None: off); `_export` keeps its traced functions below it."""


def enable_compilation_cache(path: str | None = None) -> str | None:
    """Turn on JAX's persistent compilation cache in `path`, default ``cache_dir("jax")``
    (``~/.cache/hertz_chain/jax``, or ``$HERTZ_CHAIN_CACHE_DIR/jax``; `hertz_chain._cache`).

    Set ``HERTZ_CHAIN_NO_CACHE=1`` to disable it. Returns the folder used, or None.
    """
    if os.environ.get("HERTZ_CHAIN_NO_CACHE"):
        return None
    path = path or cache_dir("jax")
    if path is None:
        return None
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return None
    jax.config.update("jax_compilation_cache_dir", path)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    global CACHE_DIR
    CACHE_DIR = path
    return path


enable_compilation_cache()
expose_cpu_cores()
