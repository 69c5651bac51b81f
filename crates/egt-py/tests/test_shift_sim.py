"""Train.simulate_shift: the 8HP 2-3 upshift from Python, against the CLI and
against the steady gear (egt shift)."""

import json
import subprocess
import sys
from typing import Any, Dict

import numpy as np
import pytest

import egt
from conftest import EXAMPLES

UPSHIFT = dict(
    input_speed=250.0,
    input_torque=300.0,
    road_load=(20.0, 0.2, 0.002),
    vehicle_inertia=12.0,
    off_going=(0.05, 0.15, 5000.0, 0.0),
    on_coming=(0.05, 0.3, 0.0, 9000.0),
)


def zf() -> egt.Train:
    return egt.Train.from_file(EXAMPLES / "zf_8hp70.toml")


def test_the_upshift_ends_in_third_with_its_energy_balanced() -> None:
    train = zf()
    s = train.simulate_shift("2", "3", **UPSHIFT)  # type: ignore[arg-type]
    assert s.elements == ("A", "C")
    assert s.kept == ("B", "E")
    assert [c[1:3] for c in s.changes] == [("A", "slipping"), ("C", "locked")]
    assert s.lock_time is not None and s.shift_start == 0.05
    third = train.gear("3")
    ratio = s.speed("input")[-1] / s.speed("output")[-1]
    assert ratio == pytest.approx(third.ratio, rel=1e-9)
    total = s.energy[0] + s.energy[1]
    assert np.abs(s.energy_residual).max() < 1e-7 * total
    assert s.dof[0] == 1 and s.dof.max() == 2 and s.dof[-1] == 1
    assert s.method == "explicit" and s.stiff is None
    df = s.to_pandas()
    assert {"input", "slip_C", "torque_A", "torque_B", "torque_E", "output_torque", "dof"} <= set(df.columns)
    # the kept elements' torques, within the reported ranges
    assert s.held == () and s.kept_torque.shape == (len(s.t), 2)
    for k, (hi, lo) in enumerate(s.to_dict()["kept_torque_range"]):
        assert lo <= s.kept_torque[:, k].min() and s.kept_torque[:, k].max() <= hi


def test_a_kept_element_given_a_capacity_is_held_by_it() -> None:
    train = zf()
    rigid = train.simulate_shift("2", "3", **UPSHIFT)  # type: ignore[arg-type]
    peak = float(np.abs(rigid.kept_torque[:, 1]).max())
    s = train.simulate_shift("2", "3", ramps={"E": 0.5 * peak / 0.15}, **UPSHIFT)  # type: ignore[arg-type]
    assert s.kept == ("B",) and s.held == ("E",) and s.elements == ("A", "C", "E")
    assert any(c[1] == "E" and c[2] == "slipping" for c in s.changes)
    assert np.abs(s.element_torque[:, 2]).max() <= 0.5 * peak * (1 + 1e-9)


def cli_upshift() -> Dict[str, Any]:
    """`egt shift-sim --format json` of the upshift."""
    out = subprocess.run(
        [
            sys.executable, "-m", "egt", "shift-sim", str(EXAMPLES / "zf_8hp70.toml"),
            "--from", "2", "--to", "3", "--input-speed", "250", "--input-torque", "300",
            "--road-load", "20,0.2,0.002", "--vehicle-inertia", "12",
            "--off-going", "0.05:0.15:5000:0", "--on-coming", "0.05:0.3:0:9000",
            "--format", "json",
        ],
        capture_output=True, text=True, check=True,
    )
    cli: Dict[str, Any] = json.loads(out.stdout)
    return cli


def test_python_and_the_cli_give_the_same_shift() -> None:
    s = zf().simulate_shift("2", "3", **UPSHIFT)  # type: ignore[arg-type]
    cli = cli_upshift()
    assert cli["lock_time"] == s.lock_time
    assert cli["dissipated"] == list(s.energy)
    assert s.to_dict() == cli


def test_bad_shifts_raise_egt_errors_naming_the_field() -> None:
    train = zf()
    with pytest.raises(egt.EgtError, match="shift.from"):
        train.simulate_shift("9", "3", **UPSHIFT)  # type: ignore[arg-type]
    with pytest.raises(egt.EgtError, match="off_going"):
        train.simulate_shift("2", "3", **{**UPSHIFT, "off_going": (1.0, 2.0)})  # type: ignore[arg-type]
    with pytest.raises(egt.EgtError, match="method"):
        train.simulate_shift("2", "3", method="rk4", **UPSHIFT)  # type: ignore[arg-type]
    with pytest.raises(egt.EgtError, match="input_torque"):
        train.simulate_shift("2", "3", **{**UPSHIFT, "input_torque": None})  # type: ignore[arg-type]


DOUBLE_SWAP = {
    "A": (0.05, 0.15, 20000.0, 0.0),
    "C": (0.05, 0.15, 20000.0, 0.0),
    "D": (0.05, 0.4, 0.0, 20000.0),
    "E": (0.05, 0.4, 0.0, 20000.0),
}


def test_a_double_swap_by_ramps_is_the_clis_and_ends_in_fourth() -> None:
    """The 8HP 1-4 (A and C off, D and E on), each element's capacity named
    in ``ramps`` as ``--ramp NAME=RAMP``: the same document as the CLI's,
    and the new gear's ratio at the end."""
    base = {k: v for k, v in UPSHIFT.items() if k not in ("off_going", "on_coming")}
    train = zf()
    s = train.simulate_shift("1", "4", ramps=DOUBLE_SWAP, t_end=1.5, **base)  # type: ignore[arg-type]
    assert s.off_going == ("A", "C") and s.on_coming == ("D", "E")
    assert s.elements == s.off_going + s.on_coming and len(s.energy) == 4
    assert s.slip.shape == (len(s.t), 4) and s.dissipated[-1].tolist() == list(s.energy)
    ratio = s.speed("input")[-1] / s.speed("output")[-1]
    assert ratio == pytest.approx(train.gear("4").ratio, rel=1e-9)
    args = [
        sys.executable, "-m", "egt", "shift-sim", str(EXAMPLES / "zf_8hp70.toml"),
        "--from", "1", "--to", "4", "--input-speed", "250", "--input-torque", "300",
        "--road-load", "20,0.2,0.002", "--vehicle-inertia", "12", "--t-end", "1.5",
        "--format", "json",
    ]
    for name, r in DOUBLE_SWAP.items():
        args += ["--ramp", f"{name}=" + ":".join(repr(x) for x in r)]
    cli = json.loads(subprocess.run(args, capture_output=True, text=True, check=True).stdout)
    assert s.to_dict() == cli


def test_ramps_and_max_steps_are_checked_by_name() -> None:
    train = zf()
    base = {k: v for k, v in UPSHIFT.items() if k != "off_going"}
    # The off-going A has no capacity: neither `off_going` nor `ramps` names it.
    with pytest.raises(egt.EgtError, match="`A`"):
        train.simulate_shift("2", "3", **base)  # type: ignore[arg-type]
    with pytest.raises(egt.EgtError, match="ramps"):
        train.simulate_shift("2", "3", ramps={"A": (1.0, 2.0)}, **base)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="ramps must be a mapping"):
        train.simulate_shift("2", "3", ramps=[("A", 1.0)], **base)  # type: ignore[arg-type]
    # Named in `ramps`, A runs: the same run as with `off_going`.
    by_name = train.simulate_shift("2", "3", ramps={"A": UPSHIFT["off_going"]}, **base)  # type: ignore[arg-type]
    assert by_name.to_dict() == train.simulate_shift("2", "3", **UPSHIFT).to_dict()  # type: ignore[arg-type]
    with pytest.raises(egt.EgtError, match="max_steps"):
        train.simulate_shift("2", "3", max_steps=0, **UPSHIFT)  # type: ignore[arg-type]
    with pytest.raises(egt.AnalysisError, match="max_steps") as budget:
        train.simulate_shift("2", "3", max_steps=5, **UPSHIFT)  # type: ignore[arg-type]
    assert budget.value.kind == "budget"
    with pytest.raises(ValueError, match="max_steps"):
        train.simulate_shift("2", "3", max_steps=-1, **UPSHIFT)  # type: ignore[arg-type]


def test_a_shift_the_spec_names_is_the_run_its_arguments_give() -> None:
    """``[[shift]]`` "2-3" of the 8HP example is UPSHIFT: the same document."""
    train = zf()
    assert train.shifts == ("2-3", "1-4")
    named = train.simulate_named_shift("2-3")
    assert named.to_dict() == train.simulate_shift("2", "3", **UPSHIFT).to_dict()  # type: ignore[arg-type]
    assert train.simulate_named_shift("2-3", rtol=1e-6).steps < named.steps
    with pytest.raises(egt.EgtError, match=r"unknown shift `2-4` \(did you mean `2-3`\?\)"):
        train.simulate_named_shift("2-4")
    with pytest.raises(egt.EgtError, match="no \\[\\[shift\\]\\]"):
        egt.Train.from_file(EXAMPLES / "ford_c4_simpson.toml").simulate_named_shift("1-2")


def test_the_phases_and_quality_measures_are_the_cli_s() -> None:
    s = zf().simulate_shift("2", "3", **UPSHIFT)  # type: ignore[arg-type]
    q, cli = s.quality, cli_upshift()["quality"]
    assert isinstance(q, egt.ShiftQuality)
    assert q.torque_phase == tuple(cli["torque_phase"])
    assert q.inertia_phase == tuple(cli["inertia_phase"])
    assert q.dip == (cli["dip"]["t"], cli["dip"]["value"])
    assert q.overshoot == (cli["overshoot"]["t"], cli["overshoot"]["value"])
    assert q.jerk == (cli["jerk"]["t"], cli["jerk"]["value"])
    assert q.oscillation_after_lock == cli["oscillation_after_lock"]
    assert [p and p[1] for p in q.peak_power] == [e["peak_power"]["value"] for e in cli["elements"]]
    # the phases of a power-on upshift, in order, and its dip
    assert q.torque_phase is not None and q.inertia_phase is not None and q.dip is not None
    assert s.shift_start == q.torque_phase[0] <= q.torque_phase[1] == q.inertia_phase[0]
    assert q.inertia_phase[1] == s.lock_time
    assert q.dip[1] < 0.0
    # the dip is the lowest output torque in the torque phase (here a sample:
    # the left limit at the release)
    t0, t1 = q.torque_phase
    inside = (s.t >= t0) & (s.t <= t1)
    assert q.output_torque_start is not None
    assert s.output_torque[inside].min() - q.output_torque_start == pytest.approx(q.dip[1], abs=1e-9)


def test_a_compliant_output_is_the_clis_and_checked_by_name() -> None:
    train = zf()
    s = train.simulate_shift("2", "3", output_shaft=(5000.0, 1.0), rtol=1e-9, **UPSHIFT)  # type: ignore[arg-type]
    out = subprocess.run(
        [
            sys.executable, "-m", "egt", "shift-sim", str(EXAMPLES / "zf_8hp70.toml"),
            "--from", "2", "--to", "3", "--input-speed", "250", "--input-torque", "300",
            "--road-load", "20,0.2,0.002", "--vehicle-inertia", "12",
            "--off-going", "0.05:0.15:5000:0", "--on-coming", "0.05:0.3:0:9000",
            "--output-shaft", "5000,1", "--rtol", "1e-9", "--format", "json",
        ],
        capture_output=True, text=True, check=True,
    )
    assert s.to_dict() == json.loads(out.stdout)
    assert s.max_energy_residual < 1e-7 * sum(s.energy)
    with pytest.raises(egt.EgtError, match="output_shaft.stiffness"):
        train.simulate_shift("2", "3", output_shaft=0.0, **UPSHIFT)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="output_shaft"):
        train.simulate_shift("2", "3", output_shaft=(1.0, 2.0, 3.0), **UPSHIFT)  # type: ignore[arg-type]


def test_mesh_losses_are_the_clis_and_close_the_energy_balance() -> None:
    train = zf()
    s = train.simulate_shift("2", "3", losses=True, **UPSHIFT)  # type: ignore[arg-type]
    out = subprocess.run(
        [
            sys.executable, "-m", "egt", "shift-sim", str(EXAMPLES / "zf_8hp70.toml"),
            "--from", "2", "--to", "3", "--input-speed", "250", "--input-torque", "300",
            "--road-load", "20,0.2,0.002", "--vehicle-inertia", "12",
            "--off-going", "0.05:0.15:5000:0", "--on-coming", "0.05:0.3:0:9000",
            "--losses", "--format", "json",
        ],
        capture_output=True, text=True, check=True,
    )
    assert s.to_dict() == json.loads(out.stdout)
    assert s.mesh_loss is not None and s.mesh_loss > 0.0
    assert s.max_energy_residual < 1e-7 * (sum(s.energy) + s.mesh_loss)
    assert train.simulate_shift("2", "3", **UPSHIFT).mesh_loss is None  # type: ignore[arg-type]


def test_a_train_braked_to_rest_rests_as_the_cli_says() -> None:
    train = zf()
    args: Dict[str, Any] = {**UPSHIFT, "input_torque": 0.0, "road_load": (0.0, 0.0, 0.0), "off_going": 20000.0}
    s = train.simulate_shift("2", "3", t_end=2.0, **args)
    assert s.rest_time is not None and s.rest_time == s.lock_time
    assert np.all(s.speeds[-1] == 0.0) and s.dof[-1] == 0
    assert train.simulate_shift("2", "3", **UPSHIFT).rest_time is None  # type: ignore[arg-type]
