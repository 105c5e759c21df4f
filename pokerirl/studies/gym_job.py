"""The record of a ``gym rl`` or ``gym expert`` folder: what its outputs were trained with.

A rerun into the same folder with the same settings resumes (finished runs are kept); with
other settings it is refused in one line before anything is touched, unless ``overwrite``,
which removes every earlier output first, so that a rerun killed midway can never leave runs
of two settings side by side.

>>> import tempfile
>>> folder = Path(tempfile.mkdtemp())
>>> claim(folder, "rl.job.json", {"reward": "env"}, outputs=["run-*"], overwrite=False)
>>> (folder / "run-0").mkdir()
>>> claim(folder, "rl.job.json", {"reward": "a.pt"}, outputs=["run-*"], overwrite=False)
... # doctest: +ELLIPSIS
Traceback (most recent call last):
...
pokerirl.store.record.UnitConflict: ...: its outputs were trained with other settings (...)...
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from pokerirl.atomic import write_text
from pokerirl.errors import Remedy
from pokerirl.store import UnitConflict, describe_changes

JOB_FORMAT = "pokerirl-gym-job/1"


def claim(
    folder: Path,
    name: str,
    identity: Mapping[str, Any],
    *,
    outputs: Sequence[str],
    overwrite: bool,
) -> None:
    """Make ``folder/name`` record ``identity``, refusing (``UnitConflict``) when the
    folder's outputs (glob patterns) were made with another identity, unless ``overwrite``:
    then they are removed first."""
    identity = json.loads(json.dumps(identity))  # as it reads back: tuples become lists
    path = folder / name
    found = _outputs(folder, outputs)
    old: Any = None
    if path.is_file():
        try:
            record = json.loads(path.read_text())
            old = record["identity"] if record.get("format") == JOB_FORMAT else None
        except (ValueError, KeyError, TypeError, AttributeError):
            old = None
        if old == identity:
            return
    if found and not overwrite:
        if old is None:
            raise UnitConflict(
                f"{folder} holds outputs without a readable {name} (another version's, or "
                "its record is corrupt)",
                remedy=Remedy.REPLACE,
            )
        raise UnitConflict(
            f"{folder}: its outputs were trained with other settings "
            f"({describe_changes(old, identity)})",
            remedy=Remedy.REPLACE,
        )
    for output in found:  # the record goes first: a kill from here leaves no stale record
        if output.is_dir() and not output.is_symlink():
            shutil.rmtree(output)
        else:
            output.unlink()
    folder.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps({"format": JOB_FORMAT, "identity": identity}, indent=2) + "\n")


def _outputs(folder: Path, patterns: Sequence[str]) -> list[Path]:
    if not folder.is_dir():
        return []
    return sorted({p for pattern in patterns for p in folder.glob(pattern)})
