"""Staged writes: build new entries beside their place, then swap them in as one.

One mechanism for every writer of a folder or of files that belong together (a unit folder,
a run folder, a table and its summary, a file and its record):

1. :func:`tidy` finishes or removes what dead writers left (below);
2. the caller writes the new entries into a private folder ``.<key>.new-XXXXXXXX/new/``
   beside them, locked (``flock``) while its writer lives;
3. commit: that folder is renamed ``.<key>.swap-XXXXXXXX`` (one atomic rename: from here on
   the new entries count, and any later writer or reader finishes the swap);
4. each entry is moved into place: a file by ``os.replace`` (atomic), a folder (or anything
   replaced by a folder) by moving the old one aside into the swap folder first; record
   files (``unit.json``, ``*.unit.json``) go last;
5. the swap folder, with the old entries, is deleted.

A kill at any instant therefore leaves the old entries (before step 3) or the new ones
(after it, once :func:`tidy` has run): never a mix, never a half-written file. The next
writer, or a reader that calls :func:`tidy`, deletes an uncommitted ``.new-`` folder and
finishes a committed ``.swap-`` one, unless its writer is still alive (it holds the lock):
writers of different units in one parent never touch each other's folders, and two writers
of the same key both finish, the later one's entries winning (entry by entry: a unit's record
then vouches only for the files it was written with, and a mismatch is recomputed).

:func:`tidy` also clears what the writers before this module left, by their exact names:
``execution.save_unit_folder``'s ``.<name>.new-*`` and ``.<name>.old-*/x`` (the old folder,
put back if nothing replaced it), ``pokerirl train``'s ``.<name>.XXXXXXXX.tmp`` and
``.<name>.<32 hex>.old`` folders, and ingest's ``.<name>.ingest-*`` work folders.

Errors name the user's path, never a hidden one: a parent that cannot be written is an
``OSError`` whose ``filename`` is ``<parent>/<key>``.

>>> import tempfile
>>> parent = Path(tempfile.mkdtemp())
>>> with staged_files(parent, key="table.parquet") as new:
...     _ = (new / "table.parquet").write_text("rows")
...     _ = (new / "table.summary.json").write_text("{}")
>>> sorted(p.name for p in parent.iterdir())
['table.parquet', 'table.summary.json']
>>> with staged_folder(parent / "run") as run:
...     _ = (run / "reward.pt").write_text("weights")
>>> sorted(p.name for p in (parent / "run").iterdir())
['reward.pt']
"""

from __future__ import annotations

import errno
import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from pokerirl.atomic import naming

NEW, SWAP = "new", "swap"  # .<key>.new-XXXXXXXX (being written), .<key>.swap-XXXXXXXX (committed)
NEW_ENTRIES, OLD_ENTRIES = "new", "old"  # inside either: the new entries, the old ones aside
RECORD_NAME, RECORD_SUFFIX = "unit.json", ".unit.json"
_RANDOM = r"[a-z0-9_]{8}"  # tempfile.mkdtemp's eight random characters


def _pattern(key: str, middle: str) -> re.Pattern[str]:
    return re.compile(rf"\.{re.escape(key)}\.{middle}")


@contextmanager
def staged_files(
    parent: str | os.PathLike[str], *, key: str, make_parent: bool = True
) -> Iterator[Path]:
    """Yield a new empty folder; on success, every entry the block wrote at its top level
    replaces the entry of that name in ``parent`` (a folder whole), all as one swap.

    ``key`` names the write: its hidden folders are ``.<key>.*`` in ``parent`` and its errors
    name ``parent/key``; writers of different keys in one parent never meet. Entries of
    ``parent`` that the block did not write stay. On an exception nothing changes.

    Raises:
        OSError: ``parent`` is missing (and not ``make_parent``) or cannot be written
            (``filename`` is ``parent/key``), or is not a folder (``filename`` is ``parent``).
    """
    parent = Path(parent)
    target = parent / key
    with naming(target):
        if os.path.lexists(parent) and not parent.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, "not a folder", str(parent))
        if not parent.exists():
            if not make_parent:
                raise FileNotFoundError(errno.ENOENT, "its folder does not exist", str(target))
            parent.mkdir(parents=True, exist_ok=True)
        tidy(parent, key=key)
        staging, lock = _claim(parent, key)
    committed = staging.with_name(staging.name.replace(f".{NEW}-", f".{SWAP}-", 1))
    try:
        try:
            (staging / NEW_ENTRIES).mkdir()
            yield staging / NEW_ENTRIES
            with naming(target):
                os.rename(staging, committed)
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
        # Committed: should moving the entries fail (or be interrupted), the swap folder stays
        # for the next tidy to finish.
        with naming(target):
            _roll_forward(parent, committed)
        shutil.rmtree(committed, ignore_errors=True)
    finally:
        _unlock(lock)


@contextmanager
def staged_folder(folder: str | os.PathLike[str], *, make_parent: bool = True) -> Iterator[Path]:
    """Yield a new empty folder that replaces ``folder`` whole on success (see
    :func:`staged_files`; the key is the folder's name)."""
    folder = Path(folder)
    with staged_files(folder.parent, key=folder.name, make_parent=make_parent) as new:
        (new / folder.name).mkdir()
        yield new / folder.name


def tidy(parent: str | os.PathLike[str], *, key: str) -> None:
    """Finish or remove what dead writers of ``key`` left in ``parent`` (see the module's
    docstring); folders whose writer is alive stay. Nothing to do when ``parent`` is not
    a folder or cannot be listed."""
    parent = Path(parent)
    hidden = f".{key}."
    try:  # names first: a parent may hold thousands of units, and each checks its own
        names = sorted(name for name in os.listdir(parent) if name.startswith(hidden))
    except OSError:
        return
    patterns = {
        NEW: _pattern(key, f"{NEW}-{_RANDOM}"),
        SWAP: _pattern(key, f"{SWAP}-{_RANDOM}"),
        "old": _pattern(key, f"old-{_RANDOM}"),  # execution.save_unit_folder's, aside
        "legacy new": _pattern(key, rf"{_RANDOM}\.tmp"),  # pokerirl train's, pre-store
        "legacy old": _pattern(key, r"[0-9a-f]{32}\.old"),  # the same, aside
        "ingest": _pattern(key, f"ingest-{_RANDOM}"),  # ingest's work folder, pre-store
    }
    target = parent / key
    for name in names:
        path = parent / name
        kind = next((k for k, pattern in patterns.items() if pattern.fullmatch(name)), None)
        if kind is None or not _is_folder(path):
            continue  # not a name any writer makes
        with naming(target), _owned(path) as mine:
            if not mine:
                continue  # its writer is alive
            if kind == SWAP:
                _roll_forward(parent, path)
            elif kind in ("old", "legacy old"):
                # A swap of the writers before the store, killed between its two renames: the
                # old folder comes back when nothing replaced it.
                inside = path / "x" if kind == "old" else path
                if not os.path.lexists(target) and inside.is_dir():
                    os.rename(inside, target)
            shutil.rmtree(path, ignore_errors=True)


def _roll_forward(parent: Path, swap: Path) -> None:
    """Move the committed entries of ``swap`` into ``parent``, records last."""
    new, old = swap / NEW_ENTRIES, swap / OLD_ENTRIES
    names = sorted(entry.name for entry in new.iterdir()) if new.is_dir() else []
    for name in sorted(names, key=lambda n: n == RECORD_NAME or n.endswith(RECORD_SUFFIX)):
        source, place = new / name, parent / name
        if os.path.lexists(place) and (source.is_dir() or _is_folder(place)):
            old.mkdir(exist_ok=True)
            aside = old / name
            if os.path.lexists(aside):
                shutil.rmtree(aside, ignore_errors=True)
            os.rename(place, aside)
        os.replace(source, place)


def _is_folder(path: Path) -> bool:
    return path.is_dir() and not path.is_symlink()


def _claim(parent: Path, key: str) -> tuple[Path, int | None]:
    """A new ``.<key>.new-XXXXXXXX`` folder in ``parent``, locked by this process."""
    for _ in range(100):
        staging = Path(tempfile.mkdtemp(prefix=f".{key}.{NEW}-", dir=parent))
        locked, lock = _lock(staging)
        if locked:
            return staging, lock
        # A tidy of another process took it between mkdtemp and the lock: take another.
    raise BlockingIOError(errno.EAGAIN, "its staging folders keep being removed", str(parent))


@contextmanager
def _owned(path: Path) -> Iterator[bool]:
    """Whether this process could lock ``path`` (its writer is gone), held in the block."""
    try:
        locked, lock = _lock(path)
    except OSError:  # cannot even be opened: leave it
        locked, lock = False, None
    try:
        yield locked
    finally:
        _unlock(lock)


def _lock(path: Path) -> tuple[bool, int | None]:
    """An exclusive ``flock`` on the folder ``path``: (True, descriptor) when this process
    holds it, (True, None) where locks are unavailable (no owner can be told apart), (False,
    None) when another process holds it or ``path`` is gone.

    Raises:
        OSError: ``path`` exists but cannot be opened (out of descriptors, say).
    """
    try:
        import fcntl
    except ImportError:  # not POSIX
        return path.is_dir(), None
    try:
        descriptor = os.open(path, os.O_RDONLY)
    except FileNotFoundError:
        return False, None
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as error:
        os.close(descriptor)
        if error.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            return False, None
        return True, None  # a filesystem without locks
    return True, descriptor


def _unlock(descriptor: int | None) -> None:
    if descriptor is not None:
        os.close(descriptor)
