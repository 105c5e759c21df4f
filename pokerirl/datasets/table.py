"""The expert state-action table: one row per decision of a player whose hole cards are known.

:func:`month_table` expands a month of kept hands into rows with vectorized numpy: each distinct
betting line is replayed once (see :mod:`pokerirl.parsers.replay`) and its decisions are laid out
as a template, which every hand that played that line indexes into.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from pokerirl.holdem import (
    ACTIONS,
    BOARD_SIZE_BY_ROUND,
    CARD_TEXT,
    NUM_ACTIONS,
    NUM_ROUNDS,
    OBS_SIZE,
    encode_obs,
)
from pokerirl.parsers.irc import MonthHands
from pokerirl.parsers.replay import Replay

SCHEMA = pa.schema(
    [
        ("hand_id", pa.string()),
        ("timestamp", pa.int64()),
        ("player", pa.string()),
        ("position", pa.int8()),
        ("street", pa.int8()),
        ("action", pa.string()),
        ("action_id", pa.int8()),
        ("hole_cards", pa.string()),
        ("board", pa.string()),
        ("raise_nums", pa.list_(pa.int8(), NUM_ROUNDS)),
        ("obs", pa.list_(pa.uint8(), OBS_SIZE)),
        ("legal_mask", pa.list_(pa.bool_(), NUM_ACTIONS)),
        ("payoff_bb", pa.float32()),
        ("reward", pa.float32()),
        ("is_last", pa.bool_()),
        # Extra columns: provenance and the raw chip counts behind payoff_bb.
        ("channel", pa.string()),
        ("big_blind", pa.int16()),
        ("chips_in", pa.int32()),
        ("chips_won", pa.int32()),
        ("raises_uncapped", pa.int16()),
    ]
)
REQUIRED_COLUMNS: tuple[str, ...] = tuple(SCHEMA.names[:15])
# ``ingest --folds impute`` (docs/folds.md) appends these; a table without them is as before.
IMPUTED_FIELDS = (
    ("imputed", pa.bool_()),  # the hole cards are a draw from the posterior, not shown
    ("weight", pa.float32()),  # the row's weight: 1 observed, (draws of this pair) / K imputed
    ("imputation", pa.int16()),  # which distinct draw of the player's cards (1..), 0 observed
    ("posterior_entropy", pa.float32()),  # bits, of the player's posterior; 0 observed
)
IMPUTED_SCHEMA = pa.schema([*SCHEMA, *(pa.field(name, kind) for name, kind in IMPUTED_FIELDS)])
_BOARD_TEXT_LENGTH = tuple(max(3 * n - 1, 0) for n in BOARD_SIZE_BY_ROUND)


class _Templates:
    """Decisions of each distinct replay, laid out contiguously for vectorized indexing."""

    def __init__(self, replays: list[Replay]) -> None:
        index_of: dict[int, int] = {}
        self.hand_template = np.empty(len(replays), dtype=np.int64)
        rows: list[tuple[int, int, int, int, int, int, int, int, int, int, int, int]] = []
        offsets: list[int] = []
        lengths: list[int] = []
        for hand, replay in enumerate(replays):
            template = index_of.get(id(replay))
            if template is None:
                template = index_of[id(replay)] = len(offsets)
                offsets.append(len(rows))
                lengths.append(len(replay.decisions))
                rows.extend(
                    (
                        d.position,
                        d.street,
                        d.action_id,
                        *d.raise_nums,
                        *d.legal_mask,
                        d.raises_uncapped,
                    )
                    for d in replay.decisions
                )
            self.hand_template[hand] = template
        table = np.array(rows, dtype=np.int64).reshape(-1, 12)
        self.position = table[:, 0]
        self.street = table[:, 1]
        self.action_id = table[:, 2]
        self.raise_nums = table[:, 3:7]
        self.legal_mask = table[:, 7:11].astype(bool)
        self.raises_uncapped = table[:, 11]
        self.offsets = np.array(offsets, dtype=np.int64)
        self.lengths = np.array(lengths, dtype=np.int64)


def fixed_size_list(matrix: np.ndarray, value_type: pa.DataType) -> pa.FixedSizeListArray:
    """An (N, k) matrix as an Arrow ``fixed_size_list<value_type>[k]`` column, without copies
    per row."""
    flat = pa.array(matrix.reshape(-1), type=value_type)
    return pa.FixedSizeListArray.from_arrays(flat, matrix.shape[1])


def month_table(hands: MonthHands, *, keep_concealed: bool = False) -> tuple[pa.Table, int]:
    """Rows of one month's kept hands, and the number of decisions dropped as concealed.

    ``keep_concealed`` keeps the decisions of players whose cards are concealed too, with an
    empty ``hole_cards`` and no hole cards in ``obs``: the templates an imputation of their
    cards fills in (:mod:`pokerirl.poker.impute`); then none is dropped.
    """
    if len(hands) == 0:
        return SCHEMA.empty_table(), 0
    templates = _Templates(hands.replays)
    n_hands = len(hands)
    lengths = templates.lengths[templates.hand_template]
    hand_of_row = np.repeat(np.arange(n_hands), lengths)
    starts = np.cumsum(lengths) - lengths
    decision = templates.offsets[templates.hand_template][hand_of_row] + (
        np.arange(hand_of_row.size) - starts[hand_of_row]
    )
    hole = np.array(hands.hole_cards, dtype=np.int64).reshape(n_hands, 2, 2)
    seat = templates.position[decision] - 1
    known = hole[hand_of_row, seat, 0] >= 0
    if keep_concealed:
        known[:] = True
    concealed = int((~known).sum())
    hand_of_row, decision, seat = hand_of_row[known], decision[known], seat[known]

    street = templates.street[decision]
    raise_nums = templates.raise_nums[decision]
    boards = np.array(hands.boards, dtype=np.int64).reshape(n_hands, 5)
    visible = np.arange(5)[None, :] < np.asarray(BOARD_SIZE_BY_ROUND)[street][:, None]
    cards = np.concatenate(
        [hole[hand_of_row, seat], np.where(visible, boards[hand_of_row], -1)], axis=1
    )
    obs = encode_obs(cards, raise_nums)

    player_index = hand_of_row * 2 + seat
    chips_in = np.array(hands.chips_in, dtype=np.int64)[player_index]
    chips_won = np.array(hands.chips_won, dtype=np.int64)[player_index]
    payoff_bb = ((chips_won - chips_in) / hands.big_blind).astype(np.float32)
    # A player's last decision is the first occurrence of (hand, seat) scanning backwards.
    is_last = np.zeros(player_index.size, dtype=bool)
    _, first_from_end = np.unique(player_index[::-1], return_index=True)
    is_last[player_index.size - 1 - first_from_end] = True
    reward = np.where(is_last, payoff_bb, np.float32(0)).astype(np.float32)

    prefix = f"{hands.channel}/{hands.month}/"
    hand_ids = pa.array([prefix + str(t) for t in hands.timestamps], type=pa.string())
    players = pa.array(hands.players, type=pa.string())
    flat_hole = hands.hole_cards
    hole_text = pa.array(
        [
            f"{CARD_TEXT[flat_hole[i]]} {CARD_TEXT[flat_hole[i + 1]]}" if flat_hole[i] >= 0 else ""
            for i in range(0, len(flat_hole), 2)
        ],
        type=pa.string(),
    )
    # Streets' boards are prefixes of the river's: "Qc Ks 8s" is the first 8 characters.
    flat_board = hands.boards
    board_text = pa.array(
        [
            text[:length]
            for text in (
                " ".join(CARD_TEXT[card] for card in flat_board[i : i + 5] if card >= 0)
                for i in range(0, len(flat_board), 5)
            )
            for length in _BOARD_TEXT_LENGTH
        ],
        type=pa.string(),
    )
    action_id = templates.action_id[decision]
    seat_index = pa.array(player_index)
    columns = {
        "hand_id": hand_ids.take(pa.array(hand_of_row)),
        "timestamp": pa.array(np.array(hands.timestamps, dtype=np.int64)[hand_of_row]),
        "player": players.take(seat_index),
        "position": pa.array((seat + 1).astype(np.int8)),
        "street": pa.array(street.astype(np.int8)),
        "action": pa.array(ACTIONS, type=pa.string()).take(pa.array(action_id)),
        "action_id": pa.array(action_id.astype(np.int8)),
        "hole_cards": hole_text.take(seat_index),
        "board": board_text.take(pa.array(hand_of_row * NUM_ROUNDS + street)),
        "raise_nums": fixed_size_list(raise_nums.astype(np.int8), pa.int8()),
        "obs": fixed_size_list(obs, pa.uint8()),
        "legal_mask": fixed_size_list(templates.legal_mask[decision], pa.bool_()),
        "payoff_bb": pa.array(payoff_bb),
        "reward": pa.array(reward),
        "is_last": pa.array(is_last),
        "channel": pa.array([hands.channel], type=pa.string()).take(
            pa.array(np.zeros(len(street), dtype=np.int32))
        ),
        "big_blind": pa.array(np.full(len(street), hands.big_blind, dtype=np.int16)),
        "chips_in": pa.array(chips_in.astype(np.int32)),
        "chips_won": pa.array(chips_won.astype(np.int32)),
        "raises_uncapped": pa.array(templates.raises_uncapped[decision].astype(np.int16)),
    }
    return pa.table(columns, schema=SCHEMA), concealed
