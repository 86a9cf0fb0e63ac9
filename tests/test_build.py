"""Stack files resolved into simulator inputs (hertz_chain.builder).

References: paper Eq 15 (MVG masses m_i = m_1 R^{(i-1)/(n-1)}); Section 4 (after the ground impact,
mass 1 meets the still-falling mass 2 at (1 + e_{1,0}) v_ff); Hertz stiffness k = (4/3) E* sqrt(R*)
with 1/E* = sum (1 - nu^2)/E and 1/R* = 1/R1 + 1/R2 (Johnson 1985); effective mass
m* = m1 m2/(m1 + m2).
"""

import math
from pathlib import Path

import numpy as np
import pytest

from hertz_chain.status import Status
from hertz_chain.builder import build
from hertz_chain.calibration import chi_from_restitution
from hertz_chain.errors import StackFileError
from hertz_chain.simulation import simulate
from hertz_chain.stackfile import load_stack_file, parse_stack

NORMATIVE = """
[drop]
impact_velocity = "1 m/s"
gravity = 0

[stack]
masses = [8.4, 3.4683, 1.4320, 0.5913, 0.2441, 0.1008]
gaps = "1 cm"

[contact]
law = "tsuji"
stiffness = "1e9 N/m^1.5"
restitution = 0.8

[solver]
rtol = 1e-10
"""


def test_normative_example():
    b = build(parse_stack(NORMATIVE))
    m = np.array([8.4, 3.4683, 1.4320, 0.5913, 0.2441, 0.1008])
    np.testing.assert_array_equal(b.masses, m)
    np.testing.assert_allclose(np.asarray(b.state.positions), np.arange(6) * 0.01, rtol=1e-15)
    np.testing.assert_array_equal(np.asarray(b.state.velocities), -np.ones(6))
    np.testing.assert_array_equal(b.nominal_restitution, np.full(6, 0.8))
    m_eff = np.concatenate([[m[0]], m[:-1] * m[1:] / (m[:-1] + m[1:])])
    np.testing.assert_allclose([float(law.m_eff) for law in b.laws], m_eff, rtol=1e-15)
    assert b.simulate_options["tolerances"].rtol == 1e-10


def test_mvg_design_masses_follow_eq15():
    spec = load_stack_file("examples/mvg6_gapped.toml")
    b = build(spec)
    R, m1, n = 0.012, 8.4, 6  # the file's design; n_max = 6 (paper Fig 17)
    np.testing.assert_allclose(b.masses, m1 * R ** (np.arange(n) / (n - 1)), rtol=1e-13)


def test_hunt_crossley_defaults_to_the_rigid_approach_speed():
    spec = parse_stack("""
[drop]
impact_velocity = "2 m/s"
gravity = 0
[stack]
masses = [2.0, 1.0]
gaps = "1 cm"
[contact]
law = "hunt-crossley"
stiffness = 1e9
restitution = 0.7
""")
    b = build(spec)
    e0, v = 0.7, 2.0
    # ground contact at v_ff; interface 1 at (1 + e_{1,0}) v_ff (paper Section 4)
    assert float(b.laws[0].alpha) == pytest.approx(chi_from_restitution(0.7) / v, rel=1e-12)
    assert float(b.laws[1].alpha) == pytest.approx(chi_from_restitution(0.7) / ((1 + e0) * v), rel=1e-12)


def test_stiffness_from_materials():
    b = build(load_stack_file("examples/steel_materials.toml"))
    # the file: 52100 spheres (E 210 GPa, nu 0.3) of radii 5 cm and 3 cm, a flat 304 top mass
    # (193 GPa, 0.29) and a flat 1045 anvil (205 GPa, 0.29)
    def k(E1, n1, E2, n2, R):
        e_star = 1 / ((1 - n1**2) / E1 + (1 - n2**2) / E2)
        return 4 / 3 * e_star * math.sqrt(R)

    expected = [
        k(205e9, 0.29, 210e9, 0.3, 0.05),  # anvil - sphere 5 cm
        k(210e9, 0.3, 210e9, 0.3, 1 / (1 / 0.05 + 1 / 0.03)),  # sphere - sphere
        k(210e9, 0.3, 193e9, 0.29, 0.03),  # sphere 3 cm - flat 304
    ]
    np.testing.assert_allclose([float(law.k) for law in b.laws], expected, rtol=1e-12)


def test_override_index_beyond_the_stack_is_reported():
    text = NORMATIVE + '\n[[contact.interface]]\nindex = 9\nstiffness = "1e8 N/m^1.5"\n'
    with pytest.raises(StackFileError, match="contact.interface"):
        build(parse_stack(text))


@pytest.mark.parametrize("path", sorted((Path(__file__).parents[1] / "examples").glob("*.toml")), ids=lambda p: p.stem)
def test_every_shipped_example_simulates_with_defaults(path):
    """Each file in examples/ runs with the simulator's defaults (the ten-mass MET stack under gravity
    settles after the cascade and needs ~22,000 steps) and closes its energy audit: kinetic + potential
    + elastic + dissipated energy is conserved (a law of mechanics, not the code's output) to within
    1e-8 of the energy scale at rtol = atol = 1e-10."""
    b = build(load_stack_file(path))
    sol = simulate(b.stack, b.state, **b.simulate_options)
    assert sol.ok
    assert float(sol.energy_error) < 1e-8


def test_kelvin_voigt_given_by_its_damping_has_a_nominal_restitution():
    """A linear spring-dashpot's restitution depends only on zeta = c / (2 sqrt(m* k)); unclamped it is
    e = exp(-zeta pi / sqrt(1 - zeta^2)) (closed form, e.g. Schwager & Pöschel 2007), so the rigid
    comparison can use it."""
    spec = parse_stack("""
[drop]
ground = false
[stack]
masses = [1.0, 0.5]
gaps = "1 mm"
velocities = [1.0, 0]
[contact]
law = "kelvin-voigt"
stiffness = 2e7
damping = 20
clamp = false
""")
    b = build(spec)
    zeta = 20.0 / (2 * math.sqrt((1.0 * 0.5 / 1.5) * 2e7))
    assert b.nominal_restitution[1] == pytest.approx(math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2)), rel=1e-9)
