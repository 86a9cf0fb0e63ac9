"""The hertz-chain command line: output contract, files, and one-line errors with exit status 2.

Expected gains: paper Eq 19 written out here; for the normative example (issue #5: tsuji, e = 0.8,
1 cm gaps, g = 0) the contacts are sequential, so the simulated gain equals Eq 19.
"""

import json
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from hertz_chain.cli import app

ROOT = Path(__file__).resolve().parents[1]
NORMATIVE = ROOT / "examples" / "issue5_normative.toml"
runner = CliRunner()


def eq19(m, e):
    m = np.asarray(m)
    return (1 + e) * np.prod((1 + e) / (1 + m[1:] / m[:-1])) - 1


@pytest.fixture(scope="module")
def normative_json():
    res = runner.invoke(app, ["simulate", str(NORMATIVE), "--json"])
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout)


def test_normative_example_json_contract(normative_json):
    d = normative_json
    for key in ("status", "top_velocity_gain", "velocity_gains", "rigid", "contacts", "top_pulse",
                "energy_error"):
        assert key in d
    assert set(d["rigid"]) >= {"nominal_gain", "measured_restitution_gain", "event_driven_gain"}
    assert set(d["contacts"][0]) >= {"interface", "start_s", "end_s", "restitution", "peak_force_N"}
    assert set(d["top_pulse"]) >= {"peak_g", "duration_ms", "delta_v_mps", "equivalent_half_sine_ms"}
    g = eq19([8.4, 3.4683, 1.4320, 0.5913, 0.2441, 0.1008], 0.8)
    assert d["status"] == "complete"
    assert d["top_velocity_gain"] == pytest.approx(g, rel=1e-6)
    assert d["rigid"]["nominal_gain"] == pytest.approx(g, rel=1e-12)
    assert d["velocity_gains"][-1] == d["top_velocity_gain"]
    assert len(d["pulses"]) == 6 and d["pulses"][-1] == d["top_pulse"]  # every mass, bottom first
    # the top mass's one pulse takes it from -v_ff to G v_ff (Eq 19): delta V = (G + 1) v_ff, v_ff = 1 m/s
    assert d["top_pulse"]["delta_v_mps"] == pytest.approx(g + 1, rel=1e-6)
    assert d["energy_error"] < 1e-5
    # the model that was run, named by its contact law (the file's [contact] law), not "Hertz" for every law
    assert d["model"] == "compliant (tsuji)"
    assert set(d["contacts"][0]) >= {"peak_force_time_s"} and len(d["peak_velocity_times_s"]) == 6


def test_outputs_and_no_overwrite(tmp_path):
    import xarray as xr

    nc, png, csv = tmp_path / "r.nc", tmp_path / "r.png", tmp_path / "r.csv"
    res = runner.invoke(app, ["simulate", str(NORMATIVE), "--output", str(nc), "--plot", str(png)])
    assert res.exit_code == 0, res.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ds = xr.open_dataset(nc, engine="h5netcdf")
    assert ds["velocity"].attrs["units"] == "m s-1" and ds["time"].attrs["units"] == "s"
    assert ds.sizes["mass"] == 6
    # per-mass pulse metrics; the top one goes from -v_ff to G v_ff (Eq 19): delta V = (G + 1) v_ff
    g = eq19([8.4, 3.4683, 1.4320, 0.5913, 0.2441, 0.1008], 0.8)
    assert ds["pulse_delta_v"].attrs["units"] == "m s-1"
    assert float(ds["pulse_delta_v"][-1]) == pytest.approx(g + 1, rel=1e-6)
    assert np.all(np.isfinite(ds["pulse_peak_g"].values))  # every mass is struck
    ds.close()
    res = runner.invoke(app, ["simulate", str(NORMATIVE), "--output", str(csv)])
    assert res.exit_code == 0
    lines = csv.read_text().splitlines()
    header = next(ln for ln in lines if not ln.startswith("#"))
    assert header == "time_s,accelerometer_mps2,accelerometer_g,velocity_mps"
    assert any(str(NORMATIVE) in ln for ln in lines if ln.startswith("#"))  # the commented metadata header
    before = csv.read_text()
    res = runner.invoke(app, ["simulate", str(NORMATIVE), "--output", str(csv)])
    assert res.exit_code == 2 and "--force" in res.output
    assert csv.read_text() == before  # nothing the user wrote is overwritten without asking


BAD = {
    "broken": "[drop\nimpact_velocity = 1\n",
    "unknown": NORMATIVE.read_text().replace("rtol = 1e-10", "rtool = 1e-10"),
    "missing": NORMATIVE.read_text().replace('law = "tsuji"\n', ""),
    "units": NORMATIVE.read_text().replace('gaps = "1 cm"', 'gaps = "1 kg"'),
    # a passive contact cannot return more energy than it received: e <= 1 (the rigid model's
    # 'active ground' e > 1 has no compliant counterpart)
    "ground_e": NORMATIVE.read_text() + '\n[contact.ground]\nrestitution = 1.2\n',
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_files_give_one_line_and_status_2(tmp_path, case):
    path = tmp_path / f"{case}.toml"
    path.write_text(BAD[case])
    res = runner.invoke(app, ["simulate", str(path)])
    assert res.exit_code == 2
    lines = [line for line in res.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("hertz-chain: error:")
    key = {"broken": "line", "unknown": "solver.rtool", "missing": "contact.law", "units": "stack.gaps",
           "ground_e": "contact.ground"}[case]
    assert key in lines[0]


def test_real_process_exit_status_and_no_traceback(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(BAD["units"])
    exe = Path(sys.executable).with_name("hertz-chain")
    proc = subprocess.run([str(exe), "simulate", str(path)], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("module", ["hertz_chain", "hertz_chain.cli"])
def test_python_dash_m_runs_the_command_line(tmp_path, module):
    # `python -m hertz_chain` (a working copy without the console script) is the same command line; a review
    # found `python -m hertz_chain.cli` exited 0 without doing anything. The bad file's exit status, no traceback
    ok = subprocess.run([sys.executable, "-m", module, "design", "-R", "0.012", "-e", "0.8", "--json"],
                        capture_output=True, text=True)
    assert ok.returncode == 0 and json.loads(ok.stdout)["mvg"]["n"] == 6  # paper Fig 17, as below
    path = tmp_path / "bad.toml"
    path.write_text(BAD["units"])
    bad = subprocess.run([sys.executable, "-m", module, "simulate", str(path)], capture_output=True, text=True)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr and "stack.gaps" in bad.stderr
    if module == "hertz_chain":  # its exports record the command as run (was the bare word "hertz_chain")
        example = Path(__file__).resolve().parents[1] / "examples" / "fit_drop.toml"
        out = tmp_path / "run.csv"
        run = subprocess.run([sys.executable, "-m", module, "simulate", str(example), "--output", str(out)],
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        assert f"python -m hertz_chain simulate {example} --output {out}" in out.read_text().splitlines()[2]


def test_design_command():
    res = runner.invoke(app, ["design", "-R", "0.012", "-e", "0.8", "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["mvg"]["n"] == 6  # paper Fig 17: the optimal MVG stack for R = 0.012, e = 0.8 has 6 masses
    assert d["mvg"]["velocity_gain"] == pytest.approx(5.0407, abs=5e-5)  # docs/references.md, Eq 20
    assert d["met"]["n"] == 10  # Figs 16-17: ten-mass MET for R ~ 0.0118
    assert d["met"]["velocity_gain"] == pytest.approx(sum(0.8**k for k in range(1, 11)), rel=1e-12)  # Eq 29
    for kind in ("mvg", "met"):  # K_n = m_n G^2 / M (top kinetic energy / stack kinetic energy)
        m = d[kind]["masses"]
        assert d[kind]["total_mass"] == pytest.approx(sum(m), rel=1e-14)
        assert d[kind]["energy_efficiency"] == pytest.approx(m[-1] * d[kind]["velocity_gain"] ** 2 / sum(m), rel=1e-12)
    # the spelling, with a bottom mass: masses in kg, m_1 = 8.4 kg, m_6 = 0.012 * 8.4 kg
    res = runner.invoke(app, ["design", "--mass-ratio", "0.012", "--restitution", "0.8", "--bottom-mass", "8.4",
                              "--json"])
    assert res.exit_code == 0, res.output
    kg = json.loads(res.stdout)
    assert kg["mvg"]["masses"][0] == 8.4 and kg["mvg"]["masses"][-1] == pytest.approx(0.1008, rel=1e-14)
    assert kg["mvg"]["velocity_gain"] == pytest.approx(d["mvg"]["velocity_gain"], rel=1e-15)  # scale-free
    table = runner.invoke(app, ["design", "--mass-ratio", "0.012", "--restitution", "0.8"])
    assert table.exit_code == 0 and "MVG/MET" in table.stdout and "5.0407" in table.stdout
    res = runner.invoke(app, ["design", "-R", "1.5", "-e", "0.8"])
    assert res.exit_code == 2 and "R" in res.output


def test_set_overrides_a_key_like_editing_the_file(tmp_path):
    """`--set KEY=VALUE` gives what the edited file gives (the reference: the file written with the new
    value), leaves the user's file untouched, and a bad override is one line with exit 2."""
    edited = tmp_path / "edited.toml"
    edited.write_text(NORMATIVE.read_text().replace('impact_velocity = "1 m/s"', 'impact_velocity = "2 m/s"'))
    assert edited.read_text() != NORMATIVE.read_text()
    before = NORMATIVE.read_text()
    ref = runner.invoke(app, ["simulate", str(edited), "--json"])
    res = runner.invoke(app, ["simulate", str(NORMATIVE), "--json", "--set", 'drop.impact_velocity="2 m/s"'])
    assert res.exit_code == 0 == ref.exit_code, res.output
    a, b = json.loads(res.stdout), json.loads(ref.stdout)
    assert a["launch_velocities_mps"] == b["launch_velocities_mps"]
    assert NORMATIVE.read_text() == before
    for bad, needle in (("drop.impact_velocity=2 kg", "drop.impact_velocity"), ("drop", "KEY=VALUE"),
                        ("drop.impact_velocity.x=1", "is a value")):
        res = runner.invoke(app, ["simulate", str(NORMATIVE), "--set", bad])
        assert res.exit_code == 2 and needle in res.output and len(res.output.strip().splitlines()) == 1


def test_design_says_when_the_top_masses_differ():
    """The MET design's n is an integer, so its top mass only approximates the one asked for (here
    0.099485 kg for 0.1 kg): the table and JSON say the ratios compare unequal stacks."""
    res = runner.invoke(app, ["design", "--bottom-mass", "8.4", "--top-mass", "0.1", "--restitution", "0.8", "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    top_mvg, top_met = d["mvg"]["masses"][-1], d["met"]["masses"][-1]
    assert top_mvg == pytest.approx(0.1, rel=1e-12) and abs(top_met / top_mvg - 1) > 1e-3
    assert d["note"] and "unequal top masses" in d["note"]
    res = runner.invoke(app, ["design", "--bottom-mass", "8.4", "--top-mass", "0.1", "--restitution", "0.8"])
    assert "note: the designs end at different top masses" in res.stdout


def test_design_takes_units_and_writes_a_stack_file_that_simulates(tmp_path):
    """`--bottom-mass "8.4 kg" --top-mass "100 g"` = 8.4 and 0.1 kg; `--write` gives the MVG stack of
    paper Eq 15 (m_i = m_1 R^((i-1)/(n-1)), n = 6 by Eqs 20/22-24 for R = 0.0119, e = 0.8); simulated with
    5 cm gaps, no gravity and Tsuji contacts (e independent of speed: independent collisions of the
    rigid model), its top gain is Eq 20's to 1e-6."""
    out = tmp_path / "d.toml"
    res = runner.invoke(app, ["design", "--bottom-mass", "8.4 kg", "--top-mass", "100 g", "-e", "0.8", "--write",
                              str(out), "--stiffness", "1e9 N/m^1.5", "--gap", "5 cm"])
    assert res.exit_code == 0, res.output
    spec = tomllib.loads(out.read_text())
    R, e, n = 0.1 / 8.4, 0.8, 6
    masses = [float(m.split()[0]) for m in spec["stack"]["masses"]]
    np.testing.assert_allclose(masses, 8.4 * R ** (np.arange(n) / (n - 1)), rtol=1e-12)
    res = runner.invoke(app, ["simulate", str(out), "--json", "--set", "drop.gravity=0", "--set", 'solver.until="launch"'])
    assert res.exit_code == 0, res.output
    eq20 = (1 + e) ** n / (1 + R ** (1 / (n - 1))) ** (n - 1) - 1
    assert json.loads(res.stdout)["top_velocity_gain"] == pytest.approx(eq20, rel=1e-6)
    # the same masses from plain numbers (kg) and grams
    a = runner.invoke(app, ["design", "--m1", "8.4", "--mn", "100 g", "-e", "0.8", "--json"])
    assert json.loads(a.stdout)["mvg"]["masses"] == pytest.approx(masses, rel=1e-12)
    for args, needle in ((["--write", str(tmp_path / "x.toml")], "--stiffness: missing"),
                         (["--write", str(tmp_path / "x.toml"), "--stiffness", "1e9 kg"], "--stiffness"),
                         (["--write", str(tmp_path / "x.toml"), "--stiffness", "1e9 N/m^1.5", "--kind", "best"], "--kind"),
                         (["--write", str(out), "--stiffness", "1e9 N/m^1.5"], "exists"),
                         (["--bottom-mass", "8 m"], "--bottom-mass")):
        res = runner.invoke(app, ["design", "-R", "0.012", "-e", "0.8", *args] if "--bottom-mass" not in args
                            else ["design", "--top-mass", "1 kg", "-e", "0.8", *args])
        assert res.exit_code == 2 and needle in res.output and len(res.output.strip().splitlines()) == 1, res.output


def test_progress_lines_only_when_asked_off_a_terminal(monkeypatch):
    """Off a terminal nothing is printed unless HERTZ_CHAIN_PROGRESS=1 (then one line at the start of the
    wait and one at the end); the results on stdout are the same either way."""
    monkeypatch.setenv("HERTZ_CHAIN_PROGRESS_DELAY", "0")
    monkeypatch.delenv("HERTZ_CHAIN_PROGRESS", raising=False)
    quiet = runner.invoke(app, ["simulate", str(NORMATIVE), "--json"])
    assert quiet.exit_code == 0 and "hertz-chain: simulating" not in quiet.stderr
    monkeypatch.setenv("HERTZ_CHAIN_PROGRESS", "1")
    loud = runner.invoke(app, ["simulate", str(NORMATIVE), "--json"])
    assert loud.exit_code == 0, loud.output
    lines = [ln for ln in loud.stderr.splitlines() if ln.startswith("hertz-chain: simulating")]
    assert len(lines) == 2 and "compiles" in lines[0] and "done in" in lines[1]
    assert json.loads(loud.stdout)["top_velocity_gain"] == json.loads(quiet.stdout)["top_velocity_gain"]
    monkeypatch.setenv("HERTZ_CHAIN_PROGRESS_DELAY", "abc")  # a malformed setting never stops a run
    odd = runner.invoke(app, ["simulate", str(NORMATIVE), "--json"])
    assert odd.exit_code == 0 and odd.exception is None


def test_options_given_twice_are_refused_only_where_they_take_one_value():
    """`_refuse_repeated_options`: a single-value option given twice exits 2 (the test_bad_input rows); these
    pass untouched to click: a repeatable `--set`, a word after `--`, `--help` (help wins), a negative value."""
    import typer

    from hertz_chain.cli import _refuse_repeated_options

    for argv in (["simulate", "f.toml", "--set", "a=1", "--set", "b=2"], ["simulate", "f.toml", "-o", "a.nc", "--", "-o"],
                 ["design", "-R", "0.012", "-e", "0.8", "-R", "0.1", "--help"], ["design", "-R", "-0.1", "-e", "-0.1"]):
        _refuse_repeated_options(argv)
    with pytest.raises(typer.Exit):
        _refuse_repeated_options(["design", "-R", "0.012", "-e0.8", "-e0.7"])
