"""Folders a process owns in the temporary folder: a worker's scratch folder
(``pokerirl-scratch-<pid>-*``, tempfile's folder while the worker lives), a private Ray
instance's (``pokerirl-ray-<pid>-*``), each locked by its owner, and
:func:`sweep_leftovers`, which removes those of processes that are gone."""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
from pathlib import Path

from pokerirl import atomic
from pokerirl.execution.processes import _running

SCRATCH_PREFIX = "pokerirl-scratch-"  # + the owner's pid: a worker's temporary files
PRIVATE_RAY_PREFIX = "pokerirl-ray-"  # + the driver's pid: a private Ray instance's folder


_scratch: tuple[Path, int | None] | None = None  # this process's scratch folder and its lock


def _owned_folder(prefix: str, parent: str | None) -> tuple[Path, int | None]:
    """A new folder ``<prefix><pid>-*`` in ``parent``, locked by this process (the lock's
    descriptor, to close when the folder goes)."""
    folder = Path(tempfile.mkdtemp(prefix=f"{prefix}{os.getpid()}-", dir=parent))
    return folder, atomic.lock_folder(folder)


def _enter_scratch(temp: str) -> Path:
    """This process's scratch folder in ``temp`` (made on the first call, after removing the
    leftovers of processes that are gone), and tempfile's folder from now on: whatever units
    leave there goes with it."""
    global _scratch
    if _scratch is None:
        sweep_leftovers(temp)
        _scratch = _owned_folder(SCRATCH_PREFIX, temp)
        tempfile.tempdir = str(_scratch[0])
        atexit.register(_leave_scratch)
    return _scratch[0]


def _leave_scratch() -> None:
    global _scratch
    if _scratch is not None:
        (folder, lock), _scratch = _scratch, None
        tempfile.tempdir = None
        shutil.rmtree(folder, ignore_errors=True)
        if lock is not None:
            os.close(lock)


def sweep_leftovers(temp: str | os.PathLike[str] | None = None) -> list[Path]:
    """Remove the scratch and private-Ray folders in ``temp`` (default: the temporary folder)
    left by processes that are gone: the pid in the name is not running, and nobody holds the
    folder's lock. Returns the folders removed."""
    removed: list[Path] = []
    try:
        entries = list(Path(temp or tempfile.gettempdir()).iterdir())
    except OSError:
        return removed
    for folder in entries:
        prefix = next(
            (p for p in (SCRATCH_PREFIX, PRIVATE_RAY_PREFIX) if folder.name.startswith(p)), None
        )
        owner = folder.name[len(prefix) :].partition("-")[0] if prefix else ""
        if not owner.isdecimal() or _running(int(owner)) or not folder.is_dir():
            continue
        lock = atomic.lock_folder(folder)
        if lock is None:  # a process it was handed to still holds it
            continue
        try:
            shutil.rmtree(folder, ignore_errors=True)
        finally:
            os.close(lock)
        removed.append(folder)
    return removed
