"""Small networks for AIRL: a reward net f_θ(s, a) and policies π_φ(a|s).

Both policies speak *action vectors*: a one-hot (or a point on the probability simplex) for
discrete actions, the action itself for continuous ones. The reward net reads the state
concatenated with such a vector, so one reward net serves expert actions, policy action
distributions and noisy versions of them alike.

The nets are plain ``nn.Module``s (their ``forward`` is for inference and checkpoints), but
training does not go through autograd: for nets this small, on CPU, building and walking
the autograd graph costs several times the arithmetic. Each net therefore also has a cached
forward pass and a hand-derived backward pass (``forward_cached`` / ``backward``), checked
against autograd in ``tests/test_irl_core.py``.

>>> reward = RewardNet(obs_dim=3, action_dim=2, hidden=(8,))
>>> reward(torch.zeros(5, 3), torch.ones(5, 2)).shape
torch.Size([5])
>>> policy = DiscretePolicy(obs_dim=3, num_actions=2, hidden=(8,))
>>> policy(torch.zeros(5, 3)).exp().sum(dim=1)
tensor([1., 1., 1., 1., 1.], grad_fn=<SumBackward1>)
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import NamedTuple

import torch
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


def mlp_forward(mlp: nn.Sequential, x: Tensor) -> list[Tensor]:
    """Run a :func:`build_mlp` net, keeping what its backward pass needs.

    Returns the input of every linear layer (hidden ones after ReLU), then the output.
    """
    linears = _linears(mlp)
    acts = [x]
    for i, layer in enumerate(linears):
        y = torch.addmm(layer.bias, acts[-1], layer.weight.T)
        acts.append(y.relu_() if i < len(linears) - 1 else y)
    return acts


def mlp_backward(
    mlp: nn.Sequential,
    acts: list[Tensor],
    grad_out: Tensor,
    *,
    params: bool = True,
    input_grad: bool = False,
) -> tuple[list[Tensor], Tensor | None]:
    """Backpropagate ``grad_out`` (dL/d output) through a :func:`build_mlp` net.

    Returns the parameter gradients in ``mlp.parameters()`` order (empty if not ``params``)
    and dL/d input (None if not ``input_grad``).
    """
    linears = _linears(mlp)
    grads: list[Tensor] = []
    grad = grad_out
    for i in reversed(range(len(linears))):
        if params:
            grads += [grad.sum(dim=0), grad.T @ acts[i]]  # bias, weight (reversed below)
        if i == 0 and not input_grad:
            return grads[::-1], None
        grad = grad @ linears[i].weight
        if i > 0:
            grad = relu_backward(grad, acts[i])
    return grads[::-1], grad


def _linears(mlp: nn.Sequential) -> list[nn.Linear]:
    return [layer for layer in mlp if isinstance(layer, nn.Linear)]


def relu_backward(grad: Tensor, relu_output: Tensor) -> Tensor:
    """``grad`` where the ReLU was active, else 0 (one fused kernel, as autograd uses)."""
    return torch.ops.aten.threshold_backward(grad, relu_output, 0.0)


class RewardCache(NamedTuple):
    obs: Tensor
    actions: Tensor
    hidden: Tensor  # first hidden layer, after ReLU
    head_acts: list[Tensor]


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

    def forward(self, obs: Tensor, action: Tensor) -> Tensor:
        return self.forward_cached(obs, action)[0]

    def forward_cached(self, obs: Tensor, actions: Tensor) -> tuple[Tensor, RewardCache]:
        """f for (B, obs_dim) states and (k·B, action_dim) action vectors, k per state.

        Returns the (k·B,) rewards and what :meth:`backward` needs.
        """
        features = torch.addmm(self.obs_layer.bias, obs, self.obs_layer.weight.T)
        action_part = (actions @ self.action_layer.weight.T).view(-1, *features.shape)
        hidden = (action_part + features).relu_().view(len(actions), -1)  # broadcast over k
        head_acts = mlp_forward(self.head, hidden)
        return head_acts[-1].squeeze(-1), RewardCache(obs, actions, hidden, head_acts)

    def forward_each_action(self, obs: Tensor) -> Tensor:
        """(B, action_dim): f(s, e_k) for every one-hot e_k, sharing the state half."""
        features = torch.addmm(self.obs_layer.bias, obs, self.obs_layer.weight.T)
        # W_a e_k is column k of W_a: broadcast it instead of multiplying by one-hots, into a
        # contiguous (k, B, H) buffer (a broadcast's own output layout is several times slower).
        hidden = features.new_empty(self.action_dim, *features.shape)
        torch.add(features, self.action_layer.weight.T.contiguous()[:, None, :], out=hidden).relu_()
        f = mlp_forward(self.head, hidden.view(-1, features.shape[1]))[-1]
        return f.view(self.action_dim, len(obs)).T

    def backward(
        self, cache: RewardCache, grad_f: Tensor, *, params: bool = True, actions: bool = True
    ) -> tuple[list[Tensor], Tensor | None]:
        """Parameter gradients (``parameters()`` order) and dL/d action vectors.

        Either can be skipped (an empty list, None) when the caller does not need it.
        """
        head_grads, grad_hidden = mlp_backward(
            self.head, cache.head_acts, grad_f[:, None], params=params, input_grad=True
        )
        assert grad_hidden is not None
        grad_pre = relu_backward(grad_hidden, cache.hidden)
        grad_actions = grad_pre @ self.action_layer.weight if actions else None
        if not params:
            return [], grad_actions
        batch = len(cache.obs)
        grad_features = grad_pre.reshape(-1, batch, grad_pre.shape[1]).sum(dim=0)
        grads = [
            grad_features.T @ cache.obs,
            grad_features.sum(dim=0),
            grad_pre.T @ cache.actions,
            *head_grads,
        ]
        return grads, grad_actions


class PolicyOutput(NamedTuple):
    """One policy pass over a batch, as the trainer uses it."""

    acts: list[Tensor]  # MLP activations, for the backward pass
    dist: Tensor  # discrete: masked log-probabilities; continuous: mean action
    action: Tensor  # the policy's action vector: π(·|s), or a sample μ + σε
    log_prob: Tensor  # (B,) log π of ``action``: Σ π log π, or the Gaussian log-density
    noise: Tensor | None  # continuous: the ε of the sample


class DiscretePolicy(nn.Module):
    """Categorical π_φ(a|s) over ``num_actions``; illegal actions get probability zero.

    ``forward`` returns masked log-probabilities (the policy's ``dist``).
    """

    discrete = True

    def __init__(self, *, obs_dim: int, num_actions: int, hidden: Sequence[int] = (64,)) -> None:
        super().__init__()
        self.obs_dim = obs_dim
        self.action_dim = num_actions
        self.mlp = build_mlp(obs_dim, hidden, num_actions)

    def forward(self, obs: Tensor, legal_mask: Tensor | None = None) -> Tensor:
        return self._log_probs(self.mlp(obs), legal_mask)

    @staticmethod
    def _log_probs(logits: Tensor, legal_mask: Tensor | None) -> Tensor:
        if legal_mask is not None:
            logits = logits.masked_fill(~legal_mask, MASKED_LOGIT)
        return torch.log_softmax(logits, dim=-1)

    def act(
        self, obs: Tensor, legal_mask: Tensor | None, generator: torch.Generator | None = None
    ) -> PolicyOutput:
        """The action distribution π(·|s) as the action vector (no sampling)."""
        acts = mlp_forward(self.mlp, obs)
        log_probs = self._log_probs(acts[-1], legal_mask)
        probs = log_probs.exp()
        return PolicyOutput(acts, log_probs, probs, self.log_prob(log_probs, probs), None)

    def log_prob(self, log_probs: Tensor, action: Tensor) -> Tensor:
        """log π(a|s) of a point on the simplex: Σ_k a_k log π(k|s) (exact for one-hots).

        For the policy's own distribution this is Σ π log π, the negative entropy.
        """
        return (action * log_probs).sum(dim=-1)

    def supervised_loss(self, log_probs: Tensor, expert_action: Tensor) -> Tensor:
        """Per-sample cross-entropy CE(π(·|s), a_E), with ``expert_action`` one-hot."""
        return -(expert_action * log_probs).sum(dim=-1)

    def backward(
        self, out: PolicyOutput, grad_action: Tensor, expert_action: Tensor, alpha: float
    ) -> list[Tensor]:
        """Gradients of (1−α)·mean(−f(s, π) + Σ π log π) + α·mean(CE) for the parameters.

        ``grad_action`` is the first term's gradient through f: −(1−α)/B · ∂f/∂a at a = π.
        """
        probs, log_probs = out.action, out.dist
        # d/d logits of Σ π·(g + s·log π) is π ⊙ (h − Σ π h) with h = g + s·log π: the softmax
        # Jacobian applied to g, plus the entropy term (its "+1" cancels, Σ π = 1). Then CE.
        h = torch.add(grad_action, log_probs, alpha=(1 - alpha) / len(probs))
        grad_logits = probs * (h - (probs * h).sum(dim=-1, keepdim=True))
        grad_logits.add_(probs - expert_action, alpha=alpha / len(probs))
        return mlp_backward(self.mlp, out.acts, grad_logits)[0]

    def sample_action(self, out: PolicyOutput, generator: torch.Generator | None = None) -> Tensor:
        """One-hots of actions drawn from π(·|s): what the discriminator compares with the
        expert's one-hots.

        Inverse-CDF sampling, three times faster than ``multinomial`` + ``one_hot`` here. With
        u < the last cumulative probability, the pick is always an action of positive
        probability, so never an illegal one.
        """
        cumulative = out.action.cumsum(dim=1)
        u = torch.rand((len(cumulative), 1), generator=generator, device=cumulative.device).mul_(
            cumulative[:, -1:]
        )
        picked = (cumulative <= u).sum(dim=1, keepdim=True)
        return torch.zeros_like(out.action).scatter_(1, picked, 1.0)

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
        return project_to_simplex(torch.addcmul(action, sigma[:, None], noise), legal_mask)

    def predict(self, log_probs: Tensor) -> Tensor:
        """Greedy action ids (B,)."""
        return log_probs.argmax(dim=-1)


class GaussianPolicy(nn.Module):
    """Diagonal Gaussian π_φ(a|s) for actions in the box [low, high].

    The mean is squashed into the box with tanh; the log standard deviation is a free
    parameter per action dimension. ``forward`` returns the mean (the policy's ``dist``).
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
        return self._mean(self.mlp(obs))

    def _mean(self, raw: Tensor) -> Tensor:
        return self.low + (self.high - self.low) / 2 * (torch.tanh(raw) + 1)

    def act(
        self, obs: Tensor, legal_mask: Tensor | None, generator: torch.Generator | None = None
    ) -> PolicyOutput:
        """A reparameterized sample a = μ(s) + σ ε as the action vector."""
        acts = mlp_forward(self.mlp, obs)
        mean = self._mean(acts[-1])
        noise = torch.randn(mean.shape, generator=generator, device=mean.device)
        action = mean + self.log_std.exp() * noise
        return PolicyOutput(acts, mean, action, self.log_prob(mean, action), noise)

    def log_prob(self, mean: Tensor, action: Tensor) -> Tensor:
        """Gaussian log-density log π(a|s), summed over action dimensions."""
        log_std = self.log_std.expand_as(mean)
        z = (action - mean) * torch.exp(-log_std)
        return (-0.5 * z.square() - log_std - 0.5 * math.log(2 * math.pi)).sum(dim=-1)

    def supervised_loss(self, mean: Tensor, expert_action: Tensor) -> Tensor:
        """Per-sample squared error between the policy's mean action and the expert's."""
        return (mean - expert_action).square().sum(dim=-1)

    def backward(
        self, out: PolicyOutput, grad_action: Tensor, expert_action: Tensor, alpha: float
    ) -> list[Tensor]:
        """Gradients of (1−α)·mean(−f(s, a) + log π(a|s)) + α·mean(MSE), a = μ + σε.

        ``grad_action`` is the first term's gradient through f: −(1−α)/B · ∂f/∂a.
        With a reparameterized, log π(a|s) = Σ(−ε²/2 − log σ) − const: it moves only log σ.
        """
        batch = len(out.action)
        std = self.log_std.exp()
        grad_mean = grad_action + (2 * alpha / batch) * (out.dist - expert_action)
        grad_log_std = (grad_action * std * out.noise).sum(dim=0) - (1 - alpha)
        squash = (self.high - self.low) / 2 * (1 - torch.tanh(out.acts[-1]).square())
        grads = mlp_backward(self.mlp, out.acts, grad_mean * squash)[0]
        return [grad_log_std, *grads]  # parameters() lists a module's own before its children

    def sample_action(self, out: PolicyOutput, generator: torch.Generator | None = None) -> Tensor:
        """The reparameterized sample μ(s) + σε that :meth:`act` already drew."""
        return out.action

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
    k = _one_to(v.shape[-1], v.device, v.dtype)
    # The threshold is max_k (Σ_{i≤k} sorted_v_i − 1) / k: the sequence rises while
    # sorted_v_k is in the support and falls after, so its maximum is at the support's end.
    theta = ((sorted_v.cumsum(dim=-1) - 1) / k).amax(dim=-1, keepdim=True)
    return (v - theta).clamp_min(0)


@functools.cache
def _one_to(n: int, device: torch.device, dtype: torch.dtype) -> Tensor:
    """1, 2, ..., n, made once per size (this runs every training step)."""
    return torch.arange(1, n + 1, device=device, dtype=dtype)
