"""Batch evaluation: results equal single calls, NumPy dtype and shape
handling, per-row errors without NaN, threads, the GIL released."""

from __future__ import annotations

import os
import threading
from typing import List, Optional

import numpy as np
import pytest

import egt

RNG = np.random.default_rng(20240601)


def _teeth_rows(rows: int) -> np.ndarray:
    # Fig. 3 style: z_11 = z_31 + ..., any positive counts will do for kinematics.
    z = RNG.integers(12, 80, size=(rows, 2, 2))
    return z


def test_batch_kinematics_equals_single_calls(fig3: egt.Train) -> None:
    teeth = _teeth_rows(64)
    speeds = RNG.uniform(-300, 300, size=64)
    b = fig3.batch_kinematics({"2": speeds}, teeth=teeth)
    assert b.speeds.shape == (64, 4) and b.speeds.dtype == np.float64
    for r in range(64):
        spec_train = _fig3_with_teeth(teeth[r])
        if not b.ok[r]:
            with pytest.raises(egt.AnalysisError):
                spec_train.kinematics({"2": float(speeds[r])})
            continue
        single = spec_train.kinematics({"2": float(speeds[r])})
        np.testing.assert_allclose(b.speeds[r], single.speeds, rtol=1e-13, atol=1e-12)
        assert b.condition[r] >= 1.0


def _fig3_with_teeth(z: np.ndarray) -> egt.Train:
    from conftest import FIG3

    s = FIG3.replace("teeth = [30, 20]", f"teeth = [{z[0, 0]}, {z[0, 1]}]").replace(
        "teeth = [18, 32]", f"teeth = [{z[1, 0]}, {z[1, 1]}]"
    )
    return egt.loads(s.replace("module = 2.0e-3\n", ""))


def test_batch_ratios_broadcast_and_match(fig5: egt.Train) -> None:
    ratios = np.array([-3.0, -1.5, 3.5])
    b = fig5.batch_kinematics({"2": [300.0, 100.0], "4": 100.0}, ratios=ratios)
    assert len(b) == 2 and b.ok.all()
    single = fig5.kinematics({"2": 100.0, "4": 100.0})
    np.testing.assert_allclose(b.speeds[1], single.speeds, rtol=1e-14)
    np.testing.assert_allclose(b.speed("6")[0], fig5.kinematics()["6"], rtol=1e-14)


def test_batch_dynamics_equals_single_calls(fig3: egt.Train) -> None:
    rows = 40
    inertia3 = RNG.uniform(1e-5, 1e-4, rows)
    mass3 = RNG.uniform(0.05, 0.2, rows)
    load = RNG.uniform(-80, 0, rows)
    alpha = RNG.uniform(-20, 20, rows)
    b = fig3.batch_dynamics(
        ["2"],
        accelerations={"4": alpha},
        torques={"4": load},
        inertias={"3": inertia3},
        masses={"3": mass3},
    )
    assert b.ok.all() and b.driving_torques.shape == (rows, 1)
    from conftest import FIG3

    for r in range(0, rows, 7):
        spec = FIG3.replace("inertia = 4.0e-5", f"inertia = {float(inertia3[r])!r}").replace(
            "mass = 0.12", f"mass = {float(mass3[r])!r}"
        )
        single = egt.loads(spec).dynamics(
            torques={"4": float(load[r])}, accelerations={"4": float(alpha[r])}, driving=["2"]
        )
        assert b.driving_torque("2")[r] == pytest.approx(single.driving_torques["2"], rel=1e-12)
        np.testing.assert_allclose(b.accelerations[r], single.accelerations, rtol=1e-13)
        np.testing.assert_allclose(b.multipliers[r], single.multipliers, rtol=1e-12)
        g1 = single.meshes[0].force
        assert g1 is not None
        assert b.forces["G1"][r] == pytest.approx(g1[0], rel=1e-12)


def test_batch_dynamics_defaults_are_the_spec(fig3: egt.Train) -> None:
    b = fig3.batch_dynamics()
    assert b.driving == ("2",)
    assert b.driving_torque("2")[0] == pytest.approx(fig3.dynamics().driving_torques["2"], rel=1e-13)


def test_static_batch_dynamics(fig3: egt.Train) -> None:
    b = fig3.batch_dynamics(["2"], torques={"4": [-10.0, -20.0]}, accelerations={})
    single = fig3.dynamics(torques={"4": -20.0}, accelerations={}, driving=["2"])
    assert b.driving_torque("2")[1] == pytest.approx(single.driving_torques["2"], rel=1e-13)
    assert not b.accelerations.any()


def test_bad_rows_are_flagged_not_nan(fig3: egt.Train) -> None:
    teeth = np.array([[[30, 20], [18, 32]], [[0, 20], [18, 32]], [[30, 20], [18, 27]], [[30, 20], [18, 32]]])
    b = fig3.batch_kinematics({"4": [1.0, 1.0, 1.0, np.nan]}, teeth=teeth)
    assert list(b.ok) == [True, False, False, False]
    assert not np.isnan(b.speeds).any() and not np.isnan(b.condition).any()
    assert (b.speeds[~b.ok] == 0).all()
    assert b.errors[1].kind == "invalid_teeth" and "G1" in b.errors[1].message
    assert b.errors[2].kind in ("singular", "ill_conditioned")  # tau_1 tau_2 = 1
    assert b.errors[3].kind == "out_of_range" and "speed.4" in b.errors[3].message
    assert set(b.errors) == {1, 2, 3}
    b.to_dict()


def test_bad_dynamics_rows(fig3: egt.Train) -> None:
    b = fig3.batch_dynamics(["2"], accelerations={"4": 1.0}, inertias={"3": [1e-5, -1.0, np.inf]})
    assert list(b.ok) == [True, False, False]
    assert not np.isnan(b.driving_torques).any()
    assert "inertia.3" in b.errors[1].message


def test_dtypes_are_converted(fig3: egt.Train) -> None:
    ref = fig3.batch_kinematics({"2": np.array([1.0, 2.0])})
    for speeds in (np.array([1, 2], dtype=np.int32), np.array([1, 2], dtype=np.float32), [1, 2], (1.0, 2.0)):
        b = fig3.batch_kinematics({"2": speeds})
        np.testing.assert_array_equal(b.speeds, ref.speeds)
    teeth = np.array([[30, 20], [18, 32]])
    for t in (teeth.astype(np.int16), teeth.astype(np.uint8), teeth.astype(np.float64)):
        b = fig3.batch_kinematics({"2": 1.0}, teeth=t)
        np.testing.assert_array_equal(b.speeds, fig3.batch_kinematics({"2": 1.0}).speeds)
    # Non-contiguous input is fine.
    wide = np.arange(8.0).reshape(2, 4)[:, ::2]
    b = fig3.batch_kinematics({"2": wide[:, 0]})
    assert b.ok.all()


def test_wrong_types_and_shapes_raise(fig3: egt.Train) -> None:
    with pytest.raises(TypeError):
        fig3.batch_kinematics({"2": np.array([1 + 1j])})
    with pytest.raises(TypeError):
        fig3.batch_kinematics({"2": np.array([True, False])})
    with pytest.raises(TypeError):
        fig3.batch_kinematics({"2": np.array(["a"])})
    with pytest.raises(ValueError, match="rows"):
        fig3.batch_kinematics({"2": [1.0, 2.0, 3.0]}, ratios=np.ones((2, 2)))
    with pytest.raises(ValueError, match="column"):
        fig3.batch_kinematics({"2": 1.0}, ratios=np.ones((2, 3)))
    with pytest.raises(ValueError):
        fig3.batch_kinematics({"2": np.ones((2, 2))})
    with pytest.raises(ValueError, match="whole numbers"):
        fig3.batch_kinematics({"2": 1.0}, teeth=np.full((2, 2), 20.5))
    with pytest.raises(ValueError, match="teeth"):
        fig3.batch_kinematics({"2": 1.0}, teeth=np.ones((3, 2), dtype=int))
    with pytest.raises(ValueError, match="not both"):
        fig3.batch_kinematics({"2": 1.0}, ratios=[-1.0, -2.0], teeth=np.ones((2, 2), dtype=int))
    plan = fig3.batch("kinematics")
    with pytest.raises(ValueError, match="shape"):
        plan.run(np.ones((3, len(plan.parameters) + 1)))
    with pytest.raises(KeyError):
        plan.params({"ratio.G9": 1.0})
    with pytest.raises(ValueError, match="threads"):
        plan.run(plan.base, threads=0)


def test_unknown_links_in_batches_are_spec_errors(fig3: egt.Train) -> None:
    with pytest.raises(egt.SpecError):
        fig3.batch_kinematics({"22": 1.0})
    with pytest.raises(egt.InputError):
        fig3.batch_kinematics({"2": 1.0, "4": 1.0})


def test_plan_columns_and_base(fig3: egt.Train) -> None:
    plan = fig3.batch("dynamics")
    assert plan.parameters[:2] == ("ratio.G1", "ratio.G2")
    assert "force.G1" in plan.outputs
    base = plan.base
    assert base[plan.column("speed.2")] == 100.0
    res = plan.run(base)
    assert len(res) == 1 and res.ok.all()
    assert res.driving == ("2",)
    assert res.driving_torque("2")[0] == pytest.approx(fig3.dynamics().driving_torques["2"], rel=1e-13)
    with pytest.raises(KeyError):
        res["nope"]
    p, bad = plan.params({"accel.4": [0.0, 1.0, 2.0]})
    assert p.shape == (3, len(plan.parameters)) and not bad


@pytest.mark.parametrize("bounds", [False, True])
def test_chosen_outputs_are_the_full_plans_columns(fig3: egt.Train, bounds: bool) -> None:
    # Fig. 3 near its lock (refused and warned rows), every row its own train.
    g2 = np.repeat(np.linspace(-1.5000001, -1.4999999, 21), 8)
    load = np.tile(np.linspace(-10.0, -50.0, 8), 21)
    values = {"ratio.G2": g2, "torque.4": load}
    chosen = ["cond.forces", "driving_torque.2", "speed.4"]
    full = fig3.batch("dynamics", condition_bounds=bounds).evaluate(values)
    plan = fig3.batch("dynamics", condition_bounds=bounds, outputs=chosen)
    assert plan.outputs == tuple(chosen)
    some = plan.evaluate(values)
    assert some.outputs == tuple(chosen) and some.values.shape == (len(g2), 3)
    np.testing.assert_array_equal(full.ok, some.ok)
    assert (~some.ok).sum() >= 8
    assert {r: e.message for r, e in full.errors.items()} == {r: e.message for r, e in some.errors.items()}
    for name in chosen:
        np.testing.assert_array_equal(full[name], some[name])
    # The choice travels with the plan (a Dask worker rebuilds it).
    import pickle

    again = pickle.loads(pickle.dumps(plan))
    assert again.outputs == tuple(chosen)
    np.testing.assert_array_equal(again.evaluate(values).values, some.values)


def test_a_bad_output_choice_is_refused_by_name(fig3: egt.Train) -> None:
    with pytest.raises(egt.SpecError, match="`force.nowhere`"):
        fig3.batch("dynamics", outputs=["speed.4", "force.nowhere"])
    with pytest.raises(egt.SpecError, match="chosen twice"):
        fig3.batch("dynamics", outputs=["speed.4", "speed.4"])
    with pytest.raises(egt.SpecError, match="no output column"):
        fig3.batch("dynamics", outputs=[])
    with pytest.raises(TypeError, match="outputs"):
        fig3.batch("dynamics", outputs="speed.4")


def test_condition_bounds_keep_every_refusal_and_number_to_rounding(fig3: egt.Train) -> None:
    # Fig. 3 swept through its lock (tau_2 = 1 / tau_1 = -1.5): the rows next
    # to it are ill-conditioned, the lock itself is refused (those rows pivot
    # unlike the base row, so the program leaves them to the row-by-row
    # solve); and near the spec's own tau_2, where the program solves and
    # bounds the conditions.
    plain = fig3.batch("dynamics")
    t2 = plain.base[plain.parameters.index("ratio.G2")]
    lock = np.repeat(np.linspace(-1.5000001, -1.4999999, 21), 8)
    g2 = np.concatenate([lock, np.repeat(t2 * np.linspace(0.999, 1.001, 21), 8)])
    load = np.tile(np.linspace(-10.0, -50.0, 8), 42)
    values = {"ratio.G2": g2, "torque.4": load}
    full = plain.evaluate(values)
    fast = fig3.batch("dynamics", condition_bounds=True).evaluate(values)
    assert full.outputs == fast.outputs
    np.testing.assert_array_equal(full.ok, fast.ok)
    assert {r: e.message for r, e in full.errors.items()} == {r: e.message for r, e in fast.errors.items()}
    assert (~full.ok).sum() >= 8
    conds = [k for k, o in enumerate(full.outputs) if o.startswith("cond.")]
    others = [k for k in range(len(full.outputs)) if k not in conds]
    # The rows the straight-line program solves differ by rounding only.
    x, y = full.values[:, others], fast.values[:, others]
    ok = full.ok
    scale = np.abs(x[ok]).max(axis=1, keepdims=True)
    assert (np.abs(x[ok] - y[ok]) <= 1e-12 * scale).all()
    np.testing.assert_array_equal(x[~ok], y[~ok])
    a, b = full.values[:, conds], fast.values[:, conds]
    moved = ~((a == b) | (np.isnan(a) & np.isnan(b)))
    assert moved.sum() > 100
    # A changed condition is an upper bound of the estimate, below the warning level.
    assert (b[moved] >= a[moved]).all() and (b[moved] <= 5e7).all()
    # Every condition past the warning level is the estimate itself.
    warned = full.ok[:, None] & (a > 1e8)
    assert warned.sum() >= 16 and not moved[warned].any()


def test_power_batch(fig3: egt.Train) -> None:
    plan = fig3.batch("power")
    res = plan.evaluate({"efficiency.G1": [0.9, 0.98, 1.0], "efficiency.G2": 0.98})
    assert res.ok.all()
    single = fig3.power()  # the spec's efficiencies: 0.98 on both meshes
    assert single.efficiency is not None
    assert res["power.efficiency"][1] == pytest.approx(single.efficiency, rel=1e-12)
    assert res["power.loss"][1] == pytest.approx(single.loss, rel=1e-12)
    inp, out, loss, kr = (res[f"power.{k}"] for k in ("input", "output", "loss", "kinetic_rate"))
    np.testing.assert_allclose(inp - out - loss - kr, 0.0, atol=1e-9 * inp.max())
    assert loss[0] > loss[1] > loss[2] > 0


def test_threads_give_the_same_answer(fig3: egt.Train) -> None:
    teeth = _teeth_rows(3000)
    a = fig3.batch_kinematics({"2": 1.0}, teeth=teeth, threads=1)
    b = fig3.batch_kinematics({"2": 1.0}, teeth=teeth, threads=2)
    c = fig3.batch_kinematics({"2": 1.0}, teeth=teeth)
    np.testing.assert_array_equal(a.speeds, b.speeds)
    np.testing.assert_array_equal(a.speeds, c.speeds)
    assert a.errors.keys() == b.errors.keys()


def test_the_gil_is_released(fig3: egt.Train) -> None:
    # While a long batch runs in a thread, this thread keeps executing Python.
    plan = fig3.batch("dynamics")
    params, _ = plan.params({"accel.4": RNG.uniform(-1, 1, 400_000)})
    started, done = threading.Event(), threading.Event()

    def work() -> None:
        started.set()
        plan.run(params, threads=1)
        done.set()

    t = threading.Thread(target=work)
    t.start()
    started.wait()
    ticks = 0
    while not done.is_set():
        ticks += 1
    t.join()
    assert ticks > 1000


def test_batch_results_to_pandas(fig3: egt.Train) -> None:
    import pandas  # noqa: F401  (a dev requirement: missing, the test fails)
    b = fig3.batch_kinematics({"2": [1.0, 2.0]})
    assert b.to_pandas().shape == (2, 6)
    assert fig3.batch_dynamics().to_pandas().shape[0] == 1


def test_documented_run_of_params_and_exact_echo(fig3: egt.Train) -> None:
    plan = fig3.batch("kinematics")
    teeth = np.array([[[30, 20], [18, 32]], [[0, 20], [18, 32]]])
    res = plan.run(plan.params({"speed.2": [75.0, 0.0]}, teeth=teeth))
    assert list(res.ok) == [True, False] and res.errors[1].kind == "invalid_teeth"
    assert (res.values[1] == 0).all()
    # Input speeds come back as given, and no -0.0 is written.
    b = fig3.batch_kinematics({"2": [75.0, 0.0]})
    assert b.speed("2")[0] == 75.0
    assert not np.signbit(b.speeds[1]).any()


@pytest.mark.parametrize("bounds", [False, True])
def test_fortran_and_c_ordered_params_give_the_same_numbers(fig3: egt.Train, bounds: bool) -> None:
    # Through the lock, as above: program rows, left rows, refused rows.
    plan = fig3.batch("dynamics", condition_bounds=bounds)
    g2 = np.repeat(np.linspace(-1.5000001, -1.4999999, 21), 40)
    load = np.tile(np.linspace(-10.0, -50.0, 40), 21)
    p, bad = plan.params({"ratio.G2": g2, "torque.4": load})
    assert not bad
    assert p.flags.f_contiguous and not p.flags.c_contiguous
    p[5, plan.column("ratio.G1")] = np.nan
    by_columns = plan.run(p)
    by_rows = plan.run(np.ascontiguousarray(p))
    assert by_columns.values.flags.f_contiguous and not by_columns.values.flags.c_contiguous
    assert by_rows.values.flags.c_contiguous
    assert by_columns.values.view(np.int64).tolist() == by_rows.values.view(np.int64).tolist()
    np.testing.assert_array_equal(by_columns.ok, by_rows.ok)
    assert {r: e.message for r, e in by_columns.errors.items()} == {r: e.message for r, e in by_rows.errors.items()}
    assert (~by_rows.ok).sum() >= 9 and 5 in by_rows.errors
    # threads=1 solves on the calling thread, with no pool: the same again.
    for layout in (p, np.ascontiguousarray(p)):
        here = plan.run(layout, threads=1)
        assert here.values.view(np.int64).tolist() == by_rows.values.view(np.int64).tolist()
        assert {r: e.message for r, e in here.errors.items()} == {r: e.message for r, e in by_rows.errors.items()}
    # A column of the result is a view, contiguous.
    assert all(by_columns[o].flags.c_contiguous for o in by_columns.outputs)


@pytest.mark.parametrize("outputs", [None, ["driving_torque.2", "speed.4"]])
def test_a_mapping_of_columns_gives_the_matrix_numbers_without_building_it(
    fig3: egt.Train, outputs: Optional[List[str]]
) -> None:
    # Through the lock, as above (program rows, left rows, refused rows),
    # a load per row, a fixed inertia, and a NaN row.
    plan = fig3.batch("dynamics", outputs=outputs)
    g2 = np.repeat(np.linspace(-1.5000001, -1.4999999, 21), 40)
    g2[5] = np.nan
    load = np.tile(np.linspace(-10.0, -50.0, 40), 21)
    inertia = [n for n in plan.parameters if n.startswith("inertia.")][0]
    values = {"ratio.G2": g2, "torque.4": load, inertia: 0.5}
    p, _ = plan.params(values)
    for threads in (None, 1):
        matrix = plan.run(p, threads=threads)
        mapped = plan.run(values, threads=threads)
        evaluated = plan.evaluate(values, threads=threads)
        for r in (mapped, evaluated):
            assert r.values.flags.f_contiguous
            assert r.values.view(np.int64).tolist() == matrix.values.view(np.int64).tolist()
            np.testing.assert_array_equal(r.ok, matrix.ok)
            assert {k: e.message for k, e in r.errors.items()} == {k: e.message for k, e in matrix.errors.items()}
    assert 5 in matrix.errors and (~matrix.ok).sum() >= 9
    # The fixed inertia is used (not the spec's): another value moves the torque.
    other = plan.run({**values, inertia: 5.0})
    torque = plan.outputs.index("driving_torque.2")
    assert (other.values[matrix.ok, torque] != matrix.values[matrix.ok, torque]).any()
    # Scalars only: one row (or `rows` of them), the base row's numbers.
    one = plan.run({"torque.4": -20.0})
    assert one.values.shape == (1, len(plan.outputs))
    three = plan.evaluate({"torque.4": -20.0}, rows=3)
    assert three.values.view(np.int64).tolist() == np.repeat(one.values, 3, axis=0).view(np.int64).tolist()
    # Bad mappings are refused, naming what is wrong.
    with pytest.raises(KeyError, match="no parameter column 'torque.99'"):
        plan.run({"torque.99": [1.0, 2.0]})
    with pytest.raises(ValueError, match="has 2 rows but"):
        plan.run({"torque.4": [1.0, 2.0, 3.0], "ratio.G2": [-1.2, -1.3]})
    with pytest.raises(ValueError, match="rows=2 disagrees"):
        plan.evaluate({"torque.4": [1.0, 2.0, 3.0]}, rows=2)
    with pytest.raises(ValueError, match="dimension"):
        plan.run({"torque.4": [[1.0, 2.0]]})
    # Rows past the memory: refused, as NumPy refuses the matrix, not aborted.
    with pytest.raises(MemoryError, match=f"the outputs of {2**40} rows"):
        plan.evaluate({"torque.4": -20.0}, rows=2**40)


def test_both_executors_of_the_program_give_the_same_numbers(fig3: egt.Train) -> None:
    # Every row its own train, some refused at the lock: the program as the
    # machine runs it by default (compiled where it can be) against the
    # interpreter, bit for bit.
    g2 = np.linspace(-3.0, -1.0, 301)
    load = np.linspace(-10.0, -50.0, 301)
    values = {"ratio.G2": g2, "torque.4": load}
    chosen = ["driving_torque.2", "speed.4"]
    auto = fig3.batch("dynamics", outputs=chosen)
    assert auto.program in ("compiled", "interpreted")
    interpreted = fig3.batch("dynamics", outputs=chosen, executor="interpreted")
    assert interpreted.program == "interpreted"
    reference = interpreted.evaluate(values)
    assert 0 < (~reference.ok).sum() < len(g2)
    got = auto.evaluate(values)
    np.testing.assert_array_equal(got.values, reference.values)
    np.testing.assert_array_equal(got.ok, reference.ok)
    # A name that is no executor is refused by name; a plan without a
    # program takes either executor.
    with pytest.raises(ValueError, match='executor must be "auto" or "interpreted", got "AVX2"'):
        fig3.batch("dynamics", outputs=chosen, executor="AVX2")
    assert fig3.batch("dynamics", executor="interpreted").program is None


def test_chosen_outputs_without_a_condition_column_take_the_program(fig3: egt.Train) -> None:
    # Every row its own train, some near the lock (warned) and at it (refused).
    g2 = np.repeat(np.linspace(-1.5000001, -1.4999999, 21), 8)
    g2[::7] = np.linspace(-3.0, -2.0, len(g2[::7]))
    load = np.tile(np.linspace(-10.0, -50.0, 8), 21)
    values = {"ratio.G2": g2, "torque.4": load}
    chosen = ["driving_torque.2", "speed.4"]
    auto = fig3.batch("dynamics", outputs=chosen)
    forced = fig3.batch("dynamics", outputs=chosen, condition_bounds=True)
    estimated = fig3.batch("dynamics", outputs=chosen, condition_bounds=False)
    # The program runs by default when no cond.* column is chosen...
    expected = ("interpreted",) if os.environ.get("EGT_JIT") == "0" else ("compiled", "interpreted")
    assert auto.program in expected and forced.program == auto.program
    # ...and not when one is, nor when every output is wanted, nor when refused.
    assert fig3.batch("dynamics", outputs=["cond.forces", "speed.4"]).program is None
    assert fig3.batch("dynamics").program is None
    assert estimated.program is None
    a, f, e = (p.evaluate(values) for p in (auto, forced, estimated))
    np.testing.assert_array_equal(a.values, f.values)
    # Against condition estimates: the same failed rows and messages, the
    # same numbers to rounding.
    np.testing.assert_array_equal(a.ok, e.ok)
    assert 0 < (~a.ok).sum() < len(g2)
    assert {r: x.message for r, x in a.errors.items()} == {r: x.message for r, x in e.errors.items()}
    scale = np.abs(e.values[e.ok]).max(axis=1, keepdims=True)
    assert (np.abs(a.values[a.ok] - e.values[e.ok]) <= 1e-12 * scale).all()
