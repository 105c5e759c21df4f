"""Atomic file writes: write a temporary file beside the target, then rename it into place.

A crash or a kill never leaves a half-written file at the target, and an existing file
survives a failed write. Errors name the target, never the hidden temporary file: a target
that is a folder, or a folder that cannot be written, is an ``OSError`` whose ``filename`` is
the path the caller gave.

>>> import tempfile, pathlib
>>> target = pathlib.Path(tempfile.mkdtemp()) / "note.txt"
>>> write_text(target, "hello")
>>> target.read_text()
'hello'
"""

from __future__ import annotations

import errno
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it to ``path``, else delete it.

    Raises:
        IsADirectoryError: ``path`` is a folder (checked before anything is written).
        OSError: the folder cannot be written, or the block failed to write the temporary
            file; ``filename`` is ``path``.
    """
    target = Path(path)
    if target.is_dir():
        raise IsADirectoryError(errno.EISDIR, "is a folder, not a file", os.fspath(target))
    with naming(target):
        handle, temporary = tempfile.mkstemp(
            prefix=f".{target.name}.", suffix=".tmp", dir=target.parent
        )
        os.close(handle)
        try:
            # mkstemp creates 0600; give the file the mode a plain open() would (0666 less
            # the umask).
            os.chmod(temporary, 0o666 & ~current_umask())
            yield Path(temporary)
            os.replace(temporary, target)
        except BaseException:
            Path(temporary).unlink(missing_ok=True)
            raise


@contextmanager
def naming(target: str | os.PathLike[str]) -> Iterator[None]:
    """Re-raise an ``OSError`` of the block about a hidden temporary path of ``target`` (one
    whose name, or a folder's name in it, starts with ``.<target name>.``), or about no path,
    as the same error about ``target``: temporary paths mean nothing to the user. Errors
    about other files pass unchanged.

    >>> try:
    ...     with naming("out/table.parquet"):
    ...         open("out/.table.parquet.x1y2.tmp/nowhere")
    ... except FileNotFoundError as error:
    ...     print(error)
    [Errno 2] No such file or directory: 'out/table.parquet'
    """
    hidden = f".{Path(target).name}."
    try:
        yield
    except OSError as error:
        about = error.filename
        if error.errno is None or not (
            about is None or any(part.startswith(hidden) for part in Path(os.fsdecode(about)).parts)
        ):
            raise
        raise type(error)(error.errno, error.strerror, os.fspath(target)) from None


def current_umask() -> int:
    """The process umask (reading it means setting it; it is put back at once)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    """Atomically write ``data`` to ``path``."""
    with atomic_path(path) as temporary:
        temporary.write_bytes(data)


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Atomically write ``text`` (UTF-8) to ``path``."""
    with atomic_path(path) as temporary:
        temporary.write_text(text, encoding="utf-8")


def write_torch(path: str | os.PathLike[str], obj: object) -> None:
    """Atomically ``torch.save`` ``obj`` to ``path``, with the same bytes for the same ``obj``.

    ``torch.save`` to a file names the zip's inner folder after the file, and a temporary
    file's name is random; saving to memory first keeps the inner name fixed (``archive``).
    """
    import io

    import torch

    buffer = io.BytesIO()
    torch.save(obj, buffer)
    write_bytes(path, buffer.getvalue())


def make_shareable(folder: str | os.PathLike[str]) -> None:
    """Give a folder made by ``tempfile.mkdtemp`` (0700) the mode ``mkdir`` would give it."""
    os.chmod(folder, 0o777 & ~current_umask())


def lock_folder(folder: str | os.PathLike[str]) -> int | None:
    """An exclusive ``flock`` on ``folder`` (released when the process ends, even when killed),
    as an open descriptor to close when done; None if another process holds it or locks are
    unavailable. How a folder's owner says it is still alive."""
    try:
        import fcntl
    except ImportError:  # not POSIX
        return None
    try:
        descriptor = os.open(folder, os.O_RDONLY)
    except OSError:
        return None
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(descriptor)
        return None
    return descriptor
