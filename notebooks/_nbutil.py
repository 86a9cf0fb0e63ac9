"""Shared switches of the notebooks (not part of the package).

* `HERTZ_CHAIN_QUICK=1`: coarse grids and fewer designs (what `tests/test_notebooks.py` runs).
* `HERTZ_CHAIN_WRITE_TABLES=1`: write the CSV tables behind the key numbers to `data/tables/`.
  Off by default, so running a notebook (or the tests) never rewrites the repository.
* `HERTZ_CHAIN_FIG_DIR=/some/dir`: save every figure there as PNG. Off by default.

Figures are shown inline in a Jupyter kernel (and saved when asked); as a plain script they use the
non-interactive Agg backend and are only saved.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import matplotlib


def _in_kernel() -> bool:
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and hasattr(shell, "kernel")


IN_KERNEL = _in_kernel()
if not IN_KERNEL:
    matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

QUICK = os.environ.get("HERTZ_CHAIN_QUICK", "") not in ("", "0")
WRITE_TABLES = os.environ.get("HERTZ_CHAIN_WRITE_TABLES", "") not in ("", "0")
FIG_DIR = os.environ.get("HERTZ_CHAIN_FIG_DIR") or None


def repo_root() -> Path:
    """The repository root (the folder holding pyproject.toml), searched upward from the cwd."""
    here = Path.cwd().resolve()
    for p in (here, *here.parents):
        if (p / "pyproject.toml").exists() and (p / "hertz_chain").is_dir():
            return p
    raise RuntimeError(f"no hertz_chain repository above {here}")


TABLES = repo_root() / "data" / "tables"


def show(fig, name: str) -> None:
    """Show `fig` inline (in a kernel), save it as `<FIG_DIR>/<name>.png` when asked, then close it."""
    if FIG_DIR:
        Path(FIG_DIR).mkdir(parents=True, exist_ok=True)
        fig.savefig(Path(FIG_DIR) / f"{name}.png", dpi=120, bbox_inches="tight")
    if IN_KERNEL:
        from IPython.display import display

        display(fig)
    plt.close(fig)


def write_table(name: str, header: list[str], rows, comments: list[str] = ()) -> Path | None:
    """Write `data/tables/<name>.csv` (only with HERTZ_CHAIN_WRITE_TABLES=1). Leading `# ` lines hold
    the provenance; numbers are written with `repr` (full float64 precision)."""
    if not WRITE_TABLES:
        return None
    TABLES.mkdir(parents=True, exist_ok=True)
    path = TABLES / f"{name}.csv"
    with open(path, "w", newline="") as f:
        for c in comments:
            f.write(f"# {c}\n")
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        for row in rows:
            w.writerow([repr(float(x)) if isinstance(x, float) or hasattr(x, "dtype") and x.dtype.kind == "f"
                        else int(x) if hasattr(x, "dtype") and x.dtype.kind in "iu" else x for x in row])
    return path


def rel(a: float, b: float) -> float:
    """Relative difference `(a − b)/b`."""
    return (a - b) / b
