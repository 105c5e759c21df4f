"""Settings as the frozen config dataclasses declare them, once: a field a command may offer as
an option (:func:`setting`), a categorical value read from a file or a flag
(:func:`enum_value`), and a named preset with overrides (:func:`with_overrides`: the studies',
the agents' and the IRL algorithms' presets).

>>> @dataclasses.dataclass(frozen=True, kw_only=True)
... class Budget:
...     epochs: int = setting(10, help="Training epochs.", min=1)
>>> dataclasses.fields(Budget)[0].metadata["help"]
'Training epochs.'
>>> with_overrides({"quick": Budget(epochs=2)}, "quick", epochs=None)
Budget(epochs=2)
>>> with_overrides({"quick": Budget(epochs=2)}, "slow")
Traceback (most recent call last):
...
pokerirl.errors.ConfigError: unknown preset 'slow'; choose one of quick
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from enum import StrEnum
from typing import Any, TypeVar

from pokerirl.errors import ConfigError

E = TypeVar("E", bound=StrEnum)
C = TypeVar("C")


# The documented upper bounds of sizes a user or a file gives (checked by check_bounds before
# anything is built: a width of 10^9 would ask torch for hundreds of GB).
MAX_WIDTH = 4096  # a hidden layer's width
MAX_LAYERS = 16  # hidden layers of a net
MAX_BATCH = 1 << 20  # a minibatch, or hands played in lock-step
MAX_REPLAY = 2_000_000  # DQN replay transitions (about 1.4 GB on the 174-d encoding)
MAX_STEPS = 10**12  # counts of hands, epochs, steps: time, never memory, bounds them
MAX_OBS_DIM = 65_536  # an observation's width (an 84 x 84 x 4 image is 28,224)
MAX_ACTIONS = 65_536  # a discrete action space's size
MAX_LBR_HANDS = 10_000_000  # LBR hands per seed (its exact equity makes each one costly)


def setting(default: Any = dataclasses.MISSING, /, help: str = "", **more: Any) -> Any:
    """A config dataclass's field that a command may offer as an option: ``help`` and
    ``more`` (``flags``, ``metavar``, ``min``, ``max``, ``show_default``) in the field's
    metadata, read by ``pokerirl.cli.options``; the field's type and default give the rest.
    ``min`` and ``max`` bound a number, or each width of a ``tuple[int, ...]`` (whose length
    ``max_len`` bounds); :func:`check_bounds` checks them."""
    return dataclasses.field(default=default, metadata={"help": help, **more})


def bounded(default: Any, /, **bounds: Any) -> Any:
    """A field with ``min``/``max``/``max_len`` bounds that no command offers as an option."""
    return dataclasses.field(default=default, metadata=bounds)


def check_bounds(config: Any) -> None:
    """Refuse a field of the dataclass ``config`` outside its metadata's ``min``/``max`` (each
    width of a tuple, and ``max_len`` its length): one :class:`ConfigError` naming the field
    and the bound. Values of another type are left to the class's own type checks.

    >>> @dataclasses.dataclass(frozen=True)
    ... class Net:
    ...     hidden: tuple[int, ...] = bounded((64,), min=1, max=MAX_WIDTH, max_len=MAX_LAYERS)
    >>> check_bounds(Net(hidden=(64, 10**9)))
    Traceback (most recent call last):
    ...
    pokerirl.errors.ConfigError: hidden must be at most 4096 (each width), got 1000000000
    """
    for item in dataclasses.fields(config):
        low, high = item.metadata.get("min"), item.metadata.get("max")
        value = getattr(config, item.name)
        numbers, what = [value], ""
        if isinstance(value, tuple):
            numbers, what = list(value), " (each width)"
            longest = item.metadata.get("max_len")
            if longest is not None and len(value) > longest:
                raise ConfigError(
                    f"{item.name} must have at most {longest} entries, got {len(value)}"
                )
        for number in numbers:
            if isinstance(number, bool) or not isinstance(number, int | float):
                continue
            if low is not None and number < low:
                raise ConfigError(f"{item.name} must be at least {low}{what}, got {number}")
            if high is not None and number > high:
                raise ConfigError(f"{item.name} must be at most {high}{what}, got {number}")


def enum_value(name: str, kind: type[E], value: object) -> E:
    """``value`` as a member of ``kind`` (a setting read as a string from a file or a flag),
    or a one-line :class:`ConfigError` naming the setting and its values.

    >>> from pokerirl.errors import Remedy
    >>> enum_value("remedy", Remedy, "replace")
    <Remedy.REPLACE: 'replace'>
    >>> enum_value("remedy", Remedy, "delete")
    Traceback (most recent call last):
    ...
    pokerirl.errors.ConfigError: remedy must be one of recompute, replace, elsewhere, got 'delete'
    """
    if isinstance(value, str) and value in kind._value2member_map_:
        return kind(value)
    raise ConfigError(f"{name} must be one of {', '.join(kind)}, got {value!r}")


def with_overrides(
    presets: Mapping[str, C], name: str, /, what: str = "preset", **overrides: Any
) -> C:
    """The preset ``name`` of ``presets`` (frozen dataclasses) with ``overrides`` (None values
    ignored: not given). A one-line :class:`ConfigError` for an unknown ``what``, an unknown
    setting, or a value the dataclass's own checks refuse (their error, as raised)."""
    if name not in presets:
        raise ConfigError(f"unknown {what} {name!r}; choose one of {', '.join(presets)}")
    preset = presets[name]
    changes = {key: value for key, value in overrides.items() if value is not None}
    known = {item.name for item in dataclasses.fields(preset) if item.init}  # type: ignore[arg-type]
    unknown = sorted(set(changes) - known)
    if unknown:
        known_names = ", ".join(sorted(known))
        raise ConfigError(f"unknown setting(s) {', '.join(unknown)}; known: {known_names}")
    return dataclasses.replace(preset, **changes)  # type: ignore[type-var]
