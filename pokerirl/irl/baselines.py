"""Rule baselines for discrete actions: what alignment a policy must beat."""

from __future__ import annotations

import torch
from torch import Tensor

from pokerirl.irl.transitions import Transitions


def baselines(train_data: Transitions, val_data: Transitions) -> dict[str, float]:
    """Validation alignment of the rule baselines (discrete actions).

    ``majority``: always the most frequent training action. ``legal_majority``: for each set
    of legal actions, the most frequent expert action among training rows with that set
    (the overall majority among legal actions for a set never seen in training). Rows with
    weights count that many times, in the rules' counts and in their alignment.
    """
    k = train_data.action_dim
    row_weights = train_data.weights
    counts = torch.bincount(train_data.actions, weights=row_weights, minlength=k).float()
    expert = val_data.actions
    result = {"majority": _aligned(expert == counts.argmax(), val_data.weights)}
    if train_data.legal_mask is None or val_data.legal_mask is None:
        result["legal_majority"] = result["majority"]
        return result
    weights = 2 ** torch.arange(k)
    train_key = (train_data.legal_mask.long() * weights).sum(-1)
    val_key = (val_data.legal_mask.long() * weights).sum(-1)
    table = torch.zeros(2**k, k)
    ones = torch.ones(len(train_key)) if row_weights is None else row_weights.float()
    table.index_put_((train_key, train_data.actions), ones, accumulate=True)
    table += counts * 1e-6  # unseen sets fall back to the overall counts; ties to majority
    table = table.masked_fill(~_mask_of(torch.arange(2**k), k), -1.0)
    predicted = table[val_key].argmax(-1)
    result["legal_majority"] = _aligned(predicted == expert, val_data.weights)
    return result


def _aligned(hit: Tensor, weights: Tensor | None) -> float:
    """The (weighted) share of rows where ``hit``."""
    if weights is None:
        return hit.float().mean().item()
    return ((hit.float() * weights).sum() / weights.sum()).item()


def _mask_of(keys: Tensor, k: int) -> Tensor:
    return (keys[:, None] >> torch.arange(k)) & 1 == 1
