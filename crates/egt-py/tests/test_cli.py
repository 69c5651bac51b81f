"""Issue 17: the wheel's command line (`python -m egt`, the `egt` console
script) is the Rust CLI: same output and exit codes as the binary."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "egt", *args], cwd=ROOT, capture_output=True, text=True)


def test_python_m_egt_runs_the_cli() -> None:
    r = run("check", "examples/fig3_example61.toml")
    assert r.returncode == 0, r.stderr
    assert "valid geared kinematic chain" in r.stdout
    r = run("kinematics", "examples/fig3_example61.toml", "--input", "2=100", "--format", "json")
    assert r.returncode == 0 and '"version"' in r.stdout


def test_exit_codes_are_the_binary_s() -> None:
    assert run("check", "examples/no_such_file.toml").returncode == 1
    bad = run("kinematics", "examples/fig3_example61.toml", "--input", "2=1/3/4")
    assert bad.returncode == 2 and "not a number" in bad.stderr
    assert run("--version").returncode == 0
    assert run("no-such-command").returncode == 2


def test_console_script_is_installed() -> None:
    script = Path(sys.executable).parent / "egt"
    assert script.exists(), script
    r = subprocess.run([str(script), "check", "examples/simple_planetary.toml"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
