"""Saying when Numba compiles, so that a first run never waits in silence.

The first run of a scene compiles its kernels to machine code, which can take tens of seconds
on a small machine; later runs load them from Numba's cache (``NUMBA_CACHE_DIR``) in a moment.
Numba reports each compilation — never a load from the cache — as a ``numba:compile`` event;
a listener counts them and says so: on the ``visviva`` logger at INFO (silent unless a script
configures logging) and, once :func:`tell` has been given a writer (the CLI on a terminal),
on the terminal: a line when compiling starts, a line that counts the kernels and seconds while
it goes on (rewritten in place), a line when it is done. The entry points that lead to
compiling (building a model, a simulation, a solve, an ensemble) call :func:`watch_compiles`.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

__all__ = ["Echo", "tell", "watch_compiles"]

logger = logging.getLogger("visviva")

#: Writes a line; ``transient`` lines are rewritten in place by the next one.
Echo = Callable[[str, bool], None]

#: Seconds without a compilation after which a burst of them is done.
QUIET = 1.0

STARTED = "compiling kernels for this scene, first run only (later runs load them from the cache)"


class _CompileWatch:
    """Counts compiled functions across threads; a burst lasts while top-level compilations
    (a kernel's callees compile inside it) follow each other."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.depth = threading.local()
        self.kernels = 0  # functions compiled in this burst, callees included
        self.compiling = ""  # the top-level function being compiled
        self.underway = 0  # top-level compilations in progress, over all threads
        self.began = 0.0  # when the current burst of compilations began [perf_counter s]
        self.last = 0.0  # when the last compilation ended
        self.bursts = 0
        self.echo: Echo | None = None
        self.ticker: threading.Thread | None = None

    def on_start(self, event: Any) -> None:
        depth = getattr(self.depth, "value", 0)
        self.depth.value = depth + 1
        if depth:
            return
        function = getattr(event.data.get("dispatcher"), "py_func", None)
        with self.lock:
            self.compiling = getattr(function, "__name__", "")
            if self.underway == 0 and self.ticker is None:
                self.began, self.kernels = time.perf_counter(), 0
                self._say(STARTED + "…" if self.bursts == 0 else "compiling more kernels…")
                self.bursts += 1
                self.ticker = threading.Thread(target=self._tick, daemon=True)
                self.ticker.start()
            self.underway += 1

    def on_end(self, _event: object) -> None:
        self.depth.value -= 1
        with self.lock:
            self.kernels += 1
            if self.depth.value == 0:
                self.underway -= 1
                self.last = time.perf_counter()

    def _tick(self) -> None:
        """Count the kernels and seconds while compiling goes on; end once it has stopped."""
        while True:
            time.sleep(0.25)
            with self.lock:
                now = time.perf_counter()
                if self.underway == 0 and now - self.last > QUIET:
                    functions = f"{self.kernels} function{'s' if self.kernels != 1 else ''}"
                    self._say(f"compiled {functions} in {self.last - self.began:.0f} s")
                    self.ticker = None
                    return
                if self.echo is not None:
                    seconds = now - self.began
                    what = f" {self.compiling}" if self.underway else ""
                    line = f"  compiling{what}… {self.kernels} functions done, {seconds:.0f} s"
                    self.echo(line, True)

    def _say(self, line: str) -> None:
        logger.info(line)
        if self.echo is not None:
            self.echo(line, False)


_WATCH = _CompileWatch()
_installed = False
_install_lock = threading.Lock()


def watch_compiles() -> None:
    """Listen for Numba's compilations (once per process; cheap to call again)."""
    global _installed
    with _install_lock:
        if _installed:
            return
        from numba.core import event

        class Listener(event.Listener):
            def on_start(self, event: event.Event) -> None:
                _WATCH.on_start(event)

            def on_end(self, event: event.Event) -> None:
                _WATCH.on_end(event)

        event.register("numba:compile", Listener())
        _installed = True


def tell(echo: Echo | None) -> None:
    """Also write the compile lines with ``echo(line, transient)`` (``None``: log them only).

    Imports nothing: the listening starts where work that compiles begins (building a model,
    a simulation, a solve), so a command that compiles nothing stays quick to start."""
    _WATCH.echo = echo
