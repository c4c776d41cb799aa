"""Reading and writing scene files (TOML or JSON), with every problem reported at once.

:func:`load_scene` reads a file, refuses what is not a scene (too large, not UTF-8, a syntax
error with its line and column), validates it against :mod:`~visviva.io.scene_schema` and
reports each validation problem as ``path: message (got X)`` with the line where it can be
found and a did-you-mean for misspelt keys. :func:`dump_scene` writes a scene back; floats are
written with ``repr`` (the shortest text that reads back to the same double), so a
dump → load round trip is bit-identical.
"""

from __future__ import annotations

import json
import os
import re
import stat
import tomllib
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from .._validation import describe, did_you_mean
from ..errors import SceneError, SceneProblem
from .scene_locate import locate_json, locate_toml
from .scene_schema import Integration, Output, ParticleCloud, Particles, Scene, SceneInfo, System
from .scene_schema import World as WorldSettings

__all__ = ["MAX_SCENE_BYTES", "dump_scene", "load_scene", "parse_scene"]

#: Largest scene file read [bytes]: scenes are descriptions, not data dumps.
MAX_SCENE_BYTES = 16 * 2**20
#: Deepest nesting of tables and arrays a scene may have: the schema needs 5 (entity
#: parameters, positions); deeper is a mistake, and unbounded depth would exhaust the stack.
MAX_DEPTH = 16

#: Names pydantic gives the branches of a union in error locations (never scene keys).
_UNION_BRANCH = re.compile(r"^(float|int|str|list|tuple|dict|[a-z]+(-[a-z]+)+)$|\[")
_TABLES: dict[str, type[BaseModel]] = {
    "scene": SceneInfo,
    "world": WorldSettings,
    "integration": Integration,
    "output": Output,
}
_ENTITIES: dict[str, type[BaseModel]] = {
    "particles": Particles,
    "particle_cloud": ParticleCloud,
    "system": System,
}


def load_scene(path: str | os.PathLike[str]) -> tuple[Scene, str]:
    """Read and validate a scene file (``.toml`` or ``.json``).

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
    return parse_scene(text, "json" if file.suffix.lower() == ".json" else "toml", source), text


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
        raise SceneError(_problems(exc, raw, lambda path: locate(text, path)), source) from None


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


def _problems(exc: ValidationError, raw: dict[str, Any], line_of: Any) -> list[SceneProblem]:
    """One problem per field: pydantic reports each branch of a union; keep the telling one."""
    chosen: dict[tuple[Any, ...], Any] = {}
    for error in exc.errors(include_url=False):
        path = _field_path(error["loc"])
        previous = chosen.get(path)
        if previous is None or (
            previous["type"].endswith("_type") and not error["type"].endswith("_type")
        ):
            chosen[path] = error
    problems = []
    for path, error in chosen.items():
        message = error["msg"].replace("Input should be", "must be", 1)
        got: str | None = describe(error["input"])
        if error["type"] == "extra_forbidden":
            key = str(path[-1])
            allowed = _allowed_keys(path[:-1], raw)
            message = f"unknown key.{did_you_mean(key, allowed)} Allowed: {', '.join(allowed)}"
            got = None
        elif error["type"] == "missing":
            got = None
        elif error["type"] == "union_tag_invalid":
            message = f"unknown entity type; valid types: {', '.join(_ENTITIES)}"
            got = describe(error["input"].get("type") if isinstance(error["input"], dict) else None)
        elif error["type"] == "finite_number":
            message = "must be a finite number (numbers beyond ±1.8e308 overflow to inf)"
        problems.append(SceneProblem(_dotted(path), message, got, line_of(path)))
    return problems


def _field_path(loc: tuple[Any, ...]) -> tuple[Any, ...]:
    """The error's location as the user wrote it: no union-branch or entity-tag segments."""
    path: list[Any] = []
    for position, segment in enumerate(loc):
        if isinstance(segment, str) and _UNION_BRANCH.search(segment):
            continue  # a union branch name such as "constrained-float", not a key
        if position == 2 and loc[0] == "entities" and segment in _ENTITIES:
            continue  # the discriminator's branch, not a key
        path.append(segment)
    return tuple(path)


def _allowed_keys(path: tuple[Any, ...], raw: dict[str, Any]) -> list[str]:
    model: type[BaseModel] | None = Scene
    if len(path) == 1:
        model = _TABLES.get(str(path[0]))
    elif len(path) == 2 and path[0] == "entities":
        entities = raw.get("entities")
        entity = entities[path[1]] if isinstance(entities, list) else None
        model = _ENTITIES.get(str(entity.get("type"))) if isinstance(entity, dict) else None
    elif path:
        model = None
    return list(model.model_fields) if model is not None else []


def _dotted(path: tuple[Any, ...]) -> str:
    text = ""
    for segment in path:
        text += f"[{segment}]" if isinstance(segment, int) else f".{segment}" if text else segment
    return text


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
