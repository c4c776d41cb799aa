"""How a ``force`` entity is built: the force of its kind on its targets (every particle by
default), summed after world gravity in scene order."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import ModelError, SceneProblem
from ...forces import (
    Attractor,
    Damping,
    Drag,
    Force,
    Gravitation,
    QuadraticDrag,
    Targets,
    Vortex,
    laws,
)
from ...mechanics.gravity import GRAVITATIONAL_CONSTANT
from ..checks import check_names, particle_holders
from ..context import BuildContext, Located
from ..kind import KindBuild, Replica
from .schema import ForceField

__all__ = ["BUILD"]


def _check(entity: ForceField, where: str, scene: Any) -> list[SceneProblem]:
    """Targets that hold particles; gravitation may not target an emitter's."""
    problems = check_names(entity.targets, where, scene)
    if entity.kind == "gravitation" and entity.targets is not None:
        holders = particle_holders(scene)
        for k, target in enumerate(entity.targets):
            if target in holders and holders[target].type == "emitter":
                problems.append(
                    SceneProblem(
                        f"{where}.targets[{k}]",
                        "gravitation acts among particles that live for the whole run; an "
                        "emitter's particles are born and die (target particles or a "
                        "particle_cloud instead)",
                    )
                )
    return problems


def _build(entity: ForceField, where: str, context: BuildContext) -> None:
    try:
        with np.errstate(all="ignore"):  # overflowing values are judged by the start check
            force = _force(entity, context.targets(entity.targets), context.arrays["mass"])
    except ModelError as error:
        raise Located(where, str(error)) from None
    context.forces.append(force)


def _force(e: ForceField, targets: Targets, mass: np.ndarray) -> Force:
    zero = (0.0, 0.0, 0.0)
    if e.kind in ("drag", "wind"):
        return Drag(e.coefficient, mass, targets, air_velocity=e.velocity or zero)  # type: ignore[arg-type]
    if e.kind == "quadratic_drag":
        return QuadraticDrag(e.coefficient, mass, targets, air_velocity=e.velocity or zero)  # type: ignore[arg-type]
    if e.kind == "damping":
        return Damping(e.rate, mass, targets)  # type: ignore[arg-type]
    if e.kind == "attractor":
        softening = 0.1 if e.softening is None else e.softening
        return Attractor(e.point, e.strength, mass, targets, softening=softening)  # type: ignore[arg-type]
    if e.kind == "vortex":
        return Vortex(
            e.point or zero,
            e.axis or (0.0, 1.0, 0.0),
            e.circulation,  # type: ignore[arg-type]
            e.coefficient,  # type: ignore[arg-type]
            mass,
            targets,
            core_radius=0.5 if e.core_radius is None else e.core_radius,
        )
    return Gravitation(
        mass,
        targets,
        G=GRAVITATIONAL_CONSTANT if e.G is None else e.G,
        softening=e.softening or 0.0,
        method=e.method or "direct",
        theta=0.5 if e.theta is None else e.theta,
    )


#: The law of each field kind (:mod:`visviva.forces.laws`).
_LAWS = {
    "drag": laws.DRAG,
    "wind": laws.DRAG,
    "quadratic_drag": laws.QUADRATIC_DRAG,
    "damping": laws.DAMPING,
    "attractor": laws.ATTRACTOR,
    "vortex": laws.VORTEX,
}


def _replica(entity: ForceField) -> Replica | None:
    """Copied per run where its values differ; gravitation couples particles: no replicas."""
    if entity.kind == "gravitation":
        return None
    # The compiled particle step folds some laws into one acceleration (laws.FOLDED).
    return Replica(room="law", folds=_LAWS[entity.kind] in laws.FOLDED)


BUILD = KindBuild(check=_check, build=_build, replica=_replica)
