"""Hand-derived gradients for one architecture: the default poker nets, one run.

Autograd is the reference; this path exists only because, for nets this small on one CPU
core, building and walking autograd's graph costs more than the arithmetic (see
``benchmarks/train.py``). It covers exactly: a :class:`StateActionReward` and a
:class:`DiscretePolicy` whose layers are Linear and ReLU only (no layer norm, no other
activation), one run, discrete actions. :func:`supports` says whether a pair is covered;
the functions below raise ``ValueError`` for anything else. ``tests/test_irl_fast.py``
compares every gradient here with autograd on the documented losses.
:class:`HandDerivedStep` is the trainer's step made of them, which
:class:`~pokerirl.irl.trainer.AdversarialTrainer` uses in place of its own where
:func:`covers` says it computes the same thing.

The gradients are written for the built-in strategies only, by exact type: the two
discriminators (:data:`DERIVED_FOR`, whose logit has d logit / d f = 1) and the
:class:`~pokerirl.irl.heads.DiscreteHead` with its mean cross-entropy term. A user's
discriminator or head, even a subclass of a built-in, runs on autograd, which differentiates
whatever it defines: the losses are written once, in :mod:`~pokerirl.irl.losses` and the
heads, and this path cannot silently disagree with them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import torch
from torch import Tensor, nn

from pokerirl.errors import ConfigError
from pokerirl.irl.config import SupervisedForm
from pokerirl.irl.discriminators import AIRL, AIRLDiscriminator, Discriminator, GAILDiscriminator
from pokerirl.irl.heads import DiscreteHead, PolicyHead, StepDraw
from pokerirl.irl.losses import weighted_mean
from pokerirl.irl.nets import MASKED_LOGIT, DiscretePolicy, StateActionReward
from pokerirl.irl.optim import FlatAdam
from pokerirl.irl.records import StepLosses, TrainingBatch, pack_step


def _plain_relu_mlp(mlp: nn.Sequential) -> bool:
    kinds = [type(layer) for layer in mlp]
    return all(k in (nn.Linear, nn.ReLU) for k in kinds) and kinds[-1] is nn.Linear


def supports(reward: nn.Module, policy: nn.Module) -> bool:
    """True for the one architecture this path covers (see the module docstring)."""
    return (
        type(reward) is StateActionReward
        and type(policy) is DiscretePolicy
        and type(reward.first_norm) is nn.Identity
        and type(reward.first_activation) is nn.ReLU
        and _plain_relu_mlp(reward.head)
        and _plain_relu_mlp(policy.mlp)
    )


# The discriminators whose gradient :func:`discriminator_grad` writes out: their logits are
# f − log π and f. Exact types: a subclass may override ``logits``.
DERIVED_FOR: frozenset[type[Discriminator]] = frozenset({AIRLDiscriminator, GAILDiscriminator})


def covers(
    *, reward: nn.Module, policy: nn.Module, head: PolicyHead, discriminator: Discriminator
) -> bool:
    """True when :class:`HandDerivedStep` computes what the trainer's autograd step does for
    these nets and strategies: :func:`supports` the nets, the built-in
    :class:`~pokerirl.irl.heads.DiscreteHead` with its mean cross-entropy supervised term,
    and a discriminator in :data:`DERIVED_FOR`.

    >>> from pokerirl.irl import NetSpec, build_nets
    >>> nets = build_nets(NetSpec(), obs_dim=5, action_dim=4, discrete=True)
    >>> head = DiscreteHead(action_dim=4, device=torch.device("cpu"))
    >>> covers(reward=nets[0], policy=nets[1], head=head, discriminator=AIRL)
    True
    >>> class Mine(AIRLDiscriminator):  # a user's logit: autograd differentiates it
    ...     def logits(self, f, log_pi): return 3 * torch.tanh(f) - log_pi
    >>> covers(reward=nets[0], policy=nets[1], head=head, discriminator=Mine())
    False
    """
    return (
        supports(reward, policy)
        and type(head) is DiscreteHead
        and head.supervised_form == SupervisedForm.MEAN_MSE  # the term policy_backward writes
        and type(discriminator) in DERIVED_FOR
    )


def check(reward: nn.Module, policy: nn.Module) -> None:
    """Raise a clear ``ValueError`` unless :func:`supports` the pair."""
    if not supports(reward, policy):
        raise ConfigError(
            "the hand-derived gradient path covers only StateActionReward and DiscretePolicy "
            "with ReLU and no layer norm; use autograd (fast_path=False) for "
            f"{type(reward).__name__} / {type(policy).__name__} as configured"
        )


def _linears(mlp: nn.Sequential) -> list[nn.Linear]:
    return [layer for layer in mlp if isinstance(layer, nn.Linear)]


def mlp_forward(mlp: nn.Sequential, x: Tensor) -> list[Tensor]:
    """The input of every linear layer (hidden ones after ReLU), then the output."""
    linears = _linears(mlp)
    acts = [x]
    for i, layer in enumerate(linears):
        y = torch.addmm(layer.bias, acts[-1], layer.weight.T)
        acts.append(y.relu_() if i < len(linears) - 1 else y)
    return acts


def mlp_backward(
    mlp: nn.Sequential, acts: list[Tensor], grad_out: Tensor, *, input_grad: bool = False
) -> tuple[list[Tensor], Tensor | None]:
    """Parameter gradients in ``mlp.parameters()`` order, and dL/d input if asked."""
    linears = _linears(mlp)
    grads: list[Tensor] = []
    grad = grad_out
    for i in reversed(range(len(linears))):
        grads += [grad.sum(dim=0), grad.T @ acts[i]]  # bias, weight (reversed below)
        if i == 0 and not input_grad:
            return grads[::-1], None
        grad = grad @ linears[i].weight
        if i > 0:
            grad = torch.ops.aten.threshold_backward(grad, acts[i], 0.0)
    return grads[::-1], grad


class RewardCache(NamedTuple):
    obs: Tensor  # (B, d)
    actions: Tensor  # (M·B, K)
    hidden: Tensor  # (M·B, H) first hidden layer after ReLU
    head_acts: list[Tensor]


def reward_forward(reward: StateActionReward, obs: Tensor, actions: Tensor) -> RewardCache:
    """f for (B, d) states and (M, B or 1, K) action vectors: ``head_acts[-1]`` is (M·B, 1)."""
    features = torch.addmm(reward.obs_layer.bias, obs, reward.obs_layer.weight.T)
    hidden = (actions @ reward.action_layer.weight.T + features).relu_()  # (M, B, H)
    flat = actions.expand(*hidden.shape[:2], actions.shape[-1]).reshape(-1, actions.shape[-1])
    hidden = hidden.view(-1, hidden.shape[-1])
    return RewardCache(obs, flat, hidden, mlp_forward(reward.head, hidden))


def reward_backward(reward: StateActionReward, cache: RewardCache, grad_f: Tensor) -> list[Tensor]:
    """Parameter gradients (``reward.parameters()`` order) for dL/df ``grad_f`` (M·B,)."""
    head_grads, grad_hidden = mlp_backward(
        reward.head, cache.head_acts, grad_f[:, None], input_grad=True
    )
    assert grad_hidden is not None
    grad_pre = torch.ops.aten.threshold_backward(grad_hidden, cache.hidden, 0.0)
    batch = len(cache.obs)
    grad_features = grad_pre.view(-1, batch, grad_pre.shape[1]).sum(dim=0)
    return [
        grad_features.T @ cache.obs,
        grad_features.sum(dim=0),
        grad_pre.T @ cache.actions,
        *head_grads,
    ]


def discriminator_grad(
    f: Tensor,
    log_pi: Tensor,
    *,
    beta: float,
    env_reward: Tensor | None,
    weights: Tensor | None = None,
    discriminator: Discriminator = AIRL,
) -> Tensor:
    """dL/df of ``discriminator_loss`` for f = (expert rows, then policy rows), both (B,).

    With D = σ(logit), the logit's derivative in f being 1 (AIRL's f − log π, GAIL's f):
    d/df of −log D is D − 1, of −log(1 − D) is D. With row ``weights`` (B,) each mean is
    Σ w·(...) / Σ w, so row i's terms scale by w_i / Σ w (its policy row is drawn at the
    same state and shares its weight). Any other ``discriminator`` raises ``ConfigError``.
    """
    if type(discriminator) not in DERIVED_FOR:
        raise ConfigError(
            f"the hand-derived discriminator gradient is written for AIRL's and GAIL's logits "
            f"only, not {type(discriminator).__name__}'s; train it with autograd"
        )
    batch = len(f) // 2
    grad = torch.sigmoid(discriminator.logits(f, log_pi))
    grad[:batch] -= 1
    if weights is not None:
        scale = weights / weights.sum()  # (B,): replaces 1 / B
        grad *= torch.cat((scale, scale))
        if env_reward is None:
            return grad
        grad *= 1 - beta
        grad[:batch] += (2 * beta) * scale * (f[:batch] - env_reward)
        return grad
    if env_reward is None:
        return grad / batch
    grad *= (1 - beta) / batch
    grad[:batch] += (2 * beta / batch) * (f[:batch] - env_reward)
    return grad


def policy_backward(
    policy: DiscretePolicy,
    acts: list[Tensor],
    log_probs: Tensor,
    g: Tensor,
    expert: Tensor,
    alpha: float,
    *,
    weights: Tensor | None = None,
) -> list[Tensor]:
    """Gradients of (1−α)·mean Σ_k π_k (log π_k − g_k) + α·mean CE(π, a_E).

    d/d logits of Σ π·h with h = (1−α)/B·(log π − g) is π ⊙ (h − Σ π h) (the entropy's "+1"
    cancels, Σ π = 1); the cross-entropy adds α/B·(π − a_E). Masked logits get zero. With
    row ``weights`` (B,), the means are weighted: 1/B becomes w_i / Σ w on row i.
    """
    probs = log_probs.exp()
    batch = len(probs)
    if weights is not None:
        scale = (weights / weights.sum())[:, None]  # (B, 1): replaces 1 / B
        h = (log_probs - g) * ((1 - alpha) * scale)
        grad_logits = probs * (h - (probs * h).sum(dim=-1, keepdim=True))
        grad_logits += (probs - expert) * (alpha * scale)
        return mlp_backward(policy.mlp, acts, grad_logits)[0]
    h = (log_probs - g) * ((1 - alpha) / batch)
    grad_logits = probs * (h - (probs * h).sum(dim=-1, keepdim=True))
    grad_logits.add_(probs - expert, alpha=alpha / batch)
    return mlp_backward(policy.mlp, acts, grad_logits)[0]


@dataclass(frozen=True, kw_only=True)
class HandDerivedStep:
    """:meth:`AdversarialTrainer.step <pokerirl.irl.trainer.AdversarialTrainer.step>` for
    one run of the covered nets and strategies (:func:`covers`, checked here too), with the
    gradients above: the same draws, the same discriminator and policy updates, the same
    (1, 4B + 3) row."""

    reward: StateActionReward
    policy: DiscretePolicy
    head: DiscreteHead
    discriminator: Discriminator
    reward_opt: FlatAdam
    policy_opt: FlatAdam
    adversarial: bool
    alpha: float
    beta: float

    def __post_init__(self) -> None:
        if not covers(reward=self.reward, policy=self.policy, head=self.head,
                      discriminator=self.discriminator):  # fmt: skip
            raise ConfigError(
                "the hand-derived step covers only the built-in discrete head and the AIRL or "
                "GAIL discriminator on plain ReLU nets; use the trainer's autograd step"
            )

    @torch.no_grad()
    def __call__(self, batch: TrainingBatch, draw: StepDraw) -> Tensor:
        one = batch.at(0)  # the one run
        obs, expert, mask, env, weights = one.obs, one.expert, one.mask, one.env, one.weights
        acts = mlp_forward(self.policy.mlp, obs)
        logits = acts[-1] if mask is None else acts[-1].masked_fill(~mask, MASKED_LOGIT)
        log_pi = torch.log_softmax(logits, dim=-1)
        probs = log_pi.exp()
        if self.adversarial:
            seen = self.head.seen(probs[None], None if mask is None else mask[None], draw)[0]
            lp = torch.cat(((expert * log_pi).sum(-1), (seen * log_pi).sum(-1)))
            cache = reward_forward(self.reward, obs, torch.stack((expert, seen)))
            f = cache.head_acts[-1].view(-1)
            grad_f = discriminator_grad(f, lp, beta=self.beta, env_reward=env, weights=weights,
                                        discriminator=self.discriminator)  # fmt: skip
            self.reward_opt.set_grad(reward_backward(self.reward, cache, grad_f))
            self.reward_opt.step()
            disc_record = torch.cat((f, lp))
        else:
            disc_record = obs.new_zeros(4 * len(obs))
        if self.alpha < 1:
            each = reward_forward(self.reward, obs, self.head.each_action).head_acts[-1]
            g = each.view(-1, len(obs)).T
        else:
            g = torch.zeros_like(log_pi)
        self.policy_opt.set_grad(
            policy_backward(self.policy, acts, log_pi, g, expert, self.alpha, weights=weights)
        )
        self.policy_opt.step()
        supervised = weighted_mean(-(expert * log_pi).sum(-1), weights)
        adversarial = (
            weighted_mean((probs * (log_pi - g)).sum(-1), weights) if self.alpha < 1 else g[0, 0]
        )
        p_loss = (1 - self.alpha) * adversarial + self.alpha * supervised
        return pack_step(disc_record, StepLosses(p_loss, adversarial, supervised))[None]
