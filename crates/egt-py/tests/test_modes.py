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


def test_damped_modes_decay_at_the_modal_damping_ratios_size() -> None:
    m = egt.load(SPEC).modes("low")
    # 600 N s/m on every mesh: each underdamped pair once, decaying, and as
    # many as the elastic modes (light damping leaves no real roots).
    elastic = [x for x in m.modes if not x.rigid]
    assert len(m.damped) == len(elastic)
    for d in m.damped:
        assert d.sigma < 0 and 0 < d.damping_ratio < 1
        assert math.isclose(d.omega_d**2 + d.sigma**2, d.omega_n**2, rel_tol=1e-12)
    # Light damping: the damped frequencies are within zeta^2 of the undamped ones.
    for d, x in zip(m.damped, elastic):
        assert abs(d.omega_n - x.omega) < 1e-3 * x.omega


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


HP = ROOT / "examples" / "zf_8hp70_compliant.toml"


def test_static_load_carries_the_rigid_models_mesh_torques() -> None:
    m = egt.load(HP).modes("2", static_torque=300.0)
    st = m.static_load
    assert st is not None and st.input_torque == 300.0
    # Second gear reacts the published ratio 3.130 (three decimals).
    assert abs(-st.output_torque / 300.0 - 3.130) < 5e-4
    # The springs' mesh torques against eq. (11)'s.
    top = max(abs(x.rigid_torque) for x in st.meshes)
    assert top > 10.0 and len(st.meshes) == 8
    for x in st.meshes:
        assert abs(x.compliant_torque - x.rigid_torque) < 1e-10 * top, x
    assert set(st.elements) == {"A", "B", "E"}
    # Every spring's force is its stiffness times its deflection.
    k = {s["name"]: s["stiffness"] for s in m.to_dict()["springs"]}
    for name, (d, f) in st.springs.items():
        assert math.isclose(f, k[name] * d, rel_tol=1e-12, abs_tol=1e-9)
    assert egt.load(HP).modes("2").static_load is None


def test_static_load_refusals() -> None:
    t = egt.load(HP)
    with pytest.raises(egt.ArgumentError, match="static_torque"):
        t.modes(static_torque=300.0)  # no gear state
    with pytest.raises(egt.ArgumentError, match="static_torque"):
        t.modes("2", static_torque=float("nan"))
    with pytest.raises(egt.ArgumentTypeError):
        t.modes("2", static_torque="300")  # type: ignore[arg-type]


def test_modes_as_pandas_and_the_campbell_plot() -> None:
    pytest.importorskip("pandas")
    import matplotlib

    matplotlib.use("Agg")
    m = egt.load(HP).modes("5", campbell=(0, 7000))
    df = m.to_pandas()
    assert list(df.index) == list(range(1, len(m.modes) + 1))
    assert df.loc[1, "rigid"] and not df.loc[2, "rigid"]
    assert df["hertz"].tolist() == [x.hertz for x in m.modes]
    assert df.loc[2, "top_spring"] in m.springs
    shapes = m.shapes()
    assert shapes.shape == (len(m.coordinates), len(m.modes))
    assert shapes.loc["output", 2] == m.modes[1].shape[m.coordinates.index("output")]
    ax = m.plot()
    # A ray per mesh and a circle per crossing, each a line artist.
    assert len(ax.lines) >= len(m.mesh_orders or {}) + len(m.crossings)
    assert ax.get_xlabel() == "input speed [rpm]"
    with pytest.raises(ValueError, match="campbell"):
        egt.load(HP).modes("5").plot()
