"""Issue 17: one shape per result. ``to_dict()`` of every analysis result is
the document the CLI prints with ``--format json`` for the same train and
arguments, compared field for field (floats exactly: both come from the same
Rust formatting of the same numbers)."""

from __future__ import annotations

import json
import pickle
import subprocess
import sys
from fractions import Fraction
from pathlib import Path
from typing import Any, Dict, Iterable, List

import pytest

import egt

ROOT = Path(__file__).resolve().parents[3]
EX = "examples"


def cli(*args: str) -> Dict[str, Any]:
    r = subprocess.run(
        [sys.executable, "-m", "egt", *args, "--format", "json"], cwd=ROOT, capture_output=True, text=True
    )
    assert r.returncode == 0, r.stderr
    doc: Dict[str, Any] = json.loads(r.stdout)
    return doc


def train(name: str) -> egt.Train:
    # Read under the same relative name the CLI is given, so `source` agrees.
    import os

    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        return egt.Train.from_file(f"{EX}/{name}")
    finally:
        os.chdir(cwd)


def differences(a: Any, b: Any, path: str = "") -> Iterable[str]:
    """Every path where two JSON values differ (empty when they are equal)."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                yield f"{path}.{k}: only in {'python' if k in a else 'cli'}"
            else:
                yield from differences(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            yield f"{path}: {len(a)} vs {len(b)} items"
        for i, (x, y) in enumerate(zip(a, b)):
            yield from differences(x, y, f"{path}[{i}]")
    elif a != b or type(a) is not type(b):
        yield f"{path}: {a!r} vs {b!r}"


def same(python: Dict[str, Any], command: Dict[str, Any]) -> None:
    diff: List[str] = list(differences(python, command))
    assert not diff, diff[:10]


@pytest.mark.parametrize(
    "spec",
    ["fig3_example61.toml", "fig5_example62.toml", "simple_planetary.toml"],
)
def test_kinematics_dynamics_power_are_the_cli_documents(spec: str) -> None:
    t = train(spec)
    same(t.kinematics().to_dict(), cli("kinematics", f"{EX}/{spec}"))
    same(t.dynamics().to_dict(), cli("dynamics", f"{EX}/{spec}"))
    p = t.power()
    same(p.to_dict(), cli("power", f"{EX}/{spec}"))
    # A power flow's speeds and dynamics are the documents of those commands:
    # equal to them for ideal meshes, the same shape with mesh losses (the
    # lossy torques differ, as they should).
    same(p.speeds.to_dict(), cli("kinematics", f"{EX}/{spec}"))
    ideal = t.power(losses=False)
    same(ideal.to_dict(), cli("power", f"{EX}/{spec}", "--ideal"))
    # Its dynamics solved the speeds, so it reports their condition where a
    # static `egt dynamics` did not factor [Psi_w] and says 1.0 (documented
    # at InverseDynamics::conditions); everything else is equal.
    mine, theirs = ideal.dynamics.to_dict(), cli("dynamics", f"{EX}/{spec}")
    if theirs["static_analysis"]:
        assert theirs["conditions"][0] == 1.0 or theirs["conditions"][0] == mine["conditions"][0]
        mine["conditions"][0] = theirs["conditions"][0]
    same(mine, theirs)
    assert p.dynamics.to_dict().keys() == ideal.dynamics.to_dict().keys()


def test_explicit_arguments_give_the_same_documents() -> None:
    t = train("fig3_example61.toml")
    same(t.kinematics({"2": Fraction(157, 3)}).to_dict(), cli("kinematics", f"{EX}/fig3_example61.toml", "--input", "2=157/3"))
    same(
        t.dynamics(torques={"4": -20.0}, driving=["2"]).to_dict(),
        cli("dynamics", f"{EX}/fig3_example61.toml", "--torque", "4=-20", "--driving", "2"),
    )


def test_modes_are_the_cli_documents() -> None:
    t = train("simple_planetary_compliant.toml")
    spec = f"{EX}/simple_planetary_compliant.toml"
    same(t.modes().to_dict(), cli("modes", spec))
    same(
        t.modes("low", campbell=(0, 55000)).to_dict(),
        cli("modes", spec, "--state", "low", "--campbell", "--speed", "0:55000"),
    )


def test_stability_and_simulation_are_the_cli_documents() -> None:
    t = train("fig5_stability.toml")
    same(t.stability().to_dict(), cli("stability", f"{EX}/fig5_stability.toml"))
    same(t.simulate().to_dict(), cli("simulate", f"{EX}/fig5_stability.toml"))
    # The equilibrium of the curves is there, as in the CLI's document.
    assert t.simulate().to_dict()["equilibrium"] is not None


@pytest.mark.parametrize(
    "spec", ["zf_8hp70.toml", "ford_c4_simpson.toml", "ford_aod_ravigneaux.toml", "zf_6hp26_lepelletier.toml"]
)
def test_shift_table_and_gear_states_are_the_cli_document(spec: str) -> None:
    t = train(spec)
    table = t.shift_table()
    doc = cli("shift", f"{EX}/{spec}")
    same(table.to_dict(), doc)
    for g, row in zip(table.gears, doc["gears"]):
        same(g.to_dict(), row)
    # A state asked for alone is the same row of the table.
    first = doc["gears"][0]
    same(t.gear(first["state"]).to_dict(), first)


def test_a_result_in_other_units_says_so_and_converts_its_document() -> None:
    t = train("simple_planetary.toml")
    rad = t.kinematics()
    doc = rad.to_dict()
    assert "unit" not in doc
    rpm = rad.to("rpm").to_dict()
    assert rpm["unit"] == "rpm"
    for a, b in zip(doc["links"], rpm["links"]):
        assert b["speed"] == pytest.approx(a["speed"] * 30 / 3.141592653589793, rel=1e-15)
        assert b["ratio"] == a["ratio"] and b["ratio_exact"] == a["ratio_exact"]
        assert b["exact"] is None  # 30/pi is not rational
    # rpm <-> rev/s is rational: exact values survive.
    given = t.kinematics({"sun": 600}, unit="rpm")
    assert given.to_dict()["unit"] == "rpm"
    revs = given.to("rev/s").to_dict()
    assert [Fraction(x["exact"]) * 60 for x in revs["links"]] == [
        Fraction(x["exact"]) for x in given.to_dict()["links"]
    ]
    # Back in rad/s the document has no unit field.
    assert "unit" not in given.to("rad/s").to_dict()


def test_documents_survive_pickling_and_are_copies() -> None:
    t = train("fig3_example61.toml")
    k = t.kinematics()
    again = pickle.loads(pickle.dumps(k))
    same(again.to_dict(), k.to_dict())
    d = k.to_dict()
    d["links"].clear()
    assert k.to_dict()["links"], "to_dict() must hand out a copy"
