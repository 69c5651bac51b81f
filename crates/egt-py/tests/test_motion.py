"""Stability (section 5, any DOF) and forward simulation (eq. 12)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import egt

# The curves of the Fig. 5 spec: (link, torque, slope, speed).
CURVES = [("2", 2.0, -0.05, 300.0), ("4", 3.0, -0.08, 100.0), ("6", -10.0, -0.2, -185.7)]


def linear_torque(t: float, w: np.ndarray) -> np.ndarray:
    out = np.zeros_like(w)
    for link, torque, slope, speed in CURVES:
        out[int(link) - 1] = torque + slope * (w[int(link) - 1] - speed)
    return out


def test_reduced_matrices_and_eigenpairs(fig5: egt.Train) -> None:
    r = fig5.stability()
    assert r.coordinates == ("2", "4") and r.source == "spec_speeds"
    np.testing.assert_allclose(r.mass_matrix, fig5.reduced_mass_matrix(["2", "4"]), rtol=1e-12)
    # [K] = V^T diag(K_l) V (eq. 26 as the paper means it).
    v = fig5.velocity_matrix(["2", "4"])
    k = np.diag([-0.05, 0.0, -0.08, 0.0, -0.2])
    np.testing.assert_allclose(r.slope_matrix, v.T @ k @ v, rtol=1e-12, atol=1e-15)
    # (lambda [M] - [K]) X = 0 for every mode.
    for mode in r.modes:
        x = mode.coordinates
        res = r.slope_matrix @ x - mode.eigenvalue * (r.mass_matrix @ x)
        assert np.abs(res).max() <= 1e-9 * np.abs(r.slope_matrix @ x).max()
    assert r.verdict == "stable" and r.stable and r.margin < 0
    assert list(r.eigenvalues) == sorted(r.eigenvalues, reverse=True)
    assert r.velocity_matrix.shape == (6, 2)
    json.dumps(r.to_dict())


def test_a_load_that_helps_as_it_speeds_up_is_unstable(fig5: egt.Train) -> None:
    r = fig5.stability(curves=[("2", 2.0, -0.05, 300.0), ("4", 3.0, -0.08, 100.0), ("6", -10.0, 5.0, -185.7)])
    assert r.verdict == "unstable" and r.margin > 0


def test_curves_may_be_given_as_objects_tuples_or_dicts(fig5: egt.Train) -> None:
    a = fig5.stability(curves=[egt.Curve(*c) for c in CURVES])
    b = fig5.stability(curves=[{"link": c[0], "torque": c[1], "slope": c[2], "speed": c[3]} for c in CURVES])
    c = fig5.stability(curves=CURVES)
    np.testing.assert_array_equal(a.eigenvalues, b.eigenvalues)
    np.testing.assert_array_equal(a.eigenvalues, c.eigenvalues)


def test_stability_needs_curves(fig3: egt.Train) -> None:
    with pytest.raises(egt.MissingDataError):
        fig3.stability()


def test_simulation_balances_energy(fig5: egt.Train) -> None:
    s = fig5.simulate(0.5, dt=1e-3)
    assert s.t[0] == 0.0 and s.t[-1] == pytest.approx(0.5)
    assert s.speeds.shape == (len(s.t), 6)
    assert s.diverged is None
    assert s.energy_error < 1e-6 and s.max_drift < 1e-10
    # The Willis equations hold at every sample (eq. 2).
    assert max(fig5.willis_residual(w) for w in s.speeds[:: max(1, len(s.t) // 20)]) < 1e-10
    # A stable train settles to the equilibrium of its curves.
    r = fig5.stability()
    eq = r.operating.equilibrium
    assert eq is not None
    long = fig5.simulate(2.0, dt=1e-3, method="implicit")
    np.testing.assert_allclose(long.speeds[-1], eq, rtol=1e-3, atol=1e-2)
    json.dumps(s.to_dict())


def test_python_torque_law_equals_the_curves(fig5: egt.Train) -> None:
    a = fig5.simulate(0.2, dt=1e-3)
    b = fig5.simulate(0.2, dt=1e-3, torque=linear_torque)
    c = fig5.simulate(0.2, dt=1e-3, curves=CURVES)
    np.testing.assert_allclose(b.speeds, a.speeds, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(c.speeds, a.speeds, rtol=1e-12, atol=1e-12)


def test_python_torque_errors_are_reraised(fig5: egt.Train) -> None:
    def boom(t: float, w: np.ndarray) -> np.ndarray:
        raise ZeroDivisionError("from the torque law")

    with pytest.raises(ZeroDivisionError, match="torque law"):
        fig5.simulate(0.1, torque=boom)
    with pytest.raises(ValueError, match="torques for 6 links"):
        fig5.simulate(0.1, torque=lambda t, w: np.zeros(3))
    with pytest.raises(TypeError, match="NumPy array"):
        fig5.simulate(0.1, torque=lambda t, w: [0.0] * 6)  # type: ignore[arg-type,return-value]
    with pytest.raises(TypeError, match="callable"):
        fig5.simulate(0.1, torque=3.0)  # type: ignore[arg-type]


def test_simulation_arguments(fig5: egt.Train) -> None:
    with pytest.raises(ValueError, match="integrator"):
        fig5.simulate(0.1, method="euler")
    with pytest.raises(ValueError, match="t_end"):
        fig5.simulate(-1.0)
    with pytest.raises(egt.SpecError):  # no t_end anywhere
        fig5.simulate()
    with pytest.raises(ValueError, match="not both"):
        fig5.simulate(0.1, curves=CURVES, torque=linear_torque)
    s = fig5.simulate(0.1, dt=1e-3, initial={"2": 250.0, "4": 90.0}, every=10)
    assert s.speed("2")[0] == pytest.approx(250.0, rel=1e-14)
    assert len(s.t) == 11


def test_simulation_to_pandas(fig5: egt.Train) -> None:
    import pandas  # noqa: F401  (a dev requirement: missing, the test fails)
    df = fig5.simulate(0.01, dt=1e-3).to_pandas()
    assert df.index.name == "t" and "energy" in df.columns
