"""The discriminator's form: its logit log D − log(1 − D) from f(s, a) and log π(a|s).

The trainer (:mod:`pokerirl.irl.trainer`) asks a :class:`Discriminator` for logits wherever it
forms them: the discriminator's loss (:func:`~pokerirl.irl.losses.discriminator_loss`), its
hand-derived gradient (:mod:`~pokerirl.irl.fast`) and the epoch's accuracies. Everything
else (the nets, the data, the noise, the supervised term, the policy step) is shared, so
an algorithm's discriminator is one small class.

* :class:`AIRLDiscriminator`: D = exp f / (exp f + π), logit f − log π (Fu et al. 2018).
* :class:`GAILDiscriminator`: D = σ(f), logit f (Ho & Ermon 2016; the ``imitation``
  library's GAIL with a reward net).

Both policies minimize E_π[log π − g] (g: the reward's action-dependent part): AIRL's
−E_π[logit], and GAIL's maximum-entropy step on its logit (``docs/method.md`` says why).

>>> import math, torch
>>> f, log_pi = torch.zeros(1), torch.tensor([math.log(0.5)])
>>> round(AIRL.logits(f, log_pi).item(), 4), GAIL.logits(f, log_pi).item()  # log 2, 0
(0.6931, 0.0)
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

from torch import Tensor

from pokerirl.irl.config import DiscriminatorForm


class Discriminator(ABC):
    """How a row's logit log D − log(1 − D) comes from its reward f and its log π."""

    form: ClassVar[DiscriminatorForm]

    @abstractmethod
    def logits(self, f: Tensor, log_pi: Tensor) -> Tensor:
        """The logits of rows with rewards ``f`` and log-probabilities ``log_pi`` (one shape).

        The trainer differentiates it with autograd; its hand-derived step
        (:mod:`~pokerirl.irl.fast`) runs only for the built-in discriminators, by exact type.
        """


@dataclass(frozen=True)
class AIRLDiscriminator(Discriminator):
    """D = exp f / (exp f + π): the logit f − log π."""

    form: ClassVar[DiscriminatorForm] = DiscriminatorForm.AIRL

    def logits(self, f: Tensor, log_pi: Tensor) -> Tensor:
        return f - log_pi


@dataclass(frozen=True)
class GAILDiscriminator(Discriminator):
    """D = σ(f): the logit is f alone; π does not enter."""

    form: ClassVar[DiscriminatorForm] = DiscriminatorForm.GAIL

    def logits(self, f: Tensor, log_pi: Tensor) -> Tensor:
        return f


AIRL = AIRLDiscriminator()
GAIL = GAILDiscriminator()
DISCRIMINATORS: dict[DiscriminatorForm, Discriminator] = {d.form: d for d in (AIRL, GAIL)}


def discriminator_for(form: str) -> Discriminator:
    """The :class:`Discriminator` of a config's ``discriminator`` field (``airl``, ``gail``)."""
    return DISCRIMINATORS[DiscriminatorForm(form)]
