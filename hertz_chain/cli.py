"""The `hertz-chain` command line: a thin layer over the public API.

Commands:

- `hertz-chain design --ratio R --restitution e` — the paper's optimal MVG and MET designs.
- `hertz-chain simulate STACK.toml [--json] [--plot F.png] [--output F.nc|F.csv]` — simulate a stack
  file and compare with the rigid model.
- `hertz-chain demo` — the paper's optimal six-mass MVG stack, gapped and touching.

Every user error (bad file, bad parameter) prints one line to stderr and exits with status 2, with no
traceback. Heavy imports (JAX, diffrax, matplotlib) happen inside the commands, so `--help` is instant.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Optional

import typer

from .errors import HertzChainError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Design and simulate shock amplifiers (stacks of progressively lighter dropped masses).",
)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _fail(message: str) -> None:
    typer.echo(f"hertz-chain: error: {message}", err=True)
    raise typer.Exit(code=2)


@app.command()
def design(
    ratio: Optional[float] = typer.Option(None, "--mass-ratio", "--ratio", "-R", help="R = m_n / m_1 (0 < R < 1)."),
    bottom_mass: Optional[float] = typer.Option(None, "--bottom-mass", "--m1", help="Bottom mass m_1 in kg (scales the design)."),
    top_mass: Optional[float] = typer.Option(None, "--top-mass", "--mn", help="Top mass m_n in kg (with --bottom-mass, instead of R)."),
    restitution: float = typer.Option(..., "--restitution", "-e", help="Restitution e of every impact."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
) -> None:
    """The optimal MVG design (Eqs 15, 20, 22-24) and the MET design (Eqs 25-30), compared."""
    from . import report

    try:
        result = report.design_report(ratio=ratio, m1=bottom_mass, mn=top_mass, e=restitution)
    except HertzChainError as exc:
        _fail(str(exc))
    typer.echo(report.to_json(report.design_dict(result)) if as_json else report.design_table(result))


@app.command()
def simulate(
    stack_file: Path = typer.Argument(..., help="Stack file (TOML with units)."),
    as_json: bool = typer.Option(False, "--json", help="Print the results as JSON."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Write a figure (PNG)."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="Write .nc (NetCDF) or .csv."),
    force: bool = typer.Option(False, "--force", help="Overwrite existing output files."),
) -> None:
    """Simulate a stack file with compliant contacts and compare it with the rigid model."""
    from . import report

    for path in (plot, output):
        if path is not None and path.exists() and not force:
            _fail(f"{path} exists; pass --force to overwrite it")
    if output is not None and output.suffix.lower() not in (".nc", ".csv"):
        _fail(f"--output {output}: expected a .nc or .csv file")
    if plot is not None and plot.suffix.lower() != ".png":
        _fail(f"--plot {plot}: expected a .png file")
    try:
        result = report.simulate_file(stack_file)
    except HertzChainError as exc:
        _fail(str(exc))
    typer.echo(report.to_json(result) if as_json else report.summary_table(result))
    if output is not None:
        report.write_output(result, output)
    if plot is not None:
        from . import plot as plotting

        plotting.plot_report(result, plot)


@app.command()
def demo() -> None:
    """The paper's optimal six-mass MVG stack (R = 0.012, e = 0.8): gapped, then touching."""
    from . import report

    try:
        typer.echo(report.demo())
    except HertzChainError as exc:
        _fail(str(exc))


def main() -> None:
    """Console-script entry point."""
    # Equinox's run-time checks (diffrax's sign check of `dt0` against the traced `t1`) are host
    # callbacks, and an executable with a host callback is never written to JAX's persistent cache.
    # The library validates every input before tracing and reports non-finite states as a failed
    # status, so the command line turns those checks into NaNs and every warm run loads its compiled
    # solve from the cache (benchmarks/results.md: warm `simulate` of the demo 5.0 s -> 3.8 s), and
    # `hertz_chain._export` keeps the traced solve on disk too (`jax.export`; 3.4 s -> 2.6 s).
    os.environ.setdefault("EQX_ON_ERROR", "nan")
    try:
        app()
    except HertzChainError as exc:  # safety net: never a traceback for a user error
        typer.echo(f"hertz-chain: error: {exc}", err=True)
        sys.exit(2)
