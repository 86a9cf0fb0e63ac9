"""Execute the notebooks and write them, with their outputs and figures, as .ipynb files.

    .venv/bin/python notebooks/execute.py [--quick] [--out out/notebooks] [01 05 ...]

The notebooks are kept as jupytext percent-format `.py` files (reviewable diffs, no stored outputs);
this script reads each with jupytext, runs it with nbclient in this interpreter's `python3` kernel
(working directory `notebooks/`) and writes `OUT/<name>.ipynb`, never overwriting a file that it did
not ask about: an existing output is replaced only with `--force`. `--quick` sets `HERTZ_CHAIN_QUICK=1`
(the coarse grids that the test suite uses). `make notebooks` runs all of them in full mode. A notebook
that fails is written up to its failing cell and the others still run; the exit status is then 1.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("only", nargs="*", help="notebook number prefixes to run (default: all)")
    ap.add_argument("--out", default=str(HERE.parent / "out" / "notebooks"), help="output folder")
    ap.add_argument("--quick", action="store_true", help="coarse grids (HERTZ_CHAIN_QUICK=1)")
    ap.add_argument("--force", action="store_true", help="overwrite existing .ipynb outputs")
    args = ap.parse_args(argv)

    import jupytext
    import nbformat
    from nbclient import NotebookClient

    paths = sorted(p for p in HERE.glob("[0-9][0-9]_*.py") if not args.only or any(p.name.startswith(k) for k in args.only))
    if not paths:
        print(f"execute.py: error: no notebook matches {args.only}", file=sys.stderr)
        return 2
    out = Path(args.out)
    targets = [out / (p.stem + ".ipynb") for p in paths]
    existing = [str(t) for t in targets if t.exists()]
    if existing and not args.force:
        print(f"execute.py: error: {', '.join(existing)} exist; pass --force to overwrite", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}  # the kernel's inline backend
    if args.quick:
        env["HERTZ_CHAIN_QUICK"] = "1"
    from nbclient.exceptions import CellExecutionError, CellTimeoutError, DeadKernelError

    failed = []
    for path, target in zip(paths, targets):
        print(f"running {path.name} ...", flush=True)
        nb = jupytext.read(path)
        try:
            NotebookClient(nb, timeout=1800, kernel_name="python3",
                           resources={"metadata": {"path": str(HERE)}}).execute(cwd=str(HERE), env=env)
        except (CellExecutionError, CellTimeoutError, DeadKernelError) as exc:  # the others still run; the
            # failed one is written up to its error
            failed.append(path.name)
            last = [ln for ln in str(exc).strip().splitlines() if ln.strip()]
            print(f"  FAILED: {last[-1] if last else exc}", file=sys.stderr, flush=True)
        nbformat.write(nb, target)
        print(f"  wrote {target}")
    if failed:
        print(f"execute.py: {len(failed)} notebook(s) failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
