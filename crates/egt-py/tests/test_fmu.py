"""Issue 44: a transmission as an FMI 2.0 Co-Simulation unit (`egt fmu`),
imported by FMPy, an FMI implementation that shares no code with egt.

The unit is packaged by the cargo-built `egt` (its shared library beside it,
docs/fmu.md); FMPy validates its model description, and FMPy's FMU2Slave
drives it step by step against `egt shift-sim` of the same shift. The last
tests package with the library the wheel carries: `Train.export_fmu` and the
wheel's `python -m egt fmu`."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any, Dict, Iterator, List, Tuple

import pytest

fmpy = pytest.importorskip("fmpy")
tomllib = pytest.importorskip("tomllib")

from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"
SPEC = EXAMPLES / "zf_8hp70.toml"


def egt_binary() -> Path:
    """The cargo-built `egt` (a no-op build after `make test-rust`), beside
    which `cargo build` leaves egt-fmu's shared library."""
    subprocess.run(["cargo", "build", "--quiet", "-p", "egt-cli", "-p", "egt-fmu"], cwd=ROOT, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "debug" / "egt"


@pytest.fixture(scope="module")
def units(tmp_path_factory: pytest.TempPathFactory) -> Dict[str, Path]:
    """`egt fmu` of the 8HP70 and the C4: the .fmu files."""
    out = tmp_path_factory.mktemp("fmu")
    egt = egt_binary()
    made = {}
    for name in ["zf_8hp70", "ford_c4_simpson"]:
        path = out / f"{name}.fmu"
        subprocess.run([str(egt), "fmu", str(EXAMPLES / f"{name}.toml"), "-o", str(path)], check=True,
                       capture_output=True)
        made[name] = path
    return made


@pytest.fixture(scope="module")
def zf_dir(units: Dict[str, Path]) -> str:
    directory: str = extract(str(units["zf_8hp70"]))
    return directory


@pytest.mark.parametrize("name", ["zf_8hp70", "ford_c4_simpson"])
def test_fmpy_validates_the_unit(units: Dict[str, Path], name: str) -> None:
    assert validate_fmu(str(units[name])) == []
    md = read_model_description(str(units[name]))
    assert md.fmiVersion == "2.0" and md.coSimulation is not None
    units_of = {v.name: v.unit for v in md.modelVariables}
    spec = tomllib.loads((EXAMPLES / f"{name}.toml").read_text())
    for e in spec["elements"]:
        assert units_of[f"{e['name']}.capacity"] == "N.m"
        assert units_of[f"{e['name']}.slip"] == "rad/s"
        assert units_of[f"{e['name']}.energy"] == "J"


def package(spec: Path, out: Path) -> Path:
    """`egt fmu SPEC -o OUT`."""
    subprocess.run([str(egt_binary()), "fmu", str(spec), "-o", str(out)], check=True, capture_output=True)
    return out


def test_a_train_without_elements_is_a_unit_that_simulates_as_egt_simulate(tmp_path: Path) -> None:
    """The Fig. 5 drive (two motors, a load, curves on each): its links'
    torques are the inputs, their speeds the outputs. FMPy's own loop at
    communication steps of 10 ms gives `egt simulate`'s RK4 run (dt 1 ms) and
    the energy balance E(t) - E(0) = W(t) holds over it."""
    spec = EXAMPLES / "fig5_stability.toml"
    unit = package(spec, tmp_path / "fig5.fmu")
    assert validate_fmu(str(unit)) == []
    md = read_model_description(str(unit))
    var = {v.name: v for v in md.modelVariables}
    assert var["2.torque"].causality == "input" and var["6.speed"].unit == "rad/s"
    assert var["2.initial_speed"].start == "330" and "initial_gear" not in var
    names = ["2.speed", "3.speed", "4.speed", "6.speed"]
    r = fmpy.simulate_fmu(str(unit), stop_time=1.0, output_interval=1e-2, output=names + ["work", "kinetic_energy"])
    out = subprocess.run([str(egt_binary()), "simulate", str(spec), "--format", "json"], check=True,
                         capture_output=True, text=True)
    ref = json.loads(out.stdout)
    last = ref["samples"][-1]
    for n in names:
        w = last["speeds"][ref["links"].index(n.split(".")[0])]
        assert r[-1][n] == pytest.approx(w, rel=1e-9)
    assert r[-1]["work"] == pytest.approx(last["work"], rel=1e-9)
    balance = r["kinetic_energy"] - r["kinetic_energy"][0] - r["work"]
    assert max(abs(balance)) < 1e-6 * max(r["kinetic_energy"])


MOTOR = """
frame = "0"
links = [{ name = "m", inertia = 0.5 }, { name = "o", inertia = 0.3 }]
revolutes = [{ links = ["0", "m"], level = "a" }, { links = ["0", "o"], level = "b" }]
gears = [{ links = ["m", "o"], ratio = -2.0 }]
[analysis]
curves = [{ link = "m", torque = 0.0, slope = -0.8, speed = 100.0 }]
[analysis.simulate]
initial = { m = 101.0 }
"""


def test_an_applied_torque_input_moves_a_motor_as_the_closed_form_says(tmp_path: Path) -> None:
    """A motor (slope -0.8 through 100 rad/s) geared 2:1 to a flywheel, with
    2 N m applied through the unit's input `m.torque`:
    w(t) = w_ss + (w0 - w_ss) exp(-0.8 t / J), w_ss = 100 + 2 / 0.8,
    J = 0.5 + 0.3 / 4."""
    import numpy as np

    spec = tmp_path / "motor.toml"
    spec.write_text(MOTOR)
    unit = package(spec, tmp_path / "motor.fmu")
    assert validate_fmu(str(unit)) == []
    table = np.array([(0.0, 2.0), (1.0, 2.0)], dtype=[("time", float), ("m.torque", float)])
    r = fmpy.simulate_fmu(str(unit), start_values={"dt": 1e-4}, input=table, stop_time=1.0, output_interval=1e-2,
                          output=["m.speed", "o.speed"])
    j, w_ss = 0.5 + 0.3 / 4, 100 + 2 / 0.8
    exact = w_ss + (101.0 - w_ss) * np.exp(-0.8 * r["time"] / j)
    assert max(abs(r["m.speed"] - exact)) < 1e-9 * w_ss
    assert max(abs(r["o.speed"] + 0.5 * r["m.speed"])) < 1e-12 * w_ss


def test_a_load_torque_input_that_balances_the_input_holds_the_8hp_in_second(units: Dict[str, Path]) -> None:
    """In second gear (A, B, E held), with no road load and no vehicle
    inertia, the load i T_in at the output (i the gear's speed ratio: power
    balance) holds every speed; the output delivers that load."""
    import numpy as np

    cols = ["input.torque", "output.load_torque"] + [f"{e}.capacity" for e in "ABCDE"]

    def run(load: float) -> Any:
        table = np.zeros(2, dtype=[("time", float)] + [(c, float) for c in cols])
        table["time"] = [0.0, 1.0]
        table["input.torque"] = 300.0
        table["output.load_torque"] = load
        table["A.capacity"] = table["B.capacity"] = table["E.capacity"] = 1e7
        return fmpy.simulate_fmu(str(units["zf_8hp70"]), start_values={"initial_gear": 2}, input=table,
                                 stop_time=0.1, output_interval=1e-2,
                                 output=["input.speed", "output.speed", "output.torque"])

    free = run(0.0)
    ratio = free[0]["input.speed"] / free[0]["output.speed"]
    assert free[-1]["input.speed"] > 101.0  # 300 N m and no load: it speeds up
    held = run(300.0 * ratio)
    assert max(abs(held["input.speed"] - 100.0)) < 1e-9 * 100.0
    assert max(abs(held["output.torque"] - 300.0 * ratio)) < 1e-9 * 300.0 * ratio


def shift_2_3() -> Dict[str, Any]:
    """The spec's `[[shift]] 2-3`."""
    spec = tomllib.loads(SPEC.read_text())
    shift: Dict[str, Any] = next(s for s in spec["shift"] if s["name"] == "2-3")
    return shift


def ramp_at(ramp: List[float], t: float) -> Tuple[float, float]:
    """A `[t0, t1, from, to]` ramp's value at `t` and its slope on `[t, t + dt)`."""
    t0, t1, c0, c1 = ramp
    if t < t0:
        return c0, 0.0
    if t >= t1:
        return c1, 0.0
    slope = (c1 - c0) / (t1 - t0)
    return c0 + slope * (t - t0), slope


class Unit:
    """One instance of the 8HP unit through FMPy's FMU2Slave."""

    def __init__(self, directory: str, name: str) -> None:
        self.md = read_model_description(directory)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=directory,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate()
        self.shift = shift_2_3()
        self.initialise()

    def initialise(self) -> None:
        s, vr = self.shift, self.vr
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.setInteger([vr["initial_gear"]], [2])
        names = ["initial_input_speed", "road_load_c0", "road_load_c1", "road_load_c2", "vehicle_inertia"]
        values = [s["input_speed"], *s["road_load"], s["vehicle_inertia"]]
        self.fmu.setReal([vr[n] for n in names], values)
        self.set_inputs(0.0)
        self.fmu.exitInitializationMode()
        self.t = 0.0

    def set_inputs(self, t: float) -> None:
        """The input table at `t`: the input torque, `A` and `C` on the
        spec's ramps (values and slopes), `B` and `E` held, `D` open."""
        vr, ramps = self.vr, self.shift["ramps"]
        caps = {"A": ramp_at(ramps["A"], t), "C": ramp_at(ramps["C"], t), "B": (1e7, 0.0),
                "D": (0.0, 0.0), "E": (1e7, 0.0)}
        refs = [vr["input.torque"]] + [vr[f"{e}.capacity"] for e in caps]
        self.fmu.setReal(refs, [self.shift["input_torque"]] + [c[0] for c in caps.values()])
        self.fmu.setRealInputDerivatives(refs, [1] * len(refs), [0.0] + [c[1] for c in caps.values()])

    def step(self, h: float) -> None:
        self.set_inputs(self.t)
        self.fmu.doStep(currentCommunicationPoint=self.t, communicationStepSize=h)
        self.t += h

    def get(self, *names: str) -> List[float]:
        values: List[float] = self.fmu.getReal([self.vr[n] for n in names])
        return values

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def run_unit(unit: Unit, h: float, t_end: float = 1.0) -> Iterator[List[float]]:
    for _ in range(round(t_end / h)):
        unit.step(h)
        yield unit.get("input.speed", "output.speed", "A.energy", "C.energy", "C.lock_time", "output.torque")


@pytest.fixture(scope="module")
def reference() -> Dict[str, Any]:
    """`egt shift-sim examples/zf_8hp70.toml --shift 2-3 --format json`."""
    out = subprocess.run([sys.executable, "-m", "egt", "shift-sim", str(SPEC), "--shift", "2-3", "--format", "json"],
                         capture_output=True, text=True, check=True)
    ref: Dict[str, Any] = json.loads(out.stdout)
    return ref


def speeds_at_end(ref: Dict[str, Any]) -> Tuple[float, float]:
    import egt

    links = egt.load(str(SPEC)).link_names
    speed = ref["samples"][-1]["speed"]
    return speed[links.index("input")], speed[links.index("output")]


@pytest.mark.parametrize("h", [1e-3, 1e-2])
def test_the_8hp_2_3_upshift_through_fmpy_equals_egt_shift_sim(zf_dir: str, reference: Dict[str, Any],
                                                                h: float) -> None:
    unit = Unit(zf_dir, "a")
    *_, last = run_unit(unit, h)
    unit.close()
    w_in, w_out, e_a, e_c, lock, _ = last
    # the lock falls inside a communication step, not on its boundary
    assert abs(lock / h - round(lock / h)) > 1e-3
    assert abs(lock - reference["lock_time"]) < 1e-6
    ref_in, ref_out = speeds_at_end(reference)
    assert w_in == pytest.approx(ref_in, rel=1e-6) and w_out == pytest.approx(ref_out, rel=1e-6)
    e_ref = dict(zip(reference["elements"], reference["dissipated"]))
    assert e_a == pytest.approx(e_ref["A"], rel=1e-6) and e_c == pytest.approx(e_ref["C"], rel=1e-6)


def test_two_instances_side_by_side_equal_one(zf_dir: str) -> None:
    alone = Unit(zf_dir, "alone")
    one = list(run_unit(alone, 1e-2))
    alone.close()
    a, b = Unit(zf_dir, "a"), Unit(zf_dir, "b")
    # zip steps a, then b, then a again: the two instances advance in turn
    both = list(zip(run_unit(a, 1e-2), run_unit(b, 1e-2)))
    a.close()
    b.close()
    assert [x for x, _ in both] == one and [y for _, y in both] == one


def test_reset_and_initialise_again_repeat_the_run(zf_dir: str) -> None:
    unit = Unit(zf_dir, "r")
    first = list(run_unit(unit, 1e-2, 0.3))
    unit.fmu.reset()
    unit.initialise()
    again = list(run_unit(unit, 1e-2, 0.3))
    unit.close()
    assert again == first


def test_a_nan_or_negative_input_is_an_error_and_python_goes_on(zf_dir: str,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    unit = Unit(zf_dir, "bad")
    unit.step(1e-3)
    before = unit.get("input.speed", "C.slip")
    for value in [math.nan, -5.0]:
        with pytest.raises(Exception, match="fmi2SetReal failed with status 3"):
            unit.fmu.setReal([unit.vr["C.capacity"]], [value])
    logged = capsys.readouterr().out
    assert "`C.capacity` = NaN is not finite" in logged and "`C.capacity` = -5 must be >= 0" in logged
    # refused values are not stored: the unit goes on from where it was
    assert unit.get("input.speed", "C.slip") == before
    unit.step(1e-3)
    assert unit.t == pytest.approx(2e-3) and all(math.isfinite(v) for v in unit.get("input.speed", "C.slip"))
    unit.close()


def test_simulate_fmu_runs_the_unit_on_held_inputs(units: Dict[str, Path], reference: Dict[str, Any]) -> None:
    """FMPy's own loop (`simulate_fmu`) sets the inputs at each communication
    point and holds them over the step (its `set_input_derivatives` needs
    exactly nine inputs in FMPy 0.3.32): the ramps become staircases, so the
    shift is that much later, and ends in third gear all the same."""
    import numpy as np

    s = shift_2_3()
    t = np.linspace(0.0, 1.0, 1001)
    table = np.zeros(len(t), dtype=[("time", float), ("input.torque", float)]
                     + [(f"{e}.capacity", float) for e in "ABCDE"])
    table["time"] = t
    table["input.torque"] = s["input_torque"]
    table["A.capacity"] = [ramp_at(s["ramps"]["A"], x)[0] for x in t]
    table["C.capacity"] = [ramp_at(s["ramps"]["C"], x)[0] for x in t]
    table["B.capacity"] = table["E.capacity"] = 1e7
    start = {"initial_gear": 2, "initial_input_speed": s["input_speed"], "vehicle_inertia": s["vehicle_inertia"],
             **{f"road_load_c{i}": c for i, c in enumerate(s["road_load"])}}
    r = fmpy.simulate_fmu(str(units["zf_8hp70"]), start_values=start, input=table, output_interval=1e-3,
                          stop_time=1.0, output=["input.speed", "output.speed", "C.lock_time", "locked_elements"])
    last = r[-1]
    md = read_model_description(str(units["zf_8hp70"]))
    bits = next(v for v in md.modelVariables if v.name == "locked_elements").description
    assert "4 = `C`" in bits and "1 = `A`" in bits
    assert last["locked_elements"] & 4 and not last["locked_elements"] & 1
    ref_in, ref_out = speeds_at_end(reference)
    assert last["input.speed"] / last["output.speed"] == pytest.approx(ref_in / ref_out, rel=1e-9)
    assert 0.0 < last["C.lock_time"] - reference["lock_time"] < 2e-3


@pytest.mark.parametrize("h", [1e-3, 1e-2])
def test_simulate_fmu_with_input_derivatives_equals_egt_shift_sim(units: Dict[str, Path], reference: Dict[str, Any],
                                                                  monkeypatch: pytest.MonkeyPatch, h: float) -> None:
    """FMPy's own loop, `simulate_fmu(..., set_input_derivatives=True)`,
    driven by a table of the 2-3 ramps: the lock time to 1e-6 s, the
    energies and speeds to 1e-6, at 1 ms and 10 ms steps.

    Two things about FMPy 0.3.32 are worked around, neither in its numbers:
    its derivative buffer holds exactly nine values (`Input.__init__`
    allocates `value_type * 9`, and assigning fewer fails), so it is sized to
    the unit's inputs here; and at a time equal to a table breakpoint it
    takes the slope on the left, so each breakpoint is put 1 ps before its
    ramp's corner (a capacity off by at most 5e-8 N m), and the step that
    starts at a corner gets the ramp's slope."""
    import numpy as np
    import fmpy.simulation as simulation

    make = simulation.Input.__init__

    def sized(self: Any, *args: Any, **kwargs: Any) -> None:
        make(self, *args, **kwargs)
        self.continuous = [c._replace(derivatives=(c.values._type_ * len(c.vrs))()) for c in self.continuous]

    monkeypatch.setattr(simulation.Input, "__init__", sized)
    s = shift_2_3()
    corners = sorted({x for r in s["ramps"].values() for x in r[:2]})
    t = np.array([0.0] + [c - 1e-12 for c in corners] + [1.0])
    cols = ["input.torque"] + [f"{e}.capacity" for e in "ABCDE"]
    table = np.zeros(len(t), dtype=[("time", float)] + [(c, float) for c in cols])
    table["time"] = t
    table["input.torque"] = s["input_torque"]
    for e, r in s["ramps"].items():
        table[f"{e}.capacity"] = [ramp_at(r, x)[0] for x in t]
    table["B.capacity"] = table["E.capacity"] = 1e7
    start = {"initial_gear": 2, "initial_input_speed": s["input_speed"], "vehicle_inertia": s["vehicle_inertia"],
             **{f"road_load_c{i}": c for i, c in enumerate(s["road_load"])}}
    r = fmpy.simulate_fmu(str(units["zf_8hp70"]), start_values=start, input=table, output_interval=h, stop_time=1.0,
                          set_input_derivatives=True,
                          output=["input.speed", "output.speed", "A.energy", "C.energy", "C.lock_time"])
    last = r[-1]
    assert abs(last["C.lock_time"] / h - round(last["C.lock_time"] / h)) > 1e-3  # inside a step
    assert abs(last["C.lock_time"] - reference["lock_time"]) < 1e-6
    e_ref = dict(zip(reference["elements"], reference["dissipated"]))
    assert last["A.energy"] == pytest.approx(e_ref["A"], rel=1e-6)
    assert last["C.energy"] == pytest.approx(e_ref["C"], rel=1e-6)
    ref_in, ref_out = speeds_at_end(reference)
    assert last["input.speed"] == pytest.approx(ref_in, rel=1e-6)
    assert last["output.speed"] == pytest.approx(ref_out, rel=1e-6)


def test_the_fmpy_example_of_the_docs_runs(units: Dict[str, Path], tmp_path: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/fmu.md's ```python block, pasted where the unit is."""
    import re
    import shutil

    import matplotlib

    matplotlib.use("Agg")
    block = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "fmu.md").read_text(), flags=re.S)
    assert len(block) == 1
    shutil.copy(units["zf_8hp70"], tmp_path / "zf_8hp70.fmu")
    monkeypatch.chdir(tmp_path)
    exec(compile(block[0], "docs/fmu.md", "exec"), {})
    assert (tmp_path / "shift.svg").stat().st_size > 0


# -- the wheel's own library: Train.export_fmu and `python -m egt fmu` -------

C4 = EXAMPLES / "ford_c4_simpson.toml"


def step_c4(path: Path, steps: int = 20, h: float = 1e-3) -> List[float]:
    """Instantiate the C4 unit at `path` in FMPy, drive its input with a
    constant torque in its first gear (the unit's defaults) and return every
    link's speed after `steps` steps."""
    directory = extract(str(path))
    md = read_model_description(directory)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="c4")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr["input.torque"]], [200.0])
    fmu.exitInitializationMode()
    for k in range(steps):
        fmu.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
    speeds: List[float] = fmu.getReal([vr[n] for n in vr if n.endswith(".speed")])
    fmu.terminate()
    fmu.freeInstance()
    return speeds


def test_export_fmu_writes_a_unit_fmpy_validates_and_steps(tmp_path: Path,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """The wheel's library (EGT_FMU_LIBRARY unset) in a unit of the C4."""
    import egt

    monkeypatch.delenv("EGT_FMU_LIBRARY", raising=False)
    out = egt.load(C4).export_fmu(tmp_path / "ford c4.fmu")
    assert out == tmp_path / "ford c4.fmu"
    assert validate_fmu(str(out)) == []
    md = read_model_description(str(out))
    assert md.coSimulation.modelIdentifier == "ford_c4"
    speeds = step_c4(out)
    assert speeds and all(math.isfinite(w) for w in speeds) and any(w != 0.0 for w in speeds)
    named = egt.load(C4).export_fmu(str(tmp_path / "c4.fmu"), model_identifier="gearbox")
    assert read_model_description(str(named)).coSimulation.modelIdentifier == "gearbox"
    assert step_c4(named) == speeds


def test_the_wheels_egt_command_packages_the_same_unit(tmp_path: Path) -> None:
    """`python -m egt fmu` (the wheel's `egt`) finds the library the wheel
    carries without EGT_FMU_LIBRARY, and its unit is export_fmu's: the same
    description (GUID included) and the same steps."""
    import zipfile

    import egt

    env = {k: v for k, v in os.environ.items() if k != "EGT_FMU_LIBRARY"}
    (tmp_path / "cli").mkdir()
    cli = tmp_path / "cli" / "c4.fmu"
    r = subprocess.run([sys.executable, "-m", "egt", "fmu", str(C4), "-o", str(cli)],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    assert f"library {Path(egt.__file__).parent / 'libegt_fmu.so'}" in r.stdout
    assert validate_fmu(str(cli)) == []
    py = egt.load(C4).export_fmu(tmp_path / "c4.fmu")
    with zipfile.ZipFile(cli) as a, zipfile.ZipFile(py) as b:
        assert sorted(a.namelist()) == sorted(b.namelist())
        for name in a.namelist():
            assert a.read(name) == b.read(name), name
    assert step_c4(cli) == step_c4(py)


def test_export_fmu_refusals_are_egt_errors_or_os_errors(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import egt

    c4 = egt.load(C4)
    missing = tmp_path / "nowhere" / "libegt_fmu.so"
    monkeypatch.setenv("EGT_FMU_LIBRARY", str(missing))
    with pytest.raises(egt.EgtError, match="EGT_FMU_LIBRARY") as info:
        c4.export_fmu(tmp_path / "c4.fmu")
    assert info.value.kind == "io" and str(missing) in str(info.value)
    assert not (tmp_path / "c4.fmu").exists()
    monkeypatch.delenv("EGT_FMU_LIBRARY")
    import egt._fmu

    with monkeypatch.context() as m:  # a package without the library (a `maturin develop` build)
        m.setattr(egt._fmu, "BUNDLED", tmp_path / "libegt_fmu.so")
        with pytest.raises(egt.EgtError, match="carries no libegt_fmu.so: set EGT_FMU_LIBRARY"):
            c4.export_fmu(tmp_path / "c4.fmu")
    with pytest.raises(FileNotFoundError):
        c4.export_fmu(tmp_path / "no such directory" / "c4.fmu")
    with pytest.raises(egt.ArgumentError, match="not a C identifier"):
        c4.export_fmu(tmp_path / "c4.fmu", model_identifier="4speed")
    zf = (EXAMPLES / "zf_8hp70.toml").read_text()
    with pytest.raises(egt.TransmissionError) as no_states:  # shift elements, no [transmission]
        egt.loads(zf[: zf.index("[transmission]")]).export_fmu(tmp_path / "cut.fmu")
    assert no_states.value.kind == "no_states"
    assert not list(tmp_path.glob("*.fmu"))
    # A train without elements is a unit of its links.
    fig5 = egt.load(EXAMPLES / "fig5_stability.toml").export_fmu(tmp_path / "fig5.fmu")
    assert validate_fmu(str(fig5)) == []
    assert {"2.torque", "6.speed"} <= {v.name for v in read_model_description(str(fig5)).modelVariables}
