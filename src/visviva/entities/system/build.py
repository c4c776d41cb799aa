"""How a ``system`` entity is built: its named system's problem for its parameters (defaults
filled in), its coordinates after the previous systems' in the generalized-coordinates block."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..._registry import did_you_mean
from ...errors import ModelError, SceneProblem
from ..context import BuildContext, Located
from ..kind import KindBuild
from ..methods import renamed_message
from .block import SystemInstance
from .schema import RENAMED_PARAMETERS, System
from .systems import SYSTEMS

__all__ = ["BUILD", "OVERFLOW", "located_parameter"]

OVERFLOW = (
    "these values overflow a float while the system is set up (the largest float is 1.8e308): "
    "use smaller values or other units"
)


def located_parameter(message: str, where: str, values: Mapping[str, float]) -> SceneProblem:
    """A system's own refusal, at the parameter its message names ("`eccentricity` must ...");
    the gravity a system takes from the world ("`g` must ...") is the world's."""
    if message.startswith("`") and message.count("`") >= 2:
        name, rest = message[1:].split("`", 1)
        if name == "g":
            return SceneProblem(
                "world.gravity", "this system moves under gravity: it must not be zero"
            )
        if name in values:
            return SceneProblem(f"{where}.{name}", rest.strip())
    return SceneProblem(where, message)


def _check(entity: System, where: str, scene: Any) -> list[SceneProblem]:
    return _check_parameters(entity, where) + _check_alone(entity, where, scene)


def _check_parameters(entity: System, where: str) -> list[SceneProblem]:
    kind = SYSTEMS[entity.system]
    renamed: Mapping[str, str] = RENAMED_PARAMETERS.get(entity.system, {})
    problems = []
    for key, value in entity.parameters.items():
        path = f"{where}.parameters.{key}"
        if key in renamed:
            problems.append(
                SceneProblem(
                    path,
                    renamed_message(key, renamed[key], f"the {entity.system} system", "parameter"),
                )
            )
            continue
        if key not in kind.parameters:
            problems.append(
                SceneProblem(
                    path,
                    f"{entity.system} has no parameter {key!r}.{did_you_mean(key, kind.parameters)}"
                    f" Parameters: {', '.join(kind.parameters)}",
                )
            )
            continue
        parameter = kind.parameters[key]
        if parameter.positive and value <= 0:
            problems.append(SceneProblem(path, f"must be positive [{parameter.unit}]", repr(value)))
        if parameter.integer and value != int(value):
            problems.append(SceneProblem(path, "must be a whole number", repr(value)))
        if parameter.minimum is not None and value < parameter.minimum:
            problems.append(
                SceneProblem(path, f"must be at least {parameter.minimum:g}", repr(value))
            )
        if parameter.maximum is not None and value > parameter.maximum:
            problems.append(
                SceneProblem(path, f"must be at most {parameter.maximum:g}", repr(value))
            )
    return problems


def _check_alone(entity: System, where: str, scene: Any) -> list[SceneProblem]:
    """A first-order system (Dahlquist's test equation) has no positions to mix with others."""
    if entity.system != "test-equation":
        return []
    from .. import entity_kinds

    kinds = entity_kinds()
    moving = [e for e in scene.entities if kinds.get(e.type).holds_particles or e.type == "system"]
    if len(moving) == 1:
        return []
    return [
        SceneProblem(
            where,
            "the test equation is a first-order system without positions: put it in a scene "
            "of its own",
        )
    ]


def _build(entity: System, where: str, context: BuildContext) -> None:
    kind = SYSTEMS[entity.system]
    values = {k: p.default for k, p in kind.parameters.items()} | dict(entity.parameters)
    at = f"{where}.parameters"
    try:
        with np.errstate(all="ignore"):  # overflow is judged by the start check
            problem = kind.build(values, context.gravity)
    except ModelError as error:
        located = located_parameter(str(error), at, values)
        raise Located(located.path, located.message) from None
    except (OverflowError, ZeroDivisionError, FloatingPointError, ValueError):
        raise Located(at, OVERFLOW) from None
    offset = sum(s.size for s in context.systems)
    index = context.index(where)
    name = context.names[index]
    context.systems.append(SystemInstance(name, entity.system, values, index, offset, problem))


BUILD = KindBuild(check=_check, build=_build)
