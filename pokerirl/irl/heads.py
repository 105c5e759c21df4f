"""What the trainer does with a policy, per action space: a :class:`PolicyHead`.

:class:`~pokerirl.irl.trainer.AdversarialTrainer` never asks whether actions are discrete;
its head knows. A head draws its own random numbers, makes the policy act at a batch's
states (:meth:`~PolicyHead.act`), says what the discriminator sees of the policy
(``disc_action``, then the noise) with log π of it and of the expert's action
(:meth:`~PolicyHead.discriminator_rows`), and gives the two policy losses:

* :class:`DiscreteHead`: π(·|s) over K actions; the discriminator sees a one-hot drawn from π
  (or π itself), noised and projected back onto the legal simplex; the adversarial loss is
  exact, Σ_k π_k (log π_k − g(s, e_k)); the supervised one the cross-entropy at a_E (or the
  authors' summed squares of π − a_E).
* :class:`GaussianHead`: a diagonal Gaussian, acting by the reparameterized sample
  μ(s) + σε; the discriminator sees that sample (or μ), noised and clipped to the box (or the
  authors' unclipped noise); the adversarial loss is the sample's log π − g; the supervised
  one ‖μ − a_E‖² (or the authors' summed squares of the sample − a_E).

Random numbers are typed: an epoch's are one :class:`EpochDraw`, a step's one
:class:`StepDraw`.

>>> import torch
>>> head = DiscreteHead(action_dim=3, device=torch.device("cpu"))
>>> log_pi = torch.log(torch.tensor([[[0.25, 0.25, 0.5]]]))  # (R, B, K)
>>> head.log_prob(DiscreteActs(log_pi=log_pi, probs=log_pi.exp()), torch.eye(3)[2]).exp()
tensor([[0.5000]])
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Generic, NamedTuple, TypeVar

import torch
from torch import Tensor

from pokerirl.irl.config import AIRLConfig, DiscAction, NoiseForm, SupervisedForm
from pokerirl.irl.losses import gaussian_log_prob, sample_one_hot, weighted_mean
from pokerirl.irl.nets import project_to_simplex
from pokerirl.irl.records import TrainingBatch
from pokerirl.irl.stacked import StackedNets
from pokerirl.irl.transitions import Transitions

# --------------------------------------------------------------------------- draws


@dataclass(frozen=True, slots=True)
class StepDraw:
    """One step's random numbers, each with the runs first, (R, B, ...).

    ``act``: the head's own (:meth:`PolicyHead.draw`); ``noise`` and ``sigma``: ε (R, B, k)
    and σ per row (R, B) of the discriminator's noise, None without noise."""

    act: Tensor | None
    noise: Tensor | None
    sigma: Tensor | None


@dataclass(frozen=True, slots=True)
class EpochDraw:
    """An epoch's random numbers: ``perm`` (steps, R, B), the rows of each step's batch;
    the others as in :class:`StepDraw`, with the steps first."""

    perm: Tensor
    act: Tensor | None
    noise: Tensor | None
    sigma: Tensor | None

    def at(self, step: int) -> StepDraw:
        return StepDraw(
            act=None if self.act is None else self.act[step],
            noise=None if self.noise is None else self.noise[step],
            sigma=None if self.sigma is None else self.sigma[step],
        )


class PolicyRows(NamedTuple):
    """What the discriminator sees of the policy at a batch's states, (R, B, k), with
    log π (R, B) of the expert's action and of that action."""

    action: Tensor
    log_pi_expert: Tensor
    log_pi_policy: Tensor


# --------------------------------------------------------------------------- heads

Acts = TypeVar("Acts")  # what a head's policy did at a batch's states


class PolicyHead(ABC, Generic[Acts]):
    """The trainer's per-action-space logic (the module docstring lists it)."""

    @abstractmethod
    def draw(
        self, generator: torch.Generator, steps: int, batch: int, *, adversarial: bool
    ) -> Tensor | None:
        """This head's random numbers for an epoch, (steps, B, ...), from ``generator``."""

    @abstractmethod
    def act(self, policies: StackedNets, batch: TrainingBatch, draw: StepDraw) -> Acts:
        """The policies at ``batch``'s states, with autograd's graph (the policy loss needs it)."""

    @abstractmethod
    def log_prob(self, acts: Acts, actions: Tensor) -> Tensor:
        """log π (R, B) of action vectors (R, B, k)."""

    @abstractmethod
    def discriminator_rows(self, acts: Acts, batch: TrainingBatch, draw: StepDraw) -> PolicyRows:
        """What the discriminator sees of the policy (detached), noised when ``draw`` has
        noise. The trainer calls it without autograd."""

    @abstractmethod
    def supervised_loss(self, acts: Acts, batch: TrainingBatch) -> Tensor:
        """The supervised term (R,): how far the policy is from the expert's actions."""

    @abstractmethod
    def adversarial_loss(self, acts: Acts, batch: TrainingBatch, rewards: StackedNets) -> Tensor:
        """E_π[log π − g] (R,), g the rewards' action-dependent part (called without s')."""


@dataclass(frozen=True, slots=True)
class DiscreteActs:
    log_pi: Tensor  # (R, B, K), illegal actions masked
    probs: Tensor


@dataclass(frozen=True, kw_only=True)
class DiscreteHead(PolicyHead[DiscreteActs]):
    """π(·|s) over ``action_dim`` actions (policies called ``policy(obs, legal_mask)``)."""

    action_dim: int
    device: torch.device
    disc_action: DiscAction = DiscAction.SAMPLE
    supervised_form: SupervisedForm = SupervisedForm.MEAN_MSE
    each_action: Tensor = field(init=False, repr=False)  # (K, 1, K): every one-hot, over B

    def __post_init__(self) -> None:
        eye = torch.eye(self.action_dim, device=self.device)
        object.__setattr__(self, "each_action", eye[:, None, :])

    def draw(
        self, generator: torch.Generator, steps: int, batch: int, *, adversarial: bool
    ) -> Tensor | None:
        if not adversarial:  # behaviour cloning draws its shuffles only
            return None
        return torch.rand(steps, batch, generator=generator, device=self.device)

    def act(self, policies: StackedNets, batch: TrainingBatch, draw: StepDraw) -> DiscreteActs:
        log_pi = policies(batch.obs, batch.mask)
        return DiscreteActs(log_pi=log_pi, probs=log_pi.exp())

    def log_prob(self, acts: DiscreteActs, actions: Tensor) -> Tensor:
        return (actions * acts.log_pi).sum(-1)  # exact on one-hots

    def seen(self, probs: Tensor, mask: Tensor | None, draw: StepDraw) -> Tensor:
        """A one-hot drawn from π (or π), plus noise projected onto the legal simplex."""
        if self.disc_action == DiscAction.SAMPLE:
            assert draw.act is not None  # drawn when adversarial
            seen = sample_one_hot(probs, draw.act)
        else:
            seen = probs
        if draw.noise is not None and draw.sigma is not None:
            seen = project_to_simplex(seen + draw.sigma[..., None] * draw.noise, mask)
        return seen

    def discriminator_rows(
        self, acts: DiscreteActs, batch: TrainingBatch, draw: StepDraw
    ) -> PolicyRows:
        seen = self.seen(acts.probs.detach(), batch.mask, draw)
        return PolicyRows(seen, self.log_prob(acts, batch.expert), self.log_prob(acts, seen))

    def supervised_loss(self, acts: DiscreteActs, batch: TrainingBatch) -> Tensor:
        if self.supervised_form == SupervisedForm.SUM_MSE:
            # The authors': mse_loss(π's probabilities, one-hot a_E, reduction="sum").
            return _summed((acts.probs - batch.expert).square(), batch.weights)
        return weighted_mean(-self.log_prob(acts, batch.expert), batch.weights)

    def adversarial_loss(
        self, acts: DiscreteActs, batch: TrainingBatch, rewards: StackedNets
    ) -> Tensor:
        # Exact over the K actions: Σ_k π_k (log π_k − g(s, e_k)).
        with torch.no_grad():
            g = rewards(batch.obs[:, None], self.each_action, shared=(False, True))
            g = g.transpose(1, 2)
        return weighted_mean((acts.probs * (acts.log_pi - g)).sum(-1), batch.weights)


@dataclass(frozen=True, slots=True)
class GaussianActs:
    mean: Tensor  # (R, B, k)
    log_std: Tensor  # clamped
    sample: Tensor  # μ + σε, reparameterized


@dataclass(frozen=True, kw_only=True)
class GaussianHead(PolicyHead[GaussianActs]):
    """A diagonal Gaussian π in the box [low, high] (policies called ``policy(obs)`` →
    (mean, log σ); log σ clamped to [log_std_min, log_std_max] here)."""

    low: Tensor  # (k,)
    high: Tensor
    log_std_min: float = -20.0
    log_std_max: float = 2.0
    disc_action: DiscAction = DiscAction.SAMPLE
    noise_form: NoiseForm = NoiseForm.OURS
    supervised_form: SupervisedForm = SupervisedForm.MEAN_MSE

    def draw(
        self, generator: torch.Generator, steps: int, batch: int, *, adversarial: bool
    ) -> Tensor | None:
        width = len(self.low)
        return torch.randn(steps, batch, width, generator=generator, device=self.low.device)

    def act(self, policies: StackedNets, batch: TrainingBatch, draw: StepDraw) -> GaussianActs:
        assert draw.act is not None  # drawn every epoch
        mean, log_std = policies(batch.obs)
        log_std = log_std.clamp(self.log_std_min, self.log_std_max)
        return GaussianActs(mean=mean, log_std=log_std, sample=mean + log_std.exp() * draw.act)

    def log_prob(self, acts: GaussianActs, actions: Tensor) -> Tensor:
        return gaussian_log_prob(actions, acts.mean, acts.log_std)

    def discriminator_rows(
        self, acts: GaussianActs, batch: TrainingBatch, draw: StepDraw
    ) -> PolicyRows:
        clean = (acts.sample if self.disc_action == DiscAction.SAMPLE else acts.mean).detach()
        if draw.noise is None or draw.sigma is None:
            seen = clean
        elif self.noise_form == NoiseForm.AUTHORS:
            # σ in units of high, no clipping, log π of the clean sample.
            seen = clean + draw.sigma[..., None] * self.high * draw.noise
            return PolicyRows(seen, self.log_prob(acts, batch.expert), self.log_prob(acts, clean))
        else:
            noise = draw.sigma[..., None] * (self.high - self.low) * draw.noise
            seen = torch.maximum(torch.minimum(clean + noise, self.high), self.low)
        return PolicyRows(seen, self.log_prob(acts, batch.expert), self.log_prob(acts, seen))

    def supervised_loss(self, acts: GaussianActs, batch: TrainingBatch) -> Tensor:
        if self.supervised_form == SupervisedForm.SUM_MSE:  # the authors': summed
            return _summed((acts.sample - batch.expert).square(), batch.weights)
        return weighted_mean((acts.mean - batch.expert).square().sum(-1), batch.weights)

    def adversarial_loss(
        self, acts: GaussianActs, batch: TrainingBatch, rewards: StackedNets
    ) -> Tensor:
        # The reparameterized sample's, with the gradient through g(s, sample).
        g = rewards(batch.obs[:, None], acts.sample[:, None])[:, 0]
        log_pi = self.log_prob(acts, acts.sample)
        return weighted_mean(log_pi - g, batch.weights)


def head_for(data: Transitions, config: AIRLConfig, device: torch.device) -> PolicyHead:
    """The head of ``data``'s action space with ``config``'s forms."""
    if data.discrete:
        return DiscreteHead(
            action_dim=data.action_dim,
            device=device,
            disc_action=config.disc_action,
            supervised_form=config.supervised_form,
        )
    return GaussianHead(
        low=torch.tensor(data.action_low, device=device),
        high=torch.tensor(data.action_high, device=device),
        log_std_min=config.log_std_min,
        log_std_max=config.log_std_max,
        disc_action=config.disc_action,
        noise_form=config.noise_form,
        supervised_form=config.supervised_form,
    )


def _summed(squares: Tensor, weights: Tensor | None) -> Tensor:
    """(..., B, k) squared errors summed over the batch and k (the authors'
    ``reduction="sum"``); with ``weights``, the weighted mean over the batch times B, so
    that the scale stays a sum's."""
    if weights is None:
        return squares.sum((-2, -1))
    return weighted_mean(squares.sum(-1), weights) * squares.shape[-2]
