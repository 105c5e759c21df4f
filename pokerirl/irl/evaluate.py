"""Validation metrics of one trained (reward, policy) pair."""

from __future__ import annotations

import math

import torch
from torch import Tensor, nn

from pokerirl.irl.metrics import Metric, Part
from pokerirl.irl.transitions import Transitions


@torch.no_grad()
def evaluate(
    reward: nn.Module, policy: nn.Module, val: Transitions, *, chunk: int = 65536
) -> dict[str, float | list[float]]:
    """Validation metrics of one run.

    Discrete: ``val_alignment`` (argmax π over legal actions = the expert's action),
    ``val_reward_alignment`` (argmax over legal actions of the reward g(s, ·) = the expert's),
    ``val_policy_dist`` (mean π), ``val_policy_argmax_dist`` and ``val_expert_dist``
    (action histograms). Continuous: ``val_mse`` of the mean action and ``log_std``, the
    policy's mean log σ.

    Rows with ``val.weights`` count that many times in every mean and histogram. When
    ``val.imputed`` is given, both alignments are also reported over the observed and the
    imputed rows apart (``val_alignment_observed``, ``val_alignment_imputed``,
    ``val_reward_alignment_observed``, ...; a part with no rows is left out).
    """
    was_training = reward.training, policy.training
    reward.eval()
    policy.eval()
    device = next(policy.parameters()).device
    try:
        if not val.discrete:
            errors = []
            for i in range(0, len(val), chunk):
                mean, log_std = policy(val.obs[i : i + chunk].to(device))
                errors.append((mean - val.actions[i : i + chunk].to(device)).square().sum(-1))
            # log σ: collapsing σ lets -log π alone win D and invert the reward (issue 20)
            return {
                Metric.VAL_MSE: torch.cat(errors).mean().item(),
                Metric.LOG_STD: log_std.mean().item(),
            }
        k = val.action_dim
        eye = torch.eye(k, device=device)[:, None, :]
        log_probs, reward_ids = [], []
        for i in range(0, len(val), chunk):
            obs = val.obs[i : i + chunk].to(device)
            mask = None if val.legal_mask is None else val.legal_mask[i : i + chunk].to(device)
            log_probs.append(policy(obs, mask))
            g = reward(obs, eye).T  # (B, K)
            if mask is not None:
                g = g.masked_fill(~mask, -math.inf)
            reward_ids.append(g.argmax(-1))
        log_pi = torch.cat(log_probs)
        expert = val.actions.to(device)
        predicted = log_pi.argmax(-1)
        by_reward = torch.cat(reward_ids)
        if val.weights is None and val.imputed is None:
            return {
                Metric.VAL_ALIGNMENT: (predicted == expert).float().mean().item(),
                Metric.VAL_REWARD_ALIGNMENT: (by_reward == expert).float().mean().item(),
                Metric.VAL_POLICY_DIST: log_pi.exp().mean(0).tolist(),
                Metric.VAL_POLICY_ARGMAX_DIST: _histogram(predicted, k),
                Metric.VAL_EXPERT_DIST: _histogram(expert, k),
            }
        return _weighted_metrics(val, log_pi, predicted, by_reward, expert)
    finally:
        reward.train(was_training[0])
        policy.train(was_training[1])


def _histogram(ids: Tensor, num_actions: int, weights: Tensor | None = None) -> list[float]:
    if weights is not None:
        counts = torch.bincount(ids, weights=weights, minlength=num_actions)
        return (counts / weights.sum()).float().tolist()
    return (torch.bincount(ids, minlength=num_actions).float() / max(len(ids), 1)).tolist()


def _weighted_metrics(
    val: Transitions, log_pi: Tensor, predicted: Tensor, by_reward: Tensor, expert: Tensor
) -> dict[str, float | list[float]]:
    """The discrete metrics with row weights, and over the observed and imputed rows apart."""
    device = log_pi.device
    w = torch.ones(len(expert), device=device) if val.weights is None else val.weights.to(device)
    k = log_pi.shape[1]

    def share(hit: Tensor, rows: Tensor) -> float:
        return ((hit.float() * w)[rows].sum() / w[rows].sum()).item()

    every = torch.ones(len(expert), dtype=torch.bool, device=device)
    found: dict[str, float | list[float]] = {
        Metric.VAL_ALIGNMENT: share(predicted == expert, every),
        Metric.VAL_REWARD_ALIGNMENT: share(by_reward == expert, every),
        Metric.VAL_POLICY_DIST: ((log_pi.exp() * w[:, None]).sum(0) / w.sum()).tolist(),
        Metric.VAL_POLICY_ARGMAX_DIST: _histogram(predicted, k, w),
        Metric.VAL_EXPERT_DIST: _histogram(expert, k, w),
    }
    if val.imputed is not None:
        imputed = val.imputed.to(device)
        for part, rows in ((Part.OBSERVED, ~imputed), (Part.IMPUTED, imputed)):
            if rows.any():
                found[Metric.VAL_ALIGNMENT.on(part)] = share(predicted == expert, rows)
                found[Metric.VAL_REWARD_ALIGNMENT.on(part)] = share(by_reward == expert, rows)
    return found
