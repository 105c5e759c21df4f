"""A command's options made from the fields of config dataclasses (a setting is declared once,
in its dataclass, and every command that offers it shows the same flag and help), and the
options the commands share: a metavar listing values (:func:`choices`, the encodings'
:data:`ENCODING_CHOICES`), a default read from a config field (:class:`Default`), which
options a command line set (:func:`given`), ``--log-dir`` (:data:`LOG_DIR`,
:func:`write_logs`) and the game of the poker commands (:data:`GAME_OPTION`,
:data:`RULES_OPTION`, :func:`leduc_rules`, :func:`holdem_only`).

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
import importlib
import inspect
import re
import types
import typing
from collections.abc import Callable, Iterable, Mapping
from enum import StrEnum
from pathlib import Path
from typing import Any, TypeVar

import typer

from pokerirl.cli.errors import echo
from pokerirl.cli.seeds import SEED_OPTION
from pokerirl.errors import UsageError
from pokerirl.game.encodings import Encoding, EncodingName  # numpy only: the values help lists
from pokerirl.game.leduc.rules import LeducRules, RuleSet, get_rules
from pokerirl.game.spec import GameName
from pokerirl.irl.config import MAX_EPOCHS, IRLMode  # torch-free
from pokerirl.settings import MAX_LAYERS, MAX_STEPS, MAX_WIDTH

T = TypeVar("T")
Settings = Mapping[str, Any]
NO_SETTINGS: Settings = types.MappingProxyType({})


def choices(values: Iterable[str]) -> str:
    """An option's metavar that lists its values, as ``--help`` shows them.

    >>> choices(("rlcard", "strength"))
    '[rlcard|strength]'
    """
    return f"[{'|'.join(values)}]"


ENCODING_CHOICES = choices(EncodingName)


class Default:
    """A typer option's default, read from a config dataclass's field: declared once, in the
    dataclass, and shown by ``--help``. Lazy: the module is imported when the default is used
    or shown, never when the command line starts. A tuple is given as the command line
    writes it (``raw,centered``).

    >>> Default("pokerirl.studies.poker.transfer:TransferConfig", "hands")()
    50000
    >>> str(Default("pokerirl.studies.poker.transfer:TransferConfig", "transforms"))
    'raw,centered,log_softmax,advantage'
    """

    def __init__(self, config: str, field: str) -> None:
        self.config, self.field = config, field

    def __call__(self) -> Any:
        module, _, name = self.config.partition(":")
        config = getattr(importlib.import_module(module), name)
        field = {f.name: f for f in dataclasses.fields(config)}[self.field]
        if field.default is dataclasses.MISSING:
            value = field.default_factory()  # type: ignore[operator]  # has one: no default
        else:
            value = field.default
        return ",".join(map(str, value)) if isinstance(value, tuple) else value

    def __str__(self) -> str:
        return str(self())

    def __repr__(self) -> str:
        return f"Default({self.config!r}, {self.field!r})"


def given(ctx: typer.Context, **options: T) -> dict[str, T]:
    """The ``options`` the command line set (not left at their default), for settings that
    a preset or a ``--config`` file gives otherwise."""
    left = ("DEFAULT", "DEFAULT_MAP")  # by name: typer's click or click's ParameterSource
    return {
        name: value
        for name, value in options.items()
        if getattr(ctx.get_parameter_source(name), "name", "DEFAULT") not in left
    }


# --log-dir DIR, one option for every command that trains runs (typer options may be shared).
LOG_DIR = typer.Option(
    None,
    "--log-dir",
    metavar="DIR",
    help="Also write each run's scalars into DIR as TensorBoard event files and progress.csv "
    "(SB3's layout; needs pip install 'pokerirl[logs]'). metrics.jsonl stays the record.",
)


def parse_encoding(name: str) -> Encoding:
    """``--encoding NAME``: the one place the name is checked (a usage error naming the known
    ones) and becomes the encoding every layer below is given."""
    from pokerirl.game.encodings import ENCODINGS

    if name not in ENCODINGS:
        raise UsageError(f"unknown --encoding {name!r} ({', '.join(ENCODINGS)})")
    return ENCODINGS[name]


def online_mode(mode: str | None, online_only: Mapping[str, object]) -> bool:
    """Whether ``--mode`` (None: not given, offline) is online, as ``train``, ``study``, ``gym
    irl`` and ``gym study`` read it: a usage error for an unknown mode, or for an online-only
    option (``online_only``: flag -> value, None when not given) given offline."""
    if mode is not None and mode not in tuple(IRLMode):
        raise UsageError(f"--mode must be one of {', '.join(IRLMode)}, got {mode!r}")
    if mode == IRLMode.ONLINE:
        return True
    given = [name for name, value in online_only.items() if value is not None]
    if given:
        raise UsageError(f"{given[0]} applies to --mode online only")
    return False


# The online IRL options of `train` and `study` (poker; gym's in cli/gym.py).
POKER_ROUNDS = typer.Option(
    None, "--rounds", min=1, max=MAX_EPOCHS,
    help="Online: rounds of generator hands, discriminator pass, policy update (default 20).",
)  # fmt: skip
POKER_GENERATOR_STEPS = typer.Option(
    None, "--generator-steps", min=1, max=MAX_STEPS,
    help="Online: the policy's decisions on the engine per round (default 2048).",
)  # fmt: skip


def write_logs(out: Path, log_dir: Path | None) -> None:
    """``--log-dir``: the scalars of the runs under ``out``, copied into ``log_dir``."""
    if log_dir is None:
        return
    from pokerirl.scalars import export_scalars

    written = export_scalars(out, log_dir)
    echo(f"scalars of {len(written)} runs -> {log_dir} (tensorboard --logdir {log_dir})")


# --game and --rules: the poker commands that also play Leduc hold'em (docs/leduc.md).
GAME_OPTION = typer.Option(
    GameName.HOLDEM, "--game", metavar=choices(GameName),
    help="holdem (heads-up limit hold'em) or leduc (Leduc hold'em, exact: docs/leduc.md).",
)  # fmt: skip
RULES_OPTION = typer.Option(
    None, "--rules", metavar=choices(RuleSet),
    help="With --game leduc: RLCard's leduc-holdem (rlcard, the default) or OpenSpiel's "
    "leduc_poker (openspiel) rules.",
)  # fmt: skip


def leduc_rules(game: GameName, rules: RuleSet | None) -> LeducRules | None:
    """The Leduc rules of ``--game leduc`` (RLCard's by default), None for hold'em (a usage
    error for ``--rules`` there)."""
    if game is GameName.HOLDEM:
        if rules is not None:
            raise UsageError("--rules applies to --game leduc only")
        return None
    return get_rules(rules or RuleSet.RLCARD)


def holdem_only(ctx: typer.Context, why: str, **options: object) -> None:
    """With ``--game leduc``: a usage error naming the hold'em options the line set (and
    ``why`` they do not apply)."""
    found = given(ctx, **options)
    if found:
        flag = {p.name: max(p.opts, key=len) for p in ctx.command.params}
        flags = ", ".join(flag.get(name, name) for name in found)
        verb = "applies" if len(found) == 1 else "apply"
        raise UsageError(f"{flags} {verb} to hold'em only ({why})")


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
