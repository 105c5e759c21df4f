"""The named epoch metrics: every key a line of ``metrics.jsonl`` may hold, declared once.

A :class:`Metric` is a ``StrEnum``: it *is* its key, so lines keep their bytes, and
``EpochMetrics``, summary curves and a run's ``final_metrics`` are all read with it
(``line[Metric.VAL_ALIGNMENT]``, ``Metric.VAL_ALIGNMENT.of(line)``), never with a string.
Adding a metric is one member here (its key, its label, whether it is the discriminator's)
plus the code that computes it (:mod:`pokerirl.irl.trainer`, :mod:`pokerirl.irl.evaluate`,
or a caller's :class:`~pokerirl.irl.records.EpochCallback`).

>>> Metric.VAL_ALIGNMENT.of({"epoch": 1, "val_alignment": 0.75})
0.75
>>> Metric.VAL_MSE.of({"epoch": 1}, None) is None
True
>>> Metric.VAL_ALIGNMENT.on(Part.IMPUTED), Metric.DISC_LOSS.label
(<Metric.VAL_ALIGNMENT_IMPUTED: 'val_alignment_imputed'>, 'discriminator')
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import StrEnum
from typing import Any

_REQUIRED: Any = object()  # Metric.of without a default: the metric must be there


class Part(StrEnum):
    """The rows of an imputed table a metric may be restricted to."""

    OBSERVED = "observed"
    IMPUTED = "imputed"


class Metric(StrEnum):
    """One epoch metric: its key (the value), a legend label, and whether it is the
    discriminator's (zero when a run has no adversary: behaviour cloning)."""

    label: str
    discriminator: bool

    def __new__(cls, key: str, label: str, discriminator: bool = False) -> Metric:
        member = str.__new__(cls, key)
        member._value_ = key
        member.label = label
        member.discriminator = discriminator
        return member

    # The trainer's losses and discriminator statistics (epoch means), in the line's order.
    DISC_LOSS = "disc_loss", "discriminator", True
    DISC_AIRL_LOSS = "disc_airl_loss", "discriminator, adversarial", True
    DISC_ENV_LOSS = "disc_env_loss", "discriminator, environment reward", True
    DISC_ACC_EXPERT = "disc_acc_expert", "on expert samples", True
    DISC_ACC_POLICY = "disc_acc_policy", "on policy samples", True
    REWARD_EXPERT = "reward_expert", "f on expert actions", True
    REWARD_POLICY = "reward_policy", "f on policy actions", True
    REWARD_GAP = "reward_gap", "f expert minus policy", True
    POLICY_LOSS = "policy_loss", "policy"
    POLICY_ADV_LOSS = "policy_adv_loss", "policy, adversarial"
    POLICY_SUP_LOSS = "policy_sup_loss", "policy, supervised"
    # Validation (pokerirl.irl.evaluate): discrete actions ...
    VAL_ALIGNMENT = "val_alignment", "policy argmax = expert"
    VAL_REWARD_ALIGNMENT = "val_reward_alignment", "reward argmax = expert"
    VAL_POLICY_DIST = "val_policy_dist", "mean policy"
    VAL_POLICY_ARGMAX_DIST = "val_policy_argmax_dist", "policy argmax"
    VAL_EXPERT_DIST = "val_expert_dist", "expert actions"
    VAL_ALIGNMENT_OBSERVED = "val_alignment_observed", "policy argmax = expert, observed"
    VAL_REWARD_ALIGNMENT_OBSERVED = (
        "val_reward_alignment_observed",
        "reward argmax = expert, observed",
    )
    VAL_ALIGNMENT_IMPUTED = "val_alignment_imputed", "policy argmax = expert, imputed"
    VAL_REWARD_ALIGNMENT_IMPUTED = "val_reward_alignment_imputed", "reward argmax = expert, imputed"
    # ... continuous actions
    VAL_MSE = "val_mse", "mean action's squared error"
    LOG_STD = "log_std", "policy's mean log σ"
    # An environment's evaluation return, added per epoch by a caller's callback.
    EVAL_RETURN = "eval_return", "evaluation return"
    EVAL_RETURN_STD = "eval_return_std", "evaluation return's std"

    def of(self, metrics: Mapping[str, Any], default: Any = _REQUIRED) -> Any:
        """This metric's value in ``metrics`` (an epoch's line, a run's ``final_metrics``,
        a summary's curves): the one way a metric is read. Without it, ``default`` when one
        is given, else a ``KeyError`` naming the metric."""
        if self in metrics:
            return metrics[self]
        if default is _REQUIRED:
            raise KeyError(f"no metric {self.value!r}")
        return default

    def on(self, part: str) -> Metric:
        """This alignment over one part (a :class:`Part`) of an imputed table's rows."""
        return Metric[f"{self.name}_{Part(part).name}"]


LOSSES = (
    Metric.DISC_LOSS,
    Metric.DISC_AIRL_LOSS,
    Metric.DISC_ENV_LOSS,
    Metric.POLICY_LOSS,
    Metric.POLICY_ADV_LOSS,
    Metric.POLICY_SUP_LOSS,
)  # what every run's line holds, adversarial or not
DISCRIMINATOR_METRICS = tuple(m for m in Metric if m.discriminator)
