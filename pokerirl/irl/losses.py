"""The Hybrid-AIRL losses and the random pieces they need, as pure functions of tensors.

The trainer (:mod:`pokerirl.irl.trainer`) calls them once per batch and once per epoch (for the
metrics); :mod:`pokerirl.irl.fast` has their hand-derived gradients.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import Tensor

from pokerirl.irl.config import NoiseSchedule
from pokerirl.irl.discriminators import AIRL, Discriminator
from pokerirl.irl.metrics import LOSSES

LOG_2PI = math.log(2 * math.pi)
LOSS_KEYS = LOSSES  # the loss metrics, named in pokerirl.irl.metrics


def noise_schedule(
    batch_size: int,
    sigma_start: float,
    sigma_end: float,
    *,
    kind: str = NoiseSchedule.LINEAR,
    decay: float = 0.1,
) -> Tensor:
    """σ_i for the i-th sample of a batch.

    ``linear`` (the paper): from σ_start on the first sample to σ_end on the last.
    ``authors`` (their code): σ_i = σ_start / (1 + k·b·i), b = (σ_start − σ_end)/(σ_end·B);
    the trainer shuffles these across the batch.

    >>> noise_schedule(5, 1.0, 0.2)
    tensor([1.0000, 0.8000, 0.6000, 0.4000, 0.2000])
    >>> noise_schedule(3, 1.0, 0.5, kind="authors", decay=1.0)
    tensor([1.0000, 0.7500, 0.6000])
    """
    if sigma_start == 0:
        return torch.zeros(batch_size)
    if kind == NoiseSchedule.AUTHORS:
        b = (sigma_start - sigma_end) / (sigma_end * batch_size)
        return sigma_start / (1 + decay * b * torch.arange(batch_size, dtype=torch.float32))
    if batch_size == 1:
        return torch.tensor([sigma_start])
    return torch.linspace(sigma_start, sigma_end, batch_size)


def weighted_mean(values: Tensor, weights: Tensor | None) -> Tensor:
    """The mean over the last dimension, each entry counted ``weights`` times (None: once).

    >>> weighted_mean(torch.tensor([1.0, 4.0]), torch.tensor([3.0, 1.0])).item()
    1.75
    """
    if weights is None:
        return values.mean(-1)
    return (values * weights).sum(-1) / weights.sum(-1)


def discriminator_loss(
    f_expert: Tensor,
    log_pi_expert: Tensor,
    f_policy: Tensor,
    log_pi_policy: Tensor,
    *,
    beta: float = 0.0,
    env_reward: Tensor | None = None,
    weights: Tensor | None = None,
    discriminator: Discriminator = AIRL,
) -> tuple[Tensor, Tensor, Tensor]:
    """(total, L_AIRL, env MSE), means over the last dimension (weighted by the expert
    rows' ``weights`` when given: the policy's actions are drawn at the same states).

    L_AIRL = −E_E[log D(s, a_E)] − E_π[log(1 − D(s, ã))] with D = σ(logit), the log-space
    form of exp f / (exp f + π) for AIRL's logit f − log π (GAIL's: f, D = σ(f)).
    total = (1−β)·L_AIRL + β·E_E[(f − r_env)²].

    >>> zero = torch.zeros(1)
    >>> round(discriminator_loss(zero, zero, zero, zero)[0].item(), 4)  # D = 1/2: 2 ln 2
    1.3863
    """
    # log(1 − σ(x)) = log σ(−x)
    airl = -(
        weighted_mean(F.logsigmoid(discriminator.logits(f_expert, log_pi_expert)), weights)
        + weighted_mean(F.logsigmoid(-discriminator.logits(f_policy, log_pi_policy)), weights)
    )
    if env_reward is None:
        return airl, airl, torch.zeros_like(airl)
    env = weighted_mean((f_expert - env_reward).square(), weights)
    return (1 - beta) * airl + beta * env, airl, env


def gaussian_log_prob(action: Tensor, mean: Tensor, log_std: Tensor) -> Tensor:
    """Diagonal Gaussian log-density, summed over the last dimension."""
    z = (action - mean) * torch.exp(-log_std)
    return (-0.5 * z.square() - log_std - 0.5 * LOG_2PI).sum(-1)


def sample_one_hot(probs: Tensor, u: Tensor) -> Tensor:
    """One-hots of actions drawn from ``probs`` (..., K) by inverse CDF with uniforms ``u``.

    With u below the last cumulative probability the pick always has positive probability,
    so it is never an illegal action.
    """
    cumulative = probs.cumsum(-1)
    picked = (cumulative <= u[..., None] * cumulative[..., -1:]).sum(-1, keepdim=True)
    return torch.zeros_like(probs).scatter_(-1, picked.clamp_max(probs.shape[-1] - 1), 1.0)
