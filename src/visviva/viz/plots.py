"""Figures for teaching and checking: stability regions, energy, convergence, phase portraits,
the two figures of an integrator comparison.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot (no global
state, no display needed); save it with ``figure.savefig(path)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..analysis.invariants import relative_change
from .colors import distinct_styles
from .legends import legend_below, legend_beside, shared_legend_below

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..simulation.recording import Recording
    from ..studies.compare import Comparison
    from ..studies.convergence import ConvergenceStudy

__all__ = [
    "comparison_figures",
    "has_momenta",
    "plot_convergence",
    "plot_energy",
    "plot_phase",
    "plot_stability_regions",
]

#: The signed energy change's axis label (its second line says where the axis is linear).
ENERGY_CHANGE = "(E(t) − E(0)) / |E(0)|"
STABLE_COLOR = "#9ecae1"
BOUNDARY_COLOR = "#08519c"


def _figure(panels: int, *, width: float = 3.2, height: float = 3.0, columns: int = 4) -> Figure:
    from matplotlib.figure import Figure

    columns = min(columns, panels)
    rows = math.ceil(panels / columns)
    figure = Figure(figsize=(width * columns, height * rows), layout="constrained")
    figure.subplots(rows, columns, squeeze=False)
    for extra in figure.axes[panels:]:
        extra.set_visible(False)
    return figure


def plot_stability_regions(
    methods: Sequence[str | Any],
    *,
    bounds: tuple[float, float, float, float] = (-5.0, 3.0, -4.0, 4.0),
    resolution: int = 401,
    columns: int = 4,
) -> Figure:
    """One panel per method: the region ``|R(z)| ≤ 1`` of the ``z = hλ`` plane, shaded.

    Args:
        methods: Method names or instances.
        bounds: ``(re_min, re_max, im_min, im_max)`` of each panel.
        resolution: Grid points per axis.
        columns: Panels per row.
    """
    from ..analysis.stability import stability_region
    from ..integrators import get

    integrators = [get(m) for m in methods]
    figure = _figure(len(integrators), columns=columns)
    for ax, method in zip(figure.axes, integrators, strict=False):
        re, im, modulus = stability_region(method, bounds, resolution)
        stable = np.where(np.isfinite(modulus), modulus, np.inf) <= 1.0 + 1e-12
        ax.contourf(re, im, stable.astype(float), levels=[0.5, 1.5], colors=[STABLE_COLOR])
        ax.contour(
            re,
            im,
            np.nan_to_num(modulus, nan=np.inf, posinf=1e300),
            levels=[1.0],
            colors=[BOUNDARY_COLOR],
            linewidths=1.2,
        )
        ax.axhline(0.0, color="0.3", linewidth=0.6)
        ax.axvline(0.0, color="0.3", linewidth=0.6)
        ax.set_xlim(bounds[0], bounds[1])
        ax.set_ylim(bounds[2], bounds[3])
        ax.set_aspect("equal")
        ax.set_title(method.name, fontsize=10)
        ax.set_xlabel("Re(hλ)")
        ax.set_ylabel("Im(hλ)")
    figure.suptitle("Stability regions |R(hλ)| ≤ 1 (shaded = stable)")
    return figure


def plot_energy(
    recordings: Mapping[str, Recording],
    *,
    title: str = "Energy relative to its initial value",
) -> Figure:
    """The relative change of the energy, ``(E(t) − E(0)) / |E(0)|``, of several runs: in
    percent, signed (top: growth and decay, linear within ±1 % and logarithmic beyond, so a
    method that multiplies the energy by 1000 and one that loses half of it both read plainly;
    the linear band is shaded, so a curve's bend at ±1 % reads as the axis', and the ticks
    carry the decimals a small change needs) and its magnitude on a log axis (bottom:
    separates the methods that keep the energy to round-off from those with a bounded
    oscillation or a slow drift). Runs without an energy are skipped; for a batch, system 0 is
    shown.
    """
    from matplotlib.figure import Figure

    from .symlog import symlog_axis
    from .ticks import PercentTicks

    figure = Figure(figsize=(9.0, 8.0), layout="constrained")
    change_ax, error_ax = figure.subplots(2, 1, sharex=True)
    runs = [(n, r) for n, r in recordings.items() if "energy" in r and r.frames > 0]
    for (name, recording), style in zip(runs, distinct_styles(len(runs)), strict=True):
        energy = recording["energy"]
        energy = energy if energy.ndim == 1 else energy[:, 0]
        change = relative_change(energy)
        change_ax.plot(recording.time, change, label=name, linewidth=1.3, **style)
        # Exact zeros would vanish from a log axis; floor them at the double-precision epsilon.
        error_ax.plot(
            recording.time,
            np.maximum(np.abs(change), np.finfo(float).eps),
            linewidth=1.1,
            **style,
        )
    symlog_axis(change_ax, linthresh=0.01, linscale=0.5, label=ENERGY_CHANGE, threshold_text="1 %")
    change_ax.yaxis.set_major_formatter(PercentTicks())
    change_ax.axhline(0.0, color="0.5", linewidth=0.8)
    legend_beside(change_ax)  # up to 17 methods: a tall list
    change_ax.set_title(title)
    error_ax.set_yscale("log")
    error_ax.set_ylabel("|E(t) − E(0)| / |E(0)|")
    error_ax.set_xlabel("time [s]")
    for ax in (change_ax, error_ax):
        ax.grid(True, which="both", alpha=0.3)
    return figure


def plot_phase(
    recordings: Mapping[str, Recording],
    *,
    exact: tuple[np.ndarray, np.ndarray] | None = None,
    columns: int = 4,
    labels: tuple[str, str] = ("q", "v"),
    velocity_scale: float = 1.0,
    title: str = "Phase portraits",
) -> Figure:
    """Phase portraits ``(q, v / velocity_scale)`` of the first coordinate, one panel per run,
    on equal axes.

    For an oscillator of angular frequency ω, ``velocity_scale = ω`` makes the exact orbit a
    circle, so a method that spirals out, spirals in or keeps a slightly different ellipse is
    seen at a glance.

    Args:
        recordings: Run name → recording of a second-order problem.
        exact: Optional exact curve ``(q, v)`` drawn under every panel (``v`` unscaled).
        columns: Panels per row.
        labels: Axis labels of what is drawn (``("q [m]", "v/ω [m]")`` with a scale).
        velocity_scale: ``v`` is drawn divided by this [1/s for v/ω].
        title: Title of the figure.
    """
    figure = _figure(len(recordings), columns=columns)
    for ax, (name, recording) in zip(figure.axes, recordings.items(), strict=False):
        q, v = recording["q"], recording["v"]
        q = q[..., 0] if q.ndim == 2 else q[:, 0, 0]
        v = (v[..., 0] if v.ndim == 2 else v[:, 0, 0]) / velocity_scale
        if exact is not None:
            ax.plot(exact[0], exact[1] / velocity_scale, color="0.6", linewidth=2.5, label="exact")
        ax.plot(q, v, color=BOUNDARY_COLOR, linewidth=0.9, label="computed")
        ax.plot(q[:1], v[:1], "o", color="#e6550d", markersize=4, label="start")
        ax.set_title(name, fontsize=10)
        ax.set_xlabel(labels[0])
        ax.set_ylabel(labels[1])
        ax.set_aspect("equal", adjustable="datalim")
    if recordings:  # every panel draws the same three things: one legend for all
        shared_legend_below(figure, figure.axes[0])
    figure.suptitle(title)
    return figure


def plot_convergence(studies: Sequence[ConvergenceStudy]) -> Figure:
    """Error against step size, log–log, with the fitted order of each method."""
    figure = _figure(1, width=7.5, height=5.5)
    ax = figure.axes[0]
    for study, style in zip(studies, distinct_styles(len(studies)), strict=True):
        finite = np.isfinite(study.error) & (study.error > 0)
        ax.loglog(
            study.dt[finite],
            study.error[finite],
            marker="o",
            markersize=3,
            label=f"{study.method}: {study.order:.2f} (declared {study.declared_order})",
            **style,
        )
        ax.loglog(
            study.dt[study.used],
            study.error[study.used],
            "o",
            markersize=6,
            color=style["color"],
            markerfacecolor="none",
        )
    ax.set_xlabel("dt [s]")
    ax.set_ylabel("error at `until` (max norm)")
    ax.grid(True, which="both", alpha=0.3)
    legend_below(ax)
    ax.set_title("Convergence: circled points are in the fitted asymptotic range")
    return figure


def comparison_figures(comparison: Comparison, *, title: str | None = None) -> dict[str, Figure]:
    """The figures of :func:`~visviva.studies.compare_methods`, by name: ``"energy"``, the
    energy of every full run (:func:`plot_energy`), and ``"convergence"``, error against step
    size with each method's fitted order (:func:`plot_convergence`).

    Args:
        comparison: What :func:`~visviva.studies.compare_methods` returned.
        title: Title of the energy figure; default ``"Energy, h = <dt> s"``.
    """
    return {
        "energy": plot_energy(comparison.runs, title=title or f"Energy, h = {comparison.dt:g} s"),
        "convergence": plot_convergence(comparison.studies),
    }


def has_momenta(recording: Recording) -> bool:
    """True if ``recording`` holds what :func:`plot_momentum` needs: the particles' positions,
    velocities and masses."""
    fields = {"particle_position", "particle_velocity"}
    return fields <= set(recording.fields) and "particle_mass" in recording.static


def plot_momentum(recording: Recording, *, title: str = "Momenta") -> Figure:
    """Linear momentum ``P = Σ m v`` and angular momentum ``L = Σ m x × v`` over time.

    Needs a particle recording: fields ``particle_position`` [m] and ``particle_velocity``
    [m/s] and the static ``particle_mass`` [kg]. Each component is drawn against time [s].
    """
    from ..analysis.invariants import angular_momentum, linear_momentum
    from ..errors import ModelError

    if not has_momenta(recording):
        raise ModelError(
            "momentum plots need a particle recording (particle_position, particle_velocity "
            f"and particle_mass); this one has fields {', '.join(recording.fields)}"
        )
    mass = recording.static["particle_mass"]
    x, v = recording["particle_position"], recording["particle_velocity"]
    series = {
        "linear momentum P [kg·m/s]": linear_momentum(mass, v),
        "angular momentum L [kg·m²/s]": angular_momentum(mass, x, v),
    }
    figure = _figure(2, width=6.0, height=3.6, columns=2)
    for ax, (label, values) in zip(figure.axes, series.items(), strict=True):
        for axis, name in enumerate("xyz"):
            ax.plot(recording.time, values[:, axis], label=f"{label.split()[-2]}{name}")
        ax.set_xlabel("t [s]")
        ax.set_ylabel(label)
        legend_below(ax)
    figure.suptitle(title)
    return figure
