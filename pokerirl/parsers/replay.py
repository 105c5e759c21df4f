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

from pokerirl.encoding import CALL, CHECK, FOLD, MAX_RAISES, NUM_ROUNDS, RAISE

# Chips are counted in small blinds: blinds 1 and 2, bets 2 preflop and on the flop, 4 later.
BET_IN_SMALL_BLINDS = (2, 2, 4, 4)
_FOLDS = frozenset("fQK")
_ACTIONS = frozenset("kcbrAfQK")


class ReplayError(ValueError):
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


@lru_cache(maxsize=1 << 16)
def replay_actions(strings: tuple[str, str, str, str, str, str, str, str]) -> Replay:
    """Replay ``(pos1 preflop, pos2 preflop, pos1 flop, pos2 flop, ..., pos2 river)``.

    ``-`` means no action on that street. Raises :class:`ReplayError` when the strings are not
    a playable hand: a check facing a bet, an action after the hand ended, a round left open.
    """
    for text in strings:
        if text != "-" and not set(text) <= _ACTIONS | {"B"}:
            raise ReplayError(f"unknown action code in {text!r}")
    pre1, pre2 = strings[0], strings[1]
    blinds = (pre1.startswith("B"), pre2.startswith("B"))
    if blinds == (True, True):
        street_in = [1, 2]
    elif blinds == (True, False):
        street_in = [2, 0]  # a lone blind is a full big blind
    elif blinds == (False, True):
        street_in = [0, 2]
    else:
        street_in = [0, 0]
    chips_in = list(street_in)
    raise_nums = [0] * NUM_ROUNDS
    decisions: list[Decision] = []
    hand_over = False
    all_in = [False, False]
    last_street = 0
    max_raises = 0

    for street in range(NUM_ROUNDS):
        texts = [strings[2 * street], strings[2 * street + 1]]
        texts = ["" if t == "-" else t for t in texts]
        if street == 0:
            texts = [t[1:] if posted else t for t, posted in zip(texts, blinds, strict=True)]
            if "B" in texts[0] or "B" in texts[1]:
                raise ReplayError("blind posted twice")
        elif "B" in texts[0] or "B" in texts[1]:
            raise ReplayError("blind after preflop")
        if hand_over or any(all_in):
            # After a fold only quits may trail; after an all-in nobody acts.
            allowed = _FOLDS if hand_over else frozenset()
            if not (set(texts[0]) | set(texts[1])) <= allowed:
                raise ReplayError("action after the hand ended")
            continue
        last_street = street
        if street > 0:
            street_in = [0, 0]
        cursor = [0, 0]
        to_act = [True, True]
        # A lone blind by position 1 was its pass-1 action, so position 2 acts first preflop.
        seat = 1 if street == 0 and blinds == (True, False) else 0
        while True:
            if not to_act[0] and not to_act[1]:
                break
            if not to_act[seat]:
                seat = 1 - seat
                continue
            text = texts[seat]
            if cursor[seat] >= len(text):
                raise ReplayError(f"street {street} ends before the round is closed")
            code = text[cursor[seat]]
            cursor[seat] += 1
            other = 1 - seat
            facing = street_in[other] > street_in[seat]
            if code == "k":
                if facing:
                    raise ReplayError("check facing a bet")
                action = CHECK
            elif code == "c":
                action = CALL if facing else CHECK
            elif code in "br":
                action = RAISE
            elif code == "A":
                action = CALL if facing else RAISE
                all_in[seat] = True
            else:
                action = FOLD
            legal = [facing, raise_nums[street] < MAX_RAISES, True, not facing]
            legal[action] = True
            decisions.append(
                Decision(
                    position=seat + 1,
                    street=street,
                    action_id=action,
                    raise_nums=tuple(min(n, MAX_RAISES) for n in raise_nums),  # type: ignore[arg-type]
                    legal_mask=tuple(legal),  # type: ignore[arg-type]
                    raises_uncapped=raise_nums[street],
                )
            )
            to_act[seat] = False
            if action == FOLD:
                hand_over = True
                break
            if action == CALL:
                chips_in[seat] += street_in[other] - street_in[seat]
                street_in[seat] = street_in[other]
            elif action == RAISE:
                bet = BET_IN_SMALL_BLINDS[street]
                new_level = max(street_in) + bet
                chips_in[seat] += new_level - street_in[seat]
                street_in[seat] = new_level
                raise_nums[street] += 1
                max_raises = max(max_raises, raise_nums[street])
                to_act[other] = not all_in[other]
            if all_in[other]:
                to_act[seat] = False
            seat = other
        # Left over: quits may trail a fold, and an ``A`` after a closed round marks a player
        # whose last call put them all-in. Nothing else may trail.
        for seat_index in (0, 1):
            rest = texts[seat_index][cursor[seat_index] :]
            if not rest or (hand_over and set(rest) <= _FOLDS):
                continue
            if rest == "A" and not hand_over:
                all_in[seat_index] = True
                continue
            raise ReplayError(f"extra actions {rest!r} on street {street}")

    return Replay(
        decisions=tuple(decisions),
        chips_in=(chips_in[0], chips_in[1]),
        showdown=not hand_over,
        last_street=last_street,
        blinds_posted=blinds,
        all_in=any(all_in),
        max_raises=max_raises,
    )
