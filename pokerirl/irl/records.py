"""Typed records the trainer passes around: one batch of rows, one step's losses, one epoch.

The trainer packs a step's numbers into one tensor row (one write per step, cheap on small
nets); :class:`StepLosses` and :class:`DiscriminatorRecord` name its parts, so nothing is
read back by position in a dict.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Protocol

from torch import Tensor, nn

# Declared with the metrics; importable from here as before.
from pokerirl.irl.metrics import DISCRIMINATOR_METRICS as DISCRIMINATOR_METRICS
from pokerirl.serial import Serializable, meta


@dataclass(frozen=True, slots=True)
class TrainingBatch:
    """A mini-batch of training rows (tensors) at some indices; every tensor has the indices'
    shape first.

    ``expert`` holds the expert's action vectors (one-hots for discrete actions); the
    optional tensors are there when the data has them.
    """

    obs: Tensor
    expert: Tensor
    mask: Tensor | None = None
    env: Tensor | None = None  # the environment's reward r_env
    next_obs: Tensor | None = None
    dones: Tensor | None = None
    weights: Tensor | None = None  # each row's weight in the losses' means

    def at(self, step: int) -> TrainingBatch:
        """The rows at first index ``step`` (one step of an epoch's batches, or one run)."""
        return TrainingBatch(
            obs=self.obs[step],
            expert=self.expert[step],
            mask=_index(self.mask, step),
            env=_index(self.env, step),
            next_obs=_index(self.next_obs, step),
            dones=_index(self.dones, step),
            weights=_index(self.weights, step),
        )


def _index(value: Tensor | None, i: int) -> Tensor | None:
    return None if value is None else value[i]


class StepLosses(NamedTuple):
    """One policy step's losses, each (R,) or (..., R): total, adversarial and supervised."""

    policy_loss: Tensor
    policy_adv_loss: Tensor
    policy_sup_loss: Tensor


class DiscriminatorRecord(NamedTuple):
    """A discriminator step's rows, each (..., B): f and log π on expert and policy actions.

    The epoch's discriminator metrics are computed once from these (not per step)."""

    f_expert: Tensor
    f_policy: Tensor
    log_pi_expert: Tensor
    log_pi_policy: Tensor


def pack_step(disc: Tensor, losses: StepLosses) -> Tensor:
    """One step's row, (..., 4B + 3): the discriminator's rows (f expert, f policy, log π
    expert, log π policy, B each) then the three policy losses."""
    import torch

    return torch.cat((disc, torch.stack(tuple(losses), dim=-1).detach()), dim=-1)


def unpack_steps(record: Tensor, batch: int) -> tuple[DiscriminatorRecord, StepLosses]:
    """The named parts of rows made by :func:`pack_step`."""
    disc = DiscriminatorRecord(*record[..., : 4 * batch].split(batch, dim=-1))
    losses = StepLosses(*(record[..., 4 * batch + i] for i in range(len(StepLosses._fields))))
    return disc, losses




@dataclass(frozen=True, kw_only=True, eq=False)
class EpochMetrics(Mapping[str, Any], Serializable):
    """One epoch of one run: a line of ``metrics.jsonl``.

    ``metrics`` are the trainer's metrics (losses, discriminator, validation: which ones
    depends on the actions and on the adversary), then an :class:`EpochCallback`'s extras,
    in that order. The metrics are named once, in :class:`~pokerirl.irl.metrics.Metric`, and
    read through it, ``Metric.VAL_ALIGNMENT.of(line)``: the record is a read-only mapping that
    starts with ``epoch`` (and equals the dict of its line), open to a callback's extras.

    >>> from pokerirl.irl.metrics import Metric
    >>> line = EpochMetrics.from_json({"epoch": 1, "disc_loss": 0.5, "val_alignment": 0.75})
    >>> line.epoch, Metric.VAL_ALIGNMENT.of(line), line.scalars()
    (1, 0.75, {'disc_loss': 0.5, 'val_alignment': 0.75})
    >>> line.to_json()
    {'epoch': 1, 'disc_loss': 0.5, 'val_alignment': 0.75}
    """

    epoch: int
    metrics: Mapping[str, Any] = field(metadata=meta(flatten=True))  # the line: epoch first

    def __post_init__(self) -> None:
        if "epoch" in self.metrics:
            raise ValueError("an epoch's metrics cannot hold another 'epoch'")

    def __getitem__(self, key: str) -> Any:
        return self.epoch if key == "epoch" else self.metrics[key]

    def __iter__(self) -> Iterator[str]:
        yield "epoch"
        yield from self.metrics

    def __len__(self) -> int:
        return 1 + len(self.metrics)

    def scalars(self) -> dict[str, float]:
        """The numeric metrics (not ``epoch``), in order: what a summary averages."""
        return {k: v for k, v in self.metrics.items() if isinstance(v, int | float)}


@dataclass(frozen=True, kw_only=True)
class EpochRecord:
    """What an :class:`EpochCallback` sees after an epoch (the nets are written back).

    ``metrics[r]`` is run r's metrics so far (read it, don't change it: return extras);
    ``rewards[r]`` and ``policies[r]`` its nets, in training mode; ``seconds`` the epoch's
    optimization time for all runs together."""

    epoch: int
    metrics: tuple[Mapping[str, Any], ...]
    rewards: tuple[nn.Module, ...]
    policies: tuple[nn.Module, ...]
    seconds: float

    @property
    def runs(self) -> int:
        return len(self.metrics)


class EpochCallback(Protocol):
    """Called by the trainer after each epoch (SB3's callback idea).

    Returns None, or one mapping per run of extra metrics for that epoch: they are added to
    each run's metrics (after the trainer's own, in their order) before ``on_epoch`` sees them.
    Its work is not timed in ``epoch_seconds``.
    """

    def __call__(self, record: EpochRecord) -> Sequence[Mapping[str, Any]] | None: ...
