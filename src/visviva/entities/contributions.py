"""Kinds made of one Force or one Stage: what most plugins are.

A package that adds a force law (a magnetic field on charged particles) or a behaviour (a
stage that steers particles) writes the class, the table of its parameters, and a function that
makes the class from an entity; :func:`force_kind` and :func:`stage_kind` make the
:class:`~.kind.EntityKind` that puts one into a model for each entity of the kind::

    KIND = force_kind("magnetic_field", MagneticFieldTable, MagneticForce, make, summary="...")

The class is checked when the kind is made — it must declare what the pipeline reads of it
(:class:`~visviva.forces.Force`: ``conservative``, ``velocity_dependent``, ``linear_damping``,
``compiled`` and its methods; :class:`~visviva.ode.stage.Stage`: ``phase``, ``order``, ``compiled``,
``changes_energy``, ``kills_particles`` and its methods) — so a plugin that would give wrong
answers is refused with what to fix (a force that claims to be conservative must report its
potential energy: a change in the energy of a conservative scene measures the integrator's
error).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from pydantic import BaseModel

from ..errors import ModelError, SceneProblem
from ..ode.stage import Phase
from .checks import check_names
from .context import BuildContext, Located
from .kind import EntityKind, KindBuild

__all__ = ["force_kind", "force_problem", "stage_kind", "stage_problem"]

#: The methods a force on particles has (visviva.forces.Force).
_FORCE_METHODS = ("accumulate", "jacobian_blocks", "add_jacobian")
#: The methods a stage has (visviva.ode.stage.Stage).
_STAGE_METHODS = ("carried_start", "apply")


def force_problem(force: type) -> str | None:
    """What the force class ``force`` lacks for the pipeline, or ``None``."""
    name = getattr(force, "__name__", repr(force))
    if not isinstance(force, type):
        return f"{name} must be a class (a Force)"
    for attribute in ("conservative", "velocity_dependent", "linear_damping"):
        if not isinstance(getattr(force, attribute, None), (bool, property)):
            return (
                f"{name} must declare `{attribute}` (True or False) as a class attribute: the "
                "pipeline reads it (visviva.forces.Force)"
            )
    for method in _FORCE_METHODS:
        if not callable(getattr(force, method, None)):
            return f"{name} must define `{method}` (visviva.forces.Force)"
    if not hasattr(force, "compiled"):
        return (
            f"{name} must declare `compiled = None` (it has no compiled form the fused particle "
            "step could take: a scene with it takes the generic road)"
        )
    if not callable(getattr(force, "potential", None)):
        if getattr(force, "conservative", None) is True:
            return (
                f"{name} claims to be conservative but reports no energy: define "
                "`potential(t, x, alive=None)` returning U [J], or set conservative = False"
            )
        return (
            f"{name} must define `potential(t, x, alive=None)` (return 0.0 for a force "
            "without potential energy)"
        )
    return None


def stage_problem(stage: type) -> str | None:
    """What the stage class ``stage`` lacks for the pipeline, or ``None``."""
    name = getattr(stage, "__name__", repr(stage))
    if not isinstance(stage, type):
        return f"{name} must be a class (a Stage)"
    if not isinstance(getattr(stage, "phase", None), Phase):
        return (
            f"{name} must declare `phase`, a visviva.ode.stage.Phase (BEHAVIOURS, CONSTRAINTS, "
            "CONTACTS or EMISSION): when in a step it runs"
        )
    if not isinstance(getattr(stage, "order", None), int):
        return f"{name} must declare `order`, an int: its place among the stages of its phase"
    for attribute in ("changes_energy", "kills_particles"):
        if not isinstance(getattr(stage, attribute, None), bool):
            return f"{name} must declare `{attribute}` (True or False) as a class attribute"
    if getattr(stage, "compiled", None) is not False:
        return (
            f"{name} must declare compiled = False: the fused steps know only visviva's own "
            "stages, and take the generic road for a scene with any other"
        )
    for method in _STAGE_METHODS:
        if not callable(getattr(stage, method, None)):
            return f"{name} must define `{method}` (visviva.ode.stage.Stage)"
    return None


def force_kind(
    name: str,
    schema: type[BaseModel],
    force: type,
    make: Callable[[Any, BuildContext], Any],
    *,
    summary: str,
    holds_particles: bool = False,
) -> EntityKind:
    """The kind whose entities each add the force ``make(entity, context)`` (an instance of
    ``force``) on particles, summed after world gravity in scene order. A ``targets`` field of
    the schema, if it has one, must name entities that hold particles
    (``context.targets(entity.targets)`` gives their indices).

    Raises:
        ModelError: If ``force`` lacks what the pipeline needs of a force.
    """
    return _contributing(
        name, schema, force, make, force_problem(force), lambda context: context.forces,
        summary=summary, holds_particles=holds_particles,
    )  # fmt: skip


def stage_kind(
    name: str,
    schema: type[BaseModel],
    stage: type,
    make: Callable[[Any, BuildContext], Any],
    *,
    summary: str,
) -> EntityKind:
    """The kind whose entities each add the stage ``make(entity, context)`` (an instance of
    ``stage``), run in its phase after every step.

    Raises:
        ModelError: If ``stage`` lacks what the pipeline needs of a stage.
    """
    return _contributing(
        name, schema, stage, make, stage_problem(stage), lambda context: context.stages,
        summary=summary,
    )  # fmt: skip


def _contributing(
    name: str,
    schema: type[BaseModel],
    kind: type,
    make: Callable[[Any, BuildContext], Any],
    problem: str | None,
    contributions: Callable[[BuildContext], list[Any]],
    *,
    summary: str,
    holds_particles: bool = False,
) -> EntityKind:
    """The kind whose entities each add ``make(entity, context)``, an instance of ``kind``, to
    the list ``contributions(context)`` (the forces or the stages); ``problem`` is what
    ``kind`` lacks of the contract, or ``None``."""
    if problem is not None:
        raise ModelError(problem)

    def build(entity: Any, where: str, context: BuildContext) -> None:
        try:
            made = make(entity, context)
        except ModelError as error:
            raise Located(where, str(error)) from None
        if not isinstance(made, kind):
            raise Located(where, f"the {name} kind made a {type(made).__name__}, not a {kind}")
        contributions(context).append(made)

    return EntityKind(
        name=name,
        schema=schema,
        summary=summary,
        build=KindBuild(check=_targets_exist, build=build),
        holds_particles=holds_particles,
    )


def _targets_exist(entity: Any, where: str, scene: Any) -> list[SceneProblem]:
    targets = entity.targets if "targets" in type(entity).model_fields else None
    return check_names(targets, where, scene)
