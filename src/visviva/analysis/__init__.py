"""Analysis of integrators and runs: stability, convergence order, invariants, chaos measures."""

from .advisor import largest_stable_step, matrix_free_eigenvalues
from .chaos import LyapunovEstimate, lyapunov_exponent, separation
from .compare import Comparison, MethodResult, compare_methods
from .convergence import ConvergenceStudy, convergence_order
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
    "Comparison",
    "ConvergenceStudy",
    "LyapunovEstimate",
    "MethodResult",
    "angular_momentum",
    "center_of_mass",
    "compare_methods",
    "convergence_order",
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
