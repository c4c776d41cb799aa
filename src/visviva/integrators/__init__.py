"""Time integrators and their registry.

Every method is an :class:`Integrator` registered by name::

    >>> import visviva as vv
    >>> "rk4" in vv.integrators.names()
    True
    >>> vv.integrators.get("velocity_verlet").order
    2

``get`` returns the registered instance; implicit methods take Newton options when built
directly, e.g. ``vv.integrators.BackwardEuler(rtol=1e-12)``, and any instance can be passed as
``method=`` wherever a name can. Register your own method with :func:`register`; it then runs
through the same solver, analysis tools and conformance tests as the built-in ones.
"""

from __future__ import annotations

from .._registry import Registry
from ..errors import ModelError
from .base import CompiledStep, Integrator
from .dopri5 import DormandPrince5
from .fast_springs import FastMassSprings
from .implicit import (
    BackwardEuler,
    ImplicitMidpoint,
    ImplicitOneStage,
    LinearlyImplicitEuler,
    Trapezoidal,
)
from .newton import NewtonOptions
from .projected_newton import ProjectedNewton, ProjectedTrapezoidal
from .runge_kutta import (
    ButcherTableau,
    ExplicitEuler,
    ExplicitRungeKutta,
    Heun,
    Midpoint,
    RungeKutta4,
)
from .symplectic import Leapfrog, SymplecticEuler, SymplecticEulerPositionFirst, VelocityVerlet
from .taylor import Taylor

__all__ = [
    "BackwardEuler",
    "ButcherTableau",
    "CompiledStep",
    "DormandPrince5",
    "ExplicitEuler",
    "ExplicitRungeKutta",
    "FastMassSprings",
    "Heun",
    "ImplicitMidpoint",
    "ImplicitOneStage",
    "Integrator",
    "Leapfrog",
    "LinearlyImplicitEuler",
    "Midpoint",
    "NewtonOptions",
    "ProjectedNewton",
    "ProjectedTrapezoidal",
    "RungeKutta4",
    "SymplecticEuler",
    "SymplecticEulerPositionFirst",
    "Taylor",
    "Trapezoidal",
    "VelocityVerlet",
    "get",
    "names",
    "register",
    "unregister",
]

_REGISTRY: Registry[Integrator] = Registry("integration method")


def register(method: Integrator | type[Integrator], *, replace: bool = False) -> Integrator:
    """Add a method to the registry under its ``name`` and return the registered instance.

    Args:
        method: An :class:`Integrator` instance, or a subclass with a no-argument constructor.
        replace: Allow replacing a method already registered under the same name.

    Raises:
        ModelError: If the method lacks a declaration, or the name is taken and ``replace``
            is false.
    """
    instance = method() if isinstance(method, type) else method
    if not isinstance(instance, Integrator):
        raise ModelError(f"register() takes an Integrator (got {type(instance).__name__})")
    for attribute in ("name", "order", "evaluations_per_step", "cost", "reference", "summary"):
        if not hasattr(instance, attribute):
            raise ModelError(
                f"integrator {type(instance).__name__} must declare the class attribute "
                f"`{attribute}`"
            )
    return _REGISTRY.register(instance, replace=replace)


def unregister(name: str) -> None:
    """Remove a registered method (e.g. one a test registered)."""
    _REGISTRY.unregister(name)


def names() -> list[str]:
    """Names of the registered methods, in registration order."""
    return _REGISTRY.names()


def get(method: str | Integrator) -> Integrator:
    """The registered method called ``method`` (an instance is returned as it is).

    Raises:
        ModelError: For an unknown name; the message lists the valid names.
    """
    if isinstance(method, Integrator):
        return method
    if not isinstance(method, str):
        raise ModelError(
            f"`method` must be a method name or an Integrator (got {type(method).__name__})"
        )
    return _REGISTRY.get(method)


for _method in (
    ExplicitEuler,
    Taylor,
    Midpoint,
    Heun,
    RungeKutta4,
    DormandPrince5,
    SymplecticEuler,
    SymplecticEulerPositionFirst,
    VelocityVerlet,
    Leapfrog,
    BackwardEuler,
    Trapezoidal,
    ImplicitMidpoint,
    LinearlyImplicitEuler,
    ProjectedNewton,
    ProjectedTrapezoidal,
    FastMassSprings,
):
    register(_method)
del _method
