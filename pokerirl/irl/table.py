"""Read the expert decision table (Parquet, one row per decision) into tensors.

Only the columns the trainer needs are read, and each goes pyarrow -> numpy -> torch through
its flat child array, without per-row Python. Problems with the table raise ``ValueError``
with a one-line message.

Required columns: ``hand_id`` (string), ``obs`` (fixed_size_list<uint8>[72]), ``action_id``
(integer), ``legal_mask`` (fixed_size_list<bool>[4]). Optional: ``reward`` (float; payoff in
big blinds on the player's last decision of a hand, else 0).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import torch

from pokerirl.encoding import NUM_ACTIONS, OBS_SIZE
from pokerirl.irl.airl import ExpertData

REQUIRED_COLUMNS = ("hand_id", "obs", "action_id", "legal_mask")
REWARD_COLUMN = "reward"


@dataclass(frozen=True, kw_only=True)
class ExpertTable:
    """The decision table as numpy arrays, plus the hand of every row."""

    obs: np.ndarray  # (N, 72) uint8
    action_ids: np.ndarray  # (N,) int64
    legal_mask: np.ndarray  # (N, 4) bool
    rewards: np.ndarray | None  # (N,) float32, None when the table has no reward column
    hand_index: np.ndarray  # (N,) int64: index of the row's hand in order of first appearance
    num_hands: int

    def __len__(self) -> int:
        return len(self.obs)

    def fingerprint(self) -> str:
        """SHA-256 over the arrays the trainer sees (hands by index, not by name)."""
        digest = hashlib.sha256()
        for array in (self.obs, self.action_ids, self.legal_mask, self.hand_index):
            digest.update(np.ascontiguousarray(array).tobytes())
        if self.rewards is not None:
            digest.update(np.ascontiguousarray(self.rewards).tobytes())
        return digest.hexdigest()

    def to_expert_data(self, rows: np.ndarray | None = None) -> ExpertData:
        """Tensors for the trainer (all rows, or ``rows``)."""
        # Arrow's zero-copy arrays are read-only; torch wants writable ones, so copy.
        pick = (lambda a: a.copy()) if rows is None else (lambda a: a[rows])
        rewards = None if self.rewards is None else torch.from_numpy(pick(self.rewards))
        return ExpertData.from_action_ids(
            torch.from_numpy(pick(self.obs)),
            torch.from_numpy(pick(self.action_ids)),
            num_actions=NUM_ACTIONS,
            legal_mask=torch.from_numpy(pick(self.legal_mask)),
            rewards=rewards,
        )


def read_expert_table(path: str | os.PathLike[str]) -> ExpertTable:
    """Read and validate the decision table at ``path``.

    Raises ``FileNotFoundError`` for a missing file and ``ValueError`` for anything else wrong
    (not Parquet, missing columns, wrong types or widths, nulls, empty, illegal expert actions).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"table not found: {path}")
    try:
        schema = pq.read_schema(path)
    except (pa.ArrowException, OSError) as error:
        raise ValueError(f"cannot read {path} as Parquet: {first_line(error)}") from None
    missing = [name for name in REQUIRED_COLUMNS if name not in schema.names]
    if missing:
        raise ValueError(f"{path} lacks required column(s): {', '.join(missing)}")
    columns = [*REQUIRED_COLUMNS] + ([REWARD_COLUMN] if REWARD_COLUMN in schema.names else [])
    try:
        table = pq.read_table(path, columns=columns)
    except (pa.ArrowException, OSError) as error:
        raise ValueError(f"cannot read {path}: {first_line(error)}") from None
    return expert_table_from_arrow(table, source=str(path))


def expert_table_from_arrow(table: pa.Table, *, source: str = "table") -> ExpertTable:
    """Validate an Arrow table with the decision-table schema and convert it."""
    if table.num_rows == 0:
        raise ValueError(f"{source} is empty: no expert decisions to learn from")
    for name in (*REQUIRED_COLUMNS, REWARD_COLUMN):
        if name in table.column_names and table.column(name).null_count:
            raise ValueError(f"{source}: column {name!r} has null values")

    hand = table.column("hand_id")
    if not (pa.types.is_string(hand.type) or pa.types.is_large_string(hand.type)):
        raise ValueError(f"{source}: column 'hand_id' must be string, got {hand.type}")
    encoded = pc.dictionary_encode(hand.combine_chunks())
    hand_index = encoded.indices.to_numpy(zero_copy_only=False).astype(np.int64)
    num_hands = len(encoded.dictionary)

    obs = _fixed_width(table, "obs", OBS_SIZE, source).astype(np.uint8, copy=False)
    mask = _fixed_width(table, "legal_mask", NUM_ACTIONS, source).astype(bool, copy=False)

    action = table.column("action_id")
    if not pa.types.is_integer(action.type):
        raise ValueError(f"{source}: column 'action_id' must be integer, got {action.type}")
    action_ids = action.to_numpy().astype(np.int64)
    if action_ids.min() < 0 or action_ids.max() >= NUM_ACTIONS:
        raise ValueError(f"{source}: 'action_id' must lie in 0..{NUM_ACTIONS - 1}")
    illegal = ~mask[np.arange(len(action_ids)), action_ids]
    if illegal.any():
        raise ValueError(
            f"{source}: {int(illegal.sum())} row(s) take an action their 'legal_mask' forbids"
        )

    rewards = None
    if REWARD_COLUMN in table.column_names:
        reward = table.column(REWARD_COLUMN)
        if not pa.types.is_floating(reward.type) and not pa.types.is_integer(reward.type):
            raise ValueError(f"{source}: column 'reward' must be numeric, got {reward.type}")
        rewards = reward.to_numpy().astype(np.float32)

    return ExpertTable(
        obs=obs,
        action_ids=action_ids,
        legal_mask=mask,
        rewards=rewards,
        hand_index=hand_index,
        num_hands=num_hands,
    )


def _fixed_width(table: pa.Table, name: str, width: int, source: str) -> np.ndarray:
    """A fixed_size_list column as an (N, width) numpy array, via its flat child values."""
    column = table.column(name)
    kind = column.type
    if not pa.types.is_fixed_size_list(kind) or kind.list_size != width:
        raise ValueError(f"{source}: column {name!r} must be fixed_size_list[{width}], got {kind}")
    value_type = kind.value_type
    if not (pa.types.is_integer(value_type) or pa.types.is_boolean(value_type)):
        raise ValueError(f"{source}: column {name!r} must hold integers or booleans")
    array = column.combine_chunks()
    # flatten() honours slicing offsets, unlike .values; null children would be corrupt data.
    values = array.flatten()
    if values.null_count:
        raise ValueError(f"{source}: column {name!r} has null entries inside its lists")
    return values.to_numpy(zero_copy_only=False).reshape(len(array), width)


def split_by_hand(
    hand_index: np.ndarray, num_hands: int, *, val_fraction: float, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """Row indices (train, validation), splitting by hand so no hand straddles the split.

    A seeded permutation of the hands picks ``round(val_fraction * num_hands)`` of them (at
    least one, and at least one left for training).

    >>> train, val = split_by_hand(np.array([0, 0, 1, 1, 2]), 3, val_fraction=0.34, seed=0)
    >>> sorted(train.tolist() + val.tolist()), len(val) in (1, 2)
    ([0, 1, 2, 3, 4], True)
    """
    if num_hands < 2:
        raise ValueError("need at least two hands to split into training and validation")
    num_val = min(max(round(val_fraction * num_hands), 1), num_hands - 1)
    rng = np.random.default_rng(seed)
    is_val_hand = np.zeros(num_hands, dtype=bool)
    is_val_hand[rng.permutation(num_hands)[:num_val]] = True
    is_val_row = is_val_hand[hand_index]
    return np.flatnonzero(~is_val_row), np.flatnonzero(is_val_row)


def first_line(error: BaseException) -> str:
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__
