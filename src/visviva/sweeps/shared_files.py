"""Runs done on other machines: their files must be visible where the sweep is gathered.

Each run writes its own directory from the process that ran it. On a cluster that process is
on another machine, so the sweep's directory must be on a file system the workers share,
mounted at the same path. :class:`SharedFiles` checks it for every run that comes back from an
executor other than the sweep's own pool: one ``stat`` of the run's ``run.json``. A run whose
file is not there is looked at again at the end of the sweep, all such runs together, for up
to :data:`GRACE` seconds (a shared file system may show a new file a moment late); a run still
missing then is recorded as failed with an error that says what to fix, never dropped.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["GRACE", "SharedFiles"]

#: Seconds the runs whose files are missing get, all together, to appear at the end.
GRACE = 5.0
#: Seconds between two looks at them.
_POLL = 0.1


class SharedFiles:
    """Pass on the rows of runs whose record file is visible here; hold back the others.

    Args:
        collect: Where rows go (the sweep's collector; returns false to stop the sweep).
        record: The name of the file each run writes last (``run.json``).
    """

    def __init__(self, collect: Callable[[dict[str, Any]], bool], record: str) -> None:
        self._collect = collect
        self._record = record
        self._missing: list[tuple[Path, dict[str, Any]]] = []

    def __call__(self, row: dict[str, Any], directory: str) -> bool:
        """Take the row of the run done in ``directory``; return what the collector says."""
        marker = Path(directory) / self._record
        if "interrupted" in row or marker.exists():  # a stopped run left no files: by design
            return self._collect(row)
        self._missing.append((marker, row))
        return True

    def settle(self, wait: bool) -> None:
        """Pass on the held-back rows: as they are if their files appeared (within
        :data:`GRACE` seconds if ``wait``), else as failed runs saying why."""
        deadline = time.monotonic() + (GRACE if wait else 0.0)
        while True:
            still = []
            for marker, row in self._missing:
                if marker.exists():
                    self._collect(row)
                else:
                    still.append((marker, row))
            self._missing = still
            if not still or time.monotonic() >= deadline:
                break
            time.sleep(_POLL)
        for marker, row in self._missing:
            error = (
                f"the worker wrote run {row['index']}'s files where this machine cannot see "
                f"them ({marker} is missing here): use an output directory on a file system "
                "shared with the workers, mounted at the same path"
            )
            if row.get("error"):
                error += f"; the run itself reported: {row['error']}"
            self._collect(row | {"success": False, "error": error})
        self._missing = []
