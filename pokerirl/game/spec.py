"""What a table of decisions is of: the game, and the encoding of its states (the width of a
row, the actions and their names). It travels with the data from the reader to the run's
``config.json``, so that no layer above passes a game's or an encoding's name.

Torch-free; ``irl/`` never sees it (it gets :class:`~pokerirl.irl.Transitions`). A third
game provides a :class:`GameName`, a spec (as :data:`LEDUC` here) and a reader in
:mod:`pokerirl.datasets.decisions` (docs/architecture.md).

>>> from pokerirl.game.encodings import RLCARD
>>> holdem_spec(RLCARD).record(), holdem_spec(RLCARD).num_actions
({'encoding': 'rlcard'}, 4)
>>> LEDUC.record(), LEDUC.width
({'encoding': 'leduc-rlcard', 'game': 'leduc'}, 36)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum

from pokerirl.game.encodings import Encoding
from pokerirl.game.leduc.batch import ACTIONS as LEDUC_ACTIONS
from pokerirl.game.leduc.engine import OBSERVATION_SIZE
from pokerirl.holdem import ACTIONS as HOLDEM_ACTIONS


class GameName(StrEnum):
    """The games a table of decisions can be of."""

    HOLDEM = "holdem"  # heads-up limit hold'em, RLCard 1.2.0's rules
    LEDUC = "leduc"


@dataclass(frozen=True, kw_only=True)
class TableSpec:
    """The game of a table and its encoding: ``encoding`` is the spec runs record
    (``config.json``'s ``data.encoding``), ``width`` a row's features, ``actions`` the
    columns of the legal mask and the ids of the actions, by name."""

    game: GameName
    encoding: str
    width: int
    actions: tuple[str, ...]

    @property
    def num_actions(self) -> int:
        return len(self.actions)

    def record(self) -> dict[str, str]:
        """The keys a run's ``config.json`` records under ``data``; ``game`` only for a game
        other than hold'em, so that hold'em runs keep their bytes."""
        found = {"encoding": self.encoding}
        if self.game is not GameName.HOLDEM:
            found["game"] = str(self.game)
        return found


def holdem_spec(encoding: Encoding) -> TableSpec:
    """A hold'em table's spec, its states in ``encoding``."""
    return TableSpec(
        game=GameName.HOLDEM, encoding=encoding.spec, width=encoding.width, actions=HOLDEM_ACTIONS
    )


# Leduc demonstrations (pokerirl leduc synth): RLCard's 36-d leduc-holdem observation.
LEDUC = TableSpec(
    game=GameName.LEDUC,
    encoding="leduc-rlcard",
    width=OBSERVATION_SIZE,
    actions=tuple(str(a) for a in LEDUC_ACTIONS),
)


def recorded_game(data: Mapping[str, object] | None) -> GameName | None:
    """The game a run's ``config.json`` ``data`` records (hold'em when it names none), or None
    for one this version does not know."""
    name = data.get("game", GameName.HOLDEM) if isinstance(data, Mapping) else GameName.HOLDEM
    try:
        return GameName(str(name)) if isinstance(name, str) else None
    except ValueError:
        return None
