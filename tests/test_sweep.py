"""Sweeps (`hertz_chain.sweeps`, `hertz-chain sweep`): every design against the ordinary path (the stack
file with the axis values written in, `build` and `simulate` one by one); paper Eq 19 for the rigid gain;
scipy's own Sobol sampler for sampled designs; a sweep killed with SIGKILL (mid-write and between the
results and their marker) and run again equals an uninterrupted one; Dask gives the same numbers."""

import copy
import os
import signal
import subprocess
import sys

import numpy as np
import pytest
import tomli_w
import xarray as xr
from scipy.integrate import quad
from scipy.stats import qmc

import hertz_chain as hc
from hertz_chain.cli import main
from hertz_chain.errors import OutputPathError
from hertz_chain.sweeps import check, sweep

BASE = {"drop": {"impact_velocity": "1 m/s"}, "stack": {"masses": [1.0, 0.3, 0.1], "gaps": "1 mm"},
        "contact": {"law": "tsuji", "stiffness": "1e9 N/m^1.5", "restitution": 0.8},
        "solver": {"rtol": 1e-12, "atol": 1e-12}}
GRID = {"chunk": 2, "axis": [{"key": "stack.gaps", "values": ["0 mm", "0.1 mm", "1 cm"]},
                             {"key": "contact.stiffness", "index": [2], "space": "log", "start": "1e8 N/m^1.5",
                              "stop": "1e10 N/m^1.5", "num": 2}]}


def _file(tmp_path, sweep_section, name="sweep.toml"):
    path = tmp_path / name
    path.write_text(tomli_w.dumps(BASE | {"sweep": sweep_section}), encoding="utf-8")
    return path


def _open(path):
    return xr.open_zarr(path, consolidated=False).load()


def test_grid_sweep_equals_the_designs_run_one_by_one(tmp_path):
    """Each grid point against `simulate_file` of the stack file with the values written in (the gaps,
    and the stiffness of interface 2 as a [[contact.interface]] override), under gravity; the rigid gain
    against paper Eq 19 written out here."""
    out = tmp_path / "grid.zarr"
    result = sweep(_file(tmp_path, GRID | {"durations": True}), out)
    assert (result.designs, result.chunks, result.computed) == (6, 3, 3)
    ds = _open(out)
    assert ds.top_velocity_gain.dims == ("stack.gaps", "contact.stiffness[2]")
    np.testing.assert_allclose(ds["stack.gaps"], [0.0, 1e-4, 1e-2])
    np.testing.assert_allclose(ds["contact.stiffness[2]"], [1e8, 1e10])
    assert ds.top_velocity_gain.attrs["units"] == "1" and ds["stack.gaps"].attrs["units"] == "m"
    m = np.array([1.0, 0.3, 0.1])
    eq19 = 1.8 * np.prod(1.8 / (1 + m[1:] / m[:-1])) - 1
    for i, gap in enumerate([0.0, 1e-4, 1e-2]):
        for j, k in enumerate([1e8, 1e10]):
            doc = copy.deepcopy(BASE)
            doc["stack"]["gaps"] = gap
            doc["contact"]["interface"] = [{"index": 2, "stiffness": k}]
            path = tmp_path / f"d{i}{j}.toml"
            path.write_text(tomli_w.dumps(doc))
            rep = hc.simulate_file(path)
            assert int(ds.status[i, j]) == rep.status
            # to the solves' global error: a vmapped solve of a batch takes its own steps (tests/test_batch.py);
            # for the soft gapped design the value moves by 2e-8 between rtol = 1e-10 and 1e-12
            assert float(ds.top_velocity_gain[i, j]) == pytest.approx(rep.top_velocity_gain, rel=1e-8)
            # (the lower masses, still on the ground when the cascade ends, report their velocities at the step
            # where it ended, which a batch places elsewhere: only the top's launch is final)
            assert float(ds.velocity_gains[i, j, -1]) == float(ds.top_velocity_gain[i, j])
            assert float(ds.rigid_gain[i, j]) == pytest.approx(eq19, rel=1e-12)
            # the top pulse's 10 % duration (`durations = true`) against the report's, on its own steps: to the
            # linear interpolation between steps at the 10 % points (measured 2e-6 .. 3e-5)
            assert float(ds.top_duration_10[i, j]) == pytest.approx(rep.top_pulse.duration_10, rel=1e-4)
            assert float(ds.top_rise_time[i, j]) == pytest.approx(rep.top_pulse.rise_time, rel=2e-4)  # measured 6.5e-5
            # the accelerometer's velocity change under gravity (a + g integrated, as the report's pulse; the
            # bare launch-minus-impact velocity missed g times the contact time: -0.4 % touching)
            assert float(ds.top_delta_v[i, j]) == pytest.approx(rep.top_pulse.delta_v, rel=1e-6)
            # the rigid gains with the measured restitutions (Eq 19; event-driven with the design's gaps and
            # gravity) as the report computes them: undefined alike (touching: no complete first contact;
            # 0.1 mm: a pair separating faster than it closed, e > 1), else equal to the measured e's error
            # (the sweep reads the ground's at the steps around it, within g h / V: measured 2.4e-8)
            for var, ref in (("rigid_gain_measured", rep.rigid.measured_restitution_gain),
                             ("rigid_gain_event_driven", rep.rigid.event_driven_gain)):
                if ref is None:
                    assert np.isnan(float(ds[var][i, j])) and gap < 1e-2
                else:
                    assert float(ds[var][i, j]) == pytest.approx(ref, rel=1e-6)
    assert ds.chunk_done.values.tolist() == [1, 1, 1]


def test_sobol_designs_are_scipys_and_zip_pairs_values(tmp_path):
    sob = {"sample": "sobol", "samples": 4, "seed": 7, "chunk": 4,
           "axis": [{"key": "drop.impact_velocity", "bounds": ["0.5 m/s", "2 m/s"]},
                    {"key": "stack.masses", "index": 2, "bounds": ["0.2 kg", "0.4 kg"]}]}
    ds = _open(sweep(_file(tmp_path, sob), tmp_path / "s.zarr").path)
    U = qmc.Sobol(2, scramble=True, seed=7).random(4)
    np.testing.assert_allclose(ds["drop.impact_velocity"], 0.5 + 1.5 * U[:, 0], rtol=1e-15)
    np.testing.assert_allclose(ds["stack.masses[2]"], 0.2 + 0.2 * U[:, 1], rtol=1e-15)
    assert ds.top_velocity_gain.dims == ("design",) and np.all(ds.status == 0)
    zipped = {"combine": "zip", "axis": [{"key": "stack.masses", "index": 2, "values": ["0.2 kg", "0.4 kg"]},
                                         {"key": "stack.gaps", "values": ["0 m", "1 mm"]}]}
    ds = _open(sweep(_file(tmp_path, zipped, "z.toml"), tmp_path / "z.zarr").path)
    assert ds.sizes["design"] == 2
    np.testing.assert_allclose(ds["stack.gaps"], [0.0, 1e-3])


def _cli_sweep(path, out, fault=None):
    env = dict(os.environ)
    if fault:
        env["HERTZ_CHAIN_SWEEP_FAULT"] = fault
    return subprocess.run([sys.executable, "-c", "from hertz_chain.cli import main; main()", "sweep", str(path),
                           "--output", str(out)], env=env, capture_output=True, text=True, timeout=600)


def test_ctrl_c_says_what_was_kept_and_how_to_resume(tmp_path, capsys, monkeypatch):
    """Ctrl-C (KeyboardInterrupt) while the sweep runs: exit 130 and one line naming the store and the way
    on (a review: the command exited 130 without a word). The interrupt is raised in place of the run, in
    this process: what a store keeps after one is the kill tests' business (below)."""
    import hertz_chain.sweeps as sweeps

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(sweeps, "sweep", interrupted)
    out = tmp_path / "int.zarr"
    with pytest.raises(SystemExit) as exc:
        main(["sweep", str(_file(tmp_path, GRID)), "--output", str(out)])
    err = capsys.readouterr().err
    assert exc.value.code == 130
    assert f"hertz-chain: sweep interrupted: the chunks written to {out} are kept; run the same command again " \
           "to resume" in err and "Traceback" not in err


def test_a_sweep_killed_mid_write_and_before_its_marker_resumes_to_the_same_store(tmp_path):
    path = _file(tmp_path, GRID)
    ref = tmp_path / "ref.zarr"
    sweep(path, ref)
    out = tmp_path / "killed.zarr"
    run = _cli_sweep(path, out, "creating:0")  # killed while the store is laid out: no store under its name
    assert run.returncode == -signal.SIGKILL, run.stderr
    assert not out.exists() and len(list(tmp_path.glob(".killed.zarr.creating-*"))) == 1
    for fault in ("mid-data:1", "after-data:2"):
        run = _cli_sweep(path, out, fault)
        assert run.returncode == -signal.SIGKILL, run.stderr
        if fault == "mid-data:1":  # the left-over layout of the dead run is gone
            assert not list(tmp_path.glob(".killed.zarr.creating-*"))
            # chunk 2 (the gaps' third value) is not run yet: status, regime and steps read -1 (not 0, which
            # read as "complete" and "independent"), the floats NaN
            part = _open(out)
            for name in ("status", "regime", "num_steps"):
                assert np.all(part[name].values[2] == -1), name
            assert np.all(np.isnan(part["top_velocity_gain"].values[2]))
            # CF flags name the codes (hertz_chain.status.Status, and -1)
            flags = dict(zip(np.asarray(part["status"].attrs["flag_values"]).tolist(), part["status"].attrs["flag_meanings"].split()))
            assert flags[-1] == "not_run" and flags[0] == "complete" and flags[5] == "failed" and len(flags) == 7
    resumed = sweep(path, out)  # the same sweep again (in this process: its solve is compiled already)
    assert (resumed.computed, resumed.skipped) == (1, 2)  # chunk 2 was recomputed, never 0 or 1 again
    a, b = _open(ref), _open(out)
    for name in a.data_vars:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


def test_dask_local_cluster_gives_the_same_store(tmp_path):
    path = _file(tmp_path, GRID)
    a = _open(sweep(path, tmp_path / "local.zarr").path)
    b = _open(sweep(path, tmp_path / "dask.zarr", workers=2).path)
    for name in a.data_vars:  # identical: a chunk's pieces do not depend on the devices (one per worker)
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
    # --scheduler: an existing cluster reached at its real tcp:// address (here one in this process, with
    # one thread worker, so that it reuses this process's compiled solves)
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                      dashboard_address=None) as cluster:
        assert cluster.scheduler_address.startswith("tcp://")
        c = _open(sweep(path, tmp_path / "scheduler.zarr", scheduler=cluster.scheduler_address).path)
    for name in a.data_vars:
        np.testing.assert_allclose(a[name].values, c[name].values, rtol=1e-12, err_msg=name)


@pytest.mark.parametrize("section, words", [
    ({"axis": [{"key": "stack.gap", "values": [0]}]}, ["stack.gap", "did you mean 'stack.gaps'"]),
    ({"axis": [{"key": "stack.masses", "index": 5, "values": [1]}]}, ["index", "5", "out of range"]),
    ({"combine": "zip", "axis": [{"key": "stack.gaps", "values": [0, 1e-3]},
                                 {"key": "drop.impact_velocity", "values": ["1 m/s"]}]}, ["same number of values"]),
    ({"sample": "sobol", "axis": [{"key": "stack.gaps", "bounds": [0, 1e-3]}]}, ["sweep.samples", "missing"]),
    ({"axis": [{"key": "contact.stiffness", "space": "log", "start": "1 kg", "stop": "2 kg", "num": 3}]},
     ["start", "stiffness"]),
    ({"axis": [{"key": "stack.gaps", "space": "cubic", "start": 0, "stop": 1e-3, "num": 3}]}, ["space", "linear, log"]),
    ({}, ["sweep.axis", "missing"]),
    ({"axis": [{"key": "stack.gaps", "values": ["-1 mm", "1 mm"]}]}, ["sweep.axis[0].values", "-0.001", ">= 0"]),
    ({"axis": [{"key": "contact.restitution", "values": [1.5, 0.5]}]}, ["restitution", "<= 1"]),
    ({"axis": [{"key": "drop.impact_velocity", "values": ["0 m/s"]}]}, ["impact_velocity", "> 0"]),
    # below the laws' calibrated range (a review: a JAX traceback, exit 1, and a half-made store)
    ({"axis": [{"key": "contact.restitution", "values": [0.0005]}]}, ["0.0005", "restitution must be >= 0.001"]),
    ({"sample": "lhs", "samples": 4, "axis": [{"key": "contact.restitution", "bounds": [0.0002, 0.01]}]},
     ["sweep.axis[0].bounds", ">= 0.001"]),
    # a fall past the largest speed a stack file takes (it ran: a 1.4e9 g peak reported complete)
    ({"axis": [{"key": "drop.height", "values": [0.1, 1e9]}]}, ["1000000000.0", "at most 5.09858e+06 m", "10000 m/s"]),
    ({"sample": "lhs", "samples": 4, "axis": [{"key": "stack.masses", "index": 2, "bounds": ["-1 kg", "1 kg"]}]},
     ["bounds", "> 0"]),
    ({"axis": [{"key": "stack.gaps", "values": [0, 1e-3]}, {"key": "stack.gaps", "index": [1], "values": [0]}]},
     ["stack.gaps[1]", "sweep.axis[0] too"]),
    ({"axis": [{"key": "drop.height", "values": ["1 cm"]}, {"key": "drop.impact_velocity", "values": ["1 m/s"]}]},
     ["drop.height and drop.impact_velocity", "vary one"]),
    # keys that do not apply to the kind of axis were silently ignored
    ({"sample": "montecarlo", "samples": 4, "axis": [{"key": "stack.gaps", "std": "0.1 mm",
                                                      "bounds": ["0 mm", "1 mm"]}]},
     ["sweep.axis[0].bounds", "not used by a normal Monte-Carlo axis"]),
    ({"sample": "sobol", "samples": 4, "axis": [{"key": "stack.gaps", "bounds": [0, 1e-3], "values": [0]}]},
     ["sweep.axis[0].values", "not used by sample = 'sobol'"]),
    ({"axis": [{"key": "stack.gaps", "values": ["1 mm"], "std": "1 mm"}]}, ["sweep.axis[0].std", "grid axis"]),
    ({"axis": [{"key": "stack.gaps", "values": ["1 mm", "0.1 cm"]}]}, ["sweep.axis[0].values", "repeats"]),
    ({"axis": [{"key": "stack.gaps", "space": "log", "start": "1 mm", "stop": "1 cm", "num": 1}]},
     ["sweep.axis[0].num", "start only"]),
    ({"sample": "lhs", "samples": 4, "combine": "zip", "axis": [{"key": "stack.gaps", "bounds": [0, 1e-3]}]},
     ["sweep.combine", "grid axes"]),
])
def test_bad_sweep_sections_give_one_line_and_exit_2(tmp_path, capsys, section, words):
    path = _file(tmp_path, section)
    with pytest.raises(SystemExit) as exc:
        main(["sweep", str(path), "--output", str(tmp_path / "o.zarr")])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and err.startswith("hertz-chain: error: ")
    for w in words:
        assert w in err, (w, err)
    assert not (tmp_path / "o.zarr").exists()


def test_a_store_of_another_sweep_or_a_foreign_folder_is_refused(tmp_path, capsys):
    path = _file(tmp_path, GRID)
    out = tmp_path / "o.zarr"
    sweep(path, out)
    other = _file(tmp_path, GRID | {"chunk": 3}, "other.toml")
    foreign = tmp_path / "mine.zarr"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    for target, word in ((out, "different stack file"), (foreign, "not a hertz_chain sweep store")):
        with pytest.raises(SystemExit) as exc:
            main(["sweep", str(other), "--output", str(target)])
        err = capsys.readouterr().err
        assert exc.value.code == 2 and word in err and f"--output {target}:" in err
        with pytest.raises(OutputPathError, match=f"^output {target}: .*{word}"):  # Python's own argument
            sweep(other, target)
    assert (foreign / "notes.txt").read_text() == "mine"
    # the store draws: a map over both axes, and a one-line refusal of an unknown axis or variable
    png = tmp_path / "map.png"
    with pytest.raises(SystemExit) as exc:
        main(["plot", str(out), "--x", "contact.stiffness[2]", "--y", "stack.gaps", "--output", str(png)])
    assert exc.value.code in (0, None) and png.read_bytes()[:4] == b"\x89PNG"
    for flags, word in ((["--x", "stack.gap"], "--x"), (["--x", "stack.gaps", "--var", "gain"], "--var"),
                        (["--x", "stack.gaps", "--var", "top_duration_10"], "--var")):  # none without durations
        with pytest.raises(SystemExit) as exc:
            main(["plot", str(out), *flags, "--output", str(tmp_path / "x.png")])
        err = capsys.readouterr().err
        assert exc.value.code == 2 and err.startswith(f"hertz-chain: error: {word}") and err.count("\n") == 1


def test_monte_carlo_tails_outside_a_key_s_range_are_failed_designs_not_a_failed_sweep(tmp_path):
    """A normal tolerance of 0.5 mm on touching gaps: about half the samples are negative gaps, which no
    stack may have. They are reported failed (status 5, NaN gains) and the others are simulated."""
    mc = {"sample": "montecarlo", "samples": 8, "seed": 1, "chunk": 8,
          "axis": [{"key": "stack.gaps", "distribution": "normal", "std": "0.5 mm"}]}
    doc = BASE | {"stack": {"masses": [1.0, 0.3, 0.1], "gaps": 0}, "sweep": mc}
    path = tmp_path / "mc.toml"
    path.write_text(tomli_w.dumps(doc))
    result = sweep(path, tmp_path / "mc.zarr")
    ds = result.dataset().load()  # `SweepResult.dataset`: the store opened as the docs say
    gaps = ds["stack.gaps"].values
    rng = np.random.default_rng(1)
    np.testing.assert_allclose(gaps, 0.5e-3 * rng.standard_normal(8), rtol=1e-15)  # numpy's own draw
    bad = gaps < 0
    assert bad.any() and (~bad).any()
    assert np.all(ds.status.values[bad] == hc.Status.FAILED) and np.all(np.isnan(ds.top_velocity_gain.values[bad]))
    assert np.all(ds.status.values[~bad] == hc.Status.COMPLETE) and np.all(ds.top_velocity_gain.values[~bad] > 1)
    # the summary counts them apart from solver failures (a review: they read as "failed 23")
    from hertz_chain.sweeps import UNRUN

    assert result.status_counts == {"complete": int((~bad).sum()), UNRUN: int(bad.sum())}


def test_an_axis_a_law_cannot_take_is_refused_before_any_store(tmp_path, capsys):
    doc = BASE | {"contact": {"law": "hertz", "stiffness": "1e9 N/m^1.5"},
                  "sweep": {"axis": [{"key": "contact.restitution", "values": [0.5]}]}}
    path = tmp_path / "h.toml"
    path.write_text(tomli_w.dumps(doc))
    with pytest.raises(SystemExit) as exc:
        main(["sweep", str(path), "--output", str(tmp_path / "h.zarr")])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and f"{path}: sweep.axis: contact.restitution" in err and "elastic" in err
    assert not (tmp_path / "h.zarr").exists()


def test_pulse_variables_of_a_sphere_on_a_hertz_ground_against_johnson(tmp_path):
    """One 0.1 kg mass on an elastic Hertz ground, no gravity, swept over the stiffness and the drop
    speed: Johnson's closed forms (Contact Mechanics, 1985, §11.4): F_max = k d^1.5 with
    d = (5 m V^2 / (4 k))^(2/5); the velocity change 2V (e = 1); the equivalent half-sine pi 2V / (2 a).
    The peaks are the solver's step samples: low, by at most 1e-3 at rtol 1e-10 (measured ~2e-4). With
    `durations = true`, the duration between the force's 10 % points from the energy integral
    (d'^2 = V^2 (1 - (d/d_max)^(5/2)), F = k d^1.5: D_10 = 2 (d_max/V) int_{0.1^(2/3)}^1 du/sqrt(1 - u^2.5),
    by scipy's quad), and the 10-90 % rise time (the same integral from 0.1^(2/3) to 0.9^(2/3)), to the
    linear interpolation between steps at those points."""
    doc = {"drop": {"impact_velocity": "1 m/s", "gravity": 0}, "stack": {"masses": ["0.1 kg"]},
           "contact": {"law": "hertz", "stiffness": "1e9 N/m^1.5"},
           "sweep": {"durations": True,
                     "axis": [{"key": "contact.stiffness", "values": ["1e8 N/m^1.5", "1e10 N/m^1.5"]},
                              {"key": "drop.impact_velocity", "values": ["0.5 m/s", "2 m/s"]}]}}
    path = tmp_path / "one.toml"
    path.write_text(tomli_w.dumps(doc))
    ds = _open(sweep(path, tmp_path / "one.zarr").path)
    m, g0 = 0.1, 9.80665
    for i, k in enumerate([1e8, 1e10]):
        for j, v in enumerate([0.5, 2.0]):
            f = k * (5 * m * v * v / (4 * k)) ** 0.6
            got = float(ds.peak_force[i, j, 0])
            assert f * (1 - 1e-3) < got <= f * (1 + 1e-9)
            assert float(ds.top_peak_g[i, j]) == pytest.approx(got / m / g0, rel=1e-14)
            assert float(ds.top_delta_v[i, j]) == pytest.approx(2 * v, rel=1e-8)
            assert float(ds.top_equivalent_half_sine[i, j]) == pytest.approx(np.pi * v * m / f, rel=1e-3)
            d_max = (5 * m * v * v / (4 * k)) ** 0.4
            d10 = 2 * d_max / v * quad(lambda u: 1 / np.sqrt(1 - u**2.5), 0.1 ** (2 / 3), 1, limit=200)[0]
            assert float(ds.top_duration_10[i, j]) == pytest.approx(d10, rel=3e-4)  # measured 1.15e-4
            rise = d_max / v * quad(lambda u: 1 / np.sqrt(1 - u**2.5), 0.1 ** (2 / 3), 0.9 ** (2 / 3))[0]
            assert float(ds.top_rise_time[i, j]) == pytest.approx(rise, rel=6e-4)  # measured 2.2e-4
    assert ds.top_duration_10.attrs["units"] == "s"
    assert ds.peak_force.dims == ("contact.stiffness", "drop.impact_velocity", "interface")
    assert ds.peak_force.attrs["units"] == "N" and ds.top_delta_v.attrs["units"] == "m s-1"


def test_restitution_per_interface_is_the_calibrated_e(tmp_path):
    """Two masses, 1 cm gaps, Tsuji contacts calibrated to e = 0.8 (speed-independent, exact to ~1e-11):
    one contact per interface, so each interface's separation over approach speed is 0.8 (paper Eq 2).
    Without gravity to 1e-7; under gravity (the default) the mass-mass interface still to 1e-7 (both
    bodies fall alike: their relative speed is unchanged in free flight) and the ground interface to
    the change of mass 1's speed by gravity within the step around its impact and release (bound
    1e-3, i.e. g h / V for a step h ~ 0.1 ms)."""
    for gravity, tol_ground in ((0.0, 1e-7), (9.80665, 1e-3)):
        doc = {"drop": {"impact_velocity": "1 m/s", "gravity": gravity},
               "stack": {"masses": ["1 kg", "0.3 kg"], "gaps": "1 cm"},
               "contact": {"law": "tsuji", "stiffness": "1e9 N/m^1.5", "restitution": 0.8},
               "solver": {"until": "launch"},
               "sweep": {"axis": [{"key": "contact.stiffness", "values": ["1e8 N/m^1.5", "1e9 N/m^1.5"]}]}}
        path = tmp_path / f"e{gravity:g}.toml"
        path.write_text(tomli_w.dumps(doc))
        ds = _open(sweep(path, tmp_path / f"e{gravity:g}.zarr").path)
        assert ds.restitution.dims == ("contact.stiffness", "interface")
        np.testing.assert_allclose(ds.restitution[:, 1], 0.8, rtol=1e-7)
        np.testing.assert_allclose(ds.restitution[:, 0], 0.8, rtol=tol_ground)


def test_a_thornton_sphere_swept_over_speed_and_stiffness_meets_thorntons_closed_form(tmp_path):
    """An elastic-perfectly plastic sphere (Thornton 1997) on a rigid flat, no gravity, swept over the drop
    speed and the stiffness at a fixed limiting pressure p_y = 1 GPa: the measured restitution equals
    Thornton's closed form e(V_y/V) with Johnson's V_y = sqrt(4 k delta_y^{5/2} / (5 m)),
    delta_y = R (pi p_y / (2 E*))^2, E* = 3k / (4 sqrt R) (docs/references.md, "Elastic-plastic contact")."""
    m, r, p_y = 0.01, 5e-3, 1e9
    doc = {"drop": {"impact_velocity": "1 m/s", "gravity": 0},
           "stack": {"masses": [f"{m} kg"], "radius": f"{r} m"},
           "contact": {"law": "thornton", "stiffness": "1e10 N/m^1.5", "yield_pressure": f"{p_y} Pa"},
           "solver": {"rtol": 1e-11, "atol": 1e-11},
           "sweep": {"axis": [{"key": "contact.stiffness", "values": ["5e9 N/m^1.5", "2e10 N/m^1.5"]},
                              {"key": "drop.impact_velocity", "values": ["0.3 m/s", "3 m/s"]}]}}
    path = tmp_path / "thornton.toml"
    path.write_text(tomli_w.dumps(doc))
    ds = _open(sweep(path, tmp_path / "thornton.zarr").path)
    for i, k in enumerate([5e9, 2e10]):
        e_star = 3 * k / (4 * np.sqrt(r))
        d_y = r * (np.pi * p_y / (2 * e_star)) ** 2
        v_y = np.sqrt(0.8 * k * d_y**2.5 / m)
        for j, v in enumerate([0.3, 3.0]):
            x = v_y / v
            e = np.sqrt(6 * np.sqrt(3) / 5) * np.sqrt(1 - x**2 / 6) * (x / (x + 2 * np.sqrt(6 / 5 - x**2 / 5))) ** 0.25
            assert x < 1  # every design yields
            # 1e-6, as through simulate (tests/test_plastic.py): the kink of the force at the peak costs
            # accuracy (measured up to 1.6e-7)
            assert float(ds.restitution[i, j, 0]) == pytest.approx(e, rel=1e-6)
            assert int(ds.status[i, j]) == 0
    assert np.all(np.isnan(ds.rigid_gain))  # a plastic law has no nominal restitution for Eq 19
    np.testing.assert_allclose(ds.rigid_gain_measured, ds.restitution[..., 0], rtol=1e-12)  # Eq 19 for n = 1: G = e


def test_overlap_fraction_and_regime_per_design_match_the_report(tmp_path):
    """Three masses without gravity: 0.4 mm gaps (the contacts overlap wholly), 0.7 mm (a little) and 1 cm
    (sequential): the sweep's step-resolved overlap fraction against `analysis.independence` of the same
    designs simulated and analysed on their own (dense, refined episodes), within 0.01, and the same
    regime. (Under gravity mass 1 rests on the ground after its bounce: overlap 1 for any gap.)"""
    from hertz_chain.workflow import simulate_file

    gaps = ["0.4 mm", "0.7 mm", "1 cm"]
    doc = {"drop": {"impact_velocity": "1 m/s", "gravity": 0}, "stack": {"masses": [1.0, 0.3, 0.1], "gaps": "0 mm"},
           "contact": {"law": "tsuji", "stiffness": "1e9 N/m^1.5", "restitution": 0.8},
           "sweep": {"axis": [{"key": "stack.gaps", "values": gaps}]}}
    path = tmp_path / "regime.toml"
    path.write_text(tomli_w.dumps(doc))
    ds = _open(sweep(path, tmp_path / "regime.zarr").path)
    independence = []
    for i, gap in enumerate(gaps):
        one = copy.deepcopy(doc)
        del one["sweep"]
        one["stack"]["gaps"] = gap
        p1 = tmp_path / f"one{i}.toml"
        p1.write_text(tomli_w.dumps(one))
        report = simulate_file(p1)
        independence.append(report.independence)
        assert float(ds.overlap_fraction[i]) == pytest.approx(report.independence, abs=0.01)
        assert int(ds.regime[i]) == (0 if report.regime == "independent" else 1)
    assert independence[0] == pytest.approx(1.0) and 0.01 < independence[1] < 0.1 and independence[2] == 0.0
    assert [int(r) for r in ds.regime] == [1, 1, 0]
    assert np.all(np.isnan(ds.top_duration_10))  # only with `durations = true`


def test_rigid_gain_with_the_measured_restitutions_is_the_gain_of_independent_collisions(tmp_path):
    """Wide gaps (1 cm), no gravity: the collisions are independent, so paper Eq 19 with each interface's
    measured restitution gives the simulated top gain (the rigid theory is exact there); Hunt-Crossley
    contacts, whose e depends on the impact speed, so the nominal-e gain (Eq 19 with the calibration e)
    does not."""
    doc = {"drop": {"impact_velocity": "1 m/s", "gravity": 0}, "stack": {"masses": [1.0, 0.3, 0.1], "gaps": "1 cm"},
           "contact": {"law": "hunt-crossley", "stiffness": "1e9 N/m^1.5", "restitution": 0.8,
                       "calibration_velocity": "1 m/s"},
           "solver": {"until": "launch", "rtol": 1e-11, "atol": 1e-11},
           "sweep": {"axis": [{"key": "drop.impact_velocity", "values": ["0.5 m/s", "2 m/s"]}]}}
    path = tmp_path / "rigid.toml"
    path.write_text(tomli_w.dumps(doc))
    ds = _open(sweep(path, tmp_path / "rigid.zarr").path)
    np.testing.assert_allclose(ds.rigid_gain_measured, ds.top_velocity_gain, rtol=1e-7)
    # the event-driven cascade with the same restitutions meets Eq 19 there (independent collisions)
    np.testing.assert_allclose(ds.rigid_gain_event_driven, ds.rigid_gain_measured, rtol=1e-12)
    assert np.all(np.abs(ds.rigid_deficit) > 1e-3)  # the nominal e is not the e of these impacts
    assert ds.rigid_gain_measured.attrs["units"] == "1"


def test_rigid_deficit_is_nan_where_eq19_leaves_the_top_falling():
    """A top mass 20 times the bottom one: Eq 19 (two independent collisions, ground then pair) gives the
    top ((1 + e) e m1 - (m2 - e m1)) / (m1 + m2) = -0.8457 of the drop speed (e = 0.8), downwards; a
    deficit against a negative gain means nothing, so the store's `rigid_deficit` (`sweeps.rigid_deficit`,
    what `_evaluate` writes) is NaN there (it was gain / -0.85 - 1); a positive one is gain / rigid - 1."""
    from hertz_chain.rigid import stack_gain
    from hertz_chain.sweeps import rigid_deficit

    m1, m2, e = 1.0, 20.0, 0.8
    rigid = stack_gain(np.array([[m1, m2], [1.0, 0.5]]), np.full((2, 2), e))
    np.testing.assert_allclose(rigid[0], ((1 + e) * e * m1 - (m2 - e * m1)) / (m1 + m2), rtol=1e-12)
    out = rigid_deficit([0.3, 1.2], rigid)
    assert np.isnan(out[0]) and out[1] == pytest.approx(1.2 / rigid[1] - 1.0, rel=1e-15)
    assert np.isnan(rigid_deficit([1.0], [np.nan])[0]) and np.isnan(rigid_deficit([1.0], [0.0])[0])


def test_time_estimate_before_the_run_from_the_last_sweep_of_the_same_structure(tmp_path, monkeypatch):
    # Issue 20: "before anything runs, the command prints the number of designs and an estimate of time".
    # The first sweep of a structure has nothing to time it by (it says so; an estimate follows its first
    # chunk); it records its steady rate (the chunks after the first, which compiles) in the cache, and the
    # next sweep of the same structure prints `designs / rate` before it runs.
    from typer.testing import CliRunner

    from hertz_chain.cli import app
    from hertz_chain.sweeps import check, recorded_rate

    monkeypatch.setenv("HERTZ_CHAIN_CACHE_DIR", str(tmp_path / "cache"))
    path = _file(tmp_path, GRID)
    plan, _ = check(path, tmp_path / "a.zarr")
    assert recorded_rate(plan) is None
    res = CliRunner().invoke(app, ["sweep", str(path), "--output", str(tmp_path / "a.zarr")])
    assert res.exit_code == 0, res.output
    assert "no earlier sweep of this structure here" in res.stderr
    # after the first chunk an upper bound (it compiles), after the second its steady rate for the last one
    assert "first chunk in" in res.stderr and "second chunk in" in res.stderr and "for the other 1" in res.stderr
    rate = recorded_rate(plan)
    assert rate is not None and np.isfinite(rate) and rate > 0
    res = CliRunner().invoke(app, ["sweep", str(path), "--output", str(tmp_path / "b.zarr")])
    assert res.exit_code == 0, res.output
    assert f"about {6 / rate:.2g} s for 6 designs at {rate:,.0f} designs/s" in res.stderr
    assert "first chunk in" not in res.stderr  # no second, compile-laden estimate after the first chunk
    res = CliRunner().invoke(app, ["sweep", str(path), "--output", str(tmp_path / "b.zarr"), "--resume"])
    assert res.exit_code == 0 and "every chunk is done already" in res.stderr and "0 chunks computed" in res.stdout
    # another structure (four masses) has no record
    other = tmp_path / "other.toml"
    other.write_text(tomli_w.dumps(BASE | {"stack": BASE["stack"] | {"masses": [1.0, 0.5, 0.3, 0.1]},
                                           "sweep": GRID}), encoding="utf-8")
    assert recorded_rate(check(other, tmp_path / "c.zarr")[0]) is None


def test_arguments_and_outputs_are_refused_before_any_store(tmp_path, capsys, monkeypatch):
    """One line naming the argument, before anything is made: `workers` outside 1..1024 in Python (0 used
    to hang), a scheduler that does not answer (it used to leave an empty store and a traceback), an output
    folder that is missing or not writable, a name longer than the file system allows; `plot` with the same
    key for --x and --y. A comment added to the stack file resumes its store (the store's identity is the
    parsed file)."""
    import hertz_chain.sweeps as sweeps
    from hertz_chain.errors import OutputPathError, ParameterError

    path = _file(tmp_path, GRID)
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ParameterError, match="workers"):
            sweep(path, tmp_path / "w.zarr", workers=bad)
    monkeypatch.setattr(sweeps, "SCHEDULER_TIMEOUT", "1s")
    with pytest.raises(ParameterError, match="scheduler = 'tcp://127.0.0.1:1'.*none answered"):
        sweep(path, tmp_path / "s.zarr", scheduler="tcp://127.0.0.1:1")
    assert not (tmp_path / "w.zarr").exists() and not (tmp_path / "s.zarr").exists()
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    targets = [(tmp_path / "no" / "o.zarr", "does not exist"), (tmp_path / ("x" * 300 + ".zarr"), "bytes")]
    if not os.access(locked, os.W_OK):  # (root writes anywhere)
        targets.append((locked / "o.zarr", "not writable"))
    for target, word in targets:
        with pytest.raises(OutputPathError, match=word):
            sweep(path, target)
    out = sweep(path, tmp_path / "o.zarr").path
    path.write_text("# a note\n" + path.read_text(), encoding="utf-8")
    again = sweep(path, out)
    assert (again.computed, again.skipped) == (0, 3)
    with pytest.raises(SystemExit) as exc:
        main(["plot", str(out), "--x", "stack.gaps", "--y", "stack.gaps", "--output", str(tmp_path / "p.png")])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.startswith("hertz-chain: error: --y") and err.count("\n") == 1


def test_a_stiffness_axis_takes_the_units_of_the_laws_it_sets(tmp_path, capsys):
    """`contact.stiffness` without an index sets every interface: where their laws take the stiffness in
    different units (Tsuji N/m^1.5, Kelvin-Voigt N/m), one line and exit 2 (the Kelvin-Voigt pad was set
    to the Hertzian values); a power law's stiffness is in N/m^p, p its exponent (it failed to parse),
    and its coordinate's CF units say so (the store's `units`, `sweeps._units`)."""
    mixed = BASE | {"contact": BASE["contact"] | {"interface": [
        {"index": 2, "law": "kelvin-voigt", "stiffness": "1e7 N/m", "restitution": 0.8}]},
        "sweep": {"axis": [{"key": "contact.stiffness", "values": ["1e9 N/m^1.5", "2e9 N/m^1.5"]}]}}
    path = tmp_path / "mixed.toml"
    path.write_text(tomli_w.dumps(mixed), encoding="utf-8")
    with pytest.raises(SystemExit) as exc:
        main(["sweep", str(path), "--output", str(tmp_path / "m.zarr")])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and "different units" in err and "kelvin-voigt at 2" in err
    power = {"drop": BASE["drop"], "stack": {"masses": [1.0, 0.3], "gaps": "1 mm"},
             "contact": {"law": "power", "exponent": 2, "alpha": "0.2 s/m", "stiffness": "1e10 N/m^2"},
             "sweep": {"axis": [{"key": "contact.stiffness", "values": ["1e10 N/m^2", "2e4 N/mm^2"]}]}}
    path = tmp_path / "power.toml"
    path.write_text(tomli_w.dumps(power), encoding="utf-8")
    plan, _ = check(path, tmp_path / "p.zarr")  # the spec and the store's layout; no solve
    (axis,) = plan.sweep.axes
    assert axis.values == pytest.approx((1e10, 2e10), rel=1e-15)  # 2e4 N/mm^2 = 2e10 N/m^2
    from hertz_chain.sweeps import _units

    assert _units(plan.spec, axis) == "N m-2"


def test_a_store_is_resumed_in_its_own_chunk_layout(tmp_path):
    """A store laid out in other chunks than the file gives now (the default `chunk` changed from 1024 to
    2048 on 2026-11-27, which changes nothing in the file) is resumed in its own layout: every one of its
    chunks computed once and marked, with the numbers of a fresh run (by rounding: other pieces)."""
    from hertz_chain import sweeps

    path = _file(tmp_path, {k: v for k, v in GRID.items() if k != "chunk"})
    text = path.read_text()
    plan = sweeps._design_map(text, str(path))[0]
    assert plan.n_chunks == 1  # the default chunk holds the whole grid
    old = tmp_path / "old.zarr"
    sweeps._create_store(old, sweeps._with_rows(plan, 1), text, str(path))  # as an older default laid it out
    result = sweep(path, old)
    assert (result.chunks, result.computed) == (3, 3)
    ds = _open(old)
    assert ds.chunk_done.values.tolist() == [1, 1, 1]
    assert (sweep(path, old).computed, sweep(path, old).skipped) == (0, 3)  # resumed again: nothing to do
    assert sweep(path, tmp_path / "new.zarr").chunks == 1
    fresh = _open(tmp_path / "new.zarr")
    np.testing.assert_allclose(ds.top_velocity_gain, fresh.top_velocity_gain, rtol=1e-8)
    np.testing.assert_array_equal(ds.status, fresh.status)


def test_plot_legends_and_titles_carry_the_axis_units():
    """`hertz-chain plot`'s legend and title values name their unit (the coordinate's `units`, as the axis
    labels do; a review: legends read "stack.gaps = 1e-06"); a dimensionless one (units "1") none."""
    from hertz_chain.plot import _label, _unit

    ds = xr.Dataset(coords={"stack.gaps": ("g", [0.0, 1e-6], {"units": "m"}),
                            "contact.restitution": ("e", [0.5], {"units": "1"})})
    assert _unit(ds, "stack.gaps") == " m" and _unit(ds, "contact.restitution") == ""
    assert _label(ds, "stack.gaps") == "stack.gaps (m)" and _unit(ds, "missing") == ""


def test_a_restitution_that_designs_the_masses_cannot_vary_in_a_sweep(tmp_path, capsys):
    """A review: a restitution axis of every interface on an MET design file (`[stack.design]` without its
    own restitution) kept the masses designed for the file's e, while `simulate --set
    contact.restitution=...` redesigns them (Eq 25; examples/regime_map.toml's stack as an MET design, 1 cm
    gaps, e = 0.5: a gain of 0.32 against 0.98). Refused in one line. One interface's e (index) leaves the
    design as it is in simulate too, and with stack.design.restitution given the masses are fixed: both
    accepted (a second review: the index was refused too)."""
    doc = {"drop": {"impact_velocity": "1 m/s", "gravity": 0}, "stack": {"gaps": "1 cm", "design": {
        "kind": "met", "n": 3, "bottom_mass": "1 kg"}},
        "contact": {"law": "tsuji", "stiffness": "1e9 N/m^1.5", "restitution": 0.8},
        "sweep": {"sample": "lhs", "samples": 2, "axis": [{"key": "contact.restitution", "bounds": [0.5, 0.9]}]}}
    path = tmp_path / "met.toml"
    path.write_text(tomli_w.dumps(doc), encoding="utf-8")
    with pytest.raises(SystemExit) as exc:
        main(["sweep", str(path), "--output", str(tmp_path / "o.zarr")])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1
    assert "sweep.axis[0].key: contact.restitution cannot vary here" in err
    assert "an MET design's masses follow from e (Eq 25)" in err and not (tmp_path / "o.zarr").exists()
    from hertz_chain.keys import check_design_follows
    from hertz_chain.stackfile import parse_stack

    check_design_follows(parse_stack(doc), "contact.restitution", 1, "x")  # one interface: accepted
    doc["stack"]["design"]["restitution"] = 0.8  # the design fixed: accepted
    check_design_follows(parse_stack(doc), "contact.restitution", None, "x")


def test_a_design_whose_top_is_never_struck_has_no_pulse_and_no_regime(tmp_path):
    """A review: a design stopped by t_max before the cascade reached the top read top_peak_g = 0 and
    regime 0 ("independent"), so that filtering on the regime counted it. 1 m/s onto the ground, 1 cm gaps,
    t_max = 2 ms: mass 1 rebounds at most at 1 m/s, so the first gap (1 cm, closing at <= 2 m/s) closes
    after >= 5 ms and the top is never struck: status incomplete (2), top_peak_g NaN (as the report's top
    pulse is None), regime -1 (undetermined); the touching design beside it is complete with a finite peak."""
    doc = copy.deepcopy(BASE)
    doc["solver"]["t_max"] = "2 ms"
    path = tmp_path / "s.toml"
    path.write_text(tomli_w.dumps(doc | {"sweep": {"axis": [{"key": "stack.gaps", "values": ["0 mm", "1 cm"]}]}}),
                    encoding="utf-8")
    d = _open(sweep(path, tmp_path / "o.zarr").path)
    assert d.status.values.tolist() == [0, 2]
    assert np.isfinite(d.top_peak_g.values[0]) and d.top_peak_g.values[0] > 0 and np.isnan(d.top_peak_g.values[1])
    assert d.regime.values[0] in (0, 1) and d.regime.values[1] == -1
    assert d.regime.attrs["flag_meanings"] == "undetermined independent overlapping"
