"""Writing several files as one: all of them appear, or none does.

An export may write more than one file (an OBJ sequence, a ``.gltf`` with its ``.bin``). Each
file is written through :func:`visviva.io.files.atomic_path` to a temporary name, and all of
them are renamed only once every one is complete; if anything fails before or during the
renames, the temporary files are removed and the files already renamed by this call are
deleted again, so a failed export leaves no partial set behind (files it would have replaced
are untouched unless the failure happens during the renames themselves).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from types import TracebackType

from ..files import atomic_path

__all__ = ["all_or_nothing"]

_ExitCallback = Callable[
    [type[BaseException] | None, BaseException | None, TracebackType | None], bool
]


def _note_commit(target: Path, committed: list[Path]) -> _ExitCallback:
    """An exit callback that records ``target`` as renamed when its context exits cleanly."""

    def exit_(
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> bool:
        if kind is None:
            committed.append(target)
        return False

    return exit_


@contextlib.contextmanager
def all_or_nothing(targets: Sequence[Path]) -> Iterator[list[Path]]:
    """Yield one temporary path per target; on success rename each to its target.

    Args:
        targets: Final file names; their directories must exist.

    Yields:
        Temporary paths (same directory and suffix as each target), in the order of
        ``targets``.

    Example:
        >>> import tempfile
        >>> folder = Path(tempfile.mkdtemp())
        >>> with all_or_nothing([folder / "a.txt", folder / "b.txt"]) as (a, b):
        ...     _ = a.write_text("A"), b.write_text("B")
        >>> sorted(p.name for p in folder.iterdir())
        ['a.txt', 'b.txt']
    """
    committed: list[Path] = []
    try:
        with contextlib.ExitStack() as stack:
            temporaries = []
            for target in targets:
                # Pushed before the atomic context, so it runs after that context's rename.
                stack.push(_note_commit(target, committed))
                temporaries.append(stack.enter_context(atomic_path(target)))
            yield temporaries
    except BaseException:
        for target in committed:
            target.unlink(missing_ok=True)
        raise
