"""One hand of two-player Leduc hold'em under a rule set: the deal, the legal actions, a step,
the payoffs in chips, each player's information-set key and RLCard's 36-d observation.

A hand is a frozen :class:`LeducState`; :meth:`LeducState.step` returns the next one. Players
are positions (0 acts first in the first round). The exact tools and the solver walk the
same rules through :mod:`pokerirl.game.leduc.tree`, which is built from this module.

>>> from pokerirl.game.leduc.rules import OPENSPIEL, Action
>>> state = deal(OPENSPIEL, cards=(5, 0, 2))  # Kh against Js, Qs to come
>>> state.legal_actions()
(<Action.CHECK: 'check'>, <Action.RAISE: 'raise'>)
>>> for action in (Action.RAISE, Action.CALL, Action.CHECK, Action.CHECK):
...     state = state.step(action)
>>> state.is_over, state.payoffs(), state.info_key(0)
(True, (3, -3), 'KhQs:rc/kk')
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from pokerirl.errors import ConfigError
from pokerirl.game.engine import IllegalActionError  # the hold'em engine's: one kind of error
from pokerirl.game.leduc.rules import Action, LeducRules, SecondRound

OBSERVATION_SIZE = 36  # RLCard's leduc-holdem: hand 3, public 3, own chips 15, other's 15


@dataclass(frozen=True, kw_only=True)
class LeducState:
    """A hand: its cards (position 0's, position 1's, the public card), the chips each has
    put in, the betting of each round so far (as key letters) and whose turn it is."""

    rules: LeducRules
    cards: tuple[int, int, int]
    chips: tuple[int, int]
    round: int = 0
    histories: tuple[str, ...] = ("",)
    to_act: int = 0
    raises: int = 0  # in this round
    settled: int = 0  # checks and calls since the last raise (RLCard's not_raise_num)
    folded: int | None = None
    round_chips: tuple[int, int] = field(default=(0, 0))  # put in during this round

    @property
    def is_over(self) -> bool:
        return self.folded is not None or self.round >= 2

    def legal_actions(self) -> tuple[Action, ...]:
        """The legal actions of the player to act, in a fixed order (fold, check, call, raise)."""
        if self.is_over:
            return ()
        facing = self.round_chips[1 - self.to_act] > self.round_chips[self.to_act]
        legal = []
        if facing or self.rules.fold_always_legal:
            legal.append(Action.FOLD)
        legal.append(Action.CALL if facing else Action.CHECK)
        if self.raises < self.rules.max_raises:
            legal.append(Action.RAISE)
        return tuple(legal)

    def step(self, action: Action) -> LeducState:
        """The state after the player to act plays ``action`` (an ``IllegalActionError`` if it
        is not legal)."""
        if action not in self.legal_actions():
            raise IllegalActionError(f"{action} is not legal here: {self.legal_actions()}")
        me, other = self.to_act, 1 - self.to_act
        histories = (*self.histories[:-1], self.histories[-1] + action.letter)
        if action is Action.FOLD:
            return replace(self, histories=histories, folded=me)
        round_chips, raises, settled = list(self.round_chips), self.raises, self.settled + 1
        if action is Action.RAISE:
            round_chips[me] = round_chips[other] + self.rules.bets[self.round]
            raises, settled = raises + 1, 1
        else:  # check or call
            round_chips[me] = round_chips[other]
        chips = list(self.chips)
        chips[me] += round_chips[me] - self.round_chips[me]
        if settled < 2:
            return replace(
                self, histories=histories, chips=(chips[0], chips[1]), to_act=other,
                raises=raises, settled=settled, round_chips=(round_chips[0], round_chips[1]),
            )  # fmt: skip
        first = other if self.rules.second_round is SecondRound.ALTERNATE else 0
        return replace(
            self, histories=histories if self.round else (*histories, ""),
            chips=(chips[0], chips[1]), round=self.round + 1, to_act=first, raises=0, settled=0,
            round_chips=(0, 0),
        )  # fmt: skip

    def payoffs(self) -> tuple[int, int]:
        """Each position's winnings in chips (zero-sum), once the hand is over."""
        if not self.is_over:
            raise ConfigError("the hand is not over")
        if self.folded is not None:
            loss = self.chips[self.folded]
            return (-loss, loss) if self.folded == 0 else (loss, -loss)
        sign = showdown(self.cards)
        return (sign * self.chips[1], -sign * self.chips[0])  # equal chips at a showdown

    def info_key(self, position: int) -> str:
        """What ``position`` knows: its card, the public card once shown, the betting.

        ``K:rc`` in the first round, ``KQ:rc/k`` in the second (suits too under OpenSpiel's
        rules: ``KhQs:rc/k``)."""
        public = self.cards[2] if self.round >= 1 else None
        return info_key(self.rules, self.cards[position], public, self.histories)

    def observation(self, position: int) -> np.ndarray:
        """RLCard's 36-d ``obs`` of ``position``: its rank (3), the public rank (3), its chips
        (15 one-hot from 0) and the other's (15)."""
        obs = np.zeros(OBSERVATION_SIZE)
        obs[self.cards[position] // 2] = 1
        if self.round >= 1:
            obs[3 + self.cards[2] // 2] = 1
        obs[6 + self.chips[position]] = 1
        obs[21 + self.chips[1 - position]] = 1
        return obs


def info_key(rules: LeducRules, card: int, public: int | None, histories: tuple[str, ...]) -> str:
    """The information-set key of a player holding ``card`` (see :meth:`LeducState.info_key`)."""
    seen = rules.key_card(card) + ("" if public is None else rules.key_card(public))
    return f"{seen}:{'/'.join(histories)}"


def showdown(cards: tuple[int, int, int]) -> int:
    """+1 when position 0 wins the showdown, -1 when it loses, 0 for a split.

    >>> showdown((0, 5, 1)), showdown((4, 2, 0)), showdown((0, 1, 4))
    (1, 1, 0)
    """
    return int(showdowns(np.array([cards]))[0])


def showdowns(cards: np.ndarray) -> np.ndarray:
    """:func:`showdown` of each row of ``hands x 3`` cards: a pair with the public card beats
    any high card, else the higher rank wins."""
    ranks = cards // 2
    strength = (ranks[:, :2] == ranks[:, 2:]) * 100 + ranks[:, :2]  # 100: above any rank
    return np.sign(strength[:, 0] - strength[:, 1])


def deal(rules: LeducRules, *, cards: tuple[int, int, int]) -> LeducState:
    """The first state of a hand with ``cards`` (position 0's, position 1's, public)."""
    if len(set(cards)) != 3 or not all(0 <= c < rules.cards for c in cards):
        raise ConfigError(f"need three different cards in 0..{rules.cards - 1}, got {cards}")
    return LeducState(
        rules=rules, cards=cards, chips=rules.chips_before, round_chips=rules.chips_before
    )


def random_deal(rules: LeducRules, rng: np.random.Generator) -> LeducState:
    """A hand dealt from a shuffled deck."""
    a, b, c = (int(x) for x in rng.choice(rules.cards, size=3, replace=False))
    return deal(rules, cards=(a, b, c))
