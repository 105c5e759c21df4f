"""Where units run: :class:`Backend` (local processes or a Ray cluster), the one a command
asked for (:func:`choose_backend`), and :class:`ExecutionError`, every backend's one-line
failure (``_first_line``: the one line of an error it reports)."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass

from pokerirl.errors import ConfigError, PokerIRLError

RETRIES = 2  # a unit whose worker dies runs at most 1 + RETRIES times
LOCAL_RAY = "local"


class ExecutionError(PokerIRLError, RuntimeError):
    """A unit could not be run (its worker kept dying, Ray is missing); one line."""


@dataclass(frozen=True, kw_only=True)
class Backend:
    """Where units run: ``local`` processes (``jobs`` of them) or a Ray cluster at ``address``
    (``"local"``: a private single-machine instance). ``threads``: torch threads per unit.
    """

    kind: str = "local"
    jobs: int = 1
    address: str | None = None
    threads: int = 1
    retries: int = RETRIES

    def __post_init__(self) -> None:
        if self.kind not in ("local", "ray"):
            raise ConfigError(f"unknown backend {self.kind!r} (local or ray)")
        if self.jobs < 1:
            raise ConfigError(f"jobs must be at least 1, got {self.jobs}")
        if self.threads < 1:
            raise ConfigError(f"threads must be at least 1, got {self.threads}")
        if self.retries < 0:
            raise ConfigError(f"retries must be at least 0, got {self.retries}")
        if (self.kind == "ray") != bool(self.address):
            raise ConfigError("a Ray backend needs an address ('local' for a private one)")

    def describe(self) -> str:
        """``local, 2 jobs`` or ``ray at ADDRESS``."""
        if self.kind == "ray":
            return f"ray at {self.address}"
        return f"local, {self.jobs} job{'s' * (self.jobs > 1)}"


def choose_backend(
    *,
    jobs: int = 1,
    ray: str | None = None,
    threads: int = 1,
    environ: Mapping[str, str] | None = None,
) -> Backend:
    """The backend a command asked for: ``ray`` (an address or ``local``), else the
    ``RAY_ADDRESS`` environment variable, else ``jobs`` local processes.

    >>> choose_backend(jobs=2, environ={}).describe()
    'local, 2 jobs'
    >>> choose_backend(environ={"RAY_ADDRESS": "10.0.0.1:6379"}).describe()
    'ray at 10.0.0.1:6379'
    """
    environ = os.environ if environ is None else environ
    address = ray if ray is not None else environ.get("RAY_ADDRESS") or None
    if address is not None:
        if not address.strip():
            raise ConfigError("Ray needs an address (HOST:PORT) or 'local', got a blank one")
        return Backend(kind="ray", address=address.strip(), jobs=jobs, threads=threads)
    return Backend(jobs=jobs, threads=threads)


def _first_line(error: BaseException) -> str:
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__
