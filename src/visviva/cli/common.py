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
)

JsonOption = Annotated[bool, typer.Option("--json", help="Print machine-readable JSON.")]
ForceOption = Annotated[bool, typer.Option("--force", help="Replace existing output files.")]


def print_json(data: Any) -> None:
    """Print ``data`` as indented JSON (NumPy values unwrapped)."""
    from ..io.job import plain_json

    typer.echo(json.dumps(plain_json(data), indent=2, allow_nan=False))


def check_new_file(path: Path, force: bool) -> None:
    from ..errors import ModelError

    if path.is_dir():
        raise ModelError(f"output {path} is a directory; give a file name such as {path}/plot.png")
    if path.exists() and not force:
        raise ModelError(f"{path} already exists; pass --force to replace it")
    if not path.parent.exists():
        raise ModelError(f"directory {path.parent} does not exist")


def save_figure(figure: Any, path: Path) -> None:
    """Save so that the file appears complete or not at all."""
    from ..io.files import atomic_path

    with atomic_path(path) as temporary:
        figure.savefig(temporary, dpi=110, format=path.suffix.lstrip(".") or "png")
