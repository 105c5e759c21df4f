"""AIRL / Hybrid-AIRL / GAIL reward learning on expert :class:`Transitions`.

:mod:`pokerirl.irl.airl` is the algorithm and its entry points :func:`train` and
:func:`train_many` (one run, or R in lock-step); :mod:`~.trainer` is its
:class:`AdversarialTrainer`, made of strategies: a :class:`Discriminator` (AIRL's D or
GAIL's, :mod:`~.discriminators`) and a :class:`PolicyHead` (discrete or Gaussian,
:mod:`~.heads`). Its other pieces are :mod:`~.losses`, :mod:`~.fast`, :mod:`~.stacked` nets,
:mod:`~.records`, :mod:`~.evaluate` and :mod:`~.baselines`; :mod:`~.nets` has the default
networks (:class:`RewardNet` and :class:`PolicyNet`: :mod:`~.reward`), :mod:`~.transitions`
the data (:mod:`~.interop`: to and from the ``imitation`` library's arrays), :mod:`~.run` the
run folders and :func:`load_reward`.
It knows nothing of poker or Gymnasium (``tests/test_layers.py``): poker tables and
``pokerirl train`` are :mod:`pokerirl.poker`, environments :mod:`pokerirl.gym`.
For example::

    from pokerirl.irl import load_reward

    reward = load_reward("runs/hairl")
    rewards = reward(obs, action_ids)  # (B, 72) uint8 and (B,) ints -> (B,) float32
"""

from __future__ import annotations

from pokerirl.irl.airl import (
    AdversarialTrainer,
    ManyResult,
    TrainResult,
    baselines,
    default_nets,
    discriminator_loss,
    evaluate,
    noise_schedule,
    train,
    train_many,
)
from pokerirl.irl.config import ALGOS, AIRLConfig, ConfigError, load_config
from pokerirl.irl.discriminators import AIRLDiscriminator, Discriminator, GAILDiscriminator
from pokerirl.irl.heads import DiscreteHead, GaussianHead, PolicyHead
from pokerirl.irl.interop import (
    ImitationTrajectory,
    ImitationTransitions,
    from_imitation_trajectories,
    from_imitation_transitions,
    to_imitation_trajectories,
    to_imitation_transitions,
)
from pokerirl.irl.nets import (
    DiscretePolicy,
    GaussianPolicy,
    NetSpec,
    ShapedReward,
    StateActionReward,
    build_nets,
    project_to_simplex,
)
from pokerirl.irl.records import Batch, EpochCallback, EpochMetrics, EpochRecord, StepLosses
from pokerirl.irl.reward import PolicyNet, RewardFn, RewardNet
from pokerirl.irl.run import (
    RewardFunction,
    RunError,
    RunResult,
    RunsSummary,
    RunSummary,
    load_policy,
    load_reward,
    load_run_config,
    train_into,
)
from pokerirl.irl.transitions import Transitions

__all__ = [
    "ALGOS",
    "AIRLConfig",
    "AIRLDiscriminator",
    "AdversarialTrainer",
    "Batch",
    "ConfigError",
    "DiscreteHead",
    "DiscretePolicy",
    "Discriminator",
    "EpochCallback",
    "EpochMetrics",
    "EpochRecord",
    "GAILDiscriminator",
    "GaussianHead",
    "GaussianPolicy",
    "ImitationTrajectory",
    "ImitationTransitions",
    "ManyResult",
    "NetSpec",
    "PolicyHead",
    "PolicyNet",
    "RewardFn",
    "RewardFunction",
    "RewardNet",
    "RunError",
    "RunResult",
    "RunSummary",
    "RunsSummary",
    "ShapedReward",
    "StateActionReward",
    "StepLosses",
    "TrainResult",
    "Transitions",
    "baselines",
    "build_nets",
    "default_nets",
    "discriminator_loss",
    "evaluate",
    "from_imitation_trajectories",
    "from_imitation_transitions",
    "load_config",
    "load_policy",
    "load_reward",
    "load_run_config",
    "noise_schedule",
    "project_to_simplex",
    "to_imitation_trajectories",
    "to_imitation_transitions",
    "train",
    "train_into",
    "train_many",
]
