"""Materials table, effective modulus/radius/mass, Hertz stiffness and geometry masses."""

import csv
import math
import re

import pytest

from hertz_chain.errors import ParameterError
from hertz_chain.materials import (
    MATERIALS_CSV,
    Material,
    contact_stiffness,
    cylinder_mass,
    disc_mass,
    effective_mass,
    effective_modulus,
    effective_radius,
    hertz_stiffness,
    load_materials,
    material,
    material_names,
    sphere_mass,
)


def test_csv_columns_and_sources():
    with open(MATERIALS_CSV, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        assert reader.fieldnames == ["name", "youngs_modulus_Pa", "poisson_ratio", "density_kg_m3",
                                     "typical_restitution", "yield_strength_Pa", "source"]
        rows = list(reader)
    assert len(rows) >= 10
    for row in rows:
        assert len(row["source"]) > 20, row["name"]  # every row cites where its numbers come from
        # the restitution column is marked as indicative (not a material constant)
        assert "indicative" in row["source"] or not row["typical_restitution"]
        # every row says where its yield strength comes from, or why it has none
        assert "Y: " in row["source"], row["name"]
        assert bool(row["yield_strength_Pa"]) is ("none given" not in row["source"]), row["name"]


@pytest.mark.parametrize(
    "name, e_range, nu_range, rho_range",
    [
        # published ranges (ASM Handbook Vols. 1/2; MatWeb datasheets named in the CSV)
        ("steel-52100", (190e9, 215e9), (0.27, 0.30), (7750, 7850)),
        ("steel-4340", (190e9, 215e9), (0.27, 0.30), (7800, 7900)),
        ("stainless-304", (190e9, 200e9), (0.27, 0.30), (7900, 8050)),
        ("aluminium-6061-t6", (68e9, 70e9), (0.32, 0.34), (2690, 2710)),
        ("ti-6al-4v", (110e9, 120e9), (0.31, 0.35), (4400, 4450)),
        ("tungsten-carbide-6co", (550e9, 700e9), (0.20, 0.24), (14500, 15300)),
        ("brass-c360", (90e9, 100e9), (0.30, 0.35), (8400, 8550)),
        ("copper-c110", (110e9, 130e9), (0.30, 0.35), (8890, 8940)),
        ("pmma", (2.4e9, 3.4e9), (0.35, 0.40), (1170, 1200)),
        ("polyurethane-90a", (1e7, 6e7), (0.45, 0.5), (1100, 1250)),
    ],
)
def test_material_values_in_published_ranges(name, e_range, nu_range, rho_range):
    m = material(name)
    assert e_range[0] <= m.youngs_modulus <= e_range[1]
    assert nu_range[0] <= m.poisson_ratio <= nu_range[1]
    assert rho_range[0] <= m.density <= rho_range[1]
    assert 0 < m.typical_restitution <= 1


def test_lookup_is_case_insensitive_and_frozen():
    assert material("STEEL_52100") is material("steel-52100")
    with pytest.raises(AttributeError):
        material("pmma").youngs_modulus = 1.0  # frozen dataclass
    assert set(material_names()) == set(load_materials())


def test_effective_modulus_formula():
    # Johnson (1985) Eq. 4.22: 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (numbers from the CSV rows)
    e_ss = 1 / (2 * (1 - 0.30**2) / 2.10e11)
    assert effective_modulus("steel-52100", "steel-52100") == pytest.approx(e_ss, rel=1e-15)
    e_mix = 1 / ((1 - 0.30**2) / 2.10e11 + (1 - 0.33**2) / 6.89e10)
    assert effective_modulus("steel-52100", "aluminium-6061-t6") == pytest.approx(e_mix, rel=1e-15)
    # rigid partner
    assert effective_modulus("pmma", None) == pytest.approx(3.0e9 / (1 - 0.37**2), rel=1e-15)


def test_effective_radius_and_mass():
    assert effective_radius(0.01, 0.01) == pytest.approx(0.005, rel=1e-15)  # 1/R* = 1/R1 + 1/R2
    assert effective_radius(0.01, 0.03) == pytest.approx(0.0075, rel=1e-15)
    assert effective_radius(0.02) == 0.02  # sphere on flat
    assert effective_radius(0.02, math.inf) == 0.02
    assert effective_mass(2.0, 3.0) == pytest.approx(1.2, rel=1e-15)
    assert effective_mass(2.0) == 2.0  # against the ground
    assert effective_mass(2.0, math.inf) == 2.0


def test_contact_stiffness():
    # k = (4/3) E* sqrt(R*) (Johnson 1985 Eq. 4.23): two 10 mm-radius 52100 balls
    e_star = 1 / (2 * (1 - 0.30**2) / 2.10e11)
    k = 4 / 3 * e_star * math.sqrt(0.005)
    assert contact_stiffness("steel-52100", "steel-52100", 0.01, 0.01) == pytest.approx(k, rel=1e-15)
    assert hertz_stiffness(e_star, 0.005) == pytest.approx(k, rel=1e-15)
    # ball on a flat of the same steel: R* = R
    assert contact_stiffness("steel-52100", "steel-52100", 0.01) == pytest.approx(
        4 / 3 * e_star * math.sqrt(0.01), rel=1e-15)


def test_masses():
    # sphere (4/3) pi r^3 rho, cylinder pi r^2 h rho
    assert sphere_mass(0.01, 7810) == pytest.approx(4 / 3 * math.pi * 1e-6 * 7810, rel=1e-15)
    assert sphere_mass(0.01, "steel-52100") == sphere_mass(0.01, 7810)  # CSV density of 52100
    assert cylinder_mass(0.02, 0.05, 2700) == pytest.approx(math.pi * 4e-4 * 0.05 * 2700, rel=1e-15)
    assert disc_mass(0.02, 0.005, "aluminium-6061-t6") == pytest.approx(math.pi * 4e-4 * 0.005 * 2700, rel=1e-15)


@pytest.mark.parametrize(
    "call, param",
    [
        (lambda: material("unobtainium"), "material"),
        (lambda: Material("x", 2e11, 0.6), "poisson_ratio"),
        (lambda: Material("x", 2e11, -1.0), "poisson_ratio"),
        (lambda: Material("x", 0.0, 0.3), "youngs_modulus"),
        (lambda: Material("x", -2e11, 0.3), "youngs_modulus"),
        (lambda: Material("x", 2e11, 0.3, density=-1.0), "density"),
        (lambda: Material("x", 2e11, 0.3, typical_restitution=1.5), "typical_restitution"),
        (lambda: effective_radius(0.0), "R1"),
        (lambda: effective_radius(math.inf, math.inf), "R1"),  # flat on flat: not Hertzian
        (lambda: effective_radius(0.01, -0.01), "R2"),
        (lambda: effective_mass(-1.0), "m1"),
        (lambda: effective_modulus(None, None), "material"),
        (lambda: sphere_mass(0.0, 7800), "radius"),
        (lambda: cylinder_mass(0.01, 0.0, 7800), "height"),
        (lambda: sphere_mass(0.01, 0.0), "density"),
        (lambda: contact_stiffness("steel-52100", "unobtainium", 0.01), "material"),
    ],
)
def test_bad_parameters(call, param):
    with pytest.raises(ParameterError) as info:
        call()
    assert info.value.name == param


def test_incompressible_limit_allowed():
    # nu = 1/2 is the incompressible limit (rubber-like); -1 < nu <= 1/2 for isotropic solids
    assert Material("rubber", 2e6, 0.5).plane_strain_compliance == pytest.approx(0.75 / 2e6)


def test_a_yield_pressure_from_the_materials_that_never_yields_names_where_it_came_from(tmp_path):
    """A review: steel on polyurethane with `law = "thornton"` ran as pure Hertz (the steel's yield pressure,
    1.6 Y = 3.248 GPa, far above the pair's 2 E*/pi, so delta_y = R (pi p_y / 2E*)^2 exceeds the radius);
    refused now, and the message says the value came from the materials (the file never set it)."""
    from hertz_chain.errors import StackFileError
    from hertz_chain.materials import material
    from hertz_chain.stackfile import load_stack_file
    from hertz_chain.builder import build

    p = tmp_path / "s.toml"
    p.write_text('[drop]\nimpact_velocity = "1 m/s"\n[stack]\nmasses = [1.0]\nradius = "1 cm"\nmaterial = "steel-52100"\n'
                 '[ground]\nmaterial = "polyurethane-90a"\n[contact]\nlaw = "thornton"\n')
    p_y = 1.6 * material("steel-52100").yield_strength
    with pytest.raises(StackFileError, match=rf"contact \(interface 0\): law 'thornton': the yield_pressure from the "
                                             rf"materials, {re.escape(f'{p_y:.4g}')} Pa \(1.6 x steel-52100's yield strength\), is "
                                             r"invalid: below 2 E\*/pi"):
        build(load_stack_file(p))


def test_an_unknown_material_names_its_key(tmp_path):
    """A review: an unknown stack.material read "material = 'unobtanium' is invalid", without its key;
    now the key, the table's names and a close match, before anything is built."""
    from hertz_chain.errors import StackFileError
    from hertz_chain.stackfile import load_stack_file

    p = tmp_path / "s.toml"
    for key, line, name in (("stack.material", 'material = "{}"\n', "steel-5210"),):
        p.write_text('[drop]\nimpact_velocity = "1 m/s"\n[stack]\nmasses = [1.0, 0.5]\ngaps = 0\nradius = "1 cm"\n'
                     + line.format(name) + '[contact]\nlaw = "hertz"\n')
        with pytest.raises(StackFileError, match=rf"{re.escape(key)}: '{name}' is unknown; the table's materials "
                                                 r"\(steel-52100.*did you mean 'steel-52100'\?"):
            load_stack_file(p)
    # a name not used (every stiffness given, no radius) is a label, as before (a second review)
    p.write_text('[drop]\nimpact_velocity = "1 m/s"\n[stack]\nmasses = [1.0, 0.5]\ngaps = 0\nmaterial = "rubber"\n'
                 '[contact]\nlaw = "hertz"\nstiffness = "1e9 N/m^1.5"\n')
    assert load_stack_file(p).stack.material == "rubber"
