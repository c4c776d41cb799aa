"""The ``visviva`` command.

Thin by design: each command parses its options and calls the library. Heavy modules (NumPy,
SciPy, Numba, matplotlib) are imported inside the commands, so ``visviva --help`` stays fast.
User errors (:class:`~visviva.errors.ModelError`) print one line and exit with status 2;
numerical failures exit with status 1. The scene and output commands live in
:mod:`visviva.cli.scenes`.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

if TYPE_CHECKING:
    from ..integrators import Integrator
    from ..ode.system import System

from .common import (
    CameraOption,
    FollowOption,
    ForceOption,
    FrameOption,
    JsonOption,
    app,
    check_figure_file,
    print_json,
    print_report,
    save_figure,
)


@app.command("integrators")
def integrators_command(as_json: JsonOption = False) -> None:
    """List the time integrators with their order and properties."""
    from .. import integrators

    methods = [integrators.get(name) for name in integrators.names()]
    if as_json:
        print_json([m.describe() for m in methods])
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title="visviva integrators", title_justify="left")
    table.add_column("name", no_wrap=True)
    table.add_column("order", justify="right")
    table.add_column("kind", no_wrap=True)
    table.add_column("what it does")
    for m in methods:
        kind = (
            ", ".join(
                k
                for k, on in (
                    ("implicit", m.implicit),
                    ("symplectic", m.symplectic),
                    ("adaptive", m.adaptive),
                )
                if on
            )
            or "explicit"
        )
        table.add_row(m.name, str(m.order), kind, m.summary)
    console = Console()
    if not console.is_terminal:
        console.width = 120
    console.print(table)


@app.command("stability")
def stability_command(
    methods: Annotated[list[str], typer.Argument(help="Method names, e.g. rk4 explicit_euler.")],
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Write the region plot (PNG).")
    ] = None,
    as_json: JsonOption = False,
    force: ForceOption = False,
) -> None:
    """Stability intervals on the real and imaginary axes, and region plots."""
    from ..analysis.stability import stability_interval
    from ..integrators import get

    instances = [get(name) for name in methods]
    if output is not None:
        check_figure_file(output, force)
    intervals = {
        m.name: {
            # `+ 0.0` turns a computed -0.0 into 0.0.
            "real": tuple(x + 0.0 for x in stability_interval(m, "real")),
            "imaginary": tuple(x + 0.0 for x in stability_interval(m, "imaginary")),
        }
        for m in instances
    }
    if output is not None:
        from ..viz.plots import plot_stability_regions

        save_figure(plot_stability_regions(instances), output)
    if as_json:
        print_json(
            {name: {axis: list(v) for axis, v in axes.items()} for name, axes in intervals.items()}
        )
        return
    for name, axes in intervals.items():
        real, imaginary = axes["real"], axes["imaginary"]
        typer.echo(
            f"{name:34s} real [{real[0]:.6g}, {real[1]:.6g}]   "
            f"imaginary [{imaginary[0]:.6g}, {imaginary[1]:.6g}]"
        )
    if output is not None:
        typer.echo(f"wrote {output}")


@app.command("convergence")
def convergence_command(
    methods: Annotated[list[str] | None, typer.Argument(help="Methods (default: all).")] = None,
    problem: Annotated[
        str, typer.Option(help="Reference problem: pendulum, forced, damped or first-order.")
    ] = "pendulum",
    until: Annotated[float, typer.Option(help="Time of the error measurement [s].")] = 2.0,
    levels: Annotated[int, typer.Option(help="Number of halved step sizes (at least 3).")] = 8,
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Write the log-log plot (PNG).")
    ] = None,
    as_json: JsonOption = False,
    force: ForceOption = False,
) -> None:
    """Measure each method's order of accuracy against an exact solution."""
    from .._validation import real_number, whole_number
    from ..analysis.reference_problems import reference_problem
    from ..errors import ModelError
    from ..integrators import get, names
    from ..studies.convergence import convergence_order

    levels = whole_number("levels", levels, minimum=3)
    if levels > MAX_LEVELS:
        raise ModelError(
            f"`--levels` must be at most {MAX_LEVELS} (got {levels}): each level halves the "
            "step and doubles the time, and beyond 14 levels round-off hides the truncation "
            "error of every method of order 2 or more"
        )
    until = real_number("until", until, positive=True, unit=" s")
    if until > MAX_CONVERGENCE_TIME:
        raise ModelError(
            f"`--until` must be at most {MAX_CONVERGENCE_TIME:g} s (got {until!r}): the "
            "measured error then mixes in chaos and round-off"
        )
    if output is not None:
        check_figure_file(output, force)
    test = reference_problem(problem)
    system = test.problem.system()
    instances = [get(name) for name in methods] if methods else _applicable(system, names())
    studies = [
        convergence_order(
            test.problem,
            m,
            until=until,
            reference=test.exact,
            dt=[until / (10 * 2**k) for k in range(levels)],
        )
        for m in instances
    ]
    if output is not None:
        from ..viz.plots import plot_convergence

        save_figure(plot_convergence(studies), output)
    rows = [
        {
            "method": s.method,
            "declared_order": s.declared_order,
            "measured_order": s.order,
            "points_fitted": int(s.used.sum()),
            "dt": s.dt.tolist(),
            "error": s.error.tolist(),
        }
        for s in studies
    ]
    if as_json:
        print_json({"problem": problem, "until": until, "methods": rows})
        return
    typer.echo(f"problem: {test.description}, error at t = {until:g} s")
    for row in rows:
        typer.echo(
            f"{row['method']:34s} declared {row['declared_order']}  measured "
            f"{row['measured_order']:.3f}  ({row['points_fitted']} points)"
        )
    if output is not None:
        typer.echo(f"wrote {output}")


#: Most halvings `convergence` makes: at 14 levels the finest step is 2⁻¹³/10 of the span and
#: every method of order ≥ 2 already meets round-off; each further level doubles the time.
MAX_LEVELS = 14
#: Longest span of a convergence measurement [s].
MAX_CONVERGENCE_TIME = 1000.0


def _applicable(system: System, names: list[str]) -> list[Integrator]:
    """The registered methods that can integrate ``system`` (e.g. no Taylor on ``y' = f``)."""
    from ..errors import ModelError
    from ..integrators import get

    methods = []
    for name in names:
        method = get(name)
        try:
            method.check(system)
        except ModelError:
            continue
        methods.append(method)
    return methods


@app.command("equations")
def equations_command(
    system: Annotated[str, typer.Argument(help="A classic system, e.g. double-pendulum.")],
    latex: Annotated[bool, typer.Option("--latex", help="Print LaTeX instead of text.")] = False,
) -> None:
    """Print the equations of motion visviva derives from a classic system's K and U."""
    from .._registry import did_you_mean
    from ..errors import ModelError
    from ..mechanics.classic import LAGRANGIAN_SYSTEMS

    if system not in LAGRANGIAN_SYSTEMS:
        raise ModelError(
            f"unknown system {system!r}.{did_you_mean(system, LAGRANGIAN_SYSTEMS)} "
            f"Available: {', '.join(LAGRANGIAN_SYSTEMS)}"
        )
    derived = LAGRANGIAN_SYSTEMS[system]()
    typer.echo(derived.latex() if latex else derived.text())


#: Methods compared by default: one of each family the notes contrast.
COMPARED = ("explicit_euler", "symplectic_euler", "velocity_verlet", "rk4", "implicit_midpoint")


@app.command("compare")
def compare_command(
    target: Annotated[
        str, typer.Argument(help="A scene file (.toml/.json) or a named system (e.g. pendulum).")
    ],
    methods: Annotated[list[str] | None, typer.Argument(help="Methods to compare.")] = None,
    dt: Annotated[
        float | None, typer.Option(help="Step [s] (default: the scene's, or 1 ms).")
    ] = None,
    duration: Annotated[
        float | None, typer.Option(help="Length of the runs [s] (default: the scene's, or 10 s).")
    ] = None,
    convergence_duration: Annotated[
        float, typer.Option(help="Span of the order measurement [s].")
    ] = 1.0,
    output: Annotated[Path | None, typer.Option("--output", "-o", help="Output directory.")] = None,
    force: ForceOption = False,
) -> None:
    """Run one system under several integrators: energy plot, convergence plot and a table."""
    from .._registry import did_you_mean
    from .._validation import real_number
    from ..entities.system.systems import SYSTEMS
    from ..errors import ModelError
    from ..io.job import JobOutput
    from ..model.builder import SceneBuilder
    from ..scenes import load_model
    from ..studies.compare import compare_methods
    from ..viz.plots import comparison_figures

    if dt is not None:
        dt = real_number("--dt", dt, positive=True, unit=" s")
    if duration is not None:
        duration = real_number("--duration", duration, positive=True, unit=" s")
    if target.endswith((".toml", ".json")) or Path(target).exists():
        model = load_model(target)
        step, span = dt or model.integration.dt, duration or model.integration.duration
        _check_steps(span, step)
    elif target in SYSTEMS:
        step, span = dt or 1e-3, duration or 10.0
        _check_steps(span, step)
        builder = SceneBuilder(name=target)
        builder.set_integration(method="rk4", dt=step, duration=span)
        builder.add_system(target)
        model = builder.build()
    else:
        raise ModelError(
            f"{target!r} is neither a scene file nor a named system.{did_you_mean(target, SYSTEMS)}"
            f" Systems: {', '.join(SYSTEMS)}"
        )
    directory = output if output is not None else Path("out") / f"compare-{_slug(model.name)}"
    job = JobOutput(directory, force=force)
    job.check_target(["recording.h5", "summary.json", "energy.png", "convergence.png"])
    problem = model.problem()
    end = problem.t0 + span
    comparison = compare_methods(
        problem,
        list(methods or COMPARED),
        dt=step,
        until=end,
        convergence_until=problem.t0 + min(convergence_duration, end - problem.t0),
        record_every=max(1, round(span / step / 2000)),
    )
    job.recordings.update(comparison.runs)
    job.figures.update(
        comparison_figures(comparison, title=f"{model.name}: energy, h = {step:g} s")
    )
    table = comparison.table()
    typer.echo(table)
    for path in job.write({"target": target, "table": table} | comparison.as_dict()).files:
        typer.echo(f"wrote {path}")


def _check_steps(span: float, step: float) -> None:
    """Refuse a comparison whose runs would take more steps than any run may."""
    from ..errors import ModelError
    from ..model.model import MAX_STEPS

    if span / step > MAX_STEPS:
        raise ModelError(
            f"a duration of {span!r} s at dt = {step!r} s would take {span / step:.3g} steps per "
            f"method; the limit is {MAX_STEPS:.0e} (use --duration and --dt)"
        )


def _slug(name: str) -> str:
    """``name`` as one safe file name: letters, digits, ``-`` and ``_`` only (no ``..``, no
    ``/``), so a scene's name can never place output outside ``out/``."""
    slug = re.sub(r"[^A-Za-z0-9_-]+", "-", name).strip("-")[:80]
    return slug or "scene"


@app.command("demo")
def demo_command(
    name: Annotated[str | None, typer.Argument(help="Demo to run; omit to list them.")] = None,
    output: Annotated[Path | None, typer.Option("--output", "-o", help="Output directory.")] = None,
    duration: Annotated[float | None, typer.Option(help="Simulated duration [s].")] = None,
    formats: Annotated[
        list[str] | None,
        typer.Option(
            "--format", "-f", help="Also write mp4, gif, html, usd, glb, obj or pc2 (repeatable)."
        ),
    ] = None,
    fps: Annotated[float, typer.Option(help="Frame rate of -f outputs [frames/s].")] = 30.0,
    full: Annotated[
        bool,
        typer.Option(
            "--full", help="The long version of a demo cut down to finish within a minute."
        ),
    ] = False,
    camera: CameraOption = None,
    frame: FrameOption = None,
    follow: FollowOption = None,
    force: ForceOption = False,
) -> None:
    """Run a demonstration and write its recording, summary and figures (no NAME: list them)."""
    if name is None:
        from ..demos import demo_summaries

        for listed, summary in sorted(demo_summaries().items()):
            typer.echo(f"{listed:16s} {summary}")
        return
    from ..demos import run_demo

    directory = output if output is not None else Path("out") / name
    report = run_demo(
        name,
        directory,
        duration=duration,
        formats=formats or (),
        fps=fps,
        force=force,
        full=full,
        camera=camera,
        frame=frame,
        follow=follow,
    )
    print_report(report)


# After the commands above, so that `visviva --help` lists them first.
from . import scenes as _scene_commands  # noqa: E402, F401 - registers run, validate, plot, ...
from . import sweeps as _sweep_commands  # noqa: E402, F401 - registers sweep


def main() -> None:
    """Entry point: run the app; user errors exit 2 with one line, failures exit 1, a run
    stopped by SIGINT/SIGTERM exits 128 + the signal's number (130 for Ctrl-C) after saying
    what it kept."""
    from .._compiling import tell
    from ..errors import ModelError, SimulationError
    from ..simulation.interrupt import Interrupted, exit_status

    if sys.stderr.isatty():  # a first run compiles for a while: say so on a terminal
        tell(_terminal_line)
    try:
        app()
    except ModelError as error:
        _print_kept(error)
        typer.echo(f"error: {error}", err=True)
        sys.exit(2)
    except SimulationError as error:
        _print_kept(error)
        typer.echo(f"simulation failed: {error}", err=True)
        sys.exit(1)
    except Interrupted as error:
        _print_kept(error)
        typer.echo(f"{error}; stopped cleanly", err=True)
        sys.exit(exit_status(error.signal))
    except KeyboardInterrupt:
        typer.echo("interrupted; no partial file was left", err=True)
        sys.exit(130)


def _terminal_line(line: str, transient: bool) -> None:
    """Write ``line`` over the transient line before it; leave it for the next if transient."""
    sys.stderr.write(f"\r\x1b[2K{line}" + ("" if transient else "\n"))
    sys.stderr.flush()


def _print_kept(error: Exception) -> None:
    """The report of the files a failed or interrupted job wrote before it stopped."""
    report = getattr(error, "report", None)
    if report is not None:
        print_report(report)
