"""Validation problems of a scene, as the user wrote it: one per field, with did-you-mean.

Pydantic reports a problem at a location such as ``("entities", 3, "mass")`` and once per
branch of a union; :func:`scene_problems` turns that into one
:class:`~visviva.errors.SceneProblem` per field at the path the user wrote
(``entities[3].mass``), names the allowed keys of a misspelt one, names the new name of a
renamed one (each kind's :attr:`~visviva.entities.EntityKind.renamed`), and leaves the line
number to the caller that has the file (``line_of``).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any, get_args

from pydantic import BaseModel, ValidationError

from .._registry import did_you_mean
from .._validation import describe
from ..entities import entity_kinds
from ..entities.methods import entity_owner, renamed_message
from ..errors import SceneProblem
from .scene import Integration, Output, Scene, SceneInfo, World

__all__ = ["scene_problems"]

#: Names pydantic gives the branches of a union in error locations (never scene keys).
_UNION_BRANCH = re.compile(r"^(float|int|str|bool|list|tuple|dict|[a-z]+(-[a-z]+)+)$|\[")
_TABLES: dict[str, type[BaseModel]] = {
    "scene": SceneInfo,
    "world": World,
    "integration": Integration,
    "output": Output,
}


def scene_problems(
    exc: ValidationError,
    raw: dict[str, Any],
    line_of: Callable[[tuple[Any, ...]], Any],
    schema: type[BaseModel] | None = None,
) -> list[SceneProblem]:
    """One problem per field: pydantic reports each branch of a union; keep the telling one.
    ``raw`` is the data validated: a whole scene, or one table of ``schema`` (an entity)."""
    chosen: dict[tuple[Any, ...], Any] = {}
    for error in exc.errors(include_url=False):
        path = _field_path(error["loc"])
        previous = chosen.get(path)
        if previous is None or (
            previous["type"].endswith("_type") and not error["type"].endswith("_type")
        ):
            chosen[path] = error
    renamed = {path: new for path in chosen if (new := _new_name(path, raw, schema)) is not None}
    replaced = {(*path[:-1], new) for path, new in renamed.items()}
    problems = []
    for path, error in chosen.items():
        if error["type"] == "missing" and path in replaced:
            continue  # its old name was given: the rename says it all
        message = error["msg"].replace("Input should be", "must be", 1)
        got: str | None = describe(error["input"])
        if isinstance(error["input"], dict):
            got = None  # a rule of the whole entity (its message names the fields)
            field = error.get("ctx", {}).get("field")
            if error["type"] == "not_a_parameter" and field:
                path = (*path, field)
        if path in renamed:
            table = _entity_table(path[:-1], raw, schema) or {}
            owner = entity_owner(str(table.get("type")), table.get("name"))
            message, got = renamed_message(str(path[-1]), renamed[path], owner), None
        elif error["type"] == "extra_forbidden":
            key = str(path[-1])
            allowed = _allowed_keys(path[:-1], raw, schema)
            message = f"unknown key.{did_you_mean(key, allowed)} Allowed: {', '.join(allowed)}"
            got = None
        elif error["type"] == "missing":
            got = None
        elif error["type"] == "union_tag_invalid":
            tag = error["input"].get("type") if isinstance(error["input"], dict) else None
            hint = did_you_mean(tag, entity_kinds()) if isinstance(tag, str) else ""
            message = f"unknown entity type.{hint} Valid types: {', '.join(entity_kinds())}"
            got = describe(tag)
        elif error["type"] == "finite_number":
            message = "must be a finite number (numbers beyond ±1.8e308 overflow to inf)"
        problems.append(SceneProblem(_dotted(path), message, got, line_of(path)))
    return problems


def _field_path(loc: tuple[Any, ...]) -> tuple[Any, ...]:
    """The error's location as the user wrote it: no union-branch or entity-tag segments."""
    path: list[Any] = []
    for segment in loc:
        if isinstance(segment, str) and _UNION_BRANCH.search(segment):
            continue  # a union branch name such as "constrained-float", not a key
        path.append(segment)
    return tuple(path)


def _entity_table(
    path: tuple[Any, ...], raw: dict[str, Any], schema: type[BaseModel] | None
) -> dict[str, Any] | None:
    """The entity table at ``path`` of ``raw`` (a scene, or with ``schema`` the entity itself
    at ``()``), or ``None`` if ``path`` is not an entity's."""
    if schema is not None:
        return raw if not path else None
    if len(path) != 2 or path[0] != "entities" or not isinstance(path[1], int):
        return None
    entities = raw.get("entities")
    entity = entities[path[1]] if isinstance(entities, list) else None
    return entity if isinstance(entity, dict) else None


def _new_name(
    path: tuple[Any, ...], raw: dict[str, Any], schema: type[BaseModel] | None
) -> str | None:
    """The field's new name if ``path`` is a field of an entity given by its old name."""
    if not path:
        return None
    table = _entity_table(path[:-1], raw, schema)
    if table is None or path[-1] not in table:
        return None
    kinds = entity_kinds()
    kind = str(table.get("type"))
    return kinds.get(kind).renamed.get(str(path[-1])) if kind in kinds else None


def _allowed_keys(
    path: tuple[Any, ...], raw: dict[str, Any], schema: type[BaseModel] | None = None
) -> list[str]:
    """The keys allowed in the table at ``path`` of ``raw`` (a scene, or a table of
    ``schema``)."""
    model, rest = schema, path
    if schema is None and path and path[0] != "entities":
        model, rest = _TABLES.get(str(path[0])), path[1:]
    elif schema is None and len(path) >= 2:
        entities = raw.get("entities")
        entity = entities[path[1]] if isinstance(entities, list) else None
        kind = entity.get("type") if isinstance(entity, dict) else None
        model = entity_kinds().get(kind).schema if kind in entity_kinds() else None
        rest = path[2:]
    elif schema is None:
        model = None if path else Scene
    for key in rest:  # a table inside the entity (a body's `handle`), or a sweep's list
        if not isinstance(key, int):  # an item of a list of tables has the list's schema
            model = _table_of(model, key)
    return list(model.model_fields) if model is not None else []


def _table_of(model: type[BaseModel] | None, key: Any) -> type[BaseModel] | None:
    """The schema of the table at ``key`` of ``model`` (``None`` if it is not a table)."""
    field = None if model is None else model.model_fields.get(str(key))
    if field is None:
        return None
    for kind in (field.annotation, *get_args(field.annotation)):
        if isinstance(kind, type) and issubclass(kind, BaseModel):
            return kind
    return None


def _dotted(path: tuple[Any, ...]) -> str:
    text = ""
    for segment in path:
        text += f"[{segment}]" if isinstance(segment, int) else f".{segment}" if text else segment
    return text
