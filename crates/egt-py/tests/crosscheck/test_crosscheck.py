"""Randomized cross-check of egt against references that share none of its
code (issue 11).

Random trains of every planetary kind the spec allows (simple, double
pinion, stepped, Ravigneaux), joined in chains with fixed and free members
(one or more DOF), with a fixed seed and bounded size:

* kinematics: every link's exact speed against the mesh relations of each
  set written here from the textbook (pitch-line speeds in the carrier's
  frame: opposite for an external mesh, equal for an internal one), solved
  in exact fractions; egt's circuit table is never read;
* inverse dynamics: every driving torque against the principle of virtual
  power, sum over links of (T_l - I_l n_l w'_l) v_l = 0 for each motion v
  the reference kinematics allows, in exact fractions;
* stability: egt's verdict against a SciPy (Radau) integration of the
  deviation dynamics [M_r] u' = [K_r] u, with [M_r] and [K_r] reduced on the
  reference kinematics.

The counts of what was compared are printed at the end of the run.
"""

from __future__ import annotations

import random
from collections import Counter
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Dict, List, Optional, Tuple

import numpy as np
import pytest
from scipy.integrate import solve_ivp  # type: ignore[import-untyped]
from scipy.linalg import eigh  # type: ignore[import-untyped]

import egt

SEED = 20261124
KINDS = ("simple", "double_pinion", "stepped", "ravigneaux")


@dataclass
class RandomTrain:
    """A spec and the mesh relations of its sets: each relation is
    (a, b, c, k) meaning (w_a - w_c) = k (w_b - w_c)."""

    spec: str
    inputs: List[str]
    kinds: List[str]
    relations: List[Tuple[str, str, str, Fraction]] = field(default_factory=list)
    moving: List[str] = field(default_factory=list)
    copies: Dict[str, int] = field(default_factory=dict)


def random_train(rng: random.Random) -> RandomTrain:
    """Sets joined one by one: each takes one member from the central links
    so far, one member fixed or a new free shaft (a new DOF, driven), and the
    rest new links."""
    lines = ['frame = "H"']
    central = ["s_in"]
    t = RandomTrain(spec="", inputs=["s_in"], kinds=[], moving=["s_in"])
    for p in range(rng.randint(1, 4)):
        kind = rng.choice(KINDS)
        t.kinds.append(kind)
        slots = {"simple": ["sun", "ring", "carrier"], "double_pinion": ["sun", "ring", "carrier"],
                 "stepped": ["sun", "ring", "carrier"], "ravigneaux": ["sun", "sun2", "ring", "carrier"]}[kind]
        rng.shuffle(slots)
        members: Dict[str, str] = {slots[0]: rng.choice(central)}
        free = rng.random() < 0.3
        members[slots[1]] = f"x{p}" if free else "H"
        if free:
            t.inputs.append(f"x{p}")
        for s in slots[2:]:
            members[s] = f"{s}{p}"
        for name in members.values():
            if name != "H" and name not in central:
                central.append(name)
                t.moving.append(name)
        z = {k: rng.randint(lo, hi) for k, lo, hi in
             [("sun", 17, 50), ("sun2", 20, 50), ("planet", 12, 30), ("planet2", 12, 30)]}
        z["ring"] = z["sun"] + 2 * z["planet"] + (2 * z["planet2"] if kind == "double_pinion" else 0)
        if kind == "ravigneaux":
            z["ring"] = max(z["ring"], z["sun2"] + 2 * z["planet2"])
        p1, p2 = f"P{p}.planet", f"P{p}.planet2"
        t.moving.append(p1)
        copies = rng.randint(1, 4)
        t.copies[p1] = copies
        if kind in ("double_pinion", "ravigneaux"):
            t.moving.append(p2)
            t.copies[p2] = copies
        teeth = ["sun", "ring", "planet"] + {"double_pinion": ["planet2"], "stepped": ["planet2"],
                                             "ravigneaux": ["sun2", "planet2"], "simple": []}[kind]
        lines += ["[[planetary]]", f'name = "P{p}"', f'kind = "{kind}"']
        lines += [f'{slot} = "{name}"' for slot, name in members.items()]
        lines.append("teeth = { " + ", ".join(f"{k} = {z[k]}" for k in teeth) + " }")
        s, r, c = members.get("sun"), members.get("ring"), members["carrier"]
        zs, zr, zp, zq = (Fraction(z[k]) for k in ("sun", "ring", "planet", "planet2"))
        rel = t.relations
        # External mesh: relative speeds opposite, in the ratio of the teeth; internal: same sign.
        if kind == "simple":
            rel += [(p1, s, c, -zs / zp), (p1, r, c, zr / zp)]
        elif kind == "double_pinion":
            rel += [(p1, s, c, -zs / zp), (p2, p1, c, -zp / zq), (p2, r, c, zr / zq)]
        elif kind == "stepped":
            # One compound planet: wheel `planet` meshes the sun, wheel `planet2` the ring.
            rel += [(p1, s, c, -zs / zp), (p1, r, c, zr / zq)]
        else:
            s2 = members["sun2"]
            zs2 = Fraction(z["sun2"])
            rel += [(p1, s, c, -zs / zp), (p2, p1, c, -zp / zq), (p2, s2, c, -zs2 / zq), (p2, r, c, zr / zq)]
    t.spec = "\n".join(lines) + "\n"
    return t


def spec_with(t: RandomTrain, inertia: Optional[Dict[str, float]] = None) -> str:
    """The spec with a [[links]] entry per moving link: the planets' copies,
    and the inertias when given."""
    lines = [t.spec]
    for n in t.moving:
        fields = [f'name = "{n}"']
        if n in t.copies:
            fields.append(f"copies = {t.copies[n]}")
        if inertia is not None:
            fields.append(f"inertia = {inertia[n]!r}")
        if len(fields) > 1:
            lines += ["[[links]]"] + fields
    return "\n".join(lines) + "\n"


def solve_exact(a: List[List[Fraction]], b: List[Fraction]) -> List[Fraction]:
    """Gauss-Jordan over fractions; the system must have one solution."""
    n = len(a[0])
    m = [row[:] + [bi] for row, bi in zip(a, b)]
    r = 0
    for col in range(n):
        piv = next((i for i in range(r, len(m)) if m[i][col] != 0), None)
        assert piv is not None, "singular reference system"
        m[r], m[piv] = m[piv], m[r]
        pv = m[r][col]
        m[r] = [v / pv for v in m[r]]
        for i in range(len(m)):
            if i != r and m[i][col] != 0:
                f = m[i][col]
                m[i] = [vi - f * vr for vi, vr in zip(m[i], m[r])]
        r += 1
    assert all(all(v == 0 for v in row) for row in m[r:]), "inconsistent reference system"
    return [m[i][n] for i in range(n)]


def reference_speeds(t: RandomTrain, inputs: Dict[str, Fraction]) -> Dict[str, Fraction]:
    """Every moving link's speed from the mesh relations and the inputs."""
    idx = {name: i for i, name in enumerate(t.moving)}
    rows, rhs = [], []
    for a, b, c, k in t.relations:
        row = [Fraction(0)] * len(idx)
        for name, v in ((a, 1), (c, -1 + k), (b, -k)):
            if name != "H":
                row[idx[name]] += v
        rows.append(row)
        rhs.append(Fraction(0))
    for name, v in inputs.items():
        row = [Fraction(0)] * len(idx)
        row[idx[name]] = Fraction(1)
        rows.append(row)
        rhs.append(v)
    w = solve_exact(rows, rhs)
    return dict(zip(t.moving, w))


def trains(count: int, salt: int) -> List[RandomTrain]:
    rng = random.Random(SEED + salt)
    return [random_train(rng) for _ in range(count)]


def test_kinematics_equal_the_mesh_relations(checked: Counter[str]) -> None:
    rng = random.Random(SEED)
    for t in trains(150, 1):
        train = egt.loads(spec_with(t))
        assert train.dof == len(t.inputs), t.spec
        ins = {name: Fraction(rng.choice([-3, -1, 1, 2, 5]) * rng.randint(1, 400), rng.randint(1, 7))
               for name in t.inputs}
        k = train.kinematics({n: str(v) for n, v in ins.items()})
        ref = reference_speeds(t, ins)
        assert k.exact is not None
        for name, v in ref.items():
            assert k.exact[name] == v, f"{name}: {k.exact[name]} != {v}\n{t.spec}"
            assert k[name] == float(v)
        checked["kinematics: trains"] += 1
        checked["kinematics: link speeds (exact)"] += len(ref)
        for kind in t.kinds:
            checked[f"kinematics: {kind} sets"] += 1


def test_driving_torques_equal_virtual_power(checked: Counter[str]) -> None:
    rng = random.Random(SEED + 2)
    for t in trains(100, 2):
        # Inertias as short decimals, so that the float is the fraction's nearest double.
        inertia = {n: Fraction(rng.randint(1, 900), 10_000) for n in t.moving}
        train = egt.loads(spec_with(t, {n: float(v) for n, v in inertia.items()}))
        out = t.moving[-1] if t.moving[-1] not in t.inputs else t.moving[0]
        load = Fraction(rng.randint(-500, 500), 10)
        alpha = {n: Fraction(rng.randint(-50, 50), 3) for n in t.inputs}
        d = train.dynamics(torques={out: float(load)}, accelerations={n: float(v) for n, v in alpha.items()},
                           driving=list(t.inputs))
        # Reference: w' = V alpha, and for each input j: T_j = sum_l (I_l n_l w'_l - Q_l) v_jl.
        v = {j: reference_speeds(t, {i: Fraction(int(i == j)) for i in t.inputs}) for j in t.inputs}
        acc = {n: sum(alpha[j] * v[j][n] for j in t.inputs) for n in t.moving}
        for j in t.inputs:
            tj = sum((inertia[n] * t.copies.get(n, 1) * acc[n] - (load if n == out else 0)) * v[j][n]
                     for n in t.moving)
            got = d.driving_torques[j]
            assert got == pytest.approx(float(tj), rel=1e-11, abs=1e-11 * float(abs(load) + 1)), t.spec
            checked["dynamics: driving torques (virtual power, exact)"] += 1
        checked["dynamics: trains"] += 1


def test_stability_verdicts_agree_with_scipy_integration(checked: Counter[str]) -> None:
    rng = random.Random(SEED + 3)
    done = 0
    for t in trains(400, 3):
        if len(t.inputs) != 2 or done >= 25:
            continue
        inertia = {n: 10 ** rng.uniform(-4, -1) for n in t.moving}
        spec = spec_with(t, inertia)
        train = egt.loads(spec)
        out = next(n for n in reversed(t.moving) if n not in t.inputs and ".planet" not in n)
        slopes = {t.inputs[0]: -rng.uniform(0.01, 1), t.inputs[1]: -rng.uniform(0.01, 1), out: rng.uniform(-2, 2)}
        curves = [{"link": n, "torque": 0.0, "slope": s, "speed": 0.0} for n, s in slopes.items()]
        rep = train.stability(list(t.inputs), curves=curves, inputs={t.inputs[0]: 10.0, t.inputs[1]: 5.0})
        # The reduced model on the reference kinematics, in floats.
        cols = [reference_speeds(t, {i: Fraction(int(i == j)) for i in t.inputs}) for j in t.inputs]
        vm = np.array([[float(c[n]) for c in cols] for n in t.moving])
        mr = vm.T @ np.diag([inertia[n] * t.copies.get(n, 1) for n in t.moving]) @ vm
        kr = vm.T @ np.diag([slopes.get(n, 0.0) for n in t.moving]) @ vm
        lam = eigh(kr, mr, eigvals_only=True)
        if min(abs(lam)) < 1e-9 * max(abs(lam)):
            continue  # too close to marginal for a finite integration to tell
        span = 5.0 / min(abs(lam))
        u0 = np.array([1.0, 0.7])
        sol = solve_ivp(lambda _t, u: np.linalg.solve(mr, kr @ u), (0.0, span), u0, method="Radau",
                        rtol=1e-8, atol=1e-12)
        energy = lambda u: float(u @ mr @ u)  # noqa: E731
        grows = energy(sol.y[:, -1]) > energy(u0)
        assert (rep.verdict == "unstable") == grows, (rep.reason, lam, spec)
        assert rep.verdict in ("stable", "unstable")
        done += 1
        checked["stability: 2-DOF verdicts (SciPy Radau)"] += 1
        checked[f"stability: {rep.verdict} verdicts"] += 1
    assert done >= 10
    assert checked["stability: stable verdicts"] and checked["stability: unstable verdicts"]


def test_adjacency_nests_equal_the_willis_definition(checked: Counter[str]) -> None:
    """The compact adjacency form of enumeration programs: link k turns on
    link k-1 (its own level), and gear pair (k-2, k) meshes across carrier
    k-1 with ratio tau, so that (w_{k-2} - w_{k-1}) = tau (w_k - w_{k-1}) by
    the definition of the ratio; the carriers are known here from the
    construction, not from egt's transfer-vertex search."""
    rng = random.Random(SEED + 4)
    for _ in range(60):
        n = rng.randint(3, 9)
        taus = {k: Fraction(rng.choice([-1, 1]) * rng.randint(2, 40), rng.randint(2, 40)) for k in range(2, n + 1)}
        taus = {k: (t if t != 1 else Fraction(3, 2)) for k, t in taus.items()}
        items = [f"{k - 1}-{k}:L{k}" for k in range(1, n + 1)]
        items += [f"{k - 2}-{k}:G={t.numerator}/{t.denominator}" for k, t in taus.items()]
        spec = f'frame = "0"\nadjacency = "{" ".join(items)}"\n'
        train = egt.loads(spec)
        assert train.dof == 1, spec
        w1 = Fraction(rng.randint(1, 500), rng.randint(1, 9))
        k = train.kinematics({"1": str(w1)})
        # Reference: w_0 = 0, w_1 given; each gear pair gives w_k from w_{k-2}, w_{k-1}.
        w = {0: Fraction(0), 1: w1}
        for j in range(2, n + 1):
            w[j] = w[j - 1] + (w[j - 2] - w[j - 1]) / taus[j]
        assert k.exact is not None
        for j in range(1, n + 1):
            assert k.exact[str(j)] == w[j], (j, spec)
        checked["kinematics: adjacency nests"] += 1
        checked["kinematics: link speeds (exact)"] += n
