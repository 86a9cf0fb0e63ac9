"""Every row of every vocabulary (`hertz_chain.registry`), end to end: stack file -> build -> simulate.

Adding a contact law, a chi map or a solver is one row there (and, for a law, one class); these tests
pick it up without an edit. References: the restitution a law is calibrated to (paper Eq 2, measured by
an independent single-impact simulation, `hc.simulate_impact`), each published chi map's own formula, and
the elastic two-mass exchange of the paper's Eqs 1-2 with e = 1 (`rigid_events.simulate_rigid`).
"""

import numpy as np
import pytest

import hertz_chain as hc
from hertz_chain import calibration, contact, registry, stackfile
from hertz_chain.builder import build
from hertz_chain.rigid_events import simulate_rigid


def test_every_entry_point_reads_the_registry():
    # ... and the stack-file manual lists every name
    from pathlib import Path

    manual = (Path(__file__).resolve().parents[1] / "docs" / "stack-files.md").read_text()
    for name in (*registry.LAWS, *registry.CHI_MAPS, *registry.SOLVERS):
        assert f'"{name}"' in manual, name
    assert stackfile.CONTACT_LAWS == tuple(registry.LAWS) == contact.LAW_NAMES
    assert stackfile.CHI_MAPS == tuple(registry.CHI_MAPS) == tuple(calibration.CHI_MAPS)
    assert stackfile.SOLVERS == tuple(registry.SOLVERS)
    for name, row in registry.LAWS.items():
        cls = getattr(contact, row.cls)
        assert cls.name == name and callable(cls.from_config)
        assert cls.has_memory == row.memory, name  # the row and the class say the same (the state has a memory)


def _file(law_lines: str, solver: str = "tsit5", gravity: str = "", radius: str = "") -> str:
    return f"""
[drop]
impact_velocity = "1 m/s"
{gravity}
[stack]
masses = [1.0, 0.4, 0.16]
gaps = "2 mm"
{radius}
[contact]
{law_lines}
[solver]
solver = "{solver}"
"""


def _law_lines(row: registry.LawRow, e: float | None) -> str:
    stiffness = "1e7 N/m" if row.stiffness == "linear_stiffness" else "1e9 N/m^1.5"
    lines = [f'law = "{row.name}"', f'stiffness = "{stiffness}"']
    if e is not None and row.damping is not None:
        lines.append(f"restitution = {e}")
    values = {"pressure": '"2 GPa"', "dimensionless": "1.5"}  # a row's further keys (`LawRow.params`)
    by_key = {"yield_strength": '"100 MPa"'}  # a yield strain in jackson-green's range (E' = 15 GPa here)
    lines += [f"{key} = {by_key.get(key, values[dim])}" for key, dim in row.params]
    return "\n".join(lines)


def _radius(row: registry.LawRow) -> str:
    return 'radius = "5 mm"' if row.needs_radius else ""


@pytest.mark.parametrize("name", list(registry.LAWS))
def test_every_law_runs_from_a_stack_file_and_meets_its_restitution(name):
    row = registry.LAWS[name]
    e = 1.0 if row.elastic else 0.7
    built = build(stackfile.parse_stack(_file(_law_lines(row, e), radius=_radius(row))))
    law = built.stack.law_of(1)
    assert type(law).__name__ == row.cls
    sol = hc.simulate(built.stack, built.state, **built.simulate_options)
    # a law with memory: the audit closes to the integration error at the default tolerance (the kink of
    # its memory rate at every peak; docs/contact-laws.md), 1e-7; the others to 1e-8
    assert sol.ok and np.isfinite(sol.gain) and sol.energy_error < (1e-7 if row.memory else 1e-8)
    if row.memory:  # no calibration: e follows from its own parameters (tests/test_plastic.py)
        assert built.stack.has_memory and np.isnan(built.nominal_restitution[1])
        return
    # the law is calibrated to the file's e (the calibrations themselves are checked against simulated
    # impacts in tests/test_calibration.py); a speed-dependent law at the rigid approach speed of
    # interface 1 (Eqs 1-2): mass 1 leaves the ground at e v_ff and meets mass 2 falling at v_ff
    m_eff = 1.0 * 0.4 / 1.4
    v = (1.0 + e) * 1.0 if row.speed_dependent else 1.0
    assert float(law.restitution_at(v, m_eff)) == pytest.approx(e, abs=1e-9)
    assert built.nominal_restitution[1] == e


@pytest.mark.parametrize("name", [n for n, r in registry.LAWS.items() if r.damping is not None])
def test_every_damped_law_takes_its_raw_parameter(name):
    # the file key of the law's own damping parameter builds the law from the raw value
    row = registry.LAWS[name]
    value = {"hunt-crossley": 0.1, "tsuji": 0.3, "kelvin-voigt": 5.0, "viscoelastic": 1e-5}.get(name, 0.1)
    text = _file(_law_lines(row, None) + f"\n{row.damping} = {value}")
    built = build(stackfile.parse_stack(text))
    assert type(built.stack.law_of(1)).__name__ == row.cls
    assert all(k in row.file_keys() for k in ("stiffness", "clamp", "restitution", row.damping))


@pytest.mark.parametrize("name", [n for n, r in registry.LAWS.items()
                                  if r.damping is not None and not r.memory and not r.params])
def test_every_calibrated_law_follows_a_design(name):
    # optimize, sweep and fit rebuild the contacts from a design's numbers (`_design.DesignMap`, through the
    # law's `dimensionless_damping` / `from_dimensionless`): at the file's own values that is the law
    # `build` made (the reference: the builder's calibration, checked against simulated impacts above); a
    # review added a law without that pair and the sweep ran it undamped (the base class returned 0)
    import jax

    from hertz_chain._design import DesignMap
    from hertz_chain.keys import resolve

    row = registry.LAWS[name]
    spec = stackfile.parse_stack(_file(_law_lines(row, 0.7)))
    built = build(spec)
    stack, _ = DesignMap(spec, resolve("stack.masses", [2], n=3, ground=True))(np.asarray([0.4]))
    for j in range(3):
        mine, ref = stack.law_of(j), built.stack.law_of(j)
        assert type(mine) is type(ref)
        for a, b in zip(jax.tree.leaves(mine), jax.tree.leaves(ref)):
            np.testing.assert_allclose(np.asarray(a, dtype=float), np.asarray(b, dtype=float), rtol=1e-9)


def test_a_damped_law_without_its_design_pair_is_refused_not_run_elastic():
    # the base class's pair raises, naming the method (it returned 0: the law ran undamped in sweeps)
    from hertz_chain._law_base import AbstractContactLaw

    with pytest.raises(NotImplementedError, match="dimensionless_damping"):
        AbstractContactLaw.dimensionless_damping.__func__(contact.KelvinVoigt, 0.7)
    with pytest.raises(NotImplementedError, match="from_dimensionless"):
        AbstractContactLaw.from_dimensionless.__func__(contact.KelvinVoigt, 1e7, 0.1, effective_mass=1.0,
                                                        calibration_velocity=1.0)


@pytest.mark.parametrize("name", list(registry.CHI_MAPS))
def test_every_chi_map(name):
    row = registry.CHI_MAPS[name]
    for e in (0.3, 0.6, 0.9):
        chi = calibration.chi_from_restitution(e, name)
        if row.formula is not None:  # the published closed form, evaluated independently here
            assert chi == pytest.approx(row.formula(e), rel=1e-15)
        else:  # the exact map: its chi reproduces e through Carvalho & Martins' exact relation
            assert calibration.restitution_from_chi(chi) == pytest.approx(e, rel=1e-10)
    text = _file('law = "hunt-crossley"\nstiffness = "1e9 N/m^1.5"\nrestitution = 0.8\n' f'chi_map = "{name}"')
    built = build(stackfile.parse_stack(text))  # the law itself runs in the test of every law above
    assert float(built.stack.law_of(1).alpha) == pytest.approx(
        calibration.chi_from_restitution(0.8, name) / 1.8, rel=1e-12)  # alpha = chi(e)/v_c, v_c = (1 + e) v


@pytest.mark.parametrize("name", list(registry.SOLVERS))
def test_every_solver_reproduces_the_elastic_exchange(name):
    # Reference: two elastic Hertz masses, no gravity, mass 1 moving up into mass 2 across a gap: the
    # impact is elastic, so the launch velocities are the rigid e = 1 exchange (paper Eqs 1-2).
    text = """
[drop]
ground = false
gravity = 0
[stack]
masses = [1.0, 0.3]
gaps = "1 mm"
velocities = ["1 m/s", "0 m/s"]
[contact]
law = "hertz"
stiffness = "1e9 N/m^1.5"
[solver]
solver = "%s"
rtol = 1e-10
atol = 1e-10
""" % name
    built = build(stackfile.parse_stack(text))
    sol = hc.simulate(built.stack, built.state, **built.simulate_options)
    rigid = simulate_rigid([1.0, 0.3], [1.0, 0.0], [0.0, 1e-3], 1.0)
    assert sol.ok
    np.testing.assert_allclose(sol.launch_velocities, rigid.launch_velocities, rtol=1e-7)


def test_a_replaced_solver_row_is_used_by_the_next_call(monkeypatch):
    """The entry points memoise their solve configuration by the options (`simulation._config_for`); a
    registry row replaced under the same name must still be read by the next call, not the memo's."""
    from hertz_chain import simulation

    tol = hc.Tolerances(rtol=1e-8, atol=1e-8)
    first = simulation._config_for("tsit5", tol, 100, None, False, "cascade")
    monkeypatch.setitem(registry.SOLVERS, "tsit5", registry.SOLVERS["dopri5"])
    second = simulation._config_for("tsit5", tol, 100, None, False, "cascade")
    assert type(second.solver) is type(registry.SOLVERS["dopri5"].make(tol))
    assert type(second.solver) is not type(first.solver)
    assert simulation._config_for("tsit5", tol, 100, None, False, "cascade") is second  # memoised again
