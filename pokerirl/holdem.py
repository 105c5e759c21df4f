"""Heads-up limit hold'em's cards, actions and RLCard 1.2.0's 72-dimensional observation.

This is the bottom layer: every other module speaks these integers.

Cards are integers 0..51, suit-major in RLCard's order (S, H, D, C) and rank order
A, 2, ..., K inside a suit, exactly as ``rlcard/games/limitholdem/card2index.json``.

>>> parse_card("Qc"), card_str(50), rlcard_card_str(50)
(50, 'Qc', 'CQ')
>>> obs = encode_obs(np.array([[0, 13, -1, -1, -1, -1, -1]]), np.array([[1, 0, 0, 0]]))
>>> np.flatnonzero(obs[0]).tolist()
[0, 13, 53, 57, 62, 67]
"""

from __future__ import annotations

import numpy as np

SUITS = "SHDC"
RANKS = "A23456789TJQK"
NUM_CARDS = 52
NUM_PAIRS = NUM_CARDS * (NUM_CARDS - 1) // 2  # 1,326 hole-card pairs
# Every pair (a, b), a < b, in itertools.combinations order: pair p's index everywhere.
PAIRS = np.array([(a, b) for a in range(NUM_CARDS) for b in range(a + 1, NUM_CARDS)], np.int64)


def pair_cards(pairs: np.ndarray, boards: np.ndarray) -> np.ndarray:
    """(R, 2 + k) row r: the cards of pair number ``pairs[r]``, then ``boards[r]`` (R, k).

    >>> pair_cards(np.array([0, 1325]), np.array([[7], [-1]])).tolist()
    [[0, 1, 7], [50, 51, -1]]
    """
    return np.concatenate([PAIRS[np.asarray(pairs, dtype=np.int64)], boards], axis=1)

ACTIONS: tuple[str, ...] = ("call", "raise", "fold", "check")
CALL, RAISE, FOLD, CHECK = 0, 1, 2, 3
NUM_ACTIONS = 4

NUM_ROUNDS = 4
MAX_RAISES = 4  # RLCard's per-round raise cap; the raise-count one-hot has 5 slots (0..4)
RAISE_OFFSET = NUM_CARDS
OBS_SIZE = NUM_CARDS + NUM_ROUNDS * (MAX_RAISES + 1)  # 72
BOARD_SIZE_BY_ROUND = (0, 3, 4, 5)

# Rank-then-suit text of every card, IRC style ("Qc"), and its inverse in any letter case.
CARD_TEXT: tuple[str, ...] = tuple(RANKS[i % 13] + SUITS[i // 13].lower() for i in range(52))
CARD_INDEX: dict[str, int] = {
    rank + suit: index
    for index, text in enumerate(CARD_TEXT)
    for rank in {text[0], text[0].lower()}
    for suit in {text[1], text[1].upper()}
}


def parse_card(text: str) -> int:
    """Parse a card written rank-then-suit, as in IRC logs (``"Qc"``, ``"Th"``).

    Raises ``ValueError`` on anything else.

    >>> parse_card("As"), parse_card("Kc")
    (0, 51)
    """
    index = CARD_INDEX.get(text)
    if index is None:
        raise ValueError(f"bad card {text!r}")
    return index


def card_str(index: int) -> str:
    """Rank-then-suit text of a card index, in IRC style (``"Qc"``)."""
    return CARD_TEXT[index]


def rlcard_card_str(index: int) -> str:
    """RLCard's suit-then-rank text of a card index (``"CQ"``)."""
    return SUITS[index // 13] + RANKS[index % 13]


def encode_obs(cards: np.ndarray, raise_nums: np.ndarray) -> np.ndarray:
    """Vectorized RLCard limit-holdem ``obs``.

    Args:
        cards: (N, k) card indices visible to the player (hole cards and board), ``-1`` pads.
        raise_nums: (N, 4) raises per round as RLCard counts them; values above 4 are capped.

    Returns:
        (N, 72) uint8: card bits, then ``52 + 5 * round + raise_nums[round]`` for every round.
    """
    cards = np.asarray(cards, dtype=np.int64)
    n = cards.shape[0]
    obs = np.zeros(n * OBS_SIZE, dtype=np.uint8)
    row_start = (np.arange(n, dtype=np.int64) * OBS_SIZE)[:, None]
    card_slots = (row_start + cards)[cards >= 0]
    capped = np.minimum(np.asarray(raise_nums, dtype=np.int64), MAX_RAISES)
    raise_slots = row_start + RAISE_OFFSET + (MAX_RAISES + 1) * np.arange(NUM_ROUNDS) + capped
    obs[card_slots] = 1
    obs[raise_slots.reshape(-1)] = 1
    return obs.reshape(n, OBS_SIZE)


def cards_from_text(hole: list[str], board: list[str]) -> np.ndarray:
    """(N, 7) int8: a decision table's ``hole_cards`` and ``board`` texts as card indices,
    hole cards first, ``-1`` for cards not shown (an empty ``hole_cards`` is concealed).

    Vectorized: the texts are laid out as fixed-width code points, three characters a card
    (rank, suit, space). ``ValueError`` names the first text that is not cards.

    >>> cards_from_text(["As Kc", ""], ["Qc Th 2d", ""]).tolist()
    [[0, 51, 50, 22, 27, -1, -1], [-1, -1, -1, -1, -1, -1, -1]]
    """
    found = np.full((len(hole), 7), -1, dtype=np.int8)
    for first, texts, lengths in ((0, hole, (0, 5)), (2, board, (0, 8, 11, 14))):
        if not len(texts):
            continue
        width = lengths[-1] + 1
        array = np.asarray(texts, dtype=str)
        codes = array.astype(f"<U{width}").view(np.uint32).reshape(len(texts), width)
        rank = _RANK_OF_CODE[np.minimum(codes[:, 0::3], 127)]
        suit = _SUIT_OF_CODE[np.minimum(codes[:, 1::3], 127)]
        count = (np.char.str_len(array) + 1) // 3
        expected = np.arange(width // 3) < count[:, None]
        spaced = np.arange(width // 3) < count[:, None] - 1  # a space after every card but the last
        valid = np.isin(np.char.str_len(array), lengths) & (
            (((rank >= 0) & (suit >= 0)) | ~expected) & ((codes[:, 2::3] == 32) | ~spaced)
        ).all(axis=1)
        if not valid.all():
            raise ValueError(f"bad cards {texts[int(np.flatnonzero(~valid)[0])]!r}")
        found[:, first : first + width // 3] = np.where(expected, suit * 13 + rank, -1)
    return found


_RANK_OF_CODE = np.full(128, -1, dtype=np.int64)
_SUIT_OF_CODE = np.full(128, -1, dtype=np.int64)
for _i, _r in enumerate(RANKS):
    _RANK_OF_CODE[ord(_r)] = _RANK_OF_CODE[ord(_r.lower())] = _i
for _i, _s in enumerate(SUITS):
    _SUIT_OF_CODE[ord(_s)] = _SUIT_OF_CODE[ord(_s.lower())] = _i
