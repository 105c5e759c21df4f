"""A toy expert decision table with a known rule, for tests, benchmarks and examples.

It has the schema ``pokerirl ingest`` writes, so the trainer can be exercised without real
hand histories (:func:`pokerirl.poker.transitions_from_arrow` makes it ``Transitions``). The
expert's rule is a function of the observation (and the legal actions): raise when more than
half of the visible cards (hole and board) are T or better and raising is legal; otherwise
check when checking is legal, else call. Folds never appear, as in the real tables.

>>> table = toy_expert_table(num_hands=50, seed=1)
>>> table.num_rows > 50, table.schema.field("obs").type
(True, FixedSizeListType(fixed_size_list<item: uint8>[72]))
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from pokerirl.datasets.table import fixed_size_list
from pokerirl.holdem import (
    ACTIONS,
    BOARD_SIZE_BY_ROUND,
    CALL,
    CARD_TEXT,
    CHECK,
    FOLD,
    MAX_RAISES,
    NUM_ACTIONS,
    NUM_CARDS,
    RAISE,
    encode_obs,
)

HIGH_RANKS = (0, 9, 10, 11, 12)  # A, T, J, Q, K in the encoding's rank order


def toy_expert_rule(obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
    """Action ids of the toy expert for (N, 72) observations and (N, 4) legal masks."""
    cards = obs[:, :NUM_CARDS].astype(bool)
    high = np.isin(np.arange(NUM_CARDS) % 13, HIGH_RANKS)
    strong = 2 * (cards & high).sum(axis=1) > cards.sum(axis=1)
    passive = np.where(legal_mask[:, CHECK], CHECK, CALL)
    return np.where(strong & legal_mask[:, RAISE], RAISE, passive).astype(np.int8)


def toy_expert_table(
    *, num_hands: int, seed: int = 0, max_decisions: int = 4, slip: float = 0.0
) -> pa.Table:
    """``num_hands`` hands of 1..``max_decisions`` expert decisions each, as an Arrow table.

    With probability ``slip`` a decision is a uniformly random legal non-fold action instead
    of the rule's, like a human expert's inconsistency.
    """
    rng = np.random.default_rng(seed)
    decisions = rng.integers(1, max_decisions + 1, size=num_hands)
    hand = np.repeat(np.arange(num_hands), decisions)
    n = len(hand)
    # Per hand: 2 hole cards and 5 board cards, all distinct.
    deck = np.argsort(rng.random((num_hands, 52)), axis=1)[:, :7]
    cards = deck[hand]
    street = rng.integers(0, 4, size=n)  # a toy: drawn per decision, not in hand order
    visible = 2 + np.asarray(BOARD_SIZE_BY_ROUND)[street]
    cards = np.where(np.arange(7) < visible[:, None], cards, -1)
    raise_nums = rng.integers(0, MAX_RAISES + 1, size=(n, 4))
    raise_nums[np.arange(4) > street[:, None]] = 0  # no raises on streets not yet reached
    obs = encode_obs(cards, raise_nums)
    hole_text = np.array([" ".join(CARD_TEXT[c] for c in row[:2]) for row in cards])
    board_text = np.array([" ".join(CARD_TEXT[c] for c in row[2:] if c >= 0) for row in cards])

    facing_bet = rng.random(n) < 0.5
    legal = np.zeros((n, NUM_ACTIONS), dtype=bool)
    legal[:, FOLD] = True
    legal[:, CALL] = facing_bet
    legal[:, CHECK] = ~facing_bet
    legal[:, RAISE] = raise_nums[np.arange(n), street] < MAX_RAISES
    action_id = toy_expert_rule(obs, legal)
    # A random legal non-fold action: rank random keys, illegal and fold ones last.
    keys = np.where(legal, rng.random((n, NUM_ACTIONS)), -1.0)
    keys[:, FOLD] = -1.0
    slipped = rng.random(n) < slip
    action_id[slipped] = keys[slipped].argmax(axis=1)

    is_last = np.r_[hand[1:] != hand[:-1], True]
    payoff = np.round(rng.normal(0.0, 3.0, size=num_hands), 1).astype(np.float32)[hand]
    reward = np.where(is_last, payoff, 0.0).astype(np.float32)
    names = np.array(ACTIONS)
    return pa.table(
        {
            "hand_id": pa.array([f"toy-{seed}-{h}" for h in hand], pa.string()),
            "timestamp": pa.array(1_000_000 + hand, pa.int64()),
            "player": pa.array(np.where(hand % 2 == 0, "alice", "bob"), pa.string()),
            "position": pa.array(rng.integers(0, 2, size=n), pa.int8()),
            "street": pa.array(street, pa.int8()),
            "action": pa.array(names[action_id], pa.string()),
            "raise_nums": fixed_size_list(raise_nums.astype(np.int8), pa.int8()),
            "payoff_bb": pa.array(payoff, pa.float32()),
            "is_last": pa.array(is_last, pa.bool_()),
            "obs": fixed_size_list(obs, pa.uint8()),
            "action_id": pa.array(action_id, pa.int8()),
            "legal_mask": fixed_size_list(legal, pa.bool_()),
            "reward": pa.array(reward, pa.float32()),
            "hole_cards": pa.array(hole_text, pa.string()),
            "board": pa.array(board_text, pa.string()),
        }
    )
