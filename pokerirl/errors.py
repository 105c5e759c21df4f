"""One error contract: what the library raises on purpose, and how a command reports it.

Every error that pokerirl raises on purpose (a bad setting: :class:`ConfigError`; a file or
data that cannot be used: :class:`InputError`; a missing optional dependency:
:class:`MissingExtra`; a unit made with other settings) derives from :class:`PokerIRLError`,
and its message is one line that names the user's file or setting, never a command-line
flag: the library does not know the command line. Where a command could get past it (another
output folder, recomputing), the error says so as a :class:`Remedy`, and the command line
adds the advice in terms of its own flags (its mapping of remedies to words,
``pokerirl.cli.errors.ADVICE``, given to :func:`report` and :class:`one_line_errors`).

:class:`one_line_errors` is the contract of every command, as a decorator or a ``with``
block:

* a :class:`PokerIRLError` or an ``OSError`` prints one ``error: ...`` line on stderr and
  exits 1 (an ``OSError`` names its file: ``error: out/table.parquet: Permission denied``);
* a :class:`UsageError` (a command line that cannot be run) does the same with exit code 2,
  like the command-line parser's own errors;
* Ctrl-C prints one line (``interrupted``, or what the command says) and exits 130;
  SIGTERM (SLURM, ``timeout``, ``docker stop``) inside :func:`sigterm_as_interrupt` is
  :class:`Terminated`, a Ctrl-C by another name: the same cleanup, the same line, exit 143;
* anything else is a bug: it keeps its traceback;
* with ``POKERIRL_DEBUG=1`` in the environment (the group's ``--debug`` sets it), every
  error also prints its traceback.

>>> class TableError(PokerIRLError, ValueError):
...     pass
>>> @one_line_errors(stream=sys.stdout, debug=False)
... def command():
...     raise TableError("out/t.parquet: not a decision table")
>>> try:
...     command()
... except SystemExit as done:
...     print("exit", done.code)
error: out/t.parquet: not a decision table
exit 1
"""

from __future__ import annotations

import contextlib
import numbers
import os
import signal
import sys
import threading
import traceback
from collections.abc import Callable, Iterator, Mapping
from enum import StrEnum
from types import TracebackType
from typing import ClassVar, Literal, TextIO

DEBUG_VARIABLE = "POKERIRL_DEBUG"
INTERRUPTED_CODE = 130  # 128 + SIGINT, what a shell reports for Ctrl-C
TERMINATED_CODE = 143  # 128 + SIGTERM, what a shell reports for a process SIGTERM ended


class Remedy(StrEnum):
    """How a command could get past an error that protects what is already on disk."""

    RECOMPUTE = "recompute"  # write elsewhere, or recompute what is there
    REPLACE = "replace"  # write elsewhere, or replace what is there
    ELSEWHERE = "elsewhere"  # write elsewhere: what is there is never replaced


class PokerIRLError(Exception):
    """The base of every error pokerirl raises on purpose; its message is one line.

    ``remedy``: how a command could get past it, if it can (the command line words it). It survives
    pickling (an error raised in a worker process reaches the driver whole).

    >>> import pickle
    >>> error = pickle.loads(pickle.dumps(PokerIRLError("x", remedy=Remedy.REPLACE)))
    >>> error.remedy, str(error)
    (<Remedy.REPLACE: 'replace'>, 'x')
    """

    exit_code: ClassVar[int] = 1

    def __init__(self, message: str, *, remedy: Remedy | None = None) -> None:
        super().__init__(message)
        self.remedy = remedy


class UsageError(PokerIRLError):
    """A command line that cannot be run (options that contradict each other, a value that no
    option type checks): exit code 2, like the parser's own errors. Raised by the command
    line, not the library."""

    exit_code: ClassVar[int] = 2


class ConfigError(PokerIRLError, ValueError):
    """A setting that cannot be used: one line naming the setting (and its file, when a file
    holds it)."""


class InputError(PokerIRLError, ValueError):
    """A user's file or data that cannot be used (missing columns, a corrupt report, an
    unknown agent): one line naming it."""


class MissingExtra(PokerIRLError, ImportError):
    """An optional dependency is missing: one line naming the pip extra that installs it."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where Ctrl-C raises ``KeyboardInterrupt`` (a subclass: every cleanup
    that Ctrl-C runs runs for it too); a command exits 143 (see :func:`sigterm_as_interrupt`)."""


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Inside the block, SIGTERM raises :class:`Terminated` in the main thread, once: a second
    SIGTERM is ignored while the first one's cleanup runs (``timeout`` signals its child, then
    the child's whole group, so the driver gets two at once). Elsewhere than the main thread
    (where Python cannot set a handler) nothing changes. The handler before is put back after.

    >>> import os
    >>> with sigterm_as_interrupt():
    ...     try:
    ...         os.kill(os.getpid(), signal.SIGTERM)
    ...     except Terminated:
    ...         print("terminated")
    terminated
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def terminated(signum: int, frame: object) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        raise Terminated()

    before = signal.signal(signal.SIGTERM, terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, before)


def debug_enabled(environ: Mapping[str, str] | None = None) -> bool:
    """Whether ``POKERIRL_DEBUG`` asks for tracebacks (``1``, ``true``, ``yes`` or ``on``)."""
    value = (os.environ if environ is None else environ).get(DEBUG_VARIABLE, "")
    return value.strip().lower() in ("1", "true", "yes", "on")


def one_line(text: str) -> str:
    """``text`` on one line: its non-blank lines joined by spaces."""
    return " ".join(line.strip() for line in text.splitlines() if line.strip())


def describe_os_error(error: OSError) -> str:
    """``PATH: reason`` (``OLD -> NEW: reason`` for a rename), or the reason alone.

    >>> describe_os_error(PermissionError(13, "Permission denied", "out/runs"))
    'out/runs: Permission denied'
    """
    reason = error.strerror or one_line(str(error)) or type(error).__name__
    names = [os.fsdecode(name) for name in (error.filename, error.filename2) if name is not None]
    return f"{' -> '.join(names)}: {reason}" if names else reason


def report(error: BaseException, advice: Mapping[Remedy, str]) -> tuple[int, str] | None:
    """The exit code and the one line for an error of the contract, with ``advice``'s words
    for its remedy (the caller's: the command line's name its flags); None for a bug.

    >>> report(UsageError("--runs must be at least 1"), {})
    (2, '--runs must be at least 1')
    >>> conflict = PokerIRLError("run-0 was made with other settings", remedy=Remedy.REPLACE)
    >>> print(report(conflict, {Remedy.REPLACE: "pass overwrite=True"}))
    (1, 'run-0 was made with other settings; pass overwrite=True')
    >>> report(KeyError("epochs"), {}) is None
    True
    """
    if isinstance(error, PokerIRLError):
        line = one_line(str(error)) or type(error).__name__
        if error.remedy is not None and error.remedy in advice:
            line = f"{line}; {advice[error.remedy]}"
        return error.exit_code, line
    if isinstance(error, OSError):
        return 1, describe_os_error(error)
    return None


class one_line_errors(contextlib.ContextDecorator):  # lower case: a decorator
    """The error contract of a command (see the module's docstring), as a decorator or a
    ``with`` block.

    Args:
        interrupted: the line Ctrl-C (and SIGTERM: :class:`Terminated`) prints (a
            resumable command says how to resume).
        advice: the words for each :class:`Remedy` (the command line's name its flags);
            default: none, the message alone.
        debug: print tracebacks too; default: :func:`debug_enabled`, read when an error
            arrives (so a ``--debug`` handled after this object was made still counts).
        stream: where the lines go (default: stderr at the time of the error).
        display: how a line is shown (the command line shows the bytes of a path that are
            not UTF-8 as ``\\xff``); default: as it is.
    """

    def __init__(
        self,
        *,
        interrupted: str = "interrupted",
        advice: Mapping[Remedy, str] | None = None,
        debug: bool | None = None,
        stream: TextIO | None = None,
        display: Callable[[str], str] | None = None,
    ) -> None:
        self.interrupted = interrupted
        self.advice = advice or {}
        self.debug = debug
        self.stream = stream
        self.display = display

    def __enter__(self) -> one_line_errors:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> Literal[False]:
        if error is None:
            return False
        if isinstance(error, KeyboardInterrupt):  # Terminated (SIGTERM) too, with its code
            code = TERMINATED_CODE if isinstance(error, Terminated) else INTERRUPTED_CODE
            line = self.interrupted
        else:
            found = report(error, self.advice)
            if found is None:
                return False  # a bug: its traceback, as Python prints it
            code, line = found
        stream = self.stream or sys.stderr
        if self.debug if self.debug is not None else debug_enabled():
            traceback.print_exception(error, file=stream)
        if self.display is not None:
            line = self.display(line)
        colour = getattr(stream, "isatty", lambda: False)()
        stream.write(f"\x1b[31merror: {line}\x1b[0m\n" if colour else f"error: {line}\n")
        stream.flush()
        raise SystemExit(code) from None


def _shown(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def check_argument(name: str, value: object, kinds: type | tuple[type, ...], what: str) -> None:
    """The check at the boundary of a public function: ``TypeError`` naming the argument,
    what it takes and what it got, unless ``value`` is one of ``kinds`` (a bool is never a
    number: ``hands=True`` is a mistake).

    >>> check_argument("hands", "10", int, "an integer")
    Traceback (most recent call last):
    ...
    TypeError: hands must be an integer, got str '10'
    """
    kinds_tuple = kinds if isinstance(kinds, tuple) else (kinds,)
    numeric = any(issubclass(k, numbers.Number) for k in kinds_tuple) and bool not in kinds_tuple
    if isinstance(value, kinds_tuple) and not (numeric and isinstance(value, bool)):
        return
    raise TypeError(f"{name} must be {what}, got {type(value).__name__} {_shown(value)}")


def check_count(name: str, value: object, *, low: int, high: int) -> int:
    """``value`` as an int in ``low..high`` (numpy's integers too): ``TypeError`` for another
    type, :class:`ConfigError` (a ``ValueError``) out of range, each naming the argument.

    >>> check_count("hands", 0, low=1, high=10)
    Traceback (most recent call last):
    ...
    pokerirl.errors.ConfigError: hands must be in 1..10, got 0
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__} {_shown(value)}")
    number = int(value)
    if not low <= number <= high:
        raise ConfigError(f"{name} must be in {low:,}..{high:,}, got {number:,}")
    return number


def check_protocol(name: str, value: object, methods: tuple[str, ...], what: str) -> None:
    """``TypeError`` naming the argument unless ``value`` has each of ``methods`` (callable):
    a string where an object was meant (``play_match("raise", ...)``) is named at the door,
    not as an ``AttributeError`` from inside."""
    if not all(callable(getattr(value, method, None)) for method in methods):
        raise TypeError(f"{name} must be {what}, got {type(value).__name__} {_shown(value)}")
