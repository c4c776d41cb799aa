"""Running a scene: ``visviva run scene.toml -o out/`` and :func:`run_scene`.

A scene file (or builder) becomes a frozen Model; its problem runs through the one simulation
loop while every recorded frame streams into ``recording.h5`` (flushed every few frames, so a
killed process keeps what was flushed in the output's hidden staging directory). When the run
ends, ``summary.json`` and the requested outputs (video, viewer, exports) are written, and
everything moves into the output directory at once. A run that diverges still delivers its
recording and summary (``success: false``) and then raises the divergence.
"""

from __future__ import annotations

import os
import time
import warnings
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ._version import __version__
from .errors import ModelError, SceneError, SceneProblem, SimulationError
from .model import Model
from .model.build import build_model

__all__ = ["DryRun", "dry_run", "load_model", "run_scene"]


def load_model(path: str | os.PathLike[str]) -> Model:
    """Read, validate and build a scene file (``.toml`` or ``.json``)."""
    from .io.scene_files import load_scene

    scene, text = load_scene(path)
    try:
        return build_model(scene, source=text)
    except SceneError as error:
        located = [_with_line(p, text, os.fspath(path)) for p in error.problems]
        raise SceneError(located, os.fspath(path)) from None


def _with_line(problem: SceneProblem, text: str, path: str) -> SceneProblem:
    from .io.scene_locate import locate_json, locate_toml

    keys = tuple(
        int(part) if part.isdigit() else part
        for part in problem.path.replace("[", ".").replace("]", "").split(".")
        if part
    )
    locate = locate_json if path.lower().endswith(".json") else locate_toml
    return SceneProblem(problem.path, problem.message, problem.got, locate(text, keys))


@dataclass(frozen=True)
class DryRun:
    """What a run would do, without doing it.

    Attributes:
        particles: Number of particles.
        system: Named system, or ``None``.
        steps: Steps of ``dt`` to the end.
        frames: Frames the recording would hold.
        max_stable_dt: The stability advisor's largest stable step for the method at the
            initial state [s] (``inf``: no limit from the linearization).
        outputs: Files the run would write.
    """

    particles: int
    system: str | None
    steps: int
    frames: int
    max_stable_dt: float
    outputs: tuple[str, ...]


def dry_run(model: Model, *, duration: float | None = None, formats: Iterable[str] = ()) -> DryRun:
    """Counts and the stability advisor's estimate for a run of ``model``; nothing is written."""
    import math

    import numpy as np

    from .analysis.stability import max_stable_dt, state_jacobian
    from .simulation.loop import initial_state

    seconds = _duration(model, duration)
    settings = model.integration
    steps = math.ceil(seconds / settings.dt - 1e-9)
    problem = model.problem()
    system = problem.system()
    if model.particle_count > 1000:
        limit = math.inf  # free particles: the Jacobian of gravity is zero, no step limit
    else:
        jacobian = state_jacobian(system, initial_state(problem))
        limit = max_stable_dt(settings.method, jacobian=np.asarray(jacobian))
    return DryRun(
        particles=model.particle_count,
        system=None if model.system is None else model.system.system,
        steps=steps,
        frames=steps // settings.record_every + 1 + (1 if steps % settings.record_every else 0),
        max_stable_dt=limit,
        outputs=tuple(_planned(model, formats)),
    )


def run_scene(
    model: Model,
    directory: str | os.PathLike[str],
    *,
    duration: float | None = None,
    formats: Iterable[str] = (),
    force: bool = False,
    progress: bool | None = None,
) -> list[Path]:
    """Run ``model`` and write its outputs into ``directory``.

    Args:
        model: The built scene (see :func:`load_model` and :class:`~visviva.SceneBuilder`).
        directory: Output directory, created if missing.
        duration: Simulated time [s] instead of the scene's.
        formats: Extra outputs besides the scene's own (``mp4``, ``gif``, ``html``, ``usd``,
            ``glb``, ``obj``, ``pc2``).
        force: Replace outputs that already exist.
        progress: Progress bar (default: when stderr is a terminal).

    Returns:
        The files written.

    Raises:
        ModelError: Bad arguments or existing outputs, before anything runs.
        SimulationError: If the run failed; its recording and summary were written first.
    """
    from .io.job import JobOutput
    from .io.writer import RecordingWriter
    from .simulation.loop import simulate

    seconds = _duration(model, duration)
    planned = _planned(model, formats)
    extra = [name for name in planned if name not in ("recording.h5", "summary.json")]
    job = JobOutput(directory, force=force)
    job.check_target(planned)
    settings = model.integration
    problem = model.problem()
    attrs = {
        "scene": model.source or "",
        "scene_name": model.name,
        "visviva_version": __version__,
        "method": settings.method,
        "dt": settings.dt,
    }
    started = time.perf_counter()
    failure: SimulationError | None = None
    with (
        warnings.catch_warnings(record=True) as caught,
        RecordingWriter(
            job.stage("recording.h5"), units=model.units(), attrs=attrs, static=model.static()
        ) as writer,
    ):
        warnings.simplefilter("always")
        try:
            recording = simulate(
                problem,
                settings.method,
                dt=settings.dt,
                t_end=problem.t0 + seconds,
                substeps=settings.substeps,
                record_every=settings.record_every,
                progress=progress,
                on_frame=lambda t, parts: writer.append(t, _frame(model, parts)),
            )
        except SimulationError as error:
            failure = error
            recording = error.recording  # type: ignore[attr-defined]
        recording = _as_scene_recording(model, recording)
        series = {"energy": recording["energy"]} if "energy" in recording else {}
        writer.finish(recording.attrs | {"scene": model.source or ""}, series)
    from .io.job import run_summary

    summary = {
        "scene": model.name,
        "duration_s": seconds,
        "particles": model.particle_count,
        "steps": int(recording.attrs.get("steps", 0)),
        "wall_time_s": time.perf_counter() - started,
        "warnings": dict(Counter(w.category.__name__ for w in caught)),
        "success": failure is None,
        "message": recording.attrs.get("message", ""),
    } | {"energy_drift": run_summary(recording)["energy_drift"]}
    if failure is None:
        from .io.outputs import write_output

        for name in extra:
            write_output(recording, job.stage(name), model.output_fps, model.output_speed)
    else:
        job.staged = [name for name in job.staged if name == "recording.h5"]
    written = job.write(summary)
    if failure is not None:
        raise failure
    return written


def _duration(model: Model, duration: float | None) -> float:
    from ._validation import real_number

    if duration is None:
        return model.integration.duration
    seconds = real_number("duration", duration, positive=True, unit=" s")
    if seconds < model.integration.dt:
        raise ModelError(
            f"`duration` ({seconds!r} s) is shorter than the step dt = {model.integration.dt!r} s"
        )
    return seconds


def _planned(model: Model, formats: Iterable[str]) -> list[str]:
    from .io.outputs import output_names

    chosen = [*model.output_formats, *formats]
    names = output_names(chosen)
    if names and not model.has_geometry:
        raise ModelError(
            f"the {model.system.system if model.system else ''} system has no picture, so it "
            f"cannot be written as {', '.join(dict.fromkeys(chosen))}; drop the output formats"
        )
    return ["recording.h5", "summary.json", *names]


def _frame(model: Model, parts: tuple[Any, ...]) -> dict[str, Any]:
    """One recorded frame's fields (the model's frame fields for a single frame)."""
    fields = model.frame_fields(tuple(p[None] for p in parts))
    return {name: value[0] for name, value in fields.items()}


def _as_scene_recording(model: Model, recording: Any) -> Any:
    """The loop's recording (``q``, ``v`` or ``y``) as the scene's fields and static arrays."""
    from .io.recording import Recording

    names = ("y",) if "y" in recording else ("q", "v")
    fields = model.frame_fields(tuple(recording[name] for name in names))
    if "energy" in recording:
        fields["energy"] = recording["energy"]
    return Recording(
        recording.time,
        fields,
        units=model.units(),
        attrs=recording.attrs | {"scene_name": model.name},
        static=model.static(),
    )
