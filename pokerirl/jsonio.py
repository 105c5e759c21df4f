"""The one reader of the JSON files pokerirl reads (agent, run, split, report, unit and study
files): bounded before anything is parsed, so a hostile or damaged file is one error line
naming it, never a traceback, a hang or gigabytes of memory.

* regular files only (``/dev/zero``, a FIFO or a folder is refused before it is read);
* at most :data:`MAX_JSON_BYTES` bytes (checked from the file's size, then on the read
  itself, in case it grows);
* integers of at most :data:`MAX_INT_DIGITS` digits (Python refuses 4,300 with a plain
  ``ValueError``; no count, width or seed pokerirl reads needs more than 20);
* nesting deeper than the parser's recursion limit refused;
* :func:`check_format`: the file's kind (``format``) and version, when it records them.

Every refusal is an :class:`~pokerirl.errors.InputError` (or the caller's own kind)
``PATH: reason``.

>>> import tempfile
>>> from pathlib import Path
>>> folder = Path(tempfile.mkdtemp())
>>> _ = (folder / "a.json").write_text('{"hidden": [64, 64]}')
>>> read_json(folder / "a.json")
{'hidden': [64, 64]}
>>> _ = (folder / "b.json").write_text('{"hidden": [' + "9" * 5000 + "]}")
>>> read_json(folder / "b.json")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
pokerirl.errors.InputError: .../b.json: not JSON (an integer of 5000 digits; at most 40)
>>> read_json("/dev/zero")
Traceback (most recent call last):
...
pokerirl.errors.InputError: /dev/zero: not a regular file
"""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Callable, Collection, Mapping
from typing import Any

from pokerirl.errors import InputError, PokerIRLError

# The largest JSON file read: the largest written (a study's report) is under 1 MiB; parsed,
# 16 MiB of small numbers is a few hundred MB of Python objects, far under the 1.5 GB bound.
MAX_JSON_BYTES = 16 * 1024 * 1024
MAX_INT_DIGITS = 40  # a seed is at most 20 digits (2^64); 40 leaves room and stays cheap

ErrorKind = Callable[[str], PokerIRLError]


class _Refused(Exception):
    """A number the parser hook refuses (raised inside ``json.loads``)."""


def _bounded_int(text: str) -> int:
    digits = len(text.lstrip("-"))
    if digits > MAX_INT_DIGITS:
        raise _Refused(f"an integer of {digits} digits; at most {MAX_INT_DIGITS}")
    return int(text)


def _first_line(error: BaseException) -> str:
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__


def parse_json(
    data: bytes | str,
    *,
    where: str | os.PathLike[str],
    error: ErrorKind = InputError,
    what: str = "",
) -> Any:
    """``data`` parsed as JSON with integers bounded; ``error`` ``WHERE: WHAT not JSON
    (...)`` for anything else (``what``: the caller's words, e.g. ``corrupt: ``)."""
    try:
        text = data.decode("utf-8") if isinstance(data, bytes) else data
        return json.loads(text, parse_int=_bounded_int)
    except UnicodeDecodeError:
        raise error(f"{os.fspath(where)}: {what}not JSON (not UTF-8 text)") from None
    except _Refused as refused:
        raise error(f"{os.fspath(where)}: {what}not JSON ({refused})") from None
    except (ValueError, RecursionError) as bad:  # JSONDecodeError, Python's 4300 digits
        raise error(f"{os.fspath(where)}: {what}not JSON ({_first_line(bad)})") from None


def read_bytes(
    path: str | os.PathLike[str],
    *,
    max_bytes: int = MAX_JSON_BYTES,
    error: ErrorKind = InputError,
    what: str = "",
) -> bytes:
    """The bytes of ``path``, a regular file of at most ``max_bytes``; ``error`` naming it
    otherwise. A missing or unreadable file raises its ``OSError`` (which names it; the
    command line prints it as one line). Never blocks on a FIFO."""
    where = f"{os.fspath(path)}: {what}"
    # a missing or unreadable file stays an OSError (it names the file): callers tell it apart
    fd = os.open(os.fspath(path), os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    try:
        found = os.fstat(fd)
        if not stat.S_ISREG(found.st_mode):
            raise error(f"{where}not a regular file")
        if found.st_size > max_bytes:
            raise error(f"{where}{found.st_size} bytes; at most {max_bytes} are read")
        with os.fdopen(fd, "rb", closefd=False) as stream:
            data = stream.read(max_bytes + 1)
    finally:
        os.close(fd)
    if len(data) > max_bytes:
        raise error(f"{where}more than {max_bytes} bytes; at most {max_bytes} are read")
    return data


def read_json(
    path: str | os.PathLike[str],
    *,
    max_bytes: int = MAX_JSON_BYTES,
    error: ErrorKind = InputError,
    what: str = "",
) -> Any:
    """The JSON value in ``path`` (see the module: bounded, regular files only); ``error``
    ``PATH: WHAT reason`` if it cannot be read (``what``: the caller's words, or none)."""
    data = read_bytes(path, max_bytes=max_bytes, error=error, what=what)
    return parse_json(data, where=path, error=error, what=what)


def read_json_object(
    path: str | os.PathLike[str], *, max_bytes: int = MAX_JSON_BYTES, error: ErrorKind = InputError
) -> dict[str, Any]:
    """:func:`read_json` of a file that must hold a JSON object."""
    found = read_json(path, max_bytes=max_bytes, error=error)
    if not isinstance(found, dict):
        raise error(f"{os.fspath(path)}: must hold a JSON object, got {type(found).__name__}")
    return found


def read_json_lines(
    path: str | os.PathLike[str], *, max_bytes: int = MAX_JSON_BYTES, error: ErrorKind = InputError
) -> list[Any]:
    """The JSON value of each non-blank line of ``path`` (``metrics.jsonl``), bounded as
    :func:`read_json`; a bad line is named ``PATH:LINE``."""
    data = read_bytes(path, max_bytes=max_bytes, error=error)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise error(f"{os.fspath(path)}: not JSON (not UTF-8 text)") from None
    return [
        parse_json(line, where=f"{os.fspath(path)}:{number}", error=error)
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip()
    ]


def check_format(
    record: Mapping[str, Any],
    *,
    where: str | os.PathLike[str],
    kind: tuple[str, str] | None = None,
    version: tuple[str, Collection[object]] | None = None,
    error: ErrorKind = InputError,
    what: str = "",
) -> None:
    """Refuse a record of another kind or of a version this pokerirl cannot read.

    ``kind``: (key, the value it must hold); ``version``: (key, the versions read). A missing
    version key reads as the first version (files written before versions were recorded).

    >>> check_format({"format": "pokerirl-dqn", "version": 99}, where="a/config.json",
    ...              kind=("format", "pokerirl-dqn"), version=("version", (1,)))
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pokerirl.errors.InputError: a/config.json: version is 99; this pokerirl reads version 1 ...
    """
    path = f"{os.fspath(where)}: {what}"
    if kind is not None and record.get(kind[0]) != kind[1]:
        found = str(record.get(kind[0]))[:60]
        raise error(f"{path}{kind[0]} is {found!r}, not {kind[1]!r}")
    if version is not None:
        key, known = version
        found_version = record.get(key, next(iter(known)))
        if isinstance(found_version, bool) or found_version not in known:
            names = ", ".join(str(v) for v in known)
            raise error(
                f"{path}{key} is {str(found_version)[:40]}; this pokerirl reads {key} {names}"
                " (a newer pokerirl wrote it?)"
            )

