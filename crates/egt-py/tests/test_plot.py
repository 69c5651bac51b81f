"""Figures and notebook views: each plot draws the numbers of the result it
is given (read back from the matplotlib artists), and every result shows as
an HTML table."""

from __future__ import annotations

import numpy as np
import pytest

import egt

import matplotlib
matplotlib.use("Agg")


@pytest.fixture
def zf() -> egt.Train:
    return egt.load("examples/zf_8hp70.toml")


def test_speed_ladder_of_the_8hp_draws_every_gear(zf: egt.Train) -> None:
    table = zf.shift_table()
    ax = table.plot()
    lines = ax.get_lines()[: len(table.gears)]
    assert len(lines) == len(table.gears) == 9
    links = [t.get_text() for t in ax.get_xticklabels()]
    for line, g in zip(lines, table.gears):
        assert line.get_label().startswith(g.state)
        np.testing.assert_array_equal(line.get_ydata(), [g.speeds[n] for n in links])
    # The input is 1 in every gear; the output is 1/ratio.
    i, o = links.index(table.input), links.index(table.output)
    for line, g in zip(lines, table.gears):
        assert line.get_ydata()[i] == 1.0
        assert line.get_ydata()[o] == pytest.approx(1.0 / g.ratio, rel=1e-14)


def test_ratio_chart_and_train_ladder(zf: egt.Train, fig3: egt.Train) -> None:
    table = zf.shift_table()
    ax = table.plot("ratios")
    heights = [b.get_height() for b in ax.patches]
    np.testing.assert_array_equal(heights, [g.ratio for g in table.gears])
    with pytest.raises(egt.ArgumentError):
        table.plot("pie")
    ax = fig3.speed_ladder(inputs={"2": 2.0})
    (line,) = ax.get_lines()[:1]
    k = fig3.kinematics({"2": 2.0})
    names = [t.get_text() for t in ax.get_xticklabels()]
    np.testing.assert_allclose(line.get_ydata(), [k[n] / 2.0 for n in names], rtol=1e-15)


def test_simulation_power_and_stability_plots(fig3: egt.Train) -> None:
    fig5 = egt.load("examples/fig5_stability.toml")
    sim = fig5.simulate()
    ax = sim.plot()
    for line in ax.get_lines():
        np.testing.assert_array_equal(line.get_ydata(), sim.speed(line.get_label()))
    flow = fig3.power(losses=True)
    ax = flow.plot()
    rolling = [b.get_height() for b in ax.patches[: len(flow.meshes)]]
    assert rolling == [m.rolling for m in flow.meshes]
    rep = fig5.stability()
    ax = rep.plot()
    xs = ax.collections[0].get_offsets()[:, 0]
    np.testing.assert_array_equal(xs, rep.eigenvalues)
    assert rep.verdict in ax.get_title()


def test_results_show_as_html_tables(zf: egt.Train, fig3: egt.Train) -> None:
    for obj, must in [
        (fig3, "Table 1"),
        (fig3.kinematics({"2": 100}), "125/8"),
        (fig3.dynamics(torques={"4": -50.0}, accelerations={"4": 10.0}, driving=["2"]), "multiplier"),
        (fig3.power(losses=True), "rolling power"),
        (zf.shift_table(), "108/23"),
    ]:
        html = obj._repr_html_()
        assert html.startswith("<table>") and must in html, (type(obj).__name__, html[:200])
