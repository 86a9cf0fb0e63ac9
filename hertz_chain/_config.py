"""One place for process-wide JAX settings: float64 and the persistent compilation cache.

Imported (for its side effects) by every module that uses JAX, before any array is created.
"""

from __future__ import annotations

import os

import jax

jax.config.update("jax_enable_x64", True)

_DEFAULT_CACHE = os.path.join(
    os.environ.get("XDG_CACHE_HOME", os.path.join(os.path.expanduser("~"), ".cache")),
    "hertz_chain",
    "jax",
)


def enable_compilation_cache(path: str | None = None) -> str | None:
    """Turn on JAX's persistent compilation cache (default: ``~/.cache/hertz_chain/jax``).

    Set ``HERTZ_CHAIN_NO_CACHE=1`` to disable it. Returns the folder used, or None.
    """
    if os.environ.get("HERTZ_CHAIN_NO_CACHE"):
        return None
    path = path or os.environ.get("HERTZ_CHAIN_CACHE_DIR", _DEFAULT_CACHE)
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return None
    jax.config.update("jax_compilation_cache_dir", path)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    return path


enable_compilation_cache()
