"""The README's Python examples run as written, and its worked example shows real output.

References: the printed numbers are the paper's (Eq 20: G = 5.0407 for the six-mass MVG stack;
Eq 29: 3.5705 for the ten-mass MET stack), so the README cannot drift from the code unnoticed.
"""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def test_python_examples_run(tmp_path):
    code = "\n".join(re.findall(r"```python\n(.*?)```", README, re.S))
    assert "hc.simulate(" in code and "hc.simulate_rigid(" in code
    code += "\nassert abs(report.top_velocity_gain - 5.0407) < 1e-4 and abs(r.gain - 5.0407) < 1e-4\n"
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]


def test_worked_example_is_the_real_design_output():
    from typer.testing import CliRunner

    from hertz_chain.cli import app

    res = CliRunner().invoke(app, ["design", "--mass-ratio", "0.012", "--restitution", "0.8", "--bottom-mass", "8.4"])
    assert res.exit_code == 0
    block = re.search(r"```\n(Optimal stacks for R = 0\.012.*?)```", README, re.S).group(1)
    lines = [ln for ln in block.strip().splitlines()]
    assert lines == res.stdout.strip().splitlines()  # the whole output, notes included
    assert "5.0407" in block and "3.5705" in block  # Eq 20, Eq 29


@pytest.mark.parametrize("cmd", ["design", "simulate", "demo"])
def test_documented_commands_exist(cmd):
    assert f"hertz-chain {cmd}" in README
