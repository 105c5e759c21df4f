"""AIRL / Hybrid-AIRL reward learning from expert decision tables.

The core (:mod:`pokerirl.irl.airl`) works on tensors of states, action vectors, legal masks
and rewards, for discrete and continuous actions; :mod:`pokerirl.irl.table` reads the poker
Parquet tables; :mod:`pokerirl.irl.run` writes and reads run directories. For example::

    from pokerirl.irl import load_reward

    reward = load_reward("runs/hairl")
    rewards = reward(obs, action_ids)  # (B, 72) uint8 and (B,) ints -> (B,) float32
"""

from __future__ import annotations

from pokerirl.irl.airl import (
    ALGOS,
    AIRLConfig,
    ExpertData,
    TrainResult,
    discriminator_grad,
    discriminator_loss,
    log_discriminator,
    noise_schedule,
    policy_loss,
    train,
)
from pokerirl.irl.nets import DiscretePolicy, GaussianPolicy, RewardNet, project_to_simplex
from pokerirl.irl.run import (
    RewardFunction,
    RunSummary,
    load_config,
    load_policy,
    load_reward,
    load_run_config,
    save_run,
    train_table,
)
from pokerirl.irl.table import ExpertTable, read_expert_table, split_by_hand

__all__ = [
    "ALGOS",
    "AIRLConfig",
    "DiscretePolicy",
    "ExpertData",
    "ExpertTable",
    "GaussianPolicy",
    "RewardFunction",
    "RewardNet",
    "RunSummary",
    "TrainResult",
    "discriminator_grad",
    "discriminator_loss",
    "load_config",
    "load_policy",
    "load_reward",
    "load_run_config",
    "log_discriminator",
    "noise_schedule",
    "policy_loss",
    "project_to_simplex",
    "read_expert_table",
    "save_run",
    "split_by_hand",
    "train",
    "train_table",
]
