"""How a unit's inputs and outputs travel: as bytes by relative path, read by the driver
(:func:`read_files`, :func:`folder_files`) and written where a worker or the driver needs
them (:func:`write_files`), so that no backend needs a shared filesystem."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path


def read_files(folder: str | os.PathLike[str], names: Sequence[str]) -> dict[str, bytes]:
    """The bytes of ``names`` in ``folder``: how a unit's inputs travel to its worker."""
    return {name: (Path(folder) / name).read_bytes() for name in names}


def folder_files(folder: str | os.PathLike[str]) -> dict[str, bytes]:
    """Every file under ``folder`` by its relative path (``run-0/reward.pt``), sorted: how a
    unit computed in a scratch folder returns its outputs."""
    root = Path(folder)
    return {
        path.relative_to(root).as_posix(): path.read_bytes()
        for path in sorted(root.rglob("*"))
        if path.is_file()
    }


def write_files(folder: str | os.PathLike[str], files: Mapping[str, bytes]) -> Path:
    """Write ``files`` into ``folder`` (created, as are subfolders named in ``files``): how a
    worker lands its inputs."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in files.items():
        path = folder / name  # names may hold subfolders: "run-0/reward.pt"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    return folder
