"""``visviva sweep``: many runs of one scene with parameters varied (:mod:`visviva.sweeps`)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Annotated, Any

import typer

from .common import app


@app.command("sweep")
def sweep_command(
    description: Annotated[Path, typer.Argument(help="Sweep file (.toml or .json).")],
    output: Annotated[Path, typer.Option("--output", "-o", help="Output directory.")] = Path("out"),
    workers: Annotated[
        int | None,
        typer.Option(
            "--workers", help="Processes of the pool or of the --dask cluster (default: all cores)."
        ),
    ] = None,
    serial: Annotated[
        bool, typer.Option("--serial", help="Run one after the other in this process.")
    ] = False,
    dask: Annotated[
        bool,
        typer.Option("--dask", help="Run on a Dask LocalCluster started on this machine."),
    ] = False,
    scheduler: Annotated[
        str | None,
        typer.Option(
            "--scheduler",
            metavar="ADDRESS",
            help="Run on the Dask cluster whose scheduler is at ADDRESS (tcp://host:8786); "
            "DIR must be on a file system its workers share.",
        ),
    ] = None,
    no_resume: Annotated[
        bool, typer.Option("--no-resume", help="Run again the runs already finished in DIR.")
    ] = False,
    no_batch: Annotated[
        bool,
        typer.Option("--no-batch", help="Run every run alone, never in a batch (same results)."),
    ] = False,
    dry_run: Annotated[
        bool,
        typer.Option("--dry-run", help="Validate, expand and print the runs; write nothing."),
    ] = False,
) -> None:
    """Run a sweep: every run into DIR/runs/, the table into DIR/results.csv, .json and .h5, the
    plots into DIR/plots/ and a page of it all, DIR/index.html."""
    from ..errors import ModelError
    from ..sweeps import SweepFailed, dask_executor, expand, load_sweep, sweep

    on_dask = dask or scheduler is not None
    if serial and (workers is not None or on_dask):
        other = "--workers" if workers is not None else "--scheduler" if scheduler else "--dask"
        raise ModelError(f"--serial runs in this process; drop {other} (or --serial)")
    if scheduler is not None and workers is not None:
        raise ModelError(
            "--workers sizes the pool or the --dask cluster; the cluster at --scheduler has its "
            "own workers: drop --workers"
        )
    chosen = load_sweep(description)
    if dry_run:
        runs = expand(chosen)
        info = chosen.info
        typer.echo(
            f"{description}: sweep {info.name!r}, {info.design} design, {len(runs)} runs, "
            f"all scenes valid; would write into {output}/runs/"
        )
        keys = [run.batch_key for run in runs if run.batch_key is not None]
        groups = [count for count in Counter(keys).values() if count > 1]
        together = sum(groups)
        if together and not no_batch:
            typer.echo(
                f"{together} runs would advance together in batches ({len(groups)} group"
                f"{'s' if len(groups) > 1 else ''} of the same equations or particle entities)"
            )
        paths = list(chosen.paths)
        typer.echo("\t".join(["index", *paths]))
        for run in runs:
            typer.echo("\t".join([str(run.index), *(_shown(run.values[p]) for p in paths)]))
        return
    try:
        if on_dask:
            # Connected (or started) before the sweep begins: a scheduler that does not
            # answer is reported before anything is written.
            with dask_executor(scheduler, workers=workers) as executor:
                result = sweep(
                    chosen, output, executor=executor, resume=not no_resume, batch=not no_batch
                )
        else:
            result = sweep(
                chosen,
                output,
                executor="serial" if serial else None,
                workers=workers,
                resume=not no_resume,
                batch=not no_batch,
            )
    except SweepFailed as failure:  # the table first, then the error line and exit status 1
        _print_result(failure.result)
        raise
    _print_result(result)


def _shown(value: Any) -> str:
    return repr(value) if isinstance(value, float) else str(value)


def _print_result(result: Any) -> None:
    """The lines that end a sweep: counts, failed runs, where the table is."""
    total = len(result.rows)
    reused = f" ({result.skipped} already finished, not run again)" if result.skipped else ""
    typer.echo(f"{total} runs{reused}; {total - result.failed} succeeded, {result.failed} failed")
    for row in result.rows:
        if not row["success"]:
            typer.echo(f"run {row['run']}: {str(row['error']).splitlines()[0]}")
    for warning in result.warnings:
        typer.echo(f"warning: {warning}", err=True)
    names = [file.name for file in result.files if file.parent == result.directory]
    plots = len([file for file in result.files if file.suffix == ".png"])
    drawn = f" and {plots} plot{'s' if plots != 1 else ''} in plots/" if plots else ""
    typer.echo(f"wrote {', '.join(names)}{drawn} into {result.directory}/")
