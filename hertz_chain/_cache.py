"""The one place that decides where hertz_chain keeps its on-disk caches (no JAX, no pint: cheap to import).

Every cache user asks `cache_dir(kind)` for its folder:

* `cache_dir("jax")`: JAX's persistent compilation cache (`_config`), with `_export`'s traced
  functions in its `export/` subfolder;
* `cache_dir("pint")`: pint's parsed unit definitions (`units`);
* `cache_dir("sweeps")`: the designs per second of the last sweep of each structure, for the time
  estimate printed before a sweep runs (`sweeps.recorded_rate`).

The root is ``HERTZ_CHAIN_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/hertz_chain``, else
``~/.cache/hertz_chain``; ``HERTZ_CHAIN_NO_CACHE`` (any non-empty value) turns every cache off, and then
`cache_dir` returns None. The environment is read at each call; nothing is created here (each user
creates its folder, and falls back to no cache when it cannot).
"""

from __future__ import annotations

import os

__all__ = ["cache_dir"]


def cache_dir(kind: str | None = None) -> str | None:
    """The cache root (``kind=None``) or its subfolder ``kind`` (``"jax"``, ``"pint"``), or None when
    ``HERTZ_CHAIN_NO_CACHE`` is set. See the module docstring for the environment variables."""
    if os.environ.get("HERTZ_CHAIN_NO_CACHE"):
        return None
    root = os.environ.get("HERTZ_CHAIN_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "hertz_chain")
    return root if kind is None else os.path.join(root, kind)
