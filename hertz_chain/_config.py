"""One place for process-wide JAX settings: float64, CPU cores as devices, CPU computations run inline,
the compilation cache.

Imported (for its side effects) by every module that uses JAX, before any array is created.
"""

from __future__ import annotations

import os

import jax

from ._cache import cache_dir

jax.config.update("jax_enable_x64", True)


def _jax_started() -> bool:
    """JAX's backends exist already (their settings can no longer change), or we cannot tell."""
    try:
        from jax._src import xla_bridge

        return bool(xla_bridge.backends_are_initialized())
    except (ImportError, AttributeError):  # pragma: no cover  (private API moved: leave JAX alone)
        return True


def run_cpu_computations_inline() -> bool:
    """Run each CPU computation on the calling thread (``jax_cpu_enable_async_dispatch = False``).

    JAX's CPU client otherwise hands every computation of more than ~1,000 flops to a worker thread and
    the caller waits for it: on the 2-core machine of `benchmarks/` that handoff cost ~170-200 us per call
    (a prepared two-mass launch: median 370-430 us per call asynchronously, 205 us inline), more than the
    whole fixed cost budget of a repeated solve. Parallel computations (a batch split over the CPU
    devices) still run one thread per device. Only before JAX has started, and only when the user has not
    chosen: ``JAX_CPU_ENABLE_ASYNC_DISPATCH`` in the environment, or ``jax.config.update`` *after*
    importing hertz_chain and before the first computation (an update before the import cannot be told
    from JAX's default, and is overridden). Returns whether it was set.
    """
    if _jax_started() or "JAX_CPU_ENABLE_ASYNC_DISPATCH" in os.environ:
        return False
    jax.config.update("jax_cpu_enable_async_dispatch", False)
    return True


def expose_cpu_cores() -> int | None:
    """Make every CPU core a JAX device, so that `simulate_batch` can split a batch over the cores (XLA
    runs one design loop per device on one thread). Only before JAX has started, and only when the user
    has not chosen (``XLA_FLAGS=--xla_force_host_platform_device_count``, ``jax_num_cpu_devices``);
    ``HERTZ_CHAIN_CPU_DEVICES=N`` sets the number (1: one device). No effect on GPU machines' GPUs.
    Returns the number set, or None.
    """
    if _jax_started():
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

#: XLA options of the compiled single solves (`simulate`, `launch_velocity`, `prepare_launch`; not batches):
#: XLA's older CPU loop emitters. A single solve is a loop of many tiny kernels, which the older emitters
#: compile ~25 % faster and run ~10-14 % faster (10-mass gapped Tsuji: 7.1 -> 6.1 ms, compile 3.8 -> 2.8 s);
#: a batch of 1,024 designs runs ~40 % slower with them, so batches keep XLA's default. CPU only: XLA
#: refuses a CPU option on another backend ("No such compile option", seen on an NVIDIA H200), so the
#: callers take them through `solve_compiler_options()`. Results differ from the default emitters' by
#: rounding (~1e-11 relative), well inside the solver's tolerance. docs/solver-defaults.md, "XLA's loop
#: emitters".
SOLVE_COMPILER_OPTIONS = {"xla_cpu_use_fusion_emitters": False}


def solve_compiler_options() -> dict | None:
    """`SOLVE_COMPILER_OPTIONS` where JAX computes on the CPU (its default backend now), else None (a GPU
    or TPU takes XLA's defaults). Costs ~0.3 us: callers ask at every call."""
    return SOLVE_COMPILER_OPTIONS if jax.default_backend() == "cpu" else None

CACHE_DIR: str | None = None
"""The compilation cache folder in use (None: off); `_export` keeps its traced functions below it."""


def enable_compilation_cache(path: str | None = None) -> str | None:
    """Turn on JAX's persistent compilation cache in `path`, default ``cache_dir("jax")``
    (``~/.cache/hertz_chain/jax``, or ``$HERTZ_CHAIN_CACHE_DIR/jax``; `hertz_chain._cache`).

    Set ``HERTZ_CHAIN_NO_CACHE=1`` to disable it. A JAX cache folder the user chose
    (``JAX_COMPILATION_CACHE_DIR``, or ``jax_compilation_cache_dir`` set before) is kept, with the user's
    other cache settings; hertz_chain's own traced solves (`_export`) still go below `path` (a review:
    since `import hertz_chain` sets this up as soon as JAX is imported, it overrode the user's folder).
    Returns the folder used, or None.
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
    if not (os.environ.get("JAX_COMPILATION_CACHE_DIR") or jax.config.jax_compilation_cache_dir):
        jax.config.update("jax_compilation_cache_dir", path)
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
        jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    global CACHE_DIR
    CACHE_DIR = path
    return path


enable_compilation_cache()
expose_cpu_cores()
run_cpu_computations_inline()
