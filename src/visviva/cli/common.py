"""What every ``visviva`` command shares: the app, common options and file helpers."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer

app = typer.Typer(
    name="visviva",
    help="Physically based animation: time integration, mechanics and simulation.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    # Plain help text: rich markup would eat units written as "[s]" and tag every flag <bool>.
    rich_markup_mode=None,
)

JsonOption = Annotated[bool, typer.Option("--json", help="Print machine-readable JSON.")]
ForceOption = Annotated[bool, typer.Option("--force", help="Replace existing output files.")]
CameraOption = Annotated[
    str | None,
    typer.Option(
        "--camera",
        help='The view of the video and the viewer: "eye=X,Y,Z target=X,Y,Z [up=X,Y,Z] '
        "[fov=DEGREES]\" [m]; default: the run's, else a framing (--frame).",
    ),
]
FollowOption = Annotated[
    str | None,
    typer.Option(
        "--follow",
        help="A rigid body the camera of the video and the viewer follows (it moves with it); "
        "default: the run's, else a still camera.",
    ),
]
FrameOption = Annotated[
    str | None,
    typer.Option(
        "--frame",
        help="Without --camera, what the view keeps in the picture for the whole run: all, "
        "or the name of one rigid body; default: the run's, else all.",
    ),
]


def print_json(data: Any) -> None:
    """Print ``data`` as indented JSON (NumPy values unwrapped)."""
    from ..io.json_values import plain_json

    typer.echo(json.dumps(plain_json(data), indent=2, allow_nan=False))


#: File types a figure may be saved as (matplotlib's Agg back end writes them all).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg", ".webp", ".eps", ".tif", ".tiff")


def check_figure_file(path: Path, force: bool) -> None:
    """Refuse, before any work, a figure file that cannot or must not be written."""
    from ..io.files import check_new_file

    check_new_file(path, force=force, suffixes=FIGURE_SUFFIXES, what="figure")


def save_figure(figure: Any, path: Path) -> None:
    """Save (creating missing directories) so that the file appears complete or not at all."""
    from ..io.files import atomic_path

    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as temporary:
        figure.savefig(temporary, dpi=110, format=path.suffix.lstrip(".").lower())


def print_report(report: Any) -> None:
    """The few lines that end ``run`` and ``demo``: what ran, how long, energy, warnings, files.

    Args:
        report: A :class:`~visviva.io.job.JobReport`.
    """
    summary = report.summary
    what = summary.get("scene") or summary.get("demo")
    typer.echo(f"{what}: {_steps(summary)} in {summary['wall_time_s']:.3g} s")
    if "interrupted" in summary:
        reached = summary.get("t_reached_s")
        at = f" at t = {reached:.6g} s of {summary['duration_s']:.6g} s" if reached else ""
        typer.echo(f"interrupted by {summary['interrupted']}{at}; kept what was finished")
    elif not summary.get("success", True):
        typer.echo(f"failed: {summary['message']}")
    for line in _energy_lines(summary):
        typer.echo(line)
    for warning in summary.get("warnings", []):
        count = f" ({warning['count']}×)" if warning.get("count", 1) > 1 else ""
        typer.echo(f"warning: {warning['message']}{count}")
    shown, runs = summary.get("outputs_show_run"), summary.get("runs", {})
    if shown is not None and len(runs) > 1:
        typer.echo(
            f"the video, viewer and exports show run {shown!r} of {len(runs)} "
            f"({', '.join(runs)}); `visviva export recording.h5 --run NAME` shows another"
        )
    for stale in report.removed_stale:
        typer.echo(f"removed {stale}, left by a run that was killed")
    if report.files:
        folder = report.files[0].parent
        names = ", ".join(f.name + ("/" if f.is_dir() else "") for f in report.files)
        typer.echo(f"wrote {names} into {folder}{'/' if str(folder) != '/' else ''}")


def _energy_lines(summary: dict[str, Any]) -> list[str]:
    """The energy change of conservative runs as a drift (the integrator's error); of the
    others as energy dissipated or gained, which is the physics and not an error."""
    runs = summary.get("runs") or {"": summary}
    changes: dict[bool, dict[str, float]] = {True: {}, False: {}}
    for name, run in runs.items():
        if run.get("energy_drift") is not None:
            changes[bool(run.get("conservative", True))][name] = float(run["energy_drift"])
    lines = []
    for conservative, found in changes.items():
        if not found:
            continue
        worst = max(found, key=lambda name: abs(found[name]))
        change, many = found[worst], len(found) > 1
        of = f" ({worst})" if many else ""
        if conservative:
            size = f"{'up to ' if many else ''}{100 * change:+.3g} %"
            lines.append(f"energy drift: {size} of the initial energy{of}")
        else:
            size = f"{'up to ' if many else ''}{100 * abs(change):.3g} %"
            word = "dissipated" if change < 0 else "gained"
            lines.append(
                f"energy {word}: {size} of the initial energy{of} "
                "(not conservative: the forces do this, not the integrator)"
            )
    return lines


def _steps(summary: dict[str, Any]) -> str:
    """How many steps a job took, each of ``dt`` (its substeps, ``steps`` in the summary
    counts, said apart): "240 steps of symplectic_euler (dt = 0.0167 s, 80 substeps each)"."""
    runs = summary.get("runs") or {"": summary}
    steps = sum(int(r.get("steps", 0)) // max(int(r.get("substeps", 1)), 1) for r in runs.values())
    text = f"{steps} steps"
    if "method" in summary:
        text += f" of {summary['method']} (dt = {summary['dt']:g} s"
        substeps = int(summary.get("substeps", 1))
        text += f", {substeps} substeps each)" if substeps > 1 else ")"
    elif any(int(r.get("substeps", 1)) > 1 for r in runs.values()):
        total = sum(int(r.get("steps", 0)) for r in runs.values())
        text += f" ({total} substeps)"
    return text
