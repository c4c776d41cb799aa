"""Expanding a sweep into runs, and checking every run's scene before any of them starts.

Designs:

* ``grid``: every combination of the parameters' values, the first parameter varying slowest
  (as nested loops written in the file's order); ``len(a) * len(b) * ...`` runs.
* ``zip``: run i takes the i-th value of every parameter (all of the same length).
* ``random``: ``samples`` runs; run i draws each parameter, in the file's order, from its own
  generator ``Generator(PCG64(SeedSequence([seed, i])))``, so a run's values depend only on
  the seed and its index, never on how many runs there are or where they are computed.

Each run's scene is the base scene with the run's values set, validated and built exactly as a
scene file is (:func:`~visviva.model.build.build_model` and the output checks of
:func:`~visviva.scenes.output_problems`); the failures of all runs are reported together in one
:class:`~visviva.errors.SweepError`.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
from collections.abc import Hashable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydantic import ValidationError

from .._validation import describe
from ..errors import ModelError, SceneError, SceneProblem, SweepError
from ..model.build import build_model
from ..model.scene import Scene
from ..model.scene_errors import scene_problems
from ..simulation.ensemble import ensemble_key
from .description import MAX_RUNS, Parameter, Sweep
from .paths import replaced

__all__ = ["SweepRun", "expand", "run_values"]

#: Most per-run problems listed in one SweepError (the count of the rest is given).
MAX_LISTED = 50


@dataclass(frozen=True)
class SweepRun:
    """One run of a sweep.

    Attributes:
        index: Position in the design (0-based).
        values: The parameters' values, by path, in the file's order.
        name: Directory name of the run: zero-padded index and the values, ``0003-dt=0.01``.
        scene: The run's scene as plain data (validated; picklable, sent to workers).
        digest: SHA-256 of the scene's data: a finished run is reused only for the same digest.
        batch_key: What runs must share to advance together in one batched state
            (:func:`~visviva.simulation.ensemble.ensemble_key` of its model, meaningful in this
            process only), or ``None`` if the run cannot join a batch or was not checked.
    """

    index: int
    values: dict[str, Any]
    name: str
    scene: dict[str, Any]
    digest: str
    batch_key: Hashable | None = field(default=None, compare=False, repr=False)


def run_values(sweep: Sweep) -> list[dict[str, Any]]:
    """Each run's values, by path, in run order (nothing is validated here).

    Raises:
        SweepError: An empty design, zip lists of different lengths, a count where none
            belongs, or more than :data:`MAX_RUNS` runs.
    """
    design, parameters = sweep.info.design, sweep.parameters
    problems = [
        SceneProblem(f"parameters[{i}]", message)
        for i, p in enumerate(parameters)
        if (message := _source_problem(p, design))
    ]
    if problems:
        raise SweepError(problems, sweep.source)
    paths = sweep.paths
    if design == "random":
        assert sweep.info.samples is not None  # checked by SweepInfo
        return [
            dict(zip(paths, _draw(parameters, sweep.info.seed, i), strict=True))
            for i in range(sweep.info.samples)
        ]
    lists = [_listed(p) for p in parameters]
    if design == "zip":
        lengths = {len(values) for values in lists}
        if len(lengths) > 1:
            counts = ", ".join(
                f"{p.path}: {len(v)}" for p, v in zip(parameters, lists, strict=True)
            )
            raise SweepError(
                [SceneProblem("parameters", f"a zip design needs lists of one length ({counts})")],
                sweep.source,
            )
        return [dict(zip(paths, row, strict=True)) for row in zip(*lists, strict=True)]
    total = math.prod(len(values) for values in lists)
    if total > MAX_RUNS:
        raise SweepError(
            [SceneProblem("parameters", f"the grid has {total} runs, more than {MAX_RUNS}")],
            sweep.source,
        )
    return [dict(zip(paths, row, strict=True)) for row in itertools.product(*lists)]


def _source_problem(parameter: Parameter, design: str) -> str | None:
    """Why the parameter's values do not fit the design, or ``None``."""
    bounds = parameter.range or parameter.log_range
    key = "range" if parameter.range is not None else "log_range"
    if bounds is None:
        return None
    if design == "random" and len(bounds) == 3:
        return (
            f"a random design draws from `{key}` = [low, high]; drop the count (the third number)"
        )
    if design != "random" and len(bounds) == 2:
        return f"a {design} design takes `{key}` = [low, high, count]; add the count"
    return None


def _listed(parameter: Parameter) -> list[Any]:
    """The values of a grid or zip parameter, as plain Python values."""
    if parameter.values is not None:
        return list(parameter.values)
    if parameter.range is not None:
        low, high, count = parameter.range
        return [float(x) for x in np.linspace(low, high, int(count))]
    assert parameter.log_range is not None
    low, high, count = parameter.log_range
    return [float(x) for x in np.geomspace(low, high, int(count))]


def _draw(parameters: tuple[Parameter, ...], seed: int, index: int) -> list[Any]:
    """Run ``index``'s values of a random design, from its own generator."""
    rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, index])))
    drawn: list[Any] = []
    for parameter in parameters:
        if parameter.values is not None:
            drawn.append(parameter.values[int(rng.integers(len(parameter.values)))])
        elif parameter.range is not None:
            drawn.append(_between(parameter.range[0], parameter.range[1], rng.random()))
        else:
            assert parameter.log_range is not None
            low, high = np.log(parameter.log_range[0]), np.log(parameter.log_range[1])
            drawn.append(float(np.exp(_between(low, high, rng.random()))))
    return drawn


def _between(low: float, high: float, u: float) -> float:
    """The point a fraction ``u`` in [0, 1) of the way from ``low`` to ``high``, either order:
    ``low + (high − low) u`` as NumPy's ``uniform`` draws it (so earlier sweeps draw the same
    values), or weighted when the difference overflows (a range of ±1e308)."""
    span = high - low
    if math.isfinite(span):
        return float(low + span * u)
    return float(low * (1.0 - u) + high * u)


def expand(sweep: Sweep, *, check: bool = True) -> list[SweepRun]:
    """The sweep's runs, each with its scene; with ``check``, every scene is validated and
    built first.

    Raises:
        SweepError: For the design (see :func:`run_values`), or listing every run whose scene
            fails validation: its index, its values and the scene's problem.
    """
    from ..scenes import output_problems

    all_values = run_values(sweep)
    width = len(str(max(len(all_values) - 1, 0)))
    runs: list[SweepRun] = []
    problems: list[SceneProblem] = []
    failed = 0
    for index, values in enumerate(all_values):
        data = sweep.base
        for keys, value in zip(sweep.keys, values.values(), strict=True):
            data = replaced(data, keys, value)
        name = f"{index:0{width}d}-{_slug(values)}"
        found: list[SceneProblem] = []
        key: Hashable | None = None
        if check:
            try:
                scene = Scene.model_validate(data)
                model = build_model(scene)
                found = output_problems(model, sweep.outputs.formats, model.integration.duration)
                key = ensemble_key(model)
            except ValidationError as exc:
                found = scene_problems(exc, data, lambda _path: None)
            except SceneError as error:
                found = error.problems
            except ModelError as error:
                found = [SceneProblem("", str(error))]
        if found:
            failed += 1
            label = ", ".join(f"{path} = {describe(v)}" for path, v in values.items())
            problems += [
                SceneProblem(f"run {index} ({label}): {p.path}".rstrip(": "), p.message, p.got)
                for p in found
            ][: max(MAX_LISTED - len(problems), 0)]
        runs.append(SweepRun(index, values, name, data, _digest(data), key))
    if problems:
        if failed > 1 or len(problems) >= MAX_LISTED:
            problems.append(
                SceneProblem("", f"{failed} of {len(all_values)} runs have invalid scenes")
            )
        raise SweepError(problems, sweep.source)
    return runs


def _digest(data: dict[str, Any]) -> str:
    text = json.dumps(data, sort_keys=True, allow_nan=False, default=list)
    return hashlib.sha256(text.encode()).hexdigest()


def _slug(values: dict[str, Any]) -> str:
    """The values as a short, safe file name: ``stiffness=100_method=rk4``."""
    parts = []
    for path, value in values.items():
        field = re.sub(r"\[[^\]]*\]", "", path).split(".")[-1]
        shown = (
            "x".join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in value)
            if isinstance(value, list)
            else f"{value:.6g}"
            if isinstance(value, float)
            else str(value)
        )
        parts.append(f"{field}={shown}")
    slug = re.sub(r"[^A-Za-z0-9_.=+-]+", "-", "_".join(parts)).strip("-.")
    return slug[:80] or "run"
