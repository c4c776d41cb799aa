"""Reading and writing scene files (TOML or JSON), with every problem reported at once.

:func:`load_scene` reads a file, refuses what is not a scene (too large, not UTF-8, a syntax
error with its line and column), validates it against :mod:`~visviva.model.scene` and
reports each validation problem as ``path: message (got X)`` with the line where it can be
found and a did-you-mean for misspelt keys; the files a scene names (a cloth mesh's
``path``) are taken relative to the scene file's folder. :func:`dump_scene` writes a scene
back; floats are written with ``repr`` (the shortest text that reads back to the same double),
so a dump → load round trip is bit-identical.
"""

from __future__ import annotations

import json
import os
import re
import stat
import tomllib
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from .._validation import describe
from ..errors import SceneError, SceneProblem
from ..model.scene import Scene
from ..model.scene_errors import scene_problems
from .scene_locate import locate_json, locate_toml

__all__ = ["MAX_SCENE_BYTES", "dump_scene", "load_scene", "parse_scene"]

#: Largest scene file read [bytes]: scenes are descriptions, not data dumps.
MAX_SCENE_BYTES = 16 * 2**20
#: Deepest nesting of tables and arrays a scene may have: the schema needs 5 (entity
#: parameters, positions); deeper is a mistake, and unbounded depth would exhaust the stack.
MAX_DEPTH = 16


def load_scene(path: str | os.PathLike[str]) -> tuple[Scene, str]:
    """Read and validate a scene file (``.toml`` or ``.json``); the relative paths of the files
    it names are made relative to its folder.

    Returns:
        The scene and the file's text.

    Raises:
        SceneError: Listing every problem, each with its path and line.
    """
    source = os.fspath(path)
    file = Path(path)
    if file.suffix.lower() not in (".toml", ".json"):
        raise SceneError(
            [SceneProblem("", "scene files end in .toml or .json", repr(file.suffix))], source
        )
    data = _read_limited(file, source)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise SceneError(
            [
                SceneProblem(
                    "",
                    f"the file is not UTF-8 text (byte 0x{data[exc.start]:02x} at offset "
                    f"{exc.start}); save it as UTF-8",
                    line=line,
                )
            ],
            source,
        ) from None
    scene = parse_scene(text, "json" if file.suffix.lower() == ".json" else "toml", source)
    return _relative_to(scene, Path(os.path.abspath(file)).parent), text


def _relative_to(scene: Scene, folder: Path) -> Scene:
    """``scene`` with the relative paths of the files its entities name (a cloth mesh's
    ``path``) made relative to ``folder`` (absolute: the scene may be built elsewhere)."""
    entities, moved = list(scene.entities), False
    for index, entity in enumerate(entities):
        path = getattr(entity, "path", None)
        if isinstance(path, str) and not os.path.isabs(path):
            entities[index] = entity.model_copy(update={"path": str(folder / path)})
            moved = True
    return scene.model_copy(update={"entities": entities}) if moved else scene


def _read_limited(file: Path, source: str) -> bytes:
    """The bytes of a regular file of at most :data:`MAX_SCENE_BYTES`, read without blocking on
    a FIFO and without trusting the size a special file reports (``/dev/zero`` says 0)."""

    def refuse(message: str) -> SceneError:
        return SceneError([SceneProblem("", message)], source)

    try:
        descriptor = os.open(file, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as exc:
        raise refuse(f"cannot read the file: {exc.strerror}") from None
    mode = os.fstat(descriptor).st_mode
    if not stat.S_ISREG(mode):
        os.close(descriptor)
        kind = "a directory" if stat.S_ISDIR(mode) else "not a regular file"
        raise refuse(f"this is {kind}; a scene is a .toml or .json text file")
    with os.fdopen(descriptor, "rb") as handle:
        try:
            data = handle.read(MAX_SCENE_BYTES + 1)
        except OSError as exc:
            raise refuse(f"cannot read the file: {exc.strerror}") from None
    if len(data) > MAX_SCENE_BYTES:
        raise refuse(
            f"the file is larger than {MAX_SCENE_BYTES} bytes, the most a scene file may be "
            '(generate large particle sets with type = "particle_cloud")'
        )
    return data


def parse_scene(text: str, format: str = "toml", source: str | None = None) -> Scene:
    """Parse and validate scene text; ``format`` is ``"toml"`` or ``"json"``."""
    if format != "json":
        _refuse_long_dotted_keys(text, source)
    try:
        raw = json.loads(text) if format == "json" else tomllib.loads(text)
    except RecursionError:
        raise SceneError(
            [SceneProblem("", f"values are nested too deeply; scenes nest at most {MAX_DEPTH}")],
            source,
        ) from None
    except tomllib.TOMLDecodeError as exc:
        # Python 3.11's TOMLDecodeError has no lineno attribute; its message ends with it.
        match = re.search(r"at line (\d+)", str(exc))
        line = int(match.group(1)) if match else None
        raise SceneError(
            [SceneProblem("", f"TOML syntax error: {exc}", line=line)], source
        ) from None
    except json.JSONDecodeError as exc:
        problem = f"JSON syntax error: {exc.msg} (at line {exc.lineno}, column {exc.colno})"
        raise SceneError([SceneProblem("", problem, line=exc.lineno)], source) from None
    except ValueError:
        # Python refuses integers of more than 4300 digits (CVE-2020-10735); no scene needs one.
        raise SceneError(
            [
                SceneProblem(
                    "", "a number has more than 4300 digits; scene numbers are at most ±1.8e308"
                )
            ],
            source,
        ) from None
    depth = _depth(raw)
    if depth > MAX_DEPTH:
        raise SceneError(
            [
                SceneProblem(
                    "", f"values are nested {depth} levels deep; scenes nest at most {MAX_DEPTH}"
                )
            ],
            source,
        )
    if not isinstance(raw, dict):
        raise SceneError(
            [SceneProblem("", "a scene is a table of settings", describe(raw))], source
        )
    try:
        return Scene.model_validate(raw)
    except ValidationError as exc:
        locate = locate_json if format == "json" else locate_toml
        problems = scene_problems(exc, raw, lambda path: locate(text, path))
        raise SceneError(problems, source) from None


#: One line's string literals (basic or literal), replaced by a placeholder before key scanning.
_STRING = re.compile(r'"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'')
#: A dotted key of more than MAX_DEPTH parts (``a.b.c…``, quoted parts already replaced).
_LONG_DOTTED_KEY = re.compile(rf"(?:[\w-]+[ \t]*\.[ \t]*){{{MAX_DEPTH},}}[\w-]+")


def _refuse_long_dotted_keys(text: str, source: str | None) -> None:
    """Refuse dotted keys deeper than a scene can be before parsing: tomllib takes time
    quadratic in a dotted key's length (45 s for 50,000 parts), so the depth check after
    parsing would come too late."""
    keys = _STRING.sub("s", text)
    match = _LONG_DOTTED_KEY.search(keys)
    if match is not None:
        line = keys[: match.start()].count("\n") + 1
        raise SceneError(
            [
                SceneProblem(
                    "",
                    f"a dotted key has more than {MAX_DEPTH} parts; scenes nest at most "
                    f"{MAX_DEPTH} levels",
                    line=line,
                )
            ],
            source,
        )


def _depth(data: Any) -> int:
    """How deeply tables and arrays nest in ``data`` (without recursion, so any depth is safe)."""
    deepest = 0
    pending = [(data, 1)]
    while pending:
        value, depth = pending.pop()
        if isinstance(value, dict):
            children: Any = value.values()
        elif isinstance(value, list):
            children = value
        else:
            continue
        deepest = max(deepest, depth)
        if depth <= MAX_DEPTH:  # deeper is refused anyway: no need to walk it all
            pending.extend((child, depth + 1) for child in children)
    return deepest


def dump_scene(scene: Scene, format: str = "toml") -> str:
    """The scene as TOML (or JSON) text that :func:`parse_scene` reads back identically."""
    data = scene.model_dump(mode="python", exclude_none=True)
    if format == "json":
        return json.dumps(data, indent=2, allow_nan=False) + "\n"
    lines: list[str] = []
    for table in ("scene", "world", "integration", "output"):
        lines.append(f"[{table}]")
        lines += [f"{key} = {_toml_value(value)}" for key, value in data[table].items()]
        lines.append("")
    for entity in data["entities"]:
        lines.append("[[entities]]")
        lines += [f"{key} = {_toml_value(value)}" for key, value in entity.items()]
        lines.append("")
    return "\n".join(lines)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)  # shortest round-trip text of the double (or the exact integer)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)  # JSON escapes are valid TOML basic strings
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        items = ", ".join(f"{json.dumps(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{" + (f" {items} " if items else "") + "}"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")
