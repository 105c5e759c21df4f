"""Many heads-up limit hold'em hands in lock-step, with RLCard 1.2.0's ``limit-holdem`` rules.

Seats, not player ids: seat 0 posts the small blind (1 chip) and acts first preflop, seat 1
posts the big blind (2 chips). RLCard draws which player id is the small blind at random; here
the caller decides which agent sits where (see :mod:`pokerirl.game.match`). Observations carry
no seat or player id, so they are RLCard's exactly.

Betting as RLCard does it (``docs/rules.md`` lists how this differs from ACPC):

* a raise is 2 chips preflop and on the flop, 4 on the turn and river, and puts the raiser
  that much above the opponent's chips in this round; at most 4 raises per round, blinds not
  counted;
* call when behind, check when level, fold always; anything else raises
  :class:`IllegalActionError` (RLCard's env silently swaps illegal actions for check or fold);
* a round closes after two actions in a row without a raise (a raise counts as the first of
  them); the player who did not close it acts first in the next round;
* the hand ends on a fold or after the river; payoffs are net chips / big blind.

All state lives in numpy arrays of length B; every method works on an index array of hands,
and only unfinished hands are visited, so hands that end early cost nothing afterwards.

>>> from pokerirl.holdem import CALL, CHECK, FOLD
>>> game = LimitHoldemBatch.from_seed(seed=0, start=0, count=2)
>>> game.legal_mask().astype(int).tolist()  # call, raise, fold, check for both small blinds
[[1, 1, 1, 0], [1, 1, 1, 0]]
>>> game.step(np.array([CALL, FOLD]))  # hand 0 limps, hand 1's small blind folds
>>> game.active().tolist(), game.legal_mask().astype(int).tolist()
([0], [[0, 1, 1, 1]])
>>> game.step(np.array([CHECK]))  # the big blind checks: on to the flop, small blind first
>>> int(game.round[0]), int(game.to_act[0]), game.payoffs[1].tolist()
(1, 0, [-0.5, 0.5])
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pokerirl.errors import PokerIRLError
from pokerirl.game.deals import DEAL_SIZE, deal_cards
from pokerirl.game.evaluator import showdown_strengths
from pokerirl.holdem import (
    BOARD_SIZE_BY_ROUND,
    CALL,
    CHECK,
    FOLD,
    MAX_RAISES,
    NUM_ACTIONS,
    NUM_ROUNDS,
    RAISE,
    encode_obs,
)

SMALL_BLIND = 1
BIG_BLIND = 2
RAISE_SIZE_BY_ROUND = np.array([2, 2, 4, 4], dtype=np.int16)
SHOWDOWN = NUM_ROUNDS  # value of ``round`` once the river has closed
# (round, card) -> visible, for a seat's 2 hole cards then the board; round 4 is after the river.
_VISIBLE = np.arange(7) < 2 + np.array((*BOARD_SIZE_BY_ROUND, 5))[:, None]
# _LEGAL[4 * situation + action], situation = behind the opponent + 2 x (a raise is left).
_LEGAL_BY_SITUATION = np.zeros((4, NUM_ACTIONS), dtype=bool)
_LEGAL_BY_SITUATION[:, FOLD] = True
_LEGAL_BY_SITUATION[[1, 3], CALL] = True
_LEGAL_BY_SITUATION[[0, 2], CHECK] = True
_LEGAL_BY_SITUATION[[2, 3], RAISE] = True
_LEGAL = _LEGAL_BY_SITUATION.reshape(-1)
# A hot step reads these tables by arithmetic on small integers, not by gathers (a gather
# from a four-entry table costs several times a few int8 operations): each situation's legal
# actions as bits (bit a: action a) and as a word of four bytes (``legal_mask_of`` reads it),
# both sums of a part for being level, one for being behind and one for a raise left.
_LEGAL_BITS = (_LEGAL_BY_SITUATION << np.arange(NUM_ACTIONS)).sum(axis=1).astype(np.int8)
_LEGAL_WORDS = _LEGAL_BY_SITUATION.view(np.int32).reshape(-1)


def _by_parts(table: np.ndarray, situation: np.ndarray) -> np.ndarray:
    """``table[situation]`` (four entries, in the table's dtype) for int8 situations: level +
    behind part + raise part."""
    level = table[0]
    return level + (table[1] - level) * (situation & 1) + (table[2] - level) * (situation >> 1)


def _raise_sizes(rnd: np.ndarray) -> np.ndarray:
    """``RAISE_SIZE_BY_ROUND[rnd]`` (2, 2, 4, 4) by a shift of int8 rounds."""
    return RAISE_SIZE_BY_ROUND[0] << (rnd >> 1)


class IllegalActionError(PokerIRLError, ValueError):
    """An action that is not legal for the hand it was given to (``position``: its place in
    the actions, where known)."""

    def __init__(self, message: str, *, position: int | None = None) -> None:
        super().__init__(message)
        self.position = position


def whole_actions(actions: np.ndarray) -> np.ndarray:
    """``actions`` as integers: whole numbers only (1.0 is a raise; 1.5 becomes -1, which no
    hand allows)."""
    actions = np.asarray(actions)
    if actions.dtype.kind not in "iu":
        whole = actions.astype(np.int64)
        actions = np.where(whole == actions, whole, -1)
    return actions


@dataclass(frozen=True, kw_only=True)
class Turn:
    """The state the seats to act in ``hands`` face (see :meth:`LimitHoldemBatch.turn`)."""

    hands: np.ndarray  # (n,) hand indices
    seat: np.ndarray  # seat to act
    mine_at: np.ndarray  # flat index of its chips (^ 1: the opponent's)
    rnd: np.ndarray  # betting round
    raises_at: np.ndarray  # flat index of this round's raise count
    mine: np.ndarray  # chips it has put in this round
    theirs: np.ndarray  # ... and the opponent
    raised: np.ndarray  # raises this round
    situation: np.ndarray  # behind the opponent + 2 x (a raise is left)

    @property
    def legal_words(self) -> np.ndarray:
        """(n,) int32: each legal mask's four bytes as one word (``legal_mask_of`` reads
        them back): no row gather, and cheap to split between agents."""
        return _by_parts(_LEGAL_WORDS, self.situation)

    @property
    def legal_mask(self) -> np.ndarray:
        """(n, 4) bool over (call, raise, fold, check)."""
        return legal_mask_of(self.legal_words)


def legal_mask_of(words: np.ndarray) -> np.ndarray:
    """(n, 4) bool legal masks of (n,) words from :attr:`Turn.legal_words`."""
    return words.view(np.bool_).reshape(-1, NUM_ACTIONS)


class LimitHoldemBatch:
    """B hands of heads-up limit hold'em in lock-step (seat 0 = small blind).

    Public state, (B,) or (B, k) arrays, read-only for callers:

    * ``cards`` (B, 9) int8 deal: seat 0 hole, seat 1 hole, board;
    * ``round`` int8, 0 preflop .. 3 river, 4 after a showdown;
    * ``raises`` (B, 4) int8: raises per round as RLCard counts them (big blind excluded);
    * ``chips`` (B, 2) int16: chips each seat has put in; ``round_chips`` (B, 2): in this round;
    * ``to_act`` int8 seat to act; ``done`` bool; ``folded`` bool, True when a fold ended it;
    * ``payoffs`` (B, 2) float64 net big blinds per seat, set when the hand ends.

    Args:
        deals: (B, 9) card indices, e.g. from :func:`pokerirl.game.deals.deal_cards`.
    """

    def __init__(self, *, deals: np.ndarray) -> None:
        self.reset(deals=deals)

    @classmethod
    def from_seed(cls, *, seed: int, start: int, count: int) -> LimitHoldemBatch:
        """A batch of deals ``start .. start + count - 1`` of ``seed`` (see ``deal_cards``)."""
        return cls(deals=deal_cards(seed=seed, start=start, count=count))

    def reset(self, *, deals: np.ndarray) -> None:
        """Start a new hand for every row of ``deals``: blinds posted, small blind to act."""
        deals = np.asarray(deals)
        if deals.ndim != 2 or deals.shape[1] != DEAL_SIZE:
            raise ValueError(f"deals must have shape (B, {DEAL_SIZE}), got {deals.shape}")
        n = deals.shape[0]
        self.cards = deals.astype(np.int8)
        self.round = np.zeros(n, dtype=np.int8)
        self.raises = np.zeros((n, NUM_ROUNDS), dtype=np.int8)
        self.chips = np.tile(np.array([SMALL_BLIND, BIG_BLIND], dtype=np.int16), (n, 1))
        self.round_chips = self.chips.copy()
        self.to_act = np.zeros(n, dtype=np.int8)
        self.done = np.zeros(n, dtype=bool)
        self.folded = np.zeros(n, dtype=bool)
        self.payoffs = np.zeros((n, 2), dtype=np.float64)
        # Actions in a row without a raise; the round closes at two (RLCard's not_raise_num).
        self._unraised = np.zeros(n, dtype=np.int8)
        self._active = np.arange(n)
        # Flat views: one 1-D gather at hand * width + column beats 2-D fancy indexing.
        self._chips = self.chips.reshape(-1)
        self._round_chips = self.round_chips.reshape(-1)
        self._raises = self.raises.reshape(-1)
        self._seat_views: np.ndarray | None = None  # built by the first observation

    @property
    def _views(self) -> np.ndarray:
        """Row hand * 2 + seat: that seat's hole cards and the whole board, for observations
        (built when first read: a match of agents that read none never needs them)."""
        if self._seat_views is None:
            # Filled by slices: a third cheaper than a gather, a repeat and a concatenation.
            views = np.empty((self.size, 2, 7), dtype=np.int8)
            views[:, 0, :2], views[:, 1, :2] = self.cards[:, 0:2], self.cards[:, 2:4]
            views[:, :, 2:] = self.cards[:, None, 4:]
            self._seat_views = views.reshape(2 * self.size, 7)
        return self._seat_views

    @property
    def size(self) -> int:
        """Number of hands B."""
        return self.cards.shape[0]

    def active(self) -> np.ndarray:
        """Indices of the hands not yet finished, ascending."""
        return self._active

    def _hands(self, hands: np.ndarray | None) -> np.ndarray:
        return self._active if hands is None else np.asarray(hands, dtype=np.int64)

    def observe(
        self, hands: np.ndarray | None = None, seat: np.ndarray | None = None
    ) -> np.ndarray:
        """RLCard's (n, 72) uint8 observation of ``seat`` (default: the seat to act).

        Args:
            hands: (n,) hand indices; default :meth:`active`.
            seat: (n,) seats (0 or 1) whose view to encode; default the seat to act.
        """
        hands = self._hands(hands)
        seat = self.to_act[hands] if seat is None else np.asarray(seat)
        visible = np.where(_VISIBLE[self.round[hands]], self._views[2 * hands + seat], -1)
        return encode_obs(visible, self.raises[hands])

    def legal_mask(self, hands: np.ndarray | None = None) -> np.ndarray:
        """(n, 4) bool mask over (call, raise, fold, check) for the seat to act.

        Only meaningful for unfinished hands.
        """
        return self.turn(self._hands(hands)).legal_mask

    def turn(self, hands: np.ndarray) -> Turn:
        """What the seats to act in ``hands`` (distinct, unfinished) face, gathered once for
        both their legal mask and :meth:`apply` (a match reads each decision's state once)."""
        seat = self.to_act[hands]
        mine_at = 2 * hands + seat  # flat index of the actor's chips; ^ 1 is the opponent's
        rnd = self.round[hands]
        raises_at = NUM_ROUNDS * hands + rnd
        mine, theirs = self._round_chips[mine_at], self._round_chips[mine_at ^ 1]
        raised = self._raises[raises_at]
        # Situation (behind?, may raise?) in int8: the legal actions are read from it.
        situation = (mine < theirs).view(np.int8) + 2 * (raised < MAX_RAISES).view(np.int8)
        return Turn(hands=hands, seat=seat, mine_at=mine_at, rnd=rnd, raises_at=raises_at,
                    mine=mine, theirs=theirs, raised=raised, situation=situation)  # fmt: skip

    def step(self, actions: np.ndarray, hands: np.ndarray | None = None) -> None:
        """Apply one action to each of ``hands`` (distinct, unfinished; default :meth:`active`).

        Raises:
            IllegalActionError: if any action is not legal in its hand; nothing is applied then.
        """
        hands = self._hands(hands)
        actions = whole_actions(actions)
        if actions.shape != hands.shape:
            raise ValueError(f"got {actions.shape} actions for {hands.shape} hands")
        if self.done[hands].any():
            raise IllegalActionError(f"hand {hands[self.done[hands]][0]} is already over")
        self.apply(self.turn(hands), actions)

    def apply(self, turn: Turn, actions: np.ndarray) -> None:
        """:meth:`step` from the :meth:`turn` of its hands, taken since no step touched them;
        ``actions`` (n,) integers (see :func:`whole_actions`).

        Raises:
            IllegalActionError: as :meth:`step` (its ``position``: the first bad one in
                ``turn.hands``); nothing is applied then.
        """
        hands, situation = turn.hands, turn.situation
        in_range = not actions.size or (actions.min() >= 0 and actions.max() < NUM_ACTIONS)
        action = actions.astype(np.int8) if in_range else actions  # int8: a few times faster
        if not in_range or not ((_by_parts(_LEGAL_BITS, situation) >> action) & 1).all():
            legal = (actions >= 0) & (actions < NUM_ACTIONS)
            legal &= _LEGAL[NUM_ACTIONS * situation + np.clip(actions, 0, NUM_ACTIONS - 1)]
            bad = int(np.flatnonzero(~legal)[0])
            allowed = np.flatnonzero(_LEGAL_BY_SITUATION[situation[bad]]).tolist()
            raise IllegalActionError(
                f"action {actions[bad]} is illegal in hand {hands[bad]} (legal: {allowed})",
                position=bad,
            )

        seat, mine_at, mine = turn.seat, turn.mine_at, turn.mine
        is_raise, not_fold = action == RAISE, action != FOLD
        # A call or a check matches the opponent; a raise goes one raise size above them.
        added = (turn.theirs - mine) * not_fold + _raise_sizes(turn.rnd) * is_raise
        self._chips[mine_at] += added
        self._round_chips[mine_at] = mine + added
        self._raises[turn.raises_at] = turn.raised + is_raise
        # Actions in a row without a raise (RLCard's not_raise_num): a raise is the first, a
        # fold leaves the count (it ends the hand).
        before = self._unraised[hands]
        unraised = before + not_fold - before * is_raise
        self._unraised[hands] = unraised
        self.to_act[hands] = 1 - seat  # also the first to act next round: they did not close it

        # Indices, not boolean masks, to pick the few hands that fold or close a round: a
        # masked gather costs several times a gather by index.
        fold_at = np.flatnonzero(~not_fold)
        folds = hands[fold_at]
        self.folded[folds] = True
        close_at = np.flatnonzero(unraised >= 2)
        closed = hands[close_at]
        next_round = turn.rnd[close_at] + 1
        self.round[closed] = next_round
        self._round_chips[mine_at[close_at]] = 0
        self._round_chips[mine_at[close_at] ^ 1] = 0
        self._unraised[closed] = 0
        showdown_at = close_at[np.flatnonzero(next_round == SHOWDOWN)]
        self._settle(folds, seat[fold_at], hands[showdown_at])
        if hands is self._active:  # a match's step: the hands still in play are the others
            keep = np.ones(hands.size, dtype=bool)
            keep[fold_at], keep[showdown_at] = False, False
            self._active = hands[np.flatnonzero(keep)]
        elif fold_at.size or showdown_at.size:
            self._active = self._active[np.flatnonzero(~self.done[self._active])]

    def _settle(self, folds: np.ndarray, loser: np.ndarray, showdowns: np.ndarray) -> None:
        """Payoffs of hands that just ended (``loser``: the folding seats); marks them done."""
        if folds.size:
            # Flat places: one 1-D gather at hand * 2 + seat beats 2-D fancy indexing.
            lost_at = 2 * folds + loser
            lost = self._chips[lost_at] / BIG_BLIND
            payoffs = self.payoffs.reshape(-1)
            payoffs[lost_at] = -lost
            payoffs[lost_at ^ 1] = lost
        if showdowns.size:
            # Both seats' seven cards in one pass of the evaluator (the engine's own cards:
            # no checks); (n, 2) strengths.
            strength = showdown_strengths(self.cards[showdowns]).astype(np.int64)
            # Both seats have equal chips in at a showdown; a tie returns them.
            won = np.sign(strength[:, 0] - strength[:, 1]) * (
                self._chips[2 * showdowns] / BIG_BLIND
            )
            self.payoffs[showdowns, 0] = won
            self.payoffs[showdowns, 1] = 0.0 - won  # not -won: no -0.0 for split pots
        self.done[folds] = True
        self.done[showdowns] = True
