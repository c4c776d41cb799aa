"""Process-wide memos of built things (compiled kernels, derived equations), bounded and shared.

Building a compiled kernel or deriving a system's equations costs a second or more, so what is
built is kept and handed to every run that asks for the same key. A long-lived process (a
notebook, a sweep worker) may ask for many keys, so a memo keeps only its most recently used
``size`` entries; and many runs may ask at once from their threads, so a lock makes each key
built once::

    >>> squares = Memo(2)
    >>> squares.get(3, lambda: 9), squares.get(4, lambda: 16), squares.get(5, lambda: 25)
    (9, 16, 25)
    >>> len(squares), 3 in squares
    (2, False)
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

__all__ = ["Memo"]

V = TypeVar("V")


class Memo(Generic[V]):
    """A bounded, thread-safe memo: the ``size`` most recently used entries.

    Args:
        size: How many entries to keep, at least 1.
    """

    def __init__(self, size: int) -> None:
        if size < 1:
            raise ValueError(f"a memo keeps at least one entry (got size={size})")
        self.size = size
        self._entries: OrderedDict[Hashable, V] = OrderedDict()
        # Reentrant: a build may ask the same memo for the parts it is made of.
        self._lock = threading.RLock()

    def get(self, key: Hashable, build: Callable[[], V]) -> V:
        """The entry of ``key``, built by ``build()`` if it is not kept."""
        with self._lock:
            if key in self._entries:
                self._entries.move_to_end(key)
                return self._entries[key]
            value = build()
            self._entries[key] = value
            while len(self._entries) > self.size:
                self._entries.popitem(last=False)
            return value

    def __contains__(self, key: Hashable) -> bool:
        with self._lock:
            return key in self._entries

    def __len__(self) -> int:
        with self._lock:
            return len(self._entries)

    def clear(self) -> None:
        """Forget every entry."""
        with self._lock:
            self._entries.clear()
