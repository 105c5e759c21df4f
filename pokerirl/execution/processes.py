"""Other processes, seen through Linux ``/proc``: whether one still runs (``_running``),
its start mark, to tell it from a later one with the same pid (``_start_mark``), and what
runs below it (``_descendants``). Elsewhere they see less, never wrongly more."""

from __future__ import annotations

import contextlib
import os
from pathlib import Path


def _running(pid: int) -> bool:
    """Whether ``pid`` is a process that has not ended (a zombie has ended)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return _start_mark(pid) != "Z"


def _start_mark(pid: int) -> str | None:
    """``pid``'s start time (Linux ``/proc``), to tell it from a later process given the same
    pid; ``"Z"`` for a zombie, None when it is gone or unknown."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return "Z" if fields[0] in ("Z", "X") else fields[19]


def _descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (Linux ``/proc``; empty elsewhere)."""
    found: set[int] = set()
    todo = [pid]
    while todo:
        for task in Path(f"/proc/{todo.pop()}/task").glob("*"):
            with contextlib.suppress(OSError, ValueError):
                for child in map(int, (task / "children").read_text().split()):
                    if child not in found:
                        found.add(child)
                        todo.append(child)
    return found
