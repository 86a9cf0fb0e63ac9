"""Every notebook in notebooks/ runs, in quick mode, so that none of them rots.

Each `notebooks/NN_*.py` (jupytext percent format) is parsed into a notebook in memory with jupytext
and executed cell by cell with nbclient in a `python3` kernel (one per test worker, its namespace reset
before each notebook: the `kernel` fixture), with the working directory `notebooks/`
(where `_nbutil.py` lives) and `HERTZ_CHAIN_QUICK=1` (coarse grids; each notebook takes well under a
minute). The test session's cache folder comes from `conftest.py` and reaches the kernel through the
environment; `HERTZ_CHAIN_WRITE_TABLES` and `HERTZ_CHAIN_FIG_DIR` are removed, so a test run never
writes into the repository. The notebooks' own `assert`s check the paper's statements; a failing cell
fails the test with that cell's error.

The `python3` kernelspec of the virtual environment starts `python -m ipykernel_launcher`, and
jupyter_client replaces a bare `python` with `sys.executable`, so the kernel is this interpreter.
Where that is not the case (another `python3` kernelspec first on the Jupyter path), the notebook is
run as a script in a subprocess of this interpreter instead, which checks the same code.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ROOT / "notebooks"
PATHS = sorted(NOTEBOOKS.glob("[0-9][0-9]_*.py"))
TIMEOUT = 600  # seconds per cell / per script

jupytext = pytest.importorskip("jupytext")
nbformat = pytest.importorskip("nbformat")


def _kernel_is_this_python() -> bool:
    """True when the `python3` kernel would run `sys.executable` (see the module docstring)."""
    try:
        from jupyter_client.kernelspec import KernelSpecManager
        from jupyter_client.manager import KernelManager
    except ImportError:
        return False
    try:
        spec = KernelSpecManager().get_kernel_spec("python3")
    except Exception:
        return False
    km = KernelManager(kernel_name="python3")
    try:
        cmd = km.format_kernel_cmd()
    except Exception:
        cmd = list(spec.argv)
    return bool(cmd) and os.path.realpath(cmd[0]) == os.path.realpath(sys.executable)


def test_all_notebooks_found():
    names = [p.name for p in PATHS]
    assert len(names) >= 7 and all(f"0{k}_" in " ".join(names) for k in range(1, 8)), names


@pytest.mark.parametrize("path", PATHS, ids=[p.stem for p in PATHS])
def test_notebook_parses(path):
    """jupytext reads the file as a notebook with markdown text and code."""
    nb = jupytext.read(path)
    nbformat.validate(nb)
    kinds = [c.cell_type for c in nb.cells]
    assert "markdown" in kinds and "code" in kinds
    assert nb.cells[0].cell_type == "markdown" and nb.cells[0].source.lstrip().startswith("# ")  # a title
    assert nb.metadata.get("kernelspec", {}).get("name") == "python3"


def _quick_env() -> dict:
    env = dict(os.environ) | {"HERTZ_CHAIN_QUICK": "1", "MPLBACKEND": "Agg"}
    for var in ("HERTZ_CHAIN_WRITE_TABLES", "HERTZ_CHAIN_FIG_DIR"):
        env.pop(var, None)
    return env


@pytest.fixture(scope="module")
def kernel():
    """One `python3` kernel for every notebook a test worker runs (None where the kernel is not this
    interpreter): each notebook starts with `%reset -f`, an empty namespace, but the modules it imports
    (JAX, hertz_chain) and what they compiled stay loaded, so a notebook pays neither the kernel's start
    nor the imports, nor a compile another notebook already made."""
    if not _kernel_is_this_python():
        yield None
        return
    from jupyter_client.manager import KernelManager

    km = KernelManager(kernel_name="python3")
    km.start_kernel(cwd=str(NOTEBOOKS), env=_quick_env())
    yield km
    km.shutdown_kernel(now=True)


@pytest.mark.slow
@pytest.mark.parametrize("path", PATHS, ids=[p.stem for p in PATHS])
def test_notebook_runs(path, kernel):
    if kernel is not None:
        from nbclient import NotebookClient
        from nbclient.exceptions import CellExecutionError

        nb = jupytext.read(path)
        nb.cells.insert(0, nbformat.v4.new_code_cell("%reset -f"))  # the namespace as a fresh kernel's
        client = NotebookClient(nb, km=kernel, timeout=TIMEOUT, kernel_name="python3",
                                resources={"metadata": {"path": str(NOTEBOOKS)}})
        try:
            client.execute()
        except CellExecutionError as exc:  # the failing cell's source and traceback
            text = re.sub(r"\x1b\[[0-9;]*m", "", str(exc))  # drop the terminal colours
            pytest.fail(f"{path.name}: a cell failed\n{text}", pytrace=False)
        finally:
            if client.kc is not None:
                client.kc.stop_channels()
        errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
                  if o.get("output_type") == "error"]
        assert not errors
    else:
        proc = subprocess.run([sys.executable, path.name], cwd=NOTEBOOKS, env=_quick_env(), capture_output=True,
                              text=True, timeout=TIMEOUT)
        if proc.returncode != 0:
            pytest.fail(f"{path.name} failed (run as a script):\n{proc.stderr[-4000:]}", pytrace=False)
