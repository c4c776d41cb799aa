"""A progress bar for long runs that stays silent for short ones and when output is not a TTY."""

from __future__ import annotations

import sys
import time
from types import TracebackType
from typing import Any

__all__ = ["Progress"]

#: A bar appears only once a run has taken this long [s]; quick runs print nothing.
SHOW_AFTER = 1.0


class Progress:
    """Counts work done; draws a rich bar on stderr if enabled and the run is long.

    Args:
        total: Total units of work (steps, or simulated seconds for adaptive runs).
        description: Text in front of the bar.
        enabled: ``True`` to allow the bar, ``False`` never, ``None`` (default) only when
            stderr is a terminal.
    """

    def __init__(self, total: float, description: str, enabled: bool | None = None) -> None:
        self.total = total
        self.description = description
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.done = 0.0
        self._start = time.perf_counter()
        self._bar: Any = None
        self._task: Any = None

    def __enter__(self) -> Progress:
        return self

    def advance(self, amount: float) -> None:
        """Record ``amount`` more units of work done."""
        self.done += amount
        if not self.enabled:
            return
        if self._bar is None:
            if time.perf_counter() - self._start < SHOW_AFTER:
                return
            from rich.console import Console
            from rich.progress import BarColumn, TimeRemainingColumn
            from rich.progress import Progress as RichProgress

            self._bar = RichProgress(
                "[progress.description]{task.description}",
                BarColumn(),
                "[progress.percentage]{task.percentage:>3.0f}%",
                TimeRemainingColumn(),
                console=Console(stderr=True),
                transient=True,
            )
            self._bar.start()
            self._task = self._bar.add_task(self.description, total=self.total)
        self._bar.update(self._task, completed=self.done)

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        if self._bar is not None:
            self._bar.stop()
