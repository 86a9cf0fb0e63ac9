"""Traced functions kept on disk (`jax.export`), so that a new process skips the Python trace.

JAX's persistent compilation cache (`_config`) saves XLA's compile, not the trace and lowering that come
before it: a warm `hertz-chain simulate` of the demo still spent 0.5 s tracing diffrax's solver loop and
0.12 s lowering it, a fifth of the command's time. `jax.export` serialises the lowered module (StableHLO
with a versioned calling convention: JAX's supported format for keeping a traced function); a later
process reads it back in about 2 ms, and compiling it hits the compilation cache.

`cached_jit(fn, name, compiler_options)` returns a function that behaves as `eqx.filter_jit(fn)`.
It uses the disk only where the result is certain to be the same:

- the key covers `name`, the structure of the arguments with their static values (as text), every array's
  shape and dtype, the versions of numpy, jax, jaxlib, equinox, diffrax, lineax and optimistix, a hash of
  hertz_chain's own source files, the JAX platform, and the JAX settings that change a trace (float64,
  dtype and rank promotion, matmul precision; read at every call, so context managers count);
- only for arguments built from classes of hertz_chain, JAX, equinox, diffrax, lineax, optimistix and
  Python's containers, and static values of plain types (numbers, strings, bools, None, enums, NumPy
  scalars and dtypes, tuples of these): a user's own class (a contact law, a solver) can change its code
  between runs under the same name, and other values may print differently in the next process;
- only under equinox's `EQX_ON_ERROR=raise` (the default) or `nan` (the command line's setting), as equinox
  read it at import, which is part of the key. Under `raise` equinox's run-time checks are host callbacks,
  and a module with a host callback cannot be serialised: such a function is marked unexportable (below)
  and keeps `jitted`'s path. The solve (`_solve._solve_plain`) has none: it reports its outcome as a status,
  and passes diffrax no `dt0` to check (`FlightController.init`);
- never for traced or weakly typed arguments (a call under an outer `jit`, `vmap` or `grad`; Python
  scalars turned into arrays), whose promotion rules an exported module does not keep;
- `fn` must return only dicts, lists, tuples, None and arrays (the pytree nodes `jax.export` serialises).

Every failure to export, read, write or run the exported module falls back to `jitted`; a function that
cannot be exported is marked (`<key>.unexportable`) so that later processes do not try again. Files live in
`<compilation cache folder>/export/` (`~/.cache/hertz_chain/jax/export`), named by the fingerprint of the
versions and source: entries of another fingerprint (an upgrade, an edit) are deleted when a new entry is
written, and at most `MAX_ENTRIES` are kept (the oldest go first). `HERTZ_CHAIN_NO_CACHE=1` turns both
caches off.
"""

from __future__ import annotations

import enum
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

_MEMO: dict[tuple, Callable | None] = {}  # (disk key, compile options) -> the exported call
MAX_ENTRIES = 256
_TRUSTED = ("hertz_chain", "jax", "jaxlib", "equinox", "diffrax", "lineax", "optimistix", "builtins",
            "collections")
_PLAIN = (bool, int, float, complex, str, bytes, type(None), np.generic, np.dtype, enum.Enum)


@functools.cache
def _fingerprint() -> str | None:
    """Versions and the package's own source: anything that could change what a trace produces (None
    when the source cannot be read, e.g. a zipped install)."""
    import diffrax
    import jaxlib
    import lineax
    import optimistix

    h = hashlib.sha256()
    for mod in (np, jax, jaxlib, eqx, diffrax, lineax, optimistix):
        h.update(f"{mod.__name__}={getattr(mod, '__version__', '?')};".encode())
    h.update(f"platform={jax.default_backend()};".encode())
    sources = sorted(Path(__file__).resolve().parent.glob("*.py"))
    if not sources:
        return None
    for path in sources:
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _settings() -> str:
    """The JAX settings that change a trace, as they are now (global or set by a context manager)."""
    c = jax.config
    return (f"x64={c.jax_enable_x64};promotion={c.jax_numpy_dtype_promotion};"
            f"rank={c.jax_numpy_rank_promotion};matmul={c.jax_default_matmul_precision}")


def _eqx_on_error() -> str | None:
    try:
        from equinox._config import EQX_ON_ERROR  # what equinox read at import; the variable may differ now

        return EQX_ON_ERROR
    except ImportError:  # pragma: no cover  (moved in another equinox: trust nothing)
        return None


def _folder() -> Path | None:
    root = _config.CACHE_DIR
    if root is None or _eqx_on_error() not in ("nan", "raise"):
        return None
    return Path(root) / "export"


def _trusted_nodes(treedef) -> bool:
    """Every node class of `treedef` comes from a package whose code the fingerprint covers."""
    if jax.tree_util.treedef_is_leaf(treedef):
        return True
    kind = treedef.node_data()[0]
    if kind.__module__.split(".")[0] not in _TRUSTED:
        return False
    return all(_trusted_nodes(child) for child in treedef.children())


def _plain(value) -> bool:
    if isinstance(value, tuple):
        return all(_plain(v) for v in value)
    return isinstance(value, _PLAIN)


def _key(name: str, leaves: list, dyn_tree, static: Any) -> str | None:
    """The cache key, or None where the cache cannot be exact (module docstring)."""
    fingerprint = _fingerprint()
    static_leaves, static_tree = jax.tree_util.tree_flatten(static)
    if (fingerprint is None or not _trusted_nodes(dyn_tree) or not _trusted_nodes(static_tree)
            or not all(_plain(v) for v in static_leaves)
            or any(getattr(x, "weak_type", False) for x in leaves)):
        return None
    static_text = f"{static_tree}|{static_leaves!r}"
    if " at 0x" in static_text:  # printed with an address: not the same text in the next process
        return None
    arrays = [(tuple(np.shape(x)), str(x.dtype)) for x in leaves]
    text = f"{name}|{_settings()}|eqx_on_error={_eqx_on_error()}|{dyn_tree}|{static_text}|{arrays}"
    return f"{fingerprint}-{hashlib.sha256(text.encode()).hexdigest()[:32]}"


def _prune(folder: Path, keep: Path) -> None:
    """Delete entries of another fingerprint, and the oldest beyond `MAX_ENTRIES`."""
    prefix = keep.name.split("-")[0] + "-"
    try:
        entries = [p for p in folder.iterdir() if p != keep]
        for p in entries:
            if not p.name.startswith(prefix):
                p.unlink(missing_ok=True)
        mine = sorted((p for p in folder.iterdir() if p.suffix == ".jaxexport"), key=lambda p: p.stat().st_mtime)
        for p in mine[:max(0, len(mine) - MAX_ENTRIES)]:
            if p != keep:
                p.unlink(missing_ok=True)
    except OSError:
        pass


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


def _load_or_export(path: Path, name: str, fn: Callable, leaves: list, dyn_tree, static: Any,
                    compiler_options: dict | None = None) -> Callable | None:
    from jax import export

    try:
        exported = export.deserialize(bytearray(path.read_bytes()))
    except Exception:  # not there yet, damaged or foreign: export afresh (and replace it)
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
        except MemoryError:
            return None  # may not recur: no marker
        except Exception as exc:  # host callbacks, a non-serialisable output, flatbuffers missing, ...
            try:
                _write(marker, f"{type(exc).__name__}: {exc}"[:2000].encode())
            except OSError:
                pass
            return None
        try:
            _write(path, bytes(blob))
            _prune(path.parent, path)
        except OSError:
            pass  # still use it in this process

    def run(*xs):
        return exported.call(*xs)

    run.__name__ = run.__qualname__ = f"{name.replace('.', '_')}_exported"  # names its compilation-cache entry
    return jax.jit(run, compiler_options=compiler_options)


def _top_level(args) -> bool:
    """No JAX transformation is tracing the call (not under the caller's `jit`, `grad` or `vmap`)."""
    try:
        from jax._src.core import trace_state_clean  # JAX's own test (private: checked, with a fallback)
    except ImportError:  # pragma: no cover
        return not any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(args))
    return trace_state_clean()


def jit_per_options(fn: Callable) -> Callable[[dict | None], Callable]:
    """A function of XLA compile options (a dict, or None for XLA's defaults) returning `eqx.filter_jit(fn)`
    compiled with them: one jit per distinct set of options, made on first use."""
    plain = eqx.filter_jit(fn)
    made: dict = {}

    def with_options(options: dict | None) -> Callable:
        if not options:
            return plain
        k = tuple(sorted(options.items()))
        if k not in made:
            made[k] = eqx.filter_jit(fn, compiler_options=options)
        return made[k]

    return with_options


def cached_jit(fn: Callable, name: str, compiler_options: Callable[[], dict | None] | None = None) -> Callable:
    """`eqx.filter_jit(fn)`, with the traced function kept on disk where that is exact (module docstring).
    A call at the top level (no argument traced) is compiled with the XLA options that
    `compiler_options()` returns at the call (None: XLA's defaults; e.g. `_config.solve_compiler_options`,
    CPU options on the CPU backend only), the exported module too; a call under the caller's own `jit`,
    `grad` or `vmap` is part of the caller's computation (JAX takes compile options only at the top
    level), compiled as the caller's is."""
    top_for = jit_per_options(fn)
    jitted = top_for(None)
    keys: dict = {}  # the disk key of each call signature seen, so that a repeated call hashes nothing

    @functools.wraps(fn)
    def call(*args):
        if not _top_level(args):
            return jitted(*args)
        options = compiler_options() if compiler_options else None
        top = top_for(options)
        folder = _folder()
        if folder is None:
            return top(*args)
        dyn, static = eqx.partition(args, eqx.is_array)
        leaves, dyn_tree = jax.tree_util.tree_flatten(dyn)
        try:
            sig = (dyn_tree, static, tuple((np.shape(x), np.dtype(x.dtype), getattr(x, "weak_type", False))
                                           for x in leaves), _settings(), str(folder))
            key = keys[sig] if sig in keys else keys.setdefault(sig, _key(name, leaves, dyn_tree, static))
        except TypeError:  # an unhashable static value: no memo
            key = _key(name, leaves, dyn_tree, static)
        if key is None:
            return top(*args)
        memo = (key, tuple(sorted(options.items())) if options else None)  # the module is compiled with them
        if memo not in _MEMO:
            _MEMO[memo] = _load_or_export(folder / f"{key}.jaxexport", name, fn, leaves, dyn_tree, static,
                                          options)
        run = _MEMO[memo]
        if run is None:
            return top(*args)
        try:
            return run(*leaves)
        except Exception:  # a file that loads but does not fit, a changed setting, ...: never the user's problem
            _MEMO[memo] = None
            return top(*args)

    return call
