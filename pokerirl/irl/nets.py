"""Small networks for AIRL: a reward net f_θ(s, a) and policies π_φ(a|s).

Both policies speak *action vectors*: a one-hot (or a point on the probability simplex) for
discrete actions, the action itself for continuous ones. The reward net reads the state
concatenated with such a vector, so one reward net serves expert actions, policy action
distributions and noisy versions of them alike.

>>> import torch
>>> reward = RewardNet(obs_dim=3, action_dim=2, hidden=(8,))
>>> reward(torch.zeros(5, 3), torch.ones(5, 2)).shape
torch.Size([5])
>>> policy = DiscretePolicy(obs_dim=3, num_actions=2, hidden=(8,))
>>> policy.action_vector(policy(torch.zeros(5, 3))).sum(dim=1)
tensor([1., 1., 1., 1., 1.], grad_fn=<SumBackward1>)
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
import torch.nn.functional as F
from torch import Tensor, nn

# Finite stand-in for log(0) on illegal actions: 0 * MASKED_LOGIT is 0, 0 * -inf would be NaN.
MASKED_LOGIT = -1e9


def build_mlp(in_dim: int, hidden: Sequence[int], out_dim: int) -> nn.Sequential:
    """ReLU MLP ``in_dim -> hidden... -> out_dim`` with a linear output."""
    layers: list[nn.Module] = []
    for width in hidden:
        layers += [nn.Linear(in_dim, width), nn.ReLU()]
        in_dim = width
    layers.append(nn.Linear(in_dim, out_dim))
    return nn.Sequential(*layers)


class RewardNet(nn.Module):
    """f_θ(s, a): an MLP over the state concatenated with an action vector, giving a scalar.

    The first layer is kept as two linear maps, ``W_s s + b`` and ``W_a a``: the same map as
    one layer on the concatenation, but the state half can be shared between the several
    action vectors that the discriminator scores at each state.
    """

    def __init__(self, *, obs_dim: int, action_dim: int, hidden: Sequence[int] = (64,)) -> None:
        super().__init__()
        if not hidden:
            raise ValueError("RewardNet needs at least one hidden layer")
        self.obs_dim = obs_dim
        self.action_dim = action_dim
        self.obs_layer = nn.Linear(obs_dim, hidden[0])
        self.action_layer = nn.Linear(action_dim, hidden[0], bias=False)
        self.head = build_mlp(hidden[0], hidden[1:], 1)

    def state_features(self, obs: Tensor) -> Tensor:
        """The state half of the first layer, ``W_s s + b`` (pre-activation)."""
        return self.obs_layer(obs)

    def from_features(self, features: Tensor, action: Tensor) -> Tensor:
        """Finish f from ``state_features(obs)`` and action vectors: (B,) rewards.

        ``action`` may hold k action vectors per state stacked as (k·B, action_dim).
        """
        repeats = len(action) // len(features)
        if repeats > 1:
            features = features.repeat(repeats, 1)
        hidden = torch.relu(features + self.action_layer(action))
        return self.head(hidden).squeeze(-1)

    def forward(self, obs: Tensor, action: Tensor) -> Tensor:
        return self.from_features(self.state_features(obs), action)


class DiscretePolicy(nn.Module):
    """Categorical π_φ(a|s) over ``num_actions``; illegal actions get probability zero.

    ``forward`` returns masked log-probabilities; the other methods take that output.
    """

    discrete = True

    def __init__(self, *, obs_dim: int, num_actions: int, hidden: Sequence[int] = (64,)) -> None:
        super().__init__()
        self.obs_dim = obs_dim
        self.action_dim = num_actions
        self.mlp = build_mlp(obs_dim, hidden, num_actions)

    def forward(self, obs: Tensor, legal_mask: Tensor | None = None) -> Tensor:
        logits = self.mlp(obs)
        if legal_mask is not None:
            logits = logits.masked_fill(~legal_mask, MASKED_LOGIT)
        return torch.log_softmax(logits, dim=-1)

    def action_vector(self, log_probs: Tensor, generator: torch.Generator | None = None) -> Tensor:
        """The policy's action vector: its action distribution, differentiable."""
        return log_probs.exp()

    def log_prob(self, log_probs: Tensor, action: Tensor) -> Tensor:
        """log π(a|s) of a point on the simplex: Σ_a a_k log π(k|s) (exact for one-hots).

        For the policy's own distribution this is Σ π log π, the negative entropy.
        """
        return (action * log_probs).sum(dim=-1)

    def supervised_loss(self, log_probs: Tensor, expert_action: Tensor) -> Tensor:
        """Cross-entropy CE(π(·|s), a_E), with ``expert_action`` one-hot."""
        return -(expert_action * log_probs).sum(dim=-1).mean()

    def perturb(
        self,
        action: Tensor,
        sigma: Tensor,
        legal_mask: Tensor | None,
        generator: torch.Generator | None = None,
    ) -> Tensor:
        """Add N(0, σ_i²) noise per row, then project back onto the (legal) simplex.

        One-hot vectors live in [0, 1], so σ is already normalized to the action range.
        """
        noise = torch.randn(action.shape, generator=generator, device=action.device)
        return project_to_simplex(action + sigma[:, None] * noise, legal_mask)

    def predict(self, log_probs: Tensor) -> Tensor:
        """Greedy action ids (B,)."""
        return log_probs.argmax(dim=-1)


class GaussianPolicy(nn.Module):
    """Diagonal Gaussian π_φ(a|s) for actions in the box [low, high].

    The mean is squashed into the box with tanh; the log standard deviation is a free
    parameter per action dimension. ``forward`` returns the mean.
    """

    discrete = False

    def __init__(
        self,
        *,
        obs_dim: int,
        low: Sequence[float],
        high: Sequence[float],
        hidden: Sequence[int] = (64,),
    ) -> None:
        super().__init__()
        if len(low) != len(high) or any(h <= lo for lo, h in zip(low, high, strict=True)):
            raise ValueError("GaussianPolicy needs low < high in every action dimension")
        self.obs_dim = obs_dim
        self.action_dim = len(low)
        self.mlp = build_mlp(obs_dim, hidden, self.action_dim)
        self.log_std = nn.Parameter(torch.full((self.action_dim,), -0.5))
        self.register_buffer("low", torch.tensor(low, dtype=torch.float32))
        self.register_buffer("high", torch.tensor(high, dtype=torch.float32))

    def forward(self, obs: Tensor, legal_mask: Tensor | None = None) -> Tensor:
        half_range = (self.high - self.low) / 2
        return self.low + half_range * (torch.tanh(self.mlp(obs)) + 1)

    def action_vector(self, mean: Tensor, generator: torch.Generator | None = None) -> Tensor:
        """A reparameterized sample a = μ + σ ε, differentiable in φ."""
        noise = torch.randn(mean.shape, generator=generator, device=mean.device)
        return mean + self.log_std.exp() * noise

    def log_prob(self, mean: Tensor, action: Tensor) -> Tensor:
        """Gaussian log-density log π(a|s), summed over action dimensions."""
        log_std = self.log_std.expand_as(mean)
        z = (action - mean) * torch.exp(-log_std)
        return (-0.5 * z.square() - log_std - 0.5 * math.log(2 * math.pi)).sum(dim=-1)

    def supervised_loss(self, mean: Tensor, expert_action: Tensor) -> Tensor:
        """MSE between the policy's mean action and the expert's."""
        return (mean - expert_action).square().sum(dim=-1).mean()

    def perturb(
        self,
        action: Tensor,
        sigma: Tensor,
        legal_mask: Tensor | None,
        generator: torch.Generator | None = None,
    ) -> Tensor:
        """Add noise with σ_i scaled by the action range, then clip to the box."""
        noise = torch.randn(action.shape, generator=generator, device=action.device)
        noisy = action + sigma[:, None] * (self.high - self.low) * noise
        return torch.maximum(torch.minimum(noisy, self.high), self.low)

    def predict(self, mean: Tensor) -> Tensor:
        """The mean action (B, k)."""
        return mean


Policy = DiscretePolicy | GaussianPolicy


def project_to_simplex(v: Tensor, mask: Tensor | None = None) -> Tensor:
    """Row-wise Euclidean projection onto the probability simplex.

    Solves ``argmin_p ||p - v||`` subject to ``p >= 0, sum(p) = 1`` (and ``p = 0`` where
    ``mask`` is False) by the sort-and-threshold method (Duchi et al., 2008).

    >>> project_to_simplex(torch.tensor([[0.5, 0.5, 2.0], [1.0, 0.0, 0.0]]))
    tensor([[0., 0., 1.],
            [1., 0., 0.]])
    """
    if mask is not None:
        # Masked entries sort last and fall below any threshold, so they project to 0.
        v = v.masked_fill(~mask, MASKED_LOGIT)
    sorted_v, _ = torch.sort(v, dim=-1, descending=True)
    cumsum = sorted_v.cumsum(dim=-1) - 1
    k = torch.arange(1, v.shape[-1] + 1, device=v.device, dtype=v.dtype)
    # rho = the largest k with sorted_v[k] > (cumsum[k]) / k; the condition holds for a prefix.
    support = (sorted_v * k > cumsum).sum(dim=-1, keepdim=True)
    theta = cumsum.gather(-1, support - 1) / support.to(v.dtype)
    return (v - theta).clamp_min(0)
