"""Property tests on random planetary chains (hypothesis): the Willis
residuals of every solution vanish (exactly, for tooth-count trains), and
power balances, with and without mesh losses and inertia."""

from __future__ import annotations

from fractions import Fraction
from typing import Dict, List, Tuple

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import egt


@st.composite
def chains(draw: st.DrawFn) -> Tuple[str, List[str], str]:
    """A chain of 1-3 simple planetary sets: set p's carrier is set p+1's sun;
    each ring is fixed or a free shaft (one more DOF, driven). Returns the
    spec, the input links and the output link."""
    k = draw(st.integers(1, 3))
    lines = ['frame = "H"']
    inputs = ["s0"]
    for p in range(k):
        zs = draw(st.integers(12, 60))
        zp = draw(st.integers(12, 40))
        free = draw(st.booleans())
        ring = f"r{p}" if free else "H"
        if free:
            inputs.append(ring)
        lines += [
            "[[planetary]]",
            f'name = "P{p}"',
            f'sun = "{"s0" if p == 0 else f"c{p - 1}"}"',
            f'ring = "{ring}"',
            f'carrier = "c{p}"',
            f"teeth = {{ sun = {zs}, planet = {zp}, ring = {zs + 2 * zp} }}",
            f"efficiency = {draw(st.sampled_from([0.95, 0.98, 1.0]))}",
            "module = 1.0e-3",
        ]
    for name in ["s0"] + [f"c{p}" for p in range(k)] + [n for n in inputs if n.startswith("r")]:
        inertia = draw(st.floats(1e-4, 1e-2))
        lines += ["[[links]]", f'name = "{name}"', f"inertia = {inertia!r}"]
    return "\n".join(lines) + "\n", inputs, f"c{k - 1}"


speeds = st.integers(-500, 500).filter(lambda v: v != 0)


def willis_residuals_exact(train: egt.Train, exact: Dict[str, Fraction]) -> List[Fraction]:
    out = []
    for c in train.circuits:
        assert c.ratio_exact is not None
        t = c.ratio_exact
        out.append(exact[c.gear_i] - t * exact[c.gear_j] + (t - 1) * exact[c.carrier])
    return out


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(chains(), st.data())
def test_willis_residuals_vanish(chain: Tuple[str, List[str], str], data: st.DataObject) -> None:
    spec, inputs, _ = chain
    train = egt.loads(spec)
    assert train.dof == len(inputs)
    ins = {n: data.draw(speeds, label=n) for n in inputs}
    k = train.kinematics(ins)
    # Exactly zero for the exact solution (tooth counts give exact ratios).
    assert k.exact is not None
    assert all(r == 0 for r in willis_residuals_exact(train, k.exact))
    # And tiny for the floating-point one, computed here independently (eq. 2).
    w = dict(k)
    scale = max(abs(v) for v in w.values())
    for c in train.circuits:
        assert c.ratio is not None
        psi = w[c.gear_i] - c.ratio * w[c.gear_j] + (c.ratio - 1) * w[c.carrier]
        assert abs(psi) <= 1e-12 * scale
    assert k.residual <= 1e-12


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(chains(), st.data())
def test_power_balances(chain: Tuple[str, List[str], str], data: st.DataObject) -> None:
    spec, inputs, out = chain
    train = egt.loads(spec)
    ins = {n: data.draw(speeds, label=n) for n in inputs}
    load = data.draw(st.floats(-100.0, -1.0), label="load")
    accel = data.draw(st.sampled_from([0.0, 5.0, -20.0]), label="alpha")
    accelerations = {n: accel for n in inputs}

    # Ideal meshes: the external powers and dK/dt balance exactly.
    p = train.power(ins, torques={out: load}, accelerations=accelerations, driving=inputs, losses=False)
    scale = max(p.input_power, p.output_power, 1e-300)
    assert abs(sum(lp.external for lp in p.links) - p.kinetic_rate) <= 1e-9 * scale
    assert abs(p.loss) <= 1e-9 * scale
    assert abs(p.balance) <= 1e-9 * scale
    # dK/dt = w^T M w' with the train's own mass matrix.
    m = train.mass_matrix().matrix
    idx = [train.link_names.index(c) for c in train.coordinates]
    w, wdot = p.speeds.speeds[idx], p.dynamics.accelerations[idx]
    assert abs(w @ m @ wdot - p.kinetic_rate) <= 1e-9 * max(scale, abs(p.kinetic_rate))

    # With mesh losses: input = output + loss + dK/dt, and losses are dissipative.
    try:
        q = train.power(ins, torques={out: load}, accelerations=accelerations, driving=inputs, losses=True)
    except egt.AnalysisError:
        return  # a self-locking combination is a legitimate outcome
    scale = max(q.input_power, q.output_power, 1e-300)
    assert abs(q.balance) <= 1e-9 * scale
    assert all(m.loss >= -1e-9 * scale for m in q.meshes)


@settings(max_examples=25, deadline=None)
@given(chains(), st.integers(1, 40))
def test_batch_rows_equal_single_calls(chain: Tuple[str, List[str], str], rows: int) -> None:
    spec, inputs, _ = chain
    train = egt.loads(spec)
    rng = np.random.default_rng(rows)
    values = {n: rng.uniform(-100, 100, rows) for n in inputs}
    b = train.batch_kinematics(values)
    assert b.ok.all()
    r = rows - 1
    single = train.kinematics({n: float(v[r]) for n, v in values.items()})
    np.testing.assert_allclose(b.speeds[r], single.speeds, rtol=1e-12, atol=1e-12)
