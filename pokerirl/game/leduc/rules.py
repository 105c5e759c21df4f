"""The two rule sets of Leduc hold'em: RLCard 1.2.0's ``leduc-holdem`` and OpenSpiel's
``leduc_poker`` (docs/leduc.md says where they differ), the cards and the actions.

The deck holds two suits of ``ranks`` ranks (J, Q, K: six cards). Card ``c`` has rank
``c // 2`` and suit ``c % 2``, the order of RLCard's deck (SJ, HJ, SQ, HQ, SK, HK) and of
OpenSpiel's card ids. A pair with the public card wins, else the higher rank; equal ranks
split the pot.

>>> RLCARD.chips_before
(1, 2)
>>> card_name(5, suited=True), card_name(5, suited=False)
('Kh', 'K')
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from pokerirl.errors import ConfigError

RANK_NAMES = "JQKA23456789T"  # Leduc's J, Q, K first; a larger deck (tests) goes on
SUIT_NAMES = "sh"  # RLCard's deck order: S before H


class Action(StrEnum):
    """The four moves; OpenSpiel's one ``call`` is a check when no bet is faced."""

    FOLD = "fold"
    CHECK = "check"
    CALL = "call"
    RAISE = "raise"

    @property
    def letter(self) -> str:
        """The move's letter in an information-set key (``k`` for check)."""
        return LETTERS[self]


LETTERS = {Action.FOLD: "f", Action.CHECK: "k", Action.CALL: "c", Action.RAISE: "r"}


class RuleSet(StrEnum):
    """The rule sets by name (``--rules``)."""

    RLCARD = "rlcard"
    OPENSPIEL = "openspiel"


class SecondRound(StrEnum):
    """Who acts first in the second round."""

    ALTERNATE = "alternate"  # RLCard: the player who did not close the first round
    FIRST = "first"  # OpenSpiel: the first player of the first round


@dataclass(frozen=True, kw_only=True)
class LeducRules:
    """One rule set. Positions: 0 acts first in the first round (RLCard's small blind, seated
    at random by RLCard; OpenSpiel's player 0), 1 is the other."""

    name: str
    chips_before: tuple[int, int]  # in the pot before the first round, by position
    bets: tuple[int, int] = (2, 4)  # the raise size of each round
    max_raises: int = 2  # raises per round (RLCard's blinds are not raises)
    fold_always_legal: bool  # RLCard: fold even when checking is free; OpenSpiel: facing a bet
    second_round: SecondRound
    suited_keys: bool  # information sets tell the suits apart (OpenSpiel's strings do)
    ranks: int = 3  # the deck: two suits of this many ranks
    env_chips_per_unit: int  # the chips of one unit of the environment's payoffs

    def __post_init__(self) -> None:
        if not 2 <= self.ranks <= len(RANK_NAMES) or self.max_raises < 0 or min(self.bets) < 1:
            raise ConfigError(f"rules {self.name!r}: need 2..13 ranks, bets >= 1, raises >= 0")

    @property
    def cards(self) -> int:
        return 2 * self.ranks

    def key_card(self, card: int) -> str:
        """A card as an information-set key writes it."""
        return card_name(card, suited=self.suited_keys)


def card_name(card: int, *, suited: bool) -> str:
    """``Ks`` (suited) or ``K``."""
    rank = RANK_NAMES[card // 2]
    return rank + SUIT_NAMES[card % 2] if suited else rank


RLCARD = LeducRules(
    name=RuleSet.RLCARD,
    chips_before=(1, 2),  # blinds: the small blind acts first
    fold_always_legal=True,
    second_round=SecondRound.ALTERNATE,
    suited_keys=False,  # RLCard's observation knows ranks only
    env_chips_per_unit=2,  # RLCard's payoffs are in big blinds
)
OPENSPIEL = LeducRules(
    name=RuleSet.OPENSPIEL,
    chips_before=(1, 1),  # antes
    fold_always_legal=False,
    second_round=SecondRound.FIRST,
    suited_keys=True,  # "[Private: 3]": OpenSpiel's default has no suit isomorphism
    env_chips_per_unit=1,
)
RULES = {RuleSet.RLCARD: RLCARD, RuleSet.OPENSPIEL: OPENSPIEL}


def get_rules(name: str) -> LeducRules:
    """The rule set named ``name`` (a :class:`ConfigError` for another)."""
    try:
        return RULES[RuleSet(name)]
    except ValueError:
        raise ConfigError(
            f"unknown Leduc rules {name!r}: choose {', '.join(RuleSet)}"
        ) from None
