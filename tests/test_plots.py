"""Legible figures: energy change in plain percentages, phase portraits with titles and circles."""

from __future__ import annotations

import numpy as np
import pytest

import visviva as vv
from visviva.viz.plots import plot_energy, plot_phase


def _oscillator_runs(omega: float = 2.0 * np.pi, dt: float = 0.02, until: float = 5.0):
    spring = vv.ode.SecondOrderProblem(
        lambda t, q: -(omega**2) * q,
        q0=[1.0],
        v0=[0.0],
        energy=lambda t, q, v: 0.5 * v[..., 0] ** 2 + 0.5 * omega**2 * q[..., 0] ** 2,
    )
    return {
        method: vv.solve(spring, method, dt=dt, until=until).recording
        for method in ("explicit_euler", "backward_euler", "velocity_verlet")
    }


def _tick_labels(axis) -> list[str]:
    axis.figure.canvas.draw()
    return [label.get_text() for label in axis.get_yticklabels() if label.get_text()]


def test_energy_change_reads_in_plain_percentages():
    runs = _oscillator_runs()
    figure = plot_energy(runs)
    change, error = figure.axes[:2]
    labels = _tick_labels(change)
    # Explicit Euler grows the energy by (1 + (ωh)²)^n, backward Euler shrinks it by the same
    # factor: both must read plainly, with no 9.99×10⁻¹-style labels of a log ratio axis.
    assert labels and all(text.endswith("%") for text in labels), labels
    assert "0%" in labels and any(text.startswith("−") for text in labels)
    assert not any("10^" in text or "×" in text for text in labels)
    # The second line of the label says where the symlog axis is linear.
    assert change.get_ylabel().splitlines()[0] == "(E(t) − E(0)) / |E(0)|"
    # The curve drawn is the relative change itself; for explicit Euler on the oscillator
    # it is (1 + (ωh)²)^n − 1 after n steps (|R(iωh)|² = 1 + (ωh)²).
    euler = change.get_lines()[0]
    np.testing.assert_allclose(
        euler.get_ydata(), vv.analysis.relative_change(runs["explicit_euler"]["energy"])
    )
    omega_h = 2.0 * np.pi * 0.02
    assert euler.get_ydata()[-1] == pytest.approx((1 + omega_h**2) ** 250 - 1)
    assert error.get_yscale() == "log"


def test_phase_portraits_have_a_title_a_legend_and_circles():
    omega = 2.0 * np.pi
    runs = _oscillator_runs(omega)
    angle = np.linspace(0.0, 2.0 * np.pi, 100)
    figure = plot_phase(
        runs,
        exact=(np.cos(angle), -omega * np.sin(angle)),
        labels=("q [m]", "v/ω [m]"),
        velocity_scale=omega,
        title="Phase portraits",
    )
    assert figure.get_suptitle() == "Phase portraits"
    # Every panel draws the same three things: one legend under the figure names them.
    (legend,) = figure.legends
    assert [t.get_text() for t in legend.get_texts()] == ["exact", "computed", "start"]
    for ax in figure.axes[: len(runs)]:
        assert ax.get_aspect() == 1.0 and ax.get_ylabel() == "v/ω [m]"
    # Scaled by ω, Verlet's orbit is the unit circle to O((ωh)²): radius within 2 %.
    verlet = figure.axes[2].get_lines()[1]
    radius = np.hypot(verlet.get_xdata(), verlet.get_ydata())
    assert np.allclose(radius, 1.0, atol=0.02)
