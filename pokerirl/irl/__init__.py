"""AIRL / Hybrid-AIRL / GAIL reward learning on expert :class:`Transitions`.

:mod:`pokerirl.irl.adversarial` holds the three algorithms and their entry points
:func:`train` and :func:`train_many` (one run, or R in lock-step); :mod:`~.trainer` is its
:class:`AdversarialTrainer`, made of strategies: a :class:`Discriminator` (AIRL's D or
GAIL's, :mod:`~.discriminators`) and a :class:`PolicyHead` (discrete or Gaussian,
:mod:`~.heads`). Its other pieces are :mod:`~.losses`, :mod:`~.fast`, :mod:`~.stacked` nets,
:mod:`~.records`, :mod:`~.metrics` (every epoch metric, named once), :mod:`~.evaluate` and
:mod:`~.baselines`; :mod:`~.nets` has the default
networks (:class:`RewardNet` and :class:`PolicyNet`: :mod:`~.reward`), :mod:`~.transitions`
the data (:mod:`~.interop`: to and from the ``imitation`` library's arrays), :mod:`~.run` the
run folders (:func:`train_runs_into`, the one trainer of runs into them) and
:func:`load_reward`.
It knows nothing of poker or Gymnasium (``tests/test_layers.py``): poker tables and
``pokerirl train`` are :mod:`pokerirl.poker`, environments :mod:`pokerirl.gym`.
For example::

    from pokerirl.irl import load_reward

    reward = load_reward("runs/hairl")
    rewards = reward(obs, action_ids)  # (B, 72) uint8 and (B,) ints -> (B,) float32
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # what the names are, for type checkers
    from pokerirl.irl.adversarial import (
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
    from pokerirl.irl.metrics import Metric
    from pokerirl.irl.nets import (
        DiscretePolicy,
        GaussianPolicy,
        NetSpec,
        ShapedReward,
        StateActionReward,
        build_nets,
        project_to_simplex,
    )
    from pokerirl.irl.records import (
        EpochCallback,
        EpochMetrics,
        EpochRecord,
        StepLosses,
        TrainingBatch,
    )
    from pokerirl.irl.reward import PolicyNet, RewardFn, RewardNet
    from pokerirl.irl.run import (
        ObsMap,
        RewardFunction,
        RunError,
        RunHooks,
        RunResult,
        RunsSummary,
        RunSummary,
        load_policy,
        load_reward,
        load_run_config,
        train_into,
        train_runs_into,
    )
    from pokerirl.irl.trainer import AdversarialTrainer
    from pokerirl.irl.transitions import Transitions

# torch takes a second to import: the command line reads the settings (config.py, torch-free)
# without it, so every name here loads its module when first used.
_LAZY = {
    "AdversarialTrainer": "trainer",
    "ManyResult": "adversarial",
    "TrainResult": "adversarial",
    "baselines": "adversarial",
    "default_nets": "adversarial",
    "discriminator_loss": "adversarial",
    "evaluate": "adversarial",
    "noise_schedule": "adversarial",
    "train": "adversarial",
    "train_many": "adversarial",
    "AIRLConfig": "config",
    "ALGOS": "config",
    "ConfigError": "config",
    "load_config": "config",
    "AIRLDiscriminator": "discriminators",
    "Discriminator": "discriminators",
    "GAILDiscriminator": "discriminators",
    "DiscreteHead": "heads",
    "GaussianHead": "heads",
    "PolicyHead": "heads",
    "ImitationTrajectory": "interop",
    "ImitationTransitions": "interop",
    "from_imitation_trajectories": "interop",
    "from_imitation_transitions": "interop",
    "to_imitation_trajectories": "interop",
    "to_imitation_transitions": "interop",
    "Metric": "metrics",
    "DiscretePolicy": "nets",
    "GaussianPolicy": "nets",
    "NetSpec": "nets",
    "ShapedReward": "nets",
    "StateActionReward": "nets",
    "build_nets": "nets",
    "project_to_simplex": "nets",
    "TrainingBatch": "records",
    "EpochCallback": "records",
    "EpochMetrics": "records",
    "EpochRecord": "records",
    "StepLosses": "records",
    "RewardFn": "reward",
    "RewardNet": "reward",
    "PolicyNet": "reward",
    "ObsMap": "run",
    "RewardFunction": "run",
    "RunHooks": "run",
    "RunError": "run",
    "RunResult": "run",
    "RunSummary": "run",
    "RunsSummary": "run",
    "load_policy": "run",
    "load_reward": "run",
    "load_run_config": "run",
    "train_into": "run",
    "train_runs_into": "run",
    "Transitions": "transitions",
}
# Functions named as the submodules they live in: the package's name is the function.
_FUNCTIONS = {"baselines", "evaluate"}


class _Package(types.ModuleType):
    def __getattribute__(self, name: str) -> Any:
        if name in _FUNCTIONS:
            return getattr(importlib.import_module("pokerirl.irl.adversarial"), name)
        return super().__getattribute__(name)

    def __getattr__(self, name: str) -> Any:
        if name in _LAZY:
            return getattr(importlib.import_module(f"pokerirl.irl.{_LAZY[name]}"), name)
        raise AttributeError(f"module 'pokerirl.irl' has no attribute {name!r}")


sys.modules[__name__].__class__ = _Package

__all__ = [
    "ALGOS",
    "AIRLConfig",
    "AIRLDiscriminator",
    "AdversarialTrainer",
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
    "Metric",
    "NetSpec",
    "ObsMap",
    "PolicyHead",
    "PolicyNet",
    "RewardFn",
    "RewardFunction",
    "RewardNet",
    "RunError",
    "RunHooks",
    "RunResult",
    "RunSummary",
    "RunsSummary",
    "ShapedReward",
    "StateActionReward",
    "StepLosses",
    "TrainResult",
    "TrainingBatch",
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
    "train_runs_into",
]
