"""The `hertz-chain` command line: a thin layer over the public API.

Commands:

- `hertz-chain design --ratio R --restitution e` — the paper's optimal MVG and MET designs.
- `hertz-chain simulate STACK.toml [--json] [--plot F.png] [--output F.nc|F.csv] [--set KEY=VALUE ...]`
  — simulate a stack file and compare with the rigid model; `--set` overrides a key of the file
  (`--set drop.height="30 cm"`; also for `check` and `compare`).
- `hertz-chain optimize STACK.toml [--json] [--write OUT.toml] [--plot F.png]` — the best stack under
  compliant contacts (`hertz_chain.optimization`; exit 0 converged, 1 pulse target not met, 3 not converged, 5 failed).
- `hertz-chain sweep STACK.toml --output OUT.zarr [--workers N | --scheduler ADDR] [--resume] [--json]` —
  a design space into a Zarr store that survives a kill (`hertz_chain.sweeps`).
- `hertz-chain plot OUT.zarr --x KEY [--y KEY] [--var NAME] --output F.png` — a line or a map from a sweep.
- `hertz-chain fit STACK.toml MEASURED.csv --vary contact.stiffness[0] [--write F.toml] [--plot F.png]` —
  contact parameters fitted to a measured pulse by least squares, with standard errors (`hertz_chain.fitting`).
- `hertz-chain check STACK.toml [--standard NAME] [--json] [--plot F.png]` — the top pulse against a
  shock-test condition (`hertz_chain.standards`; exit 1 when a criterion fails); `--standard list`.
- `hertz-chain compare STACK.toml MEASURED.csv [--cfc N] [--align xcorr|onset|none] [--json] [--plot F.png]`
  — the top pulse against a measured one (`hertz_chain.measured`).
- `hertz-chain demo` — the paper's optimal six-mass MVG stack, gapped and touching.

Every user error (bad file, bad parameter, bad path, unknown command or flag, missing argument) prints
one line `hertz-chain: error: ...` to stderr, naming the key or flag, the value and what is allowed, and
exits with status 2, with no traceback. Output paths (`--output`, `--plot`) are checked before anything
is simulated (`hertz_chain._paths`) and written atomically after it: an existing file is never replaced
without `--force`, and of two runs writing the same file one wins and the other fails with one line.
Heavy imports (JAX, diffrax, matplotlib) happen inside the commands, so `--help` and the usage errors
answer at once.

Exit status (`hertz_chain.status.Status.exit_code`):

| status | meaning |
|---|---|
| 0 | the run completed (`complete`, `complete with rebounds`); `--help`; `check`: every criterion passed |
| 1 | `check`: a criterion failed (the table/JSON says which, with its margin) |
| 2 | bad input: a stack file, flag, value or output path refused before anything ran; a usage error; an output file that could not be written after the run |
| 3 | incomplete: `t_max` or `max_steps` came before the cascade ended (partial results are written) |
| 4 | no contact: nothing touched before `t_max` |
| 5 | failed: the solver produced a non-finite state |

After a run that is not `ok` the table/JSON and the outputs are still written (marked partial), then one
line `hertz-chain: <status>: <hint>` goes to stderr. Each warning of the run is one line
`hertz-chain: warning: ...` on stderr (not when stdout and stderr are the same terminal: the report
already lists them). Running `hertz-chain` without arguments prints the help and exits
with status 2.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Optional

import typer

from ._progress import progress

from .errors import HertzChainError, SolverError
from .status import EXIT_BAD_INPUT, Status

try:  # the parser's own errors (typer >= 0.20 vendors click; older versions use click itself)
    from typer._click.exceptions import ClickException as _ClickException
except ImportError:  # pragma: no cover
    from click.exceptions import ClickException as _ClickException

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Design and simulate shock amplifiers (stacks of progressively lighter dropped masses).",
)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


OUTPUT_SUFFIXES = (".nc", ".csv")
PLOT_SUFFIXES = (".png",)

# options shared by several commands
_SET = typer.Option([], "--set", help="Override a stack-file key: --set drop.height=\"30 cm\" (repeatable).")
_MEASURED = typer.Argument(..., help="Measured pulse: CSV with a time and an acceleration column.")
_TIME_UNIT = typer.Option(None, "--time-unit", help="Unit of the time column (s, ms, us).")
_CFC = typer.Option(None, "--cfc", help="Filter both by SAE J211 / ISO 6487 class 60, 180, 600 or 1000.")
_ACCEL_UNIT = typer.Option(None, "--accel-unit", help="Unit of the acceleration column (g, m/s^2, ft/s^2).")


def _one_line(text: object) -> str:
    return " ".join(str(text).split())



def _same_file(a, b, exists: bool = True) -> bool:
    """Whether the paths `a` and `b` name the same file, through symbolic links too (a link to the input
    stack file given as `--write` replaced the input); `exists`: only when `b` exists."""
    if exists and not os.path.exists(b):
        return False
    return os.path.realpath(a) == os.path.realpath(b)

def _fail(message: str) -> None:
    typer.echo(f"hertz-chain: error: {_one_line(message)}", err=True)
    raise typer.Exit(code=EXIT_BAD_INPUT)


def _check_number(value: float | None, flag: str, lo: float, hi: float, allowed: str) -> None:
    import math

    if value is not None and not (math.isfinite(value) and lo <= value <= hi):
        _fail(f"{flag} = {value!r} is invalid: {allowed}")


def _check_design_inputs(ratio, bottom_mass, top_mass, restitution) -> None:
    """The `design` command's bounds: finite values, R in (0, 1), e in [MIN_RESTITUTION, 1), masses in
    the stack-file mass range, and optimal stacks of at most MAX_MASSES masses. Plain checks first;
    the rigid model (numpy, scipy) only to count the masses, stopping at MAX_MASSES."""
    import math

    from .constants import MAX_MASSES
    from .stackfile import MIN_RESTITUTION
    from .units import LIMITS

    lo, hi = LIMITS["mass"]
    _check_number(restitution, "--restitution", MIN_RESTITUTION, 1.0,
                  f"the restitution of every impact, {MIN_RESTITUTION:g} <= e < 1 (e = 1 has no optimal stack)")
    if restitution >= 1:
        _fail(f"--restitution = {restitution!r} is invalid: the optimal MVG stack needs e < 1 (for e = 1 "
              "the gain grows with n without bound)")
    if ratio is not None and not (math.isfinite(ratio) and 0 < ratio < 1):
        _fail(f"--mass-ratio = {ratio!r} is invalid: R = m_n/m_1 must lie in (0, 1)")
    _check_number(bottom_mass, "--bottom-mass", lo, hi, f"a mass in kg between {lo:g} and {hi:g}")
    _check_number(top_mass, "--top-mass", lo, hi, f"a mass in kg between {lo:g} and {hi:g}")
    if ratio is None:
        if bottom_mass is None or top_mass is None:
            _fail("--mass-ratio: missing; give --mass-ratio R, or both --bottom-mass and --top-mass")
        if not top_mass < bottom_mass:
            _fail(f"--top-mass = {top_mass!r} is invalid: must be lighter than --bottom-mass = {bottom_mass!r}")
        ratio = top_mass / bottom_mass
    elif top_mass is not None:
        _fail("--top-mass: give --mass-ratio or --top-mass, not both")
    from .errors import ParameterError
    from .rigid import met_n_for_ratio, mvg_optimal_n

    for name, count in (("MVG", mvg_optimal_n), ("MET", met_n_for_ratio)):
        try:
            count(ratio, restitution, n_limit=MAX_MASSES)
        except ParameterError as exc:
            if exc.name != "n_limit":
                raise
            _fail(f"--mass-ratio = {ratio:.6g} is invalid with --restitution = {restitution:.6g}: the "
                  f"{name} stack has more than {MAX_MASSES} masses, the most a stack may have "
                  "(raise the mass ratio)")


@app.command()
def design(
    ratio: Optional[float] = typer.Option(None, "--mass-ratio", "--ratio", "-R", help="R = m_n / m_1 (0 < R < 1)."),
    bottom_mass: Optional[str] = typer.Option(None, "--bottom-mass", "--m1", help="Bottom mass m_1, e.g. \"8 kg\" (a plain number is kg)."),
    top_mass: Optional[str] = typer.Option(None, "--top-mass", "--mn", help="Top mass m_n, e.g. \"100 g\" (with --bottom-mass, instead of R)."),
    restitution: float = typer.Option(..., "--restitution", "-e", help="Restitution e of every impact."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
    write: Optional[Path] = typer.Option(None, "--write", "-w", help="Write a design as a stack file (.toml) that simulate runs."),
    kind: str = typer.Option("mvg", "--kind", help="The design --write writes: mvg or met."),
    stiffness: Optional[str] = typer.Option(None, "--stiffness", help="Contact stiffness for --write, e.g. \"1e9 N/m^1.5\"."),
    law: str = typer.Option("tsuji", "--law", help="Contact law for --write (restitution e at every interface)."),
    impact_velocity: str = typer.Option("1 m/s", "--impact-velocity", help="Drop speed for --write."),
    gap: str = typer.Option("0 m", "--gap", help="Gap between neighbouring masses for --write (0: a touching stack)."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing --write file."),
) -> None:
    """The optimal MVG design (Eqs 15, 20, 22-24) and the MET design (Eqs 25-30), compared; --write makes a stack file."""
    from . import report, workflow

    try:
        m1, mn = _mass_option(bottom_mass, "--bottom-mass"), _mass_option(top_mass, "--top-mass")
        _check_design_inputs(ratio, m1, mn, restitution)
        if write is not None:
            doc = _design_document(kind, stiffness, law, impact_velocity, gap, restitution, write, force)
        result = workflow.design_report(ratio=ratio, m1=m1, mn=mn, e=restitution)
    except HertzChainError as exc:
        _fail(str(exc))
    typer.echo(report.to_json(report.design_dict(result)) if as_json else report.design_table(result))
    if write is not None:
        from . import _paths

        text = _design_text(result, kind, doc, m1 is not None)
        try:
            _paths.write_atomically(write, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"), force, "--write")
        except HertzChainError as exc:
            _fail(str(exc))
        if not as_json:
            typer.echo(f"wrote the {kind.upper()} stack to {write} (hertz-chain simulate {write})")


def _check_test_section(stack_file: Path, overrides) -> None:
    """A `[test]` section is checked even where it is not used (`simulate`), so that a mistake in it is
    found at once rather than at the first `check`."""
    import tomllib

    try:
        has_test = "test" in tomllib.loads(stack_file.read_text(encoding="utf-8-sig"))
    except (OSError, ValueError):
        return  # load_stack_file has already judged the file
    if has_test or any(str(o).strip().startswith("test.") for o in overrides or ()):
        from .standards import read_test_file

        read_test_file(stack_file, None, overrides)


def _mass_option(raw: str | None, flag: str) -> float | None:
    """A mass option: `"8 kg"`, `"100 g"`, or a plain number of kg."""
    from .units import parse_quantity

    if raw is None:
        return None
    try:
        return parse_quantity(float(raw), "mass", flag)
    except ValueError:
        return parse_quantity(raw, "mass", flag)


def _design_document(kind, stiffness, law, impact_velocity, gap, e, write, force) -> dict:
    """The `[drop]`, `[stack]` gaps and `[contact]` of `design --write`, checked as a stack file would
    be (one line naming the option on error), before anything is designed."""
    from . import _paths
    from .registry import LAWS
    from .stackfile import parse_stack
    from .units import parse_quantity

    _paths.check_output_path(write, "--write", (".toml",), force)
    if kind not in ("mvg", "met"):
        _fail(f"--kind = {kind!r} is invalid: mvg or met")
    if stiffness is None:
        _fail("--stiffness: missing; --write needs the contact stiffness, e.g. --stiffness \"1e9 N/m^1.5\"")
    if law not in LAWS:
        _fail(f"--law = {law!r} is invalid: one of {', '.join(LAWS)}")
    takes_e = [name for name, row in LAWS.items() if not (row.elastic or row.memory or row.params)]
    if law not in takes_e:  # a review: "--restitution: not used by law 'hertz'", while --restitution is
        # required (the design's e): the two options contradicted each other
        row = LAWS[law]
        what = ("an elastic law (e = 1) cannot hold the design's e" if row.elastic else
                "an elastic-plastic law (its e follows from its yield and the impact speed) cannot hold the "
                "design's e" if row.memory else
                f"it needs {', '.join(k for k, _ in row.params)}, which --write cannot set (write the file "
                "with another law, then edit its [contact])")
        _fail(f"--law = {law!r} is invalid for --write: {what}; a law calibrated to e = {e:g} at every "
              f"interface: {', '.join(takes_e)}")
    parse_quantity(impact_velocity, "velocity", "--impact-velocity")
    parse_quantity(gap, "length", "--gap")
    doc = {"drop": {"impact_velocity": impact_velocity}, "stack": {"masses": ["1 kg", "0.5 kg"], "gaps": gap},
           "contact": {"law": law, "stiffness": stiffness, "restitution": e}}
    try:
        parse_stack(doc)  # the options as the stack file will hold them
    except HertzChainError as exc:
        msg = str(exc)
        for key, flag in (("contact.stiffness", "--stiffness"), ("contact.restitution", "--restitution"),
                          ("stack.gaps", "--gap"), ("drop.impact_velocity", "--impact-velocity"),
                          ("contact", "--law")):
            msg = msg.replace(key, flag)
        _fail(msg)
    return doc


def _design_text(result, kind: str, doc: dict, in_kg: bool) -> str:
    """The stack file of the chosen design: explicit masses (kg; units of m_1 when no mass was given)."""
    import tomli_w

    d = result.mvg if kind == "mvg" else result.met
    doc = dict(doc)
    doc["stack"] = dict(doc["stack"], masses=[f"{float(m)!r} kg" for m in d.masses])
    head = [f"# The {d.kind} stack of the rigid theory for R = {result.R:.6g}, e = {doc['contact']['restitution']:g}:",
            f"# {d.n} masses, rigid gain G = {d.gain:.6g} (paper Eq {'20' if kind == 'mvg' else '29'}), written by",
            "# hertz-chain design --write. The rigid gain assumes independent collisions; this file's compliant",
            "# contacts, gaps and gravity decide what the stack really does: hertz-chain simulate FILE."]
    if not in_kg:
        head.append("# No mass was given: the masses are in units of m_1 = 1 kg.")
    return "\n".join(head) + "\n" + tomli_w.dumps({"title": f"{d.kind} design, R = {result.R:.6g}"} | doc)


@app.command()
def simulate(
    stack_file: Path = typer.Argument(..., help="Stack file (TOML with units)."),
    as_json: bool = typer.Option(False, "--json", help="Print the results as JSON."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Write a figure (PNG)."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="Write .nc (NetCDF) or .csv."),
    force: bool = typer.Option(False, "--force", help="Overwrite existing output files."),
    overrides: list[str] = _SET,
) -> None:
    """Simulate a stack file with compliant contacts and compare it with the rigid model."""
    from . import _paths
    from .stackfile import load_stack_file

    try:  # everything the user gave is checked before anything heavy is imported or run
        if output is not None and plot is not None and os.path.abspath(output) == os.path.abspath(plot):
            _fail(f"--plot {plot}: the same file as --output")
        if output is not None:
            _paths.check_output_path(output, "--output", OUTPUT_SUFFIXES, force)
        if plot is not None:
            _paths.check_output_path(plot, "--plot", PLOT_SUFFIXES, force)
        spec = load_stack_file(stack_file, overrides)
        _check_test_section(stack_file, overrides)
    except HertzChainError as exc:
        _fail(str(exc))
    from . import report, workflow

    try:
        with progress(f"simulating {stack_file.name}"):
            result = workflow.run_spec(spec)
    except SolverError as exc:
        typer.echo(f"hertz-chain: {Status.FAILED.text}: {_one_line(exc)}", err=True)
        raise typer.Exit(code=Status.FAILED.exit_code)
    except HertzChainError as exc:
        _fail(str(exc))
    typer.echo(report.to_json(result) if as_json else report.summary_table(result))
    try:
        if output is not None:
            meta = {"title": spec.title, "source_file": str(stack_file)}
            _paths.write_atomically(output, lambda tmp: report.write_output(result, tmp, meta), force, "--output")
        if plot is not None:
            from . import plot as plotting

            _paths.write_atomically(plot, lambda tmp: plotting.plot_report(result, tmp), force, "--plot")
    except HertzChainError as exc:
        _fail(str(exc))
    # the report on stdout lists its warnings; repeat them on stderr unless both go to the same terminal
    if not (sys.stdout.isatty() and sys.stderr.isatty()):
        for warning in getattr(result, "warnings", None) or ():
            typer.echo(f"hertz-chain: warning: {_one_line(warning)}", err=True)
    status = result.status
    if not status.ok:
        hint = status.hint(spec.solver.max_steps)
        typer.echo(f"hertz-chain: {status.text}: {_one_line(hint)}" if hint else f"hertz-chain: {status.text}",
                   err=True)
        raise typer.Exit(code=status.exit_code)


@app.command()
def optimize(
    stack_file: Path = typer.Argument(..., help="Stack file with an optimize section (docs/optimize.md)."),
    as_json: bool = typer.Option(False, "--json", help="Print the result as JSON."),
    write: Optional[Path] = typer.Option(None, "--write", "-w", help="Write the optimum as a stack file (.toml)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Write the convergence and the pulses (PNG)."),
    force: bool = typer.Option(False, "--force", help="Overwrite existing output files."),
) -> None:
    """Find the stack that maximises the launch gain, or that gives a target pulse, under compliant contacts."""
    from . import _paths
    from .optimization import read_optimize_file

    try:
        if write is not None and plot is not None and _same_file(write, plot, exists=False):
            _fail(f"--plot {plot}: the same file as --write")
        if write is not None:
            _paths.check_output_path(write, "--write", (".toml",), force)
            if _same_file(write, stack_file):
                _fail(f"--write {write}: the input stack file itself; write the optimum to another file")
        if plot is not None:
            _paths.check_output_path(plot, "--plot", PLOT_SUFFIXES, force)
        read_optimize_file(stack_file)  # the file and its [optimize] section, before JAX is imported
    except HertzChainError as exc:
        _fail(str(exc))
    from . import report
    from .optimization import optimize as run_optimize

    try:
        with progress(f"optimising {stack_file.name}"):
            result = run_optimize(stack_file)
    except SolverError as exc:
        _solver_failed(exc)
    except HertzChainError as exc:
        _fail(str(exc))
    typer.echo(report.to_json(result.to_dict()) if as_json else report.optimize_table(result))
    try:
        if write is not None:
            _paths.write_atomically(write, lambda tmp: Path(tmp).write_text(result.document(), encoding="utf-8"),
                                    force, "--write")
        if plot is not None:
            from . import plot as plotting

            _paths.write_atomically(plot, lambda tmp: plotting.plot_optimize(result, tmp), force, "--plot")
    except HertzChainError as exc:
        _fail(str(exc))
    if not result.status.ok:
        typer.echo(f"hertz-chain: optimize {result.status.text}: {_one_line(result.convergence['why'])}; the "
                   "best point found is reported", err=True)
        raise typer.Exit(code=result.status.exit_code)
    if result.convergence.get("pulse_target_met") is False:  # converged on the closest pulse within reach
        miss = result.convergence["pulse_misses"]
        typer.echo(f"hertz-chain: optimize: pulse target NOT MET (peak g {100 * miss['peak_g']:+.3g} %, duration "
                   f"{100 * miss['duration']:+.3g} %): the bounds or limits keep it out of reach; the closest pulse "
                   "within them is reported", err=True)
        raise typer.Exit(code=EXIT_CHECK_FAILED)


@app.command()
def sweep(
    stack_file: Path = typer.Argument(..., help="Stack file with a sweep section and its axes (docs/sweeps.md)."),
    output: Path = typer.Option(..., "--output", "-o", help="The Zarr store to write (a folder ending in .zarr)."),
    workers: Optional[int] = typer.Option(None, "--workers", help="Run on a local Dask cluster of N worker processes."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Run on an existing Dask cluster (tcp://host:port)."),
    resume: bool = typer.Option(False, "--resume", help="Continue a killed sweep (the same command does it too)."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Sweep a design space (the file's sweep axes: a grid or samples) into a Zarr store that survives a kill."""
    from .sweeps import check

    try:
        if workers is not None and scheduler is not None:
            _fail("--workers: give --workers or --scheduler, not both")
        _check_number(workers, "--workers", 1, 1024, "a number of worker processes from 1 to 1024")
        if scheduler is not None and "://" not in scheduler:
            _fail(f"--scheduler = {scheduler!r} is invalid: a Dask scheduler address such as tcp://host:8786")
        plan, _ = check(stack_file, output)
        if resume and not output.exists():
            _fail(f"--resume: {output} does not exist yet; run without --resume to start the sweep")
    except HertzChainError as exc:
        _fail(_as_option(exc))
    from .sweeps import _EXTRA_DIM, VARIABLES

    # every variable a float64 per design (n per mass or interface), the sampled values, and the markers
    per_design = 8 * (len(VARIABLES) - len(_EXTRA_DIM) + len(_EXTRA_DIM) * plan.spec.n + len(plan.sweep.axes))
    plural = lambda k, word: f"{k} {word}{'' if k == 1 else 's'}"  # noqa: E731
    typer.echo(f"hertz-chain: sweep: {plural(plan.size, 'design')} in {plural(plan.n_chunks, 'chunk')} of "
               f"up to {plan.chunk_rows * plan.row} designs; about {plan.size * per_design / 1e6:.3g} MB uncompressed",
               err=True)
    from .sweeps import _done, recorded_rate
    from .sweeps import sweep as run_sweep

    left = plan.size if not output.exists() else plan.size - sum(
        (plan.region(c).stop - plan.region(c).start) * plan.row for c in _done(output))
    rate = recorded_rate(plan, workers, scheduler)
    if left == 0:
        typer.echo("hertz-chain: sweep: every chunk is done already: nothing to run", err=True)
    elif rate:  # before anything runs: the steady rate of the last sweep of this structure here
        typer.echo(f"hertz-chain: sweep: about {left / rate:.2g} s for {plural(left, 'design')} at "
                   f"{rate:,.0f} designs/s (the last sweep of this structure on this machine), plus the first "
                   "chunk's compilation", err=True)
    elif plan.n_chunks > 1:
        typer.echo("hertz-chain: sweep: no earlier sweep of this structure here to time it by: an estimate "
                   "follows the first chunk", err=True)
    else:  # one chunk: no steady rate to record either (the first chunk includes the compilation)
        typer.echo("hertz-chain: sweep: one chunk: no time estimate", err=True)

    first = {}

    def estimate(done, todo, seconds):  # when no recorded rate was printed: after the first chunk (which
        # compiles: an upper bound), and after the second at its steady rate
        if rate or sys.stderr.isatty() or todo < 2:
            return
        if done == 1:
            first["s"] = seconds
            typer.echo(f"hertz-chain: sweep: first chunk in {seconds:.1f} s (with compilation); at most about "
                       f"{seconds * (todo - 1):.0f} s for the other {todo - 1}", err=True)
        elif done == 2 and todo > 2:
            typer.echo(f"hertz-chain: sweep: second chunk in {seconds - first['s']:.2g} s; about "
                       f"{(seconds - first['s']) * (todo - 2):.2g} s for the other {todo - 2}", err=True)

    try:
        result = run_sweep(stack_file, output, workers=workers, scheduler=scheduler, progress=sys.stderr.isatty(),
                           on_chunk=estimate)
    except HertzChainError as exc:
        _fail(_as_option(exc))
    except KeyboardInterrupt:  # a review: Ctrl-C left no word of what was kept
        typer.echo(f"hertz-chain: sweep interrupted: the chunks written to {output} are kept; run the same "
                   "command again to resume", err=True)
        raise typer.Exit(code=130)
    summary = result.to_dict()
    if as_json:
        from .report import to_json

        typer.echo(to_json(summary))
    else:
        rate = f", {summary['designs_per_second']:.3g} designs/s" if result.computed else ""
        counts = ", ".join(f"{k} {v}" for k, v in result.status_counts.items())
        chunks = f"{result.computed} chunk{'' if result.computed == 1 else 's'}"
        typer.echo(f"{result.path}: {plural(result.designs, 'design')}; {chunks} computed, {result.skipped} "
                   f"already done{rate}; status: {counts}")


def _solver_failed(exc: SolverError):
    """Exit after a `SolverError`: one line, and the exit status of the run's own status where the error
    carries one (`Status.error`: an incomplete run), else `failed`'s."""
    status = getattr(exc, "status", None)
    typer.echo(f"hertz-chain: {_one_line(exc)}" if status else
               f"hertz-chain: {Status.FAILED.text}: {_one_line(exc)}", err=True)
    raise typer.Exit(code=(status or Status.FAILED).exit_code)


def _as_option(exc: HertzChainError) -> str:
    """The message of `exc`, an `OutputPathError` about the Python argument `output` (`sweeps.sweep`)
    named as the command line's option `--output`."""
    from .errors import OutputPathError

    if isinstance(exc, OutputPathError) and exc.key == "output":
        return str(OutputPathError("--output", exc.path, exc.problem))
    return str(exc)


EXIT_CHECK_FAILED = 1  # `check`: a judged criterion failed


@app.command()
def check(
    stack_file: Optional[Path] = typer.Argument(None, help="Stack file; its \\[test] section or --standard says what to check."),
    standard: Optional[str] = typer.Option(None, "--standard", help="A test condition (e.g. \"JESD22-B110 B\"); 'list' prints the table."),
    as_json: bool = typer.Option(False, "--json", help="Print the result as JSON."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Draw the pulse inside its band (PNG)."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing plot."),
    strict: bool = typer.Option(False, "--strict", help="Exit 1 when nothing was judged (no tolerance, band or SRS tolerance)."),
    overrides: list[str] = _SET,
) -> None:
    """Check the top pulse against a shock-test condition: peak, duration, velocity change, band (exit 1 on FAIL)."""
    from . import _paths
    from .standards import read_test_file, standards_table

    if standard is not None and standard.strip().lower() == "list":
        if stack_file is not None or plot is not None or overrides:  # nothing is checked: say so
            typer.echo("hertz-chain: note: --standard list prints the table only; the stack file, --plot and "
                       "--set are not used", err=True)
        if as_json:
            import dataclasses

            from . import report
            from .standards import conditions

            typer.echo(report.to_json([dict(dataclasses.asdict(c), name=c.name) for c in conditions()]))
        else:
            typer.echo(standards_table())
        return
    try:
        if stack_file is None:
            _fail("STACK_FILE: missing; give a stack file (or --standard list for the table)")
        if plot is not None:
            _paths.check_output_path(plot, "--plot", PLOT_SUFFIXES, force)
        from .stackfile import load_stack_file

        load_stack_file(stack_file, overrides)
        read_test_file(stack_file, standard, overrides)
    except HertzChainError as exc:
        _fail(str(exc))
    from . import report
    from .standards import check as run_check

    try:
        with progress(f"simulating {stack_file.name}"):
            result_report, result = run_check(stack_file, standard, overrides)
    except SolverError as exc:
        typer.echo(f"hertz-chain: {Status.FAILED.text}: {_one_line(exc)}", err=True)
        raise typer.Exit(code=Status.FAILED.exit_code)
    except HertzChainError as exc:
        _fail(str(exc))
    typer.echo(report.to_json(result.to_dict()) if as_json else result.table())
    if plot is not None:
        from . import plot as plotting

        try:
            _paths.write_atomically(plot, lambda tmp: plotting.plot_check(result, tmp), force, "--plot")
        except HertzChainError as exc:
            _fail(str(exc))
    if standard and ", modified: " in result.spec.name:  # a review: `--standard X` on a file whose [test]
        # gives its own pulse checked that pulse, under X's name, and passed
        base, changed = result.spec.name.split(", modified: ", 1)
        typer.echo(f"hertz-chain: note: the file's [test] section changes {base}'s nominal pulse ({changed}): "
                   f"this is a check of the changed pulse, not of {base} as written", err=True)
    status = result_report.status
    if not status.ok:
        typer.echo(f"hertz-chain: {status.text}: the run did not complete; the check is of a partial pulse", err=True)
        raise typer.Exit(code=status.exit_code)
    if result.passed is None:
        typer.echo("hertz-chain: note: nothing was judged (no tolerance, band or SRS tolerance given): the values "
                   "are reported only" + ("; --strict: exit 1" if strict else ""), err=True)
        if strict:  # a lab's script reading the exit status would take NOT JUDGED for a pass
            raise typer.Exit(code=EXIT_CHECK_FAILED)
    elif not result.passed:
        raise typer.Exit(code=EXIT_CHECK_FAILED)


def _check_align_cfc(align: str, cfc: int | None) -> None:
    """`--align` and `--cfc` of compare and fit: one line and exit 2 unless allowed."""
    from .filters import CFC_CLASSES
    from .measured import ALIGNMENTS

    if align not in ALIGNMENTS:
        _fail(f"--align = {align!r} is invalid: one of {', '.join(ALIGNMENTS)}")
    if cfc is not None and cfc not in CFC_CLASSES:
        _fail(f"--cfc = {cfc} is invalid: one of {', '.join(map(str, CFC_CLASSES))}")


@app.command()
def compare(
    stack_file: Path = typer.Argument(..., help="Stack file whose top pulse is compared."),
    measured: Path = _MEASURED,
    time_unit: Optional[str] = _TIME_UNIT,
    accel_unit: Optional[str] = _ACCEL_UNIT,
    cfc: Optional[int] = _CFC,
    align: str = typer.Option("xcorr", "--align", help="Time alignment: xcorr, onset or none."),
    as_json: bool = typer.Option(False, "--json", help="Print the comparison as JSON."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Overlay the pulses and their SRS (PNG)."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing plot."),
    overrides: list[str] = _SET,
) -> None:
    """Compare the model's top pulse with a measured pulse: metrics, SRS and Sprague-Geers errors."""
    from . import _paths
    from .measured import read_pulse_csv
    from .stackfile import load_stack_file

    try:
        _check_align_cfc(align, cfc)
        if plot is not None:
            _paths.check_output_path(plot, "--plot", PLOT_SUFFIXES, force)
        spec = load_stack_file(stack_file, overrides)
        record = read_pulse_csv(measured, time_unit=time_unit, accel_unit=accel_unit)
    except HertzChainError as exc:
        _fail(str(exc))
    from . import report, workflow
    from .measured import compare as run_compare

    try:
        with progress(f"simulating {stack_file.name}"):
            result_report = workflow.run_spec(spec)
            comparison = run_compare(result_report, record, cfc=cfc, align=align,
                                     srs_options=workflow.srs_options(spec))
    except SolverError as exc:
        typer.echo(f"hertz-chain: {Status.FAILED.text}: {_one_line(exc)}", err=True)
        raise typer.Exit(code=Status.FAILED.exit_code)
    except HertzChainError as exc:
        _fail(str(exc))
    typer.echo(report.to_json(comparison.to_dict()) if as_json else report.compare_table(comparison))
    if plot is not None:
        from . import plot as plotting

        try:
            _paths.write_atomically(plot, lambda tmp: plotting.plot_compare(comparison, tmp), force, "--plot")
        except HertzChainError as exc:
            _fail(str(exc))
    for note in comparison.notes:
        typer.echo(f"hertz-chain: note: {_one_line(note)}", err=True)
    status = result_report.status
    if not status.ok:  # as `check`: the comparison is of a partial pulse
        typer.echo(f"hertz-chain: {status.text}: the run did not complete; the comparison is of a partial pulse",
                   err=True)
        raise typer.Exit(code=status.exit_code)


@app.command()
def fit(
    stack_file: Path = typer.Argument(..., help="Stack file whose contacts are fitted (its \\[fit] section is optional)."),
    measured: Path = _MEASURED,
    vary: list[str] = typer.Option([], "--vary", help="A parameter to fit: contact.stiffness[1], contact.restitution[0] (repeatable)."),
    time_unit: Optional[str] = _TIME_UNIT,
    accel_unit: Optional[str] = _ACCEL_UNIT,
    cfc: Optional[int] = _CFC,
    align: str = typer.Option("xcorr", "--align", help="How the starting time shift is found: xcorr, onset or none."),
    as_json: bool = typer.Option(False, "--json", help="Print the result as JSON."),
    write: Optional[Path] = typer.Option(None, "--write", "-w", help="Write the fitted stack as a stack file (.toml)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Draw the measured, start and fitted pulses (PNG)."),
    force: bool = typer.Option(False, "--force", help="Overwrite existing output files."),
    overrides: list[str] = _SET,
) -> None:
    """Fit contact stiffness and restitution to a measured pulse by least squares, with standard errors."""
    from . import _paths
    from .fitting import read_fit_file
    from .measured import read_pulse_csv

    try:
        _check_align_cfc(align, cfc)
        if write is not None and plot is not None and _same_file(write, plot, exists=False):
            _fail(f"--plot {plot}: the same file as --write")
        if write is not None:
            _paths.check_output_path(write, "--write", (".toml",), force)
            if _same_file(write, stack_file):
                _fail(f"--write {write}: the input stack file itself; write the fitted stack to another file")
        if plot is not None:
            _paths.check_output_path(plot, "--plot", PLOT_SUFFIXES, force)
        read_fit_file(stack_file, vary, overrides)
        record = read_pulse_csv(measured, time_unit=time_unit, accel_unit=accel_unit)
    except HertzChainError as exc:
        _fail(str(exc))
    from . import report
    from .fitting import fit as run_fit

    try:
        with progress(f"fitting {stack_file.name} to {measured.name}"):
            result = run_fit(stack_file, record, vary, cfc=cfc, align=align, overrides=overrides)
    except SolverError as exc:
        _solver_failed(exc)
    except HertzChainError as exc:
        _fail(str(exc))
    typer.echo(report.to_json(result.to_dict()) if as_json else result.table())
    try:
        if write is not None:
            _paths.write_atomically(write, lambda tmp: Path(tmp).write_text(result.document, encoding="utf-8"),
                                    force, "--write")
        if plot is not None:
            from . import plot as plotting

            _paths.write_atomically(plot, lambda tmp: plotting.plot_fit(result, tmp), force, "--plot")
    except HertzChainError as exc:
        _fail(str(exc))
    for note in result.fitted.notes:
        if note not in result.notes:  # the table has printed those
            typer.echo(f"hertz-chain: note: {_one_line(note)}", err=True)
    if result.poor:
        typer.echo("hertz-chain: warning: poor fit (see the POOR FIT notes): the values above are not a calibration",
                   err=True)
    if not result.status.ok:
        typer.echo(f"hertz-chain: fit {result.status.text}: {_one_line(result.message).rstrip('.')}"
                   + ("" if "reported" in result.message else "; the last point is reported"), err=True)
        raise typer.Exit(code=result.status.exit_code)


@app.command("plot")
def plot_command(
    store: Path = typer.Argument(..., help="A sweep store (OUT.zarr) written by hertz-chain sweep."),
    x: str = typer.Option(..., "--x", help="The axis (or sampled key) along x, e.g. stack.gaps."),
    y: Optional[str] = typer.Option(None, "--y", help="A second axis: draw a map instead of lines."),
    var: str = typer.Option("top_velocity_gain", "--var", help="The variable to draw."),
    output: Path = typer.Option(..., "--output", "-o", help="The figure to write (.png)."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing figure."),
) -> None:
    """Draw a line or a map from a sweep store."""
    from . import _paths

    try:
        if not (store / "chunk_done").is_dir():
            _fail(f"{store}: not a hertz_chain sweep store (written by hertz-chain sweep)")
        _paths.check_output_path(output, "--output", PLOT_SUFFIXES, force)
        from . import plot as plotting

        _paths.write_atomically(output, lambda tmp: plotting.plot_sweep(store, tmp, x=x, y=y, var=var), force,
                                "--output")
    except HertzChainError as exc:
        _fail(str(exc))


@app.command()
def demo() -> None:
    """The paper's optimal six-mass MVG stack (R = 0.012, e = 0.8): gapped, then touching."""
    from . import workflow

    try:
        typer.echo(workflow.demo())
    except HertzChainError as exc:
        _fail(str(exc))


def _usage_error(exc) -> str:
    """One line for a usage error of the command-line parser (unknown command or flag, a missing
    or malformed argument), with the command to ask for help."""
    message = _one_line(exc.format_message())
    ctx = getattr(exc, "ctx", None)
    if ctx is not None:
        message += f" (see '{ctx.command_path} --help')"
    return message


def _refuse_repeated_options(args: list[str]) -> None:
    """Exit 2 where an option that takes one value is given twice (`--output a.nc --output b.csv`: click
    keeps the last without a word, and a review found only `b.csv` written). Repeatable options
    (`--set`) and flags pass."""
    args = [str(a) for a in args]
    if "--" in args:  # after it, words are values, not options
        args = args[: args.index("--")]
    if any(a in ("--help", "-h") for a in args):  # help wins, as click has it
        return
    # `--opt=value` and `-xVALUE` (a short option with its value attached) name the option before the value
    words = [a.split("=", 1)[0] if a.startswith("--") else a[:2] for a in args if a.startswith("-") and len(a) > 1]
    if len(words) < 2:  # (the command tree costs ~8 ms; a short and a long name may be one option)
        return
    group = typer.main.get_command(app)
    name = next((str(a) for a in args if not str(a).startswith("-")), None)
    command = getattr(group, "commands", {}).get(name)
    for param in getattr(command, "params", ()):  # (typer's own click: its classes are not click's)
        if getattr(param, "param_type_name", "") == "option" and not (
                param.multiple or getattr(param, "is_flag", False) or getattr(param, "count", False)):
            names = set(param.opts) | set(param.secondary_opts)
            given = sum(w in names for w in words)
            if given > 1:
                _fail(f"{param.opts[0]} given {given} times: it takes one value (give it once)")


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point. Exits with the status of the module docstring's table."""
    # Equinox's run-time checks (diffrax's sign check of `dt0` against the traced `t1`) are host
    # callbacks, and an executable with a host callback is never written to JAX's persistent cache.
    # The library validates every input before tracing and reports non-finite states as a failed
    # status, so the command line turns those checks into NaNs and every warm run loads its compiled
    # solve from the cache (benchmarks/results.md: warm `simulate` of the demo 5.0 s -> 3.8 s), and
    # `hertz_chain._export` keeps the traced solve on disk too (`jax.export`; 3.4 s -> 2.6 s).
    os.environ.setdefault("EQX_ON_ERROR", "nan")
    try:
        _refuse_repeated_options(sys.argv[1:] if argv is None else list(argv))
        code = app(args=argv, prog_name="hertz-chain", standalone_mode=False)
    except HertzChainError as exc:  # safety net: never a traceback for a user error
        typer.echo(f"hertz-chain: error: {_one_line(exc)}", err=True)
        sys.exit(EXIT_BAD_INPUT)
    except typer.Exit as exc:
        sys.exit(exc.exit_code)
    except (typer.Abort, EOFError):
        typer.echo("hertz-chain: error: aborted", err=True)
        sys.exit(1)
    except KeyboardInterrupt:
        typer.echo("hertz-chain: interrupted", err=True)
        sys.exit(130)
    except _ClickException as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":  # bare `hertz-chain`: the help, on stdout
            typer.echo(exc.format_message())
            sys.exit(EXIT_BAD_INPUT)
        typer.echo(f"hertz-chain: error: {_usage_error(exc)}", err=True)
        code = getattr(exc, "exit_code", EXIT_BAD_INPUT)
        sys.exit(code if isinstance(code, int) and code else EXIT_BAD_INPUT)
    sys.exit(code if isinstance(code, int) else 0)


if __name__ == "__main__":  # python -m hertz_chain.cli
    main()
