"""Visual output: figures (matplotlib, no display needed)."""

from .plots import plot_convergence, plot_energy, plot_phase, plot_stability_regions

__all__ = ["plot_convergence", "plot_energy", "plot_phase", "plot_stability_regions"]
