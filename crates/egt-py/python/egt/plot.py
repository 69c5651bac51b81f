"""Figures of egt's results with matplotlib (optional:
``pip install 'egt-gears[plot]'``). Each function draws on ``ax`` (a new
figure's axes when omitted) and returns the axes, so figures compose and
render inline in notebooks; the result classes' ``plot()`` methods call these.

- :func:`speed_ladder`: the speed ladder (lever diagram) of a train or of every
  gear state of a transmission: each link's speed per unit input speed.
- :func:`ratios`: a transmission's gear ratios with the steps between them.
- :func:`simulation`: link speeds against time.
- :func:`power_flow`: per mesh, the rolling power and the loss.
- :func:`eigenvalues`: a stability report's eigenvalues and verdict.
- :func:`campbell`: natural frequencies against tooth-pass frequencies over
  the input speed, crossings circled (``egt modes --campbell --plot``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, List, Mapping, Optional, Sequence, Tuple, Union, cast

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

    from ._motion import Simulation, StabilityReport
    from ._results import PowerFlow
    from ._train import Train
    from ._transmission import ShiftTable
    from ._vibration import Modes

__all__ = ["speed_ladder", "ratios", "simulation", "power_flow", "eigenvalues", "campbell"]


def _axes(ax: Optional["Axes"]) -> "Axes":
    if ax is not None:
        return ax
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("egt.plot needs matplotlib: pip install 'egt-gears[plot]'") from e
    _, new = plt.subplots()
    return new


def speed_ladder(
    what: Union["Train", "ShiftTable"],
    ax: Optional["Axes"] = None,
    *,
    inputs: Optional[Mapping[str, Any]] = None,
) -> "Axes":
    """Every link's speed per unit input speed, links along the x axis.

    A :class:`~egt.ShiftTable` (or a train with a ``[transmission]``) gives one
    line per gear state, the lever diagram of the transmission; another train
    gives one line, from ``inputs`` (default: the spec's speeds) scaled so that
    the largest input is 1. Planets without teeth (unknown speed) are left out.
    """
    from ._egt import TransmissionError

    ax = _axes(ax)
    lines: List[Tuple[str, List[float]]] = []
    table: Optional["ShiftTable"] = None
    # A train has a shift_table(); a ShiftTable is one (checked by what it
    # has, so that this module imports no result class: they import it).
    if not hasattr(what, "shift_table"):
        table = what
    elif inputs is None and cast("Train", what).elements:
        try:
            table = cast("Train", what).shift_table()
        except TransmissionError:  # elements but no gear states: the train itself
            table = None
    if table is not None:
        links = [n for n in table.gears[0].speeds if all(g.speeds[n] is not None for g in table.gears)]
        for g in table.gears:
            lines.append((f"{g.state} ({g.ratio:.3g})", [float(g.speeds[n] or 0.0) for n in links]))
        ax.set_ylabel(f"speed / speed of {table.input}")
    else:
        train: "Train" = what  # type: ignore[assignment]
        k = train.kinematics(inputs)
        given = list(inputs) if inputs else [n for n, _, _ in train._spec_speeds()]
        scale = max((abs(float(k[n])) for n in given), default=1.0) or 1.0
        links = [n for n, known in zip(k.links, k.known) if known]
        lines.append(("speeds", [float(k[n]) / scale for n in links]))
        ax.set_ylabel("speed / largest input speed")
    x = list(range(len(links)))
    for label, ys in lines:
        ax.plot(x, ys, marker="o", label=label)
    ax.axhline(0.0, color="0.6", linewidth=0.8)
    ax.set_xticks(x)
    ax.set_xticklabels(links, rotation=45, ha="right", fontsize="small")
    ax.set_xlabel("link")
    ax.set_title("speed ladder")
    fig = ax.get_figure()
    if fig is not None and hasattr(fig, "tight_layout"):  # a SubFigure lays itself out
        fig.tight_layout()
    if len(lines) > 1:
        ax.legend(fontsize="small")
    return ax


def ratios(table: "ShiftTable", ax: Optional["Axes"] = None) -> "Axes":
    """A transmission's gear ratios (bars, labelled with the engaged elements)
    and the step to the next forward gear."""
    ax = _axes(ax)
    x = list(range(len(table.gears)))
    values = [g.ratio for g in table.gears]
    bars = ax.bar(x, values, color=["C0" if f else "C3" for f in table.forward])
    for b, g in zip(bars, table.gears):
        ax.annotate(" ".join(g.engaged), (b.get_x() + b.get_width() / 2, b.get_height()),
                    ha="center", va="bottom" if b.get_height() >= 0 else "top", fontsize="x-small")
    names = [g.state for g in table.gears]
    top = max(abs(v) for v in values) or 1.0
    for s in table.steps:
        i, j = names.index(s.lower), names.index(s.upper)
        y = max(values[i], values[j]) + 0.08 * top
        ax.annotate(f"x{s.value:.3g}", ((i + j) / 2, y), ha="center", va="bottom",
                    fontsize="x-small", color="0.3")
    ax.axhline(0.0, color="0.6", linewidth=0.8)
    ax.set_xticks(x)
    ax.set_xticklabels(names)
    ax.margins(y=0.12)
    ax.set_xlabel("gear state")
    ax.set_ylabel(f"ratio {table.input} / {table.output}")
    spread = "" if table.spread is None else f", spread {table.spread.value:.3g}"
    ax.set_title(f"gear ratios{spread}")
    return ax


def simulation(sim: "Simulation", ax: Optional["Axes"] = None, links: Optional[Sequence[str]] = None) -> "Axes":
    """Link speeds against time (every moving link, or ``links``)."""
    ax = _axes(ax)
    chosen = list(links) if links is not None else [n for i, n in enumerate(sim.links) if sim.speeds[:, i].any()]
    for n in chosen:
        ax.plot(sim.t, sim.speed(n), label=n)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("speed [rad/s]")
    ax.set_title(f"simulation ({sim.method}, dt = {sim.dt:g} s)")
    ax.legend(fontsize="small")
    return ax


def power_flow(flow: "PowerFlow", ax: Optional["Axes"] = None) -> "Axes":
    """Per mesh: the rolling power (in the carrier's frame) and the loss."""
    ax = _axes(ax)
    x = list(range(len(flow.meshes)))
    ax.bar([i - 0.2 for i in x], [m.rolling for m in flow.meshes], width=0.4, label="rolling power")
    ax.bar([i + 0.2 for i in x], [m.loss for m in flow.meshes], width=0.4, label="loss")
    ax.set_xticks(x)
    ax.set_xticklabels([m.gear for m in flow.meshes])
    ax.set_xlabel("gear pair")
    ax.set_ylabel("power [W]")
    eff = "" if flow.efficiency is None else f", efficiency {flow.efficiency:.4g}"
    ax.set_title(f"power flow{eff}")
    ax.legend(fontsize="small")
    return ax


def eigenvalues(report: "StabilityReport", ax: Optional["Axes"] = None) -> "Axes":
    """The eigenvalues of the linearised motion (eq. 18, corrected) on the
    real axis, with the verdict: stable exactly when none is positive."""
    ax = _axes(ax)
    ev = [float(v) for v in report.eigenvalues]
    ax.scatter(ev, [0.0] * len(ev), marker="x", s=60, color="C3" if report.verdict == "unstable" else "C0")
    ax.axvline(0.0, color="0.6", linewidth=0.8)
    ax.set_yticks([])
    ax.set_xlabel("eigenvalue [1/s]")
    ax.set_title(f"stability: {report.verdict}")
    return ax


def campbell(modes: "Modes", ax: Optional["Axes"] = None) -> "Axes":
    """The Campbell diagram of :meth:`egt.Train.modes` with ``campbell=``:
    each distinct elastic frequency up to a little above the highest mesh
    frequency as a grey line, each mesh's tooth-pass frequency as a ray from
    the origin over the input speed, the crossings circled."""
    if modes.mesh_orders is None or modes.speed_range is None:
        raise ValueError("a Campbell diagram needs Train.modes(state, campbell=(min, max))")
    ax = _axes(ax)
    lo, hi = modes.speed_range
    top = max((o * hi / 60.0 for o in modes.mesh_orders.values()), default=0.0)
    ceiling = 1.15 * top if top > 0 else 1.0
    for k, m in enumerate(modes.modes):
        if not m.rigid and m.group == k and m.hertz <= ceiling:
            ax.axhline(m.hertz, color="0.6", lw=1.0)
            ax.annotate(f"mode {k + 1}", (lo, m.hertz), fontsize="x-small", color="0.4", va="bottom")
    colours = {}
    for gear, order in modes.mesh_orders.items():
        (line,) = ax.plot([lo, hi], [order * lo / 60.0, order * hi / 60.0], label=f"{gear} (order {order:.4g})")
        colours[gear] = line.get_color()
    for c in modes.crossings:
        ax.plot([c.speed], [c.hertz], "o", mfc="none", color=colours.get(c.gear, "k"))
    ax.set_xlim(lo, hi)
    ax.set_ylim(0.0, ceiling)
    ax.set_xlabel("input speed [rpm]")
    ax.set_ylabel("frequency [Hz]")
    state = "" if modes.state is None else f" in gear state {modes.state}"
    ax.set_title(f"Campbell diagram{state}: {len(modes.crossings)} crossing(s)")
    ax.legend(fontsize="x-small")
    return ax

