"""The public API: one flat namespace, resolved lazily so that start-up stays cheap."""

import subprocess
import sys

import hertz_chain as hc


def test_every_public_name_resolves():
    for name in hc.__all__:
        assert getattr(hc, name) is not None, name


def test_functions_are_not_shadowed_by_their_submodules():
    import hertz_chain.build  # noqa: F401  (binds the submodule onto the package)
    import hertz_chain.simulate  # noqa: F401
    import hertz_chain.optimize  # noqa: F401
    import hertz_chain.srs  # noqa: F401
    import hertz_chain.sweep  # noqa: F401
    import hertz_chain.fit  # noqa: F401

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


def _devices_in_subprocess(env: dict, code: str = "import hertz_chain.simulate, jax; print(jax.local_device_count())"):
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
    started = "import jax; jax.devices(); import hertz_chain.simulate; print(jax.local_device_count())"
    assert _devices_in_subprocess({"HERTZ_CHAIN_CPU_DEVICES": "3"}, started) == 1
