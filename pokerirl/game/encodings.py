"""Feature encodings of a poker decision: what a reward, a policy or a DQN sees of a state.

A decision state is what the engine and the decision tables both hold (:class:`RawStates`): the
player's hole cards and the board shown so far (in the order dealt, ``-1`` beyond), the
raises per round as RLCard counts them, and the legal actions. An :class:`Encoding` turns a
batch of them into one row of features each. Two exist:

* ``rlcard``: RLCard 1.2.0's 72-d ``limit-holdem`` observation (:func:`~pokerirl.holdem.
  encode_obs`), bit for bit: 52 card bits with hole and board merged, and a raise-count
  one-hot per round. The paper's protocol and the authors' stay on it.
* ``strength``: hole and board kept apart, and generic hand features computed by the
  vectorized evaluator (:data:`STRENGTH_FEATURES` lists them; ``docs/encodings.md`` says why
  each). None is a synthetic bot's own score.

An encoding has a version, and what runs and agents record is its ``spec``: ``rlcard``,
``strength-v2`` (equity exact on every street, :mod:`pokerirl.game.equity`), or
``strength-v1`` (equity after the flop from 64 fixed Monte Carlo runouts), which is what a
bare ``strength`` in a record made before versions means (:func:`recorded_encoding`). A user
asking for ``strength`` gets the current version (:func:`get_encoding`); a run of the old one
still loads, and says ``strength-v1``. A mismatch is refused in one line where it is loaded.

>>> from pokerirl.holdem import parse_card
>>> cards = np.array([[parse_card(c) for c in "As Ah Ad Kc 7h".split()] + [-1, -1]], np.int8)
>>> states = RawStates(cards=cards, raise_nums=np.zeros((1, 4), np.int8),
...                 legal_mask=np.array([[False, True, True, True]]))
>>> RLCARD.encode(states).shape, STRENGTH.encode(states).shape
((1, 72), (1, 174))
>>> row = STRENGTH.features(states)
>>> int(row["category"].argmax()) + 1, bool(row["equity"][0, 0] > 0.85)  # trips, far ahead
(4, True)
>>> STRENGTH.spec, recorded_encoding("strength").spec  # a bare name in a record: version 1
('strength-v2', 'strength-v1')
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import ClassVar

import numpy as np

from pokerirl.errors import ConfigError
from pokerirl.game.equity import exact_equity, range_equity
from pokerirl.game.evaluator import _RANK, _SUIT, hand_strength, pair_index
from pokerirl.game.preflop import sampled_preflop_equity
from pokerirl.holdem import (
    CALL,
    MAX_RAISES,
    NUM_CARDS,
    NUM_ROUNDS,
    OBS_SIZE,
    PAIRS,
    encode_obs,
    pair_cards,
)

NUM_RANKS = 13
BOARD_CARDS_BY_STREET = (0, 3, 4, 5)
# Chips in this game: blinds 1 and 2, bets 2 preflop and on the flop, 4 on the turn and river.
BET_BY_STREET = np.array([2, 2, 4, 4])
MAX_POT = 100  # 50 chips a player: 2 + 2·4 preflop, + 2·4 flop, + 4·4 turn, + 4·4 river
EQUITY_SAMPLES = 64  # version 1: Monte Carlo runouts per state after the flop
_SAMPLE_SEED = 20_261_204  # version 1's fixed sample bank: the same state, the same features
STRENGTH_VERSION = 2  # the current version: exact equity on every street

# Board cards shown (0 .. 5) -> street (0 preflop .. 3 river).
_STREET_OF_SHOWN = np.searchsorted(np.array(BOARD_CARDS_BY_STREET), np.arange(6))


class EncodingName(StrEnum):
    """The feature encodings."""

    RLCARD = "rlcard"
    STRENGTH = "strength"


@dataclass(frozen=True, kw_only=True, eq=False)
class RawStates:
    """A batch of decision states, as the engine and the tables hold them, before encoding.

    What an :class:`Encoding` reads; a reward reads
    :class:`~pokerirl.poker.rewards.ObservedDecisions` (the encoded observations).

    ``cards`` (N, 7): hole cards, then the board shown so far, ``-1`` beyond (see
    :func:`pokerirl.game.bots.seat_cards`); ``raise_nums`` (N, 4): raises per round as
    RLCard counts them (big blind excluded, capped at 4); ``legal_mask`` (N, 4) over (call,
    raise, fold, check).
    """

    cards: np.ndarray
    raise_nums: np.ndarray
    legal_mask: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.cards)
        shapes = (np.shape(self.cards), np.shape(self.raise_nums), np.shape(self.legal_mask))
        if shapes != ((n, 7), (n, NUM_ROUNDS), (n, 4)):
            raise ValueError(f"RawStates need (N, 7), (N, 4) and (N, 4) arrays, got {shapes}")

    def __len__(self) -> int:
        return len(self.cards)

    @property
    def street(self) -> np.ndarray:
        """(N,) 0 preflop .. 3 river, from how many board cards are shown."""
        return _STREET_OF_SHOWN[(np.asarray(self.cards)[:, 2:] >= 0).sum(axis=1)]

    def take(self, rows: np.ndarray) -> RawStates:
        rows = np.asarray(rows)
        return RawStates(cards=self.cards[rows], raise_nums=self.raise_nums[rows],
                      legal_mask=self.legal_mask[rows])  # fmt: skip


class Encoding:
    """A named feature map of :class:`RawStates` to (N, ``width``) rows of ``dtype``.

    ``needs_cards``: whether it reads the cards in the order dealt (hole apart from board),
    which RLCard's observation cannot give back.
    """

    name: ClassVar[EncodingName]
    width: ClassVar[int]
    dtype: ClassVar[type[np.generic]]
    needs_cards: ClassVar[bool]
    version: int = 1

    @property
    def spec(self) -> str:
        """What runs and agents record: the name, with ``-v<version>`` for an encoding that
        has had more than one."""
        return str(self.name)

    def encode(self, states: RawStates) -> np.ndarray:
        raise NotImplementedError

    def encode_pairs(self, pairs: np.ndarray, states: RawStates, of: np.ndarray) -> np.ndarray:
        """(R, ``width``) rows of hypothetical states: row r is state ``of[r]`` of ``states``
        with hole pair ``pairs[r]`` (a number of :data:`~pokerirl.holdem.PAIRS`) in place of
        its hole cards; the rows :meth:`encode` gives those states. Local best response
        encodes every pair of a range this way."""
        of = np.asarray(of, dtype=np.int64)
        cards = pair_cards(pairs, np.asarray(states.cards)[of, 2:]).astype(np.int8)
        return self.encode(RawStates(cards=cards, raise_nums=np.asarray(states.raise_nums)[of],
                                     legal_mask=np.asarray(states.legal_mask)[of]))  # fmt: skip

    def __repr__(self) -> str:
        return f"Encoding({self.spec!r}, width={self.width})"


class RLCardEncoding(Encoding):
    """RLCard 1.2.0's 72-d observation (uint8), bit for bit."""

    name = EncodingName.RLCARD
    width = OBS_SIZE
    dtype = np.uint8
    needs_cards = False

    def encode(self, states: RawStates) -> np.ndarray:
        return encode_obs(states.cards, states.raise_nums)


# The strength encoding's blocks, in order: name -> width.
STRENGTH_FEATURES: Mapping[str, int] = {
    "hole": NUM_CARDS,  # one-hot of the two hole cards
    "board": NUM_CARDS,  # one-hot of the board shown
    "raises": NUM_ROUNDS * (MAX_RAISES + 1),  # RLCard's raise-count one-hot per round
    "street": NUM_ROUNDS,  # one-hot
    "high_rank": NUM_RANKS,  # one-hot of the higher hole rank (2 .. A)
    "low_rank": NUM_RANKS,  # ... and of the lower one
    "pocket_pair": 1,
    "suited": 1,
    "category": 9,  # one-hot made hand of the visible cards: high card .. straight flush
    "hole_pairs_board": 1,  # hole cards whose rank is on the board: 0, 1/2 or 1
    "top_pair": 1,  # a hole card pairs the board's highest rank
    "overpair": 1,  # a pocket pair above every board card
    "flush_draw": 1,  # four of a suit with a hole card among them, cards to come
    "straight_draw": 1,  # four of five consecutive ranks with a hole card, cards to come
    "equity": 1,  # P(win) + P(tie)/2 against a random hand, the board rolled out (exact)
    "facing_bet": 1,
    "pot": 1,  # chips in the pot / MAX_POT
    "pot_odds": 1,  # to call / (pot + to call); 0 when not facing a bet
}


# Each block's columns (start, stop) in the strength encoding's row.
_EDGES = [0, *itertools.accumulate(STRENGTH_FEATURES.values())]
_COLUMNS: Mapping[str, tuple[int, int]] = dict(
    zip(STRENGTH_FEATURES, itertools.pairwise(_EDGES), strict=True)
)
# Where each one-hot block's first column is: a round's raise count's column is its own plus
# the round's; a card's its own plus its block's.
_ONE_HOT_AT: Mapping[str, int] = {
    name: _COLUMNS[name][0] for name in ("board", "street", "high_rank", "low_rank", "category")
}
_RAISE_COLUMN = _COLUMNS["raises"][0] + (MAX_RAISES + 1) * np.arange(NUM_ROUNDS)


class StrengthEncoding(Encoding):
    """Hole and board apart, plus generic hand features (float32; see the module docstring).

    ``version`` 2 (the current one) computes the equity exactly; version 1, kept so that runs
    made with it load and play as they were trained, estimates it after the flop from
    ``equity_samples`` fixed runouts (preflop from a 200,000-runout table).
    """

    name = EncodingName.STRENGTH
    width = sum(STRENGTH_FEATURES.values())
    dtype = np.float32
    needs_cards = True

    def __init__(
        self, *, version: int = STRENGTH_VERSION, equity_samples: int = EQUITY_SAMPLES
    ) -> None:
        if version not in (1, 2):
            raise ConfigError(f"the strength encoding has versions 1 and 2, not {version}")
        self.version = version
        self.equity_samples = equity_samples

    @property
    def spec(self) -> str:
        return f"{self.name}-v{self.version}"

    def encode(self, states: RawStates) -> np.ndarray:
        cards = np.asarray(states.cards, dtype=np.int64)
        if len(cards) and cards[:, :2].min() < 0:
            raise ValueError("the strength encoding needs both hole cards of every state")
        return self.encode_pairs(pair_index(cards[:, 0], cards[:, 1]), states)

    def encode_pairs(
        self, pairs: np.ndarray, states: RawStates, of: np.ndarray | None = None
    ) -> np.ndarray:
        """(R, width) row r: hole pair ``pairs[r]`` (a number of ``PAIRS``) in state
        ``of[r]`` of ``states`` (``of`` None: state r), as :meth:`encode` gives it."""
        # A row's ones come from the pair (a table of the 1,326 pairs), the state (its board
        # and betting, computed once a state: local best response encodes ~1,000 pairs of
        # each) and the category of both, in one scatter; then the numbers, those of both
        # from the two's packed cards. The same values as each block cast to float32, bit for
        # bit. A DQN's batches are small and many: few array operations, whatever their size.
        pairs = np.asarray(pairs, dtype=np.int64)
        own, of_state = _PAIR_FEATURES, _BoardFeatures.of(states)
        board = of_state if of is None else of_state.take(np.asarray(of, dtype=np.int64))
        masks = _suit_masks(own.packed[pairs] | board.packed)  # (4, R) suit by suit
        present = np.bitwise_or.reduce(masks, axis=0)
        flags = _SUIT_FLAGS[masks]
        category = _category(masks, present, flags) + _CATEGORY_AT
        found = np.zeros((len(pairs), self.width), dtype=np.float32)
        ones = np.concatenate([own.ones[pairs], board.ones, category[:, None]], axis=1)
        ones += (np.arange(len(pairs)) * self.width)[:, None]  # flat: the fastest scatter
        found.reshape(-1)[ones.reshape(-1)] = 1.0  # a card not shown: _SPARE
        found[:, _COLUMNS["pocket_pair"][0] : _COLUMNS["suited"][1]] = own.flags[pairs]
        found[:, _COLUMNS["facing_bet"][0] :] = board.numbers
        # Four of a suit holding a hole card: _FOUR_SUITED where a hole card is of the suit.
        suited_four = np.bitwise_or.reduce(flags & own.suits[:, pairs], axis=0)
        hole_bits, draws_possible = own.rank_bits[pairs], board.cards_to_come
        top_bit = board.top_bit
        paired = hole_bits & board.rank_bits  # the hole ranks on the board
        pocket = own.pocket[pairs]
        if self.version >= 2:  # each board's work once for all its rows
            equity = range_equity(pairs, of_state.cards, of)
        else:
            equity = self.equity(pair_cards(pairs, board.cards))
        found[:, _COLUMNS["hole_pairs_board"][0] : _COLUMNS["equity"][1]] = np.stack(
            [
                _POPCOUNT[paired] * (1 + pocket) / 2,  # a pocket pair: two cards
                (paired & top_bit) != 0,
                pocket & (own.high_bit[pairs] > top_bit) & (top_bit > 0),
                (suited_four != 0) & draws_possible,  # four of a suit: no flush in 7 cards
                ((_FOUR_OF_WINDOW[present] & hole_bits) != 0) & ~_STRAIGHT[present]
                & draws_possible,
                equity,
            ],
            axis=1,
        )  # fmt: skip
        return found

    def features(self, states: RawStates) -> dict[str, np.ndarray]:
        """Each block of :data:`STRENGTH_FEATURES` as an (N, width) float32 array (views of
        :meth:`encode`'s row)."""
        found = self.encode(states)
        return {name: found[:, start:stop] for name, (start, stop) in _COLUMNS.items()}

    def equity(self, cards: np.ndarray) -> np.ndarray:
        """(N,) equity against a uniformly random hand, the board rolled out. Version 2:
        exact (:func:`pokerirl.game.equity.exact_equity`). Version 1: preflop from its
        169-class Monte Carlo table, after the flop by ``equity_samples`` runouts of a fixed
        sample bank (a function of the cards alone: the same state, the same bytes)."""
        cards = np.asarray(cards, dtype=np.int64)
        if self.version >= 2:
            return exact_equity(cards)
        found = np.empty(len(cards))
        preflop = cards[:, 2] < 0
        found[preflop] = sampled_preflop_equity(cards[preflop, :2])
        later = np.flatnonzero(~preflop)
        for first in range(0, later.size, 4096):  # bounded memory: 4096 x samples x 7 cards
            rows = later[first : first + 4096]
            found[rows] = sampled_equity(cards[rows], samples=self.equity_samples)
        return found


@functools.cache
def _sample_bank(samples: int) -> np.ndarray:
    """(samples, 16) the first 16 cards of ``samples`` fixed random deck orders."""
    rng = np.random.default_rng(_SAMPLE_SEED)
    return rng.random((samples, NUM_CARDS)).argsort(axis=1)[:, :16]


def sampled_equity(cards: np.ndarray, *, samples: int = EQUITY_SAMPLES) -> np.ndarray:
    """(N,) Monte Carlo equity against a random hand of states with a board shown.

    Sample k deals, from the k-th fixed deck order, the first cards not already known: the
    opponent's two, then the board still to come. At most 7 cards are known and at most 7
    drawn, so the first 16 cards of an order always suffice.
    """
    cards = np.asarray(cards, dtype=np.int64)
    n = len(cards)
    bank = _sample_bank(samples)  # (K, 16)
    known = np.zeros((n, NUM_CARDS), dtype=bool)
    rows = np.repeat(np.arange(n), 7)
    flat = cards.reshape(-1)
    known[rows[flat >= 0], flat[flat >= 0]] = True
    free = ~known[:, bank]  # (N, K, 16): candidates not already known
    slot = np.cumsum(free, axis=2, dtype=np.int8) - 1  # the k-th free candidate goes to slot k
    keep = free & (slot < 7)
    drawn = np.empty((n, samples, 7), dtype=np.int64)
    where_n, where_k, where_j = np.nonzero(keep)
    drawn[where_n, where_k, slot[keep]] = bank[where_k, where_j]
    # The board still to come, in the order drawn after the opponent's two cards.
    missing = cards[:, 2:] < 0  # (N, 5), the same for every sample of a state
    fill = np.maximum(np.cumsum(missing, axis=1) - 1, 0) + 2
    to_come = np.take_along_axis(drawn, np.broadcast_to(fill[:, None, :], (n, samples, 5)), 2)
    board = np.where(missing[:, None, :], to_come, cards[:, None, 2:])
    mine = np.concatenate([np.broadcast_to(cards[:, None, :2], (n, samples, 2)), board], axis=2)
    theirs = np.concatenate([drawn[:, :, :2], board], axis=2)
    ours = hand_strength(mine.reshape(-1, 7)).reshape(n, samples)
    other = hand_strength(theirs.reshape(-1, 7)).reshape(n, samples)
    return ((ours > other) + 0.5 * (ours == other)).mean(axis=1)


def pot_and_call(
    street: np.ndarray, raise_nums: np.ndarray, facing: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(pot, to call) in chips for the player to act, from what RLCard's state holds.

    A round closes only with both players level, so each has ``2 + 2·r₀`` chips in after
    preflop, plus the bet size times the raises of each later closed round. In the current
    round the opponent is at the top level (the blind, or the last raise) and the player one
    bet below it when facing a bet (the small blind's 1 chip before any raise), else level.

    >>> pot, call = pot_and_call(np.array([0, 0, 1]), np.array([[0, 0, 0, 0], [1, 0, 0, 0],
    ...     [2, 1, 0, 0]]), np.array([True, True, True]))
    >>> pot.tolist(), call.tolist()
    ([3, 6, 14], [1, 2, 2])
    """
    street = np.asarray(street, dtype=np.int64)
    raises = np.asarray(raise_nums, dtype=np.int64)
    closed = np.arange(NUM_ROUNDS)[None, :] < street[:, None]
    before = np.where(closed[:, 0], 2, 0) + (np.where(closed, raises, 0) * BET_BY_STREET).sum(1)
    now = raises[np.arange(len(street)), street]
    bet = BET_BY_STREET[street]
    top = np.where(street == 0, 2, 0) + bet * now
    below = np.where((street == 0) & (now == 0), 1, top - bet)
    mine = np.where(facing, below, top)
    return 2 * before + top + mine, top - mine


# Rank masks: bit r for rank r (2 .. A as 0 .. 12). A straight is one of ten windows (the
# wheel: A 2 3 4 5); tables over the 8,192 masks give popcounts and made straights.
_POPCOUNT = np.array([bin(mask).count("1") for mask in range(1 << NUM_RANKS)], dtype=np.int8)
_WINDOWS = np.array([(1 << 12) | 0b1111] + [0b11111 << low for low in range(9)], np.int64)
_STRAIGHT = ((np.arange(1 << NUM_RANKS)[:, None] & _WINDOWS) == _WINDOWS).any(axis=1)
# _FOUR_OF_WINDOW[mask]: the union of the windows of which the mask holds exactly four ranks.
_FOUR_OF_WINDOW = np.bitwise_or.reduce(
    np.where(_POPCOUNT[np.arange(1 << NUM_RANKS)[:, None] & _WINDOWS] == 4, _WINDOWS, 0), axis=1
)
_CARD_RANK_BIT = np.int64(1) << _RANK
# A set of cards as one int64: bit 16 x suit + rank. A card's bit; the extra last entry, 0,
# is what index -1 (no card) reads.
_SUIT_SHIFTS = 16 * np.arange(4, dtype=np.int64)[:, None]
_PACKED_CARD = np.append(_CARD_RANK_BIT << _SUIT_SHIFTS[_SUIT, 0], 0)
_RANKS = (1 << NUM_RANKS) - 1
# _TOP_BIT[mask]: the mask's highest bit (0 for none).
_TOP_BIT = np.array([1 << (mask.bit_length() - 1) if mask else 0 for mask in range(_RANKS + 1)])


def _packed(cards: np.ndarray) -> np.ndarray:
    """(N,) int64 the set of cards (N, k) with ``-1`` pads, packed as :data:`_PACKED_CARD`."""
    return np.bitwise_or.reduce(_PACKED_CARD[cards], axis=1)


def _suit_masks(packed: np.ndarray) -> np.ndarray:
    """(4, N) each suit's rank mask (bit r for rank r, 2 .. A as 0 .. 12) of packed sets."""
    return (packed[None] >> _SUIT_SHIFTS) & _RANKS


# Flags of one suit's rank mask: exactly four cards of the suit, a flush, a straight flush.
_FOUR_SUITED, _FLUSH, _STRAIGHT_FLUSH = np.uint8(1), np.uint8(2), np.uint8(4)
_SUIT_FLAGS = (
    np.where(_POPCOUNT == 4, _FOUR_SUITED, 0)
    | np.where(_POPCOUNT >= 5, _FLUSH, 0)
    | np.where((_POPCOUNT >= 5) & _STRAIGHT, _STRAIGHT_FLUSH, 0)
).astype(np.uint8)
# Category 1 (high card) is the block's first column (an int64: the category is uint8).
_CATEGORY_AT = np.int64(_ONE_HOT_AT["category"] - 1)


def visible_category(cards: np.ndarray) -> np.ndarray:
    """(N,) made-hand category (1 high card .. 9 straight flush, as
    :func:`pokerirl.game.evaluator.category`) of the visible cards, 2 to 7 of them
    (``-1`` pads)."""
    masks = _suit_masks(_packed(np.asarray(cards, dtype=np.int64)))
    return _category(masks, np.bitwise_or.reduce(masks, axis=0), _SUIT_FLAGS[masks])


def _category_of_code() -> np.ndarray:
    """(96,) uint8: the category of each :func:`_category` code, each made hand overriding
    those below it."""
    paired, trips, straight, quads, flush = np.indices((3, 2, 2, 2, 4)).reshape(5, -1)
    code = paired + 3 * trips + 6 * straight + 12 * quads + 24 * flush
    category = np.ones(code.size, dtype=np.uint8)
    for applies, value in (
        (paired >= 1, 2),
        (paired >= 2, 3),
        (trips == 1, 4),
        (straight == 1, 5),
        ((flush & 1) != 0, 6),  # _FLUSH
        ((trips == 1) & (paired >= 2), 7),  # trips and a pair of another rank
        (quads == 1, 8),
        ((flush & 2) != 0, 9),  # _STRAIGHT_FLUSH
    ):
        category[applies] = value
    found = np.empty(code.size, dtype=np.uint8)
    found[code] = category
    return found


# A category code adds, over rank masks: how many ranks are held twice (0, 1, 2 or more),
# 3 x any held three times, 6 x a straight, 12 x any held four times, and over suit flags
# 24 x (flush, straight flush) as two bits. Tables of uint8: small enough to stay in cache.
_PAIRED_CODE = np.minimum(_POPCOUNT, 2).astype(np.uint8)
_TRIPS_CODE = np.where(np.arange(_RANKS + 1) != 0, 3, 0).astype(np.uint8)
_STRAIGHT_CODE = np.where(_STRAIGHT, 6, 0).astype(np.uint8)
_QUADS_CODE = np.where(np.arange(_RANKS + 1) != 0, 12, 0).astype(np.uint8)
_FLUSH_CODE = (24 * ((np.arange(256) >> 1) & 3)).astype(np.uint8)  # _FLUSH, _STRAIGHT_FLUSH
_CATEGORY_OF_CODE = _category_of_code()


def _category(masks: np.ndarray, present: np.ndarray, flags: np.ndarray) -> np.ndarray:
    """(N,) uint8 the category from the suits' rank masks (4, N) alone, their union
    ``present`` and their :data:`_SUIT_FLAGS` (4, N): the ranks held in two, three and four
    suits are ANDs of the masks (a pair, trips, quads), without counting card by card; a
    code of what is made reads the category from a table."""
    m0, m1, m2, m3 = masks
    both_low, both_high, low, high = m0 & m1, m2 & m3, m0 | m1, m2 | m3
    two = both_low | (low & high) | both_high
    three = (both_low & high) | (both_high & low)
    code = _PAIRED_CODE[two] + _TRIPS_CODE[three] + _STRAIGHT_CODE[present]
    code += _QUADS_CODE[both_low & both_high] + _FLUSH_CODE[np.bitwise_or.reduce(flags, axis=0)]
    return _CATEGORY_OF_CODE[code]


@dataclass(frozen=True, kw_only=True, eq=False)
class _PairFeatures:
    """What the strength encoding reads of a hole pair alone, for the 1,326 pairs."""

    ones: np.ndarray  # (1326, 4) the columns of its ones: the two cards, high and low rank
    flags: np.ndarray  # (1326, 2) float32: the pocket-pair and suited columns
    rank_bits: np.ndarray  # (1326,) the two ranks' bits (2 .. A as bits 0 .. 12)
    high_bit: np.ndarray  # the higher rank's
    pocket: np.ndarray  # (1326,) bool: a pocket pair
    packed: np.ndarray  # (1326,) the two cards, as :data:`_PACKED_CARD`
    suits: np.ndarray  # (4, 1326) uint8: _FOUR_SUITED where a hole card is of the suit

    @classmethod
    def build(cls) -> _PairFeatures:
        rank = _RANK[PAIRS]
        high, low = rank.max(axis=1), rank.min(axis=1)
        held = (_SUIT[PAIRS][:, :, None] == np.arange(4)).any(axis=1).T
        ranks = np.stack([high + _ONE_HOT_AT["high_rank"], low + _ONE_HOT_AT["low_rank"]], axis=1)
        return cls(
            ones=np.concatenate([PAIRS + _COLUMNS["hole"][0], ranks], axis=1),
            flags=np.stack([rank[:, 0] == rank[:, 1],
                            _SUIT[PAIRS[:, 0]] == _SUIT[PAIRS[:, 1]]],
                           axis=1).astype(np.float32),
            rank_bits=_CARD_RANK_BIT[PAIRS[:, 0]] | _CARD_RANK_BIT[PAIRS[:, 1]],
            high_bit=np.int64(1) << high, pocket=rank[:, 0] == rank[:, 1], packed=_packed(PAIRS),
            suits=np.where(held, _FOUR_SUITED, 0).astype(np.uint8),
        )  # fmt: skip


@dataclass(frozen=True, kw_only=True, eq=False)
class _BoardFeatures:
    """What the strength encoding reads of a batch of states apart from their hole cards."""

    cards: np.ndarray  # (n, 5) the board, -1 beyond
    ones: np.ndarray  # (n, 10) the columns of its ones: the board's cards, raises, street
    numbers: np.ndarray  # (n, 3) float32: facing a bet, pot, pot odds
    packed: np.ndarray  # (n,) the board, as :data:`_PACKED_CARD`
    rank_bits: np.ndarray  # (n,) the ranks on the board
    top_bit: np.ndarray  # (n,) the board's highest rank's bit, 0 for no board
    cards_to_come: np.ndarray  # (n,) bool: the flop or the turn (a draw can come in)

    @classmethod
    def of(cls, states: RawStates) -> _BoardFeatures:
        board = np.asarray(states.cards, dtype=np.int64)[:, 2:]
        shown = (board >= 0).sum(axis=1)
        raises = np.minimum(np.asarray(states.raise_nums, dtype=np.int64), MAX_RAISES)
        facing = np.asarray(states.legal_mask, dtype=bool)[:, CALL]
        betting = _BETTING_OF_SHOWN[shown] + raises @ (2 * _RAISE_PLACES) + facing
        rank_bits = np.bitwise_or.reduce(_BOARD_RANK_BIT[board], axis=1)
        return cls(
            cards=board,
            ones=np.concatenate([_BOARD_COLUMN[board], _BETTING.ones[betting]], axis=1),
            numbers=_BETTING.numbers[betting],
            packed=_packed(board),
            rank_bits=rank_bits,
            top_bit=_TOP_BIT[rank_bits],
            cards_to_come=(shown == 3) | (shown == 4),
        )

    def take(self, rows: np.ndarray) -> _BoardFeatures:
        """The features of states ``rows`` (a row per pair in local best response)."""
        return _BoardFeatures(**{name: getattr(self, name)[rows] for name in _BOARD_FIELDS})


@dataclass(frozen=True, kw_only=True, eq=False)
class _BettingTable:
    """Every betting state's columns, by (street, raises per round, facing a bet): where its
    ones are (the raise counts' and the street's) and its numbers (facing, pot, pot odds)."""

    ones: np.ndarray  # (5,000, 5)
    numbers: np.ndarray  # (5,000, 3) float32

    @classmethod
    def build(cls) -> _BettingTable:
        every = np.indices((NUM_ROUNDS,) + (MAX_RAISES + 1,) * NUM_ROUNDS + (2,)).reshape(6, -1)
        street, raises, facing = every[0], every[1:5].T, every[5].astype(bool)
        pot, to_call = pot_and_call(street, raises, facing)
        numbers = np.stack([facing, pot / MAX_POT,
                            np.where(facing, to_call / np.maximum(pot + to_call, 1), 0.0)],
                           axis=1).astype(np.float32)  # fmt: skip
        ones = np.concatenate([raises + _RAISE_COLUMN, (street + _ONE_HOT_AT["street"])[:, None]],
                              axis=1)  # fmt: skip
        return cls(ones=ones, numbers=numbers)


_RAISE_PLACES = (MAX_RAISES + 1) ** np.arange(NUM_ROUNDS - 1, -1, -1)  # as np.indices orders
# A betting state's number (np.indices' order: street, raises per round, facing) without its
# raises and facing, by the board cards shown.
_BETTING_OF_SHOWN = _STREET_OF_SHOWN * (MAX_RAISES + 1) ** NUM_ROUNDS * 2
_BOARD_FIELDS = tuple(field.name for field in dataclasses.fields(_BoardFeatures))
_BOARD_RANK_BIT = np.append(_CARD_RANK_BIT, 0)  # index -1 (no card): no rank
# Where a board card's 1 goes; a card not shown (index -1) puts its 1 in the equity column,
# which is written after the ones.
_SPARE = _COLUMNS["equity"][0]
_BOARD_COLUMN = np.append(np.arange(NUM_CARDS) + _COLUMNS["board"][0], _SPARE)
_BETTING = _BettingTable.build()
_PAIR_FEATURES = _PairFeatures.build()
RLCARD = RLCardEncoding()
STRENGTH = StrengthEncoding()
STRENGTH_V1 = StrengthEncoding(version=1)
# The current encoding of each name (what a user asks for).
ENCODINGS: Mapping[str, Encoding] = {e.name: e for e in (RLCARD, STRENGTH)}
# Every version by its spec (what runs record).
ENCODING_SPECS: Mapping[str, Encoding] = {e.spec: e for e in (RLCARD, STRENGTH, STRENGTH_V1)}
# Records made before encodings had versions wrote the bare name.
_UNVERSIONED: Mapping[str, Encoding] = {"rlcard": RLCARD, "strength": STRENGTH_V1}
DEFAULT_ENCODING = EncodingName.RLCARD


def get_encoding(name: str | Encoding | None) -> Encoding:
    """The encoding called ``name`` (None: ``rlcard``): a name gives its current version, a
    spec (``strength-v1``) that version; :class:`ConfigError` naming the known ones otherwise.

    >>> get_encoding("strength").width, get_encoding(None).name
    (174, <EncodingName.RLCARD: 'rlcard'>)
    >>> get_encoding("strength-v1").version
    1
    """
    if isinstance(name, Encoding):
        return name
    key = DEFAULT_ENCODING if name is None else name
    found = ENCODINGS.get(key) or ENCODING_SPECS.get(key)
    if found is None:
        raise ConfigError(f"unknown encoding {name!r} (known: {', '.join(ENCODINGS)})")
    return found


def recorded_encoding(spec: str | None) -> Encoding:
    """The encoding a run or an agent recorded (None: ``rlcard``, as records made before
    encodings): a spec, or a bare name meaning the version there was before versions
    (``strength`` is ``strength-v1``). :class:`ConfigError` for one it does not know."""
    key = DEFAULT_ENCODING if spec is None else str(spec)
    found = _UNVERSIONED.get(key) or ENCODING_SPECS.get(key)
    if found is None:
        raise ConfigError(f"unknown encoding {key[:40]!r} (known: {', '.join(ENCODING_SPECS)})")
    return found
