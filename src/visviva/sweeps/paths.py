"""Parameter paths: where in a scene a sweep sets its values.

A path is written as in scene error messages: dotted table and field names with list indices in
brackets, ``integration.dt``, ``world.gravity[1]``, ``entities[0].stiffness``. An entity may
also be named instead of counted: ``entities[jelly].stiffness`` (or ``entities["jelly"]``).
:func:`resolve` checks a path against a validated base scene (an unknown field is refused with
the nearest valid path) and returns its keys with names turned into indices; :func:`replaced`
sets a value at those keys in the scene's plain data without touching the original.
"""

from __future__ import annotations

import re
from typing import Any

from pydantic import BaseModel

from .._registry import did_you_mean
from .._validation import describe
from ..entities import entity_kinds
from ..entities.methods import entity_owner, renamed_message

__all__ = ["display", "replaced", "resolve"]

#: One segment: a field name followed by any number of ``[index]`` or ``[name]`` subscripts.
_SEGMENT = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[[^\[\]]*\])*)")
_SUBSCRIPT = re.compile(r"\[([^\[\]]*)\]")


class PathProblem(ValueError):
    """A parameter path that does not lead to a value of the base scene (message says why)."""


def _parse(path: str) -> list[str | int | tuple[str]]:
    """``"entities[jelly].k"`` → ``["entities", ("jelly",), "k"]``: fields as strings, indices
    as ints, entity names as 1-tuples."""
    keys: list[str | int | tuple[str]] = []
    for part in path.split("."):
        match = _SEGMENT.fullmatch(part.strip())
        if match is None:
            raise PathProblem(
                f"{path!r} is not a parameter path; write fields with dots and list items in "
                "brackets, such as entities[0].stiffness or world.gravity[1]"
            )
        keys.append(match.group(1))
        for inner in _SUBSCRIPT.findall(match.group(2)):
            text = inner.strip().strip("\"'")
            keys.append(int(text) if text.isdigit() else (text,))
    return keys


def display(keys: tuple[Any, ...] | list[Any]) -> str:
    """Keys back as a path: ``("entities", 0, "k")`` → ``entities[0].k``."""
    text = ""
    for key in keys:
        if isinstance(key, int):
            text += f"[{key}]"
        elif isinstance(key, tuple):
            text += f"[{key[0]}]"
        else:
            text += f".{key}" if text else key
    return text


def resolve(scene: BaseModel, path: str) -> tuple[str | int, ...]:
    """The keys of ``path`` in ``scene`` (entity names replaced by their indices).

    Args:
        scene: The validated base scene (:class:`~visviva.model.scene.Scene`).
        path: The parameter path as the user wrote it.

    Raises:
        PathProblem: The path names no field of the scene; the message suggests the nearest
            valid path.
    """
    keys = _parse(path)
    node: Any = scene
    done: list[str | int] = []
    for position, key in enumerate(keys):
        last = position == len(keys) - 1
        where = display(done)
        if isinstance(node, BaseModel):
            fields = list(type(node).model_fields)
            if not isinstance(key, str):
                raise PathProblem(f"`{where}` is a table, not a list: name one of its fields")
            kind = str(getattr(node, "type", None))
            kinds = entity_kinds()
            new = kinds.get(kind).renamed.get(key) if kind in kinds else None
            if new is not None:
                owner = entity_owner(kind, getattr(node, "name", None))
                raise PathProblem(
                    f"unknown parameter path `{path}`: {renamed_message(key, new, owner)}"
                )
            if key not in fields:
                prefix = f"{where}." if where else ""
                hint = did_you_mean(prefix + key, [prefix + f for f in fields])
                raise PathProblem(
                    f"unknown parameter path `{path}`: `{where or 'a scene'}` has no field "
                    f"{key!r}.{hint} Valid: {', '.join(fields)}"
                )
            node = getattr(node, key)
        elif isinstance(node, (list, tuple)):
            key = _index(node, key, where)
            node = node[key]
        elif isinstance(node, dict):
            if not isinstance(key, str):
                raise PathProblem(f"`{where}` is a table: name one of its keys")
            if key not in node and not last:
                raise PathProblem(f"`{where}` of the base scene has no key {key!r}")
            node = node.get(key)
        elif node is None:
            raise PathProblem(
                f"`{where}` is not set in the base scene, so `{path}` cannot be set; "
                "give it a value in the scene first"
            )
        else:
            raise PathProblem(f"`{where}` is a value ({describe(node)}), not a table or a list")
        done.append(key)
    return tuple(done)


def _index(items: list[Any] | tuple[Any, ...], key: Any, where: str) -> int:
    """The position ``key`` (an index or an entity's name) picks in ``items``."""
    if isinstance(key, tuple):
        names = [getattr(item, "name", None) for item in items]
        if key[0] in names:
            return names.index(key[0])
        known = [n for n in names if n is not None]
        raise PathProblem(
            f"`{where}` holds no item named {key[0]!r}.{did_you_mean(key[0], known)} "
            f"Named: {', '.join(known) or 'none (use an index such as [0])'}"
        )
    if not isinstance(key, int):
        raise PathProblem(f"`{where}` is a list: pick an item with [index] or [name]")
    if key >= len(items):
        raise PathProblem(
            f"`{where}` has {len(items)} item{'s' if len(items) != 1 else ''}, so index {key} "
            f"does not exist (the first is [0])"
        )
    return key


def replaced(data: Any, keys: tuple[str | int, ...], value: Any) -> Any:
    """``data`` (plain dicts, lists and tuples) with ``value`` at ``keys``; ``data`` is left
    unchanged (only the containers on the path are copied)."""
    if not keys:
        return value
    key, rest = keys[0], keys[1:]
    if isinstance(data, dict):
        copy = dict(data)
        copy[key] = replaced(data.get(key), rest, value)
        return copy
    items = list(data)
    items[key] = replaced(items[key], rest, value)  # type: ignore[index]
    return items
