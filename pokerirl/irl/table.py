"""Read a poker decision table (Parquet, one row per decision) into :class:`Transitions`.

Only the columns the trainer needs are read, and each goes pyarrow -> numpy -> torch through
its flat child array, without per-row Python. Problems with the table raise ``ValueError``
with a one-line message naming it.

Required columns: ``hand_id`` (string), ``obs`` (fixed_size_list<uint8>[72]), ``action_id``
(integer), ``legal_mask`` (fixed_size_list<bool>[4]). Optional: ``reward`` (float; payoff in
big blinds on the player's last decision of a hand, else 0) and ``player`` (string), which
gives next_obs (the same player's next decision in the hand) and done (their last one).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from pokerirl.encoding import NUM_ACTIONS, OBS_SIZE
from pokerirl.irl.transitions import Transitions

REQUIRED_COLUMNS = ("hand_id", "obs", "action_id", "legal_mask")
OPTIONAL_COLUMNS = ("reward", "player")


def read_table(path: str | os.PathLike[str]) -> Transitions:
    """Read and validate the decision table at ``path``.

    Raises ``FileNotFoundError`` for a missing file and ``ValueError`` for anything else wrong
    (not Parquet, missing columns, wrong types or widths, nulls, empty, illegal expert actions).
    """
    table = read_parquet(path, REQUIRED_COLUMNS, OPTIONAL_COLUMNS, what="table")
    return transitions_from_arrow(table, source=str(Path(path)))


def read_parquet(
    path: str | os.PathLike[str],
    required: Sequence[str],
    optional: Sequence[str] = (),
    *,
    what: str,
) -> pa.Table:
    """The ``required`` columns (and the ``optional`` ones present) of the Parquet file at
    ``path``: ``FileNotFoundError`` if it is missing, else a one-line ``ValueError`` naming it.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{what} not found: {path}")
    # Through a file object: pyarrow cannot open a path whose name is not UTF-8.
    with open(path, "rb") as file:
        try:
            parquet = pq.ParquetFile(file)
            schema = parquet.schema_arrow
        except (pa.ArrowException, OSError) as error:
            raise ValueError(f"cannot read {path} as Parquet: {first_line(error)}") from None
        missing = [name for name in required if name not in schema.names]
        if missing:
            raise ValueError(f"{path} lacks required column(s): {', '.join(missing)}")
        columns = [*required, *(c for c in optional if c in schema.names)]
        try:
            return parquet.read(columns=columns)
        except (pa.ArrowException, OSError) as error:
            raise ValueError(f"cannot read {path}: {first_line(error)}") from None


def transitions_from_arrow(table: pa.Table, *, source: str = "table") -> Transitions:
    """Validate an Arrow table with the decision-table schema and convert it."""
    if table.num_rows == 0:
        raise ValueError(f"{source} is empty: no expert decisions to learn from")
    for name in (*REQUIRED_COLUMNS, *OPTIONAL_COLUMNS):
        if name in table.column_names and table.column(name).null_count:
            raise ValueError(f"{source}: column {name!r} has null values")
    hand = _strings(table, "hand_id", source)
    obs = fixed_width(table, "obs", OBS_SIZE, source).astype(np.uint8, copy=False)
    mask = fixed_width(table, "legal_mask", NUM_ACTIONS, source).astype(bool, copy=False)

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
    if "reward" in table.column_names:
        reward = table.column("reward")
        if not pa.types.is_floating(reward.type) and not pa.types.is_integer(reward.type):
            raise ValueError(f"{source}: column 'reward' must be numeric, got {reward.type}")
        rewards = reward.to_numpy().astype(np.float32)

    next_obs = dones = None
    if "player" in table.column_names:
        player = _strings(table, "player", source)
        following = next_decision(hand.indices, player.indices)
        dones = following < 0
        next_obs = obs[np.where(dones, np.arange(len(obs)), following)]

    return Transitions.from_arrays(
        obs,
        action_ids,
        groups=np.asarray(hand.dictionary.to_numpy(zero_copy_only=False))[hand.indices],
        next_obs=next_obs,
        dones=dones,
        rewards=rewards,
        legal_mask=mask,
        num_actions=NUM_ACTIONS,
    )


class _Encoded:
    def __init__(self, indices: np.ndarray, dictionary: pa.Array) -> None:
        self.indices, self.dictionary = indices, dictionary


def _strings(table: pa.Table, name: str, source: str) -> _Encoded:
    column = table.column(name)
    if not (pa.types.is_string(column.type) or pa.types.is_large_string(column.type)):
        raise ValueError(f"{source}: column {name!r} must be string, got {column.type}")
    encoded = pc.dictionary_encode(column.combine_chunks())
    indices = encoded.indices.to_numpy(zero_copy_only=False).astype(np.int64)
    return _Encoded(indices, encoded.dictionary)


def next_decision(hand: np.ndarray, player: np.ndarray) -> np.ndarray:
    """Per row, the row of the same player's next decision in the same hand, or -1.

    Rows of a hand are in decision order, as ``pokerirl ingest`` writes them.

    >>> next_decision(np.array([0, 0, 0, 0, 1]), np.array([0, 1, 0, 1, 0])).tolist()
    [2, 3, -1, -1, -1]
    """
    key = hand * (int(player.max()) + 1) + player
    order = np.argsort(key, kind="stable")  # rows of one (hand, player), in table order
    same = key[order[1:]] == key[order[:-1]]
    following = np.full(len(key), -1, dtype=np.int64)
    following[order[:-1][same]] = order[1:][same]
    return following


def fixed_width(
    table: pa.Table, name: str, width: int | None, source: str, *, floating: bool = False
) -> np.ndarray:
    """A fixed_size_list column as an (N, width) numpy array, via its flat child values.

    ``width`` None accepts any list size; ``floating`` accepts float values too.
    """
    column = table.column(name)
    kind = column.type
    if not pa.types.is_fixed_size_list(kind) or (width is not None and kind.list_size != width):
        size = "" if width is None else f"[{width}]"
        raise ValueError(f"{source}: column {name!r} must be fixed_size_list{size}, got {kind}")
    value_type = kind.value_type
    numeric = pa.types.is_integer(value_type) or pa.types.is_boolean(value_type)
    if not (numeric or (floating and pa.types.is_floating(value_type))):
        raise ValueError(f"{source}: column {name!r} holds {value_type}, not numbers")
    array = column.combine_chunks()
    # flatten() honours slicing offsets, unlike .values; null children would be corrupt data.
    values = array.flatten()
    if values.null_count:
        raise ValueError(f"{source}: column {name!r} has null entries inside its lists")
    return values.to_numpy(zero_copy_only=False).reshape(len(array), kind.list_size)


def first_line(error: BaseException) -> str:
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__
