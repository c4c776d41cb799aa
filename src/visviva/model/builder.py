"""The Python way to write a scene: ``vv.SceneBuilder`` → ``build()`` → frozen Model.

The builder holds the same validated scene a file would (:mod:`visviva.io.scene_schema`), so a
scene built in Python and the same scene read from TOML give the same Model, and
:meth:`SceneBuilder.dump` writes the file that reproduces it. Each ``add_*`` validates its
entity at once and returns the entity's id (its index in the scene).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from pydantic import BaseModel, ValidationError

from ..errors import SceneError
from ..io.scene_files import _problems, dump_scene
from ..io.scene_schema import (
    Integration,
    Output,
    ParticleCloud,
    Particles,
    Scene,
    System,
    World,
)
from .build import build_model
from .model import Model

__all__ = ["SceneBuilder"]


class SceneBuilder:
    """Builds a scene step by step.

    Args:
        name: Scene name.
        description: What the scene shows.

    Example:
        >>> import visviva as vv
        >>> builder = vv.SceneBuilder(name="drop")
        >>> builder.set_integration(method="symplectic_euler", dt=0.01, duration=1.0)
        >>> builder.add_particles(positions=[[0.0, 2.0, 0.0]], mass=0.5, name="ball")
        0
        >>> model = builder.build()
        >>> model.particle_count, float(model.particle_mass[0])
        (1, 0.5)
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
        """The validated scene so far."""
        return self._scene

    def set_world(self, *, gravity: Sequence[float] = (0.0, -9.81, 0.0)) -> None:
        """Set the gravitational acceleration [m/s²] (Y up)."""
        self._replace(world=_validated(World, "world", gravity=gravity))

    def set_integration(self, **settings: Any) -> None:
        """Set ``method``, ``dt`` [s], ``duration`` [s], ``substeps``, ``record_every``."""
        self._replace(integration=_validated(Integration, "integration", **settings))

    def set_output(self, **settings: Any) -> None:
        """Set the extra output ``formats`` of ``visviva run``, their ``fps`` and ``speed``
        (simulated seconds per second of playback)."""
        self._replace(output=_validated(Output, "output", **settings))

    def add_particles(self, **fields: Any) -> int:
        """Add particles at ``positions`` [m] with optional ``velocities`` [m/s], ``mass`` [kg],
        ``radius`` [m] and ``name``; returns the entity id."""
        return self._add(Particles, fields | {"type": "particles"})

    def add_particle_cloud(self, **fields: Any) -> int:
        """Add ``count`` particles at random in a box (``center``, ``size`` [m], ``velocity``,
        ``velocity_jitter`` [m/s], ``mass``, ``radius``, ``seed``); returns the entity id."""
        return self._add(ParticleCloud, fields | {"type": "particle_cloud"})

    def add_system(self, system: str, *, name: str | None = None, **parameters: float) -> int:
        """Add a named system (``visviva schema`` lists them: ``pendulum``, ``kepler``, ...)
        with parameter values; returns the entity id."""
        fields = {"type": "system", "system": system, "name": name, "parameters": parameters}
        return self._add(System, fields)

    def build(self) -> Model:
        """Check the scene as a whole and return the frozen :class:`Model`."""
        return build_model(self._scene, source=self.dump())

    def dump(self, format: str = "toml") -> str:
        """The scene as file text (``"toml"`` or ``"json"``)."""
        return dump_scene(self._scene, format)

    def _add(self, kind: type[BaseModel], fields: dict[str, Any]) -> int:
        index = len(self._scene.entities)
        entity = _validated(kind, f"entities[{index}]", **fields)
        self._replace(entities=[*self._scene.entities, entity])
        return index

    def _replace(self, **parts: Any) -> None:
        self._scene = self._scene.model_copy(update=parts)


def _validated(kind: type[Any], where: str, **fields: Any) -> Any:
    """``kind(**fields)`` validated, with problems reported at ``where`` like a file's."""
    try:
        return kind.model_validate(fields)
    except ValidationError as exc:
        problems = _problems(exc, fields, lambda path: None)
        for i, problem in enumerate(problems):
            path = f"{where}.{problem.path}" if problem.path else where
            problems[i] = type(problem)(path, problem.message, problem.got)
        raise SceneError(problems) from None
