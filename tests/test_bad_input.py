"""A catalogue of bad and extreme inputs: stack files, command-line flags, output paths, API calls.

Every row checks the contract of issue 16: the command line exits with status 2 (`EXIT_BAD_INPUT`) and
writes exactly one line to stderr, `hertz-chain: error: ...`, naming the key or flag; the library
raises a specific `HertzChainError` subclass; nothing prints a traceback or hangs. Most rows run
in-process (`hertz_chain.cli.main(argv)`); `SUBPROCESS` rows run the real executable with a timeout.

Expected numbers are the documented bounds, imported by name: `MAX_MASSES` (hertz_chain.constants),
`MAX_STEPS`, `MAX_OUTPUT_POINTS`, `MIN_DT_OUTPUT`, `MIN_RESTITUTION`, `LIMITS`, `DAMPING_LIMITS`,
`MAX_FILE_BYTES`, `MAX_QUANTITY_LENGTH` (hertz_chain.stackfile; docs/stack-files.md, "Physical ranges
and sizes"), and `NAME_MAX_FALLBACK` / `os.pathconf(..., "PC_NAME_MAX")` (hertz_chain._paths).
"""

from __future__ import annotations

from _helpers import DELETE
from _helpers import patched as _patched
import os
import subprocess
import sys
import threading
import tomllib
from pathlib import Path

import pytest
import tomli_w

from hertz_chain import _paths, cli
from hertz_chain.constants import MAX_MASSES
from hertz_chain.errors import HertzChainError, OutputPathError, ParameterError, StackFileError
from hertz_chain.status import EXIT_BAD_INPUT, Status
from hertz_chain.stackfile import (
    DAMPING_LIMITS,
    LIMITS,
    MAX_FILE_BYTES,
    MAX_OUTPUT_POINTS,
    MAX_QUANTITY_LENGTH,
    MAX_STEPS,
    MIN_DT_OUTPUT,
    MIN_RESTITUTION,
    load_stack_file,
    parse_quantity,
    parse_stack,
)

ROOT = Path(__file__).resolve().parents[1]
NORMATIVE_TEXT = (ROOT / "examples" / "issue5_normative.toml").read_text(encoding="utf-8")
NORMATIVE = tomllib.loads(NORMATIVE_TEXT)
EXE = Path(sys.executable).with_name("hertz-chain")
M_LO, M_HI = LIMITS["mass"]
V_HI = LIMITS["velocity"][1]
L_HI = LIMITS["length"][1]
T_HI = LIMITS["time"][1]
INF, NAN = float("inf"), float("nan")


def patched(changes: dict) -> dict:
    """The normative example (issue #5) with dotted keys set (`DELETE` removes one)."""
    return _patched(NORMATIVE, changes)


NO_V = {"drop.impact_velocity": DELETE}
NO_E = {"contact.restitution": DELETE}
DESIGN = {"stack.masses": DELETE}
GEOM = {"contact.stiffness": DELETE, "stack.material": "AISI 52100"}


def design(**kw) -> dict:
    return {**DESIGN, "stack.design": kw}


# ------------------------------------------------------------------------------------------ files
# (id, changes to the normative example, the key the one-line message must name)
FILE_ROWS = [
    # masses: overflow, pint powers, non-finite, wrong kind, count
    ("mass_1e308", {"stack.masses": [1e308, 1e308]}, "stack.masses[0]"),
    ("mass_above_range", {"stack.masses": [M_HI * 2, 1.0]}, "stack.masses[0]"),
    ("mass_below_range", {"stack.masses": [1.0, M_LO / 10]}, "stack.masses[1]"),
    ("mass_1e-300", {"stack.masses": [1e-300, 1e-300]}, "stack.masses[0]"),
    ("mass_pow_10_400", {"stack.masses": ["10**400 kg", 1]}, "stack.masses[0]"),
    ("mass_pow_tower", {"stack.masses": ["10**10**10 kg", 1]}, "stack.masses[0]"),
    ("mass_caret_tower", {"stack.masses": ["9^9^9 kg", 1]}, "stack.masses[0]"),
    ("mass_pow_paren", {"stack.masses": ["10**(10**10) kg", 1]}, "stack.masses[0]"),
    ("mass_1e400_string", {"stack.masses": ["1e400 kg", 1]}, "stack.masses[0]"),
    ("mass_product_overflow", {"stack.masses": ["1e308*10 kg", 1]}, "stack.masses[0]"),
    ("mass_negative", {"stack.masses": [-1, 1]}, "stack.masses[0]"),
    ("mass_zero", {"stack.masses": [1, 0]}, "stack.masses[1]"),
    ("mass_nan_string", {"stack.masses": ["nan kg", 1]}, "stack.masses[0]"),
    ("mass_inf_string", {"stack.masses": ["inf kg", 1]}, "stack.masses[0]"),
    ("mass_nan_float", {"stack.masses": [NAN, 1]}, "stack.masses[0]"),
    ("mass_inf_float", {"stack.masses": [1, INF]}, "stack.masses[1]"),
    ("mass_wrong_unit", {"stack.masses": ["1 m", 1]}, "stack.masses[0]"),
    ("mass_bool", {"stack.masses": [True, 1]}, "stack.masses[0]"),
    ("mass_word", {"stack.masses": ["heavy", 1]}, "stack.masses[0]"),
    ("mass_list", {"stack.masses": [[1], 1]}, "stack.masses[0]"),
    ("mass_table", {"stack.masses": [{"a": 1}, 1]}, "stack.masses[0]"),
    ("mass_empty_string", {"stack.masses": ["", 1]}, "stack.masses[0]"),
    ("mass_long_string", {"stack.masses": ["1" * (MAX_QUANTITY_LENGTH + 1) + " kg", 1]}, "stack.masses[0]"),
    ("masses_none", {"stack.masses": []}, "stack.masses"),
    ("masses_too_many", {"stack.masses": [1.0] * (MAX_MASSES + 1), "stack.gaps": 0}, "stack.masses"),
    ("masses_million", {"stack.masses": [1.0] * 1_000_000, "stack.gaps": 0}, "stack.masses"),
    ("masses_not_list", {"stack.masses": "1 kg"}, "stack.masses"),
    # gaps
    ("gap_1e308", {"stack.gaps": 1e308}, "stack.gaps"),
    ("gap_above_range", {"stack.gaps": L_HI * 10}, "stack.gaps"),
    ("gap_negative", {"stack.gaps": "-1 cm"}, "stack.gaps"),
    ("gap_wrong_unit", {"stack.gaps": "1 kg"}, "stack.gaps"),
    ("gap_count", {"stack.gaps": [0.01] * 3}, "stack.gaps"),
    ("gap_nan", {"stack.gaps": "nan m"}, "stack.gaps"),
    ("gap_inf", {"stack.gaps": INF}, "stack.gaps"),
    ("gap_bool", {"stack.gaps": True}, "stack.gaps"),
    ("gaps_missing", {"stack.gaps": DELETE}, "stack.gaps"),
    # initial velocities
    ("velocities_1e300", {**NO_V, "stack.velocities": [-1e300] * 6}, "stack.velocities[0]"),
    ("velocities_above_range", {**NO_V, "stack.velocities": [0, 0, 0, 0, 0, V_HI * 2]}, "stack.velocities[5]"),
    ("velocities_count", {**NO_V, "stack.velocities": [-1] * 5}, "stack.velocities"),
    ("velocities_not_list", {**NO_V, "stack.velocities": "1 m/s"}, "stack.velocities"),
    ("velocities_unit", {**NO_V, "stack.velocities": ["1 kg"] * 6}, "stack.velocities[0]"),
    ("velocities_and_drop", {"stack.velocities": [-1] * 6}, "stack.velocities"),
    # the drop
    ("impact_1e300", {"drop.impact_velocity": 1e300}, "drop.impact_velocity"),
    ("impact_1e300_string", {"drop.impact_velocity": "1e300 m/s"}, "drop.impact_velocity"),
    ("impact_above_range", {"drop.impact_velocity": V_HI * 1.5}, "drop.impact_velocity"),
    ("impact_negative", {"drop.impact_velocity": -1}, "drop.impact_velocity"),
    ("impact_unit", {"drop.impact_velocity": "1 kg"}, "drop.impact_velocity"),
    ("impact_nan", {"drop.impact_velocity": "nan m/s"}, "drop.impact_velocity"),
    ("impact_pow", {"drop.impact_velocity": "10**400 m/s"}, "drop.impact_velocity"),
    ("impact_c", {"drop.impact_velocity": "1 c"}, "drop.impact_velocity"),  # the speed of light
    ("height_1e300", {**NO_V, "drop.gravity": DELETE, "drop.height": 1e300}, "drop.height"),
    # a height inside the length range whose free fall sqrt(2 g h) exceeds the velocity range
    ("height_too_fast", {**NO_V, "drop.gravity": DELETE, "drop.height": (V_HI * 2) ** 2 / (2 * 9.80665)},
     "drop.height"),
    ("height_without_gravity", {**NO_V, "drop.height": "5 cm"}, "drop.height"),
    ("height_and_velocity", {"drop.height": "5 cm"}, "drop.height"),
    ("gravity_1e308", {"drop.gravity": 1e308}, "drop.gravity"),
    ("gravity_negative", {"drop.gravity": -9.8}, "drop.gravity"),
    ("gravity_unit", {"drop.gravity": "9.8 m/s"}, "drop.gravity"),
    ("ground_not_bool", {"drop.ground": "yes"}, "drop.ground"),
    ("drop_misspelt", {"drop.heigth": "5 cm"}, "drop.heigth"),
    ("drop_missing_state", {**NO_V}, "drop.impact_velocity"),
    # contact stiffness and damping
    ("stiffness_1e308", {"contact.stiffness": 1e308}, "contact.stiffness"),
    ("stiffness_1e308_string", {"contact.stiffness": "1e308 N/m^1.5"}, "contact.stiffness"),
    ("stiffness_negative", {"contact.stiffness": -1}, "contact.stiffness"),
    ("stiffness_zero", {"contact.stiffness": 0}, "contact.stiffness"),
    ("stiffness_wrong_unit", {"contact.stiffness": "1e9 N/m"}, "contact.stiffness"),
    ("tsuji_damping_1e300", {**NO_E, "contact.damping": 1e300}, "contact.damping"),
    ("tsuji_damping_above", {**NO_E, "contact.damping": DAMPING_LIMITS["tsuji"][0] * 10}, "contact.damping"),
    ("tsuji_damping_negative", {**NO_E, "contact.damping": -1}, "contact.damping"),
    ("visco_damping_1e6_s", {**NO_E, "contact.law": "viscoelastic", "contact.damping": "1e6 s"},
     "contact.damping"),
    ("visco_damping_above", {**NO_E, "contact.law": "viscoelastic",
                             "contact.damping": f"{DAMPING_LIMITS['viscoelastic'][0] * 10} s"}, "contact.damping"),
    ("visco_damping_unit", {**NO_E, "contact.law": "viscoelastic", "contact.damping": "1 kg"}, "contact.damping"),
    ("kv_damping_1e300", {**NO_E, "contact.law": "kelvin-voigt", "contact.stiffness": "1e7 N/m",
                          "contact.damping": "1e300 N*s/m"}, "contact.damping"),
    ("kv_stiffness_1e308", {"contact.law": "kelvin-voigt", "contact.stiffness": "1e308 N/m"}, "contact.stiffness"),
    ("hc_alpha_1e300", {**NO_E, "contact.law": "hunt-crossley", "contact.alpha": 1e300}, "contact.alpha"),
    ("hc_alpha_negative", {**NO_E, "contact.law": "hunt-crossley", "contact.alpha": "-1 s/m"}, "contact.alpha"),
    ("hc_calibration_1e300", {"contact.law": "hunt-crossley", "contact.calibration_velocity": 1e300},
     "contact.calibration_velocity"),
    ("hc_calibration_negative", {"contact.law": "hunt-crossley", "contact.calibration_velocity": -1},
     "contact.calibration_velocity"),
    ("hc_chi_map", {"contact.law": "hunt-crossley", "contact.chi_map": "magic"}, "contact.chi_map"),
    ("restitution_1e-300", {"contact.restitution": 1e-300}, "contact.restitution"),
    ("restitution_below_floor", {"contact.restitution": MIN_RESTITUTION / 2}, "contact.restitution"),
    ("restitution_zero", {"contact.restitution": 0}, "contact.restitution"),
    ("restitution_above_one", {"contact.restitution": 1.5}, "contact.restitution"),
    ("restitution_nan", {"contact.restitution": NAN}, "contact.restitution"),
    ("restitution_unit", {"contact.restitution": "0.8 m"}, "contact.restitution"),
    ("restitution_bool", {"contact.restitution": True}, "contact.restitution"),
    ("restitution_word", {"contact.restitution": "high"}, "contact.restitution"),
    ("law_misspelt", {"contact.law": "tsujii"}, "contact.law"),
    ("law_number", {"contact.law": 5}, "contact.law"),
    ("clamp_not_bool", {"contact.clamp": "no"}, "contact.clamp"),
    ("contact_unknown_key", {"contact.stifness": 1e9}, "contact.stifness"),
    ("contact_missing", {"contact": DELETE}, "contact"),
    ("ground_restitution_active", {"contact.ground": {"restitution": 1.2}}, "contact.ground.restitution"),
    ("interface_index_zero", {"contact.interface": [{"index": 0, "restitution": 0.5}]}, "contact.interface[0].index"),
    ("interface_index_million", {"contact.interface": [{"index": 1_000_000, "restitution": 0.5}]},
     "contact.interface[0].index"),
    ("interface_index_int64", {"contact.interface": [{"index": 2**63 - 1, "restitution": 0.5}]},
     "contact.interface[0].index"),
    ("interface_index_beyond_n", {"contact.interface": [{"index": 9, "restitution": 0.5}]},
     "contact.interface[0].index"),
    ("interface_index_word", {"contact.interface": [{"index": "one", "restitution": 0.5}]},
     "contact.interface[0].index"),
    ("interface_index_empty", {"contact.interface": [{"index": [], "restitution": 0.5}]},
     "contact.interface[0].index"),
    ("interface_index_missing", {"contact.interface": [{"restitution": 0.5}]}, "contact.interface[0].index"),
    ("interface_stiffness_1e308", {"contact.interface": [{"index": 1, "stiffness": 1e308}]},
     "contact.interface[0].stiffness"),
    # solver sizes
    ("max_steps_1e8", {"solver.max_steps": 10**8}, "solver.max_steps"),
    # 50 masses x 2e6 steps: 8 (2e6 + 1)(11 x 50 + 2) bytes = 8.2 GiB of step history > MAX_RUN_MEMORY
    ("max_steps_memory", {"stack.masses": [1.0] * 50, "stack.gaps": 0, "solver.max_steps": 2_000_000},
     "solver.max_steps"),
    ("max_steps_above", {"solver.max_steps": MAX_STEPS + 1}, "solver.max_steps"),
    ("max_steps_1e300", {"solver.max_steps": 1e300}, "solver.max_steps"),
    ("max_steps_int64", {"solver.max_steps": 2**63 - 1}, "solver.max_steps"),
    ("max_steps_zero", {"solver.max_steps": 0}, "solver.max_steps"),
    ("max_steps_negative", {"solver.max_steps": -5}, "solver.max_steps"),
    ("max_steps_fraction", {"solver.max_steps": 10.5}, "solver.max_steps"),
    ("max_steps_word", {"solver.max_steps": "many"}, "solver.max_steps"),
    ("max_steps_inf", {"solver.max_steps": INF}, "solver.max_steps"),
    ("max_steps_nan", {"solver.max_steps": NAN}, "solver.max_steps"),
    ("n_output_above", {"solver.n_output": MAX_OUTPUT_POINTS + 1}, "solver.n_output"),
    ("n_output_1e7", {"solver.n_output": 10**7}, "solver.n_output"),
    ("n_output_int64", {"solver.n_output": 2**63 - 1}, "solver.n_output"),
    ("n_output_one", {"solver.n_output": 1}, "solver.n_output"),
    ("n_output_fraction", {"solver.n_output": 1.5}, "solver.n_output"),
    ("dt_output_tiny", {"solver.dt_output": MIN_DT_OUTPUT / 10}, "solver.dt_output"),
    ("dt_output_1e-12", {"solver.dt_output": 1e-12}, "solver.dt_output"),
    ("dt_output_vs_t_max", {"solver.t_max": 1.0, "solver.dt_output": 1.0 / (MAX_OUTPUT_POINTS * 10)},
     "solver.dt_output"),
    ("dt_output_negative", {"solver.dt_output": -1}, "solver.dt_output"),
    ("dt_output_unit", {"solver.dt_output": "1 m"}, "solver.dt_output"),
    ("dt_and_n_output", {"solver.dt_output": "1 us", "solver.n_output": 100}, "solver.dt_output"),
    ("t_max_1e300", {"solver.t_max": 1e300}, "solver.t_max"),
    ("t_max_above", {"solver.t_max": T_HI * 10}, "solver.t_max"),
    ("t_max_negative", {"solver.t_max": -1}, "solver.t_max"),
    ("t_max_unit", {"solver.t_max": "1 kg"}, "solver.t_max"),
    ("rtol_zero", {"solver.rtol": 0}, "solver.rtol"),
    ("rtol_two", {"solver.rtol": 2}, "solver.rtol"),
    ("rtol_nan", {"solver.rtol": NAN}, "solver.rtol"),
    ("atol_negative", {"solver.atol": -1}, "solver.atol"),
    ("solver_unknown", {"solver.solver": "rk4"}, "solver.solver"),
    ("solver_misspelt_key", {"solver.rtool": 1e-10}, "solver.rtool"),
    # designs
    ("design_n_million", design(kind="mvg", n=1_000_000, mass_ratio=0.012, bottom_mass=8.4), "stack.design.n"),
    ("design_n_int64", design(kind="mvg", n=2**63 - 1, mass_ratio=0.012, bottom_mass=8.4), "stack.design.n"),
    ("design_n_above", design(kind="mvg", n=MAX_MASSES + 1, mass_ratio=0.012, bottom_mass=8.4), "stack.design.n"),
    ("design_n_1e300", design(kind="mvg", n=1e300, mass_ratio=0.012, bottom_mass=8.4), "stack.design.n"),
    ("design_n_word", design(kind="mvg", n="best", mass_ratio=0.012, bottom_mass=8.4), "stack.design.n"),
    ("design_optimal_mvg_too_long", design(kind="mvg", mass_ratio=1e-300, bottom_mass=1, restitution=0.95),
     "stack.design.n"),
    ("design_optimal_met_too_long", design(kind="met", mass_ratio=1e-300, bottom_mass=1), "stack.design.n"),
    ("design_met_mass_below_range", design(kind="met", n=MAX_MASSES, bottom_mass=1, restitution=0.3),
     "stack.design"),
    ("design_mvg_derived_mass_above", design(kind="mvg", n=6, mass_ratio=1e-9, top_mass=1), "stack.design"),
    ("design_kind", design(kind="best", mass_ratio=0.012, bottom_mass=8.4), "stack.design.kind"),
    ("design_bottom_1e308", design(kind="mvg", mass_ratio=0.012, bottom_mass=1e308), "stack.design.bottom_mass"),
    ("design_top_pow", design(kind="mvg", mass_ratio=0.012, top_mass="10**400 kg"), "stack.design.top_mass"),
    ("design_ratio_above_one", design(kind="mvg", mass_ratio=1.5, bottom_mass=8.4), "stack.design.mass_ratio"),
    ("design_ratio_nan", design(kind="mvg", mass_ratio=NAN, bottom_mass=8.4), "stack.design.mass_ratio"),
    ("design_optimal_e_one", design(kind="mvg", mass_ratio=0.1, bottom_mass=1, restitution=1),
     "stack.design.restitution"),
    # materials and geometry
    ("radius_1e300", {**GEOM, "stack.radius": 1e300}, "stack.radius"),
    ("radius_negative", {**GEOM, "stack.radius": "-1 cm"}, "stack.radius"),
    ("radius_count", {**GEOM, "stack.radius": ["1 cm"] * 3}, "stack.radius"),
    ("shape_cube", {**GEOM, "stack.radius": "1 cm", "stack.shape": "cube"}, "stack.shape"),
    ("material_not_name", {**GEOM, "stack.radius": "1 cm", "stack.material": 5}, "stack.material"),
    ("youngs_1e300", {"materials": {"x": {"youngs_modulus": 1e300, "poisson_ratio": 0.3}}},
     "materials.x.youngs_modulus"),
    ("poisson_above", {"materials": {"x": {"youngs_modulus": "200 GPa", "poisson_ratio": 0.7}}},
     "materials.x.poisson_ratio"),
    ("density_1e300", {"materials": {"x": {"youngs_modulus": "200 GPa", "poisson_ratio": 0.3, "density": 1e300}}},
     "materials.x.density"),
    ("ground_radius_1e300", {"ground": {"radius": 1e300}}, "ground.radius"),
    ("preload_not_bool", {"stack.preload": "yes"}, "stack.preload"),
    ("title_number", {"title": 5}, "title"),
    ("top_level_misspelt", {"solverr": {}}, "solverr"),
    ("stack_missing", {"stack": DELETE}, "stack"),
]

# (id, file bytes, a fragment of the message)
RAW_ROWS = [
    ("broken_toml", b"[drop\nimpact_velocity = 1\n", "invalid TOML"),
    ("bom_then_broken", b"\xef\xbb\xbf[drop\n", "invalid TOML"),
    ("not_utf8", b"\xff\xfe\x00\x01 binary \x80\x81", "UTF-8"),
    ("nul_bytes", b"[drop]\x00\x00\nimpact_velocity = 1\n", "invalid TOML"),
    ("empty_file", b"", "contact"),
    ("deep_nesting", b"a = " + b"[" * 100_000 + b"]" * 100_000 + b"\n", "nested too deeply"),
    ("duplicate_key", b"[drop]\ngravity = 0\ngravity = 1\n", "invalid TOML: Cannot overwrite a value (at line 3, column 12): 'gravity = 1'"),
    ("array_of_drop", b"[[drop]]\ngravity = 0\n", "drop"),
]


def write_row(tmp_path: Path, changes: dict) -> Path:
    path = tmp_path / "stack.toml"
    path.write_text(tomli_w.dumps(patched(changes)), encoding="utf-8")
    return path


def run_main(argv, capsys) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    code = info.value.code
    return (0 if code is None else code), out, err


def assert_one_error_line(code: int, err: str, *fragments: str) -> str:
    assert code == EXIT_BAD_INPUT, err
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("hertz-chain: error: "), err
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


@pytest.mark.parametrize("changes, key", [r[1:] for r in FILE_ROWS], ids=[r[0] for r in FILE_ROWS])
def test_bad_stack_file_cli(tmp_path, capsys, changes, key):
    path = write_row(tmp_path, changes)
    code, out, err = run_main(["simulate", path], capsys)
    line = assert_one_error_line(code, err, key)
    assert out == ""
    assert f"{path}: {key}" in line  # the file, then the key the user wrote


@pytest.mark.parametrize("changes, key", [r[1:] for r in FILE_ROWS], ids=[r[0] for r in FILE_ROWS])
def test_bad_stack_file_api(changes, key, recwarn):
    with pytest.raises(StackFileError) as info:
        parse_stack(patched(changes))
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{key}: "), message
    assert info.value.key == key
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]  # no overflow warnings


@pytest.mark.parametrize("content, fragment", [r[1:] for r in RAW_ROWS], ids=[r[0] for r in RAW_ROWS])
def test_bad_raw_file(tmp_path, capsys, content, fragment):
    path = tmp_path / "raw.toml"
    path.write_bytes(content)
    code, _, err = run_main(["simulate", path], capsys)
    assert_one_error_line(code, err, fragment)
    with pytest.raises(StackFileError):
        load_stack_file(path)


def test_oversized_file(tmp_path, capsys):
    path = tmp_path / "huge.toml"
    with open(path, "wb") as f:
        f.truncate(MAX_FILE_BYTES + 1)
    code, _, err = run_main(["simulate", path], capsys)
    assert_one_error_line(code, err, "too large", f"{MAX_FILE_BYTES:_}")


def test_byte_order_mark_is_accepted(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + NORMATIVE_TEXT.encode("utf-8"))
    assert load_stack_file(path).stack.masses == tuple(NORMATIVE["stack"]["masses"])
    assert parse_stack("\ufeff" + NORMATIVE_TEXT).drop.impact_velocity == 1.0  # "1 m/s"


def test_bounds_accept_their_limits():
    """The documented limits themselves are accepted (the ranges are closed)."""
    spec = parse_stack(patched({"stack.masses": [M_HI, M_LO], "drop.impact_velocity": V_HI,
                                "solver.max_steps": MAX_STEPS, "solver.n_output": MAX_OUTPUT_POINTS}))
    assert spec.stack.masses == (M_HI, M_LO) and spec.solver.max_steps == MAX_STEPS
    spec = parse_stack(patched({"solver.dt_output": MIN_DT_OUTPUT}))
    assert spec.solver.dt_output == MIN_DT_OUTPUT
    spec = parse_stack(patched({"stack.masses": [1.0] * MAX_MASSES, "stack.gaps": 0}))
    assert spec.n == MAX_MASSES


# ------------------------------------------------------------------------------------------ flags
def _existing(tmp_path: Path) -> Path:
    path = tmp_path / "exists.nc"
    path.write_text("keep me")
    return path


def _file_parent(tmp_path: Path) -> Path:
    (tmp_path / "afile").write_text("x")
    return tmp_path / "afile" / "out.nc"


NAME = "n" * 300 + ".nc"  # longer than NAME_MAX (255 on Linux); the limit is read with os.pathconf

# (id, argv builder (tmp_path -> argv), fragments of the one line)
FLAG_ROWS = [
    ("unknown_command", lambda t: ["simulat"], ["simulat"]),
    ("unknown_flag", lambda t: ["simulate", "--bogus", "x"], ["--bogus"]),
    ("unknown_short_flag", lambda t: ["design", "-Z", "1"], ["-Z"]),
    ("missing_argument", lambda t: ["simulate"], ["stack_file"]),
    ("extra_argument", lambda t: ["simulate", "a.toml", "b.toml"], ["b.toml"]),
    ("missing_stack_file", lambda t: ["simulate", t / "nope.toml"], ["no such stack file"]),
    ("folder_as_stack_file", lambda t: ["simulate", t], ["is a folder"]),
    ("option_without_value", lambda t: ["simulate", "x.toml", "--output"], ["--output"]),
    ("design_ratio_word", lambda t: ["design", "-R", "abc", "-e", "0.8"], ["--mass-ratio"]),
    ("design_restitution_missing", lambda t: ["design", "-R", "0.012"], ["--restitution"]),
    ("design_ratio_above_one", lambda t: ["design", "-R", "1.5", "-e", "0.8"], ["--mass-ratio", "1.5"]),
    ("design_ratio_nan", lambda t: ["design", "-R", "nan", "-e", "0.8"], ["--mass-ratio", "nan"]),
    ("design_ratio_inf", lambda t: ["design", "-R", "inf", "-e", "0.8"], ["--mass-ratio", "inf"]),
    ("design_ratio_zero", lambda t: ["design", "-R", "0", "-e", "0.8"], ["--mass-ratio"]),
    ("design_ratio_negative", lambda t: ["design", "-R", "-0.1", "-e", "0.8"], ["--mass-ratio"]),
    ("design_ratio_too_small", lambda t: ["design", "-R", "1e-300", "-e", "0.8"], ["--mass-ratio", str(MAX_MASSES)]),
    ("design_e_zero", lambda t: ["design", "-R", "0.012", "-e", "0"], ["--restitution"]),
    ("design_e_one", lambda t: ["design", "-R", "0.012", "-e", "1"], ["--restitution"]),
    ("design_e_above_one", lambda t: ["design", "-R", "0.012", "-e", "2"], ["--restitution"]),
    ("design_e_1e-300", lambda t: ["design", "-R", "0.012", "-e", "1e-300"], ["--restitution", f"{MIN_RESTITUTION:g}"]),
    ("design_e_near_one", lambda t: ["design", "-R", "0.5", "-e", "0.9999999999"], ["--mass-ratio", str(MAX_MASSES)]),
    ("design_e_nan", lambda t: ["design", "-R", "0.012", "-e", "nan"], ["--restitution"]),
    ("design_bottom_1e308", lambda t: ["design", "-R", "0.012", "-e", "0.8", "--m1", "1e308"], ["--bottom-mass"]),
    ("design_bottom_negative", lambda t: ["design", "-R", "0.012", "-e", "0.8", "--m1", "-1"], ["--bottom-mass"]),
    ("design_top_heavier", lambda t: ["design", "-e", "0.8", "--m1", "1", "--mn", "2"], ["--top-mass"]),
    ("design_top_and_ratio", lambda t: ["design", "-e", "0.8", "-R", "0.1", "--mn", "0.1"], ["--top-mass"]),
    ("design_top_tiny", lambda t: ["design", "-e", "0.8", "--m1", "1e308", "--mn", "1e-308"], ["--bottom-mass"]),
    ("design_no_ratio", lambda t: ["design", "-e", "0.8", "--m1", "1"], ["--mass-ratio"]),
    ("design_write_elastic_law", lambda t: ["design", "-R", "0.012", "-e", "0.8", "--write", t / "d.toml", "--law",
                                            "hertz", "--stiffness", "1e9 N/m^1.5"], ["--law", "'hertz'", "tsuji"]),
    # output paths, checked before anything runs
    ("output_missing_folder", lambda t: ["simulate", "S", "--output", t / "no" / "r.nc"], ["--output", "does not exist"]),
    ("output_parent_is_file", lambda t: ["simulate", "S", "--output", _file_parent(t)], ["--output", "not a folder"]),
    ("output_long_name", lambda t: ["simulate", "S", "--output", t / NAME], ["--output", "bytes"]),
    ("output_unknown_extension", lambda t: ["simulate", "S", "--output", t / "r.txt"], ["--output", ".nc"]),
    ("output_no_extension", lambda t: ["simulate", "S", "--output", t / "r"], ["--output", ".nc"]),
    ("output_exists", lambda t: ["simulate", "S", "--output", _existing(t)], ["--output", "--force"]),
    ("output_is_folder", lambda t: ["simulate", "S", "--output", t / "d.nc", "--force"], ["--output", "folder"]),
    ("output_same_as_plot", lambda t: ["simulate", "S", "--output", t / "a.png", "--plot", t / "a.png"], ["--"]),
    # click keeps the last of a repeated option without a word (a review: only b.csv written)
    ("output_repeated", lambda t: ["simulate", "S", "--output", t / "a.nc", "--output", t / "b.csv"],
     ["--output given 2 times"]),
    ("design_restitution_repeated", lambda t: ["design", "-R", "0.1", "-e", "0.8", "--restitution", "0.7"],
     ["--restitution given 2 times"]),
    ("design_restitution_repeated_attached", lambda t: ["design", "-R", "0.1", "-e0.8", "-e0.7"],
     ["--restitution given 2 times"]),
    ("plot_missing_folder", lambda t: ["simulate", "S", "--plot", t / "no" / "p.png"], ["--plot", "does not exist"]),
    ("plot_parent_is_file", lambda t: ["simulate", "S", "--plot", t / "afile" / "p.png"], ["--plot"]),
    ("plot_jpg", lambda t: ["simulate", "S", "--plot", t / "p.jpg"], ["--plot", ".png"]),
    ("plot_long_name", lambda t: ["simulate", "S", "--plot", t / ("p" * 300 + ".png")], ["--plot", "bytes"]),
    ("plot_exists", lambda t: ["simulate", "S", "--plot", _existing(t).with_suffix(".png")], ["--plot"]),
]


def _prepare(tmp_path: Path, argv: list) -> list:
    (tmp_path / "d.nc").mkdir(exist_ok=True)
    (tmp_path / "afile").write_text("x")
    stack = tmp_path / "ok.toml"
    stack.write_text(NORMATIVE_TEXT)
    out = []
    for a in argv:
        out.append(stack if a == "S" else a)
    for a in out:  # an existing --plot target
        if isinstance(a, Path) and a.name == "exists.png":
            a.write_text("keep me")
    return out


@pytest.mark.parametrize("build, fragments", [r[1:] for r in FLAG_ROWS], ids=[r[0] for r in FLAG_ROWS])
def test_bad_flags(tmp_path, capsys, monkeypatch, build, fragments):
    import hertz_chain.workflow as workflow

    def no_run(*a, **k):  # bad input must be refused before anything is simulated
        raise AssertionError("simulated despite bad input")

    monkeypatch.setattr(workflow, "run_spec", no_run)
    argv = _prepare(tmp_path, build(tmp_path))
    before = {p: p.read_text() for p in tmp_path.glob("exists.*")}
    code, out, err = run_main(argv, capsys)
    assert_one_error_line(code, err, *fragments)
    assert {p: p.read_text() for p in tmp_path.glob("exists.*")} == before  # nothing overwritten


def test_read_only_folder(tmp_path, capsys, monkeypatch):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        probe = folder / "probe"
        try:  # as root, permissions do not stop writes: nothing to test then
            probe.write_text("x")
            probe.unlink()
            pytest.skip("this user can write into a read-only folder (root)")
        except PermissionError:
            pass
        stack = tmp_path / "ok.toml"
        stack.write_text(NORMATIVE_TEXT)
        code, _, err = run_main(["simulate", stack, "--output", folder / "r.nc"], capsys)
        assert_one_error_line(code, err, "--output", "not writable")
    finally:
        folder.chmod(0o755)


def test_help_still_works(capsys):
    code, out, err = run_main(["--help"], capsys)
    assert code == 0 and "simulate" in out and err == ""
    code, out, err = run_main(["simulate", "--help"], capsys)
    assert code == 0 and "--output" in out and "--force" in out


def test_no_arguments_prints_the_help(capsys):
    code, out, err = run_main([], capsys)
    assert code == EXIT_BAD_INPUT and "simulate" in out and "Traceback" not in err


# ------------------------------------------------------------------------------------------ API
def _stack(n_masses: int):
    import hertz_chain as hc

    return hc.Stack([1.0] * n_masses, hc.Hertz(1e9), gravity=0.0)


def _batch(n_masses: int):
    """Two designs of `n_masses` stacked (`stack_designs`), and their states."""
    import jax
    import numpy as np

    import hertz_chain as hc

    stacks = [hc.Stack([s, 0.5 * s][:n_masses], hc.Hertz(1e9), gravity=0.0) for s in (1.0, 1.2)]
    states = [hc.at_impact(st, 1.0) for st in stacks]
    return hc.stack_designs(stacks), jax.tree.map(lambda *x: np.stack(x), *states)


API_ROWS = [
    ("parse_quantity_tower", lambda: parse_quantity("10**10**10 kg", "mass", "m"), StackFileError, "m"),
    ("parse_quantity_caret", lambda: parse_quantity("2^1000 kg", "mass", "m"), StackFileError, "m"),
    ("parse_quantity_long", lambda: parse_quantity("1" * 10_000, "mass", "m"), StackFileError, "m"),
    ("parse_quantity_overflow", lambda: parse_quantity("10**400 kg", "mass", "m"), StackFileError, "m"),
    ("parse_stack_not_toml", lambda: parse_stack("[drop\n"), StackFileError, "invalid TOML"),
    ("parse_stack_int", lambda: parse_stack(123), StackFileError, "expected TOML text"),
    ("parse_stack_deep", lambda: parse_stack("a = " + "[" * 50_000 + "]" * 50_000), StackFileError, "nested"),
    ("load_missing", lambda: load_stack_file("/nonexistent/x.toml"), StackFileError, "no such stack file"),
    ("load_folder", lambda: load_stack_file(ROOT), StackFileError, "is a folder"),
    ("load_nul_path", lambda: load_stack_file("a\x00b.toml"), StackFileError, "path"),
    ("stack_too_many", lambda: _stack(MAX_MASSES + 1), ParameterError, "len(masses)"),
    ("stack_nan_mass", lambda: __import__("hertz_chain").Stack([1.0, NAN], __import__("hertz_chain").Hertz(1e9), gravity=0.0), ParameterError, "masses"),
    ("at_impact_nan", lambda: __import__("hertz_chain").at_impact(_stack(2), NAN), ParameterError, "velocity"),
    ("at_impact_negative", lambda: __import__("hertz_chain").at_impact(_stack(2), -1.0), ParameterError, "velocity"),
    # numbers of the wrong kind or shape: one line naming the argument (they were raw TypeError/ValueError)
    ("stack_laws_name", lambda: __import__("hertz_chain").Stack([1.0, 0.5], "hertz"), ParameterError, "make_law"),
    ("stack_string_masses", lambda: __import__("hertz_chain").Stack(["1", "2"], __import__("hertz_chain").Hertz(1e9)),
     ParameterError, "masses = ['1', '2'] is invalid: real numbers"),
    ("stack_complex_masses", lambda: __import__("hertz_chain").Stack([1.0 + 1j, 0.5], __import__("hertz_chain").Hertz(1e9)),
     ParameterError, "masses"),
    ("stack_gravity_list", lambda: __import__("hertz_chain").Stack([1.0, 0.5], __import__("hertz_chain").Hertz(1e9),
                                                                  gravity=[9.8, 1.0]), ParameterError, "gravity"),
    ("at_impact_list", lambda: __import__("hertz_chain").at_impact(_stack(2), [1.0, 1.0]), ParameterError,
     "velocity = 'shape (2,)' is invalid: a single number"),
    ("at_impact_string", lambda: __import__("hertz_chain").at_impact(_stack(2), "1 m/s"), ParameterError, "velocity"),
    ("at_impact_infinite_gap", lambda: __import__("hertz_chain").at_impact(_stack(2), 1.0, float("inf")),
     ParameterError, "gaps"),
    ("state_nan", lambda: __import__("hertz_chain").State([0.0, NAN], [0.0, 0.0]), ParameterError, "positions"),
    ("simulate_max_steps_bool", lambda: __import__("hertz_chain").simulate(
        _stack(2), __import__("hertz_chain").at_impact(_stack(2), 1.0), max_steps=True), ParameterError, "max_steps"),
    ("simulate_t_max_array", lambda: __import__("hertz_chain").simulate(
        _stack(2), __import__("hertz_chain").at_impact(_stack(2), 1.0), t_max=[1.0, 2.0]), ParameterError,
     "t_max = 'shape (2,)' is invalid: one time"),
    # a batch of designs (`stack_designs`) where one design is solved: it was a bare TypeError/ValueError
    *[(f"{name}_of_a_batch", call, ParameterError, "stack = 'a batch of designs (masses of shape (2, 2))'")
      for name, call in [
          ("launch_velocity", lambda: __import__("hertz_chain").launch_velocity(*_batch(2))),
          ("simulate", lambda: __import__("hertz_chain").simulate(*_batch(2))),
          ("prepare_launch", lambda: __import__("hertz_chain").prepare_launch(*_batch(2))),
          ("prepared_function", lambda: __import__("hertz_chain").prepare_launch(_stack(2), __import__(
              "hertz_chain").at_impact(_stack(2), 1.0))(*_batch(2)))]],
    ("stack_ground_string", lambda: __import__("hertz_chain").Stack([1.0, 0.5], __import__("hertz_chain").Hertz(1e9),
                                                                   ground="false"), ParameterError,
     "ground = 'false' is invalid: True or False"),
    ("simulate_ts_past_t_max", lambda: __import__("hertz_chain").simulate(
        _stack(2), __import__("hertz_chain").at_impact(_stack(2), 1.0, 1e-3), ts=[0.0, 10.0]), ParameterError,
     "ts = 'last time 10 s' is invalid: times up to t_max = "),
    # derivatives through an implicit solver: 13-19 % off central differences (a review), forward mode failed
    ("grad_through_kvaerno5", lambda: __import__("jax").grad(lambda m: __import__("hertz_chain").launch_velocity(
        __import__("hertz_chain").Stack(m, __import__("hertz_chain").Hertz(1e9)),
        __import__("hertz_chain").at_impact(__import__("hertz_chain").Stack(m, __import__("hertz_chain").Hertz(1e9)),
                                            1.0, 1e-3), solver="kvaerno5")[-1])(__import__("jax.numpy").numpy.asarray(
        [1.0, 0.5])), ParameterError, "solver = 'kvaerno5' is invalid: an explicit Runge-Kutta solver (e.g. tsit5, dopri5, dopri8"),
    # plain numbers of the Python API: a string, None or an array is one line (were float()'s TypeError or
    # ValueError, or a string such as "1" accepted)
    ("simulate_impact_none", lambda: __import__("hertz_chain").simulate_impact(__import__("hertz_chain").Hertz(1e9),
                                                                               1.0, None), ParameterError,
     "effective_mass = None is invalid: a number"),
    ("simulate_impact_string", lambda: __import__("hertz_chain").simulate_impact(__import__("hertz_chain").Hertz(1e9),
                                                                                 "1", 1.0), ParameterError,
     "impact_velocity = '1' is invalid: a number (SI units"),
    ("simulate_impact_array", lambda: __import__("hertz_chain").simulate_impact(__import__("hertz_chain").Hertz(1e9),
                                                                                __import__("numpy").array([1.0, 2.0]), 1.0),
     ParameterError, "impact_velocity"),
    ("make_law_string_stiffness", lambda: __import__("hertz_chain").make_law("hertz", stiffness="1e9"),
     ParameterError, "stiffness = '1e9' is invalid: a number (SI units"),
    # the stack files' caps on a law's own damping (`registry.LawRow.damping_max`) hold from Python too
    ("make_law_kv_damping_cap", lambda: __import__("hertz_chain").make_law("kelvin-voigt", stiffness=1e9, damping=1e10,
                                                                           effective_mass=1.0),
     ParameterError, "damping = 10000000000.0 is invalid: at most 1e+09 (c, N s/m) for the 'kelvin-voigt' law"),
    ("make_law_hc_alpha_cap", lambda: __import__("hertz_chain").make_law("hunt-crossley", stiffness=1e9, alpha=1e7),
     ParameterError, "alpha = 10000000.0 is invalid: at most 1e+06"),
    ("make_law_viscoelastic_cap", lambda: __import__("hertz_chain").make_law("viscoelastic", stiffness=1e9, A=2.0,
                                                                             effective_mass=1.0),
     ParameterError, "A = 2.0 is invalid: at most 1 (A, s)"),
    # a contact-law review: make_law took what stack files refuse, or what the law cannot be
    ("make_law_power_exponent_6", lambda: __import__("hertz_chain").make_law("power", stiffness=1e9, alpha=0.1,
                                                                             exponent=6),
     ParameterError, "exponent = 6 is invalid: a number between 1 and 5"),
    ("make_law_restitution_bool", lambda: __import__("hertz_chain").make_law("tsuji", stiffness=1e9, restitution=True,
                                                                             effective_mass=0.1),
     ParameterError, "restitution = True is invalid: a number in (0, 1], not a boolean"),
    # delta_y = R (pi p_y / (2 E*))^2 >= R: the law would never yield (E* = 3 k / (4 sqrt R) = 2.372e10 Pa)
    ("make_law_thornton_never_yields", lambda: __import__("hertz_chain").make_law(
        "thornton", stiffness=1e9, yield_pressure=2e13, effective_radius=1e-3),
     ParameterError, "yield_pressure = 20000000000000.0 is invalid: below 2 E*/pi = 1.51e+10 Pa"),
    # the rigid theory from Python (a review of the rigid model: numpy's own errors, a wrong value shown,
    # an 80 GB array, scipy's "f(a) and f(b) must have different signs")
    ("design_R_string", lambda: __import__("hertz_chain").design(R="abc", e=0.8), ParameterError,
     "R = 'abc' is invalid: a real number"),
    ("design_R_list", lambda: __import__("hertz_chain").design(R=[0.1, 0.2], e=0.8), ParameterError,
     "R = [0.1, 0.2] is invalid: a single number"),
    ("design_e_zero", lambda: __import__("hertz_chain").design(R=0.012, e=0.0), ParameterError,
     "e = 0.0 is invalid: coefficient of restitution must lie in (0, 1)"),
    ("mvg_gain_n_1e20", lambda: __import__("hertz_chain.rigid").rigid.mvg_gain(0.012, 0.8, 1e20), ParameterError,
     "n = 1e+20 is invalid"),
    ("mvg_masses_n_1e10", lambda: __import__("hertz_chain.rigid").rigid.mvg_masses(0.012, 10**10), ParameterError,
     "n = 10000000000 is invalid: number of masses must be an integer >= 2 and at most 1,000,000"),
    ("met_masses_n_1e10", lambda: __import__("hertz_chain.rigid").rigid.met_masses(0.8, 10**10), ParameterError,
     "at most 1,000,000"),
    ("optimal_pair_ratio_e_zero", lambda: __import__("hertz_chain.rigid").rigid.optimal_pair_ratio(0.0), ParameterError,
     "e = 0.0 is invalid: the continuous-n optimum (Eqs 22-24) needs e > 0"),
    ("continuous_gain_e_tiny", lambda: __import__("hertz_chain.rigid").rigid.continuous_optimal_gain(0.012, 1e-300),
     ParameterError, "e = 1e-300 is invalid"),
    ("simulate_rigid_string_masses", lambda: __import__("hertz_chain").simulate_rigid(["a", "b"], [-1, -1], [0, 0.01], 0.8, 0.8),
     ParameterError, "masses = ['a', 'b'] is invalid: a real number"),
    ("simulate_rigid_max_collisions_nan", lambda: __import__("hertz_chain").simulate_rigid(
        [1, 0.5], [-1, -1], [0, 0.01], 0.8, 0.8, max_collisions=NAN), ParameterError, "max_collisions = nan"),
    ("simulate_rigid_batch_shows_the_value", lambda: __import__("hertz_chain").simulate_rigid_batch(
        [[1, 0.5], [1, -0.3]], -__import__("numpy").ones((2, 2)), [[0, 0.01]] * 2, 0.8, 0.8), ParameterError,
     "masses[1, 1] = -0.3 is invalid"),
    ("check_output_missing", lambda: _paths.check_output_path("/nonexistent/r.nc", "--output", (".nc",), False),
     OutputPathError, "--output"),
    ("check_output_suffix", lambda: _paths.check_output_path("r.txt", "--output", (".nc",), False),
     OutputPathError, ".nc"),
    ("check_output_folder", lambda: _paths.check_output_path(ROOT / "tests", "--output", ("",), True),
     OutputPathError, "folder"),
]


@pytest.mark.parametrize("call, exc_type, fragment", [r[1:] for r in API_ROWS], ids=[r[0] for r in API_ROWS])
def test_bad_api_calls(call, exc_type, fragment):
    with pytest.raises(exc_type) as info:
        call()
    assert isinstance(info.value, HertzChainError)
    message = str(info.value)
    assert "\n" not in message and fragment in message, message


# ------------------------------------------------------------------------------------------ writes
def test_atomic_write_refuses_a_file_that_appeared(tmp_path):
    """The race, simulated: the target appears between the check (before the run) and the write."""
    target = _paths.check_output_path(tmp_path / "r.csv", "--output", (".csv",), False)
    target.write_text("the other run's result")

    def write(tmp):
        Path(tmp).write_text("this run's result")

    with pytest.raises(OutputPathError) as info:
        _paths.write_atomically(target, write, False, "--output")
    assert "--output" in str(info.value) and "\n" not in str(info.value)
    assert target.read_text() == "the other run's result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]  # no temporary file left
    _paths.write_atomically(target, write, True, "--output")  # --force replaces it
    assert target.read_text() == "this run's result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]


def test_two_writers_exactly_one_wins(tmp_path):
    target = tmp_path / "r.nc"
    barrier = threading.Barrier(2)
    outcomes: dict[int, object] = {}

    def run(i):
        def write(tmp):
            Path(tmp).write_text(f"writer {i}")
            barrier.wait(timeout=10)  # both have checked and written their temporary file

        try:
            _paths.check_output_path(target, "--output", (".nc",), False)
            _paths.write_atomically(target, write, False, "--output")
            outcomes[i] = "won"
        except OutputPathError as exc:
            outcomes[i] = exc

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=30)
    assert sorted(map(str, outcomes.values())).count("won") == 1
    loser = next(v for v in outcomes.values() if v != "won")
    assert isinstance(loser, OutputPathError) and "\n" not in str(loser)
    winner = next(i for i, v in outcomes.items() if v == "won")
    assert target.read_text() == f"writer {winner}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.nc"]


def test_failed_writer_leaves_nothing(tmp_path):
    def write(tmp):
        Path(tmp).write_text("half")
        raise OSError(28, "No space left on device")

    with pytest.raises(OutputPathError) as info:
        _paths.write_atomically(tmp_path / "r.csv", write, False, "--output")
    assert "No space left" in str(info.value)
    assert list(tmp_path.iterdir()) == []


def test_name_max_comes_from_the_file_system(tmp_path):
    limit = _paths.name_max(tmp_path)
    try:
        expected = os.pathconf(tmp_path, "PC_NAME_MAX")
    except (OSError, ValueError):
        expected = _paths.NAME_MAX_FALLBACK
    assert limit == expected
    ok = "a" * (limit - len(".nc")) + ".nc"
    assert _paths.check_output_path(tmp_path / ok, "--output", (".nc",), False).name == ok
    with pytest.raises(OutputPathError):
        _paths.check_output_path(tmp_path / ("a" + ok), "--output", (".nc",), False)


# ------------------------------------------------------------------------------------------ status
class _FakeReport:
    def __init__(self, status, warnings=()):
        self.status, self.warnings = status, list(warnings)


@pytest.mark.parametrize("status", list(Status))
def test_exit_status_after_a_run(tmp_path, capsys, monkeypatch, status):
    """After the table, a run that is not ok prints one line `hertz-chain: <status>: <hint>` and exits
    with `Status.exit_code`; each warning is one line too."""
    import hertz_chain.report as report
    import hertz_chain.workflow as workflow

    monkeypatch.setattr(workflow, "run_spec", lambda spec: _FakeReport(status, ["first\nwarning", "second"]))
    monkeypatch.setattr(report, "summary_table", lambda r: "TABLE")
    stack = tmp_path / "ok.toml"
    stack.write_text(NORMATIVE_TEXT)
    code, out, err = run_main(["simulate", stack], capsys)
    assert out.strip() == "TABLE" and "Traceback" not in err
    lines = err.splitlines()
    assert lines[:2] == ["hertz-chain: warning: first warning", "hertz-chain: warning: second"]
    assert code == status.exit_code
    if status.ok:
        assert len(lines) == 2
    else:
        assert lines[2:] == [f"hertz-chain: {status.text}: {' '.join(status.hint().split())}"]


# ------------------------------------------------------------------------------------------ processes
SUBPROCESS = [
    (["simulat"], "simulat"),
    (["simulate", "--bogus"], "--bogus"),
    (["simulate"], "stack_file"),
    (["simulate", "/nonexistent/stack.toml"], "no such stack file"),
    (["simulate", "/"], "is a folder"),
    (["design", "-R", "abc", "-e", "0.8"], "--mass-ratio"),
    (["design", "-R", "0.012", "-e", "1e-300"], "--restitution"),
    (["design", "-R", "1e-300", "-e", "0.8"], "--mass-ratio"),
    (["design", "-R", "0.012", "-e", "0.8", "--m1", "1e308"], "--bottom-mass"),
]
SUBPROCESS_FILES = ["mass_1e308", "mass_pow_tower", "mass_pow_10_400", "tsuji_damping_1e300",
                    "visco_damping_1e6_s", "stiffness_1e308", "impact_1e300", "max_steps_1e8",
                    "max_steps_1e300", "max_steps_int64", "design_n_million", "masses_too_many"]


def _run_exe(argv):
    env = dict(os.environ, PYTHONWARNINGS="default")  # a RuntimeWarning would show on stderr
    return subprocess.run([str(EXE), *map(str, argv)], capture_output=True, text=True, timeout=60, env=env)


@pytest.mark.parametrize("argv, fragment", SUBPROCESS, ids=[" ".join(a) for a, _ in SUBPROCESS])
def test_real_process_flags(argv, fragment):
    proc = _run_exe(argv)
    assert_one_error_line(proc.returncode, proc.stderr, fragment)


@pytest.mark.parametrize("row", SUBPROCESS_FILES)
def test_real_process_files(tmp_path, row):
    changes, key = next(r[1:] for r in FILE_ROWS if r[0] == row)
    path = write_row(tmp_path, changes)
    proc = _run_exe(["simulate", path, "--output", tmp_path / "r.nc"])
    assert_one_error_line(proc.returncode, proc.stderr, key)
    assert not (tmp_path / "r.nc").exists()
