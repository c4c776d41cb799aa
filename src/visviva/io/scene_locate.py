"""Finding the line of a scene file where a value lives, for error messages.

Neither ``tomllib`` nor ``json`` reports positions of values, so these small scanners map a
path such as ``("entities", 2, "mass")`` to a 1-based line number. They only need to be right
for files that parsed, and fall back to the nearest enclosing table or key (or ``None``) when
the exact key is absent — a missing key is reported at its table.
"""

from __future__ import annotations

import json
import re
from typing import Any

__all__ = ["locate_json", "locate_toml"]

_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_PART = r"""(?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*')"""
_KEY = re.compile(rf"^\s*({_PART}(?:\s*\.\s*{_PART})*)\s*=")


def _split_key(key: str) -> tuple[str, ...]:
    parts = re.findall(r"""[A-Za-z0-9_-]+|"[^"]*"|'[^']*'""", key)
    return tuple(p[1:-1] if p[:1] in "\"'" else p for p in parts)


def locate_toml(text: str, path: tuple[Any, ...]) -> int | None:
    """Line of ``path`` in TOML ``text``: the key's line, else its table's header line."""
    table: tuple[Any, ...] = ()
    counts: dict[tuple[Any, ...], int] = {}
    found: dict[tuple[Any, ...], int] = {}
    depth = 0  # open brackets of a multi-line array: its lines hold no keys
    for number, line in enumerate(text.splitlines(), start=1):
        if depth == 0:
            header = _HEADER.match(line)
            if header:
                name = _split_key(header.group(2))
                if header.group(1) == "[[":
                    counts[name] = counts.get(name, -1) + 1
                    table = (*_within(name[:-1], counts), name[-1], counts[name])
                else:
                    table = _within(name, counts)
                found.setdefault(table, number)
                continue
            key = _KEY.match(line)
            if key:
                found.setdefault((*table, *_split_key(key.group(1))), number)
        depth = max(0, depth + _bracket_balance(line))
    for end in range(len(path), -1, -1):
        if path[:end] in found:
            return found[path[:end]]
    return None


def _within(name: tuple[str, ...], counts: dict[tuple[Any, ...], int]) -> tuple[Any, ...]:
    """The path of table ``name``, inside the latest element of each array of tables it
    names (``[entities.handle]`` after the third ``[[entities]]``: ``entities, 2, handle``)."""
    path: list[Any] = []
    for end in range(1, len(name) + 1):
        path.append(name[end - 1])
        if name[:end] in counts and end < len(name):
            path.append(counts[name[:end]])
    return tuple(path)


def _bracket_balance(line: str) -> int:
    """Net ``[`` minus ``]`` outside strings and comments (enough for multi-line arrays)."""
    balance, quote = 0, ""
    value = line.split("=", 1)[1] if _KEY.match(line) else line
    for char in value:
        if quote:
            quote = "" if char == quote else quote
        elif char in "\"'":
            quote = char
        elif char == "#":
            break
        elif char == "[":
            balance += 1
        elif char == "]":
            balance -= 1
    return balance


def locate_json(text: str, path: tuple[Any, ...]) -> int | None:
    """Line of ``path`` in JSON ``text``: where the value (or its nearest parent) starts."""
    starts: dict[tuple[Any, ...], int] = {}
    decoder = json.JSONDecoder()

    def walk(index: int, here: tuple[Any, ...]) -> int:
        index = _skip_space(text, index)
        starts[here] = index
        if text.startswith("{", index):
            index = _skip_space(text, index + 1)
            while not text.startswith("}", index):
                key, index = decoder.raw_decode(text, index)
                index = _skip_space(text, index) + 1  # the colon
                index = _skip_space(text, walk(index, (*here, key)))
                if text.startswith(",", index):
                    index = _skip_space(text, index + 1)
            return index + 1
        if text.startswith("[", index):
            index = _skip_space(text, index + 1)
            item = 0
            while not text.startswith("]", index):
                index = _skip_space(text, walk(index, (*here, item)))
                item += 1
                if text.startswith(",", index):
                    index = _skip_space(text, index + 1)
            return index + 1
        _, end = decoder.raw_decode(text, index)
        return end

    try:
        walk(0, ())
    except (ValueError, IndexError):
        return None
    for end in range(len(path), -1, -1):
        if path[:end] in starts:
            return text.count("\n", 0, starts[path[:end]]) + 1
    return None


def _skip_space(text: str, index: int) -> int:
    while index < len(text) and text[index] in " \t\r\n":
        index += 1
    return index
