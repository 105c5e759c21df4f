"""Real ``pokerirl`` processes for the tests that kill or signal them: the command line, an
environment that imports this checkout, and the processes below a driver (Linux /proc)."""

from __future__ import annotations

import os
import sys
from pathlib import Path


def command(*args: str) -> list[str]:
    """``python -m pokerirl ARGS`` with this interpreter."""
    return [sys.executable, "-m", "pokerirl", *args]


def environment() -> dict[str, str]:
    """The current environment with this checkout first on ``PYTHONPATH``."""
    root = str(Path(__file__).resolve().parents[1])
    path = os.environ.get("PYTHONPATH")
    return {**os.environ, "PYTHONPATH": root + (os.pathsep + path if path else "")}


def descendants(pid: int) -> set[int]:
    """Every live process below ``pid`` (Linux /proc)."""
    found: set[int] = set()
    todo = [pid]
    while todo:
        parent = todo.pop()
        for task in Path(f"/proc/{parent}/task").glob("*"):
            try:
                children = (task / "children").read_text().split()
            except OSError:
                continue
            for child in map(int, children):
                if child not in found:
                    found.add(child)
                    todo.append(child)
    return found


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie has ended)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


def as_from_a_shell() -> None:
    """A ``preexec_fn``: the child starts with Ctrl-C at its default, as a shell starts a
    command, whatever an earlier test left in this process (a SIGINT ignored here would be
    inherited, and Python would then never raise KeyboardInterrupt in the child)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
