"""Analysis of integrators and runs: stability, convergence order, invariants."""

from .stability import (
    max_stable_dt,
    spectrum,
    stability_function,
    stability_interval,
    stability_region,
    state_jacobian,
)

__all__ = [
    "max_stable_dt",
    "spectrum",
    "stability_function",
    "stability_interval",
    "stability_region",
    "state_jacobian",
]
