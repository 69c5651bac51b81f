"""Single-scenario analyses: kinematics (eq. 2), mass matrix (eq. 3-5),
inverse dynamics (eq. 6-11), power flow, reduced matrices (eq. 23-25).
Checked by closed forms of the paper, residuals and energy balance."""

from __future__ import annotations

import json
from fractions import Fraction

import numpy as np
import pytest

import egt
from conftest import FIG5

T1, T2 = Fraction(-2, 3), Fraction(-16, 9)  # Fig. 3 ratios from teeth


def test_kinematics_matches_the_paper_closed_form(fig3: egt.Train) -> None:
    k = fig3.kinematics({"2": 100.0})
    # w_2 = t1 t2 / (t1 t2 - 1) w_4 and w_3 = (t1 - 1) t2 / (t1 t2 - 1) w_4 (section 6.1).
    w4 = Fraction(100) * (T1 * T2 - 1) / (T1 * T2)
    assert k.exact is not None
    assert k.exact["4"] == w4
    assert k.exact["3"] == (T1 - 1) * T2 / (T1 * T2 - 1) * w4
    assert k["4"] == pytest.approx(float(w4), rel=1e-15)
    assert k["1"] == 0.0
    assert k.residual < 1e-14
    assert fig3.willis_residual(k.speeds) < 1e-14


def test_kinematics_is_a_mapping_with_numpy_arrays(fig3: egt.Train) -> None:
    k = fig3.kinematics({"2": 100})
    assert set(k) == {"1", "2", "3", "4"} and len(k) == 4
    assert "4" in k and "9" not in k
    with pytest.raises(KeyError):
        k["9"]
    assert isinstance(k.speeds, np.ndarray) and k.speeds.dtype == np.float64
    assert k.speeds.shape == (4,)
    assert k.known.dtype == np.bool_ and k.known.all()
    assert dict(k) == {n: float(v) for n, v in zip(k.links, k.speeds)}
    json.dumps(k.to_dict())


def test_input_speeds_may_be_exact(fig3: egt.Train) -> None:
    for v in (Fraction(1, 3), "1/3"):
        k = fig3.kinematics({"2": v})
        assert k.exact is not None and k.exact["2"] == Fraction(1, 3)
    # A float is the decimal it prints as.
    k = fig3.kinematics({"2": 0.1})
    assert k.exact is not None and k.exact["2"] == Fraction(1, 10)
    k = fig3.kinematics({"2": np.float32(2.0)})
    assert k["2"] == 2.0
    with pytest.raises(TypeError):
        fig3.kinematics({"2": True})
    with pytest.raises(TypeError):
        fig3.kinematics({"2": [1.0]})  # type: ignore[dict-item]


def test_spec_speeds_are_the_default(fig3: egt.Train) -> None:
    assert fig3.kinematics()["2"] == 100.0
    assert fig3.kinematics().exact == fig3.kinematics({"2": 100}).exact


def test_relative_speeds_of_planets(planetary: egt.Train) -> None:
    k = planetary.kinematics({"sun": 102})
    assert k["carrier"] == pytest.approx(30.0)
    rel = {r.link: r for r in k.relative}
    assert rel["P.planet"].carrier == "carrier"
    assert rel["P.planet"].speed == pytest.approx(k["P.planet"] - k["carrier"])


def test_willis_jacobian(fig3: egt.Train) -> None:
    j = fig3.willis_jacobian()
    t1, t2 = float(T1), float(T2)
    # Rows follow eq. (2) with gear i, gear j, carrier; columns (w2, w3, w4).
    assert j == pytest.approx(np.array([[t1 - 1, -t1, 0.0], [t2 - 1, 1.0, -t2]]))
    k = fig3.kinematics({"2": 3.0})
    assert np.abs(j @ k.speeds[1:]).max() < 1e-13


def test_mass_matrix_of_fig3(fig3: egt.Train) -> None:
    m = fig3.mass_matrix()
    assert m.coordinates == ("2", "3", "4")
    # diag(I2 + n m3 d_ab^2, n I3, I4) with d_ab = r11 + r31 = 0.05 (section 6.1).
    expected = np.diag([2.0e-3 + 3 * 0.12 * 0.05**2, 3 * 4.0e-5, 1.2e-3])
    assert m.matrix == pytest.approx(expected, rel=1e-14)
    assert m.offsets[0].levels == ("a", "b") and m.offsets[0].distance == pytest.approx(0.05)
    json.dumps(m.to_dict())


def test_dynamics_driving_torque_matches_the_closed_form(fig3: egt.Train) -> None:
    tr, alpha = -50.0, 10.0
    d = fig3.dynamics(torques={"4": tr}, accelerations={"4": alpha}, driving=["2"])
    t1, t2 = float(T1), float(T2)
    i2, i3, i4, m3, n, dab = 2.0e-3, 4.0e-5, 1.2e-3, 0.12, 3, 0.05
    # Example 6.1 with Q_4 = T_r applied (eq. 6; docs/errata.md).
    td = -tr * (1 - 1 / (t1 * t2)) + alpha * (
        (i2 + m3 * dab**2 * n) * t1 * t2 / (t1 * t2 - 1)
        + i3 * n * t2 * (t1 - 1) ** 2 / (t1 * (t1 * t2 - 1))
        + i4 * (1 - 1 / (t1 * t2))
    )
    assert d.driving_torques["2"] == pytest.approx(td, rel=1e-12)
    assert d.accelerations[3] == alpha
    assert d.accelerations[1] == pytest.approx(t1 * t2 / (t1 * t2 - 1) * alpha)
    # eq. (11): F42 = (T_r - I4 alpha) / r42.
    g2 = next(m for m in d.meshes if m.gear == "G2")
    assert g2.force is not None
    assert g2.force[1] == pytest.approx((tr - i4 * alpha) / 0.032, rel=1e-12)
    json.dumps(d.to_dict())


def test_dynamics_equation_of_motion_residual(fig5: egt.Train) -> None:
    # eq. (6): M w' + psi^T lambda = Q on every coordinate.
    d = fig5.dynamics(
        torques={"6": -10.0}, accelerations={"2": 3.0, "4": -1.0}, driving=["2", "4"]
    )
    m = fig5.mass_matrix().matrix
    j = fig5.willis_jacobian()
    q = d.torques[1:]
    r = m @ d.accelerations[1:] + j.T @ d.multipliers - q
    assert np.abs(r).max() < 1e-12 * max(1.0, np.abs(q).max())


def test_static_analysis_when_no_acceleration(fig3: egt.Train) -> None:
    d = fig3.dynamics(torques={"4": -50.0}, accelerations={}, driving=["2"])
    t1, t2 = float(T1), float(T2)
    assert d.driving_torques["2"] == pytest.approx(50.0 * (1 - 1 / (t1 * t2)))
    assert not d.accelerations.any()


def test_power_balance(fig3: egt.Train) -> None:
    for losses in (False, True):
        p = fig3.power(losses=losses)
        assert abs(p.balance) < 1e-9 * p.input_power
        assert p.input_power > 0
        if losses:
            assert 0 < p.loss and p.efficiency is not None and p.efficiency < 1
        else:
            assert abs(p.loss) < 1e-9 * p.input_power
        assert {m.gear for m in p.meshes} == {"G1", "G2"}
        json.dumps(p.to_dict())


def test_static_power_flow_with_losses(planetary: egt.Train) -> None:
    p = planetary.power({"sun": 157.08}, torques={"carrier": -40.0}, driving=["sun"])
    assert p.efficiency is not None and 0.9 < p.efficiency < 1.0
    assert abs(p.balance) < 1e-9 * p.input_power
    assert p.kinetic_rate == 0.0


def test_velocity_and_reduced_mass_matrix(fig5: egt.Train) -> None:
    v = fig5.velocity_matrix(["2", "4"])
    assert v.shape == (5, 2)
    assert np.abs(fig5.willis_jacobian() @ v).max() < 1e-14  # eq. (24)
    m = fig5.mass_matrix().matrix
    assert fig5.reduced_mass_matrix(["2", "4"]) == pytest.approx(v.T @ m @ v, rel=1e-13)
    assert fig5.reduced_mass_matrix() == pytest.approx(v.T @ m @ v, rel=1e-13)


def test_equivalent_inertia_is_twice_the_kinetic_energy(fig3: egt.Train) -> None:
    k = fig3.kinematics({"2": 1.0})
    m = fig3.mass_matrix().matrix
    w = k.speeds[1:]
    assert fig3.equivalent_inertia("2") == pytest.approx(w @ m @ w, rel=1e-13)
    assert fig3.equivalent_inertia() == fig3.equivalent_inertia("2")  # reduce_to = "2"
    assert fig3.reduced_mass_matrix(["2"])[0, 0] == pytest.approx(fig3.equivalent_inertia("2"))


def test_brake_constraint_in_dynamics() -> None:
    train = egt.loads(FIG5 + '\n[[elements]]\nname = "B"\nkind = "brake"\nlinks = ["4"]\n')
    d = train.dynamics(torques={"6": -10.0}, accelerations={}, driving=["2"], engaged=["B"])
    assert d.element_torques.shape == (1,)
    v = train.velocity_matrix(["2"], engaged=["B"])
    assert abs(v[2, 0]) < 1e-15  # link 4 held


def test_to_pandas_when_available(fig3: egt.Train) -> None:
    import pandas  # noqa: F401  (a dev requirement: missing, the test fails)
    df = fig3.kinematics().to_pandas()
    assert list(df.index) == ["1", "2", "3", "4"]
    assert fig3.dynamics().to_pandas().shape == (4, 2)
    assert fig3.power().to_pandas().shape[0] == 2
    assert fig3.mass_matrix().to_pandas().shape == (3, 3)
