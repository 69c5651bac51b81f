"""The gear changes in time of :class:`egt.Train` (``egt shift-sim``): a
shift given by its arguments, or one the spec names (``[[shift]]``); a mixin
the train class takes its shift methods from."""

from __future__ import annotations

from numbers import Real
from typing import Any, List, Mapping, Optional, Sequence, Tuple, Union

from ._args import ArgumentError, ArgumentTypeError, count, number
from ._egt import TrainCore
from ._egt import shift_named as _shift_named
from ._egt import shift_names as _shift_names
from ._egt import shift_sim as _shift_sim
from ._motion import ShiftSimulation


class ShiftMethods:
    """The shift-simulation methods of :class:`egt.Train`."""

    __slots__ = ()
    _core: TrainCore
    _links: Tuple[str, ...]

    def simulate_shift(
        self,
        from_: str,
        to: str,
        *,
        input_speed: float,
        off_going: Optional[Union[float, Sequence[float]]] = None,
        on_coming: Optional[Union[float, Sequence[float]]] = None,
        ramps: Optional[Mapping[str, Union[float, Sequence[float]]]] = None,
        input_torque: Optional[float] = None,
        torque_table: Optional[Sequence[Tuple[float, float]]] = None,
        road_load: Sequence[float] = (0.0, 0.0, 0.0),
        vehicle_inertia: float = 0.0,
        mu: Sequence[float] = (0.15, 0.12),
        mu_decay: Optional[float] = None,
        t_end: float = 1.0,
        rtol: float = 1e-8,
        atol: float = 1e-8,
        method: str = "auto",
        max_steps: Optional[int] = None,
        output_shaft: Optional[Union[float, Sequence[float]]] = None,
        losses: bool = False,
    ) -> ShiftSimulation:
        """A gear change in time, as ``egt shift-sim`` (docs/shift_dynamics.md).

        The train starts in ``from_``'s steady motion at ``input_speed``
        [rad/s]; the off-going element's capacity falls and the on-coming
        one's rises. A capacity [N m per unit friction coefficient] is a
        number or a ramp ``(t0, t1, from, to)``. The input torque is a
        constant ``input_torque`` or a ``torque_table`` of (speed, torque)
        points. ``road_load`` is ``(c0, c1, c2)``: c0 sgn(w) + c1 w + c2 w|w|
        at the output; ``vehicle_inertia`` is reflected to the output link.
        ``mu`` is (static, kinetic). ``method``: ``"auto"`` (explicit until a
        stiff mode limits its steps, then implicit; ``stiff`` says when),
        ``"explicit"`` or ``"implicit"``.

        ``off_going`` and ``on_coming`` give the capacities of a single swap
        (one element off, one on); ``ramps`` gives each changing element's
        capacity by name, for any change between the two gear states (a
        skip shift, a double swap), as ``egt shift-sim --ramp NAME=RAMP``;
        a name in ``ramps`` comes before ``off_going``/``on_coming``.
        ``max_steps`` raises the step budget (``egt shift-sim --max-steps``;
        default 2 000 000). ``output_shaft`` is a compliant shaft from the
        output link to the vehicle inertia, ``k`` or ``(k, c)`` [N m/rad,
        N m s/rad] (``egt shift-sim --output-shaft K,C``); default rigid.
        ``losses=True`` puts the gear pairs' efficiencies on the meshing
        forces, as ``egt power`` does (``egt shift-sim --losses``); the
        meshes' loss is ``mesh_loss`` and enters the energy balance.
        """

        def cap(v: Union[float, Sequence[float]], field: str) -> List[float]:
            if isinstance(v, (int, float, Real)):
                return [number(v, field)]
            return [number(x, f"{field}[{k}]") for k, x in enumerate(v)]

        rl = [number(x, f"road_load[{k}]") for k, x in enumerate(road_load)]
        if len(rl) != 3:
            raise ArgumentError(f"road_load: expected (c0, c1, c2), got {len(rl)} numbers")
        m = [number(x, f"mu[{k}]") for k, x in enumerate(mu)]
        if len(m) != 2:
            raise ArgumentError(f"mu: expected (static, kinetic), got {len(m)} numbers")
        shaft: Optional[Tuple[float, float]] = None
        if output_shaft is not None:
            sh = cap(output_shaft, "output_shaft")
            if len(sh) not in (1, 2):
                raise ArgumentError(f"output_shaft: expected k or (k, c), got {len(sh)} numbers")
            shaft = (sh[0], sh[1] if len(sh) == 2 else 0.0)
        changing: Mapping[Any, Any] = {} if ramps is None else ramps
        if not isinstance(changing, Mapping):
            raise ArgumentTypeError(
                f"ramps must be a mapping of element names to capacities, got {type(ramps).__name__}"
            )
        raw = _shift_sim(
            self._core,
            str(from_),
            str(to),
            number(input_speed, "input_speed"),
            None if input_torque is None else number(input_torque, "input_torque"),
            None
            if torque_table is None
            else [(number(w, f"torque_table[{k}]"), number(t, f"torque_table[{k}]")) for k, (w, t) in enumerate(torque_table)],
            (rl[0], rl[1], rl[2]),
            number(vehicle_inertia, "vehicle_inertia"),
            (m[0], m[1]),
            None if mu_decay is None else number(mu_decay, "mu_decay"),
            None if off_going is None else cap(off_going, "off_going"),
            None if on_coming is None else cap(on_coming, "on_coming"),
            [(str(name), cap(c, f"ramps[{name!r}]")) for name, c in changing.items()],
            number(t_end, "t_end"),
            number(rtol, "rtol"),
            number(atol, "atol"),
            str(method),
            None if max_steps is None else count(max_steps, "max_steps", 2**63 - 1),
            shaft,
            bool(losses),
        )
        return ShiftSimulation._from_core(self._links, raw)

    @property
    def shifts(self) -> Tuple[str, ...]:
        """The names of the spec's ``[[shift]]`` entries (docs/spec.md), for
        :meth:`simulate_named_shift`."""
        return tuple(_shift_names(self._core))

    def simulate_named_shift(
        self,
        name: str,
        *,
        rtol: float = 1e-8,
        atol: float = 1e-8,
        method: str = "auto",
        max_steps: Optional[int] = None,
    ) -> ShiftSimulation:
        """The spec's shift ``name`` (``[[shift]]``) in time, as ``egt
        shift-sim SPEC --shift NAME``: its gears, operating point and ramps
        from the spec, the integration settings from here (as
        :meth:`simulate_shift`)."""
        raw = _shift_named(
            self._core,
            str(name),
            number(rtol, "rtol"),
            number(atol, "atol"),
            str(method),
            None if max_steps is None else count(max_steps, "max_steps", 2**63 - 1),
        )
        return ShiftSimulation._from_core(self._links, raw)
