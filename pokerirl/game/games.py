"""What a two-player game is to pokerirl: a :class:`Game` deals :class:`Hands` played in
lock-step (who acts, the legal actions, a step, the actor's observation and information-set
key, the payoffs), and names the table its decisions make (:class:`~pokerirl.game.spec.TableSpec`).

Heads-up limit hold'em (:data:`HOLDEM`, on :class:`~pokerirl.game.engine.LimitHoldemBatch`)
and Leduc hold'em (:class:`LeducGame`, on :class:`~pokerirl.game.leduc.batch.LeducBatch`)
both implement it; a third game implements it too (docs/architecture.md). The commands'
fast paths read each engine directly (hold'em's matches gather a decision's state once;
Leduc's are exact over the betting tree); :func:`play_out` is the game-blind loop.

>>> hands = HOLDEM.deal(hands=3, seed=0)
>>> payoffs = play_out(hands, uniform_legal(np.random.default_rng(0)))
>>> payoffs.shape, bool((payoffs.sum(axis=1) == 0).all())
((3, 2), True)
>>> leduc = LeducGame(RLCARD)
>>> leduc.actions, leduc.unit
(('fold', 'check', 'call', 'raise'), 'chips')
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from pokerirl.game.deals import deal_cards
from pokerirl.game.encodings import RLCARD as RLCARD_ENCODING
from pokerirl.game.engine import IllegalActionError, LimitHoldemBatch
from pokerirl.game.leduc.batch import LeducBatch
from pokerirl.game.leduc.infosets import info_sets
from pokerirl.game.leduc.rules import RLCARD, LeducRules
from pokerirl.game.spec import LEDUC, GameName, TableSpec, holdem_spec
from pokerirl.holdem import ACTIONS as HOLDEM_ACTIONS


@runtime_checkable
class Hands(Protocol):
    """Hands of one game in lock-step. ``hands`` arguments are (n,) distinct indices of
    unfinished hands; actions are indices into the game's :attr:`Game.actions`."""

    @property
    def size(self) -> int:
        """How many hands."""
        ...

    def active(self) -> np.ndarray:
        """(n,) indices of the hands not over, ascending."""
        ...

    def actors(self, hands: np.ndarray) -> np.ndarray:
        """(n,) the seat to act in each of ``hands`` (0 or 1)."""
        ...

    def legal_mask(self, hands: np.ndarray) -> np.ndarray:
        """(n, actions) bool: the actor's legal actions."""
        ...

    def step(self, actions: np.ndarray, hands: np.ndarray) -> None:
        """Play one action in each of ``hands``; an ``IllegalActionError`` (nothing played)
        if one is illegal."""
        ...

    def observe(self, hands: np.ndarray) -> np.ndarray:
        """(n, width) the actor's observation in the game's default encoding."""
        ...

    def infoset_keys(self, hands: np.ndarray) -> np.ndarray:
        """(n,) keys, equal where the actor cannot tell the states apart under the game's
        encoding."""
        ...

    def payoffs(self) -> np.ndarray:
        """(size, 2) float64 each seat's net winnings in the game's unit (0 while a hand
        is not over)."""
        ...


@runtime_checkable
class Game(Protocol):
    """A two-player game: its name, actions, unit of winnings, deals and table."""

    @property
    def name(self) -> GameName: ...

    @property
    def actions(self) -> tuple[str, ...]: ...

    @property
    def unit(self) -> str: ...

    def deal(self, *, hands: int, seed: int) -> Hands:
        """``hands`` new hands, dealt from ``seed`` (the same seed, the same deals)."""
        ...

    def table_spec(self) -> TableSpec:
        """What a table of this game's decisions is (its encoding's width and actions)."""
        ...


class HoldemHands:
    """:class:`Hands` of heads-up limit hold'em: ``batch`` the engine, read directly by the
    commands. Its information-set key is RLCard's 72-bit observation (hole and public cards,
    raises per round): what RLCard's agents and the ``rlcard`` encoding see, which forgets
    the order of the bets within a round."""

    def __init__(self, batch: LimitHoldemBatch) -> None:
        self.batch = batch

    @property
    def size(self) -> int:
        return self.batch.size

    def active(self) -> np.ndarray:
        return self.batch.active()

    def actors(self, hands: np.ndarray) -> np.ndarray:
        return self.batch.to_act[hands].astype(np.int64)

    def legal_mask(self, hands: np.ndarray) -> np.ndarray:
        return self.batch.legal_mask(hands)

    def step(self, actions: np.ndarray, hands: np.ndarray) -> None:
        self.batch.step(actions, hands)

    def observe(self, hands: np.ndarray) -> np.ndarray:
        return self.batch.observe(hands)

    def infoset_keys(self, hands: np.ndarray) -> np.ndarray:
        bits = np.packbits(self.batch.observe(hands), axis=1)
        return np.ascontiguousarray(bits).view(f"V{bits.shape[1]}").reshape(-1)

    def payoffs(self) -> np.ndarray:
        return self.batch.payoffs.copy()


class LeducHands:
    """:class:`Hands` of Leduc hold'em: ``batch`` the engine. Its information-set key is the
    set's name in :func:`~pokerirl.game.leduc.infosets.info_sets` (the actor's card, the
    public card once shown, the betting so far), exact: Leduc keeps the whole history."""

    def __init__(self, batch: LeducBatch) -> None:
        self.batch = batch
        self._sets = info_sets(batch.rules)
        self._names = np.asarray(self._sets.keys)

    @property
    def size(self) -> int:
        return len(self.batch.node)

    def active(self) -> np.ndarray:
        return np.flatnonzero(~self.batch.over)

    def actors(self, hands: np.ndarray) -> np.ndarray:
        return self.batch.to_act[hands]

    def legal_mask(self, hands: np.ndarray) -> np.ndarray:
        return self.batch.legal()[hands]

    def step(self, actions: np.ndarray, hands: np.ndarray) -> None:
        batch = self.batch
        if batch.over[hands].any():
            raise IllegalActionError(f"hand {hands[batch.over[hands]][0]} is already over")
        nxt = batch.arrays.child[batch.node[hands], np.asarray(actions, dtype=np.int64)]
        if np.any(nxt < 0):
            raise IllegalActionError(f"an illegal action in hand {hands[nxt < 0][0]}")
        batch.node[hands] = nxt

    def observe(self, hands: np.ndarray) -> np.ndarray:
        return self.batch.observations(self.batch.to_act.clip(0))[hands]

    def infoset_keys(self, hands: np.ndarray) -> np.ndarray:
        rows = self._sets.rows_of(self.batch.node[hands], self.batch.cards[hands])
        return self._names[rows]

    def payoffs(self) -> np.ndarray:
        return self.batch.payoffs()


@dataclass(frozen=True)
class HoldemGame:
    """Heads-up limit hold'em under RLCard 1.2.0's rules; winnings in big blinds."""

    @property
    def name(self) -> GameName:
        return GameName.HOLDEM

    @property
    def actions(self) -> tuple[str, ...]:
        return tuple(HOLDEM_ACTIONS)

    @property
    def unit(self) -> str:
        return "big blinds"

    def deal(self, *, hands: int, seed: int) -> HoldemHands:
        return HoldemHands(LimitHoldemBatch(deals=deal_cards(seed=seed, start=0, count=hands)))

    def table_spec(self) -> TableSpec:
        return holdem_spec(RLCARD_ENCODING)


@dataclass(frozen=True)
class LeducGame:
    """Leduc hold'em under ``rules`` (RLCard's or OpenSpiel's); winnings in chips."""

    rules: LeducRules = RLCARD

    @property
    def name(self) -> GameName:
        return GameName.LEDUC

    @property
    def actions(self) -> tuple[str, ...]:
        return LEDUC.actions

    @property
    def unit(self) -> str:
        return "chips"

    def deal(self, *, hands: int, seed: int) -> LeducHands:
        return LeducHands(LeducBatch.dealt(self.rules, hands, np.random.default_rng(seed)))

    def table_spec(self) -> TableSpec:
        return LEDUC


HOLDEM = HoldemGame()

Choose = Callable[[Hands, np.ndarray], np.ndarray]


def play_out(hands: Hands, choose: Choose) -> np.ndarray:
    """Play every hand to its end, ``choose(hands, live)`` giving the actions of the hands
    ``live`` at each step; their :meth:`Hands.payoffs`."""
    while (live := hands.active()).size:
        hands.step(choose(hands, live), live)
    return hands.payoffs()


def uniform_legal(rng: np.random.Generator) -> Choose:
    """A chooser drawing each action uniformly among the legal ones."""

    def choose(hands: Hands, live: np.ndarray) -> np.ndarray:
        legal = hands.legal_mask(live)
        return np.argmax(rng.random(legal.shape) * legal, axis=1)

    return choose
