"""Reading and validating the Parquet decision table; the split by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from pokerirl.irl import read_expert_table, split_by_hand
from pokerirl.irl.toy import toy_expert_rule, toy_expert_table


def write(table: pa.Table, path: Path, **kwargs: object) -> Path:
    pq.write_table(table, path, **kwargs)
    return path


def test_round_trip_through_parquet_with_many_row_groups(tmp_path: Path) -> None:
    table = toy_expert_table(num_hands=300, seed=3)
    path = write(table, tmp_path / "t.parquet", row_group_size=97)  # several chunks
    expert = read_expert_table(path)
    obs = np.array(table.column("obs").to_pylist(), dtype=np.uint8)
    assert expert.obs.dtype == np.uint8 and np.array_equal(expert.obs, obs)
    assert np.array_equal(expert.action_ids, table.column("action_id").to_numpy())
    assert np.array_equal(expert.legal_mask, np.array(table.column("legal_mask").to_pylist()))
    assert np.array_equal(expert.rewards, table.column("reward").to_numpy())
    assert expert.num_hands == 300
    hands = table.column("hand_id").to_pylist()
    same_name = np.array(hands[1:]) == np.array(hands[:-1])
    assert np.array_equal(same_name, expert.hand_index[1:] == expert.hand_index[:-1])
    # The toy expert really follows its rule on what the trainer sees.
    assert np.array_equal(toy_expert_rule(expert.obs, expert.legal_mask), expert.action_ids)
    assert expert.fingerprint() == read_expert_table(path).fingerprint()
    other = read_expert_table(write(toy_expert_table(num_hands=300, seed=4), tmp_path / "o.pq"))
    assert other.fingerprint() != expert.fingerprint()


def test_sliced_table_is_read_from_its_offset(tmp_path: Path) -> None:
    table = toy_expert_table(num_hands=50, seed=1)
    expert = read_expert_table(write(table, tmp_path / "full.parquet"))
    from pokerirl.irl.table import expert_table_from_arrow

    sliced = expert_table_from_arrow(table.slice(10, 20))
    assert np.array_equal(sliced.obs, expert.obs[10:30])
    assert np.array_equal(sliced.legal_mask, expert.legal_mask[10:30])


def test_reward_column_is_optional(tmp_path: Path) -> None:
    table = toy_expert_table(num_hands=20).drop_columns(["reward"])
    assert read_expert_table(write(table, tmp_path / "t.parquet")).rewards is None


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda t: t.drop_columns(["obs", "legal_mask"]), "lacks required column.*obs, legal_mask"),
        (lambda t: t.slice(0, 0), "empty"),
        (
            lambda t: t.set_column(
                t.column_names.index("obs"),
                "obs",
                pa.FixedSizeListArray.from_arrays(
                    pa.array(np.zeros(t.num_rows * 71, np.uint8)), 71
                ),
            ),
            r"fixed_size_list\[72\]",
        ),
        (
            lambda t: t.set_column(
                t.column_names.index("action_id"),
                "action_id",
                pa.array([3] * t.num_rows, pa.int8()),
            ),
            "forbids",
        ),
        (
            lambda t: t.set_column(
                t.column_names.index("action_id"),
                "action_id",
                pa.array([7] * t.num_rows, pa.int8()),
            ),
            "0..3",
        ),
        (
            lambda t: t.set_column(
                t.column_names.index("hand_id"), "hand_id", pa.array(range(t.num_rows))
            ),
            "hand_id' must be string",
        ),
    ],
)
def test_bad_tables_raise_one_line_value_errors(tmp_path: Path, mutate, message: str) -> None:
    path = write(mutate(toy_expert_table(num_hands=10)), tmp_path / "bad.parquet")
    with pytest.raises(ValueError, match=message) as info:
        read_expert_table(path)
    assert "\n" not in str(info.value)


def test_missing_and_non_parquet_files(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="not found"):
        read_expert_table(tmp_path / "nope.parquet")
    junk = tmp_path / "junk.parquet"
    junk.write_text("hand_id,obs\n1,2\n")
    with pytest.raises(ValueError, match="Parquet") as info:
        read_expert_table(junk)
    assert "\n" not in str(info.value)


def test_split_by_hand_never_straddles_and_is_seeded() -> None:
    rng = np.random.default_rng(0)
    hand_index = np.sort(rng.integers(0, 500, size=2000))
    hand_index = np.unique(hand_index, return_inverse=True)[1]
    num_hands = hand_index.max() + 1
    train, val = split_by_hand(hand_index, num_hands, val_fraction=0.2, seed=5)
    assert len(train) + len(val) == len(hand_index)
    assert not set(hand_index[train]) & set(hand_index[val])
    assert len(set(hand_index[val])) == round(0.2 * num_hands)
    again, _ = split_by_hand(hand_index, num_hands, val_fraction=0.2, seed=5)
    other, _ = split_by_hand(hand_index, num_hands, val_fraction=0.2, seed=6)
    assert np.array_equal(train, again) and not np.array_equal(train, other)
    with pytest.raises(ValueError, match="two hands"):
        split_by_hand(np.zeros(5, dtype=np.int64), 1, val_fraction=0.2, seed=0)
