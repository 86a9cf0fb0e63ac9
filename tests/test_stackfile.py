"""Stack files (hertz_chain.stackfile): TOML with units → StackSpec.

Every expected number comes from the unit definitions themselves (SI prefixes: 1 cm = 1e-2 m,
1 GPa = 1e9 Pa, 1 us = 1e-6 s, 1 g = 1e-3 kg; the international inch = 0.0254 m and pound =
0.45359237 kg, exact since 1959), from standard gravity g0 = 9.80665 m/s^2 (3rd CGPM, 1901), from the
free-fall formula v = sqrt(2 g h), or from the MVG definition R = m_n / m_1 (seed paper Eq 15).
Floats are compared with a relative tolerance of 1e-12 (unit conversions multiply by a factor).
"""

from __future__ import annotations

from _helpers import DELETE
from _helpers import patched as _patched
import dataclasses
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hertz_chain.errors import StackFileError
from hertz_chain.stackfile import (
    StackSectionSpec,
    ContactSpec,
    DesignSpec,
    StackSpec,
    load_stack_file,
    parse_quantity,
    parse_stack,
)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
REL = 1e-12
G0 = 9.80665  # standard gravity, m/s^2 (3rd CGPM 1901)

# The normative example of project issue #5, verbatim.
NORMATIVE = """\
[drop]
impact_velocity = "1 m/s"     # or: height = "5 cm"
gravity = 0                   # default 9.80665 m/s^2

[stack]
masses = [8.4, 3.4683, 1.4320, 0.5913, 0.2441, 0.1008]   # kg, bottom first
gaps = "1 cm"                 # one value for all, or a list of n-1

[contact]                     # default for every interface, the ground included
law = "tsuji"
stiffness = "1e9 N/m^1.5"
restitution = 0.8

[solver]
rtol = 1e-10
"""


def close(a, b, rel=REL):
    return math.isclose(a, b, rel_tol=rel, abs_tol=0.0)


def base() -> dict:
    return tomllib.loads(NORMATIVE)


def patched(changes: dict) -> dict:
    """The normative example with dotted keys set (value `DELETE` removes the key)."""
    return _patched(base(), changes)




def error_of(data) -> str:
    with pytest.raises(StackFileError) as info:
        parse_stack(data)
    return str(info.value)


def assert_one_line_error(data, key: str, *fragments: str) -> str:
    message = error_of(data)
    assert "\n" not in message and "\r" not in message, message
    assert message.startswith(f"{key}: "), message
    for fragment in fragments:
        assert fragment in message, message
    return message


def walk(obj):
    yield obj
    if dataclasses.is_dataclass(obj):
        for f in dataclasses.fields(obj):
            yield from walk(getattr(obj, f.name))
    elif isinstance(obj, tuple):
        for item in obj:
            yield from walk(item)


# --------------------------------------------------------------------------------------------------
# The normative example
# --------------------------------------------------------------------------------------------------


def test_normative_example_parses_to_si():
    spec = parse_stack(NORMATIVE)
    assert isinstance(spec, StackSpec)
    assert spec.stack.masses == (8.4, 3.4683, 1.4320, 0.5913, 0.2441, 0.1008)  # bare numbers are SI
    assert spec.n == 6
    assert close(spec.stack.gaps, 1e-2)  # 1 cm
    assert close(spec.stack.gap_list(6)[4], 1e-2) and len(spec.stack.gap_list(6)) == 5
    assert spec.drop.impact_velocity == 1.0 and spec.drop.gravity == 0.0 and spec.drop.height is None
    assert spec.has_ground and spec.ground.shape == "flat" and math.isinf(spec.ground.radius)
    for j in range(6):  # the default applies to every interface, the ground included
        c = spec.contact_for(j)
        assert (c.law, c.stiffness, c.restitution, c.clamp) == ("tsuji", 1e9, 0.8, True)
        assert c.damping is None and c.alpha is None
    assert spec.solver.rtol == 1e-10 and spec.solver.solver == "tsit5" and spec.solver.atol is None
    assert spec.stack.velocities is None and spec.stack.preload is False
    # upward-positive initial velocities: the dropped stack moves down at 1 m/s
    assert spec.initial_velocities() == (-1.0,) * 6


def test_normative_example_file_and_dict_agree():
    from_file = load_stack_file(EXAMPLES / "issue5_normative.toml")
    assert from_file.source.endswith("issue5_normative.toml")
    assert dataclasses.replace(from_file, source=None) == parse_stack(NORMATIVE) == parse_stack(base())


def test_spec_is_frozen_plain_python():
    spec = load_stack_file(EXAMPLES / "steel_materials.toml")
    allowed = (float, int, str, bool, type(None), tuple)
    for item in walk(spec):
        assert dataclasses.is_dataclass(item) or isinstance(item, allowed), type(item)
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.drop.gravity = 1.0


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.name)
def test_every_example_file_loads(path):
    assert isinstance(load_stack_file(path), StackSpec)


def test_pint_is_imported_lazily():
    code = "import sys, hertz_chain.stackfile; print('pint' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# --------------------------------------------------------------------------------------------------
# The drop
# --------------------------------------------------------------------------------------------------


def test_height_uses_standard_gravity_by_default():
    spec = parse_stack(patched({"drop.impact_velocity": DELETE, "drop.gravity": DELETE, "drop.height": "5 cm"}))
    assert spec.drop.gravity == G0
    assert close(spec.drop.height, 0.05)
    assert close(spec.drop.impact_velocity, math.sqrt(2 * G0 * 0.05))


def test_height_uses_the_files_gravity():
    spec = parse_stack(patched({"drop.impact_velocity": DELETE, "drop.gravity": "1.62 m/s^2", "drop.height": "2 ft"}))
    h = 2 * 12 * 0.0254  # 2 ft, international foot = 12 in = 0.3048 m
    assert close(spec.drop.impact_velocity, math.sqrt(2 * 1.62 * h))


def test_height_with_zero_gravity_is_an_error():
    data = patched({"drop.impact_velocity": DELETE, "drop.height": "5 cm"})  # gravity = 0
    assert_one_line_error(data, "drop.height", "gravity", "impact_velocity")


def test_gravity_units_and_sign():
    assert close(parse_stack(patched({"drop.gravity": "981 cm/s^2"})).drop.gravity, 9.81)
    assert_one_line_error(patched({"drop.gravity": -9.8}), "drop.gravity", ">= 0")
    assert_one_line_error(patched({"drop.gravity": "9.8 m/s"}), "drop.gravity", "acceleration")


def test_explicit_velocities_with_ground():
    data = patched({"drop.impact_velocity": DELETE, "stack.velocities": ["-1 m/s"] * 5 + ["-200 cm/s"]})
    spec = parse_stack(data)
    assert spec.drop.impact_velocity is None
    assert spec.initial_velocities() == (-1.0,) * 5 + (-2.0,)
    both = patched({"stack.velocities": [0.0] * 6})
    assert_one_line_error(both, "stack.velocities", "drop.impact_velocity")


# --------------------------------------------------------------------------------------------------
# Contact sections and overrides
# --------------------------------------------------------------------------------------------------


def test_ground_override_inherits_from_the_default():
    spec = parse_stack(patched({"contact.ground": {"restitution": 0.6, "stiffness": "4 GN/m^1.5"}}))
    g = spec.contact_for(0)
    assert (g.law, g.restitution, g.source) == ("tsuji", 0.6, "contact.ground")
    assert close(g.stiffness, 4e9)
    assert spec.contact_for(1).restitution == 0.8 and spec.contact_for(1).stiffness == 1e9


def test_ground_contact_cannot_be_active():
    """A contact law is passive (it returns at most the energy stored), so its restitution is <= 1; the
    paper's active ground e_{1,0} > 1 (Eq 19) exists only in the rigid model."""
    assert_one_line_error(patched({"contact.ground": {"restitution": 1.2}}), "contact.ground.restitution",
                          "1.2", "(0, 1]", "rigid-model only")


def test_override_with_another_law_starts_afresh_except_clamp():
    data = patched({"contact.clamp": False, "contact.ground": {"law": "hertz", "stiffness": "2e9 N/m^1.5"}})
    g = parse_stack(data).contact_for(0)
    assert g == ContactSpec("hertz", 2e9, None, None, None, None, None, False, "contact.ground")


def test_interface_overrides_single_and_list():
    data = patched(
        {
            "contact.interface": [
                {"index": 3, "stiffness": "5e8 N/m^1.5"},
                {"index": [4, 5], "law": "kelvin-voigt", "stiffness": "2e7 N/m", "damping": "20 N*s/m"},
                {"index": 1, "damping": 0.3},  # tsuji eta replaces the inherited restitution
            ]
        }
    )
    spec = parse_stack(data)
    assert [j for j, _ in spec.contact.overrides] == [1, 3, 4, 5]
    c1, c2, c3, c4 = (spec.contact_for(j) for j in (1, 2, 3, 4))
    assert (c1.law, c1.damping, c1.restitution, c1.stiffness) == ("tsuji", 0.3, None, 1e9)
    assert c2 == spec.contact.default
    assert (c3.law, c3.stiffness, c3.restitution) == ("tsuji", 5e8, 0.8)
    assert (c4.law, c4.stiffness, c4.damping, c4.restitution) == ("kelvin-voigt", 2e7, 20.0, None)
    assert spec.contact_for(5) == c4 and c4.source == "contact.interface[1]"


def test_interface_override_errors():
    one = lambda entry: patched({"contact.interface": [entry]})  # noqa: E731
    assert_one_line_error(one({"index": 0, "restitution": 0.5}), "contact.interface[0].index", "contact.ground")
    assert_one_line_error(one({"index": 6, "restitution": 0.5}), "contact.interface[0].index", "1..5")
    assert_one_line_error(one({"restitution": 0.5}), "contact.interface[0].index", "missing")
    assert_one_line_error(one({"index": 2, "restitution": 1.2}), "contact.interface[0].restitution", "(0, 1]")
    assert_one_line_error(one({"index": 2, "stifness": 1e9}), "contact.interface[0].stifness", "'stiffness'")
    dup = patched({"contact.interface": [{"index": [2, 3], "restitution": 0.7}, {"index": 3, "restitution": 0.6}]})
    assert_one_line_error(dup, "contact.interface[1].index", "already set")


def test_hunt_crossley_options():
    hc = {"law": "hunt-crossley", "stiffness": "1e9 N/m^1.5", "restitution": 0.7}
    spec = parse_stack(patched({"contact": dict(hc)}))
    assert spec.contact.default.chi_map == "exact" and spec.contact.default.calibration_velocity is None
    spec = parse_stack(patched({"contact": dict(hc, chi_map="lankarani-nikravesh", calibration_velocity="150 cm/s")}))
    assert spec.contact.default.chi_map == "lankarani-nikravesh"
    assert close(spec.contact.default.calibration_velocity, 1.5)
    alpha = {"law": "hunt-crossley", "stiffness": 1e9, "alpha": "0.3 s/m"}
    spec = parse_stack(patched({"contact": alpha}))
    assert spec.contact.default.alpha == 0.3 and spec.contact.default.restitution is None
    assert_one_line_error(patched({"contact": dict(hc, chi_map="flors")}), "contact.chi_map", "'flores'")
    assert_one_line_error(patched({"contact": dict(hc, alpha=0.3)}), "contact.alpha", "conflicts")
    assert_one_line_error(patched({"contact": dict(alpha, chi_map="flores")}), "contact.chi_map", "restitution")
    assert_one_line_error(patched({"contact": dict(alpha, alpha="0.3 m/s")}), "contact.alpha", "s/m")
    assert_one_line_error(patched({"contact": dict(hc, damping=1.0)}), "contact.damping", "alpha")


@pytest.mark.parametrize(
    ("law", "damping", "expected"),
    [("tsuji", 0.25, 0.25), ("kelvin-voigt", "3 kN*s/m", 3e3), ("viscoelastic", "2 us", 2e-6)],
)
def test_damping_units_per_law(law, damping, expected):
    k = "1e7 N/m" if law == "kelvin-voigt" else "1e9 N/m^1.5"
    spec = parse_stack(patched({"contact": {"law": law, "stiffness": k, "damping": damping}}))
    assert close(spec.contact.default.damping, expected)


def test_stiffness_dimension_depends_on_the_law():
    assert parse_stack(patched({"contact.law": "viscoelastic"})).contact.default.stiffness == 1e9
    kv = patched({"contact.law": "kelvin-voigt"})  # still 1e9 N/m^1.5
    assert_one_line_error(kv, "contact.stiffness", "N/m^1.5", "expected a linear stiffness in N/m")
    kv = patched({"contact.law": "kelvin-voigt", "contact.stiffness": "50 kN/mm"})
    assert close(parse_stack(kv).contact.default.stiffness, 5e7)
    assert_one_line_error(patched({"contact.stiffness": "1e9 N/m"}), "contact.stiffness", "Hertzian stiffness")


def test_law_specific_keys_are_rejected():
    hertz = patched({"contact.law": "hertz"})  # the normative restitution is then unused
    assert_one_line_error(hertz, "contact.restitution", "not used by law 'hertz'")
    tsuji = patched({"contact.calibration_velocity": "1 m/s"})
    assert_one_line_error(tsuji, "contact.calibration_velocity", "not used by law 'tsuji'")
    assert_one_line_error(patched({"contact.law": "hertzian"}), "contact.law", "'hertz'")
    assert_one_line_error(patched({"contact.restitution": DELETE}), "contact.restitution", "missing")
    assert_one_line_error(patched({"contact.clamp": "yes"}), "contact.clamp", "boolean")


# --------------------------------------------------------------------------------------------------
# Designs instead of masses
# --------------------------------------------------------------------------------------------------


def design(**keys) -> dict:
    return patched({"stack.masses": DELETE, "stack.design": {"kind": "mvg", **keys}})


def test_mvg_design_from_ratio_and_bottom_mass():
    spec = parse_stack(design(mass_ratio=0.012, bottom_mass="8.4 kg", restitution=0.8, n=6))
    d = spec.stack.design
    assert spec.stack.masses is None and spec.n == 6
    assert (d.kind, d.n, d.restitution, d.mass_ratio, d.bottom_mass) == ("mvg", 6, 0.8, 0.012, 8.4)
    assert close(d.top_mass, 8.4 * 0.012)  # R = m_n / m_1 (Eq 15)


def test_mvg_design_other_pairs_and_optimal_n():
    d = parse_stack(design(top_mass="100 g", bottom_mass="8.4 kg")).stack.design
    assert d.n is None  # "optimal" is the default
    assert close(d.mass_ratio, 0.1 / 8.4) and d.restitution == 0.8  # e from contact.restitution
    d = parse_stack(design(top_mass="0.25 lb", mass_ratio=0.02, n="optimal")).stack.design
    assert close(d.top_mass, 0.25 * 0.45359237) and close(d.bottom_mass, 0.25 * 0.45359237 / 0.02)
    spec = parse_stack(design(top_mass="100 g", bottom_mass="8.4 kg"))
    assert spec.n is None and spec.stack.gaps == 0.01
    with pytest.raises(ValueError):
        spec.initial_velocities()
    assert spec.initial_velocities(6) == (-1.0,) * 6


def test_met_design():
    d = parse_stack(patched({"stack.masses": DELETE, "stack.design": {"kind": "met", "n": 10, "bottom_mass": 8.4}})).stack.design
    assert d == DesignSpec("met", 10, 0.8, 8.4, None, None, restitution_given=False)  # e: contact.restitution
    d = parse_stack(design(kind="met", mass_ratio=0.1, bottom_mass=1.0)).stack.design
    assert d.n is None and close(d.top_mass, 0.1)
    err = design(kind="met", n=10, bottom_mass=8.4, mass_ratio=0.012)
    assert_one_line_error(err, "stack.design", "MET", "exactly one of bottom_mass, top_mass")


def test_design_errors():
    assert_one_line_error(design(mass_ratio=0.012), "stack.design", "two of bottom_mass, top_mass, mass_ratio")
    assert_one_line_error(design(mass_ratio=0.012, bottom_mass=8.4, top_mass=0.1), "stack.design", "two of")
    assert_one_line_error(design(mass_ratio=1.5, bottom_mass=8.4), "stack.design.mass_ratio", "(0, 1)")
    assert_one_line_error(design(top_mass=9, bottom_mass=8.4), "stack.design.top_mass", "lighter")
    assert_one_line_error(design(mass_ratio=0.01, bottom_mass=8.4, n=1), "stack.design.n", ">= 2")
    assert_one_line_error(design(mass_ratio=0.01, bottom_mass=8.4, n="best"), "stack.design.n", "'optimal'")
    assert_one_line_error(design(mass_ratio=0.01, bottom_mass="8.4 m"), "stack.design.bottom_mass", "a mass")
    assert_one_line_error(design(mass_ratio=0.01, bottom_mass=8.4, kind="mvp"), "stack.design.kind", "'mvg'")
    assert_one_line_error(design(mass_ratio=0.01, bottom_mass=8.4, restitution=1.2), "stack.design.restitution", "(0, 1]")
    both = patched({"stack.design": {"kind": "mvg", "mass_ratio": 0.01, "bottom_mass": 8.4}})
    assert_one_line_error(both, "stack.design", "stack.masses")
    gaps = design(mass_ratio=0.01, bottom_mass=8.4)
    gaps["stack"]["gaps"] = ["1 cm"] * 5
    assert_one_line_error(gaps, "stack.gaps", "optimal")
    no_e = design(mass_ratio=0.01, bottom_mass=8.4)
    no_e["contact"] = {"law": "tsuji", "stiffness": 1e9, "damping": 0.2}
    assert_one_line_error(no_e, "stack.design.restitution", "missing")
    ok = design(mass_ratio=0.01, bottom_mass=8.4, n=4)
    ok["stack"]["gaps"] = ["1 cm", "2 cm", "3 cm"]  # n known: a list of n-1 is fine
    assert parse_stack(ok).stack.gap_list(4) == pytest.approx((0.01, 0.02, 0.03), rel=REL)


# --------------------------------------------------------------------------------------------------
# Materials and geometry
# --------------------------------------------------------------------------------------------------


def test_materials_example():
    spec = load_stack_file(EXAMPLES / "steel_materials.toml")
    assert spec.stack.masses == pytest.approx((1.0, 0.4, 0.16), rel=REL)
    assert spec.stack.material == ("AISI 52100", "AISI 52100", "AISI 304")
    assert spec.stack.shape == ("sphere", "sphere", "flat")
    r = spec.stack.radius
    assert close(r[0], 0.05) and close(r[1], 0.03) and math.isinf(r[2])
    assert spec.contact.default.stiffness is None and spec.contact_for(0).stiffness is None
    assert spec.ground.material == "AISI 1045" and spec.ground.shape == "flat"
    m = spec.material("AISI 52100")
    assert close(m.youngs_modulus, 210e9) and m.poisson_ratio == 0.3 and close(m.density, 7810.0)
    assert spec.material("unobtainium") is None
    assert close(spec.drop.impact_velocity, math.sqrt(2 * G0 * 0.10))


def materials(**stack) -> dict:
    data = patched({"contact.stiffness": DELETE, "stack.material": "my steel"})
    data["stack"].update(stack)
    data["materials"] = {"my steel": {"youngs_modulus": "200 GPa", "poisson_ratio": 0.3}}
    return data


def test_materials_single_values_and_inline_material():
    spec = parse_stack(materials(radius="2 cm"))
    assert spec.stack.material == "my steel" and spec.stack.shape == "sphere" and close(spec.stack.radius, 0.02)
    assert spec.stack.material_list(6) == ("my steel",) * 6 and spec.stack.shape_list(6) == ("sphere",) * 6
    m = spec.materials[0]
    assert (m.name, m.youngs_modulus, m.poisson_ratio, m.density) == ("my steel", 2e11, 0.3, None)  # 200 GPa
    sphere_ground = materials(radius="2 cm")
    sphere_ground["ground"] = {"radius": "1 m"}
    assert parse_stack(sphere_ground).ground.shape == "sphere"


def test_materials_and_geometry_errors():
    assert_one_line_error(materials(), "stack.radius", "missing")
    assert_one_line_error(materials(shape="flat"), "contact.stiffness", "flat")
    assert_one_line_error(materials(shape="flat", radius="1 cm"), "stack.radius", "flat")
    assert_one_line_error(materials(shape="sphere", radius=math.inf), "stack.radius", "finite")
    assert_one_line_error(materials(radius=["1 cm"] * 5), "stack.radius", "5 entries, expected 6")
    shapes = ["sphere"] * 5 + ["flat"]
    assert_one_line_error(materials(shape=shapes, radius=["1 cm"] * 6), "stack.radius[5]", "flat")
    assert parse_stack(materials(shape=shapes, radius=["1 cm"] * 5 + [math.inf])).stack.radius[:5] == (0.01,) * 5
    assert_one_line_error(materials(radius="1 kg"), "stack.radius", "kilogram", "a length")
    assert_one_line_error(materials(radius="-1 cm"), "stack.radius", "> 0")
    no_material = patched({"contact.stiffness": DELETE})
    assert_one_line_error(no_material, "contact.stiffness", "missing", "stack.material")
    bad_nu = materials(radius="2 cm")
    bad_nu["materials"]["my steel"]["poisson_ratio"] = 0.7
    assert_one_line_error(bad_nu, 'materials."my steel".poisson_ratio', "(-1, 0.5]")
    bad_e = materials(radius="2 cm")
    bad_e["materials"]["my steel"]["youngs_modulus"] = "200 GN"
    assert_one_line_error(bad_e, 'materials."my steel".youngs_modulus', "a pressure")
    bad_ground = materials(radius="2 cm")
    bad_ground["ground"] = {"shape": "cone"}
    assert_one_line_error(bad_ground, "ground.shape", "'sphere'")
    kv = materials(radius="2 cm")
    kv["contact"] = {"law": "kelvin-voigt", "restitution": 0.8}
    assert_one_line_error(kv, "contact.stiffness", "kelvin-voigt")


# --------------------------------------------------------------------------------------------------
# A horizontal chain and a resting stack
# --------------------------------------------------------------------------------------------------


def test_horizontal_chain_example():
    spec = load_stack_file(EXAMPLES / "horizontal_chain.toml")
    assert not spec.has_ground and spec.ground is None and spec.contact.ground is None
    assert spec.drop.gravity == 0.0 and spec.drop.impact_velocity is None
    assert spec.stack.velocities == (1.0, 0.0, 0.0) and spec.initial_velocities() == (1.0, 0.0, 0.0)
    assert spec.stack.gaps == pytest.approx((2e-3, 1e-3), rel=REL)
    assert spec.contact_for(1).law == "hertz" and spec.contact_for(2).law == "kelvin-voigt"
    with pytest.raises(ValueError):
        spec.contact_for(0)


def horizontal(**drop) -> dict:
    return patched({"drop": {"ground": False, **drop}, "stack.velocities": [1, 0, 0, 0, 0, 0]})


def test_horizontal_chain_errors():
    assert parse_stack(horizontal()).drop.gravity == 0.0
    assert_one_line_error(horizontal(impact_velocity=1.0), "drop.impact_velocity", "drop.ground = false")
    assert_one_line_error(horizontal(height=1.0), "drop.height", "drop.ground = false")
    no_v = horizontal()
    del no_v["stack"]["velocities"]
    assert_one_line_error(no_v, "stack.velocities", "missing")
    short = horizontal()
    short["stack"]["velocities"] = [1, 0]
    assert_one_line_error(short, "stack.velocities", "2 entries, expected 6")
    bad_v = horizontal()
    bad_v["stack"]["velocities"][1] = "1 m"
    assert_one_line_error(bad_v, "stack.velocities[1]", "a velocity")
    ground = horizontal()
    ground["contact"]["ground"] = {"restitution": 0.5}
    assert_one_line_error(ground, "contact.ground", "drop.ground = false")
    ground = horizontal()
    ground["ground"] = {"material": "steel"}
    assert_one_line_error(ground, "ground", "drop.ground = false")
    assert_one_line_error(horizontal(ground="no"), "drop.ground", "boolean")


def test_resting_preloaded_stack():
    resting = {"stack.preload": True, "stack.gaps": 0, "drop.gravity": DELETE,
               "solver": {"solver": "dopri8", "dt_output": "1 us"}}
    spec = parse_stack(patched(resting))
    assert spec.stack.preload and spec.stack.gaps == 0.0 and spec.drop.gravity == G0
    assert spec.stack.masses == pytest.approx((8.4, 3.4683, 1.4320, 0.5913, 0.2441, 0.1008), rel=REL)
    assert close(spec.solver.dt_output, 1e-6) and spec.solver.solver == "dopri8"
    assert_one_line_error(patched({"stack.preload": True}), "stack.preload", "gaps")  # gaps = 1 cm
    zero_g = patched({"stack.preload": True, "stack.gaps": 0})  # normative gravity = 0
    assert_one_line_error(zero_g, "stack.preload", "gravity")


# --------------------------------------------------------------------------------------------------
# Solver
# --------------------------------------------------------------------------------------------------


def test_solver_settings():
    settings = {"solver": "tsit5", "rtol": 1e-10, "atol": 1e-12, "n_output": 4000, "t_max": "20 ms"}
    s = parse_stack(patched({"solver": settings})).solver
    assert (s.solver, s.rtol, s.atol, s.n_output, s.dt_output) == ("tsit5", 1e-10, 1e-12, 4000, None)
    assert close(s.t_max, 20e-3)
    s = parse_stack(patched({"solver": {"solver": "kvaerno5", "max_steps": 1000, "t_max": 0.5}})).solver
    assert (s.solver, s.max_steps, s.t_max, s.rtol) == ("kvaerno5", 1000, 0.5, None)
    assert_one_line_error(patched({"solver.n_output": 100, "solver.dt_output": "1 us"}), "solver.dt_output", "n_output")
    assert_one_line_error(patched({"solver.solver": "tsit"}), "solver.solver", "'tsit5'")
    assert_one_line_error(patched({"solver.rtol": 2}), "solver.rtol", "(0, 1)")
    assert_one_line_error(patched({"solver.max_steps": 10.5}), "solver.max_steps", "integer")
    assert_one_line_error(patched({"solver.t_max": "1 m"}), "solver.t_max", "a time")
    # free-flight steps: on by default, off on request, into the built solve's Tolerances
    from hertz_chain.builder import build

    assert s.flight_steps is True
    off = parse_stack(patched({"solver.flight_steps": False}))
    assert off.solver.flight_steps is False
    assert build(off).simulate_options["tolerances"].flight_steps is False
    assert_one_line_error(patched({"solver.flight_steps": "no"}), "solver.flight_steps", "true or false")
    # onsets met: on by default with Tolerances' window, off or another window on request
    assert s.land_onsets is True and s.onset_window is None
    assert build(parse_stack(patched({}))).simulate_options["tolerances"].land_onsets is True
    tol = build(parse_stack(patched({"solver.land_onsets": False, "solver.onset_window": 0.1}))).simulate_options["tolerances"]
    assert (tol.land_onsets, tol.onset_window) == (False, 0.1)
    assert_one_line_error(patched({"solver.land_onsets": 1}), "solver.land_onsets", "true or false")
    assert_one_line_error(patched({"solver.onset_window": 0}), "solver.onset_window", "(0, 1]")
    assert_one_line_error(patched({"solver.onset_window": "2 ms"}), "solver.onset_window", "plain number")
    assert_one_line_error(patched({"solver.n_output": 1}), "solver.n_output", ">= 2")


# --------------------------------------------------------------------------------------------------
# Bad input: one line, naming the dotted key
# --------------------------------------------------------------------------------------------------


def test_wrong_units_message_is_exact():
    message = error_of(patched({"stack.gaps": "1 kg"}))
    assert message == "stack.gaps: '1 kg' has units of kilogram, expected a length (e.g. '1 cm')"


BAD = [
    # unknown keys, with the closest suggestion
    ({"drop.impact_velocty": "1 m/s"}, "drop.impact_velocty", ["unknown key", "'impact_velocity'"]),
    ({"stack.mass": [1, 2]}, "stack.mass", ["unknown key", "'masses'"]),
    ({"contact.stifness": 1e9}, "contact.stifness", ["'stiffness'"]),
    ({"solvr": {"rtol": 1e-6}}, "solvr", ["'solver'"]),
    ({"solver.zzz": 1}, "solver.zzz", ["unknown key", "allowed:"]),
    # missing fields
    ({"stack.masses": DELETE}, "stack.masses", ["missing"]),
    ({"stack.gaps": DELETE}, "stack.gaps", ["missing"]),
    ({"contact.law": DELETE}, "contact.law", ["missing"]),
    ({"contact": DELETE}, "contact", ["missing"]),
    ({"stack": DELETE}, "stack", ["missing"]),
    ({"contact.stiffness": DELETE}, "contact.stiffness", ["missing"]),
    # units and numbers
    ({"stack.gaps": "1 blarg"}, "stack.gaps", ["cannot parse", "'1 blarg'", "a length"]),
    ({"stack.gaps": "1 cm +"}, "stack.gaps", ["cannot parse"]),
    ({"stack.gaps": ""}, "stack.gaps", ["empty"]),
    ({"stack.gaps": True}, "stack.gaps", ["boolean"]),
    ({"stack.gaps": "-1 mm"}, "stack.gaps", [">= 0"]),
    ({"stack.gaps": math.nan}, "stack.gaps", ["finite"]),
    ({"stack.gaps": {"a": 1}}, "stack.gaps", ["a table"]),
    ({"drop.impact_velocity": "1 m"}, "drop.impact_velocity", ["units of meter", "a velocity"]),
    ({"drop.impact_velocity": "-1 m/s"}, "drop.impact_velocity", [">= 0"]),
    ({"contact.stiffness": "1e9 N/m^2"}, "contact.stiffness", ["N/m^1.5"]),
    ({"contact.stiffness": 0}, "contact.stiffness", ["> 0"]),
    ({"contact.stiffness": math.inf}, "contact.stiffness", ["finite"]),
    # masses
    ({"stack.masses": [8.4, -1.0, 0.5]}, "stack.masses[1]", ["> 0"]),
    ({"stack.masses": [8.4, 0, 0.5]}, "stack.masses[1]", ["> 0"]),
    ({"stack.masses": [8.4, "1 m"]}, "stack.masses[1]", ["a mass"]),
    ({"stack.masses": []}, "stack.masses", ["at least 1"]),
    ({"stack.masses": 8.4}, "stack.masses", ["a list"]),
    # list lengths
    ({"stack.gaps": ["1 cm"] * 4}, "stack.gaps", ["4 entries, expected 5"]),
    ({"stack.gaps": ["1 cm"] * 6}, "stack.gaps", ["6 entries, expected 5"]),
    ({"stack.gaps": ["1 cm", "1 kg", 0, 0, 0]}, "stack.gaps[1]", ["a length"]),
    # the initial state
    ({"drop.height": "5 cm"}, "drop.height", ["conflicts with drop.impact_velocity"]),
    ({"drop.impact_velocity": DELETE}, "drop.impact_velocity", ["missing", "drop.height"]),
    # restitution
    ({"contact.restitution": 0}, "contact.restitution", ["(0, 1]"]),
    ({"contact.restitution": 1.01}, "contact.restitution", ["(0, 1]"]),
    ({"contact.restitution": "0.8 m"}, "contact.restitution", ["a plain number"]),
    ({"contact.ground": {"restitution": 0}}, "contact.ground.restitution", ["(0, 1]"]),
    # kinds of values
    ({"drop": 5}, "drop", ["expected a table"]),
    ({"title": 5}, "title", ["not a string"]),
]


@pytest.mark.parametrize(("changes", "key", "fragments"), BAD, ids=[case[1] + "-" + str(i) for i, case in enumerate(BAD)])
def test_bad_input_names_the_key(changes, key, fragments):
    assert_one_line_error(patched(changes), key, *fragments)


def test_broken_toml_reports_line_and_column():
    broken = NORMATIVE.replace('gaps = "1 cm"', "gaps = 1 cm")  # line 7
    message = error_of(broken)
    assert "\n" not in message
    assert message.startswith("invalid TOML: ") and "line 7, column" in message


def test_file_errors_name_the_file(tmp_path):
    path = tmp_path / "stack.toml"
    path.write_text(NORMATIVE.replace('gaps = "1 cm"', 'gaps = "1 kg"'))
    with pytest.raises(StackFileError) as info:
        load_stack_file(path)
    assert str(info.value) == f"{path}: stack.gaps: '1 kg' has units of kilogram, expected a length (e.g. '1 cm')"
    assert info.value.key == "stack.gaps"
    path.write_text("[drop\n")
    with pytest.raises(StackFileError, match=r"invalid TOML: .*line 1, column"):
        load_stack_file(path)
    with pytest.raises(StackFileError, match="no such stack file"):
        load_stack_file(tmp_path / "missing.toml")
    path.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(StackFileError, match="UTF-8"):
        load_stack_file(path)


def test_not_text_nor_dict():
    with pytest.raises(StackFileError, match="TOML text or a dict"):
        parse_stack(42)


# --------------------------------------------------------------------------------------------------
# Units: round trips (definitions: SI prefixes; inch = 0.0254 m, ft = 0.3048 m, yd = 0.9144 m,
# mile = 1609.344 m, exact since the 1959 international yard and pound agreement)
# --------------------------------------------------------------------------------------------------

LENGTHS = {
    "m": 1.0,
    "meter": 1.0,
    "km": 1e3,
    "cm": 1e-2,
    "mm": 1e-3,
    "um": 1e-6,
    "micrometer": 1e-6,
    "nm": 1e-9,
    "inch": 0.0254,
    "ft": 0.3048,
    "yard": 0.9144,
    "mile": 1609.344,
}


@settings(max_examples=200, deadline=None)
@given(
    value=st.floats(min_value=1e-6, max_value=1e6, allow_nan=False, allow_infinity=False),
    unit=st.sampled_from(sorted(LENGTHS)),
    spaced=st.booleans(),
)
def test_lengths_round_trip_to_metres(value, unit, spaced):
    text = f"{value!r}{' ' if spaced else ''}{unit}"  # e.g. "12.5 cm", "3e-05inch"
    assert close(parse_quantity(text, "length", "stack.gaps"), value * LENGTHS[unit])
    spec = parse_stack(patched({"stack.gaps": text}))
    assert close(spec.stack.gaps, value * LENGTHS[unit])


@settings(max_examples=50, deadline=None)
@given(value=st.floats(min_value=1e-3, max_value=1e3), unit=st.sampled_from(["kg", "g", "lb", "mg"]))
def test_masses_round_trip_to_kilograms(value, unit):
    factor = {"kg": 1.0, "g": 1e-3, "lb": 0.45359237, "mg": 1e-6}[unit]
    spec = parse_stack(patched({"stack.masses": [f"{value!r} {unit}", 1.0]}))
    assert close(spec.stack.masses[0], value * factor)


def test_parse_quantity_accepts_pint_quantities_and_bare_numbers():
    from hertz_chain.units import _ureg

    q = _ureg().Quantity(3.0, "mm")
    assert close(parse_quantity(q, "length"), 3e-3)
    assert parse_quantity(2.5, "length") == 2.5  # bare numbers are SI
    assert parse_quantity("0.5", "length") == 0.5  # a unitless string too
    assert close(parse_quantity("50 percent", "dimensionless"), 0.5)
    assert close(parse_quantity("1e9 N/m^1.5", "hertz_stiffness"), 1e9)
    assert close(parse_quantity("1 kN/mm^1.5", "hertz_stiffness"), 1e3 / (1e-3) ** 1.5)
    with pytest.raises(StackFileError, match="^x: "):
        parse_quantity(_ureg().Quantity(1.0, "s"), "length", "x")


def test_bodies_helpers():
    b = StackSectionSpec(masses=(1.0, 0.5, 0.25), design=None, gaps=0.01)
    assert b.n == 3 and b.gap_list(3) == (0.01, 0.01) and b.radius_list(3) is None
    with pytest.raises(ValueError):
        StackSectionSpec(masses=(1.0, 0.5), design=None, gaps=(0.1, 0.2)).gap_list(2)


@pytest.mark.parametrize("broken", ["file", "garbage"])
def test_unit_registry_cache_never_stops_a_run(tmp_path, broken):
    """pint's parsed-definitions cache (`~/.cache/hertz_chain/pint`) is an optimisation only: a cache
    root that is a plain file, or a cache folder full of garbage, must still parse "1 cm" to 0.01 m."""
    code = "from hertz_chain.stackfile import parse_quantity; print(parse_quantity('1 cm', 'length'))"
    env = {**__import__("os").environ, "XDG_CACHE_HOME": str(tmp_path)}
    env.pop("HERTZ_CHAIN_NO_CACHE", None)
    env.pop("HERTZ_CHAIN_CACHE_DIR", None)  # the test session's own cache folder (conftest.py)
    if broken == "file":
        (tmp_path / "hertz_chain").write_text("not a folder")
    else:  # a real cache, written by a first run, then every file in it damaged
        subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True, timeout=120)
        files = list((tmp_path / "hertz_chain" / "pint").iterdir())
        assert files
        for f in files:
            f.write_bytes(b"\x00garbage")
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert float(proc.stdout) == 0.01  # 1 cm = 0.01 m exactly (SI definition)


def test_every_key_the_parser_accepts_is_in_the_manual():
    # docs/stack-files.md is the user manual: every key of every section the parser accepts (its own
    # tables of allowed keys) appears there as a dotted key or a `key` entry
    from pathlib import Path

    from hertz_chain import _stackspec as sf

    manual = (Path(__file__).resolve().parents[1] / "docs" / "stack-files.md").read_text()
    sections = {"drop": sf._DROP_KEYS, "stack": sf._STACK_KEYS, "stack.design": sf._DESIGN_KEYS,
                "ground": sf._GROUND_KEYS, "contact": sf._CONTACT_KEYS, "solver": sf._SOLVER_KEYS,
                "materials": sf._MATERIAL_KEYS, "wall": sf._WALL_KEYS, "srs": sf._SRS_KEYS, "": sf._TOP_KEYS}
    missing = [f"{sec}.{key}" if sec else key for sec, keys in sections.items() for key in keys
               if not any(form in manual for form in (f"`{sec}.{key}`", f"`{key}`", f"[{key}]", f"[{sec}.{key}]",
                                                      f"[[{key}]]", f"[{key}.NAME]"))]
    assert not missing, missing


# --------------------------------------------------------------------------------------------------
# [srs] and one-mass files
# --------------------------------------------------------------------------------------------------


def test_srs_section():
    spec = parse_stack(patched({"srs.damping": 0.05, "srs.per_octave": 3, "srs.band": ["100 Hz", "10 kHz"],
                                "srs.peak": "neg", "srs.type": "pseudo-velocity"}))
    assert spec.srs.q == pytest.approx(10.0, rel=1e-15)  # Q = 1/(2 zeta)
    assert (spec.srs.per_octave, spec.srs.band, spec.srs.peak, spec.srs.type) == (3, (100.0, 1e4), "neg",
                                                                                    "pseudo-velocity")
    assert parse_stack(base()).srs.q == 10.0  # the default: Q = 10, maximax acceleration


@pytest.mark.parametrize("changes, key, fragment", [
    ({"srs.q": 0.3}, "srs.q", "0.5"),
    ({"srs.q": 10, "srs.damping": 0.05}, "srs.damping", "conflicts"),
    ({"srs.damping": 1.5}, "srs.damping", "(0, 1)"),
    ({"srs.band": ["10 kHz", "100 Hz"]}, "srs.band", "f_min < f_max"),
    ({"srs.band": ["1 m", "2 m"]}, "srs.band[0]", "frequency"),
    ({"srs.band": "1 kHz"}, "srs.band", "pair"),
    ({"srs.peak": "max"}, "srs.peak", "'abs'"),
    ({"srs.type": "velocity"}, "srs.type", "pseudo-velocity"),
    ({"srs.per_octave": 100}, "srs.per_octave", "48"),
    ({"srs.band": ["1 Hz", "1 GHz"]}, "srs.band", "5 decades"),
    ({"srs.band": ["1e-6 Hz", "100 Hz"]}, "srs.band", "[0.01 Hz, 1e+07 Hz]"),
    ({"srs.window": 1}, "srs.window", "unknown"),
])
def test_srs_section_errors(changes, key, fragment):
    assert_one_line_error(patched(changes), key, fragment)


def test_one_mass_needs_no_gaps():
    spec = parse_stack({"drop": {"impact_velocity": "1 m/s"}, "stack": {"masses": ["0.1 kg"]},
                        "contact": {"law": "hertz", "stiffness": "1e9 N/m^1.5"}})
    assert spec.n == 1 and spec.stack.gap_list(1) == ()


def test_set_of_an_alternative_key_replaces_the_files_other():
    """`--set srs.q=20` on a file with srs.damping (and height for impact_velocity) replaces it, as
    editing the file would; both given on the command line still conflict."""
    from hertz_chain.stackfile import apply_overrides

    doc = {"drop": {"impact_velocity": "1 m/s"}, "srs": {"damping": 0.05}}
    out = apply_overrides(doc, ["srs.q=20", "drop.height=\"5 cm\""])
    assert out == {"drop": {"height": "5 cm"}, "srs": {"q": 20}}
    assert doc == {"drop": {"impact_velocity": "1 m/s"}, "srs": {"damping": 0.05}}  # the input untouched
    both = apply_overrides(doc, ["srs.q=20", "srs.damping=0.1"])
    assert both["srs"] == {"q": 20, "damping": 0.1}
    with pytest.raises(StackFileError, match="conflicts"):
        parse_stack(patched({"srs.q": 20, "srs.damping": 0.1}))
