"""Results of :meth:`egt.Train.gear` and :meth:`egt.Train.shift_table`: the
gear states of an automatic transmission, per unit input speed and torque."""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Dict, Mapping, Optional, Sequence, Tuple

from ._args import ArgumentError, ArgumentKeyError
from ._results import _Documented, _document_field, _pandas

if TYPE_CHECKING:  # pragma: no cover
    import pandas


Names = Tuple[Tuple[str, ...], Tuple[str, ...], Tuple[str, ...]]
"""Link, gear-pair and shift-element names, by index (the core's ids)."""


def _frac(x: Optional[str]) -> Optional[Fraction]:
    return None if x is None else Fraction(x)


@dataclass(frozen=True)
class ElementLoad:
    """An engaged element's torque per unit input torque (on its first link)."""

    element: str
    torque: float
    holds: Optional[bool]
    """One-way elements: whether the torque has the direction it can hold."""
    parallel: bool


@dataclass(frozen=True)
class Slip:
    """The slip across an open element per unit input speed."""

    element: str
    speed: float
    exact: Optional[Fraction]
    freewheel: Optional[str]
    """One-way elements: ``"overruns"``, ``"idle"`` or ``"locks"``."""


@dataclass(frozen=True)
class GearPowerFlow:
    """A state's power flow with the meshes' basic efficiencies."""

    efficiency: float
    output_torque: float
    loss: float
    circulation_ratio: float
    circulating: Optional[Tuple[Tuple[str, ...], Tuple[str, ...]]]


@dataclass(frozen=True)
class GearState(_Documented):
    """One gear state: ratio, speeds, element torques, power flow.

    ``to_dict()`` is this state's row of ``egt shift --format json``'s ``gears``."""

    state: str
    index: int
    engaged: Tuple[str, ...]
    ratio: float
    """Input speed over output speed."""
    ratio_exact: Optional[Fraction]
    speeds: Dict[str, Optional[float]]
    """Every link's speed per unit input speed (None: a planet without teeth)."""
    speeds_exact: Optional[Dict[str, Optional[Fraction]]]
    relative: Tuple[Tuple[str, str, float], ...]
    slips: Tuple[Slip, ...]
    output_torque: float
    housing_torque: float
    elements: Tuple[ElementLoad, ...]
    meshes: Tuple[Tuple[str, float, Optional[Tuple[float, float]]], ...]
    """(gear pair, multiplier, tangential forces) per mesh, ideal."""
    power: Optional[GearPowerFlow]
    power_balance: float
    torque_balance: float
    warnings: Tuple[str, ...]
    notes: Tuple[str, ...]
    _document: Dict[str, Any] = _document_field()

    @classmethod
    def _from_core(cls, names: Names, d: Mapping[str, Any], document: Dict[str, Any]) -> "GearState":
        """From the core's `GearAnalysis` (its serde form: ids are indices,
        exact values text) and its row of the CLI's shift document."""
        links, gears, elements = names
        p = d["power"]
        exact = d["speed_exact"]
        return cls(
            _document=document,
            state=d["state"],
            index=d["index"],
            engaged=tuple(elements[e] for e in d["engaged"]),
            ratio=d["ratio"],
            ratio_exact=_frac(d["ratio_exact"]),
            speeds=dict(zip(links, d["speed"])),
            speeds_exact=None if exact is None else {n: _frac(x) for n, x in zip(links, exact)},
            relative=tuple((links[r["link"]], links[r["carrier"]], r["speed"]) for r in d["relative"]),
            slips=tuple(
                Slip(elements[x["element"]], x["speed"], _frac(x["exact"]), x["freewheel"])
                for x in d["slips"]
            ),
            output_torque=d["output_torque"],
            housing_torque=d["housing_torque"],
            elements=tuple(
                ElementLoad(elements[e["element"]], e["torque"], e["holds"], e["parallel"])
                for e in d["elements"]
            ),
            meshes=tuple(
                (gears[m["gear"]], m["multiplier"], None if m["force"] is None else tuple(m["force"]))
                for m in d["meshes"]
            ),
            power=None
            if p is None
            else GearPowerFlow(
                efficiency=p["efficiency"],
                output_torque=p["output_torque"],
                loss=p["loss"],
                circulation_ratio=p["circulation_ratio"],
                circulating=None
                if p["circulating"] is None
                else (
                    tuple(gears[g] for g in p["circulating"][0]),
                    tuple(links[l] for l in p["circulating"][1]),
                ),
            ),
            power_balance=d["power_balance"],
            torque_balance=d["torque_balance"],
            warnings=tuple(d["warnings"]),
            notes=tuple(d["notes"]),
        )

@dataclass(frozen=True)
class Step:
    """The step between two forward gears adjacent in the list."""

    lower: str
    upper: str
    value: float
    exact: Optional[Fraction]


@dataclass(frozen=True)
class Spread:
    """The overall spread: ratio(lowest) / ratio(highest) forward gear."""

    lowest: str
    highest: str
    value: float
    exact: Optional[Fraction]


@dataclass(frozen=True)
class Shift:
    """A sequential or garage shift: the elements released, applied and kept."""

    source: str
    target: str
    kind: str
    off: Tuple[str, ...]
    on: Tuple[str, ...]
    kept: Tuple[str, ...]
    single_swap: bool


@dataclass(frozen=True)
class ShiftTable(_Documented):
    """Every gear state of a transmission and the table across them.

    ``to_dict()`` is ``egt shift --format json``."""

    input: str
    output: str
    gears: Tuple[GearState, ...]
    forward: Tuple[bool, ...]
    steps: Tuple[Step, ...]
    spread: Optional[Spread]
    shifts: Tuple[Shift, ...]
    warnings: Tuple[str, ...]
    _document: Dict[str, Any] = _document_field()

    @classmethod
    def _from_core(cls, names: Names, raw: Sequence[Any]) -> "ShiftTable":
        """From the core's `ShiftTable` (its serde form: ids and gear states
        are indices) and the CLI's document of it."""
        d, document = raw
        links, _, elements = names
        gears = tuple(GearState._from_core(names, g, row) for g, row in zip(d["gears"], document["gears"]))

        def name(i: int) -> str:
            return gears[i].state

        def els(ids: Any) -> Tuple[str, ...]:
            return tuple(elements[e] for e in ids)

        sp = d["spread"]
        return cls(
            _document=document,
            input=links[d["input"]],
            output=links[d["output"]],
            gears=gears,
            forward=tuple(d["forward"]),
            steps=tuple(
                Step(name(x["from"]), name(x["to"]), x["value"], _frac(x["exact"])) for x in d["steps"]
            ),
            spread=None
            if sp is None
            else Spread(name(sp["lowest"]), name(sp["highest"]), sp["value"], _frac(sp["exact"])),
            shifts=tuple(
                Shift(
                    name(x["from"]),
                    name(x["to"]),
                    x["kind"],
                    els(x["off"]),
                    els(x["on"]),
                    els(x["kept"]),
                    x["single_swap"],
                )
                for x in d["shifts"]
            ),
            warnings=tuple(d["warnings"]),
        )

    def __getitem__(self, state: str) -> GearState:
        for g in self.gears:
            if g.state == state:
                return g
        raise ArgumentKeyError(state)

    def plot(self, kind: str = "ladder", ax: Any = None) -> Any:
        """``"ladder"``: the speed ladder of every gear state
        (:func:`egt.plot.speed_ladder`); ``"ratios"``: the gear ratios and
        steps (:func:`egt.plot.ratios`)."""
        from . import plot

        if kind == "ladder":
            return plot.speed_ladder(self, ax)
        if kind == "ratios":
            return plot.ratios(self, ax)
        raise ArgumentError(f"kind must be \"ladder\" or \"ratios\", got {kind!r}")

    def _repr_html_(self) -> str:
        from ._results import _html_table

        steps = {s.upper: s.value for s in self.steps}
        return _html_table(
            f"shift table ({self.input} -> {self.output})",
            ["state", "engaged", "ratio", "exact", "step", "efficiency"],
            (
                (g.state, " ".join(g.engaged), g.ratio, g.ratio_exact, steps.get(g.state),
                 None if g.power is None else g.power.efficiency)
                for g in self.gears
            ),
        )

    def to_pandas(self) -> "pandas.DataFrame":
        pd = _pandas()
        return pd.DataFrame(
            {
                "engaged": [" ".join(g.engaged) for g in self.gears],
                "ratio": [g.ratio for g in self.gears],
                "ratio_exact": [g.ratio_exact for g in self.gears],
                "forward": list(self.forward),
                "output_torque": [g.output_torque for g in self.gears],
                "efficiency": [None if g.power is None else g.power.efficiency for g in self.gears],
            },
            index=pd.Index([g.state for g in self.gears], name="state"),
        )
