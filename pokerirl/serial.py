"""One serializer for every JSON file pokerirl writes: dataclasses to JSON values and back,
driven by their fields and type hints.

Types: ``int``, ``float`` (an int is a number too, kept as written), ``str``, ``bool``,
``None``, StrEnum, ``Literal``, ``Path``, ``list``, ``tuple`` (fixed or ``...``; written as a
list), ``Mapping``/``dict`` (keys ``str``, StrEnum or ``int``), ``X | None`` and other unions
(tried in order), nested dataclasses, ``Any``/``object`` (kept as they are).

A field's :func:`meta` says what differs from the default (the field's name as the key, always
written): another ``key``, ``omit`` it when None or its default, ``skip`` it, ``flatten`` a
dataclass or mapping into its parent's keys. A key the class does not know is ignored on
read; a missing one reads as the field's default. Classes keep ``x.to_json()`` and
``X.from_json(data)`` through :class:`Serializable`; one may override either and call the
generic one around its own step (a derived key, a legacy layout).

>>> from dataclasses import dataclass, field
>>> @dataclass(frozen=True, kw_only=True)
... class Point(Serializable):
...     x: float
...     label: str | None = field(default=None, metadata=meta(omit=Omit.NONE))
>>> Point(x=1.5).to_json()
{'x': 1.5}
>>> Point.from_json({"x": 2, "label": "a"})
Point(x=2, label='a')
>>> Point.from_json({"x": "no"}, path="points[3]")
Traceback (most recent call last):
...
pokerirl.serial.SerialError: points[3].x: expected a number, got 'no'
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar, cast

from pokerirl.errors import InputError

T = TypeVar("T")
S = TypeVar("S", bound="Serializable")

Json = Any  # a JSON value: dict, list, str, int, float, bool or None

_META = "pokerirl.serial"


class SerialError(InputError):
    """A JSON value that does not fit its type: one line naming its path in the file."""


class Omit(enum.StrEnum):
    """When a field is left out of the JSON (files written before it existed lack it)."""

    NONE = "none"  # when None
    DEFAULT = "default"  # when equal to its default


@dataclasses.dataclass(frozen=True, kw_only=True)
class FieldMeta:
    key: str | None = None  # the JSON key, where it is not the field's name
    omit: Omit | None = None
    skip: bool = False  # never written; read as its default
    # A dataclass field: its keys are the parent's. A mapping field: every key of the parent
    # that no other field claims.
    flatten: bool = False


def meta(
    *, key: str | None = None, omit: Omit | None = None, skip: bool = False, flatten: bool = False
) -> dict[str, FieldMeta]:
    """The metadata of a ``dataclasses.field`` whose JSON differs from the default."""
    return {_META: FieldMeta(key=key, omit=omit, skip=skip, flatten=flatten)}


@dataclasses.dataclass(frozen=True)
class _Field:
    name: str
    key: str
    hint: Any
    meta: FieldMeta
    default: Any  # dataclasses.MISSING when required

    def default_value(self) -> Any:
        return self.default() if callable(self.default) else self.default


@functools.cache
def _fields(cls: Any) -> tuple[_Field, ...]:
    hints = typing.get_type_hints(cls)
    found = []
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        field_meta = f.metadata.get(_META, FieldMeta())
        default: Any = dataclasses.MISSING
        if f.default is not dataclasses.MISSING:
            default = _Constant(f.default)
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory
        found.append(_Field(f.name, field_meta.key or f.name, hints[f.name], field_meta, default))
    return tuple(found)


@dataclasses.dataclass(frozen=True)
class _Constant:
    value: Any

    def __call__(self) -> Any:
        return self.value


# ------------------------------------------------------------------------------- writing


def to_json(obj: Any) -> Json:
    """``obj`` as a JSON value: dataclasses as objects (their fields in order), tuples as
    lists, StrEnums as their values, paths as strings."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        # Serializable, or a class that writes itself
        return obj.to_json() if hasattr(obj, "to_json") else _dataclass_to_json(obj)
    if isinstance(obj, enum.Enum):
        return obj.value
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, Mapping):
        return {_key_to_json(key): to_json(value) for key, value in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_json(value) for value in obj]
    return obj


def _key_to_json(key: Any) -> str:
    if isinstance(key, enum.Enum):
        return str(key.value)
    return key if isinstance(key, str) else str(key)


def _dataclass_to_json(obj: Any) -> dict[str, Json]:
    found: dict[str, Json] = {}
    for f in _fields(obj.__class__):
        if f.meta.skip:
            continue
        value = getattr(obj, f.name)
        if f.meta.omit is Omit.NONE and value is None:
            continue
        if f.meta.omit is Omit.DEFAULT and value == f.default_value():
            continue
        written = to_json(value)
        if f.meta.flatten:
            found.update(written)
        else:
            found[f.key] = written
    return found


# ------------------------------------------------------------------------------- reading


def from_json(cls: type[T], data: Json, path: str = "") -> T:
    """``data`` read as a ``cls`` (a dataclass or any type above); ``path``: where ``data``
    is in its file, for the error's message (``summary.tasks[2]``)."""
    return cast(T, _read(cls, data, path))


def _at(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _fail(path: str, expected: str, data: Any) -> SerialError:
    shown = repr(data)
    shown = shown if len(shown) <= 60 else shown[:57] + "..."
    return SerialError(f"{path or 'the value'}: expected {expected}, got {shown}")


def _number(data: Any) -> bool:
    return isinstance(data, int | float) and not isinstance(data, bool)


_SCALARS: dict[type, tuple[str, Callable[[Any], bool]]] = {
    bool: ("true or false", lambda data: isinstance(data, bool)),
    int: ("an integer", lambda data: isinstance(data, int) and not isinstance(data, bool)),
    float: ("a number", _number),
    str: ("a string", lambda data: isinstance(data, str)),
}


def _read(hint: Any, data: Any, path: str) -> Any:
    if hint is Any or hint is object:
        return data
    origin = typing.get_origin(hint)
    if origin is typing.Union or origin is types.UnionType:
        return _read_union(typing.get_args(hint), data, path)
    if origin is typing.Literal:
        if data not in typing.get_args(hint):
            choices = ", ".join(repr(a) for a in typing.get_args(hint))
            raise _fail(path, f"one of {choices}", data)
        return data
    if origin is not None:
        return _read_generic(origin, typing.get_args(hint), data, path)
    if dataclasses.is_dataclass(hint):
        return _read_dataclass(cast(type, hint), data, path)
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        try:
            return hint(data)
        except ValueError:
            choices = ", ".join(repr(m.value) for m in hint)
            raise _fail(path, f"one of {choices}", data) from None
    if hint in _SCALARS:
        expected, fits = _SCALARS[hint]
        if not fits(data):
            raise _fail(path, expected, data)
        return data  # an int read as a float stays one: written again, the file keeps its bytes
    if hint is Path:
        if not isinstance(data, str):
            raise _fail(path, "a path", data)
        return Path(data)
    raise TypeError(f"{path}: pokerirl.serial cannot read a {hint!r}")  # a bug, not the file's


def _read_union(alternatives: tuple[Any, ...], data: Any, path: str) -> Any:
    if data is None and type(None) in alternatives:
        return None
    others = [a for a in alternatives if a is not type(None)]
    if len(others) == 1:
        return _read(others[0], data, path)
    failures = []
    for alternative in others:
        try:
            return _read(alternative, data, path)
        except SerialError as error:
            failures.append(error)
    names = " or ".join(getattr(a, "__name__", str(a)) for a in others)
    raise SerialError(f"{path or 'the value'}: fits none of {names} ({failures[0]})")


def _read_generic(origin: Any, args: tuple[Any, ...], data: Any, path: str) -> Any:
    if origin in (list, tuple, Sequence):
        if not isinstance(data, list | tuple):
            raise _fail(path, "a list", data)
        if origin is tuple and not (len(args) == 2 and args[1] is Ellipsis):
            if len(data) != len(args):
                raise _fail(path, f"a list of {len(args)}", data)
            return tuple(
                _read(a, v, f"{path}[{i}]") for i, (a, v) in enumerate(zip(args, data, strict=True))
            )
        item = args[0] if args else Any
        values = [_read(item, v, f"{path}[{i}]") for i, v in enumerate(data)]
        return values if origin is list else tuple(values)
    if origin in (dict, Mapping):
        if not isinstance(data, Mapping):
            raise _fail(path, "an object", data)
        key_hint, value_hint = args if args else (Any, Any)
        return {
            _read_key(key_hint, key, path): _read(value_hint, value, _at(path, str(key)))
            for key, value in data.items()
        }
    raise TypeError(f"{path}: pokerirl.serial cannot read a {origin!r}")


def _read_key(hint: Any, key: str, path: str) -> Any:
    if hint is int:
        try:
            return int(key)
        except ValueError:
            raise _fail(path, "integer keys", key) from None
    return _read(hint, key, _at(path, key))


def _read_dataclass(cls: type, data: Any, path: str) -> Any:
    if issubclass(cls, Serializable):
        return cls.from_json(data, path)  # its own, where it overrides it
    if hasattr(cls, "from_json"):
        return cls.from_json(data)  # a class that reads itself
    return _read_fields(cls, data, path)


def _read_fields(cls: type, data: Any, path: str) -> Any:
    if not isinstance(data, Mapping):
        raise _fail(path, f"an object ({cls.__name__})", data)
    fields = _fields(cls)
    claimed = {f.key for f in fields if not f.meta.flatten}
    values: dict[str, Any] = {}
    for f in fields:
        if f.meta.skip:
            continue
        if f.meta.flatten:
            origin = typing.get_origin(f.hint)
            if origin in (dict, Mapping):
                rest = {k: v for k, v in data.items() if k not in claimed}
                values[f.name] = _read(f.hint, rest, path)
            else:
                values[f.name] = _read(f.hint, data, path)
            continue
        if f.key in data:
            values[f.name] = _read(f.hint, data[f.key], _at(path, f.key))
        elif f.default is dataclasses.MISSING:
            raise SerialError(f"{_at(path, f.key)}: missing")
    return cls(**values)


class Serializable:
    """``to_json()`` and ``from_json(data)`` for a dataclass, by :func:`to_json` and
    :func:`from_json`."""

    def to_json(self) -> Json:
        return _dataclass_to_json(self)

    @classmethod
    def from_json(cls: type[S], data: Json, path: str = "") -> S:
        return cast(S, _read_fields(cls, data, path))
