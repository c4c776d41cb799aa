"""The builder's typed ``add_*`` methods, one per entity kind, beside each kind's schema.

Each kind's ``schema.py`` holds a small class of its builder method (``ClothMethods.add_cloth``)
with one keyword per field of its table, typed, so that editors and type checkers know every
field; :class:`visviva.model.SceneBuilder` inherits them all, and ``tests/test_entities.py``
checks that every method's keywords are its schema's fields. An argument left at ``None``
takes the table's default. The method hands what was given to the builder's generic
``add(type, **fields)``, which validates it as a scene file's table is validated.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Concatenate, ParamSpec, Protocol

from pydantic import BaseModel

from ..errors import SceneError, SceneProblem

__all__ = ["Builds", "Triple", "given", "refusing_renamed", "renamed_message"]

#: A point or vector given to a builder method: any three numbers [unit of the field].
Triple = Sequence[float]

P = ParamSpec("P")


class Builds(Protocol):
    """What the kinds' methods need of the builder."""

    def add(self, type: str, /, **fields: Any) -> int:
        """Add an entity of kind ``type`` with ``fields``; its index in the scene."""
        ...

    @property
    def entity_count(self) -> int:
        """Entities in the scene so far."""
        ...


def given(arguments: dict[str, Any]) -> dict[str, Any]:
    """The arguments the caller gave (not ``None``), as plain Python values (NumPy arrays and
    scalars become lists and floats, which the strict schemas accept)."""
    return {
        key: _plain(value)
        for key, value in arguments.items()
        if key != "self" and value is not None
    }


def _plain(value: Any) -> Any:
    import numpy as np  # here: reading the kinds' tables (`visviva schema`) needs no NumPy

    if isinstance(value, BaseModel):  # a table given as its schema (a Handle): validated again
        return _plain(value.model_dump(exclude_none=True))
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    return value


def renamed_message(old: str, new: str, owner: str, what: str = "field") -> str:
    """``field "bend" of cloth "sheet" was renamed; did you mean "bending"?``."""
    return f'{what} "{old}" of {owner} was renamed; did you mean "{new}"?'


def entity_owner(kind: str, name: Any = None) -> str:
    """An entity of type ``kind`` in a message: ``cloth "sheet"`` if it is called ``name``,
    else ``the cloth entity``."""
    return f'{kind} "{name}"' if isinstance(name, str) else f"the {kind} entity"


def refusing_renamed(
    kind: str, renamed: Mapping[str, str]
) -> Callable[[Callable[Concatenate[Any, P], int]], Callable[Concatenate[Any, P], int]]:
    """The ``add_*`` method of ``kind``, refusing the field names it gave up (``renamed``:
    old → new) with a :class:`~visviva.errors.SceneError` that names the new one, where Python
    would only say "unexpected keyword argument". The method keeps its signature."""

    def decorate(method: Callable[Concatenate[Any, P], int]) -> Callable[Concatenate[Any, P], int]:
        @functools.wraps(method)
        def checked(self: Any, /, *args: P.args, **kwargs: P.kwargs) -> int:
            old = [key for key in kwargs if key in renamed]
            if old:
                where = f"entities[{self.entity_count}]"
                owner = entity_owner(kind, kwargs.get("name"))
                raise SceneError(
                    [
                        SceneProblem(f"{where}.{key}", renamed_message(key, renamed[key], owner))
                        for key in old
                    ]
                )
            return method(self, *args, **kwargs)

        return checked

    return decorate
