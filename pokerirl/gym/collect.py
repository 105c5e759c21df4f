"""Expert data: roll an expert out in its environment and write a Parquet transition table.

The table has exactly these columns (the IRL reader relies on them):

=============  =================================================================
``obs``        ``fixed_size_list<float32>[obs_dim]``: the state the action was taken in
``action``     ``int64`` (discrete) or ``fixed_size_list<float32>[act_dim]`` (continuous,
               as the environment executed it: clipped to the action space)
``reward``     ``float32``: the environment's reward
``next_obs``   ``fixed_size_list<float32>[obs_dim]``: the state after the step (the final
               state at an episode's end, never the next episode's first)
``done``       ``bool``: terminated (a terminal state), not merely truncated by a time limit
``truncated``  ``bool``: the episode was cut by its time limit
``episode``    ``int64``: the episode's number, 0, 1, 2, ...; episode ``k`` starts from
               ``reset(seed=seed + k)``
=============  =================================================================

Episodes are played in lock-step over a few environments, then written in episode order and
cut at exactly ``transitions`` rows (the last episode may end early). The same expert, seed and
size give the same bytes.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from pokerirl.atomic import atomic_path
from pokerirl.errors import ConfigError
from pokerirl.execution import unit_progress
from pokerirl.gym.envs import make_env
from pokerirl.gym.expert_policies import Expert
from pokerirl.gym.presets import MAX_TRANSITIONS, TASKS

COLUMNS = ("obs", "action", "reward", "next_obs", "done", "truncated", "episode")
LOCKSTEP_ENVS = 8  # fixed: the batching must not depend on the machine


@dataclass(frozen=True, kw_only=True)
class Episode:
    obs: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    next_obs: np.ndarray
    terminated: bool
    truncated: bool


@dataclass(frozen=True, kw_only=True)
class CollectSummary:
    """What a collection wrote: rows, episodes, and the expert's return on complete episodes."""

    path: str
    env: str
    transitions: int
    episodes: int
    seed: int
    deterministic: bool
    return_mean: float
    return_std: float
    complete_episodes: int


def default_deterministic(env_id: str) -> bool:
    """Whether ``env_id``'s demonstrations are the expert's deterministic actions by default.

    Discrete tasks: yes (the greedy action, as before). Continuous tasks: no, SB3's sampled
    actions, as the authors record them (``train_irl.py``: ``expert.predict(obs)``). On
    deterministic continuous demos the policy's log σ collapses and AIRL's reward inverts
    (issue 20).
    """
    if env_id in TASKS:
        return TASKS[env_id].discrete
    env = make_env(env_id)
    try:
        return hasattr(env.action_space, "n")
    finally:
        env.close()


def rollout(
    expert: Expert, *, transitions: int, seed: int, deterministic: bool | None = None
) -> list[Episode]:
    """Play episodes ``seed``, ``seed + 1``, ... until they hold ``transitions`` steps
    (``deterministic`` None: the task's default, :func:`default_deterministic`)."""
    if deterministic is None:
        deterministic = default_deterministic(expert.env_id)
    if not 1 <= transitions <= MAX_TRANSITIONS:
        raise ConfigError(
            f"transitions must be within 1..{MAX_TRANSITIONS:,} (held in memory until "
            f"written), got {transitions:,}"
        )
    envs = [make_env(expert.env_id) for _ in range(LOCKSTEP_ENVS)]
    finished: dict[int, Episode] = {}
    slots: list[dict | None] = [None] * len(envs)  # per env: its episode's id and lists
    opened, finished_steps = 0, 0

    def steps() -> int:  # steps finished or under way
        return finished_steps + sum(len(s["rewards"]) for s in slots if s is not None)

    try:
        with torch.random.fork_rng():
            torch.manual_seed(seed)  # only used when the expert samples (deterministic=False)
            while True:
                # Open episodes in order while the request is not covered; once every opened
                # episode has finished, they cover it.
                for i, env in enumerate(envs):
                    if slots[i] is None and steps() < transitions:
                        obs, _ = env.reset(seed=seed + opened)
                        slots[i] = {"id": opened, "obs": [obs], "actions": [], "rewards": [],
                                    "next": []}  # fmt: skip
                        opened += 1
                open_slots = [(i, slot) for i, slot in enumerate(slots) if slot is not None]
                if not open_slots:
                    break
                batch = np.stack([slot["obs"][-1] for _, slot in open_slots]).astype(np.float32)
                actions = expert.act(batch, deterministic=deterministic)
                for row, (i, slot) in enumerate(open_slots):
                    obs, reward, terminated, truncated, _ = envs[i].step(actions[row])
                    slot["actions"].append(actions[row])
                    slot["rewards"].append(reward)
                    slot["next"].append(obs)
                    if terminated or truncated:
                        finished[slot["id"]] = _episode(slot, terminated, truncated)
                        finished_steps += len(slot["rewards"])
                        slots[i] = None
                        unit_progress(finished_steps, transitions)  # the driver's bar
                    else:
                        slot["obs"].append(obs)
    finally:
        for env in envs:
            env.close()
    return [finished[k] for k in sorted(finished)]


def _episode(slot: dict, terminated: bool, truncated: bool) -> Episode:
    return Episode(
        obs=np.asarray(slot["obs"], dtype=np.float32),
        actions=np.asarray(slot["actions"]),
        rewards=np.asarray(slot["rewards"], dtype=np.float32),
        next_obs=np.asarray(slot["next"], dtype=np.float32),
        terminated=bool(terminated),
        truncated=bool(truncated),
    )


def collect(
    expert: Expert,
    out: str | os.PathLike[str],
    *,
    transitions: int,
    seed: int = 0,
    deterministic: bool | None = None,
) -> CollectSummary:
    """Write ``transitions`` rows of the expert's play to the Parquet table ``out``
    (``deterministic`` None: the task's default, :func:`default_deterministic`; the table's
    metadata and the summary record the value used)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    if deterministic is None:
        deterministic = default_deterministic(expert.env_id)
    episodes = rollout(expert, transitions=transitions, seed=seed, deterministic=deterministic)
    lengths = np.array([len(e.rewards) for e in episodes])
    obs = np.concatenate([e.obs for e in episodes])[:transitions]
    next_obs = np.concatenate([e.next_obs for e in episodes])[:transitions]
    actions = np.concatenate([e.actions for e in episodes])[:transitions]
    rewards = np.concatenate([e.rewards for e in episodes])[:transitions]
    episode_ids = np.repeat(np.arange(len(episodes), dtype=np.int64), lengths)[:transitions]
    terminated, truncated = (
        np.zeros(len(rewards), dtype=bool),
        np.zeros(len(rewards), dtype=bool),
    )
    ends = np.cumsum(lengths) - 1
    for k, end in enumerate(ends):
        if end < transitions:  # a cut last episode keeps both flags False
            terminated[end], truncated[end] = episodes[k].terminated, episodes[k].truncated

    discrete = np.issubdtype(actions.dtype, np.integer)
    action_column = (
        pa.array(actions.astype(np.int64))
        if discrete
        else _fixed_list(actions.reshape(len(actions), -1).astype(np.float32))
    )
    complete = [float(e.rewards.sum()) for e, end in zip(episodes, ends, strict=True)
                if end < transitions]  # fmt: skip
    summary = CollectSummary(
        path=str(out),
        env=expert.env_id,
        transitions=len(rewards),
        episodes=int(episode_ids[-1]) + 1,
        seed=seed,
        deterministic=deterministic,
        return_mean=float(np.mean(complete)) if complete else float("nan"),
        return_std=float(np.std(complete)) if complete else float("nan"),
        complete_episodes=len(complete),
    )
    table = pa.table(
        {
            "obs": _fixed_list(obs),
            "action": action_column,
            "reward": pa.array(rewards, type=pa.float32()),
            "next_obs": _fixed_list(next_obs),
            "done": pa.array(terminated),
            "truncated": pa.array(truncated),
            "episode": pa.array(episode_ids),
        }
    )
    meta = {
        "env": expert.env_id,
        "expert_algo": expert.algo,
        "expert_return_mean": expert.record.get("return_mean"),
        "seed": seed,
        "deterministic": deterministic,
    }
    table = table.replace_schema_metadata({"pokerirl.gym": json.dumps(meta, sort_keys=True)})
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as temporary, open(temporary, "wb") as file:
        pq.write_table(table, file)  # a file object: pyarrow cannot name non-UTF-8 paths
    return summary


def _fixed_list(values: np.ndarray):
    import pyarrow as pa

    values = np.ascontiguousarray(values, dtype=np.float32)
    return pa.FixedSizeListArray.from_arrays(pa.array(values.reshape(-1)), values.shape[1])


def read_transitions(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """The table as numpy arrays: ``obs`` and ``next_obs`` ``(n, d)`` float32, and so on."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    with open(path, "rb") as file:  # a file object: pyarrow cannot name non-UTF-8 paths
        table = pq.read_table(file)
    out: dict[str, np.ndarray] = {}
    for name in COLUMNS:
        column = table.column(name).combine_chunks()
        if pa.types.is_fixed_size_list(column.type):
            out[name] = column.flatten().to_numpy().reshape(len(column), column.type.list_size)
        else:
            out[name] = column.to_numpy(zero_copy_only=False)
    return out
