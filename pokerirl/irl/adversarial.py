"""AIRL, Hybrid-AIRL and GAIL on :class:`Transitions`, for one run or R runs in lock-step.

Per shuffled mini-batch of expert rows (s, a_E[, s', done, r_env]):

1. the policy acts at s: π(·|s) for discrete actions, a reparameterized sample μ(s) + σε
   for continuous ones (one forward pass, kept for step 3);
2. discriminator step: D = exp f / (exp f + π) learns to call (s, a_E) expert and (s, ã)
   policy, with loss (1−β)·L_AIRL + β·mean (f(s, a_E) − r_env)². ã is what the discriminator
   sees of the policy (``disc_action``): a one-hot drawn from π (default), or π itself; then
   Gaussian noise with σ_i along the batch (``noise_schedule``), projected back onto the
   legal simplex (or clipped to the box). log π(ã|s) = Σ_k ã_k log π(k|s), exact on one-hots;
3. policy step against the just-updated reward:
   (1−α)·E_{a∼π}[log π(a|s) − g(s, a)] + α·(CE(π, a_E) or ‖μ(s) − a_E‖²). For discrete
   actions the expectation is exact, Σ_k π_k (log π_k − g(s, e_k)); for continuous ones it is
   the reparameterized sample. g is the reward's action-dependent part: all of f for the
   ``state_action`` family; for ``shaped`` the γh(s') − h(s) terms do not depend on a.

:class:`~pokerirl.irl.trainer.AdversarialTrainer` runs these steps, with what depends on
the action space (the forms above: discrete or continuous) in its
:class:`~pokerirl.irl.heads.PolicyHead`; :func:`train` and :func:`train_many` build one.

AIRL is α = β = 0 and no noise. GAIL is AIRL with another discriminator, D = σ(f): the
trainer asks its :class:`~pokerirl.irl.discriminators.Discriminator` for the logits
log D − log(1 − D) wherever it needs them (AIRL's f − log π above, GAIL's f); the policy
step is the same for both (GAIL's causal-entropy weight is 1). ``docs/method.md`` says
which choice comes from where.

Gradients are autograd's, except on the one architecture :mod:`pokerirl.irl.fast` covers
(the default poker nets, one run on CPU), where hand-derived gradients, tested against
autograd, make a step about twice as fast; ``fast_path=False`` turns that off.

R runs in lock-step (:func:`train_many`) stack the R nets' parameters (batched products for
the default nets' layers, ``torch.func.vmap`` for other architectures); every run has its
own seed, shuffle and noise, and its own Adam state (Adam is elementwise, so one optimizer
over stacked parameters is R independent ones).

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> obs = rng.random((512, 6)).astype(np.float32)
>>> data = Transitions.from_arrays(obs, (obs[:, 0] > 0.5).astype(np.int64), groups=np.arange(512))
>>> config = AIRLConfig.for_algo("hairl", epochs=20, batch_size=64, alpha=1.0)
>>> result = train(data, data, config=config, progress=False)
>>> from pokerirl.irl.metrics import Metric
>>> Metric.VAL_ALIGNMENT.of(result.metrics[-1]) > 0.9
True
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import cast

import torch
from torch import nn

from pokerirl.errors import check_argument
from pokerirl.irl.baselines import baselines
from pokerirl.irl.config import AIRLConfig
from pokerirl.irl.evaluate import evaluate
from pokerirl.irl.losses import (
    LOG_2PI,
    LOSS_KEYS,
    discriminator_loss,
    gaussian_log_prob,
    noise_schedule,
    sample_one_hot,
)
from pokerirl.irl.nets import NetSpec, build_nets
from pokerirl.irl.records import EpochCallback, EpochMetrics, EpochRecord, StepLosses, TrainingBatch
from pokerirl.irl.reward import PolicyNet, RewardNet
from pokerirl.irl.stacked import (
    StackedLayerNorm,
    StackedLinear,
    StackedNets,
    stack_modules,
)
from pokerirl.irl.trainer import AdversarialTrainer, ManyResult, TrainResult, resolve_device
from pokerirl.irl.transitions import Transitions

# Importable from here as before the split (losses, stacked nets, evaluation, baselines).
__all__ = [
    "LOG_2PI",
    "LOSS_KEYS",
    "AdversarialTrainer",
    "EpochCallback",
    "EpochRecord",
    "ManyResult",
    "StackedLayerNorm",
    "StackedLinear",
    "StackedNets",
    "StepLosses",
    "TrainResult",
    "TrainingBatch",
    "baselines",
    "default_nets",
    "discriminator_loss",
    "evaluate",
    "gaussian_log_prob",
    "noise_schedule",
    "resolve_device",
    "sample_one_hot",
    "stack_modules",
    "train",
    "train_many",
]

# --------------------------------------------------------------------------- training


def default_nets(
    data: Transitions, config: AIRLConfig, seed: int | None = None
) -> tuple[nn.Module, nn.Module]:
    """The default (reward, policy) for ``data``'s spaces, initialized from ``seed``
    (default ``config.seed``) without touching torch's global generator."""
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(config.seed if seed is None else seed)
        return build_nets(
            NetSpec.of(config),
            obs_dim=data.obs_dim,
            action_dim=data.action_dim,
            discrete=data.discrete,
            low=data.action_low,
            high=data.action_high,
        )


def train(
    train_data: Transitions,
    val_data: Transitions,
    *,
    config: AIRLConfig,
    reward: nn.Module | None = None,
    policy: nn.Module | None = None,
    adversarial: bool = True,
    fast_path: bool = True,
    device: str | torch.device = "cpu",
    progress: bool = True,
    on_epoch: Callable[[EpochMetrics], None] | None = None,
    callback: EpochCallback | None = None,
) -> TrainResult:
    """Train ``reward`` and ``policy`` (default: :func:`default_nets`) on ``train_data``;
    evaluate on ``val_data`` each epoch. Deterministic on CPU for a given seed and data.

    ``adversarial=False`` skips the discriminator (behaviour cloning when α = 1).
    ``fast_path``: use the hand-derived gradients of :mod:`pokerirl.irl.fast` where they
    cover the nets (the default poker nets, one run, on CPU); autograd otherwise.
    ``on_epoch`` gets each epoch's metrics as soon as they are ready; ``callback`` (an
    :class:`EpochCallback`) may add metrics to it first.
    """
    check_argument("train_data", train_data, Transitions, "Transitions")
    check_argument("val_data", val_data, Transitions, "Transitions")
    check_argument("config", config, AIRLConfig, "an AIRLConfig (AIRLConfig.for_algo gives one)")
    if reward is None or policy is None:
        default_reward, default_policy = default_nets(train_data, config)
        reward = default_reward if reward is None else reward
        policy = default_policy if policy is None else policy
    many = train_many(
        train_data,
        val_data,
        config=config,
        seeds=[config.seed],
        rewards=[reward],
        policies=[policy],
        adversarial=adversarial,
        fast_path=fast_path,
        device=device,
        progress=progress,
        on_epoch=None if on_epoch is None else (lambda ms: on_epoch(ms[0])),
        callback=callback,
    )
    return many.runs[0]


def train_many(
    train_data: Transitions,
    val_data: Transitions,
    *,
    config: AIRLConfig,
    seeds: Sequence[int],
    rewards: Sequence[nn.Module] | None = None,
    policies: Sequence[nn.Module] | None = None,
    adversarial: bool = True,
    fast_path: bool = True,
    device: str | torch.device = "cpu",
    progress: bool = True,
    on_epoch: Callable[[list[EpochMetrics]], None] | None = None,
    callback: EpochCallback | None = None,
) -> ManyResult:
    """R = len(seeds) runs of ``config`` on the same data, in lock-step.

    Run r uses ``seeds[r]`` for its shuffles and noise (and, with default nets, its
    initialization), so it is the run ``train`` would make with that seed, up to floating
    point. The nets must share one architecture. After each epoch ``callback`` (an
    :class:`EpochCallback`) may add metrics per run; then ``on_epoch`` gets the R runs' metrics.
    """
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("train_many needs at least one seed")
    if rewards is None or policies is None:
        built = [default_nets(train_data, config, seed) for seed in seeds]
        rewards = [b[0] for b in built] if rewards is None else rewards
        policies = [b[1] for b in built] if policies is None else policies
    return AdversarialTrainer(
        demonstrations=train_data,
        validation=val_data,
        config=config,
        seeds=seeds,
        # Modules in the Protocols' shape (mypy cannot see it: nn.Module's __getattr__).
        rewards=cast(Sequence[RewardNet], rewards),
        policies=cast(Sequence[PolicyNet], policies),
        adversarial=adversarial,
        fast_path=fast_path,
        device=device,
    ).train(progress=progress, on_epoch=on_epoch, callback=callback)
