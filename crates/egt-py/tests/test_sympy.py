"""The paper's symbolic derivations, redone from the train's structure.

Example 6.1 (Fig. 3): T_d, F31, F32, F42 from eq. (8)-(11).
Example 6.2 (Fig. 5): [V], the reduced [M] (eq. 25) and [K] (eq. 26).
Each is compared with the expression printed in the paper by
``sympy.simplify(ours - printed) == 0``; where the paper is wrong the
comparison is with the corrected form and cites docs/errata.md.
"""

from __future__ import annotations

import numpy as np
import pytest

import egt

import sympy as sp


@pytest.fixture
def fig3_sym(fig3: egt.Train):  # type: ignore[no-untyped-def]
    return fig3.to_sympy()


def zero(e) -> bool:  # type: ignore[no-untyped-def]
    return sp.simplify(e) == 0


def test_symbols_are_named_as_in_the_paper(fig3_sym) -> None:  # type: ignore[no-untyped-def]
    names = set(fig3_sym.symbols)
    assert {"tau_1", "tau_2", "I_2", "I_3", "I_4", "m_3", "n_s3", "delta_ab"} <= names
    assert {"omega_2", "omega_3", "omega_4"} <= names
    assert fig3_sym.tau == (sp.Symbol("tau_1"), sp.Symbol("tau_2"))
    assert fig3_sym.radius("3", 1) == sp.Symbol("r_31")
    assert fig3_sym.offset("b", "a") == sp.Symbol("delta_ab")


def test_example_61_kinematics(fig3_sym) -> None:  # type: ignore[no-untyped-def]
    t1, t2 = fig3_sym.tau
    w2, w3, w4 = fig3_sym.omega
    # Printed: psi_1 = t1 w3 + (1 - t1) w2, psi_2 = w3 - t2 w4 + (t2 - 1) w2. Our
    # psi_1 has gear i = 1 (the frame), gear j = 3: the printed row times -1
    # (docs/errata.md, "columns of the printed Jacobian").
    psi1, psi2 = fig3_sym.willis
    assert zero(psi1 + (t1 * w3 + (1 - t1) * w2))
    assert zero(psi2 - (w3 - t2 * w4 + (t2 - 1) * w2))
    # The printed [psi_w] read with columns (w3, w2, w4), up to the sign of row 1.
    printed = sp.Matrix([[t1, 1 - t1, 0], [1, t2 - 1, -t2]])
    j = fig3_sym.jacobian
    reordered = sp.Matrix([[-j[0, 1], -j[0, 0], -j[0, 2]], [j[1, 1], j[1, 0], j[1, 2]]])
    assert (reordered - printed).applyfunc(sp.simplify) == sp.zeros(2, 3)


def test_example_61_mass_matrix(fig3_sym) -> None:  # type: ignore[no-untyped-def]
    S = fig3_sym.symbol
    I2, I3, I4, m3, n, d = (S(x) for x in ("I_2", "I_3", "I_4", "m_3", "n_s3", "delta_ab"))
    printed = sp.diag(I2 + m3 * n * d**2, I3 * n, I4)
    assert (fig3_sym.mass_matrix - printed).applyfunc(sp.simplify) == sp.zeros(3, 3)
    w2, w3, w4 = fig3_sym.omega
    K = sp.Rational(1, 2) * (I2 + n * m3 * d**2) * w2**2 + sp.Rational(1, 2) * n * I3 * w3**2 + sp.Rational(1, 2) * I4 * w4**2
    assert zero(fig3_sym.kinetic_energy - K)


def test_example_61_driving_torque_and_meshing_forces(fig3_sym) -> None:  # type: ignore[no-untyped-def]
    S = fig3_sym.symbol
    t1, t2 = fig3_sym.tau
    I2, I3, I4, m3, n, d = (S(x) for x in ("I_2", "I_3", "I_4", "m_3", "n_s3", "delta_ab"))
    Tr, a = sp.symbols("T_r alpha_out")
    dyn = fig3_sym.inverse_dynamics(torques={"4": Tr}, accelerations={"4": a}, driving=["2"])

    # Accelerations from eq. (8), as printed.
    assert zero(dyn.accelerations["2"] - t1 * t2 / (t1 * t2 - 1) * a)
    assert zero(dyn.accelerations["3"] - (t1 - 1) * t2 / (t1 * t2 - 1) * a)

    # T_d as printed reads T_r as a resisting magnitude, Q_4 = -T_r; with
    # Q = {T_d, 0, T_r} of eq. (6) the sign of T_r flips (docs/errata.md,
    # "Example 6.1: the sign of T_r in the printed driving torque").
    printed_td = Tr * (1 - 1 / (t1 * t2)) + a * (
        (I2 + m3 * d**2 * n) * t1 * t2 / (t1 * t2 - 1)
        + I3 * n * t2 * (t1 - 1) ** 2 / (t1 * (t1 * t2 - 1))
        + I4 * (1 - 1 / (t1 * t2))
    )
    td = dyn.driving_torques["2"]
    assert zero(td.subs(Tr, -Tr) - printed_td)
    assert not zero(td - printed_td)
    corrected_td = printed_td.subs(Tr, -Tr)
    assert zero(td - corrected_td)

    # The printed meshing forces use Q_4 = +T_r (eq. 11).
    r31, r32, r42 = fig3_sym.radius("3", 1), fig3_sym.radius("3", 2), fig3_sym.radius("4", 2)
    F31 = (Tr - I4 * a) / (r31 * t2) - I3 * n * t2 * (t1 - 1) / (r31 * (t1 * t2 - 1)) * a
    F32 = -(Tr - I4 * a) / (r32 * t2)
    F42 = (Tr - I4 * a) / r42
    assert zero(dyn.mesh_force("3", 1) - F31)
    assert zero(dyn.mesh_force("3", "G2") - F32)
    assert zero(dyn.mesh_force("4", 2) - F42)
    assert dyn.mesh_force("4", 1) == 0  # F41 = 0: link 4 is not on circuit 1
    # lambda*_{jG+1} = 0 is what fixed T_d (eq. 10).
    assert zero(dyn.lambda_star[2])


def test_example_61_symbolic_matches_numeric(fig3: egt.Train, fig3_sym) -> None:  # type: ignore[no-untyped-def]
    vals = fig3_sym.values()
    m = np.array(fig3_sym.mass_matrix.subs(vals).evalf(), dtype=float)
    np.testing.assert_allclose(m, fig3.mass_matrix().matrix, rtol=1e-14)
    j = np.array(fig3_sym.jacobian.subs(vals).evalf(), dtype=float)
    np.testing.assert_allclose(j, fig3.willis_jacobian(), rtol=1e-15)
    Tr, a = sp.symbols("T_r alpha_out")
    dyn = fig3_sym.inverse_dynamics(torques={"4": Tr}, accelerations={"4": a}, driving=["2"])
    td = float(dyn.driving_torques["2"].subs(vals).subs({Tr: -50.0, a: 10.0}))
    assert td == pytest.approx(fig3.dynamics().driving_torques["2"], rel=1e-12)
    f31 = float(dyn.mesh_force("3", 1).subs(vals).subs({Tr: -50.0, a: 10.0}))
    g1 = fig3.dynamics().meshes[0].force
    assert g1 is not None and f31 == pytest.approx(g1[1], rel=1e-12)


def test_example_62_reduced_matrices(fig5: egt.Train) -> None:
    st = fig5.to_sympy(inputs=["2", "4"])
    S = st.symbol
    t1, t2, t3 = st.tau
    I2, I3, I4, I5, I6, m5, dbc = (S(x) for x in ("I_2", "I_3", "I_4", "I_5", "I_6", "m_5", "delta_bc"))

    # Printed Willis Jacobian of Table 2 (with 6 at level b, docs/errata.md).
    printed_psi = sp.Matrix([[1, -t1, 0, 0, 0], [0, t2 - 1, -t2, 1, 0], [0, t3 - 1, 0, 1, -t3]])
    assert (st.jacobian - printed_psi).applyfunc(sp.simplify) == sp.zeros(3, 5)

    printed_V = sp.Matrix(
        [[1, 0], [1 / t1, 0], [0, 1], [(1 - t2) / t1, t2], [(t3 - t2) / (t1 * t3), t2 / t3]]
    )
    assert st.velocity_matrix is not None
    assert (st.velocity_matrix - printed_V).applyfunc(sp.simplify) == sp.zeros(5, 2)
    assert (st.jacobian * st.velocity_matrix).applyfunc(sp.simplify) == sp.zeros(3, 2)  # eq. (24)

    # The paper's 6.2 treats one planet: n_s5 = 1.
    assert st.reduced_mass_matrix is not None
    M = st.reduced_mass_matrix.subs(S("n_s5"), 1)
    M11 = I2 + (I3 + m5 * dbc**2) / t1**2 + ((t2 - 1) / t1) ** 2 * I5 + ((t2 - t3) / (t1 * t3)) ** 2 * I6
    M12 = (1 - t2) * t2 / t1 * I5 + (t3 - t2) * t2 / (t1 * t3**2) * I6
    M22 = I4 + I5 * t2**2 + t2**2 / t3**2 * I6
    assert zero(M[0, 0] - M11) and zero(M[0, 1] - M12) and zero(M[1, 0] - M12) and zero(M[1, 1] - M22)

    # The printed [K] = [V]^T {T} means V^T diag(K) V (docs/errata.md), with the
    # curves on 2 (K_d1), 4 (K_d2) and 6 (K_r).
    Kd1, Kd2, Kr = sp.symbols("K_d1 K_d2 K_r")
    assert st.slopes == {"2": S("K_2"), "4": S("K_4"), "6": S("K_6")}
    assert st.reduced_stiffness is not None
    K = st.reduced_stiffness.subs({S("K_2"): Kd1, S("K_4"): Kd2, S("K_6"): Kr})
    K11 = Kd1 + ((t2 - t3) / (t1 * t3)) ** 2 * Kr
    K12 = t2 * (t3 - t2) / (t1 * t3**2) * Kr
    K22 = Kd2 + t2**2 / t3**2 * Kr
    assert zero(K[0, 0] - K11) and zero(K[0, 1] - K12) and zero(K[1, 0] - K12) and zero(K[1, 1] - K22)


def test_example_62_symbolic_matches_numeric(fig5: egt.Train) -> None:
    st = fig5.to_sympy(inputs=["2", "4"])
    vals = st.values()
    assert st.reduced_mass_matrix is not None
    m = np.array(st.reduced_mass_matrix.subs(vals).evalf(), dtype=float)
    np.testing.assert_allclose(m, fig5.reduced_mass_matrix(["2", "4"]), rtol=1e-13)
    v = np.array(st.velocity_matrix_for(["2", "4"]).subs(vals).evalf(), dtype=float)
    np.testing.assert_allclose(v, fig5.velocity_matrix(["2", "4"]), rtol=1e-14)


def test_spec_inputs_are_the_default(fig5: egt.Train) -> None:
    st = fig5.to_sympy()
    assert st.inputs == ("2", "4") and st.reduced_mass_matrix is not None


def test_symbolic_errors(fig3_sym) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(KeyError):
        fig3_sym.speed("9")
    with pytest.raises(KeyError):
        fig3_sym.radius("3", 5)
    with pytest.raises(ValueError, match="DOF"):
        fig3_sym.inverse_dynamics(torques={}, accelerations={}, driving=["2"])
    with pytest.raises(ValueError, match="determine"):
        fig3_sym.velocity_matrix_for(["3", "4"])
    from egt.sympy_export import SymbolicTrain

    with pytest.raises(TypeError):
        SymbolicTrain()


def test_planet_names_are_sanitised(planetary: egt.Train) -> None:
    st = planetary.to_sympy(inputs=["sun"])
    assert "I_P_planet" in st.symbols and "n_s_P_planet" in st.symbols
    assert "m_P_planet" in st.symbols
    assert st.reduced_mass_matrix is not None
    vals = st.values()
    m = float(st.reduced_mass_matrix.subs(vals)[0, 0])
    assert m == pytest.approx(planetary.equivalent_inertia("sun"), rel=1e-12)


def test_numeric_gives_float_arrays_equal_to_the_float_path(fig3: egt.Train) -> None:
    train = fig3
    st = train.to_sympy()
    m = st.numeric(st.mass_matrix)
    assert m.dtype == np.float64
    np.testing.assert_allclose(m, train.mass_matrix().matrix, rtol=1e-14)
    tr = sp.Symbol("T_r")
    dyn = st.inverse_dynamics(torques={"4": tr}, accelerations={"4": 10.0}, driving=["2"])
    with pytest.raises(egt.ArgumentError, match="T_r"):
        st.numeric(dyn.driving_torques["2"])
    t_d = st.numeric(dyn.driving_torques["2"], {tr: -50.0})
    assert t_d.shape == ()
    ref = train.dynamics(torques={"4": -50.0}, accelerations={"4": 10.0}, driving=["2"])
    assert float(t_d) == pytest.approx(ref.driving_torques["2"], rel=1e-12)
