"""Analysis of integrators and runs: stability functions and regions, the largest stable step
from a spectrum (the advisor the divergence watch asks), invariants, chaos measures. Studies
that run the solver to measure methods — convergence orders, comparisons — are
:mod:`visviva.studies`, a layer above the simulation loop."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_names

if TYPE_CHECKING:
    from .advisor import largest_stable_step, matrix_free_eigenvalues
    from .chaos import LyapunovEstimate, lyapunov_exponent, separation
    from .invariants import (
        angular_momentum,
        center_of_mass,
        energy_drift,
        linear_momentum,
        max_energy_error,
        relative_change,
    )
    from .stability import (
        max_stable_dt,
        spectrum,
        stability_function,
        stability_interval,
        stability_region,
        state_jacobian,
    )

__all__ = [
    "LyapunovEstimate",
    "angular_momentum",
    "center_of_mass",
    "energy_drift",
    "largest_stable_step",
    "linear_momentum",
    "lyapunov_exponent",
    "matrix_free_eigenvalues",
    "max_energy_error",
    "max_stable_dt",
    "relative_change",
    "separation",
    "spectrum",
    "stability_function",
    "stability_interval",
    "stability_region",
    "state_jacobian",
]

# Names load on first use (visviva._lazy): a run's summary needs `invariants` without the
# stability functions' integrators.
__getattr__, __dir__ = lazy_names(
    __name__,
    __all__,
    {
        "largest_stable_step": "advisor",
        "matrix_free_eigenvalues": "advisor",
        "LyapunovEstimate": "chaos",
        "lyapunov_exponent": "chaos",
        "separation": "chaos",
        "angular_momentum": "invariants",
        "center_of_mass": "invariants",
        "energy_drift": "invariants",
        "linear_momentum": "invariants",
        "max_energy_error": "invariants",
        "relative_change": "invariants",
        "max_stable_dt": "stability",
        "spectrum": "stability",
        "stability_function": "stability",
        "stability_interval": "stability",
        "stability_region": "stability",
        "state_jacobian": "stability",
    },
)
