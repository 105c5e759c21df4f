"""A command's options made from the fields of config dataclasses: a setting is declared once,
in its dataclass, and every command that offers it shows the same flag and help.

A field is offered when its metadata holds ``help`` (``pokerirl.irl.config.setting``), with
optional ``flags`` (default ``--field-name``), ``metavar``, ``min``, ``max`` and
``show_default`` (show the field's default: for a setting that no preset or file changes).
The field's type gives the rest: a StrEnum lists its values (``[a|b]``), a
``tuple[int, ...]`` is written ``64,64`` (``WIDTHS``), a ``seed`` or ``*_seed`` field takes
any seed (0 .. 2^32 - 1).

:func:`settings_options` puts a dataclass's options in place of a parameter of the command;
the command receives, under that parameter, the settings its command line gave (never
the defaults: a preset or a ``--config`` file gives those), as a dict of field names.

>>> from pokerirl.irl.config import AIRLConfig
>>> @settings_options(irl=AIRLConfig)
... def command(ctx: typer.Context, irl: Settings = NO_SETTINGS) -> None:
...     print(dict(irl))
>>> sorted(inspect.signature(command).parameters)[:4]
['alpha', 'batch_size', 'beta', 'ctx']
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import re
import types
import typing
from collections.abc import Callable, Mapping
from enum import StrEnum
from typing import Any, TypeVar

import typer

from pokerirl.cli.app import SEED_OPTION, choices, given
from pokerirl.errors import UsageError
from pokerirl.settings import MAX_LAYERS, MAX_WIDTH

T = TypeVar("T")
Settings = Mapping[str, Any]
NO_SETTINGS: Settings = types.MappingProxyType({})


def widths(text: str, flag: str = "--hidden") -> tuple[int, ...]:
    """``64,64`` as layer widths (a usage error naming ``flag`` when not integers).

    >>> widths("64, 32")
    (64, 32)
    >>> widths("1000000000")
    Traceback (most recent call last):
    ...
    pokerirl.errors.UsageError: --hidden takes at most 16 widths of at most 4096, got '1000000000'

    """
    found = [w.strip() for w in text.split(",") if w.strip()]
    if not all(re.fullmatch(r"[+-]?\d{1,20}", w) for w in found):
        raise UsageError(f"{flag} must be comma-separated integers, got {text[:60]!r}")
    if len(found) > MAX_LAYERS or any(int(w) > MAX_WIDTH for w in found):
        raise UsageError(
            f"{flag} takes at most {MAX_LAYERS} widths of at most {MAX_WIDTH}, got {text[:60]!r}"
        )
    return tuple(int(w) for w in found)


@dataclasses.dataclass(frozen=True, kw_only=True)
class _Option:
    """One offered field: its parameter name (the field's) and how its text becomes a value."""

    name: str
    kind: Any  # the field's type, None and str-for-callers taken out
    flag: str

    def value(self, given: Any) -> Any:
        """The command line's value as the field takes it (widths as a tuple)."""
        return widths(given, self.flag) if typing.get_origin(self.kind) is tuple else given


def _kind(hint: Any) -> Any:
    """``X`` of ``X | None``; the StrEnum of ``Enum | str``."""
    parts = [a for a in typing.get_args(hint) if a is not type(None)]
    if typing.get_origin(hint) not in (types.UnionType, typing.Union):
        return hint
    enums = [a for a in parts if isinstance(a, type) and issubclass(a, StrEnum)]
    return (enums or parts)[0]


def _parameter(item: dataclasses.Field[Any], hint: Any) -> tuple[_Option, inspect.Parameter]:
    meta = item.metadata
    kind = _kind(hint)
    more: dict[str, Any] = {}
    typed: Any = kind
    if isinstance(kind, type) and issubclass(kind, StrEnum):
        typed, more["metavar"] = str, choices(kind)
    elif typing.get_origin(kind) is tuple:
        typed, more["metavar"] = str, "WIDTHS"
    if item.name == "seed" or item.name.endswith("_seed"):
        more.update(SEED_OPTION)
    # a tuple's bounds are each width's, checked by the config (settings.check_bounds)
    passed = ("metavar",) if typing.get_origin(kind) is tuple else ("metavar", "min", "max")
    more.update({key: meta[key] for key in passed if key in meta})
    flags = tuple(meta.get("flags", (f"--{item.name.replace('_', '-')}",)))
    default = item.default if meta.get("show_default") else None
    option = typer.Option(default, *flags, help=meta["help"], **more)
    parameter = inspect.Parameter(
        item.name, inspect.Parameter.POSITIONAL_OR_KEYWORD, default=option,
        annotation=typed | None,
    )  # fmt: skip
    return _Option(name=item.name, kind=kind, flag=flags[0]), parameter


def offered(config: type) -> list[tuple[_Option, inspect.Parameter]]:
    """The options of ``config``'s fields that have help, in the fields' order."""
    hints = typing.get_type_hints(config)
    return [
        _parameter(item, hints[item.name])
        for item in dataclasses.fields(config)
        if "help" in item.metadata
    ]


def settings_options(**groups: type) -> Callable[[Callable[..., T]], Callable[..., T]]:
    """Offer each dataclass's fields as options, in place of the command's parameter of the
    group's name; the command gets that parameter as the settings given (see the module)."""

    def decorate(command: Callable[..., T]) -> Callable[..., T]:
        signature = inspect.signature(command)
        made = {group: offered(config) for group, config in groups.items()}
        parameters: list[inspect.Parameter] = []
        for parameter in signature.parameters.values():
            if parameter.name in made:
                parameters += [p for _, p in made[parameter.name]]
            else:
                parameters.append(parameter)
        annotations = {k: v for k, v in command.__annotations__.items() if k not in made}
        annotations |= {p.name: p.annotation for p in parameters if p.name not in annotations}

        @functools.wraps(command)
        def run(**options: Any) -> T:
            for group, found in made.items():
                values = {o.name: options.pop(o.name) for o, _ in found}
                typed = {o.name: o for o, _ in found}
                options[group] = {
                    name: typed[name].value(value)
                    for name, value in given(options["ctx"], **values).items()
                    if value is not None
                }
            return command(**options)

        run.__signature__ = signature.replace(parameters=parameters)  # type: ignore[attr-defined]
        run.__annotations__ = annotations
        return run

    return decorate
