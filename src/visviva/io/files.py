"""Writing files so that nothing partial is ever seen under the real name.

A file is written to a hidden temporary name in the target's directory and renamed over the
target only once complete (a rename within one file system is atomic). Temporary files are
created private (mode 0600); before the rename they get the permissions an ordinary new file
would have (``0666`` minus the umask), so others can read recordings and plots as usual.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ..errors import ModelError

__all__ = ["atomic_path", "check_directory", "check_new_file"]


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


def check_directory(path: str | os.PathLike[str], what: str = "output directory") -> None:
    """Refuse, before any work, a directory that cannot be created or written.

    ``path`` may not exist yet: then its nearest existing ancestor must be a directory in which
    files can be created (checked by creating and removing a probe file), so that ``-o
    afile/out`` or ``-o /proc/out`` fail at once instead of after the simulation.
    """
    target = Path(path)
    if target.exists() and not target.is_dir():
        raise ModelError(f"{what} {os.fspath(target)!r} is a file, not a directory")
    _check_creatable(target if target.exists() else target.parent, target, what)


def check_new_file(
    path: str | os.PathLike[str],
    *,
    force: bool,
    suffixes: tuple[str, ...] | None = None,
    what: str = "output",
) -> None:
    """Refuse, before any work, an output file that cannot or must not be written.

    Args:
        path: The file to write; missing parent directories will be created.
        force: Allow replacing an existing file.
        suffixes: Accepted file name endings (lower case, with the dot), or ``None``.
        what: What the file is, for messages.
    """
    target = Path(path)
    if suffixes is not None and target.suffix.lower() not in suffixes:
        raise ModelError(
            f"{what} {os.fspath(target)!r} must end in {', '.join(suffixes)} "
            f"(got {target.suffix or 'no suffix'!r})"
        )
    if target.is_dir():
        raise ModelError(
            f"{what} {os.fspath(target)!r} is a directory; give a file name such as "
            f"{os.fspath(target / ('output' + (suffixes[0] if suffixes else '')))}"
        )
    if target.exists() or target.is_symlink():
        if not force:
            raise ModelError(f"{os.fspath(target)} already exists; pass --force to replace it")
        if not stat.S_ISREG(target.stat().st_mode):
            raise ModelError(f"{what} {os.fspath(target)!r} is not a regular file")
    _check_creatable(target.parent, target, what)


def _check_creatable(directory: Path, target: Path, what: str) -> None:
    """``directory`` (or its nearest existing ancestor) accepts new files."""
    ancestor = directory
    while not ancestor.exists() and ancestor != ancestor.parent:
        if ancestor.is_symlink():
            break  # a dangling link: the probe below reports it
        ancestor = ancestor.parent
    if ancestor.exists() and not ancestor.is_dir():
        raise ModelError(
            f"cannot create {what} {os.fspath(target)!r}: {os.fspath(ancestor)!r} is a file, "
            "not a directory"
        )
    try:
        handle, name = tempfile.mkstemp(prefix=".visviva-probe-", dir=ancestor)
    except OSError as exc:
        raise ModelError(
            f"cannot create {what} {os.fspath(target)!r}: {exc.strerror or exc} in "
            f"{os.fspath(ancestor)!r}; choose another location"
        ) from None
    os.close(handle)
    os.unlink(name)
