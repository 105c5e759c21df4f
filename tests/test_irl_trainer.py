"""The trainer's open surface: a user's Discriminator or PolicyHead, plugged into
:class:`AdversarialTrainer`, is the one that trains (on a tiny table)."""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor

from pokerirl.irl import (
    AdversarialTrainer,
    AIRLConfig,
    DiscreteHead,
    Discriminator,
    PolicyHead,
    Transitions,
    default_nets,
)
from pokerirl.irl.heads import DiscreteActs
from pokerirl.irl.records import TrainingBatch


def _data() -> Transitions:
    obs = np.random.default_rng(0).random((192, 4)).astype(np.float32)
    return Transitions.from_arrays(obs, (obs[:, 0] > 0.5).astype(np.int64), groups=np.arange(192))


def _params(*modules: torch.nn.Module) -> list[Tensor]:
    return [p.detach().clone() for m in modules for p in m.parameters()]


def _train(
    config: AIRLConfig,
    *,
    discriminator: Discriminator | None = None,
    head: PolicyHead | None = None,
    adversarial: bool = True,
    fast_path: bool = True,
) -> tuple[list[Tensor], list[Tensor], str]:
    data = _data()
    reward, policy = default_nets(data, config)
    before = _params(policy)
    many = AdversarialTrainer(
        demonstrations=data,
        validation=data,
        config=config,
        seeds=[config.seed],
        rewards=[reward],
        policies=[policy],
        discriminator=discriminator,
        head=head,
        adversarial=adversarial,
        fast_path=fast_path,
    ).train(progress=False)
    return before, _params(reward, policy), many.runs[0].gradients


class MyAIRL(Discriminator):
    """AIRL's logit, written by a user (no config or enum entry needed)."""

    def logits(self, f: Tensor, log_pi: Tensor) -> Tensor:
        return f - log_pi


class Shifted(Discriminator):
    """AIRL's logit plus one: another discriminator (still d logit / d f = 1)."""

    def logits(self, f: Tensor, log_pi: Tensor) -> Tensor:
        return f - log_pi + 1


def test_a_users_discriminator_is_the_one_that_trains() -> None:
    config = AIRLConfig.for_algo("airl", epochs=2, batch_size=64)
    _, builtin, gradients = _train(config, fast_path=False)
    assert gradients == "autograd"
    for fast_path in (True, False):  # a user's discriminator always runs on autograd
        _, mine, mine_gradients = _train(config, discriminator=MyAIRL(), fast_path=fast_path)
        _, shifted, _ = _train(config, discriminator=Shifted(), fast_path=fast_path)
        assert mine_gradients == "autograd"
        assert all(torch.equal(a, b) for a, b in zip(builtin, mine, strict=True))
        assert not all(torch.equal(a, b) for a, b in zip(builtin, shifted, strict=True))
    assert _train(config, fast_path=True)[2] == "hand-derived"  # the built-in's default


class NoSupervision(DiscreteHead):
    """A head whose supervised term has no gradient."""

    def supervised_loss(self, acts: DiscreteActs, batch: TrainingBatch) -> Tensor:
        return 0 * super().supervised_loss(acts, batch)


def test_a_users_policy_head_is_the_one_that_trains() -> None:
    # Behaviour cloning (α = 1, no discriminator): the policy moves by its supervised term only.
    config = AIRLConfig.for_algo("hairl", epochs=2, batch_size=64, alpha=1.0)
    head = NoSupervision(action_dim=2, device=torch.device("cpu"))
    before, after, gradients = _train(config, head=head, adversarial=False)
    assert gradients == "autograd"  # the hand-derived step knows only the built-in head
    assert all(torch.equal(a, b) for a, b in zip(before, after[-len(before) :], strict=True))
    before, after, _ = _train(config, adversarial=False)
    assert not torch.equal(before[0], after[-len(before)])
