"""Replayable deals: hand ``i`` of seed ``s`` is always the same nine cards.

A deal is nine card indices: seat 0's two hole cards, seat 1's two hole cards, then the five
board cards in the order they are turned (flop, flop, flop, turn, river). Seat 0 posts the
small blind (see :mod:`pokerirl.game.engine`).

Deals are made in blocks of :data:`DEAL_BLOCK` hands; block ``b`` draws from its own
counter-based Philox stream keyed by ``SeedSequence(seed, spawn_key=(0, b))``. So deal ``i``
depends only on ``(seed, i)``, never on how many hands are asked for at once, and a deal can be
replayed with the seats swapped (duplicate poker).

>>> a = deal_cards(seed=7, start=0, count=10)
>>> b = deal_cards(seed=7, start=5, count=3)
>>> bool((a[5:8] == b).all()), a.shape
(True, (10, 9))
"""

from __future__ import annotations

import numpy as np

from pokerirl.encoding import NUM_CARDS

DEAL_SIZE = 9  # 2 + 2 hole cards, 5 board cards
DEAL_BLOCK = 4096
DEAL_STREAM = 0  # first spawn-key word for deals; other seeded streams use other values


def _deal_block(seed: int, block: int) -> np.ndarray:
    """(DEAL_BLOCK, 9) deals: the first nine cards of a partial Fisher-Yates shuffle."""
    sequence = np.random.SeedSequence(seed, spawn_key=(DEAL_STREAM, block))
    rng = np.random.Generator(np.random.Philox(sequence))
    row_start = np.arange(DEAL_BLOCK) * NUM_CARDS
    decks = np.tile(np.arange(NUM_CARDS, dtype=np.int8), DEAL_BLOCK)  # one deck per row, flat
    for j in range(DEAL_SIZE):
        # Position j swaps with a uniform position in j..51: exact draws without replacement.
        pick = row_start + rng.integers(j, NUM_CARDS, size=DEAL_BLOCK, dtype=np.int16)
        chosen = decks[pick]
        decks[pick] = decks[row_start + j]
        decks[row_start + j] = chosen
    return decks.reshape(DEAL_BLOCK, NUM_CARDS)[:, :DEAL_SIZE]


def deal_cards(*, seed: int, start: int, count: int) -> np.ndarray:
    """Deals ``start .. start + count - 1`` of ``seed`` as a (count, 9) int8 array.

    Args:
        seed: non-negative integer.
        start: index of the first hand (non-negative).
        count: how many hands.
    """
    if seed < 0 or start < 0 or count < 0:
        raise ValueError("seed, start and count must be non-negative")
    if count == 0:
        return np.zeros((0, DEAL_SIZE), dtype=np.int8)
    first, last = start // DEAL_BLOCK, (start + count - 1) // DEAL_BLOCK
    blocks = np.vstack([_deal_block(seed, b) for b in range(first, last + 1)])
    offset = start - first * DEAL_BLOCK
    return blocks[offset : offset + count]
