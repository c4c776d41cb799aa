"""One way to keep things by name: integrators, named systems and demos.

A :class:`Registry` holds items that carry their own ``name``. Looking up a name that is not
there raises :class:`~visviva.errors.ModelError` with the closest name (:func:`did_you_mean`,
which names checked without a registry use too) and the valid ones, so every "unknown method /
system / demo" message reads the same::

    >>> from dataclasses import dataclass
    >>> @dataclass(frozen=True)
    ... class Colour:
    ...     name: str
    >>> colours = Registry[Colour]("colour")
    >>> colours.register(Colour("red")).name
    'red'
    >>> "red" in colours, colours.names()
    (True, ['red'])
    >>> colours.get("rde")
    Traceback (most recent call last):
    ...
    visviva.errors.ModelError: unknown colour 'rde'. Did you mean 'red'? Valid names: red
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Iterator
from typing import Generic, Protocol, TypeVar

from .errors import ModelError

__all__ = ["Named", "Registry", "did_you_mean"]


class Named(Protocol):
    """Anything with a ``name``."""

    @property
    def name(self) -> str: ...


T = TypeVar("T", bound=Named)


class Registry(Generic[T]):
    """Items by their ``name``, in registration order.

    Iterating gives the names, and ``name in registry`` asks whether one is registered, so a
    registry reads like the dictionary it replaces; ``registry[name]`` is ``registry.get(name)``.

    Args:
        kind: What the items are, for messages (``"integration method"``, ``"demo"``).
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._items: dict[str, T] = {}

    def register(self, item: T, *, replace: bool = False) -> T:
        """Add ``item`` under its ``name`` and return it.

        Raises:
            ModelError: If the name is taken and ``replace`` is false.
        """
        if item.name in self._items and not replace:
            raise ModelError(
                f"{self.kind} {item.name!r} is already registered; pass replace=True to replace it"
            )
        self._items[item.name] = item
        return item

    def unregister(self, name: str) -> None:
        """Remove ``name`` if it is registered (e.g. something a test registered)."""
        self._items.pop(name, None)

    def get(self, name: str) -> T:
        """The item called ``name``.

        Raises:
            ModelError: For an unknown name; the message suggests the closest one and lists
                the valid names.
        """
        try:
            return self._items[name]
        except (KeyError, TypeError):
            raise ModelError(
                f"unknown {self.kind} {name!r}.{did_you_mean(str(name), self._items)} "
                f"Valid names: {', '.join(self._items)}"
            ) from None

    def names(self) -> list[str]:
        """The registered names, in registration order."""
        return list(self._items)

    def values(self) -> list[T]:
        """The registered items, in registration order."""
        return list(self._items.values())

    def __getitem__(self, name: str) -> T:
        return self.get(name)

    def __contains__(self, name: object) -> bool:
        try:
            return name in self._items
        except TypeError:  # unhashable: no item has that name
            return False

    def __iter__(self) -> Iterator[str]:
        return iter(list(self._items))

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}: {', '.join(self._items)})"


def did_you_mean(word: str, options: Iterable[str]) -> str:
    """Return ``" Did you mean 'x'?"`` for the closest option, or ``""`` (case ignored)."""
    by_lower = {option.lower(): option for option in options}
    close = difflib.get_close_matches(word.lower(), list(by_lower), n=1, cutoff=0.6)
    return f" Did you mean {by_lower[close[0]]!r}?" if close else ""
