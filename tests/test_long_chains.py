"""Long granular chains and the smallest stack (issue 21): 1 to 1,000 masses.

References:

- one mass dropped on the ground with an elastic Hertz contact: energy conservation (the contact returns
  all its energy and the ground does no work, so the mass leaves the ground at its impact speed, under
  gravity too) and the closed-form Hertz contact time `t_c = 3.21807 (m/k)^{2/5} v^{-1/5}` (Hertz 1882;
  docs/references.md, "Hertz single impact"), checked without gravity;
- a chain of equal beads struck at one end: the solitary wave of Nesterenko (Nesterenko 1983, "Propagation
  of nonlinear compression pulses in granular media", J. Appl. Mech. Tech. Phys. 24, 733), whose speed
  scales as `V_s ∝ v_m^{1/5}` with the particle velocity `v_m`. For a Hertz chain of equal beads the
  scaling is exact (the equations are invariant under `x -> mu x`, `t -> mu^{-1/4} t`, so velocities
  scale as `mu^{5/4}` and wave speeds in beads per second as `mu^{1/4}`), so two strikes at speeds in the
  ratio 4 give wave speeds in the ratio `4^{1/5}` to the accuracy of the solve; the wave's peak bead
  velocity (0.6816 of an equal striker's speed), its speed `0.9075 (k/m)^{2/5} v_m^{1/5}` beads per second,
  and the recoils of the striker and the next bead (-0.07109,
  -0.03027), docs/references.md, "Stacks and chains";
- the size limits of `constants.MAX_MASSES`.
"""

import re

import numpy as np
import pytest
import tomli_w

import hertz_chain as hc
from hertz_chain.constants import MAX_MASSES
from hertz_chain.errors import ParameterError, StackFileError


def _file(tmp_path, doc, name="s.toml"):
    p = tmp_path / name
    p.write_text(tomli_w.dumps(doc))
    return p


@pytest.mark.parametrize("gravity", [None, 0])
def test_one_mass_dropped_on_the_ground_is_a_stack_file(tmp_path, gravity):
    m, k, v = 0.2, 1e9, 1.5
    doc = {"drop": {"impact_velocity": f"{v} m/s"}, "stack": {"masses": [f"{m} kg"], "gaps": []},
           "contact": {"law": "hertz", "stiffness": f"{k} N/m^1.5"}}
    if gravity is not None:
        doc["drop"]["gravity"] = gravity
    built = hc.build(hc.load_stack_file(_file(tmp_path, doc)))
    assert built.stack.n == 1 and built.stack.ground
    sol = hc.simulate(built.stack, built.state, tolerances=hc.Tolerances(rtol=1e-11, atol=1e-11))
    assert sol.ok
    assert sol.launch_velocities[0] == pytest.approx(v, rel=1e-8)  # energy conservation
    if gravity == 0:
        t_c = 3.21807 * (m / k) ** 0.4 * v**-0.2
        assert sol.launch_times[0] == pytest.approx(t_c, rel=1e-5)  # closed form, 6 digits published


def test_one_mass_without_the_ground_is_refused_in_one_line(tmp_path):
    doc = {"drop": {"ground": False}, "stack": {"masses": ["1 kg"], "gaps": [], "velocities": [0]},
           "contact": {"law": "hertz", "stiffness": "1e9 N/m^1.5"}}
    with pytest.raises(StackFileError, match=r"stack\.masses.*drop\.ground = false.*at least 2"):
        hc.load_stack_file(_file(tmp_path, doc))


def test_a_thousand_masses_are_accepted_and_one_more_is_refused(tmp_path):
    doc = {"drop": {"impact_velocity": "1 m/s"}, "stack": {"masses": [0.01] * MAX_MASSES, "gaps": 0},
           "contact": {"law": "hertz", "stiffness": "1e9 N/m^1.5"}}
    assert MAX_MASSES >= 1000
    assert hc.load_stack_file(_file(tmp_path, doc)).n == MAX_MASSES
    doc["stack"]["masses"] = [0.01] * (MAX_MASSES + 1)
    with pytest.raises(StackFileError, match=rf"stack\.masses.*at most {MAX_MASSES}"):
        hc.load_stack_file(_file(tmp_path, doc, "big.toml"))
    with pytest.raises(ParameterError, match="len\\(masses\\)"):
        hc.Stack(np.ones(MAX_MASSES + 1), hc.Hertz(1e9))


def _wave_times(v0: float, n: int = 40, probes=(10, 30)):
    """Times at which the force of interfaces `probes` peaks, for a chain of equal steel-like beads struck
    at one end at `v0` (no ground, no gravity). Peak times from the dense output on a fine grid, refined by
    a parabola through the three samples around the largest."""
    m, k = 0.0045, 1.2e10  # ~1 cm steel beads: m = rho pi D^3/6, k = E D^{1/2} / (3 (1 - nu^2)) / sqrt(2)
    stack = hc.Stack(np.full(n, m), hc.Hertz(k), gravity=0.0, ground=False)
    v = np.zeros(n)
    v[0] = v0
    state = hc.State(np.zeros(n), v)
    t_c = 3.21807 * (0.5 * m / k) ** 0.4 * v0**-0.2  # one contact time, to size the grid
    grid = np.linspace(0.0, 1.3 * n * t_c, 40 * n)
    sol = hc.simulate(stack, state, ts=grid, tolerances=hc.Tolerances(rtol=1e-11, atol=1e-11), max_steps=200_000)
    f = np.asarray(sol.grid.forces)
    _wave_times.last = sol
    _wave_times.reports = getattr(_wave_times, "reports", []) + [hc.analyse(sol)]
    out = []
    for j in probes:
        i = int(np.nanargmax(f[:, j]))
        y0, y1, y2 = f[i - 1, j], f[i, j], f[i + 1, j]
        h = grid[1] - grid[0]
        out.append(grid[i] + 0.5 * h * (y0 - y2) / (y0 - 2 * y1 + y2))
    vel = np.asarray(sol.grid.velocities)[:, 20]
    i = int(np.nanargmax(vel))
    y0, y1, y2 = vel[i - 1 : i + 2]
    v_peak = y1 - 0.125 * (y2 - y0) ** 2 / (y2 - 2 * y1 + y0)  # the parabola's vertex
    return np.asarray(out), float(v_peak)


def test_solitary_wave_speed_follows_nesterenkos_one_fifth_power():
    (a1, b1), vm1 = _wave_times(0.5)
    (a2, b2), vm2 = _wave_times(2.0)
    speed1, speed2 = 20 / (b1 - a1), 20 / (b2 - a2)  # beads per second between interfaces 10 and 30
    # the particle velocity of the wave scales with the striker speed (similarity), and the speed as its 1/5 power
    assert vm2 / vm1 == pytest.approx(4.0, rel=1e-6)
    assert speed2 / speed1 == pytest.approx(4.0**0.2, rel=1e-4)  # parabolic peak times: ~1e-5 measured
    # the wave's bead velocity and the recoil of the striker and of bead 2 (equal striker): 0.6816, -0.07109
    # and -0.03027 of the striker speed (docs/references.md, "Stacks and chains"; 4 digits given)
    assert vm2 / 2.0 == pytest.approx(0.6816, abs=1e-4)
    # the discrete chain's wave speed in beads per second, 0.9075 (k/m)^{2/5} v_m^{1/5} (same section;
    # the continuum's (16/25)^{1/5} = 0.9146 is 0.8 % higher)
    m, k = 0.0045, 1.2e10
    assert speed2 / ((k / m) ** 0.4 * vm2**0.2) == pytest.approx(0.9075, abs=1e-4)
    v_end = np.asarray(_wave_times.last.launch_velocities)[:2] / 2.0
    np.testing.assert_allclose(v_end, [-0.07109, -0.03027], atol=1e-5)
    # the report's wave speed (least squares over the middle half's peak-force times, `hc.wave_speed`) on the
    # same two solves: the same references, travelling up from the struck mass 1
    r1, r2 = _wave_times.reports[-2:]
    for r in (r1, r2):
        assert r.wave_speed > 0
        assert r.wave_speed / ((k / m) ** 0.4 * r.peak_velocities[20] ** 0.2) == pytest.approx(0.9075, abs=1e-4)
    assert r2.wave_speed / r1.wave_speed == pytest.approx(4.0**0.2, rel=1e-6)
    from hertz_chain.report import to_dict

    assert to_dict(r2)["wave_speed_per_s"] == r2.wave_speed
    # the text report of a 40-bead chain: the masses in a few words, the first and last ten rows of the
    # per-mass table (the rest in --json), the touching beads' undefined restitutions as one range
    from hertz_chain.report import summary_table

    text = summary_table(r2)
    assert "40 masses (0.0045 kg each)" in text
    rows = [line for line in text.splitlines() if re.match(r"\s*\d+\s+-?\d\.\d{4}\s+\|", line)]
    assert [int(line.split()[0]) for line in rows] == list(range(1, 11)) + list(range(31, 41))
    assert "(20 masses 11-30 left out; --json lists every mass)" in text
    assert len(to_dict(r2)["masses_kg"]) == 40 and len(to_dict(r2)["velocity_gains"]) == 40
    undefined = [j for j in range(1, 40) if not np.isfinite(r2.restitution[j])]
    assert undefined == list(range(undefined[0], 40)) and len(undefined) > 2  # touching beads: one run
    assert f"interface(s) [{undefined[0]}-39]" in text


def test_interface_lists_in_messages_join_runs():
    from hertz_chain.analysis import _index_ranges

    assert _index_ranges([1, 2, 3, 4, 7]) == "[1-4, 7]"
    assert _index_ranges([2, 3, 5, 9, 10, 11]) == "[2, 3, 5, 9-11]"
    assert _index_ranges([0]) == "[0]"
    assert _index_ranges([]) == "[]"


def test_wave_speed_needs_one_monotone_wave():
    # a wave down a chain of 12 contacts, 1 ms per contact: -1000 contacts/s exactly (a straight line)
    t = 1e-3 * np.arange(12)[::-1]
    assert hc.wave_speed(t) == pytest.approx(-1000.0, rel=1e-12)
    t_up = 1e-3 * np.arange(12)
    t_up[5] = t_up[7]  # two contacts of the middle half peak out of order: no single wave
    assert np.isnan(hc.wave_speed(t_up))
    assert np.isnan(hc.wave_speed([0.0, 1.0, 2.0, np.nan]))  # too few contacts
