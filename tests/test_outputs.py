"""Exports other tools read correctly: CF NetCDF, CSV with a metadata header, the requested output grid.

References: the CF conventions (1.10) as cf_xarray reads them (the time axis from `standard_name`/`axis`,
UDUNITS units through cf_xarray's pint registry); the requested grid `solver.dt_output` itself; the
accelerometer on the dense solution (`hc.accelerometer`) for the exported column; and the bound on a
sampled peak, `A (1 - cos(pi dt / D))` for a pulse of duration D sampled every dt.
"""

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
    assert ds.attrs["source_file"] == str(path) and "hertz_chain" in ds.attrs["version"]
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
