"""Visual output: figures (matplotlib, no display needed), video, the web viewer, and the
table of output formats a run writes (:mod:`.outputs`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_names

if TYPE_CHECKING:
    from .plots import plot_convergence, plot_energy, plot_phase, plot_stability_regions
    from .sweep_plots import plot_against_parameter

__all__ = [
    "plot_against_parameter",
    "plot_convergence",
    "plot_energy",
    "plot_phase",
    "plot_stability_regions",
]

# Names load on first use (visviva._lazy): writing a video or listing the output formats needs
# no matplotlib figures.
__getattr__, __dir__ = lazy_names(
    __name__,
    __all__,
    {
        "plot_against_parameter": "sweep_plots",
        "plot_convergence": "plots",
        "plot_energy": "plots",
        "plot_phase": "plots",
        "plot_stability_regions": "plots",
    },
)
