"""Runnable demonstrations: ``visviva demo NAME -o DIR`` or :func:`run_demo`.

Each demo runs real simulations through the public API and writes ``recording.h5`` (one run per
method), ``summary.json`` and its figures into the output directory. Demos register themselves
here; the built-in ones are listed in :mod:`~visviva.demos.catalogue`, so that a list of them
(:func:`demo_summaries`) imports none, and running one imports only its module.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .._lazy import lazy_names
from .._registry import Registry
from .catalogue import BUILTIN_DEMOS

if TYPE_CHECKING:
    from ..io.job import JobOutput
    from .runner import run_demo

__all__ = ["Demo", "demo_summaries", "demos", "find_demo", "register_demo", "run_demo"]


@dataclass(frozen=True)
class Demo:
    """A named demonstration.

    Attributes:
        name: Name on the command line.
        summary: One line describing what it shows.
        duration: Default simulated duration [s].
        run: ``run(output, duration)``: simulates, adds recordings and figures to ``output``
            and returns extra summary entries.
        picture: The demo's first recording carries drawable geometry (``points``), so it can
            be written as a video, the web viewer or an export (``visviva demo NAME -f mp4``).
        speed: Simulated seconds per second of those outputs' playback.
        trail: Simulated seconds of each point's path drawn behind it in the video and the
            viewer (0: none).
        color_by: What colours the points of the video and the viewer: ``"scene"`` (the
            recorded colours) or ``"speed"``.
        labels: The video writes each rigid body's name above it (where the lesson depends
            on telling them apart).
        style: How the video and the viewer draw the points: ``"auto"``, ``"day"`` or
            ``"night"`` (spots of light on a night sky: fireworks).
        full: The long version's ``run`` (``visviva demo NAME --full``), for a demo whose
            default is cut down to finish within a minute; ``None`` if there is none.
    """

    name: str
    summary: str
    duration: float
    run: Callable[[JobOutput, float], dict[str, Any]]
    picture: bool = False
    speed: float = 1.0
    trail: float = 0.0
    color_by: str = "scene"
    labels: bool = False
    style: str = "auto"
    full: Callable[[JobOutput, float], dict[str, Any]] | None = None


_DEMOS: Registry[Demo] = Registry("demo")


def register_demo(demo: Demo, *, replace: bool = False) -> Demo:
    """Add a demo to the list shown by ``visviva demo`` and return it.

    Raises:
        ModelError: If a demo of that name is registered and ``replace`` is false.
    """
    return _DEMOS.register(demo, replace=replace)


def demos() -> dict[str, Demo]:
    """Every registered demo by name (importing every built-in one)."""
    for name in BUILTIN_DEMOS:
        _load(name)
    return {name: _DEMOS.get(name) for name in _DEMOS}


def demo_summaries() -> dict[str, str]:
    """Every demo's one-line summary by name, without importing the built-in demos."""
    summaries = {name: builtin.summary for name, builtin in BUILTIN_DEMOS.items()}
    return summaries | {name: _DEMOS.get(name).summary for name in _DEMOS}


def find_demo(name: str) -> Demo:
    """The demo called ``name``, importing only its module if it is a built-in one.

    Raises:
        ModelError: For an unknown name; the message suggests the closest one and lists them
            all.
    """
    if name in BUILTIN_DEMOS:
        _load(name)
    else:  # so that an unknown name is answered with every valid one
        demos()
    return _DEMOS.get(name)


def _load(name: str) -> None:
    """Import built-in demo ``name``'s module, which registers it (once: imports are cached)."""
    importlib.import_module(f".{BUILTIN_DEMOS[name].module}", __name__)


# run_demo loads on first use (visviva._lazy): it brings in the job's files and NumPy, which
# listing the demos does not need.
__getattr__, __dir__ = lazy_names(__name__, __all__, {"run_demo": "runner"})
