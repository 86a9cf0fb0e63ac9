"""Exports other tools read correctly: CF NetCDF, CSV with a metadata header, the requested output grid.

References: the CF conventions (1.10) as cf_xarray reads them (the time axis from `standard_name`/`axis`,
UDUNITS units through cf_xarray's pint registry); the requested grid `solver.dt_output` itself; the
accelerometer on the dense solution (`hc.accelerometer`) for the exported column; and the bound on a
sampled peak, `A (1 - cos(pi dt / D))` for a pulse of duration D sampled every dt.
"""

import dataclasses

import numpy as np
import pytest
import xarray as xr

import hertz_chain as hc
from hertz_chain.constants import G0
from hertz_chain.report import write_output

STACK = """
title = "one sphere on a Hertz ground, sampled every microsecond"
[drop]
impact_velocity = "1 m/s"
[stack]
masses = ["0.1 kg"]
[contact]
law = "hertz"
stiffness = "1e9 N/m^1.5"
[solver]
dt_output = "1 us"
"""


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("outputs")
    path = d / "one.toml"
    path.write_text(STACK)
    report = hc.simulate_file(path)
    meta = {"title": "one sphere", "source_file": str(path)}
    write_output(report, d / "r.nc", meta)
    write_output(report, d / "r.csv", meta)
    return report, d, path


def test_netcdf_follows_cf(run):
    import cf_xarray  # noqa: F401  (registers the .cf accessor)
    from cf_xarray.units import units as cf_units

    report, d, path = run
    ds = xr.open_dataset(d / "r.nc", engine="h5netcdf")
    assert ds.attrs["Conventions"] == "CF-1.10"
    for key in ("title", "history", "source", "source_file", "version"):
        assert ds.attrs[key]
    assert ds.attrs["source_file"] == str(path.resolve()) and "hertz_chain" in ds.attrs["version"]
    import hashlib  # the input's SHA-256 (provenance: which stack the file came from)

    assert ds.attrs["source_file_sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    # the refined peak force (at the refined peak's time) beside the sampled one: never below it
    assert float(ds["peak_force_refined"][0]) >= float(ds["peak_force"][0]) > 0
    assert ds.cf.axes["T"] == ["time"] and ds.cf.standard_names["time"] == ["time"]
    for name, var in {**ds.data_vars, **ds.coords}.items():
        assert var.attrs.get("long_name"), name
        unit = var.attrs["units"]
        assert unit != "g", name  # UDUNITS' g is the gram
        cf_units.parse_units(unit)  # a UDUNITS unit string
    assert ds["srs_maximax"].attrs["units"] == "m s-2"
    assert ds["velocity"].encoding.get("compression") in ("gzip", "zlib") or ds["velocity"].encoding.get("zlib")
    ds.close()


def test_the_requested_grid_is_what_is_exported(run):
    report, d, _ = run
    ds = xr.open_dataset(d / "r.nc", engine="h5netcdf")
    t = ds["time"].values
    np.testing.assert_allclose(np.diff(t), 1e-6, rtol=1e-9)
    assert ds.attrs["time_sampling"].startswith("uniform")
    ds.close()
    rec = hc.read_pulse_csv(d / "r.csv")  # our own reader takes its units from the header
    np.testing.assert_allclose(np.diff(rec.t), 1e-6, rtol=1e-9)
    # the exported accelerometer against an independent scipy DOP853 solve (rtol 1e-12) of the same drop:
    # 1e-9 of the peak (measured 3e-11); hc.accelerometer (Hermite slope, O(h^3)) to 1e-5 (measured 2e-6)
    from scipy.integrate import solve_ivp

    m, k = 0.1, 1e9
    sol = solve_ivp(lambda t, y: [y[1], k * max(-y[0], 0.0) ** 1.5 / m - G0], (0, 1e-3), [0.0, -1.0],
                    method="DOP853", rtol=1e-12, atol=1e-16, dense_output=True, max_step=1e-6)
    ref = k * np.maximum(-sol.sol(rec.t)[0], 0.0) ** 1.5 / m
    np.testing.assert_allclose(rec.a, ref, rtol=0, atol=1e-9 * ref.max())
    np.testing.assert_allclose(hc.accelerometer(report, rec.t), ref, rtol=0, atol=1e-5 * ref.max())
    # the reported peak and the exported samples agree within the sampling bound A (1 - cos(pi dt / D))
    peak, D = report.top_pulse.peak_g, report.top_pulse.equivalent_half_sine_duration
    assert rec.a.max() / G0 <= peak * (1 + 1e-9)
    assert rec.a.max() / G0 >= peak * np.cos(np.pi * 1e-6 / D)


def test_csv_starts_with_its_provenance(run):
    _, d, path = run
    lines = (d / "r.csv").read_text().splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    assert lines[: len(comments)] == comments and len(comments) >= 4
    text = "\n".join(comments)
    assert str(path) in text and "hertz_chain" in text and "m/s^2" in text and "uniform grid" in text


def test_a_report_of_a_stack_file_exported_from_python_keeps_its_title_and_source(run):
    # hc.simulate_file's report carries the file's title and path: write_output without `meta` records
    # them (a review: the default title and no input file); `meta` still overrides
    report, d, path = run
    assert report.title == "one sphere on a Hertz ground, sampled every microsecond" and report.source_file == str(path.resolve())
    write_output(report, d / "own.nc")
    write_output(report, d / "own.csv")
    with xr.open_dataset(d / "own.nc", engine="h5netcdf") as ds:
        assert ds.attrs["title"] == "one sphere on a Hertz ground, sampled every microsecond"
        assert ds.attrs["source_file"] == str(path.resolve())
        import hashlib

        assert ds.attrs["source_file_sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    head = (d / "own.csv").read_text().splitlines()[:2]
    assert head[0] == "# one sphere on a Hertz ground, sampled every microsecond" and f"input file: {path.resolve()}" in head[1]
    bare = dataclasses.replace(report, title=None, source_file=None)  # a report from hc.analyse: the defaults
    write_output(bare, d / "bare.csv")
    head = (d / "bare.csv").read_text().splitlines()[:2]
    assert head[0] == "# hertz_chain simulation" and head[1] == "# input file: (none)"


def test_a_partial_run_is_marked_in_every_file_and_headers_stay_one_line(tmp_path, monkeypatch):
    """A review: the CSV of a run cut short by t_max read as a finished one (only JSON and NetCDF said
    "partial"), the NetCDF dropped the analysis's warnings, a title with a line break ended the CSV's
    comment (pandas then read a column named after its second line), `write_output` wrote CSV text into
    `out.json`, and the recorded command (`--set solver.t_max="10 ms"`) did not parse back. The sphere's
    contact lasts 0.32 ms (Hertz: 3.218 (m/k)^(2/5) v^(-1/5)), so t_max = 0.1 ms cuts it."""
    import shlex

    import pandas as pd

    from hertz_chain.errors import OutputPathError
    from hertz_chain.report import _metadata

    path = tmp_path / "cut.toml"
    path.write_text(STACK.replace('dt_output = "1 us"', 'dt_output = "1 us"\nt_max = "0.1 ms"'))
    report = hc.simulate_file(path)
    assert report.status.incomplete
    meta = {"title": "first line\nsecond line", "source_file": str(path)}
    write_output(report, tmp_path / "cut.csv", meta)
    write_output(report, tmp_path / "cut.nc", meta)
    lines = (tmp_path / "cut.csv").read_text().splitlines()
    header = [ln for ln in lines if ln.startswith("#")]
    assert lines[: len(header)] == header  # every header line a comment, the title's break included
    assert any(ln.startswith("# status: incomplete: t_max reached (PARTIAL RESULTS") for ln in header)
    table = pd.read_csv(tmp_path / "cut.csv", comment="#")
    assert list(table.columns) == ["time_s", "accelerometer_mps2", "accelerometer_g", "velocity_mps"]
    ds = xr.open_dataset(tmp_path / "cut.nc", engine="h5netcdf")
    assert ds.attrs["partial"] == 1 and ds.attrs["warnings"] == "\n".join(report.warnings)
    with pytest.raises(OutputPathError, match=r"path .*out\.json: a \.nc \(NetCDF\) or \.csv file"):
        write_output(report, tmp_path / "out.json")
    assert not (tmp_path / "out.json").exists()
    argv = ["/usr/bin/hertz-chain", "simulate", "my stack.toml", "--set", 'solver.t_max="10 ms"']
    monkeypatch.setattr("sys.argv", argv)
    command = _metadata(None)["history"].split(" ", 1)[1]
    assert shlex.split(command) == ["hertz-chain", *argv[1:]]
