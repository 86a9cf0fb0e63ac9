"""The disk cache of traced solves (`hertz_chain._export`).

Reference for every result: the same solve through `eqx.filter_jit` alone (`HERTZ_CHAIN_NO_CACHE=1`, or
the process's own jitted path), which must agree bit for bit: the exported module is the same StableHLO
that `jax.jit` compiles, so any difference at all would be a defect, not round-off.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hertz_chain as hc
from hertz_chain import _config, _export

SCRIPT = r"""
import json, sys
import numpy as np
import hertz_chain as hc
from hertz_chain import _export
n = int(sys.argv[1])
stack = hc.Stack(0.5 ** np.arange(n), hc.Hertz(1e9), gravity=0.0)
sol = hc.simulate(stack, hc.at_impact(stack, 1.0, gaps=1e-3))
print(json.dumps({"v": [float(x).hex() for x in np.asarray(sol.launch_velocities)],
                  "t": [float(x).hex() for x in np.asarray(sol.steps.t)[:sol.num_accepted_steps + 1]],
                  "e": float(sol.energy_error).hex(), "steps": int(sol.num_steps),
                  "cached": [k for k, v in _export._MEMO.items() if v is not None]}))
"""


def _run(n: int, tmp: Path, **env) -> dict:
    full = {**os.environ, "HERTZ_CHAIN_CACHE_DIR": str(tmp), "EQX_ON_ERROR": "nan"}
    full.pop("HERTZ_CHAIN_NO_CACHE", None)
    full.update(env)
    full = {k: v for k, v in full.items() if v is not None}
    proc = subprocess.run([sys.executable, "-c", SCRIPT, str(n)], env=full, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _same(a: dict, b: dict) -> bool:
    return all(a[k] == b[k] for k in ("v", "t", "e", "steps"))


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("export")
    folder = tmp / "jax" / "export"
    first = _run(3, tmp)
    files_after_first = sorted(p.name for p in folder.glob("*.jaxexport"))
    stamps = {p.name: p.stat().st_mtime_ns for p in folder.iterdir()}
    second = _run(3, tmp)
    reread = stamps == {p.name: p.stat().st_mtime_ns for p in folder.iterdir()}
    plain = _run(3, tmp, HERTZ_CHAIN_NO_CACHE="1")
    return dict(tmp=tmp, folder=folder, first=first, second=second, plain=plain, files=files_after_first,
                reread=reread)


def test_exported_solve_is_written_read_and_bit_identical(runs):
    assert len(runs["files"]) == 1
    assert runs["first"]["cached"] and runs["second"]["cached"]  # both ran the exported module
    assert runs["reread"]  # the second process read the file and wrote nothing
    # issue 6: "make sure the compiled functions can be cached": the solve's executable is in JAX's cache
    assert any(p.name.startswith("jit_simulate__solve_exported") for p in (runs["tmp"] / "jax").iterdir())
    assert not runs["plain"]["cached"]  # HERTZ_CHAIN_NO_CACHE: filter_jit only
    assert _same(runs["first"], runs["plain"]) and _same(runs["second"], runs["plain"])


def test_another_shape_gets_its_own_entry(runs, tmp_path):
    other = _run(4, runs["tmp"])
    assert len(list(runs["folder"].glob("*.jaxexport"))) == 2
    assert _same(other, _run(4, tmp_path, HERTZ_CHAIN_NO_CACHE="1"))


def test_a_damaged_entry_is_replaced_not_trusted(runs):
    (path,) = [runs["folder"] / name for name in runs["files"]]
    path.write_bytes(b"\x00 not a serialized module")
    again = _run(3, runs["tmp"])
    assert _same(again, runs["plain"])
    assert path.read_bytes() != b"\x00 not a serialized module"  # exported afresh


def test_python_api_default_exports_too_and_keys_equinox_s_setting(runs, tmp_path):
    """Under equinox's default (`EQX_ON_ERROR=raise`, the Python API's) the solve holds no host callback
    (no `dt0` for diffrax to check at run time), so it is exported as well: under its own key (the
    setting is part of it) and bit for bit the plain path's result, in a first and a second process."""
    first = _run(3, tmp_path, EQX_ON_ERROR=None)
    second = _run(3, tmp_path, EQX_ON_ERROR=None)
    assert first["cached"] and second["cached"]
    assert first["cached"] != runs["first"]["cached"]  # another key than under `nan`
    folder = tmp_path / "jax" / "export"
    assert len(list(folder.glob("*.jaxexport"))) == 1 and not list(folder.glob("*.unexportable"))
    assert _same(first, runs["plain"]) and _same(second, runs["plain"])


def test_unexportable_function_is_marked_and_falls_back(tmp_path, monkeypatch):
    """In this process equinox raises, so its run-time check is a host callback and a function with one
    cannot be exported: the call must still return the jitted result (and raise where it should), and a
    marker must stop later processes from trying again."""
    import equinox as eqx
    import jax.numpy as jnp

    monkeypatch.setattr(_config, "CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(_export, "_eqx_on_error", lambda: "nan")  # a lie: equinox was imported with raise
    monkeypatch.setattr(_export, "_MEMO", {})

    def checked(x):
        return eqx.error_if(2.0 * x, x < 0, "negative input")

    f = _export.cached_jit(checked, "test.checked")
    np.testing.assert_array_equal(np.asarray(f(jnp.arange(3.0))), [0.0, 2.0, 4.0])
    markers = list((tmp_path / "export").glob("*.unexportable"))
    assert len(markers) == 1 and not list((tmp_path / "export").glob("*.jaxexport"))
    with pytest.raises(Exception, match="negative input"):
        f(-jnp.ones(3))


def _parts(*args):
    import equinox as eqx
    import jax

    dyn, static = eqx.partition(args, eqx.is_array)
    leaves, tree = jax.tree_util.tree_flatten(dyn)
    return leaves, tree, static


def test_static_values_without_stable_text_are_not_cached():
    assert _export._key("f", *_parts(np.zeros(3), lambda x: x)) is None
    assert _export._key("f", *_parts(np.zeros(3), frozenset({"a", "b"}))) is None  # order varies per process
    assert _export._key("f", *_parts(np.zeros(3), 1.5, "tsit5", (1, 2))) is not None


def test_user_classes_and_weak_types_are_not_cached():
    """A user's class may change its code under the same name between runs (the fingerprint covers only
    hertz_chain and its libraries); a weakly typed array promotes differently from the exported one."""
    import equinox as eqx
    import jax.numpy as jnp

    class Law(eqx.Module):
        k: float

    assert _export._key("f", *_parts(Law(np.ones(2)))) is None
    assert _export._key("f", *_parts(hc.Hertz(1e9))) is not None
    assert _export._key("f", *_parts(jnp.asarray(2.0))) is None  # weak_type=True
    assert _export._key("f", *_parts(jnp.asarray(2.0, dtype=float))) is not None


def test_jax_settings_are_part_of_the_key():
    import jax

    parts = _parts(np.zeros(3))
    plain = _export._key("f", *parts)
    with jax.numpy_dtype_promotion("strict"):
        assert _export._key("f", *parts) != plain
    with jax.default_matmul_precision("highest"):
        assert _export._key("f", *parts) != plain
    assert _export._key("f", *parts) == plain


def test_a_failing_exported_call_falls_back(tmp_path, monkeypatch):
    """An entry that loads but fails when run (here: one that raises) must give the jitted result and be
    dropped for the rest of the process."""
    calls = []

    def fn(x):
        calls.append("traced")  # once, by the fallback's `jit` (the broken entry traces nothing)
        return {"y": x * 2.0}

    monkeypatch.setattr(_config, "CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(_export, "_eqx_on_error", lambda: "nan")
    x = np.arange(3.0)
    key = _export._key("t", *_parts(x))

    def broken(*_):
        raise ValueError("Dtype mismatch")

    monkeypatch.setattr(_export, "_MEMO", {(key, None): broken})  # (disk key, compile options)
    out = _export.cached_jit(fn, "t")(x)
    np.testing.assert_array_equal(out["y"], [0.0, 2.0, 4.0])
    assert calls == ["traced"] and _export._MEMO[(key, None)] is None


def test_prune_keeps_this_fingerprint_and_at_most_max_entries(tmp_path, monkeypatch):
    import time

    monkeypatch.setattr(_export, "MAX_ENTRIES", 3)
    old = [tmp_path / f"aaaa-{i}.jaxexport" for i in range(2)] + [tmp_path / "aaaa-9.unexportable"]
    mine = [tmp_path / f"bbbb-{i}.jaxexport" for i in range(5)]
    for i, p in enumerate(old + mine):
        p.write_bytes(b"x")
        os.utime(p, (time.time() - 100 + i, time.time() - 100 + i))
    _export._prune(tmp_path, mine[-1])
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == ["bbbb-2.jaxexport", "bbbb-3.jaxexport", "bbbb-4.jaxexport"]


def test_cpu_compile_options_only_on_the_cpu_backend(tmp_path, monkeypatch):
    """XLA refuses a CPU option on another backend ("No such compile option: 'xla_cpu_use_fusion_emitters'",
    seen on an NVIDIA H200), so the single solves take `SOLVE_COMPILER_OPTIONS` on the CPU backend only,
    asked at each call. Here the options are made invalid for every backend: reported as the CPU backend,
    `prepare_launch`, `launch_velocity` and `simulate` (through the disk cache of traced solves; each its
    own path to the options) must fail with them, so the options do reach XLA on every path; reported as a
    GPU, the same three must run without them and give paper Eq 19 for two elastic masses (ratio 0.3,
    gap 1 cm, no gravity: mass 1 bounces off the ground first, so the top leaves at 2 (2 / 1.3) - 1
    times the drop speed) to 1e-8."""
    import jax

    if jax.default_backend() != "cpu":
        pytest.skip("reports the backend as the CPU: on the CPU backend only")
    monkeypatch.setattr(_config, "CACHE_DIR", str(tmp_path))  # a fresh disk cache of traced solves
    monkeypatch.setattr(_export, "_MEMO", {})
    monkeypatch.setattr(_config, "SOLVE_COMPILER_OPTIONS", {"xla_hertz_chain_no_such_option": True})
    stack = hc.Stack([1.0, 0.3], hc.Hertz(1e9), gravity=0.0)
    state = hc.at_impact(stack, 1.0, 0.01)
    tol = hc.Tolerances(rtol=1e-11, atol=1e-11)
    eq19 = 2 * (2 / 1.3) - 1
    assert _config.solve_compiler_options() is not None
    for call in (lambda: hc.prepare_launch(stack, state, tolerances=tol)(stack, state),
                 lambda: hc.launch_velocity(stack, state, tolerances=tol),
                 lambda: hc.simulate(stack, state, tolerances=tol)):
        with pytest.raises(Exception, match="xla_hertz_chain_no_such_option"):
            call()
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    assert _config.solve_compiler_options() is None
    assert float(hc.prepare_launch(stack, state, tolerances=tol)(stack, state)[-1]) == pytest.approx(eq19, rel=1e-8)
    assert float(hc.launch_velocity(stack, state, tolerances=tol)[-1]) == pytest.approx(eq19, rel=1e-8)
    assert float(hc.simulate(stack, state, tolerances=tol).launch_velocities[-1]) == pytest.approx(eq19, rel=1e-8)
