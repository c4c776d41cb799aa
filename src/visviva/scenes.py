"""Running a scene: ``visviva run scene.toml -o out/`` and :func:`run_scene`.

A scene file (or builder) becomes a frozen Model; a :class:`~visviva.simulation.Simulation` of
it runs through the one simulation loop while every recorded frame streams into
``recording.h5`` (nothing of the frames stays in memory) (flushed every few frames, so a
killed process keeps what was flushed in the output's hidden staging directory). When the run
ends, ``summary.json`` and the requested outputs (video, viewer, exports) are written, and
everything moves into the output directory at once. A run that diverges still delivers its
recording and summary (``success: false``) and then raises the divergence.
"""

from __future__ import annotations

import dataclasses
import os
import time
import warnings
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._validation import real_number
from ._version import __version__
from .errors import ModelError, SceneError, SceneProblem, SimulationError, VisvivaError
from .io.job import JobReport, python_warnings
from .io.recording import load_recording
from .io.scene_files import dump_scene
from .model import Model
from .model.build import build_model

if TYPE_CHECKING:
    from .ode.state import State
    from .simulation.interrupt import Interrupted, StopOnSignal

__all__ = [
    "DryRun",
    "RunFigures",
    "dry_run",
    "final_values",
    "load_model",
    "run_scene",
    "with_view",
    "write_run",
]


def with_view(
    model: Model, camera: str | None, frame: str | None, follow: str | None = None
) -> Model:
    """``model`` with the view of its videos and viewer replaced (``--camera``, ``--frame``,
    ``--follow``; ``None`` keeps the scene's), checked before anything runs. A view given
    replaces the scene's camera and the body it follows."""
    from .model.build import frame_problem
    from .viz.framing import parse_camera

    if camera is not None:
        parse_camera(camera)  # a bad one is refused now, not after the run
    for option, name in (("--frame", frame), ("--follow", follow)):
        problem = None if name is None else frame_problem(model, name)
        if problem is not None:
            raise ModelError(f"{option}: {problem}")
    if camera is None and frame is None and follow is None:
        return model
    return dataclasses.replace(
        model,
        output_camera=camera,
        output_frame=frame if frame is not None else model.output_frame,
        output_follow=follow,
    )


def load_model(path: str | os.PathLike[str]) -> Model:
    """Read, validate and build a scene file (``.toml`` or ``.json``)."""
    from .io.scene_files import load_scene

    scene, text = load_scene(path)
    try:
        model = build_model(scene, source=text)
        problems = output_problems(model, (), model.integration.duration)
    except SceneError as error:
        problems = error.problems
    if problems:
        located = [_with_line(p, text, os.fspath(path)) for p in problems]
        raise SceneError(located, os.fspath(path)) from None
    return model


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
        particles: Number of particle slots (an emitter counts its capacity).
        systems: The named systems' kinds.
        steps: Steps of ``dt`` to the end.
        frames: Frames the recording would hold.
        max_stable_dt: The stability advisor's largest stable step for the method at the
            initial state [s] (``inf``: no limit from the linearization; ``None``: rigid
            bodies, which the advisor does not linearize).
        outputs: Files the run would write.
    """

    particles: int
    systems: tuple[str, ...]
    steps: int
    frames: int
    max_stable_dt: float | None
    outputs: tuple[str, ...]


def dry_run(model: Model, *, duration: float | None = None, formats: Iterable[str] = ()) -> DryRun:
    """Counts and the stability advisor's estimate for a run of ``model``; nothing is written."""
    import math

    from .analysis.advisor import largest_stable_step
    from .integrators import get

    seconds = _duration(model, duration)
    settings = model.integration
    steps = math.ceil(seconds / settings.dt - 1e-9)
    limit = (
        None  # the advisor linearizes q'' = F(q, v); bodies' quaternions do not fit it
        if model.body_count
        else largest_stable_step(model.system(), get(settings.method), model.initial_state())
    )
    return DryRun(
        particles=model.particle_count,
        systems=tuple(s.system for s in model.systems),
        steps=steps,
        frames=steps // settings.record_every + 1 + (1 if steps % settings.record_every else 0),
        max_stable_dt=limit,
        outputs=tuple(_planned(model, formats, seconds)),
    )


def run_scene(
    model: Model,
    directory: str | os.PathLike[str],
    *,
    duration: float | None = None,
    formats: Iterable[str] = (),
    force: bool = False,
    progress: bool | None = None,
    energy_tolerance: float | None = None,
) -> JobReport:
    """Run ``model`` and write its outputs into ``directory``.

    Args:
        model: The built scene (see :func:`load_model` and :class:`~visviva.SceneBuilder`).
        directory: Output directory, created if missing.
        duration: Simulated time [s] instead of the scene's.
        formats: Extra outputs besides the scene's own (``mp4``, ``gif``, ``html``, ``usd``,
            ``glb``, ``obj``, ``pc2``).
        force: Replace outputs that already exist.
        progress: Progress bar (default: when stderr is a terminal).
        energy_tolerance: Relative energy change of a conservative scene beyond which the run
            ends with a warning (default: the scene's ``energy_tolerance``, 1 %).

    Returns:
        The files written and the summary (also in ``summary.json``).

    Raises:
        ModelError: Bad arguments, existing outputs or an unwritable directory, before anything
            runs.
        SimulationError: If the run failed; its recording and summary were written first
            (``error.report``).
        Interrupted: On SIGINT/SIGTERM: the run stopped after the current step and the
            recording (marked incomplete), the summary and the outputs finished before the
            signal were written (``error.report``).
    """
    seconds = _duration(model, duration)

    def simulate(path: Path | None, stops: StopOnSignal) -> tuple[RunFigures, VisvivaError | None]:
        assert path is not None  # a run always keeps its recording
        return _simulate_streaming(model, path, seconds, progress, stops)

    return write_run(
        model,
        directory,
        simulate,
        seconds=seconds,
        formats=formats,
        force=force,
        energy_tolerance=energy_tolerance,
    )


def write_run(
    model: Model,
    directory: str | os.PathLike[str],
    produce: Callable[[Path | None, StopOnSignal], tuple[RunFigures, VisvivaError | None]],
    *,
    seconds: float,
    formats: Iterable[str] = (),
    force: bool = False,
    energy_tolerance: float | None = None,
    record: bool = True,
) -> JobReport:
    """Write a run's outputs into ``directory``, all or nothing: :func:`run_scene` for a run
    that ``produce`` computes (or replays) into its recording.

    ``produce(path, stops)`` streams the recording into ``path`` (``None`` without ``record``)
    and returns the run's figures and the failure or interrupt that ended it, if any. The
    summary, the extra outputs and the error handling are those of :func:`run_scene`.
    """
    from .io.job import JobOutput
    from .simulation.interrupt import Interrupted, StopOnSignal
    from .viz.outputs import write_output

    planned = _planned(model, formats, seconds)
    if not record:
        if len(planned) > 2:
            raise ModelError("outputs other than summary.json are made from the recording")
        planned.remove("recording.h5")
    tolerance = (
        model.integration.energy_tolerance
        if energy_tolerance is None
        else real_number("energy_tolerance", energy_tolerance, nonnegative=True)
    )
    extra = [name for name in planned if name not in ("recording.h5", "summary.json")]
    with (
        warnings.catch_warnings(record=True) as caught,
        StopOnSignal() as stops,
        JobOutput(directory, force=force) as job,
    ):
        warnings.simplefilter("always")
        job.check_target(planned)
        started = time.perf_counter()
        staged = job.stage("recording.h5") if record else None
        run, failure = produce(staged, stops)
        summary = _summary(model, run, failure, seconds, tolerance)
        unwritten: list[str] = []
        recording = None
        for name in extra if failure is None else ():
            try:
                if recording is None:
                    assert staged is not None  # outputs besides the summary need a recording
                    recording = load_recording(staged)
                with job.writing(name) as path:
                    write_output(
                        recording,
                        path,
                        model.output_fps,
                        model.output_speed,
                        model.output_trail,
                        model.output_color_by,
                    )
            except ModelError as error:
                # The simulation is done: keep it, and say which output could not be made.
                unwritten.append(f"{name} was not written: {error}")
                summary["warnings"].append({"kind": "output", "message": unwritten[-1]})
            except KeyboardInterrupt:
                failure = Interrupted(stops.requested or "SIGINT", run.t_reached)
                summary["interrupted"] = failure.signal
                summary["message"] = f"{failure.signal} while writing {name}; not written"
                break
        summary["wall_time_s"] = run.wall_time_s + time.perf_counter() - started
        summary["warnings"] += python_warnings(caught)
        report = job.write(summary)
    if unwritten and failure is None:
        failure = ModelError("; ".join(unwritten) + " (the recording and summary were kept)")
    if failure is not None:
        failure.report = report
        raise failure
    return report


@dataclass
class RunFigures:
    """What a run leaves besides its recording: outcome, work and energy figures.

    The energy is followed frame by frame (first, last, largest change), so nothing in
    memory grows with the number of frames. ``final`` holds the named systems' coordinates at
    the last frame (see :func:`final_values`). ``wall_time_s`` is time spent before the job's
    own clock started and ``batch_size`` the number of runs computed together with this one
    (:mod:`visviva.simulation.ensemble`), 0 for a run of its own.
    """

    t_reached: float = float("nan")
    frames: int = 0
    points: int = 0
    counters: dict[str, Any] = field(default_factory=dict)
    energy_start: float | None = None
    energy_last: float | None = None
    energy_change: float = 0.0
    emitters: dict[str, dict[str, int]] = field(default_factory=dict)
    wall_time_s: float = 0.0
    batch_size: int = 0
    final: dict[str, float] = field(default_factory=dict)

    def see(self, t: float, energy: Any) -> None:
        self.t_reached = t
        self.frames += 1
        if energy is None:
            return
        value = float(energy)
        if self.energy_start is None:
            self.energy_start = value
        self.energy_last = value
        self.energy_change = max(self.energy_change, abs(value - self.energy_start))

    def drift(self) -> tuple[float | None, float | None]:
        """``(E_last − E_0)/|E_0|`` and ``max |E − E_0|/|E_0|``, or ``None`` without energy."""
        if self.energy_start is None or self.energy_last is None or self.energy_start == 0.0:
            return None, None
        scale = abs(self.energy_start)
        return (self.energy_last - self.energy_start) / scale, self.energy_change / scale

    def recorder(self, model: Model, writer: Any) -> Callable[[State, Any], None]:
        """``record(state, energy)``: what a recording keeps of ``state`` (the model's frame
        and the energy) appended to ``writer`` (``writer.append(t, fields)``), and seen here."""
        from .simulation.frames import frame_fields

        def record(state: State, energy: Any) -> None:
            fields = frame_fields(model, state)
            if energy is not None:
                fields["energy"] = np.asarray(energy, dtype=np.float64)
            writer.append(state.t, fields)
            self.see(state.t, energy)
            self.points = drawn_points(fields)
            self.final = final_values(fields)

        return record


def drawn_points(fields: dict[str, np.ndarray]) -> int:
    """How many points one recorded frame draws: its particles and its systems' points."""
    return sum(
        fields[name].shape[0] for name in ("particle_position", "system_points") if name in fields
    )


#: Recorded fields whose values at the end of a run join its summary, if they are small.
FINAL_FIELDS = ("generalized_position", "generalized_velocity", "y")
#: Most values of one field in the summary: the state of a pendulum or a double pendulum, not
#: of a thousand bodies.
MAX_FINAL_VALUES = 16


def final_values(fields: Mapping[str, np.ndarray]) -> dict[str, float]:
    """The named systems' coordinates in a frame, by name and index
    (``{"generalized_position[1]": 0.42, ...}``), for fields of at most
    :data:`MAX_FINAL_VALUES` values: what an ensemble's results table compares across runs
    (where a chaotic pendulum ends up)."""
    return {
        f"{name}[{i}]": float(value)
        for name in FINAL_FIELDS
        if name in fields
        and np.size(fields[name]) <= MAX_FINAL_VALUES
        and not np.iscomplexobj(fields[name])
        for i, value in enumerate(np.ravel(fields[name]))
    }


def recording_attrs(model: Model, seconds: float) -> dict[str, Any]:
    """The attributes a scene run's recording starts with."""
    from .simulation import frames

    settings = model.integration
    return (
        {
            "scene": model.source or dump_scene(model.scene),
            "scene_name": model.name,
            "visviva_version": __version__,
            "method": settings.method,
            "dt": settings.dt,
            "substeps": settings.substeps,
            "record_every": settings.record_every,
            "t0": 0.0,
            "until": seconds,
            "playback_speed": model.output_speed,
            "playback_trail": model.output_trail,
            "playback_color_by": model.output_color_by,
            "playback_frame": model.output_frame,
            "playback_style": model.output_style,
            "playback_follow": model.output_follow or "",
            "compiled": False,
        }
        | ({} if model.output_camera is None else {"playback_camera": model.output_camera})
        | (frames.recording_attrs(model))
    )


def final_attrs(
    run: RunFigures, failure: VisvivaError | None, wall_time_s: float
) -> dict[str, Any]:
    """The attributes a scene run's recording ends with: work, time and outcome."""
    from .simulation.interrupt import Interrupted

    final: dict[str, Any] = run.counters | {
        "wall_time_s": wall_time_s,
        "complete": failure is None,
        "success": failure is None,
        "message": "completed" if failure is None else str(failure),
    }
    if isinstance(failure, Interrupted):
        final["interrupted"] = failure.signal
    return final


def _simulate_streaming(
    model: Model,
    path: Path,
    seconds: float,
    progress: bool | None,
    stops: StopOnSignal,
) -> tuple[RunFigures, SimulationError | Interrupted | None]:
    """Run the scene, streaming each recorded frame into the recording at ``path``.

    Returns what the run leaves (:class:`RunFigures`) and the failure or interrupt that ended
    it early, if any.
    """
    from .io.writer import RecordingWriter
    from .simulation import Simulation
    from .simulation.frames import UNITS, static_fields
    from .simulation.interrupt import Interrupted

    run = RunFigures()
    failure: SimulationError | Interrupted | None = None
    simulation = Simulation(model)
    with RecordingWriter(
        path, units=UNITS, attrs=recording_attrs(model, seconds), static=static_fields(model)
    ) as writer:
        record = run.recorder(model, writer)
        started = time.perf_counter()
        record(simulation.raw_state, simulation.system.energy(simulation.raw_state))
        try:
            with stops.polled():
                simulation.run(
                    seconds,
                    record_every=model.integration.record_every,
                    on_frame=record,
                    progress=progress,
                )
        except (SimulationError, Interrupted) as error:
            failure = error
        except KeyboardInterrupt:
            # A second signal: the user wants out now; keep the frames already streamed.
            failure = Interrupted(stops.requested or "SIGINT", writer.last_time)
        counters = simulation.system.counters.as_dict()
        run.counters = {"steps": counters["accepted_steps"]} | counters
        end = simulation.raw_state
        run.emitters = {
            spec.name: {
                "births": int(end["emitter_serial"][spec.index]),
                "dropped": int(end["emitter_dropped"][spec.index]),
                "capacity": spec.capacity,
            }
            for spec in model.emitters
        }
        writer.finish(final_attrs(run, failure, time.perf_counter() - started))
    return run, failure


def _summary(
    model: Model,
    run: RunFigures,
    failure: Exception | None,
    seconds: float,
    tolerance: float,
) -> dict[str, Any]:
    """``summary.json`` of a scene run (wall time and Python warnings are added after)."""
    from .simulation.interrupt import Interrupted

    settings = model.integration
    drift, largest = run.drift()
    summary: dict[str, Any] = {
        "scene": model.name,
        "counts": _counts(model, run),
        "method": settings.method,
        "dt": settings.dt,
        "duration_s": seconds,
        "t_reached_s": run.t_reached if run.frames else None,
        "complete": failure is None,
        "success": failure is None,
        "message": "completed" if failure is None else str(failure),
        "steps": int(run.counters.get("steps", 0)),
        "substeps": settings.substeps,
        "conservative": model.conservative,
        "energy_drift": drift,
        "max_energy_error": largest,
        "energy_tolerance": tolerance,
        "warnings": [],
    }
    if isinstance(failure, Interrupted):
        summary["interrupted"] = failure.signal
    if run.final:
        summary["final"] = run.final
    if run.batch_size:
        summary["batch_size"] = run.batch_size
    if run.emitters:
        summary["emitters"] = run.emitters
    for name, counts in run.emitters.items():
        if counts["dropped"]:
            summary["warnings"].append(
                {
                    "kind": "dropped_births",
                    "message": f"emitter {name!r} had no free slot for {counts['dropped']} of its "
                    f"{counts['births']} births (capacity {counts['capacity']}): raise its "
                    "`capacity`, or leave it unset to have room for every particle",
                }
            )
    if model.conservative and drift is not None and abs(drift) > tolerance:
        summary["warnings"].append(
            {"kind": "energy_drift", "message": _energy_warning(model, drift, tolerance)}
        )
    return summary


def _energy_warning(model: Model, drift: float, tolerance: float) -> str:
    from .integrators import get
    from .simulation.watch import energy_drift_advice, suggested_dt

    method = get(model.integration.method)
    suggestion = suggested_dt(model.system(), method, model.initial_state())
    return (
        f"the energy of this conservative scene changed by {100 * drift:+.3g} % (tolerance "
        f"{100 * tolerance:.3g} %, [integration] energy_tolerance). "
        + energy_drift_advice(method, model.integration.dt, suggestion)
    )


def _counts(model: Model, run: RunFigures) -> dict[str, int]:
    """What the scene holds: particle slots, systems' degrees of freedom, drawn points."""
    counts = {}
    if model.particle_count:
        counts["particles"] = model.particle_count
    if model.body_count:
        counts["bodies"] = model.body_count
    if model.systems:
        counts["degrees_of_freedom"] = model.coordinate_count
        if run.points and run.points != model.particle_count:
            counts["points"] = run.points
    return counts


def _duration(model: Model, duration: float | None) -> float:
    if duration is None:
        return model.integration.duration
    seconds = real_number("duration", duration, positive=True, unit=" s")
    if seconds < model.integration.dt:
        raise ModelError(
            f"`duration` ({seconds!r} s) is shorter than the step dt = {model.integration.dt!r} s"
        )
    return seconds


def _planned(model: Model, formats: Iterable[str], seconds: float) -> list[str]:
    """The files a run writes, after checking that its outputs can be written."""
    from .viz.outputs import output_names

    names = output_names([*model.output_formats, *formats])
    problems = output_problems(model, formats, seconds)
    if problems:
        raise SceneError(problems)
    return ["recording.h5", "summary.json", *names]


def output_problems(model: Model, formats: Iterable[str], seconds: float) -> list[SceneProblem]:
    """What stops the scene's outputs (its own and ``formats``) from being written for a run
    of ``seconds`` [s]: no picture, too many frames, a GIF rate players cannot keep."""
    from .io.timeline import MAX_OUTPUT_FRAMES
    from .viz.video import MAX_GIF_FPS, MIN_GIF_FPS

    chosen = list(dict.fromkeys([*model.output_formats, *formats]))
    if not chosen:
        return []
    problems = []
    if not model.has_geometry:
        name = " and ".join(s.system for s in model.systems)
        problems.append(
            SceneProblem(
                "output.formats",
                f"the {name} system has no picture, so it cannot be written as "
                f"{', '.join(chosen)}; drop the output formats",
            )
        )
    fps, speed = model.output_fps, model.output_speed
    frames = seconds * fps / speed
    if frames >= MAX_OUTPUT_FRAMES:
        problems.append(
            SceneProblem(
                "output.speed",
                f"{seconds:g} s at {fps:g} frames/s is {frames:.3g} output frames, more than "
                f"{MAX_OUTPUT_FRAMES}; play faster (speed is simulated seconds per second; "
                f"{seconds / 60:.3g} gives a one-minute clip)",
                repr(speed),
            )
        )
    if "gif" in chosen and not MIN_GIF_FPS <= fps <= MAX_GIF_FPS:
        problems.append(
            SceneProblem(
                "output.fps",
                f"a GIF plays between {MIN_GIF_FPS:.4f} and {MAX_GIF_FPS:g} frames/s (its delays "
                "are whole hundredths of a second, at most 65535); use mp4 for other rates",
                repr(fps),
            )
        )
    return problems
