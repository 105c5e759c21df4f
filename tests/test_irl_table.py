"""Expert data: the poker decision table and environment rollouts as Transitions; the split."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import torch

from pokerirl.datasets.toy import toy_expert_rule, toy_expert_table
from pokerirl.irl import Transitions
from pokerirl.poker import read_table, transitions_from_arrow


def write(table: pa.Table, path: Path, **kwargs: object) -> Path:
    pq.write_table(table, path, **kwargs)
    return path


def test_round_trip_through_parquet_with_many_row_groups(
    tmp_path: Path, small_table: Callable[..., pa.Table]
) -> None:
    table = small_table(num_hands=300, seed=3)
    path = write(table, tmp_path / "t.parquet", row_group_size=97)  # several chunks
    expert = read_table(path)
    obs = np.array(table.column("obs").to_pylist(), dtype=np.float32)
    assert expert.obs.dtype == torch.float32 and np.array_equal(expert.obs.numpy(), obs)
    assert np.array_equal(expert.actions.numpy(), table.column("action_id").to_numpy())
    mask = np.array(table.column("legal_mask").to_pylist())
    assert np.array_equal(expert.legal_mask.numpy(), mask)
    assert np.array_equal(expert.rewards.numpy(), table.column("reward").to_numpy())
    assert expert.discrete and expert.action_dim == 4 and expert.obs_dim == 72
    assert list(expert.groups) == table.column("hand_id").to_pylist()
    # The toy expert really follows its rule on what the trainer sees.
    rule = toy_expert_rule(expert.obs.numpy().astype(np.uint8), mask)
    assert np.array_equal(rule, expert.actions.numpy())
    assert expert.fingerprint() == read_table(path).fingerprint()
    other = read_table(write(toy_expert_table(num_hands=300, seed=4), tmp_path / "o.pq"))
    assert other.fingerprint() != expert.fingerprint()


def test_next_obs_is_the_same_players_next_decision_in_the_hand() -> None:
    obs = np.zeros((6, 72), np.uint8)
    obs[:, 0] = np.arange(6)  # tag each row
    table = pa.table(
        {
            "hand_id": ["a", "a", "a", "a", "b", "b"],
            "player": ["x", "y", "x", "y", "x", "y"],
            "obs": pa.FixedSizeListArray.from_arrays(pa.array(obs.reshape(-1)), 72),
            "action_id": pa.array([1] * 6, pa.int8()),
            "legal_mask": pa.FixedSizeListArray.from_arrays(pa.array([True] * 24), 4),
        }
    )
    t = transitions_from_arrow(table)
    assert t.dones.tolist() == [False, False, True, True, True, True]
    assert t.next_obs[:2, 0].tolist() == [2, 3]  # x's next decision, then y's
    without_player = transitions_from_arrow(table.drop_columns(["player"]))
    assert without_player.next_obs is None and without_player.dones is None


def env_rollouts(n: int, *, continuous: bool) -> pa.Table:
    rng = np.random.default_rng(0)
    obs = rng.random((n, 3), dtype=np.float32)
    episode = np.arange(n) // 5
    done = np.r_[episode[1:] != episode[:-1], True]
    next_obs = np.roll(obs, -1, axis=0)
    vectors = lambda a, k: pa.FixedSizeListArray.from_arrays(  # noqa: E731
        pa.array(a.reshape(-1), pa.float32()), k
    )
    if continuous:
        action = vectors(rng.uniform(-1, 1, (n, 2)).astype(np.float32), 2)
    else:
        action = pa.array(rng.integers(0, 3, n), pa.int64())
    return pa.table(
        {
            "obs": vectors(obs, 3),
            "action": action,
            "reward": pa.array(rng.random(n), pa.float32()),
            "next_obs": vectors(next_obs, 3),
            "done": pa.array(done),
            "episode": pa.array(episode, pa.int64()),
        }
    )


@pytest.mark.parametrize("continuous", [False, True])
def test_environment_rollouts_parquet_as_written_by_gym_collect(
    tmp_path: Path, continuous: bool
) -> None:
    table = env_rollouts(40, continuous=continuous)
    t = Transitions.from_parquet(write(table, tmp_path / "rollouts.parquet"))
    assert len(t) == 40 and t.obs.shape == (40, 3) and t.next_obs.shape == (40, 3)
    assert t.discrete != continuous
    if continuous:
        assert t.actions.shape == (40, 2) and t.actions.dtype == torch.float32
        assert all(lo < hi for lo, hi in zip(t.action_low, t.action_high, strict=True))
    else:
        assert t.actions.dtype == torch.int64 and t.action_dim == 3
    assert t.dones.sum() == 8 and t.groups.tolist() == table.column("episode").to_pylist()
    train, val, val_groups = t.split(val_fraction=0.25, seed=0)
    assert len(val_groups) == 2 and set(val.groups.tolist()) == set(val_groups)
    assert not set(train.groups.tolist()) & set(val_groups)
    with pytest.raises(ValueError, match=r"lacks required column.*done"):
        Transitions.from_parquet(write(table.drop_columns(["done"]), tmp_path / "bad.parquet"))


def test_sliced_table_is_read_from_its_offset(tmp_path: Path) -> None:
    table = toy_expert_table(num_hands=50, seed=1)
    expert = read_table(write(table, tmp_path / "full.parquet"))
    sliced = transitions_from_arrow(table.slice(10, 20))
    assert torch.equal(sliced.obs, expert.obs[10:30])
    assert torch.equal(sliced.legal_mask, expert.legal_mask[10:30])


def test_reward_column_is_optional(tmp_path: Path) -> None:
    table = toy_expert_table(num_hands=20).drop_columns(["reward"])
    assert read_table(write(table, tmp_path / "t.parquet")).rewards is None


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
        read_table(path)
    assert "\n" not in str(info.value)


def test_missing_and_non_parquet_files(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="not found"):
        read_table(tmp_path / "nope.parquet")
    junk = tmp_path / "junk.parquet"
    junk.write_text("hand_id,obs\n1,2\n")
    with pytest.raises(ValueError, match="Parquet") as info:
        read_table(junk)
    assert "\n" not in str(info.value)


def test_split_never_cuts_a_group_and_is_seeded() -> None:
    rng = np.random.default_rng(0)
    groups = np.sort(rng.integers(0, 500, size=2000))
    t = Transitions.from_arrays(np.zeros((2000, 2)), np.zeros(2000, np.int64), groups=groups)
    train, val, val_groups = t.split(val_fraction=0.2, seed=5)
    assert len(train) + len(val) == len(t)
    assert not set(train.groups.tolist()) & set(val.groups.tolist())
    assert sorted(set(val.groups.tolist())) == sorted(val_groups)
    assert len(val_groups) == round(0.2 * len(np.unique(groups)))
    again = t.split(val_fraction=0.2, seed=5)[2]
    other = t.split(val_fraction=0.2, seed=6)[2]
    assert again == val_groups and other != val_groups
    with pytest.raises(ValueError, match="two groups"):
        t.subset(np.flatnonzero(groups == groups[0])).split(val_fraction=0.2, seed=0)
