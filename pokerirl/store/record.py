"""Unit records: what a finished unit was made from, and which bytes it left.

A record holds the unit's **fingerprint** (``sha256:<hex>`` of its identity: its
configuration and the digests of its inputs, as one canonical JSON document), the
configuration and the inputs themselves (so a conflict can say what changed), the sha256 of
every output file it vouches for (timings are written beside it, never hashed), and, for a
unit that is only a record, its result.

One format is written, ``pokerirl-unit/2``. Three older ones are read, so a folder written
before the store is recognised:

* ``pokerirl-unit/1`` (``execution.make_record``: ``unit.json`` in unit folders,
  ``*.unit.json`` beside a file, tournament ``seed-<k>.json``): the configuration held the
  input digests, so its identity is its configuration and its fingerprint is unchanged;
* ``pokerirl-study-stage/1`` (``stages/<stage>.json`` of a poker study): identity
  ``{"stage": name, "settings": settings}``, no file digests, and a ``finished`` flag;
* ``pokerirl-gym-job/1`` (``expert.job.json`` / ``rl.job.json`` of a ``gym expert`` or
  ``gym rl`` folder): identity its ``identity``, no file digests, finished.

A unit's identity is ``{**config, **inputs}``: a configuration that named its inputs'
digests inline (all of today's) keeps its fingerprint when they move to ``inputs``.

>>> record = UnitRecord.make({"seed": 1}, inputs={"table": digest(b"rows")},
...                          files={"model.pt": b"weights"})
>>> record.fingerprint == fingerprint({"seed": 1, "table": digest(b"rows")})
True
>>> UnitRecord.from_json(record.to_json()) == record
True
>>> describe_changes({"a": 1, "d": {"x": 2}}, {"a": 1, "d": {"x": 3}})
'd.x 2 -> 3'
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pokerirl.errors import PokerIRLError, Remedy
from pokerirl.jsonio import read_json

# JSON values as json.loads gives them (what configs, inputs and results are made of).
Json = None | bool | int | float | str | list[Any] | dict[str, Any]

RECORD_FORMAT = "pokerirl-unit/2"
UNIT_FORMAT_1 = "pokerirl-unit/1"
STAGE_FORMAT_1 = "pokerirl-study-stage/1"
GYM_JOB_FORMAT_1 = "pokerirl-gym-job/1"
READABLE_FORMATS = (RECORD_FORMAT, UNIT_FORMAT_1, STAGE_FORMAT_1, GYM_JOB_FORMAT_1)
_OURS = re.compile(r"pokerirl-(unit|study-stage)/(\d+)")


class StoreError(PokerIRLError):
    """A unit or its place on disk cannot be used as asked; one line naming the path."""


class UnitConflict(StoreError, ValueError):
    """What is at a unit's place may not be replaced without asking: a unit made with another
    configuration, a record of a newer pokerirl, or files that no unit wrote. ``remedy`` says
    what would get past it."""


class NotARecord(StoreError, ValueError):
    """Text that is not a unit record of a readable format (corrupt, truncated, another
    tool's): the unit is recomputed. Internal: never reaches a user."""


def fingerprint(identity: Json | Mapping[str, Any]) -> str:
    """``sha256:<hex>`` of ``identity`` as canonical JSON (sorted keys, no spaces); the same
    as ``execution.fingerprint``, so records written before the store keep matching.

    >>> fingerprint({"b": 1, "a": [2]}) == fingerprint({"a": [2], "b": 1})
    True
    """
    text = json.dumps(identity, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return f"sha256:{hashlib.sha256(text.encode()).hexdigest()}"


def digest(data: bytes) -> str:
    """``sha256:<hex>`` of ``data``: how records name files and inputs."""
    return f"sha256:{hashlib.sha256(data).hexdigest()}"


def identity_of(config: Mapping[str, Any], inputs: Mapping[str, Any]) -> dict[str, Json]:
    """``{**config, **inputs}`` as plain JSON (tuples become lists), refusing a name in both."""
    both = sorted(config.keys() & inputs.keys())
    if both:
        raise ValueError(f"{both[0]!r} is both a setting and an input of the unit")
    plain: dict[str, Json] = json.loads(json.dumps({**config, **inputs}, allow_nan=False))
    return plain


@dataclass(frozen=True, kw_only=True)
class UnitRecord:
    """A finished unit's record (see the module's docstring).

    ``files`` maps paths relative to the record's folder to their digests. ``finished`` and
    ``format`` describe what was read: only a stage record of an interrupted study is
    unfinished, and every record written is :data:`RECORD_FORMAT`.
    """

    fingerprint: str
    config: Mapping[str, Any]
    inputs: Mapping[str, Any] = field(default_factory=dict)
    files: Mapping[str, str] = field(default_factory=dict)
    result: Json = None
    finished: bool = True
    format: str = RECORD_FORMAT

    @classmethod
    def make(
        cls,
        config: Mapping[str, Any],
        *,
        inputs: Mapping[str, Any] | None = None,
        files: Mapping[str, bytes] | None = None,
        result: Json = None,
    ) -> UnitRecord:
        """The record of a unit of ``config`` and ``inputs`` that wrote ``files``."""
        inputs = dict(inputs or {})
        identity = identity_of(config, inputs)
        plain_config = {key: identity[key] for key in config}
        return cls(
            fingerprint=fingerprint(identity),
            config=plain_config,
            inputs={key: identity[key] for key in inputs},
            files={name: digest(data) for name, data in sorted((files or {}).items())},
            result=json.loads(json.dumps(result)),  # NaN allowed, as before (a p-value)
        )

    @property
    def identity(self) -> dict[str, Json]:
        """What the fingerprint covers: ``{**config, **inputs}``."""
        return {**self.config, **self.inputs}

    def to_json(self) -> dict[str, Json]:
        """The record as written (always :data:`RECORD_FORMAT`)."""
        return {
            "format": RECORD_FORMAT,
            "fingerprint": self.fingerprint,
            "config": dict(self.config),
            "inputs": dict(self.inputs),
            "files": dict(sorted(self.files.items())),
            "result": self.result,
        }

    def to_text(self) -> str:
        return json.dumps(self.to_json(), indent=2, sort_keys=True) + "\n"

    @classmethod
    def from_json(cls, data: Any, *, path: str | os.PathLike[str] | None = None) -> UnitRecord:
        """A record of any readable format.

        Raises:
            UnitConflict: a record of a newer pokerirl (naming ``path``): it is not replaced
                unless asked.
            NotARecord: anything else that is not a readable record.
        """
        if not isinstance(data, dict):
            raise NotARecord(f"a JSON {type(data).__name__}, not a record")
        kind = data.get("format")
        if kind not in READABLE_FORMATS:
            ours = _OURS.fullmatch(kind) if isinstance(kind, str) else None
            if ours and int(ours[2]) > int(_current(ours[1])):
                raise UnitConflict(
                    f"{path or 'a record'} was written by a newer pokerirl (format {kind})",
                    remedy=Remedy.RECOMPUTE,
                )
            raise NotARecord(f"format {kind!r}")
        if kind == STAGE_FORMAT_1:
            return _stage_record(data)
        if kind == GYM_JOB_FORMAT_1:
            return _gym_job_record(data)
        try:
            record = cls(
                fingerprint=_text(data["fingerprint"]),
                config=_object(data["config"]),
                inputs=_object(data.get("inputs", {})) if kind == RECORD_FORMAT else {},
                files={_text(k): _text(v) for k, v in _object(data["files"]).items()},
                result=data.get("result"),
                format=kind,
            )
        except (KeyError, TypeError, ValueError) as error:
            raise NotARecord(f"{kind} record without a usable {error}") from None
        return record

    def missing_or_changed(self, folder: str | os.PathLike[str]) -> str | None:
        """The first file of ``files`` (relative to ``folder``) that is missing or holds other
        bytes, with why; None when all match."""
        for name, expected in sorted(self.files.items()):
            path = Path(folder) / name
            try:
                found = digest(path.read_bytes())
            except OSError:
                return f"{name} is missing"
            if found != expected:
                return f"{name} has other bytes"
        return None


def _current(kind: str) -> str:
    return (RECORD_FORMAT if kind == "unit" else STAGE_FORMAT_1).rpartition("/")[2]


def _text(value: Any) -> str:
    if not isinstance(value, str):
        raise TypeError("text")
    return value


def _object(value: Any) -> dict[str, Json]:
    if not isinstance(value, dict):
        raise TypeError("object")
    return value


def _stage_record(data: Mapping[str, Any]) -> UnitRecord:
    try:
        stage, settings = _text(data["stage"]), _object(data["settings"])
        finished = data.get("finished") is True
        return UnitRecord(
            fingerprint=_text(data["fingerprint"]),
            config={"stage": stage, "settings": settings},
            result=data.get("result") if finished else None,
            finished=finished,
            format=STAGE_FORMAT_1,
        )
    except (KeyError, TypeError) as error:
        raise NotARecord(f"stage record without a usable {error}") from None


def _gym_job_record(data: Mapping[str, Any]) -> UnitRecord:
    try:
        identity = _object(data["identity"])
        return UnitRecord(
            fingerprint=fingerprint(identity), config=identity, format=GYM_JOB_FORMAT_1
        )
    except (KeyError, TypeError, ValueError) as error:  # ValueError: a NaN in it
        raise NotARecord(f"gym job record without a usable {error}") from None


def read_record(path: str | os.PathLike[str]) -> UnitRecord | None:
    """The record at ``path``; None when there is none or it is not a readable record
    (corrupt, truncated, another format: its unit is recomputed).

    Raises:
        UnitConflict: a record of a newer pokerirl.
    """
    try:
        data = read_json(Path(path))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    try:
        return UnitRecord.from_json(data, path=path)
    except NotARecord:
        return None


def describe_changes(old: Any, new: Any, *, limit: int = 4) -> str:
    """``key old -> new, ...`` over the leaves of two JSON-like documents (at most
    ``limit``, then how many more)."""
    flat_old, flat_new = _flatten(old), _flatten(new)
    keys = sorted(
        k for k in flat_old.keys() | flat_new.keys() if flat_old.get(k) != flat_new.get(k)
    )
    parts = [f"{k} {flat_old.get(k)!r} -> {flat_new.get(k)!r}" for k in keys[:limit]]
    if len(keys) > limit:
        parts.append(f"{len(keys) - limit} more")
    return ", ".join(parts) or "fingerprint differs"


def _flatten(value: Any, prefix: str = "") -> dict[str, Json]:
    if isinstance(value, Mapping):
        out: dict[str, Json] = {}
        for key, item in value.items():
            out.update(_flatten(item, f"{prefix}{key}."))
        return out
    return {prefix.rstrip("."): value}
