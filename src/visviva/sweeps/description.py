"""The sweep description: a base scene, the parameters to vary and the outputs to keep.

A sweep file (``.toml`` or ``.json``) holds a ``[sweep]`` table (name, the base scene's file,
seed, design), one ``[[parameters]]`` table per varied value, an optional ``[outputs]`` table
and optional ``[[plots]]`` of the results against a parameter (:mod:`.plot_spec`); the base
scene may instead be written inline under ``[scene]`` (a whole scene: ``[scene.integration]``,
``[[scene.entities]]``...). Validation follows the scene files': unknown keys are refused with a
did-you-mean, numbers must be finite, a value of the wrong type is refused rather than
converted, and every problem is reported at once with its line.
:func:`load_sweep` reads a file into a :class:`Sweep`; :mod:`.design` expands it into runs.
"""

from __future__ import annotations

import json
import math
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, ValidationError, field_validator, model_validator

from ..entities.fields import Finite, Name, Strict
from ..errors import SceneError, SceneProblem, SweepError
from ..io.scene_files import MAX_SCENE_BYTES, _read_limited, _relative_to, load_scene
from ..io.scene_locate import locate_json, locate_toml
from ..model.scene import OutputFormat, Scene
from ..model.scene_errors import scene_problems
from .paths import PathProblem, resolve
from .plot_spec import Plot, named, plot_problems

__all__ = [
    "MAX_RUNS",
    "Outputs",
    "Parameter",
    "Plot",
    "Sweep",
    "SweepFile",
    "SweepInfo",
    "load_sweep",
]

#: Most runs one sweep may expand to: a description, not a way to exhaust memory.
MAX_RUNS = 1_000_000
#: Longest text value a parameter may take (an integrator's or a system's name is far shorter).
MAX_TEXT = 200

Design = Literal["grid", "random", "zip"]
Count = Annotated[int, Field(strict=True, ge=1, le=MAX_RUNS)]


class SweepInfo(Strict):
    """``[sweep]``: what is swept and how the runs are chosen."""

    name: Name = "sweep"
    description: Annotated[str, Field(strict=True, max_length=10_000)] = ""
    scene: Annotated[str, Field(strict=True, min_length=1, max_length=4096)] | None = Field(
        None, description="base scene file, relative to the sweep file (or an inline [scene])"
    )
    seed: Annotated[int, Field(strict=True, ge=0, lt=2**63)] = Field(
        0, description="seed of a random design: run i draws from (seed, i)"
    )
    design: Design = Field(
        "grid",
        description="grid (every combination), zip (the i-th value of each parameter) or "
        "random (`samples` runs, each parameter drawn at random)",
    )
    samples: Count | None = Field(None, description="number of runs of a random design")

    @model_validator(mode="after")
    def _samples_with_random(self) -> SweepInfo:
        if self.design == "random" and self.samples is None:
            raise ValueError('design = "random" needs `samples`, the number of runs')
        if self.design != "random" and self.samples is not None:
            raise ValueError(
                f"`samples` sets the size of a random design; a {self.design} design has one run "
                'per combination of values (set design = "random" or drop `samples`)'
            )
        return self


class Parameter(Strict):
    """``[[parameters]]``: one value of the scene to vary, and the values it takes.

    Exactly one of ``values`` (a list), ``range`` (``[low, high, count]``: evenly spaced,
    ends included) and ``log_range`` (``[low, high, count]``, evenly spaced in log, ``low``
    and ``high`` positive). In a random design the count is left out: ``range = [low, high]``
    draws uniformly, ``log_range`` log-uniformly, ``values`` picks one with equal chances.
    """

    path: Annotated[str, Field(strict=True, min_length=1, max_length=500)] = Field(
        description="where in the scene: entities[0].stiffness, integration.dt, ..."
    )
    values: Annotated[list[Any], Field(min_length=1, max_length=MAX_RUNS)] | None = None
    range: Annotated[list[Finite], Field(min_length=2, max_length=3)] | None = None
    log_range: Annotated[list[Finite], Field(min_length=2, max_length=3)] | None = None

    @field_validator("values")
    @classmethod
    def _plain_values(cls, values: list[Any] | None) -> list[Any] | None:
        for value in values or ():
            _check_value(value)
        return values

    @model_validator(mode="after")
    def _one_source(self) -> Parameter:
        given = [k for k in ("values", "range", "log_range") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                "give exactly one of `values`, `range` = [low, high, count] and `log_range` "
                f"= [low, high, count] (got {', '.join(given) or 'none'})"
            )
        bounds = self.range or self.log_range
        if bounds is not None:
            key = "range" if self.range is not None else "log_range"
            if len(bounds) == 3 and not (
                float(bounds[2]).is_integer() and 1 <= bounds[2] <= MAX_RUNS
            ):
                raise ValueError(
                    f"the count of `{key}` (its third number) must be a whole number from 1 to "
                    f"{MAX_RUNS} (got {bounds[2]!r})"
                )
            if key == "log_range" and not (bounds[0] > 0 and bounds[1] > 0):
                raise ValueError(
                    f"`log_range` spaces values evenly in log, so low and high must be positive "
                    f"(got {bounds[0]!r}, {bounds[1]!r}); use `range` for values through zero"
                )
        return self


def _check_value(value: Any, depth: int = 0) -> None:
    """A parameter value is a finite number, a bool, a short text or a list of numbers."""
    if isinstance(value, bool):
        return
    if isinstance(value, (int, float)):
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"values must be finite (got {value!r})")
        if isinstance(value, int) and abs(value) > 2**63:
            raise ValueError(f"a whole-number value must be below 2**63 (got {value})")
        return
    if isinstance(value, str):
        if len(value) > MAX_TEXT:
            raise ValueError(f"a text value may have at most {MAX_TEXT} characters")
        return
    if isinstance(value, list) and depth == 0 and len(value) <= 1000:
        for item in value:
            if isinstance(item, (list, str)):
                raise ValueError("a list value holds numbers, such as [0.0, -9.81, 0.0]")
            _check_value(item, depth + 1)
        return
    raise ValueError(
        "each value is a number, true/false, a text or a list of numbers (got "
        f"{type(value).__name__})"
    )


class Outputs(Strict):
    """``[outputs]``: what each run keeps besides its ``summary.json``."""

    recordings: Annotated[bool, Field(strict=True)] = Field(
        False, description="keep each run's recording.h5 (default: summaries only)"
    )
    formats: list[OutputFormat] = Field(
        default_factory=list, description="extra outputs of every run: mp4, html, usd, ..."
    )


class SweepFile(Strict):
    """A whole sweep file."""

    sweep: SweepInfo
    scene: dict[str, Any] | None = Field(None, description="the base scene, inline")
    parameters: Annotated[list[Parameter], Field(min_length=1, max_length=64)]
    outputs: Outputs = Outputs()
    plots: Annotated[list[Plot], Field(max_length=64)] = Field(
        default_factory=list, description="figures of the results against a parameter"
    )

    @model_validator(mode="after")
    def _one_scene_and_distinct_paths(self) -> SweepFile:
        if (self.sweep.scene is None) == (self.scene is None):
            raise ValueError(
                "give the base scene either as a file (`scene` in [sweep]) or inline ([scene] "
                "tables), not both" + (" and not neither" if self.scene is None else "")
            )
        seen: set[str] = set()
        for parameter in self.parameters:
            path = parameter.path.replace(" ", "")
            if path in seen:
                raise ValueError(f"the path {parameter.path!r} is swept twice; give it once")
            # One path inside another ("integration" and "integration.dt"): the outer one's
            # values replace the table the inner one would set a field of.
            for other in seen:
                outer, inner = sorted((path, other), key=len)
                if inner.startswith(outer) and inner[len(outer)] in ".[":
                    raise ValueError(
                        f"the paths {outer!r} and {inner!r} overlap: {outer!r} replaces what "
                        f"{inner!r} sets; sweep one of them"
                    )
            seen.add(path)
        return self


@dataclass(frozen=True)
class Sweep:
    """A validated sweep: the base scene as plain data and the parameters with their keys.

    Attributes:
        info: The ``[sweep]`` table.
        parameters: The ``[[parameters]]`` tables, in the file's order.
        keys: Each parameter's keys in the scene (entity names replaced by indices).
        outputs: The ``[outputs]`` table.
        base: The base scene as plain data (what ``Scene.model_dump`` gives).
        source: The sweep file's name, when read from one.
        plots: The ``[[plots]]`` tables, each with its ``name``.
    """

    info: SweepInfo
    parameters: tuple[Parameter, ...]
    keys: tuple[tuple[str | int, ...], ...]
    outputs: Outputs
    base: dict[str, Any]
    source: str | None = None
    plots: tuple[Plot, ...] = ()

    @property
    def paths(self) -> tuple[str, ...]:
        """The parameters' paths as written."""
        return tuple(p.path for p in self.parameters)


def load_sweep(path: str | os.PathLike[str]) -> Sweep:
    """Read and validate a sweep file (``.toml`` or ``.json``), its base scene and its paths.

    Raises:
        SweepError: Listing every problem of the description, each with its line; a problem of
            the base scene file is reported as that file's :class:`~visviva.errors.SceneError`.
    """
    source = os.fspath(path)
    file = Path(path)
    if file.suffix.lower() not in (".toml", ".json"):
        raise SweepError([SceneProblem("", "sweep files end in .toml or .json")], source)
    try:
        data = _read_limited(file, source)
    except SceneError as error:
        raise SweepError(error.problems, source) from None
    if len(data) > MAX_SCENE_BYTES:
        raise SweepError([SceneProblem("", "the file is too large for a sweep")], source)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise SweepError([SceneProblem("", "the file is not UTF-8 text")], source) from None
    return parse_sweep(text, "json" if file.suffix.lower() == ".json" else "toml", source)


def parse_sweep(text: str, format: str = "toml", source: str | None = None) -> Sweep:
    """Validate sweep text (``format`` ``"toml"`` or ``"json"``); a relative scene file is
    found from ``source``'s folder (else the working directory)."""
    from ..io.scene_files import _depth, _refuse_long_dotted_keys

    locate = locate_json if format == "json" else locate_toml
    try:
        if format != "json":
            _refuse_long_dotted_keys(text, source)
        raw = json.loads(text) if format == "json" else tomllib.loads(text)
        if _depth(raw) > 16:
            raise SceneError([SceneProblem("", "values are nested more than 16 levels deep")])
    except SceneError as error:
        raise SweepError(error.problems, source) from None
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        raise SweepError([SceneProblem("", f"syntax error: {exc}")], source) from None
    except (RecursionError, ValueError):
        raise SweepError(
            [SceneProblem("", "values nested too deeply or a number of over 4300 digits")],
            source,
        ) from None
    if not isinstance(raw, dict):
        raise SweepError([SceneProblem("", "a sweep is a table of settings")], source)
    try:
        description = SweepFile.model_validate(raw)
    except ValidationError as exc:
        problems = [
            SceneProblem(p.path, p.message.removeprefix("Value error, "), p.got, p.line)
            for p in scene_problems(exc, raw, lambda p: locate(text, p), SweepFile)
        ]
        raise SweepError(problems, source) from None
    folder = Path(os.path.abspath(source)).parent if source else Path.cwd()
    base = _base_scene(description, raw, text, locate, folder, source)
    problems, keys = [], []
    for index, parameter in enumerate(description.parameters):
        try:
            keys.append(resolve(base, parameter.path))
        except PathProblem as problem:
            line = locate(text, ("parameters", index, "path"))
            problems.append(SceneProblem(f"parameters[{index}].path", str(problem), line=line))
    for index, key, message in _plot_problems(description):
        line = locate(text, ("plots", index, key))
        problems.append(SceneProblem(f"plots[{index}].{key}", message, line=line))
    if problems:
        raise SweepError(problems, source)
    return Sweep(
        info=description.sweep,
        parameters=tuple(description.parameters),
        keys=tuple(keys),
        outputs=description.outputs,
        base=base.model_dump(mode="python", exclude_none=True),
        source=source,
        plots=named(description.plots, [p.path for p in description.parameters]),
    )


def _plot_problems(description: SweepFile) -> list[tuple[int, str, str]]:
    """The plots' problems (:func:`.plot_spec.plot_problems`) given the parameters' values."""
    random = description.sweep.design == "random"
    counts: list[int | None] = []
    for parameter in description.parameters:
        bounds = parameter.range or parameter.log_range
        if random:
            counts.append(None)
        elif parameter.values is not None:
            counts.append(len(parameter.values))
        else:
            counts.append(int(bounds[2]) if bounds is not None and len(bounds) == 3 else None)
    return plot_problems(
        description.plots,
        [p.path for p in description.parameters],
        [p.values for p in description.parameters],
        counts,
        description.sweep.design,
    )


def _base_scene(
    description: SweepFile,
    raw: dict[str, Any],
    text: str,
    locate: Any,
    folder: Path,
    source: str | None,
) -> Scene:
    """The validated base scene, from its file or the inline ``[scene]`` tables."""
    if description.sweep.scene is not None:
        path = Path(description.sweep.scene)
        scene, _ = load_scene(path if path.is_absolute() else folder / path)
        return scene
    inline = raw["scene"]
    try:
        scene = Scene.model_validate(inline)
    except ValidationError as exc:
        problems = scene_problems(exc, inline, lambda p: locate(text, ("scene", *p)))
        located = [
            SceneProblem(f"scene.{p.path}" if p.path else "scene", p.message, p.got, p.line)
            for p in problems
        ]
        raise SweepError(located, source) from None
    return _relative_to(scene, folder)
