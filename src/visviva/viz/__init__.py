"""Visual output: figures (matplotlib, no display needed)."""

from .plots import plot_convergence, plot_energy, plot_phase, plot_stability_regions
from .sweep_plots import plot_against_parameter

__all__ = [
    "plot_against_parameter",
    "plot_convergence",
    "plot_energy",
    "plot_phase",
    "plot_stability_regions",
]
