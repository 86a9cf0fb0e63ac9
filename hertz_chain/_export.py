"""Traced functions kept on disk (`jax.export`), so that a new process skips the Python trace.

JAX's persistent compilation cache (`_config`) saves XLA's compile, not the trace and lowering that come
before it: a warm `hertz-chain simulate` of the demo still spent 0.5 s tracing diffrax's solver loop and
0.12 s lowering it, a fifth of the command's time. `jax.export` serialises the lowered module (StableHLO
with a versioned calling convention: JAX's supported format for keeping a traced function); a later
process reads it back in about 2 ms, and compiling it hits the compilation cache.

`cached_jit(fn, jitted, name)` returns a function that behaves as `jitted` (an `eqx.filter_jit` of `fn`).
It uses the disk only where the result is certain to be the same:

- the key covers `name`, the structure of the arguments with their static values (as text), every array's
  shape and dtype, the versions of jax, jaxlib, equinox, diffrax, lineax and optimistix, a hash of
  hertz_chain's own source files, float64 and the JAX platform. A static value whose text is not stable
  (an object printed with its address) turns the cache off for that call;
- only under `EQX_ON_ERROR=nan` (the command line's setting): equinox's run-time checks are host
  callbacks otherwise, and a module with a host callback cannot be serialised. The Python API therefore
  keeps `jitted`'s path unless the user sets it;
- never for traced arguments (a call under an outer `jit`, `vmap` or `grad`);
- `fn` must return only dicts, lists, tuples, None and arrays (the pytree nodes `jax.export` serialises).

Every failure to export, read or write falls back to `jitted`; a function that cannot be exported is
marked (`<key>.unexportable`) so that later processes do not try again. Files live in
`<compilation cache folder>/export/` (`~/.cache/hertz_chain/jax/export`); `HERTZ_CHAIN_NO_CACHE=1` turns
both caches off.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from pathlib import Path
from typing import Any, Callable

import equinox as eqx
import jax
import numpy as np

from . import _config

_MEMO: dict[str, Callable | None] = {}


@functools.cache
def _fingerprint() -> str:
    """Versions and the package's own source: anything that could change what a trace produces."""
    import diffrax
    import jaxlib
    import lineax
    import optimistix

    h = hashlib.sha256()
    for mod in (jax, jaxlib, eqx, diffrax, lineax, optimistix):
        h.update(f"{mod.__name__}={getattr(mod, '__version__', '?')};".encode())
    h.update(f"x64={jax.config.jax_enable_x64};platform={jax.default_backend()};".encode())
    for path in sorted(Path(__file__).resolve().parent.glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def _folder() -> Path | None:
    root = _config.CACHE_DIR
    if root is None or os.environ.get("EQX_ON_ERROR") != "nan":
        return None
    return Path(root) / "export"


def _key(name: str, leaves: list, dyn_tree, static: Any) -> str | None:
    static_text = f"{jax.tree_util.tree_structure(static)}|{jax.tree_util.tree_leaves(static)!r}"
    if " at 0x" in static_text:  # printed with an address: not the same text in the next process
        return None
    arrays = [(tuple(np.shape(x)), str(x.dtype), bool(getattr(x, "weak_type", False))) for x in leaves]
    text = f"{name}|{_fingerprint()}|{dyn_tree}|{static_text}|{arrays}"
    return hashlib.sha256(text.encode()).hexdigest()[:40]


def _write(path: Path, blob: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(blob)
        os.replace(tmp, path)  # atomic: a concurrent reader sees the old file or the new one
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _load_or_export(path: Path, name: str, fn: Callable, leaves: list, dyn_tree, static: Any) -> Callable | None:
    from jax import export

    try:
        exported = export.deserialize(bytearray(path.read_bytes()))
    except FileNotFoundError:
        exported = None
    except Exception:  # damaged or foreign file: export afresh and replace it
        exported = None
    if exported is None:
        marker = path.with_suffix(".unexportable")
        if marker.exists():
            return None

        def flat(*xs):
            return fn(*eqx.combine(jax.tree_util.tree_unflatten(dyn_tree, xs), static))

        specs = [jax.ShapeDtypeStruct(np.shape(x), x.dtype) for x in leaves]
        try:
            exported = export.export(jax.jit(flat))(*specs)
            blob = exported.serialize()
        except Exception as exc:  # host callbacks, a non-serialisable output, flatbuffers missing, ...
            try:
                _write(marker, f"{type(exc).__name__}: {exc}"[:2000].encode())
            except OSError:
                pass
            return None
        try:
            _write(path, bytes(blob))
        except OSError:
            pass  # still use it in this process
    def run(*xs):
        return exported.call(*xs)

    run.__name__ = run.__qualname__ = f"{name.replace('.', '_')}_exported"  # names its compilation-cache entry
    return jax.jit(run)


def cached_jit(fn: Callable, jitted: Callable, name: str) -> Callable:
    """`jitted` (an `eqx.filter_jit(fn)`), with the traced function kept on disk where that is exact
    (module docstring)."""

    @functools.wraps(fn)
    def call(*args):
        folder = _folder()
        if folder is None:
            return jitted(*args)
        dyn, static = eqx.partition(args, eqx.is_array)
        leaves, dyn_tree = jax.tree_util.tree_flatten(dyn)
        if any(isinstance(x, jax.core.Tracer) for x in leaves):
            return jitted(*args)
        key = _key(name, leaves, dyn_tree, static)
        if key is None:
            return jitted(*args)
        if key not in _MEMO:
            _MEMO[key] = _load_or_export(folder / f"{key}.jaxexport", name, fn, leaves, dyn_tree, static)
        run = _MEMO[key]
        return jitted(*args) if run is None else run(*leaves)

    return call
