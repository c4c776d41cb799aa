"""Figures that show the physics and nothing else: distinct colours, legends off the data,
symlog axes that say where they are linear, percent ticks that are distinct and true."""

from __future__ import annotations

import re

import numpy as np
import pytest
from matplotlib.colors import to_rgb

from visviva.demos import find_demo
from visviva.io.job import JobOutput
from visviva.simulation.recording import Recording
from visviva.viz.colors import distinct_colors, shades
from visviva.viz.plots import plot_energy
from visviva.viz.symlog import LINEAR_BAND_GID, BandTicks
from visviva.viz.ticks import percent_labels

#: Short runs that still draw every curve of the demos' figures [s].
SHORT = {
    "oscillator": 1.0,
    "pendulum": 4.5,  # two swings: the period is measured
    "constrained-pendulum": 2.0,
    "kepler": 6.0,
    "dzhanibekov": 1.0,
}


@pytest.fixture(scope="module")
def demo_figures(tmp_path_factory):
    """Each demo's figures from a short run: {demo: {name: Figure}}, drawn once."""
    figures = {}
    for name, duration in SHORT.items():
        with JobOutput(tmp_path_factory.mktemp(name)) as output:
            find_demo(name).run(output, duration)
            figures[name] = dict(output.figures)
    for drawn in figures.values():
        for figure in drawn.values():
            figure.draw_without_rendering()  # lays out and places the legends
    return figures


def _labelled_lines(ax):
    return [line for line in ax.get_lines() if not line.get_label().startswith("_")]


def _legends(figure):
    """Every legend of a figure: the axes' and the figure's own."""
    return [ax.get_legend() for ax in figure.axes if ax.get_legend()] + list(figure.legends)


@pytest.mark.parametrize("count", [1, 3, 10, 11, 17, 20, 21, 60, 300])
def test_no_colour_repeats_for_any_number_of_lines(count):
    colors = distinct_colors(count)
    assert len(colors) == count and len(set(colors)) == count
    assert len(set(shades(count, "Reds"))) == count


def test_the_oscillator_s_17_methods_each_have_their_own_colour_and_name(demo_figures):
    energy = demo_figures["oscillator"]["energy"]
    for ax in energy.axes:
        lines = _labelled_lines(ax) or ax.get_lines()
        colors = [to_rgb(line.get_color()) for line in lines]
        assert len(colors) >= 17 and len(set(colors)) == len(colors)
    legend = energy.axes[0].get_legend()
    names = [text.get_text() for text in legend.get_texts()]
    assert "explicit_euler" in names and "velocity_verlet" in names and len(set(names)) >= 17


@pytest.mark.parametrize("demo", list(SHORT))
def test_legends_sit_outside_every_axes_and_its_tick_labels(demo, demo_figures):
    for figure in demo_figures[demo].values():
        canvas = figure.bbox
        legends = _legends(figure)
        assert legends, f"{demo}: no legend"
        for legend in legends:
            box = legend.get_window_extent()
            assert canvas.x0 - 1 <= box.x0 and box.x1 <= canvas.x1 + 1  # not cut off
            assert canvas.y0 - 1 <= box.y0 and box.y1 <= canvas.y1 + 1
            for ax in figure.axes:
                if not ax.get_visible():
                    continue
                assert not box.overlaps(ax.get_window_extent()), f"{demo}: legend on data"
                labels = ax.xaxis.get_tightbbox()  # None: no tick labels, no label
                assert labels is None or not box.overlaps(labels), f"{demo}: on the x labels"


def test_every_labelled_line_of_the_demos_is_distinct_from_its_neighbours(demo_figures):
    for demo, figures in demo_figures.items():
        for figure in figures.values():
            for ax in figure.axes:
                looks = [
                    (to_rgb(line.get_color()), line.get_linestyle(), line.get_marker())
                    for line in _labelled_lines(ax)
                ]
                assert len(set(looks)) == len(looks), f"{demo}: two lines look alike"


def test_dzhanibekov_names_each_handle_and_the_axis_it_spins_about(demo_figures):
    panels = demo_figures["dzhanibekov"]["dzhanibekov"].axes[:3]
    for ax, role in zip(panels, ("minor", "intermediate", "major"), strict=True):
        assert f"spun about its {role} axis" in ax.get_title()
        entries = [text.get_text() for text in ax.get_legend().get_texts()]
        assert entries == [
            f"ω_x: minor axis{', spun' * (role == 'minor')}",
            f"ω_y: intermediate axis{', spun' * (role == 'intermediate')}",
            f"ω_z: major axis{', spun' * (role == 'major')}",
        ]


def _tiny_change(size: float) -> dict[str, Recording]:
    """A recording whose energy wanders by ``size`` of itself (the galaxy demo: 0.25 %)."""
    time = np.linspace(0.0, 15.0, 400)
    energy = -2.0 * (1.0 + size * (time / 15.0) ** 2 - 0.1 * size * np.sin(3 * time))
    return {"velocity_verlet": Recording(time, {"energy": energy})}


def _value(label: str) -> float:
    """The number a percent tick label writes, as a fraction."""
    text = label.replace("−", "-").rstrip("%")
    if "times10" in text:
        mantissa, exponent = re.match(r"\$(.+)\\times10\^\{(.+)\}\$", text).groups()
        return float(mantissa) * 10.0 ** int(exponent) / 100.0
    return float(text) / 100.0


@pytest.mark.parametrize("size", [2.5e-3, 3e-7, 1e-12])
def test_percent_ticks_of_a_tiny_energy_change_are_distinct_and_true(size):
    figure = plot_energy(_tiny_change(size))
    figure.draw_without_rendering()
    change = figure.axes[0]
    low, high = change.get_ylim()
    ticks = [
        (tick, label.get_text())
        for tick, label in zip(change.get_yticks(), change.get_yticklabels(), strict=True)
        if low <= tick <= high
    ]
    labels = [text for _, text in ticks]
    assert len(ticks) >= 3, labels
    assert len(set(labels)) == len(labels), labels  # not "0%", "0%", "−0%"
    spacing = np.diff(sorted(tick for tick, _ in ticks)).min()
    for tick, text in ticks:
        assert _value(text) == pytest.approx(tick, abs=1e-3 * spacing), (tick, text)


def test_percent_labels_keep_decades_plain():
    assert percent_labels([-0.01, 0.0, 0.01, 0.1, 10.0]) == ["−1%", "0%", "1%", "10%", "1000%"]
    assert percent_labels([0.0, 0.0025, 0.005]) == ["0%", "0.25%", "0.5%"]


def test_symlog_axes_shade_and_name_their_linear_band(demo_figures):
    figures = [*demo_figures["oscillator"].values(), plot_energy(_tiny_change(0.05))]
    symlog = [ax for figure in figures for ax in figure.axes if ax.get_yscale() == "symlog"]
    assert symlog
    for ax in symlog:
        marked = [artist for artist in ax.get_children() if artist.get_gid() == LINEAR_BAND_GID]
        assert len(marked) == 2  # the shading and the dotted edges
        assert "linear within ±1 %" in ax.get_ylabel()


def test_band_ticks_fill_the_band_only_where_it_has_room():
    from matplotlib.figure import Figure

    ax = Figure().subplots()
    ax.plot([0.0, 1.0], [-1.0, 2500.0])
    ax.set_yscale("symlog", linthresh=0.01, linscale=0.5)
    ax.yaxis.set_major_locator(BandTicks(0.01))
    ax.figure.draw_without_rendering()
    inside = [t for t in ax.get_yticks() if 0 < abs(t) < 0.01]
    assert not inside  # the band is a sliver of a 5-decade axis: 0 and ±1 % say enough
    ax.set_ylim(-0.001, 0.02)
    inside = [t for t in ax.get_yticks() if 0 < abs(t) < 0.01]
    assert len(inside) >= 3 and np.allclose(np.diff(inside), inside[1] - inside[0])
