"""Issue 43: ``Train.modes``, the torsional natural frequencies, from Python:
properties of the result (the physics is tested in egt-core's tests), the
refusals and argument checks."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import egt

ROOT = Path(__file__).resolve().parents[3]
SPEC = ROOT / "examples" / "simple_planetary_compliant.toml"


def test_modes_in_low_gear() -> None:
    m = egt.load(SPEC).modes("low")
    assert m.state == "low" and m.dof == 1 and m.constraints == ("B",)
    assert m.coordinates == ("sun", "ring", "carrier", "P.planet#1", "P.planet#2", "P.planet#3")
    rigid = [x for x in m.modes if x.rigid]
    assert len(rigid) == 1 and rigid[0].hertz == 0.0
    # The rigid-body mode is the kinematics: carrier = 30/102 sun, ring at rest.
    s = rigid[0].shape
    assert math.isclose(s[2] / s[0], 30 / 102, rel_tol=1e-12)
    assert abs(s[1]) < 1e-12 * abs(s[0])
    # Mass-normalised shapes, energy shares that sum to 1.
    for x in m.modes:
        assert math.isclose(float(np.sum(m.inertias * x.shape**2)), 1.0, rel_tol=1e-10)
        assert math.isclose(float(x.kinetic_energy.sum()), 1.0, rel_tol=1e-12)
    # Three planets: one planet mode of multiplicity 2 at sqrt((k_sp + k_rp) r_bp^2 / J_p).
    rbp = 1.5e-3 * 21 / 2 * math.cos(math.radians(20))
    w = math.sqrt((4e8 + 6e8) * rbp**2 / 1.5e-5)
    planet = [x for x in m.modes if math.isclose(x.omega, w, rel_tol=1e-10)]
    assert len(planet) == 2 and all(x.multiplicity == 2 for x in planet)
    assert np.all(np.diff(m.frequencies) >= 0)
    assert m.mesh_orders is not None
    assert math.isclose(m.mesh_orders["P/sun-planet"], 30 * 72 / 102, rel_tol=1e-12)


def test_campbell_crossings() -> None:
    m = egt.load(SPEC).modes("low", campbell=(0, 55000))
    assert len(m.crossings) == 4
    for c in m.crossings:
        assert math.isclose(c.speed, 60 * c.hertz / (30 * 72 / 102), rel_tol=1e-12)
        assert m.modes[c.mode].hertz == c.hertz


def test_modes_refusals() -> None:
    with pytest.raises(egt.MissingDataError) as info:
        egt.load(ROOT / "examples" / "simple_planetary.toml").modes()
    assert "`P/sun-planet`" in str(info.value)
    t = egt.load(SPEC)
    with pytest.raises(egt.MissingDataError):
        t.modes(campbell=(0, 7000))  # the bare train has 2 DOF
    with pytest.raises(egt.TransmissionError):
        t.modes("lo")
    with pytest.raises(egt.ArgumentTypeError):
        t.modes("low", campbell="0:7000")  # type: ignore[arg-type]
    with pytest.raises(egt.ArgumentTypeError):
        t.modes("low", campbell=(0, "x"))  # type: ignore[arg-type]
