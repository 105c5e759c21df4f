"""Default networks for AIRL: reward nets f(s, a) and policies π(a|s), plain ``nn.Module``s.

The trainer takes any modules with these call signatures; :func:`build_nets` makes the
defaults from a :class:`NetSpec` (hidden sizes, activation, optional layer norm, reward family).
Gradients are autograd's (plus a tested hand-derived path for the default poker nets only,
:mod:`pokerirl.irl.fast`).

* A **reward** module is called ``reward(obs, action, next_obs, done) -> f``; without
  ``next_obs`` and ``done`` it returns the transferable reward g (f for ``state_action``).
  ``obs`` is (..., B, d); ``action`` is (..., M, B, k): M action vectors per state (one-hots
  or simplex points for discrete actions, values for continuous ones), broadcast against
  ``obs``; the result is (..., M, B).
  - :class:`StateActionReward`: f(s, a), the paper's form; g = f.
  - :class:`ShapedReward`: f = g(s, a) + γ·(1 − done)·h(s') − h(s), AIRL's disentangled form.
* A **discrete policy** is called ``policy(obs, legal_mask) -> log π`` (B, K), illegal actions
  at log-probability :data:`MASKED_LOGIT`-ish (exp 0). A **Gaussian policy** is called
  ``policy(obs) -> (mean, log_std)``, both (B, k).

>>> spec = NetSpec(reward_hidden=(8,), policy_hidden=(8,), activation="tanh", layer_norm=True)
>>> reward, policy = build_nets(spec, obs_dim=3, action_dim=2, discrete=True)
>>> reward(torch.zeros(5, 3), torch.ones(4, 5, 2)).shape   # 4 action vectors per state
torch.Size([4, 5])
>>> torch.allclose(policy(torch.zeros(5, 3), None).exp().sum(dim=1), torch.ones(5))
True
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from pokerirl.errors import ConfigError
from pokerirl.irl.config import Activation, AIRLConfig, RewardFamily

# Finite stand-in for log(0) on illegal actions: 0 * MASKED_LOGIT is 0, 0 * -inf would be NaN.
MASKED_LOGIT = -1e9
ACTIVATIONS: dict[str, type[nn.Module]] = {
    Activation.RELU: nn.ReLU,
    Activation.TANH: nn.Tanh,
    Activation.LEAKY_RELU: nn.LeakyReLU,
}
REWARD_FAMILIES: tuple[str, ...] = tuple(RewardFamily)


@dataclass(frozen=True, kw_only=True)
class NetSpec:
    """What the default nets look like (the TOML keys of the same names)."""

    reward_hidden: tuple[int, ...] = (64,)
    policy_hidden: tuple[int, ...] = (64,)
    activation: str = "relu"
    layer_norm: bool = False
    reward_family: RewardFamily = RewardFamily.STATE_ACTION
    gamma: float = 0.99  # discount of the shaped family

    def __post_init__(self) -> None:
        if self.activation not in ACTIVATIONS:
            raise ConfigError(f"activation must be one of {', '.join(ACTIVATIONS)}")
        if self.reward_family not in REWARD_FAMILIES:
            raise ConfigError(f"reward_family must be one of {', '.join(REWARD_FAMILIES)}")
        object.__setattr__(self, "reward_family", RewardFamily(self.reward_family))
        if not self.reward_hidden or min(self.reward_hidden + self.policy_hidden, default=1) < 1:
            raise ConfigError("hidden widths must be >= 1, with at least one reward layer")

    @classmethod
    def of(cls, config: AIRLConfig) -> NetSpec:
        """The nets ``config`` asks for (its net fields). Here, not a method of the torch-free
        config, so that config never imports the nets (no import loop)."""
        return cls(
            reward_hidden=config.reward_hidden,
            policy_hidden=config.policy_hidden,
            activation=config.activation,
            layer_norm=config.layer_norm,
            reward_family=config.reward_family,
            gamma=config.gamma,
        )


def build_mlp(
    in_dim: int,
    hidden: Sequence[int],
    out_dim: int,
    *,
    activation: str = "relu",
    layer_norm: bool = False,
) -> nn.Sequential:
    """``in_dim -> hidden... -> out_dim``: Linear, [LayerNorm], activation per hidden layer.

    Without layer norm and with ReLU the layout (and the state_dict names) is that of the
    format-1 runs, which therefore still load.
    """
    layers: list[nn.Module] = []
    for width in hidden:
        layers.append(nn.Linear(in_dim, width))
        if layer_norm:
            layers.append(nn.LayerNorm(width))
        layers.append(ACTIVATIONS[activation]())
        in_dim = width
    layers.append(nn.Linear(in_dim, out_dim))
    return nn.Sequential(*layers)


class _RewardMethods:
    """What makes a reward module a :class:`pokerirl.irl.reward.RewardNet`: g and numpy."""

    def transferable(self, obs: Tensor, action: Tensor) -> Tensor:
        """g(s, a): f without the shaping terms (f itself for ``state_action``)."""
        return self(obs, action)  # type: ignore[operator]

    def predict(
        self,
        obs: np.ndarray,
        action: np.ndarray,
        next_obs: np.ndarray | None = None,
        done: np.ndarray | None = None,
    ) -> np.ndarray:
        """float32 rewards of numpy inputs: f with ``next_obs`` and ``done``, else g."""
        extra: tuple[Tensor, ...] = ()
        if next_obs is not None and done is not None:
            extra = (torch.as_tensor(next_obs).float(), torch.as_tensor(done).bool())
        with torch.inference_mode():
            out = self(torch.as_tensor(obs).float(), torch.as_tensor(action).float(), *extra)  # type: ignore[operator]
        return out.numpy().astype(np.float32, copy=False)


class StateActionReward(_RewardMethods, nn.Module):
    """f(s, a): an MLP over [s, a], giving a scalar.

    The first layer is two maps, ``W_s s + b`` and ``W_a a`` (the same as one layer on the
    concatenation), so that several action vectors per state share the state half.
    """

    def __init__(
        self,
        *,
        obs_dim: int,
        action_dim: int,
        hidden: Sequence[int] = (64,),
        activation: str = "relu",
        layer_norm: bool = False,
    ) -> None:
        super().__init__()
        if not hidden:
            raise ValueError("a reward net needs at least one hidden layer")
        self.obs_dim, self.action_dim = obs_dim, action_dim
        self.obs_layer = nn.Linear(obs_dim, hidden[0])
        self.action_layer = nn.Linear(action_dim, hidden[0], bias=False)
        self.first_norm = nn.LayerNorm(hidden[0]) if layer_norm else nn.Identity()
        self.first_activation = ACTIVATIONS[activation]()
        self.head = build_mlp(
            hidden[0], hidden[1:], 1, activation=activation, layer_norm=layer_norm
        )

    def forward(
        self,
        obs: Tensor,
        action: Tensor,
        next_obs: Tensor | None = None,
        done: Tensor | None = None,
    ) -> Tensor:
        pre = self.obs_layer(obs) + self.action_layer(action)  # broadcast over action rows
        hidden = self.first_activation(self.first_norm(pre))
        return self.head(hidden).squeeze(-1)


class ShapedReward(_RewardMethods, nn.Module):
    """f(s, a, s') = g(s, a) + γ·(1 − done)·h(s') − h(s), AIRL's disentangled reward.

    g is a :class:`StateActionReward`, h a state-only MLP. Called without s' and done, it is g.
    """

    def __init__(
        self,
        *,
        obs_dim: int,
        action_dim: int,
        hidden: Sequence[int] = (64,),
        activation: str = "relu",
        layer_norm: bool = False,
        gamma: float = 0.99,
    ) -> None:
        super().__init__()
        self.obs_dim, self.action_dim, self.gamma = obs_dim, action_dim, gamma
        self.g = StateActionReward(
            obs_dim=obs_dim,
            action_dim=action_dim,
            hidden=hidden,
            activation=activation,
            layer_norm=layer_norm,
        )
        self.h = build_mlp(obs_dim, hidden, 1, activation=activation, layer_norm=layer_norm)

    def forward(
        self,
        obs: Tensor,
        action: Tensor,
        next_obs: Tensor | None = None,
        done: Tensor | None = None,
    ) -> Tensor:
        if next_obs is None or done is None:
            return self.g(obs, action)
        shaping = self.gamma * (~done).float() * self.h(next_obs).squeeze(-1)
        return self.g(obs, action) + shaping - self.h(obs).squeeze(-1)


class DiscretePolicy(nn.Module):
    """Categorical π(a|s) over ``num_actions``; illegal actions get probability zero.

    ``forward`` returns masked log-probabilities.
    """

    def __init__(
        self,
        *,
        obs_dim: int,
        num_actions: int,
        hidden: Sequence[int] = (64,),
        activation: str = "relu",
        layer_norm: bool = False,
    ) -> None:
        super().__init__()
        self.obs_dim, self.action_dim = obs_dim, num_actions
        self.mlp = build_mlp(
            obs_dim, hidden, num_actions, activation=activation, layer_norm=layer_norm
        )

    def forward(self, obs: Tensor, legal_mask: Tensor | None = None) -> Tensor:
        logits = self.mlp(obs)
        if legal_mask is not None:
            logits = logits.masked_fill(~legal_mask, MASKED_LOGIT)
        return torch.log_softmax(logits, dim=-1)


class GaussianPolicy(nn.Module):
    """Diagonal Gaussian π(a|s) for actions in the box [low, high].

    The mean is squashed into the box with tanh; log σ is a free parameter per dimension.
    ``forward`` returns (mean, log σ), both (B, k).
    """

    def __init__(
        self,
        *,
        obs_dim: int,
        low: Sequence[float],
        high: Sequence[float],
        hidden: Sequence[int] = (64,),
        activation: str = "relu",
        layer_norm: bool = False,
    ) -> None:
        super().__init__()
        if len(low) != len(high) or any(h <= lo for lo, h in zip(low, high, strict=True)):
            raise ValueError("GaussianPolicy needs low < high in every action dimension")
        self.obs_dim, self.action_dim = obs_dim, len(low)
        self.mlp = build_mlp(
            obs_dim, hidden, self.action_dim, activation=activation, layer_norm=layer_norm
        )
        self.log_std = nn.Parameter(torch.full((self.action_dim,), -0.5))
        self.low: Tensor
        self.high: Tensor
        self.register_buffer("low", torch.tensor(low, dtype=torch.float32))
        self.register_buffer("high", torch.tensor(high, dtype=torch.float32))

    def forward(self, obs: Tensor, legal_mask: Tensor | None = None) -> tuple[Tensor, Tensor]:
        # unsqueeze(-2): broadcast over the batch, also when parameters carry a run dimension
        low, high = self.low.unsqueeze(-2), self.high.unsqueeze(-2)
        mean = low + (high - low) / 2 * (torch.tanh(self.mlp(obs)) + 1)
        return mean, self.log_std.unsqueeze(-2).expand_as(mean)


def build_nets(
    spec: NetSpec,
    *,
    obs_dim: int,
    action_dim: int,
    discrete: bool,
    low: Sequence[float] | None = None,
    high: Sequence[float] | None = None,
) -> tuple[nn.Module, nn.Module]:
    """The default (reward, policy) pair for ``spec`` and an action space.

    Initialized from torch's global generator: seed it first (``torch.manual_seed``).
    """
    style: dict[str, Any] = {"activation": spec.activation, "layer_norm": spec.layer_norm}
    reward: nn.Module
    if spec.reward_family == RewardFamily.SHAPED:
        reward = ShapedReward(
            obs_dim=obs_dim,
            action_dim=action_dim,
            hidden=spec.reward_hidden,
            gamma=spec.gamma,
            **style,
        )
    else:
        reward = StateActionReward(
            obs_dim=obs_dim, action_dim=action_dim, hidden=spec.reward_hidden, **style
        )
    policy: nn.Module
    if discrete:
        policy = DiscretePolicy(
            obs_dim=obs_dim, num_actions=action_dim, hidden=spec.policy_hidden, **style
        )
    else:
        if low is None or high is None:
            raise ValueError("a continuous action space needs its bounds low and high")
        policy = GaussianPolicy(
            obs_dim=obs_dim, low=low, high=high, hidden=spec.policy_hidden, **style
        )
    return reward, policy


def project_to_simplex(v: Tensor, mask: Tensor | None = None) -> Tensor:
    """Row-wise Euclidean projection onto the probability simplex (last dimension).

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
    k = torch.arange(1, v.shape[-1] + 1, device=v.device, dtype=v.dtype)
    # The threshold is max_k (Σ_{i≤k} sorted_v_i − 1) / k: the sequence rises while
    # sorted_v_k is in the support and falls after, so its maximum is at the support's end.
    theta = ((sorted_v.cumsum(dim=-1) - 1) / k).amax(dim=-1, keepdim=True)
    return (v - theta).clamp_min(0)


def obs_input_layers(module: nn.Module) -> list[nn.Linear]:
    """The Linear layers of a default net that read the observation directly.

    Raises ``TypeError`` for any other module: only the default nets' layouts are known.
    """
    if isinstance(module, StateActionReward):
        return [module.obs_layer]
    if isinstance(module, ShapedReward):
        return [module.g.obs_layer, module.h[0]]  # type: ignore[list-item]
    if isinstance(module, (DiscretePolicy, GaussianPolicy)):
        return [module.mlp[0]]  # type: ignore[list-item]
    raise TypeError(f"{type(module).__name__} is not one of the default nets")


@torch.no_grad()
def fold_obs_standardization(module: nn.Module, shift: Tensor, scale: Tensor) -> nn.Module:
    """Make a default net trained on ``(obs - shift) / scale`` take raw observations.

    Each first layer ``W z + b`` with ``z = (x - shift) / scale`` becomes
    ``(W / scale) x + (b - (W / scale) shift)``: the same function, so saved nets (and
    :func:`pokerirl.irl.load_reward`) need no extra preprocessing. In place; returns ``module``.

    >>> torch.manual_seed(0) and None
    >>> net = DiscretePolicy(obs_dim=2, num_actions=3, hidden=(4,))
    >>> x = torch.randn(5, 2); shift, scale = torch.tensor([1.0, -2.0]), torch.tensor([0.5, 3.0])
    >>> before = net((x - shift) / scale, None)
    >>> torch.allclose(fold_obs_standardization(net, shift, scale)(x, None), before, atol=1e-6)
    True
    """
    for layer in obs_input_layers(module):
        layer.weight.div_(scale)
        if layer.bias is not None:
            layer.bias.sub_(layer.weight @ shift)
    return module
