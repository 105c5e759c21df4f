"""Replay one heads-up hand's IRC action strings into RLCard-style decisions.

The IRC logs give each player four action strings, one per street. The k-th character is the
player's action on the k-th pass around the table, and in heads-up hands position 1 acts first
within every pass, preflop and postflop. Replaying them yields the ordered decisions with what
RLCard's limit-holdem state would show at each: the raise counts per round and the legal actions.

Replays depend only on the eight strings, and real play repeats the same lines endlessly, so
:func:`replay_actions` is memoized: most hands cost one dictionary lookup.

>>> replay = replay_actions(("Bc", "Bk", "kc", "b", "k", "k", "k", "k"))
>>> [(d.position, d.street, d.action_id) for d in replay.decisions][:5]
[(1, 0, 0), (2, 0, 3), (1, 1, 3), (2, 1, 1), (1, 1, 0)]
>>> replay.chips_in, replay.showdown
((4, 4), True)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

from pokerirl.errors import InputError
from pokerirl.holdem import CALL, CHECK, FOLD, MAX_RAISES, NUM_ROUNDS, RAISE

# Chips are counted in small blinds: blinds 1 and 2, bets 2 preflop and on the flop, 4 later.
BET_IN_SMALL_BLINDS = (2, 2, 4, 4)
_FOLDS = frozenset("fQK")
_ACTIONS = frozenset("kcbrAfQK")


class ReplayError(InputError):
    """The action strings do not describe a playable hand."""


@dataclass(frozen=True, slots=True)
class Decision:
    """One decision as RLCard would see it, just before the action is taken."""

    position: int  # 1 or 2
    street: int  # 0 preflop .. 3 river
    action_id: int  # RLCard id: call 0, raise 1, fold 2, check 3
    raise_nums: tuple[int, int, int, int]  # raises so far per round, capped at RLCard's 4
    legal_mask: tuple[bool, bool, bool, bool]  # RLCard's legal actions, plus the action taken
    raises_uncapped: int  # raises so far this round, without the cap


@dataclass(frozen=True, slots=True)
class Replay:
    """The outcome of replaying one hand's eight action strings."""

    decisions: tuple[Decision, ...]
    chips_in: tuple[int, int]  # per position, in small blinds (all-ins make this approximate)
    showdown: bool  # no one folded or quit
    last_street: int  # the last street on which anyone acted or the hand was still live
    blinds_posted: tuple[bool, bool]  # per position
    all_in: bool
    max_raises: int  # the most raises in any single round


def _opening_chips(blinds: tuple[bool, bool]) -> list[int]:
    """Chips each position has in the pot before the first action, in small blinds."""
    if blinds == (True, True):
        return [1, 2]
    if blinds == (True, False):
        return [2, 0]  # a lone blind is a full big blind
    if blinds == (False, True):
        return [0, 2]
    return [0, 0]


def _street_texts(
    strings: tuple[str, ...], street: int, blinds: tuple[bool, bool]
) -> tuple[str, str]:
    """The two positions' actions on ``street``, without the posted blinds."""
    texts = ["" if t == "-" else t for t in strings[2 * street : 2 * street + 2]]
    if street == 0:
        texts = [t[1:] if posted else t for t, posted in zip(texts, blinds, strict=True)]
        if "B" in texts[0] or "B" in texts[1]:
            raise ReplayError("blind posted twice")
    elif "B" in texts[0] or "B" in texts[1]:
        raise ReplayError("blind after preflop")
    return texts[0], texts[1]


def _action(code: str, facing: bool) -> int:
    """RLCard's action id for one IRC action code."""
    if code == "k":
        if facing:
            raise ReplayError("check facing a bet")
        return CHECK
    if code == "c":
        return CALL if facing else CHECK
    if code in "br":
        return RAISE
    if code == "A":
        return CALL if facing else RAISE
    return FOLD


class _Replayer:
    """The hand's state while its streets are replayed, one action at a time."""

    def __init__(self, blinds: tuple[bool, bool]) -> None:
        self.blinds = blinds
        self.street_in = _opening_chips(blinds)
        self.chips_in = list(self.street_in)
        self.raise_nums = [0] * NUM_ROUNDS
        self.decisions: list[Decision] = []
        self.hand_over = False
        self.all_in = [False, False]
        self.last_street = 0
        self.max_raises = 0

    def play_street(self, street: int, texts: tuple[str, str]) -> None:
        if self.hand_over or any(self.all_in):
            # After a fold only quits may trail; after an all-in nobody acts.
            allowed = _FOLDS if self.hand_over else frozenset()
            if not (set(texts[0]) | set(texts[1])) <= allowed:
                raise ReplayError("action after the hand ended")
            return
        self.last_street = street
        if street > 0:
            self.street_in = [0, 0]
        cursor = [0, 0]
        to_act = [True, True]
        # A lone blind by position 1 was its pass-1 action, so position 2 acts first preflop.
        seat = 1 if street == 0 and self.blinds == (True, False) else 0
        while to_act[0] or to_act[1]:
            if not to_act[seat]:
                seat = 1 - seat
                continue
            if cursor[seat] >= len(texts[seat]):
                raise ReplayError(f"street {street} ends before the round is closed")
            code = texts[seat][cursor[seat]]
            cursor[seat] += 1
            if self._act(street, seat, code, to_act):
                break
            seat = 1 - seat
        self._check_leftovers(street, texts, cursor)

    def _act(self, street: int, seat: int, code: str, to_act: list[bool]) -> bool:
        """Play ``code`` for ``seat``; True when it ends the hand."""
        other = 1 - seat
        facing = self.street_in[other] > self.street_in[seat]
        action = _action(code, facing)
        if code == "A":
            self.all_in[seat] = True
        legal = [facing, self.raise_nums[street] < MAX_RAISES, True, not facing]
        legal[action] = True
        self.decisions.append(
            Decision(
                position=seat + 1,
                street=street,
                action_id=action,
                raise_nums=tuple(min(n, MAX_RAISES) for n in self.raise_nums),  # type: ignore[arg-type]
                legal_mask=tuple(legal),  # type: ignore[arg-type]
                raises_uncapped=self.raise_nums[street],
            )
        )
        to_act[seat] = False
        if action == FOLD:
            self.hand_over = True
            return True
        if action == CALL:
            self.chips_in[seat] += self.street_in[other] - self.street_in[seat]
            self.street_in[seat] = self.street_in[other]
        elif action == RAISE:
            new_level = max(self.street_in) + BET_IN_SMALL_BLINDS[street]
            self.chips_in[seat] += new_level - self.street_in[seat]
            self.street_in[seat] = new_level
            self.raise_nums[street] += 1
            self.max_raises = max(self.max_raises, self.raise_nums[street])
            to_act[other] = not self.all_in[other]
        if self.all_in[other]:
            to_act[seat] = False
        return False

    def _check_leftovers(self, street: int, texts: tuple[str, str], cursor: list[int]) -> None:
        # Quits may trail a fold, and an ``A`` after a closed round marks a player whose last
        # call put them all-in. Nothing else may trail.
        for seat in (0, 1):
            rest = texts[seat][cursor[seat] :]
            if not rest or (self.hand_over and set(rest) <= _FOLDS):
                continue
            if rest == "A" and not self.hand_over:
                self.all_in[seat] = True
                continue
            raise ReplayError(f"extra actions {rest!r} on street {street}")


@lru_cache(maxsize=1 << 16)
def replay_actions(strings: tuple[str, str, str, str, str, str, str, str]) -> Replay:
    """Replay ``(pos1 preflop, pos2 preflop, pos1 flop, pos2 flop, ..., pos2 river)``.

    ``-`` means no action on that street. Raises :class:`ReplayError` when the strings are not
    a playable hand: a check facing a bet, an action after the hand ended, a round left open.
    """
    for text in strings:
        if text != "-" and not set(text) <= _ACTIONS | {"B"}:
            raise ReplayError(f"unknown action code in {text!r}")
    blinds = (strings[0].startswith("B"), strings[1].startswith("B"))
    hand = _Replayer(blinds)
    for street in range(NUM_ROUNDS):
        hand.play_street(street, _street_texts(strings, street, blinds))
    return Replay(
        decisions=tuple(hand.decisions),
        chips_in=(hand.chips_in[0], hand.chips_in[1]),
        showdown=not hand.hand_over,
        last_street=hand.last_street,
        blinds_posted=blinds,
        all_in=any(hand.all_in),
        max_raises=hand.max_raises,
    )
