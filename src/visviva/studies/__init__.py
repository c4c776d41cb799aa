"""Studies of integrators that run the solver: measured convergence orders, and methods
compared side by side on one problem (energy error, work, wall time).

They sit above the simulation loop (:func:`visviva.solve` runs each case), while the
analysis they use — invariants, stability — is :mod:`visviva.analysis`, below it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_names

if TYPE_CHECKING:
    from .compare import Comparison, MethodResult, compare_methods
    from .convergence import ConvergenceStudy, convergence_order

__all__ = ["Comparison", "ConvergenceStudy", "MethodResult", "compare_methods", "convergence_order"]

__getattr__, __dir__ = lazy_names(
    __name__,
    __all__,
    {
        "Comparison": "compare",
        "MethodResult": "compare",
        "compare_methods": "compare",
        "ConvergenceStudy": "convergence",
        "convergence_order": "convergence",
    },
)
