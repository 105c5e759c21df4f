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

from pokerirl.holdem import NUM_CARDS

DEAL_SIZE = 9  # 2 + 2 hole cards, 5 board cards
DEAL_BLOCK = 4096
DEAL_STREAM = 0  # first spawn-key word for deals; other seeded streams use other values


def _deal_blocks(seed: int, first: int, last: int) -> np.ndarray:
    """(k * DEAL_BLOCK, 9) deals of blocks ``first .. last``: the first nine cards of a partial
    Fisher-Yates shuffle of 0..51 in which step j swaps position j with a uniform position
    p_j in j..51 (exact draws without replacement).

    No deck is kept (scattering into 52 bytes a row was a fifth of a match's time): step j
    takes the card at p_j, which is p_j itself unless an earlier step i had p_i = p_j, and
    then the card position i held just before step i (``before[i]``: likewise i itself
    unless an earlier step had drawn i). So the deals are the shuffle's exactly, from a few
    comparisons of the draws, done for all the blocks at once."""
    rows = (last - first + 1) * DEAL_BLOCK
    draws = np.empty((DEAL_SIZE, rows), dtype=np.int8)  # p_j of every row
    for k, block in enumerate(range(first, last + 1)):
        sequence = np.random.SeedSequence(seed, spawn_key=(DEAL_STREAM, block))
        rng = np.random.Generator(np.random.Philox(sequence))
        for j in range(DEAL_SIZE):
            # The same int16 draws as ever: the stream's words depend on the dtype asked.
            draws[j, k * DEAL_BLOCK : (k + 1) * DEAL_BLOCK] = rng.integers(
                j, NUM_CARDS, size=DEAL_BLOCK, dtype=np.int16
            )
    before = np.empty_like(draws)  # the card at position j just before step j
    deals = np.empty_like(draws)  # the card step j puts at position j
    for j in range(DEAL_SIZE):
        held, taken = np.full_like(draws[j], j), draws[j].copy()
        last = j == DEAL_SIZE - 1  # no later step reads what the last position held
        for i in range(j):  # ascending: the last earlier swap of a position decides its card
            # x += (y - x) * mask: int8 arithmetic, half of np.copyto(..., where=mask)'s time.
            if not last:
                held += (before[i] - held) * (draws[i] == j)
            taken += (before[i] - taken) * (draws[i] == draws[j])
        before[j], deals[j] = held, taken
    return np.ascontiguousarray(deals.T)  # rows of nine cards, as the engine reads them


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
    blocks = _deal_blocks(seed, first, last)
    offset = start - first * DEAL_BLOCK
    return blocks[offset : offset + count]
