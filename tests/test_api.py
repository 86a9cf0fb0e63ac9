"""The public API: one flat namespace, resolved lazily so that start-up stays cheap."""

import os
import subprocess
import sys

import pytest

import hertz_chain as hc


def test_every_public_name_resolves():
    for name in hc.__all__:
        assert getattr(hc, name) is not None, name


def test_no_module_shares_a_name_with_a_public_name():
    # a submodule bound onto the package under a public function's name would shadow the function
    # (issue 17): every module file of the package is named apart from every public name
    import importlib
    import pkgutil

    modules = {m.name for m in pkgutil.iter_modules(hc.__path__)}
    assert not modules & set(hc.__all__), sorted(modules & set(hc.__all__))
    for m in sorted(modules - {"__main__"}):
        importlib.import_module(f"hertz_chain.{m}")  # binds every submodule onto the package
    assert callable(hc.simulate) and callable(hc.srs) and callable(hc.build)
    assert callable(hc.optimize) and callable(hc.sweep) and callable(hc.fit)


def test_import_and_cli_help_do_not_import_jax():
    code = ("import sys, hertz_chain, hertz_chain.cli; "
            "print(any(m == 'jax' or m.startswith('jax.') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_float64_is_on_once_jax_modules_load():
    import jax.numpy as jnp

    assert hc.Hertz(1e9).k.dtype == jnp.float64


@pytest.mark.parametrize("code", ["import hertz_chain, jax.numpy as jnp", "import jax.numpy as jnp, hertz_chain"])
def test_float64_is_on_from_the_import(code):
    """An array made right after `import hertz_chain`, before any part of it that uses JAX is loaded, is
    float64, whether JAX was imported before or after (a review: it was float32, its values rounded)."""
    env = {k: v for k, v in os.environ.items() if k != "JAX_ENABLE_X64"}
    out = subprocess.run([sys.executable, "-c", code + "; print(jnp.array([0.1]).dtype)"], capture_output=True,
                         text=True, check=True, env=env)
    assert out.stdout.strip() == "float64"


def _devices_in_subprocess(env: dict, code: str = "import hertz_chain.simulation, jax; print(jax.local_device_count())"):
    import os

    full = {k: v for k, v in os.environ.items() if k not in ("HERTZ_CHAIN_CPU_DEVICES", "XLA_FLAGS")} | env
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=full)
    return int(out.stdout.strip())


def test_cpu_cores_become_devices_unless_the_user_chose():
    # simulate_batch splits designs over devices: hertz_chain exposes CPU cores as devices, the number
    # set by HERTZ_CHAIN_CPU_DEVICES, and leaves JAX alone when the user already chose or started JAX.
    assert _devices_in_subprocess({"HERTZ_CHAIN_CPU_DEVICES": "3"}) == 3
    assert _devices_in_subprocess({"HERTZ_CHAIN_CPU_DEVICES": "3",
                                   "XLA_FLAGS": "--xla_force_host_platform_device_count=5"}) == 5
    started = "import jax; jax.devices(); import hertz_chain.simulation; print(jax.local_device_count())"
    assert _devices_in_subprocess({"HERTZ_CHAIN_CPU_DEVICES": "3"}, started) == 1


def test_cpu_computations_run_inline_unless_the_user_chose():
    # _config.run_cpu_computations_inline: JAX's CPU client runs computations on the calling thread (its
    # worker-thread handoff cost ~170-200 us per call), unless the user set JAX_CPU_ENABLE_ASYNC_DISPATCH
    # or started JAX before importing hertz_chain
    flag = "print(int(jax.config.values['jax_cpu_enable_async_dispatch']))"
    code = "import hertz_chain.simulation, jax; jax.numpy.zeros(1); " + flag
    started = "import jax; jax.numpy.zeros(1); import hertz_chain.simulation; " + flag
    assert _devices_in_subprocess({}, code) == 0
    assert _devices_in_subprocess({"JAX_CPU_ENABLE_ASYNC_DISPATCH": "1"}, code) == 1
    assert _devices_in_subprocess({}, started) == 1


@pytest.mark.parametrize("code", ["import hertz_chain, jax.numpy as jnp", "import jax.numpy as jnp, hertz_chain"])
def test_the_cores_and_inline_dispatch_hold_when_the_first_array_is_the_users(code):
    """A review: a user's first JAX array (Monte-Carlo samples drawn with jax.random) made before any
    hertz_chain function left one device and JAX's asynchronous dispatch (batches 2.1x, prepared calls
    1.7-3x slower); `import hertz_chain` sets both now, before or after `import jax`, without importing JAX
    itself (an import hook runs `_config` right after JAX's own import)."""
    flag = "int(jax.config.values['jax_cpu_enable_async_dispatch'])"
    probe = code + f"; import jax; jnp.zeros(1); print(jax.local_device_count() * 10 + {flag})"
    assert _devices_in_subprocess({"HERTZ_CHAIN_CPU_DEVICES": "3"}, probe) == 30
    # a mere `importlib.util.find_spec("jax")` first (an "is it installed?" check) keeps the hook (a review)
    probe = ("import hertz_chain, importlib.util; importlib.util.find_spec('jax'); import jax; jax.numpy.zeros(1); "
             f"print(jax.local_device_count() * 10 + {flag})")
    assert _devices_in_subprocess({"HERTZ_CHAIN_CPU_DEVICES": "3"}, probe) == 30
    # and `import hertz_chain` alone still does not import JAX (the command line's start-up)
    assert _devices_in_subprocess({}, "import sys, hertz_chain; print(int('jax' in sys.modules))") == 0


def test_a_jax_cache_folder_the_user_chose_is_kept():
    """A review: since `import hertz_chain` sets the compilation cache up as soon as JAX is imported, it
    overrode the user's own `JAX_COMPILATION_CACHE_DIR`; kept now (hertz_chain's traced solves stay in its
    own folder)."""
    code = "import hertz_chain, jax; print(int(jax.config.jax_compilation_cache_dir == '/tmp/user-jax-cache'))"
    assert _devices_in_subprocess({"JAX_COMPILATION_CACHE_DIR": "/tmp/user-jax-cache"}, code) == 1


def test_a_renamed_name_fails_with_its_new_name():
    # CHANGELOG.md's table: the old public names point to the new ones
    import pytest

    from hertz_chain import rigid

    with pytest.raises(AttributeError, match="renamed BuiltStack"):
        hc.Built  # noqa: B018
    with pytest.raises(AttributeError, match="renamed optimal_pair_ratio"):
        rigid.pb_x0  # noqa: B018
    with pytest.raises(AttributeError, match="has no attribute 'nothing'"):
        hc.nothing  # noqa: B018
