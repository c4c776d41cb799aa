"""Writing files so that nothing partial is ever seen under the real name.

A file is written to a hidden temporary name in the target's directory and renamed over the
target only once complete (a rename within one file system is atomic). Temporary files are
created private (mode 0600); before the rename they get the permissions an ordinary new file
would have (``0666`` minus the umask), so others can read recordings and plots as usual.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

__all__ = ["atomic_path"]


def _default_mode() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path next to ``target``; on success rename it to ``target``.

    On any exception the temporary file is removed and ``target`` is left untouched.

    Example:
        >>> import pathlib, tempfile
        >>> target = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
        >>> with atomic_path(target) as path:
        ...     _ = path.write_text("complete")
        >>> target.read_text()
        'complete'
    """
    destination = Path(target)
    handle, name = tempfile.mkstemp(
        dir=destination.parent, prefix=f".{destination.name}.", suffix=destination.suffix
    )
    os.close(handle)
    temporary = Path(name)
    try:
        yield temporary
        os.chmod(temporary, _default_mode())
        os.replace(temporary, destination)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
