"""Running a demo: :func:`run_demo`, behind ``visviva demo NAME -o DIR``."""

from __future__ import annotations

import time
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from .._validation import real_number
from ..errors import ModelError
from ..io.job import JobOutput, JobReport, python_warnings, run_summary
from ..simulation.interrupt import Interrupted, StopOnSignal
from ..viz.framing import parse_camera
from ..viz.outputs import output_names, write_output
from . import Demo, demos, find_demo

__all__ = ["MAX_DURATION_FACTOR", "run_demo"]

#: A demo runs at most this many times its default duration: demos pick their steps and frame
#: counts for their default, and 1000× is already minutes of computing for most of them.
MAX_DURATION_FACTOR = 1000


def run_demo(
    name: str,
    directory: str | Path,
    *,
    duration: float | None = None,
    formats: Iterable[str] = (),
    fps: float = 30.0,
    force: bool = False,
    full: bool = False,
    camera: str | None = None,
    frame: str | None = None,
    follow: str | None = None,
) -> JobReport:
    """Run demo ``name`` and write its outputs into ``directory``.

    Args:
        name: Demo name (see :func:`demos`).
        directory: Output directory, created if missing.
        duration: Simulated duration [s]; default: the demo's own.
        formats: Outputs of the demo's first recording (``mp4``, ``gif``, ``html``, ``usd``,
            ``glb``, ``obj``, ``pc2``), for demos with a picture.
        fps: Frame rate of those outputs [frames/s].
        force: Replace outputs that already exist.
        full: Run the demo's long version (:attr:`Demo.full`), where its default is cut down
            to finish within a minute.
        camera: The view of the video and the viewer,
            ``"eye=x,y,z target=x,y,z [up=x,y,z] [fov=degrees]"``; default: a framing.
        frame: Without ``camera``, what the framing keeps in view: ``"all"`` (default) or a
            rigid body's name.
        follow: A rigid body the camera follows (instead of ``camera``).

    Returns:
        The files written and the summary (also in ``summary.json``).

    Raises:
        ModelError: Bad arguments or existing outputs, before anything runs.
        Interrupted: On SIGINT/SIGTERM: the runs finished so far, the one cut short (marked
            ``-interrupted``) and the summary were written (``error.report``).
    """
    demo = find_demo(name)
    if full and demo.full is None:
        raise ModelError(
            f"demo {name!r} has no long version: its default is the whole demo (drop --full)"
        )
    seconds = (
        demo.duration
        if duration is None
        else real_number("duration", duration, positive=True, unit=" s")
    )
    if seconds > MAX_DURATION_FACTOR * demo.duration:
        raise ModelError(
            f"`duration` of demo {name!r} must be at most {MAX_DURATION_FACTOR} times its "
            f"default of {demo.duration:g} s (got {seconds!r} s); for longer runs write a scene "
            "file and use `visviva run`"
        )
    extras = output_names(formats)
    if extras and not demo.picture:
        raise ModelError(
            f"demo {name!r} has no picture, so it cannot be written as "
            f"{', '.join(dict.fromkeys(formats))}; demos with one: "
            f"{', '.join(d.name for d in demos().values() if d.picture)}"
        )
    fps = real_number("fps", fps, positive=True, unit=" frames/s")
    if camera is not None:
        parse_camera(camera)  # a bad one is refused before the demo runs
    view = {"playback_frame": frame or "all", "playback_follow": follow or ""} | (
        {"playback_camera": camera} if camera else {}
    )
    with (
        warnings.catch_warnings(record=True) as caught,
        StopOnSignal() as stops,
        JobOutput(directory, force=force) as output,
    ):
        warnings.simplefilter("always")
        output.check_target(["recording.h5", "summary.json", *extras])
        started = time.perf_counter()
        interrupted: Interrupted | None = None
        extra: dict[str, Any] = {}
        unwritten: list[str] = []
        try:
            with stops.polled():
                extra = (demo.full if full and demo.full else demo.run)(output, seconds)
        except Interrupted as error:
            interrupted = error
            if error.recording is not None:
                output.recordings[_interrupted_run_name(output, error)] = error.recording
        if interrupted is None and stops.requested:
            interrupted = Interrupted(stops.requested, seconds)
        for recording in output.recordings.values():  # later exports play them the same way
            recording.attrs |= {
                "playback_speed": demo.speed,
                "playback_trail": demo.trail,
                "playback_color_by": demo.color_by,
                "playback_labels": demo.labels,
                "playback_style": demo.style,
            } | view
        summary = _summary(demo, output, seconds, interrupted) | extra
        if full:
            summary["full"] = True
        if extras and interrupted is None:
            run, primary = next(iter(output.recordings.items()))
            summary["outputs_show_run"] = run
            for file_name in extras:
                try:
                    with output.writing(file_name) as path:
                        write_output(primary, path, fps, demo.speed, demo.trail, demo.color_by)
                except ModelError as error:  # a bad --frame, say: the runs are kept all the same
                    unwritten.append(f"{file_name} was not written: {error}")
                except KeyboardInterrupt:
                    interrupted = Interrupted(stops.requested or "SIGINT", seconds)
                    summary["interrupted"] = interrupted.signal
                    summary["message"] = f"{interrupted.signal} while writing {file_name}"
                    break
        summary["wall_time_s"] = time.perf_counter() - started
        summary["warnings"] = python_warnings(caught)
        summary["warnings"] += [{"kind": "output", "message": line} for line in unwritten]
        report = output.write(summary)
    if interrupted is not None:
        interrupted.report = report
        raise interrupted
    if unwritten:
        failure = ModelError("; ".join(unwritten) + " (the recording and summary were kept)")
        failure.report = report  # type: ignore[attr-defined]
        raise failure
    return report


def _summary(
    demo: Demo, output: JobOutput, seconds: float, interrupted: Interrupted | None
) -> dict[str, Any]:
    runs = {run: run_summary(recording) for run, recording in output.recordings.items()}
    # The drift of the conservative runs: the others' energy change is physics, not error.
    drifts = [
        r["energy_drift"]
        for r in runs.values()
        if r["energy_drift"] is not None and r.get("conservative", True)
    ]
    summary: dict[str, Any] = {
        "demo": demo.name,
        "description": demo.summary,
        "duration_s": seconds,
        "complete": interrupted is None,
        "steps": sum(int(r.get("steps", 0)) for r in runs.values()),
        "energy_drift": max(drifts, key=abs) if drifts else None,
        "runs": runs,
    }
    if interrupted is not None:
        summary["interrupted"] = interrupted.signal
        summary["message"] = str(interrupted)
    return summary


def _interrupted_run_name(output: JobOutput, error: Interrupted) -> str:
    """A name for the run a signal cut short: its method, marked, unique in the job."""
    base = f"{error.recording.attrs.get('method', 'run')}-interrupted"
    name, k = base, 1
    while name in output.recordings:
        k += 1
        name = f"{base}-{k}"
    return name
