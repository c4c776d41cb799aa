"""The Python way to write a scene: ``vv.SceneBuilder`` → ``build()`` → frozen Model.

The builder holds the same validated scene description a file would
(:mod:`visviva.model.scene`), so a scene built in Python and the same scene read from TOML give
the same Model, and ``vv.io.dump_scene(builder.scene)`` writes the file that reproduces it.
Each entity kind has its typed method (``add_cloth``, ``add_collider``, ...: every field of the
kind's table a keyword, :mod:`visviva.entities.methods`); ``add(type, **fields)`` adds an
entity of any kind, a plugin's too, whose ``add_<type>`` is also offered (with its schema's
fields as its signature). Each add validates its entity at once (an argument left at ``None``
takes the scene file's default) and returns the entity's index in the scene.

Every deformable body's ``pinned`` points stay where they are, unless its ``handle`` — a
:class:`~visviva.entities.Handle` or a dict of its fields, as in a scene file's
``[entities.handle]`` table — moves them (:mod:`visviva.particles.handles`)::

    builder.add_hair(points, mass=5e-4, stiffness=200.0, bending=20.0,
                     handle={"pivot": (0, 1.5, 0), "angular_velocity": 1.6,
                             "start": 1.0, "stop": 2.0, "ramp": 0.25})
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable, Sequence
from typing import Any

from pydantic import ValidationError

from .._registry import did_you_mean
from ..entities import BUILT_IN, EntityMethods, entity_kinds
from ..entities.methods import given
from ..errors import SceneError, SceneProblem
from .build import build_model
from .model import Model
from .scene import Integration, Output, Scene, World
from .scene_errors import scene_problems

__all__ = ["SceneBuilder"]

Vector = Sequence[float]
#: The built-in kinds, whose methods the builder has (each kind's ``*Methods``).
BUILT_IN_KINDS = frozenset(kind.name for kind in BUILT_IN)


class SceneBuilder(EntityMethods):
    """Builds a scene step by step.

    Args:
        name: Scene name.
        description: What the scene shows.

    Example:
        >>> import visviva as vv
        >>> builder = vv.SceneBuilder(name="drop")
        >>> builder.set_integration(method="symplectic_euler", dt=0.01, duration=1.0)
        >>> builder.add_particles([[0.0, 2.0, 0.0]], mass=0.5, name="ball")
        0
        >>> builder.add_force("drag", coefficient=0.1, targets=["ball"])
        1
        >>> builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), restitution=0.8)
        2
        >>> model = builder.build()
        >>> model.particle_count, float(model.particle_mass[0]), len(model.forces)
        (1, 0.5, 2)
    """

    def __init__(self, *, name: str = "untitled", description: str = "") -> None:
        self._scene = _validated(Scene, "scene", scene={"name": name, "description": description})

    @classmethod
    def from_scene(cls, scene: Scene) -> SceneBuilder:
        """A builder holding an already validated scene (for example one read from a file)."""
        builder = cls()
        builder._scene = scene
        return builder

    @property
    def scene(self) -> Scene:
        """The validated scene description so far."""
        return self._scene

    @property
    def entity_count(self) -> int:
        """Entities in the scene so far."""
        return len(self._scene.entities)

    def set_world(self, *, gravity: Vector = (0.0, -9.81, 0.0)) -> None:
        """Set the gravitational acceleration [m/s²] (Y up) acting on every particle."""
        self._replace(world=_validated(World, "world", gravity=gravity))

    def set_integration(
        self,
        *,
        method: str | None = None,
        dt: float | None = None,
        duration: float | None = None,
        substeps: int | None = None,
        record_every: int | None = None,
        energy_tolerance: float | None = None,
    ) -> None:
        """Set the integrator ``method``, the step ``dt`` [s], the ``duration`` [s], the
        ``substeps`` per step, ``record_every`` k-th step, and the ``energy_tolerance``."""
        self._replace(integration=_validated(Integration, "integration", **given(locals())))

    def set_output(
        self,
        *,
        formats: Sequence[str] | None = None,
        fps: float | None = None,
        speed: float | None = None,
        trail: float | None = None,
        color_by: str | None = None,
    ) -> None:
        """Set the extra output ``formats`` of ``visviva run``, their ``fps``, ``speed``
        (simulated seconds per second of playback), ``trail`` [s] and ``color_by``
        (``"scene"`` or ``"speed"``)."""
        self._replace(output=_validated(Output, "output", **given(locals())))

    def add(self, type: str, /, **fields: Any) -> int:
        """Add an entity of the kind ``type`` (any registered kind: ``vv.entities``) with the
        fields of its table; returns its index in the scene.

        Raises:
            SceneError: For an unknown kind (with the closest one) or fields its table refuses,
                located at the entity (``entities[3].stiffness``).
        """
        kinds = entity_kinds()
        index = len(self._scene.entities)
        where = f"entities[{index}]"
        if type not in kinds:
            message = (
                f"unknown entity type {type!r}.{did_you_mean(type, kinds)} Valid types: "
                f"{', '.join(kinds)}"
            )
            raise SceneError([SceneProblem(f"{where}.type", message)])
        kind = kinds.get(type)
        entity = _validated(kind.schema, where, **(given(fields) | {"type": type}))
        if kind.hooks.prepare is not None:
            entity = kind.hooks.prepare(entity, where)
        self._replace(entities=[*self._scene.entities, entity])
        return index

    def build(self) -> Model:
        """Check the scene as a whole and return the frozen :class:`Model`."""
        return build_model(self._scene)

    def __getattr__(self, name: str) -> Any:
        """``add_<type>`` of a kind without a method of its own (a plugin's): :meth:`add` for
        that kind, with its schema's fields as its signature."""
        if name.startswith("add_") and name[4:] in entity_kinds():  # a built-in's is a method
            return _plugin_method(self, name[4:])
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def __dir__(self) -> list[str]:
        plugins = [f"add_{kind}" for kind in entity_kinds() if kind not in BUILT_IN_KINDS]
        return sorted({*super().__dir__(), *plugins})

    def _replace(self, **parts: Any) -> None:
        self._scene = self._scene.model_copy(update=parts)


def _plugin_method(builder: SceneBuilder, kind: str) -> Callable[..., int]:
    """``builder.add(kind, ...)`` as a method whose signature is the kind's fields."""
    schema = entity_kinds().get(kind).schema
    parameters = [
        inspect.Parameter(
            name,
            inspect.Parameter.KEYWORD_ONLY,
            default=inspect.Parameter.empty if field.is_required() else None,
            annotation=field.annotation,
        )
        for name, field in schema.model_fields.items()
        if name != "type"
    ]

    @functools.wraps(builder.add)
    def add(**fields: Any) -> int:
        return builder.add(kind, **fields)

    add.__name__ = f"add_{kind}"
    add.__doc__ = schema.__doc__
    add.__signature__ = inspect.Signature(parameters, return_annotation=int)  # type: ignore[attr-defined]
    return add


def _validated(schema: type[Any], where: str, /, **fields: Any) -> Any:
    """``schema(**fields)`` validated, with problems reported at ``where`` like a file's."""
    try:
        return schema.model_validate(fields)
    except ValidationError as exc:
        problems = scene_problems(exc, fields, lambda path: None, schema)
        for i, problem in enumerate(problems):
            path = f"{where}.{problem.path}" if problem.path else where
            problems[i] = type(problem)(path, problem.message, problem.got)
        raise SceneError(problems) from None
