"""Chain end conditions (issue 21): an end force `F0` on the top mass, a rigid wall beyond it, and the
precompressed chain in static equilibrium that they make.

References:

- Hertz's law `F = k delta^{3/2}` carrying the end force and the weight above: the static overlaps
  `delta_j = ((F0 + g sum_{i > j} m_i)/k)^{2/3}` (closed form);
- the small oscillation of one bead pressed onto a wall by `F0`: the linearised contact stiffness
  `k_1 = dF/d delta = (3/2) k delta_0^{1/2}`, so the period is `2 pi sqrt(m/k_1)` (the frequency's
  correction is second order in the amplitude over `delta_0`, 1e-3 here);
- an independent scipy integration (`solve_ivp`, DOP853, rtol 1e-12), written here, of a precompressed
  Hertz chain under gravity whose top bead is struck: Newton's equations with the wall, the contacts,
  gravity and the end force, from the closed-form equilibrium above; the same with a far wall (an elastic
  Hertz contact `k_w <x_n - x_w>^{3/2}`) carrying `F0` instead of a dead load;
- one bead bouncing between the ground and a far wall without gravity: its period is the two flights
  `2 gap / v` plus the two Hertz contact times `3.21807 (m/k)^{2/5} v^{-1/5}` (Hertz 1882; docs/references.md,
  "Hertz single impact"), and a flat wall's stiffness is `(4/3) E* sqrt(R)` (Johnson 1985, Eq. 4.23).
"""

import numpy as np
import pytest
import tomli_w
from scipy.integrate import solve_ivp

import hertz_chain as hc
from hertz_chain.errors import ParameterError, StackFileError

G = hc.G0
TOL = hc.Tolerances(rtol=1e-11, atol=1e-11)


def _file(tmp_path, doc, name="chain.toml"):
    p = tmp_path / name
    p.write_text(tomli_w.dumps(doc))
    return p


def _chain_doc(n=8, f0="2 N", striker="-0.05 m/s", t_max="0.4 ms"):
    """A vertical chain of n equal beads on a wall, pressed by `f0` on the top bead, gravity on (the
    default), the top bead struck downward at `striker` (the rest start at rest)."""
    return {"drop": {}, "stack": {"masses": ["4.5 g"] * n, "gaps": 0, "end_force": f0,
                                  "velocities": [0] * (n - 1) + [striker]},
            "contact": {"law": "hertz", "stiffness": "1.2e10 N/m^1.5"},
            "solver": {"until": "t_max", "t_max": t_max, "rtol": 1e-11, "atol": 1e-11}}


def test_resting_chain_carries_end_force_and_weight_closed_form():
    m = np.array([0.3, 0.2, 0.1, 0.05])
    k, f0 = 2e9, 7.0
    stack = hc.Stack(m, hc.Hertz(k), gravity=G, end_force=f0)
    x = np.asarray(hc.resting(stack).positions)
    load = f0 + G * np.array([m.sum(), m[1:].sum(), m[2:].sum(), m[3:].sum()])
    np.testing.assert_allclose(x, -np.cumsum((load / k) ** (2 / 3)), rtol=1e-13)
    # Newton: no net force on any mass (the end force included)
    a = np.asarray(stack.vector_field(0.0, hc.resting(stack).flat())[4:8])
    np.testing.assert_allclose(a, 0.0, atol=1e-12 * G)


def test_one_bead_pressed_on_a_wall_oscillates_at_the_linearised_hertz_frequency():
    m, k, f0 = 0.01, 1e9, 5.0
    d0 = (f0 / k) ** (2 / 3)
    k1 = 1.5 * k * np.sqrt(d0)
    omega = np.sqrt(k1 / m)
    v0 = 1e-3 * d0 * omega  # amplitude 1e-3 of the static overlap
    stack = hc.Stack([m], hc.Hertz(k), gravity=0.0, end_force=f0)
    rest = hc.resting(stack)
    period = 2 * np.pi / omega
    ts = np.linspace(0.0, 3 * period, 3001)
    sol = hc.simulate(stack, hc.State(rest.positions, [-v0]), ts=ts, t_max=3 * period, until="t_max",
                      tolerances=TOL)
    assert sol.status is hc.Status.COMPLETE  # a held chain's run ends at t_max by design
    v = np.asarray(sol.grid.velocities)[:, 0]
    up = np.nonzero((v[:-1] < 0) & (v[1:] >= 0))[0]  # upward zero crossings, linear between samples
    t_up = ts[up] - v[up] * (ts[up + 1] - ts[up]) / (v[up + 1] - v[up])
    assert len(t_up) == 3
    assert np.diff(t_up) == pytest.approx(period, rel=1e-5)
    assert abs(sol.energy_error) < 1e-9


def _scipy_chain(m, k, f0, g, v_top, t_eval, k_wall=None, positions=False):
    """Independent reference: the precompressed Hertz chain on a wall, written out (positions upward,
    x_1 = -delta_0 on the wall), from the closed-form equilibrium, top bead struck at `v_top`. With `k_wall`
    a far wall at `x_n - (F0/k_wall)^{2/3}` carries F0 instead of a dead load."""
    n = len(m)
    load = f0 + g * np.cumsum(m[::-1])[::-1]
    delta = (load / k) ** (2 / 3)
    x0 = -np.cumsum(delta)
    v_init = np.zeros(n)
    v_init[-1] = v_top
    x_wall = None if k_wall is None else x0[-1] - (f0 / k_wall) ** (2 / 3)

    def rhs(_, y):
        x, v = y[:n], y[n:]
        d = np.concatenate([[-x[0]], x[:-1] - x[1:]])
        f = k * np.maximum(d, 0.0) ** 1.5
        top = f0 if k_wall is None else k_wall * max(x[-1] - x_wall, 0.0) ** 1.5
        above = np.concatenate([f[1:], [top]])
        return np.concatenate([v, (f - above) / m - g])

    out = solve_ivp(rhs, (0.0, t_eval[-1]), np.concatenate([x0, v_init]), method="DOP853", rtol=1e-12,
                    atol=1e-20, t_eval=t_eval)
    return out.y[:n].T if positions else out.y[n:].T


def test_precompressed_chain_from_a_stack_file_matches_an_independent_scipy_solve(tmp_path):
    n, m, k, f0, v_top = 8, 4.5e-3, 1.2e10, 2.0, -0.05
    built = hc.build(hc.load_stack_file(_file(tmp_path, _chain_doc(n))))
    assert built.stack.n == n and float(built.stack.end_force) == f0 and float(built.stack.gravity) == G
    ts = np.linspace(0.0, 4e-4, 41)
    sol = hc.simulate(built.stack, built.state, ts=ts, **built.simulate_options)
    assert sol.status is hc.Status.COMPLETE
    ref = _scipy_chain(np.full(n, m), k, f0, G, v_top, ts)
    np.testing.assert_allclose(np.asarray(sol.grid.velocities), ref, rtol=0, atol=1e-8 * abs(v_top))
    assert abs(sol.energy_error) < 1e-8  # the end force's work F0 x_n is in the audit
    # a held chain's "launch" velocities are its velocities at t_max (every mass, the top one too)
    np.testing.assert_allclose(np.asarray(sol.launch_velocities), ref[-1], rtol=0, atol=1e-8 * abs(v_top))
    report = hc.analyse(sol)
    assert np.all(np.isnan(report.restitution)) and report.rigid.event_driven_gain is None
    assert not any("restitution =" in note for note in report.rigid.notes)


def test_end_force_bad_input_is_one_line(tmp_path):
    doc = _chain_doc()
    doc["solver"] = {}
    with pytest.raises(StackFileError, match=r"solver\.until.*end_force.*t_max"):
        hc.load_stack_file(_file(tmp_path, doc))
    doc = _chain_doc()
    doc["drop"] = {"ground": False}
    with pytest.raises(StackFileError, match=r"stack\.end_force.*drop\.ground = true"):
        hc.load_stack_file(_file(tmp_path, doc, "b.toml"))
    # preload without the ground: no static equilibrium (a review: it ran, the chain flying apart)
    doc = _chain_doc()
    doc["drop"] = {"ground": False, "gravity": "9.8 m/s^2"}
    doc["stack"].pop("end_force")
    doc["stack"]["preload"] = True
    with pytest.raises(StackFileError, match=r"stack\.preload: true needs drop\.ground = true"):
        hc.load_stack_file(_file(tmp_path, doc, "p.toml"))
    doc = _chain_doc(f0="-1 N")
    with pytest.raises(StackFileError, match=r"stack\.end_force"):
        hc.load_stack_file(_file(tmp_path, doc, "c.toml"))
    doc = _chain_doc(f0="2 m")
    with pytest.raises(StackFileError, match=r"stack\.end_force.*force"):
        hc.load_stack_file(_file(tmp_path, doc, "d.toml"))
    with pytest.raises(ParameterError, match="end_force"):
        hc.Stack([1.0, 1.0], hc.Hertz(1e9), ground=False, end_force=1.0)
    with pytest.raises(ParameterError, match="end_force"):
        hc.Stack([1.0], hc.Hertz(1e9), end_force=-1.0)
    stack = hc.Stack([1.0], hc.Hertz(1e9), end_force=1.0)
    with pytest.raises(ParameterError, match="until.*t_max"):
        hc.simulate(stack, hc.resting(stack))


def test_cli_simulates_a_precompressed_chain(tmp_path):
    from typer.testing import CliRunner
    import json
    from hertz_chain.cli import app

    path = _file(tmp_path, _chain_doc())  # the structure of the scipy test above: its compiled solver is reused
    res = CliRunner().invoke(app, ["simulate", str(path), "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["status"] == "complete"


def test_chain_between_two_walls_from_a_stack_file_matches_scipy(tmp_path):
    n, m, k, k_w, f0, v_top = 8, 4.5e-3, 1.2e10, 1.7e10, 2.0, -0.05
    doc = _chain_doc(n)
    doc["wall"] = {"stiffness": f"{k_w} N/m^1.5"}
    built = hc.build(hc.load_stack_file(_file(tmp_path, doc)))
    assert built.stack.wall and float(built.stack.end_force) == 0.0  # the wall carries F0, no dead load
    ts = np.linspace(0.0, 4e-4, 41)
    sol = hc.simulate(built.stack, built.state, ts=ts, **built.simulate_options)
    assert sol.status is hc.Status.COMPLETE
    ref = _scipy_chain(np.full(n, m), k, f0, G, v_top, ts, k_wall=k_w)
    np.testing.assert_allclose(np.asarray(sol.grid.velocities), ref, rtol=0, atol=1e-8 * abs(v_top))
    assert abs(sol.energy_error) < 1e-8  # the wall's elastic energy is in the audit
    # at rest the wall's force is F0 (Newton on the top bead, the end force gone)
    rest = hc.State(built.state.positions, np.zeros(n))
    assert float(built.stack.wall_force(rest.positions)) == pytest.approx(f0, rel=1e-12)
    # the report's largest wall force is the scipy trajectory's (at the steps: within the sampling)
    report = hc.analyse(sol)
    t_fine = np.linspace(0.0, 4e-4, 4001)
    x_ref = _scipy_chain(np.full(n, m), k, f0, G, v_top, t_fine, k_wall=k_w, positions=True)
    x_wall = float(built.stack.wall_position)
    f_ref = k_w * np.maximum(x_ref[:, -1] - x_wall, 0.0) ** 1.5
    assert report.wall_peak_force == pytest.approx(f_ref.max(), rel=1e-4)  # refined between steps
    assert report.wall_peak_force > 2 * f0  # the wave reached the wall
    # the text report and the CSV carry the wall force too (the same values as the JSON / the positions give)
    from hertz_chain.report import summary_table, write_output

    assert f"far wall: peak force {report.wall_peak_force:,.6g} N" in summary_table(report)
    write_output(report, tmp_path / "wall.csv")
    lines = (tmp_path / "wall.csv").read_text().splitlines()
    header = next(ln for ln in lines if not ln.startswith("#"))  # after the `#` provenance lines
    rows = np.loadtxt(tmp_path / "wall.csv", delimiter=",", comments="#", skiprows=lines.index(header) + 1)
    assert header.endswith(",wall_force_N") and rows.shape[1] == 5
    assert 2 * f0 < rows[:, 4].max() <= report.wall_peak_force * (1 + 1e-12)  # sampled on the 10 us grid
    assert rows[0, 4] == pytest.approx(f0, rel=1e-9)  # at rest the wall carries the end force
    # the figure's contact-force panel draws it too (kN): F0 at rest, the scipy peak within the step sampling
    from hertz_chain.plot import report_figure

    fig = report_figure(report)
    (line,) = [ln for ln in fig.axes[1].get_lines() if ln.get_label() == f"{n}–wall"]
    y = np.asarray(line.get_ydata())
    assert y[0] == pytest.approx(f0 / 1e3, rel=1e-9)
    assert 2 * f0 / 1e3 < y.max() <= report.wall_peak_force / 1e3 * (1 + 1e-12)
    assert fig.axes[1].get_xlim()[1] >= 1e3 * float(sol.t_final)  # a held chain: its whole record is drawn
    # a held chain has no launch: the text and the figure say what its "gain" is, and no rigid line or
    # energy transfer to a launched top mass is printed
    text = summary_table(report)
    assert "top-mass velocity at t_max over the striker speed" in text and "striker speed 0.05 m/s" in text
    assert "rigid, Eq 19" not in text and "energy transfer" not in text and "G_n = V_n / v_ff" not in text
    assert "rigid theory assumes" not in text  # the regime line cites no rigid cascade either
    assert fig._suptitle.get_text().startswith("Held chain: top velocity at t_max / striker speed")


def test_one_bead_bounces_between_the_ground_and_a_wall_with_hertz_contact_times(tmp_path):
    m, r, v, gap = 4e-3, 5e-3, 0.7, 1e-3
    doc = {"drop": {"gravity": 0},
           "materials": {"steel": {"youngs_modulus": "200 GPa", "poisson_ratio": 0.3}},
           "stack": {"masses": [f"{m} kg"], "velocities": [f"{v} m/s"], "material": "steel", "radius": f"{r} m"},
           "ground": {"material": "steel"}, "contact": {"law": "hertz"},
           "wall": {"material": "steel", "gap": f"{gap} m"},
           "solver": {"until": "t_max", "t_max": "10 ms", "rtol": 1e-12, "atol": 1e-12}}
    built = hc.build(hc.load_stack_file(_file(tmp_path, doc)))
    k = 4 / 3 * 200e9 / (2 * (1 - 0.3**2)) * np.sqrt(r)  # sphere on a flat of the same steel
    assert float(built.stack.wall_stiffness) == pytest.approx(k, rel=1e-14)
    assert float(built.stack.wall_position) == pytest.approx(gap, rel=1e-14)
    t_c = 3.21807 * (m / k) ** 0.4 * v**-0.2
    period = 2 * gap / v + 2 * t_c
    sol = hc.simulate(built.stack, built.state, ts=np.array([period, 2 * period]), t_max=2 * period,
                      until="t_max", tolerances=hc.Tolerances(rtol=1e-12, atol=1e-12))
    x, vel = np.asarray(sol.grid.positions)[:, 0], np.asarray(sol.grid.velocities)[:, 0]
    # back where it started, moving up at v; t_c's six published digits allow ~1e-6 t_c v of position
    np.testing.assert_allclose(x, 0.0, atol=1e-5 * t_c * v)
    np.testing.assert_allclose(vel, v, rtol=1e-9)


def test_wall_bad_input_is_one_line(tmp_path):
    base = _chain_doc()
    cases = [
        ({}, r"wall\.stiffness.*missing"),
        ({"material": "steel-52100"}, r"wall\.material.*stack\.material"),
        ({"stiffness": "1e10 N/m^1.5", "gap": "1 mm"}, r"wall\.gap.*end_force"),
        ({"stiffness": "1e10 N/m^1.5", "material": "steel-52100"}, r"wall\.material.*conflicts"),
        ({"stiffness": "-1 N/m^1.5"}, r"wall\.stiffness"),
        ({"stiffness": "1e10 N/m^1.5", "colour": "red"}, r"wall\.colour"),
    ]
    for i, (wall, pattern) in enumerate(cases):
        doc = dict(base, wall=wall)
        with pytest.raises(StackFileError, match=pattern):
            hc.load_stack_file(_file(tmp_path, doc, f"w{i}.toml"))
    doc = dict(base, wall={"stiffness": "1e10 N/m^1.5"})
    doc["stack"] = dict(doc["stack"], end_force=0)
    doc["solver"] = {}
    with pytest.raises(StackFileError, match=r"solver\.until.*\[wall\]"):
        hc.load_stack_file(_file(tmp_path, doc, "u.toml"))
    doc = dict(base, wall={"material": "unobtainium"})
    doc["stack"] = dict(doc["stack"], material="steel-52100", radius="5 mm")
    with pytest.raises(StackFileError, match=r"wall\.material: 'unobtainium' is unknown; the table's materials \(steel-52100"):
        hc.build(hc.load_stack_file(_file(tmp_path, doc, "m.toml")))
    with pytest.raises(ParameterError, match="wall_position"):
        hc.Stack([1.0], hc.Hertz(1e9), wall_stiffness=1e9)
    stack = hc.Stack([1.0], hc.Hertz(1e9), wall_stiffness=1e9, wall_position=0.1)
    with pytest.raises(ParameterError, match="until.*t_max"):
        hc.launch_velocity(stack, hc.at_impact(stack, 1.0))


def test_design_maps_refuse_held_chains_in_one_line(tmp_path):
    doc = _chain_doc()
    doc["sweep"] = {"axis": [{"key": "stack.masses", "index": [2], "values": ["4 g", "5 g"]}]}
    with pytest.raises(StackFileError, match=r"sweep.*held by stack\.end_force"):
        hc.sweep(_file(tmp_path, doc), tmp_path / "out.zarr")


def test_a_wall_without_the_ground_is_refused_in_one_line():
    """A review: `[wall]` with `drop.ground = false` ran, and the analysis called the chain held ("never flies
    apart") while its beads left the wall; a wall closes a chain between the ground and it, as
    `stack.end_force` needs the ground."""
    from hertz_chain.errors import StackFileError
    from hertz_chain.stackfile import parse_stack

    doc = {"drop": {"gravity": 0, "ground": False},
           "stack": {"masses": [0.01, 0.01, 0.01], "gaps": 0, "velocities": ["1 m/s", 0, 0]},
           "contact": {"law": "hertz", "stiffness": "1e9 N/m^1.5"},
           "wall": {"gap": 0, "stiffness": "1e9 N/m^1.5"}, "solver": {"until": "t_max", "t_max": "1 ms"}}
    with pytest.raises(StackFileError, match=r"^wall: needs drop.ground = true") as info:
        parse_stack(doc)
    assert "\n" not in str(info.value)
    with pytest.raises(hc.ParameterError, match=r"^wall_stiffness = .* a far wall only with the ground"):
        hc.Stack([0.01] * 3, hc.Hertz(1e9), ground=False, wall_stiffness=1e9, wall_position=0.1)



@pytest.mark.parametrize("extra", [{}, {"end_force": "20 N"}])
def test_contacts_still_loaded_at_t_max_end_there(tmp_path, extra):
    """A review: a preloaded stack at rest (and one held by an end force), run to t_max, reported a
    contact "ending" at 43,378 s (17,594 s), far past the 5 ms run: the end of a contact still closed at
    the run's end was extrapolated from its round-off drift (1e-9 m/s) as if the contact were flying apart.
    A run that stops at t_max (or at the top's launch) ends such contacts at t_final."""
    doc = {"drop": {"impact_velocity": 0}, "stack": {"masses": [8.4, 3.4683, 1.4320], "gaps": 0, "preload": True}
           | extra, "contact": {"law": "hertz", "stiffness": "1e9 N/m^1.5"},
           "solver": {"until": "t_max", "t_max": "5 ms"}}
    p = tmp_path / "s.toml"
    p.write_text(tomli_w.dumps(doc), encoding="utf-8")
    r = hc.simulate_file(p)
    assert r.solution.t_final == pytest.approx(5e-3)
    assert [ep.end for ep in r.episodes] == [r.solution.t_final] * 3


def test_a_far_wall_of_a_real_material_warns_when_it_yields(tmp_path):
    """A review: a steel-4340 wall struck by a steel-52100 sphere at 2.5x its yield pressure was never
    warned about (the interfaces were). The warning's pressure is Hertz's peak pressure of the wall's
    contact at the report's wall peak force, p0 = (6 F E*^2 / (pi^3 R^2))^(1/3) (Johnson 1985, Eq 4.24),
    E* from the two materials and R the sphere's radius (a flat wall), against 1.6 Y of the 4340."""
    import re

    from hertz_chain.materials import effective_modulus, material

    p = tmp_path / "w.toml"
    p.write_text('[drop]\nimpact_velocity = "0.2 m/s"\ngravity = 0\n[stack]\nmasses = ["20 g"]\ngaps = []\n'
                 'material = "steel-52100"\nradius = "8 mm"\n[contact]\nlaw = "hertz"\n[wall]\n'
                 'material = "steel-4340"\ngap = "0.1 mm"\n[solver]\nuntil = "t_max"\nt_max = "2 ms"\n')
    r = hc.simulate_file(p)
    E = effective_modulus(material("steel-52100"), material("steel-4340"))
    p0 = (6 * r.wall_peak_force * E**2 / (np.pi**3 * 8e-3**2)) ** (1 / 3)
    p_y = 1.6 * material("steel-4340").yield_strength
    (line,) = [w for w in r.warnings if w.startswith("interface top-wall")]
    got = re.search(r"peak Hertz pressure ([\d.]+) GPa exceeds the yield pressure ([\d.]+) GPa", line)
    assert float(got[1]) == pytest.approx(p0 / 1e9, rel=5e-3) and float(got[2]) == pytest.approx(p_y / 1e9, rel=5e-3)
    assert p0 > 2 * p_y and "steel-4340" in line


def test_the_output_grid_reaches_t_max(tmp_path):
    """A review: `dt_output = "1 us"` to `t_max = "0.3 ms"` wrote 300 samples ending at 0.299 ms (0.3 ms / 1 us
    is 299.99999... in floating point, and the grid stopped short): 301 samples, 0 to t_max, 1 us apart."""
    p = tmp_path / "g.toml"
    p.write_text('[drop]\ngravity = 0\n[stack]\nmasses = ["10 g", "10 g"]\ngaps = 0\nvelocities = [0, "-0.1 m/s"]\n'
                 'end_force = "1 N"\n[contact]\nlaw = "hertz"\nstiffness = "1e10 N/m^1.5"\n[solver]\nuntil = "t_max"\n'
                 't_max = "0.3 ms"\ndt_output = "1 us"\n')
    t = hc.simulate_file(p).solution.grid.t
    assert len(t) == 301 and t[0] == 0.0 and t[-1] == pytest.approx(3e-4, rel=1e-15)
    np.testing.assert_allclose(np.diff(t), 1e-6, rtol=1e-9)
