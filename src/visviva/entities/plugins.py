"""Entity kinds from other packages: the ``visviva.entities``, ``visviva.forces`` and
``visviva.stages`` entry points.

A package adds kinds by naming them in its metadata::

    [project.entry-points."visviva.forces"]
    magnetic_field = "visviva_magnetic:KIND"

The entry point's object is an :class:`~.kind.EntityKind` (or a list of them): any kind under
``visviva.entities``, a kind made by :func:`~.contributions.force_kind` (one force per entity)
under ``visviva.forces``, one made by :func:`~.contributions.stage_kind` under
``visviva.stages`` (their classes are checked when they are made). They are loaded
the first time a scene is read or built, checked like the built-in kinds are
(:func:`kind_problem`) and registered after them; from then on scene files, the builder
(``builder.add("magnet", ...)`` and ``builder.add_magnet(...)``), the build and the recordings
treat them as their own. A plugin that fails to import, or whose kind is refused (a name that
clashes with a kind already registered, a schema without its ``type``), is left out with a
:class:`PluginWarning` that names the plugin and what to fix; every other kind keeps working.
``docs/extending.md`` walks through writing one.
"""

from __future__ import annotations

import re
import typing
import warnings
from importlib.metadata import EntryPoint, entry_points

from pydantic import BaseModel

from .._registry import Registry
from ..errors import ModelError
from .kind import EntityKind

__all__ = ["GROUPS", "PluginWarning", "kind_problem", "load_plugins", "register_entity_kind"]

#: The entry-point groups of entity kinds: any kind, a force's, a stage's.
GROUPS = ("visviva.entities", "visviva.forces", "visviva.stages")
#: What a kind's name may be: its builder method is ``add_<name>``.
_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


class PluginWarning(UserWarning):
    """A plugin was left out; the message names it and what to fix."""


def kind_problem(kind: object, registry: Registry[EntityKind]) -> str | None:
    """Why ``kind`` cannot be registered in ``registry``, or ``None`` if it can."""
    if not isinstance(kind, EntityKind):
        return f"it gives a {type(kind).__name__}, not a visviva.entities.EntityKind"
    if not _NAME.match(kind.name):
        return (
            f"its kind's name {kind.name!r} must be lower-case letters, digits and underscores, "
            "starting with a letter (it names the builder's add_<name> method)"
        )
    if kind.name in registry:
        return (
            f"its kind {kind.name!r} clashes with a kind already registered "
            f"({registry.get(kind.name).build}): give it another name"
        )
    schema = kind.schema
    if not (isinstance(schema, type) and issubclass(schema, BaseModel)):
        return f"the schema of kind {kind.name!r} must be a pydantic model class"
    tag = schema.model_fields.get("type")
    if tag is None or typing.get_args(tag.annotation) != (kind.name,):
        return (
            f"the schema {schema.__name__} of kind {kind.name!r} must have the field "
            f'`type: Literal["{kind.name}"]`, the tag scene files give'
        )
    name = schema.model_fields.get("name")
    if name is None or name.is_required():
        return (
            f"the schema {schema.__name__} of kind {kind.name!r} must have the field "
            "`name: str | None = None`, the name other entities and messages call it by"
        )
    return None


def register_entity_kind(kind: EntityKind, registry: Registry[EntityKind]) -> EntityKind:
    """Register ``kind`` in ``registry`` (checked as a plugin's is).

    Raises:
        ModelError: Saying why the kind is refused.
    """
    problem = kind_problem(kind, registry)
    if problem is not None:
        raise ModelError(f"entity kind refused: {problem}")
    return registry.register(kind)


def load_plugins(registry: Registry[EntityKind]) -> None:
    """Register the kinds of every installed entry point of :data:`GROUPS` in ``registry``; a
    plugin refused is left out with a :class:`PluginWarning`."""
    points = [point for group in GROUPS for point in entry_points(group=group)]
    for point in points:
        try:
            loaded = point.load()
        except ModelError as error:  # force_kind or stage_kind refused its class
            _refuse(point, str(error))
            continue
        except Exception as error:  # a plugin's bug must not take the built-in kinds down
            _refuse(point, f"it failed to import ({type(error).__name__}: {error})")
            continue
        for kind in loaded if isinstance(loaded, (list, tuple)) else [loaded]:
            problem = kind_problem(kind, registry)
            if problem is None:
                registry.register(kind)
            else:
                _refuse(point, problem)


def _refuse(point: EntryPoint, problem: str) -> None:
    package = point.dist.name if point.dist is not None else point.value.split(":")[0]
    warnings.warn(
        PluginWarning(
            f"visviva plugin {point.name!r} ({point.value}, from the package {package!r}) was "
            f"left out: {problem}. The other kinds work; fix the plugin or uninstall its package."
        ),
        stacklevel=3,
    )
