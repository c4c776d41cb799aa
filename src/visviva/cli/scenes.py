"""Scene and output commands: ``run``, ``validate``, ``schema``, ``plot``, ``view``, ``export``."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

from .common import (
    CameraOption,
    FollowOption,
    ForceOption,
    FrameOption,
    app,
    check_figure_file,
    print_json,
    print_report,
    save_figure,
)

SceneArgument = Annotated[Path, typer.Argument(help="Scene file (.toml or .json).")]
RecordingArgument = Annotated[Path, typer.Argument(help="Recording file (recording.h5).")]
RunOption = Annotated[
    str | None, typer.Option("--run", help="Run to use when the file holds several.")
]
FpsOption = Annotated[
    float | None, typer.Option("--fps", help="Frames per second of the output [1/s].")
]
SpeedOption = Annotated[
    float | None,
    typer.Option(
        "--speed",
        help="Simulated seconds per second of playback (86400: a day per second); default: "
        "the speed the run was made with (its scene's or demo's), else 1.",
    ),
]
TrailOption = Annotated[
    float | None,
    typer.Option(
        "--trail",
        help="Simulated seconds [s] of each point's path drawn behind it (video, viewer); "
        "default: the run's, else 0.",
    ),
]
ColorByOption = Annotated[
    str | None,
    typer.Option(
        "--color-by",
        help="What colours the points (video, viewer): scene (the recorded colours) or speed; "
        "default: the run's, else scene.",
    ),
]


@app.command("run")
def run_command(
    scene: SceneArgument,
    output: Annotated[Path, typer.Option("--output", "-o", help="Output directory.")] = Path("out"),
    duration: Annotated[
        float | None, typer.Option(help="Simulated time [s] instead of the scene's.")
    ] = None,
    formats: Annotated[
        list[str] | None,
        typer.Option("--format", "-f", help="Extra output: mp4, gif, html, usd, glb, obj, pc2."),
    ] = None,
    dry_run: Annotated[
        bool, typer.Option("--dry-run", help="Validate and print counts; write nothing.")
    ] = False,
    energy_tolerance: Annotated[
        float | None,
        typer.Option(
            help="Warn when a conservative scene's energy changes by more than this fraction "
            "(default: the scene's, 0.01)."
        ),
    ] = None,
    camera: CameraOption = None,
    frame: FrameOption = None,
    follow: FollowOption = None,
    force: ForceOption = False,
) -> None:
    """Run a scene: recording.h5, summary.json and the requested outputs into a directory."""
    from ..scenes import dry_run as plan
    from ..scenes import load_model, run_scene, with_view

    model = with_view(load_model(scene), camera, frame, follow)
    if dry_run:
        estimate = plan(model, duration=duration, formats=formats or ())
        what = _held(model)
        limit, settings = estimate.max_stable_dt, model.integration
        # The integrator takes steps of h = dt / substeps: that is what must be stable.
        h = settings.dt / settings.substeps
        step = f"h = dt / {settings.substeps} = {h:.4g} s" if settings.substeps > 1 else "dt"
        advice = (
            "no stable-step advice (the advisor does not linearize rigid bodies)"
            if limit is None
            else "no step limit from the linearization"
            if math.isinf(limit)
            else f"largest stable step for {settings.method} ≈ {limit:.4g} s"
            + (f" ({step} is above it!)" if h > limit else f" ({step} is within it)")
        )
        substeps = f" ({settings.substeps} substeps each)" if settings.substeps > 1 else ""
        typer.echo(f"{scene}: {what}, {estimate.steps} steps of dt = {settings.dt:.6g} s{substeps}")
        typer.echo(f"recording: {estimate.frames} frames; {advice}")
        typer.echo(f"would write: {', '.join(estimate.outputs)} into {output}")
        return
    report = run_scene(
        model,
        output,
        duration=duration,
        formats=formats or (),
        force=force,
        energy_tolerance=energy_tolerance,
    )
    print_report(report)


@app.command("validate")
def validate_command(scene: SceneArgument) -> None:
    """Check a scene file and report every problem at once (exit status 2 if any)."""
    from ..scenes import load_model

    model = load_model(scene)
    what = _held(model)
    typer.echo(f"{scene}: valid ({what}, method {model.integration.method})")


def _held(model: Any) -> str:
    """What a scene holds: "400 particles, system pendulum, 3 rigid bodies"."""
    held = [f"{model.particle_count} particles"] if model.particle_count else []
    held += [f"system {s.system}" for s in model.systems]
    if model.body_count:
        held.append(f"{model.body_count} rigid bod{'y' if model.body_count == 1 else 'ies'}")
    return ", ".join(held)


@app.command("schema")
def schema_command() -> None:
    """Print the JSON Schema of scene files (for editor completion)."""
    from ..model.scene import Scene

    print_json(Scene.model_json_schema())


@app.command("plot")
def plot_command(
    recording: RecordingArgument,
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Image file (default: next to it).")
    ] = None,
    energy: Annotated[bool, typer.Option("--energy", help="Energy over time.")] = False,
    momentum: Annotated[bool, typer.Option("--momentum", help="Momenta over time.")] = False,
    run: RunOption = None,
    force: ForceOption = False,
) -> None:
    """Plot a recording: energy or momenta over time (default: energy if it was recorded)."""
    from ..errors import ModelError
    from ..io.recording import load_recording, read_recordings
    from ..viz.plots import has_momenta, plot_energy, plot_momentum

    if energy and momentum:
        raise ModelError("choose one of --energy and --momentum per plot")
    runs = read_recordings(recording)
    if run is not None:
        runs = {run: load_recording(recording, run)}
    with_energy = {name: r for name, r in runs.items() if "energy" in r and r.frames > 0}
    kind = "momentum" if momentum or (not energy and not with_energy) else "energy"
    if kind == "energy" and not with_energy:
        raise ModelError(
            f"{recording} has no energy to plot (fields: {_fields(runs)}); "
            "try --momentum for a particle recording"
        )
    if kind == "momentum":
        if len(runs) > 1:
            raise ModelError(
                f"{recording} holds {len(runs)} runs ({', '.join(runs)}); choose one with "
                "--run NAME for --momentum"
            )
        (chosen,) = runs.values()
        if not has_momenta(chosen):
            # --momentum on a recording with energy (a named system's): it has energy to plot.
            has = "no momenta" if with_energy else "neither energy nor momenta"
            instead = "; without --momentum, its energy" if with_energy else ""
            raise ModelError(
                f"{recording} has {has} to plot (fields: {_fields(runs)}); momenta need the "
                f"positions, velocities and masses of a particle recording{instead}"
            )
    target = output or recording.with_name(f"{kind}.png")
    check_figure_file(target, force)
    figure = plot_momentum(chosen) if kind == "momentum" else plot_energy(with_energy)
    save_figure(figure, target)
    typer.echo(f"wrote {target}")


def _fields(runs: dict[str, Any]) -> str:
    names = dict.fromkeys(name for r in runs.values() for name in r.fields)
    return ", ".join(names) or "none"


@app.command("view")
def view_command(
    recording: RecordingArgument,
    output: Annotated[
        Path | None,
        typer.Option("--output", "-o", help="HTML file (default: viewer.html next to it)."),
    ] = None,
    fps: FpsOption = None,
    speed: SpeedOption = None,
    trail: TrailOption = None,
    color_by: ColorByOption = None,
    run: RunOption = None,
    camera: CameraOption = None,
    frame: FrameOption = None,
    follow: FollowOption = None,
    force: ForceOption = False,
) -> None:
    """Write the single-file web viewer of a recording (open it in any browser)."""
    from ..io.files import check_new_file
    from ..io.recording import load_recording
    from ..viz.outputs import playback
    from ..viz.viewer import write_viewer

    target = output or recording.with_name("viewer.html")
    check_new_file(target, force=force)
    source = load_recording(recording, run)
    chosen = playback(source, speed, trail, color_by, camera, frame, follow)
    written = write_viewer(
        source,
        target,
        fps=fps,
        speed=chosen.speed,
        trail=chosen.trail,
        color_by=chosen.color_by,
        camera=chosen.camera,
        frame=chosen.frame,
        follow=chosen.follow,
    )
    typer.echo(f"wrote {written}; open it in a browser (file://{written.resolve()})")


@app.command("export")
def export_command(
    recording: RecordingArgument,
    to: Annotated[str, typer.Option("--to", help="usd, glb, obj, pc2, mp4 or gif.")],
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Output file (default: next to it).")
    ] = None,
    fps: FpsOption = None,
    speed: SpeedOption = None,
    trail: TrailOption = None,
    color_by: ColorByOption = None,
    size: Annotated[
        str | None,
        typer.Option("--size", help="Video size WIDTHxHEIGHT in pixels (mp4, gif), e.g. 1280x720."),
    ] = None,
    run: RunOption = None,
    camera: CameraOption = None,
    frame: FrameOption = None,
    follow: FollowOption = None,
    force: ForceOption = False,
) -> None:
    """Export a recording for Blender/Houdini (USD, glTF, OBJ, PC2) or as a video."""
    from .._registry import did_you_mean
    from ..errors import ModelError
    from ..io.files import check_new_file
    from ..io.recording import load_recording
    from ..viz.outputs import OUTPUT_FILES, playback

    formats = ("usd", "glb", "obj", "pc2", "mp4", "gif")
    if to not in formats:
        raise ModelError(
            f"unknown export format {to!r}.{did_you_mean(to, formats)} Valid: {', '.join(formats)}"
        )
    video = to in ("mp4", "gif")
    if size is not None and not video:
        raise ModelError(f"--size {size} sets a video's size; it does not apply to --to {to}")
    pixels = _video_size(size) if size is not None else (960, 540)
    default = recording.with_name(OUTPUT_FILES[to])
    target = output or default
    if to == "obj" and target.is_dir():
        if any(target.glob("*.obj")) and not force:
            raise ModelError(f"{target} already holds OBJ files; pass --force to replace them")
    else:
        check_new_file(target, force=force)
    source = load_recording(recording, run)
    chosen = playback(source, speed, trail, color_by, camera, frame, follow)
    if video:
        from ..viz.video import render_video

        written = [
            render_video(
                source,
                target,
                fps=30.0 if fps is None else fps,
                size=pixels,
                speed=chosen.speed,
                trail=chosen.trail,
                color_by=chosen.color_by,
                camera=chosen.camera,
                frame=chosen.frame,
                follow=chosen.follow,
                labels=chosen.labels,
            )
        ]
    else:
        from ..io.export import export_recording

        written = export_recording(source, target, to=to, fps=fps, speed=chosen.speed)
    if to == "obj":
        folder = written[0].parent
        typer.echo(f"wrote {len(written)} OBJ files into {folder}/ ({written[0].name} …)")
    else:
        for path in written:
            typer.echo(f"wrote {path}")


def _video_size(text: str) -> tuple[int, int]:
    """``"1280x720"`` → ``(1280, 720)``; the renderer checks the range and evenness."""
    from ..errors import ModelError

    width, _, height = text.lower().partition("x")
    if not (width.isdigit() and height.isdigit()):
        raise ModelError(f"--size must be WIDTHxHEIGHT in pixels, such as 1280x720 (got {text!r})")
    return int(width), int(height)
