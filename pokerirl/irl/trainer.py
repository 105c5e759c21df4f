"""The adversarial trainer: R runs of AIRL, H-AIRL or GAIL in lock-step, made of strategies.

:class:`AdversarialTrainer` is given its nets and two small strategies, in the style of the
``imitation`` library's trainers:

* a :class:`~pokerirl.irl.discriminators.Discriminator`: the logit log D − log(1 − D) from
  f and log π (AIRL's f − log π, GAIL's f);
* a :class:`~pokerirl.irl.heads.PolicyHead`: everything that depends on the action space
  (discrete or Gaussian: act, log π, what the discriminator sees of π, the two policy losses).

Its :meth:`~AdversarialTrainer.step` is the algorithm of :mod:`pokerirl.irl.adversarial`, top to
bottom: the policy acts, the discriminator is updated on the logits of expert and policy
rows, then the policy. Where :func:`pokerirl.irl.fast.covers` the nets and strategies (the
default poker nets, one run, the built-in head and discriminators, by exact type), a
:class:`~pokerirl.irl.fast.HandDerivedStep` (the same step with hand-derived gradients) takes
its place; a user's strategy always runs on autograd. :func:`~pokerirl.irl.adversarial.train` and
:func:`~pokerirl.irl.adversarial.train_many` build one with the config's strategies.

>>> import numpy as np
>>> from pokerirl.irl import AIRLConfig, GAILDiscriminator, Transitions, default_nets
>>> obs = np.random.default_rng(0).random((256, 4)).astype(np.float32)
>>> data = Transitions.from_arrays(obs, (obs[:, 0] > 0.5).astype(np.int64), groups=np.arange(256))
>>> config = AIRLConfig.for_algo("airl", epochs=2, batch_size=64)
>>> reward, policy = default_nets(data, config)
>>> trainer = AdversarialTrainer(
...     demonstrations=data, validation=data, config=config, seeds=[0],
...     rewards=[reward], policies=[policy], discriminator=GAILDiscriminator(),
... )
>>> type(trainer.head).__name__
'DiscreteHead'
>>> [len(run.metrics) for run in trainer.train(progress=False).runs]
[2]
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, cast

import torch
from torch import Tensor, nn
from tqdm.auto import tqdm

from pokerirl.errors import ConfigError, InputError
from pokerirl.execution import unit_progress
from pokerirl.irl import fast
from pokerirl.irl.config import AIRLConfig, NoiseSchedule
from pokerirl.irl.discriminators import Discriminator, discriminator_for
from pokerirl.irl.evaluate import evaluate
from pokerirl.irl.heads import EpochDraw, PolicyHead, StepDraw, head_for
from pokerirl.irl.losses import discriminator_loss, noise_schedule
from pokerirl.irl.metrics import DISCRIMINATOR_METRICS, Metric
from pokerirl.irl.nets import RewardFamily
from pokerirl.irl.optim import FlatAdam
from pokerirl.irl.records import (
    EpochCallback,
    EpochMetrics,
    EpochRecord,
    StepLosses,
    TrainingBatch,
    pack_step,
    unpack_steps,
)
from pokerirl.irl.reward import PolicyNet, RewardNet
from pokerirl.irl.stacked import StackedNets
from pokerirl.irl.transitions import Transitions

# --------------------------------------------------------------------------- results


@dataclass
class TrainResult:
    """One run: the trained nets and its metrics, one :class:`EpochMetrics` per epoch."""

    reward: nn.Module
    policy: nn.Module
    config: AIRLConfig
    beta_used: float  # β actually used: 0 when the data has no rewards
    gradients: str = "autograd"  # or "hand-derived" (pokerirl.irl.fast)
    metrics: list[EpochMetrics] = field(default_factory=list)
    epoch_seconds: list[float] = field(default_factory=list)  # optimization only
    samples_per_epoch: int = 0

    @property
    def samples_per_second(self) -> float:
        """Training throughput: expert samples per second of optimization steps."""
        seconds = sum(self.epoch_seconds)
        return self.samples_per_epoch * len(self.epoch_seconds) / seconds if seconds else math.nan

    def save(
        self,
        folder: str | os.PathLike[str],
        *,
        algo: str,
        data: Mapping[str, Any] | None = None,
        baselines: Mapping[str, float] | None = None,
    ) -> Path:
        """Write this result as a run folder (``reward.pt``, ``policy.pt``, ``config.json``,
        ``metrics.jsonl``), which :func:`~pokerirl.irl.run.load_reward`,
        :func:`~pokerirl.irl.run.load_policy` and every command read; no training again.
        ``algo`` is recorded (``airl``, ``hairl``, ``gail``); ``data`` describes the data."""
        from pokerirl.irl.folder import MetricsLog, save_run

        out = Path(folder)
        save_run(self, out, algo=algo, data=data or {}, baselines=baselines)
        log = MetricsLog(out / "metrics.jsonl")
        for line in self.metrics:
            log.write(line)
        return out


@dataclass
class ManyResult:
    """R runs trained in lock-step: one :class:`TrainResult` per seed."""

    runs: list[TrainResult]
    epoch_seconds: list[float]  # all runs together
    samples_per_epoch: int  # all runs together

    @property
    def samples_per_second(self) -> float:
        seconds = sum(self.epoch_seconds)
        return self.samples_per_epoch * len(self.epoch_seconds) / seconds if seconds else math.nan


# --------------------------------------------------------------------------- the trainer

_OPTIONAL = ("mask", "env", "next_obs", "dones", "weights")  # what a table may lack


class AdversarialTrainer:
    """R runs of one config on the same data in lock-step, one per seed.

    ``rewards[r]`` and ``policies[r]`` (``nn.Module``s of one architecture) are run r's nets,
    trained in place; ``seeds[r]`` its shuffles and noise. ``discriminator`` and ``head``
    default to the config's (:func:`~pokerirl.irl.discriminators.discriminator_for`) and the
    data's action space's (:func:`~pokerirl.irl.heads.head_for`). ``adversarial=False``
    skips the discriminator (behaviour cloning when α = 1); ``fast_path`` allows the
    hand-derived gradients where they cover the nets.
    """

    def __init__(
        self,
        *,
        demonstrations: Transitions,
        validation: Transitions,
        config: AIRLConfig,
        seeds: Sequence[int],
        rewards: Sequence[RewardNet],
        policies: Sequence[PolicyNet],
        discriminator: Discriminator | None = None,
        head: PolicyHead | None = None,
        adversarial: bool = True,
        fast_path: bool = True,
        device: str | torch.device = "cpu",
    ) -> None:
        device = resolve_device(device)
        data = demonstrations
        if len(data) == 0 or len(validation) == 0:
            raise InputError("training and validation data must both be non-empty")
        if not len(rewards) == len(policies) == len(seeds):
            raise ValueError("give one reward net and one policy per seed")
        if config.reward_family == RewardFamily.SHAPED and data.next_obs is None:
            raise ConfigError("the shaped reward family needs transitions with next_obs and done")
        modules = [cast(nn.Module, m) for m in (*rewards, *policies)]  # the Protocols' modules
        for module in modules:
            module.to(device).train()
        self.data, self.val, self.config, self.device = data, validation, config, device
        self.rewards = StackedNets(modules[: len(seeds)])
        self.policies = StackedNets(modules[len(seeds) :])
        self.adversarial = adversarial
        self.discriminator = discriminator or discriminator_for(config.discriminator)
        self.head = head or head_for(data, config, device)
        self.runs = len(seeds)
        self.seeds = [int(s) for s in seeds]
        self.generators = [torch.Generator(device=device).manual_seed(s) for s in self.seeds]
        self.beta = config.beta if data.rewards is not None else 0.0
        self.alpha = config.alpha
        self.shaped = config.reward_family == RewardFamily.SHAPED
        self.batch = min(config.batch_size, len(data))
        self.steps = len(data) // self.batch  # drop the ragged tail; the next shuffle covers it
        self.noisy = config.sigma_start > 0 and adversarial
        sigma = noise_schedule(
            self.batch,
            config.sigma_start,
            config.sigma_end,
            kind=config.noise_schedule,
            decay=config.noise_decay,
        )
        self.sigma = sigma.to(device)
        optional = {
            "mask": data.legal_mask,
            "env": data.rewards,  # r_env
            "next_obs": data.next_obs,
            "dones": data.dones,
            "weights": data.weights,
        }
        self.rows = TrainingBatch(  # every training row, on the device
            obs=data.obs.to(device),
            expert=data.action_vectors().to(device),
            **{
                name: None if value is None else value.to(device)
                for name, value in optional.items()
            },
        )
        # One Adam over stacked parameters is R independent Adams (it is elementwise).
        self.reward_opt = FlatAdam(
            self.rewards.params, lr=config.reward_lr, weight_decay=config.reward_weight_decay
        )
        self.policy_opt = FlatAdam(self.policies.params, lr=config.policy_lr)
        # Gather a whole epoch's batches at once when that is small (one index per tensor
        # per epoch instead of per step); else per step.
        self.gather_epoch = self.runs * len(data) * (data.obs_dim + 8) <= 2**25
        self.update: Callable[[TrainingBatch, StepDraw], Tensor] = self.step
        if (
            fast_path
            and self.runs == 1
            and device.type == "cpu"
            and not self.shaped
            and fast.covers(
                reward=self.rewards.modules[0],
                policy=self.policies.modules[0],
                head=self.head,
                discriminator=self.discriminator,
            )
        ):
            self.update = fast.HandDerivedStep(
                reward=self.rewards.modules[0],  # type: ignore[arg-type]  # covers() checked
                policy=self.policies.modules[0],  # type: ignore[arg-type]
                head=self.head,  # type: ignore[arg-type]  # covers() checked
                discriminator=self.discriminator,
                reward_opt=self.reward_opt,
                policy_opt=self.policy_opt,
                adversarial=adversarial,
                alpha=self.alpha,
                beta=self.beta,
            )
        self.hand_derived = isinstance(self.update, fast.HandDerivedStep)

    # ------------------------------------------------------------------ one epoch's randomness

    def draw_epoch(self) -> EpochDraw:
        """All of an epoch's random numbers, per run from its own generator, in a fixed
        order (the rows, the head's, the noise's ε, then σ's shuffle)."""
        n, steps, batch = len(self.rows.obs), self.steps, self.batch
        width = self.rows.expert.shape[1]
        perm, act, noise, sigma = [], [], [], []
        for gen in self.generators:
            kw: dict[str, Any] = {"generator": gen, "device": self.device}
            perm.append(torch.randperm(n, **kw)[: steps * batch].view(steps, batch))
            own = self.head.draw(gen, steps, batch, adversarial=self.adversarial)
            if own is not None:
                act.append(own)
            if self.noisy:
                noise.append(torch.randn(steps, batch, width, **kw))
                if self.config.noise_schedule == NoiseSchedule.AUTHORS:
                    sigma.append(self.sigma[torch.rand(steps, batch, **kw).argsort(dim=1)])
                else:
                    sigma.append(self.sigma.expand(steps, batch))
        return EpochDraw(perm=torch.stack(perm, dim=1), act=_stack(act), noise=_stack(noise),
                         sigma=_stack(sigma))  # fmt: skip

    # ------------------------------------------------------------------ one batch

    def gather(self, rows: Tensor) -> TrainingBatch:
        """The training tensors at ``rows`` (any shape of indices)."""
        optional = {name: getattr(self.rows, name) for name in _OPTIONAL}
        return TrainingBatch(
            obs=self.rows.obs[rows],
            expert=self.rows.expert[rows],
            **{name: None if value is None else value[rows] for name, value in optional.items()},
        )

    def step(self, batch: TrainingBatch, draw: StepDraw) -> Tensor:
        """One discriminator and one policy update on a batch of (R, B) rows.

        Returns (R, 4B + 3), :func:`~pokerirl.irl.records.pack_step`'s row: f on expert and
        policy rows, log π of both, then the :class:`StepLosses`.
        """
        # 1. the policy acts at s (kept with its graph for step 3)
        acts = self.head.act(self.policies, batch, draw)

        # 2. discriminator step on the logits of expert and policy rows
        if self.adversarial:
            with torch.no_grad():
                seen, log_pi_expert, log_pi_seen = self.head.discriminator_rows(acts, batch, draw)
            f = self.reward(batch, torch.stack((batch.expert, seen), dim=1))  # (R, 2, B)
            d_loss, _d_airl, _d_env = discriminator_loss(
                f[:, 0], log_pi_expert, f[:, 1], log_pi_seen, beta=self.beta, env_reward=batch.env,
                weights=batch.weights, discriminator=self.discriminator,
            )  # fmt: skip
            self.reward_opt.zero_grad()
            d_loss.sum().backward()
            self.reward_opt.step()
            # What the epoch's metrics need, computed once per epoch from these rows.
            disc_record = torch.cat((f.detach().flatten(1), log_pi_expert, log_pi_seen), dim=1)
        else:
            disc_record = batch.obs.new_zeros(self.runs, 4 * self.batch)

        # 3. policy step against the updated reward
        supervised = self.head.supervised_loss(acts, batch)
        if self.alpha < 1:
            adversarial = self.head.adversarial_loss(acts, batch, self.rewards)
        else:
            adversarial = batch.obs.new_zeros(self.runs)
        p_loss = (1 - self.alpha) * adversarial + self.alpha * supervised
        self.policy_opt.zero_grad()
        p_loss.sum().backward(inputs=self.policies.params)
        self.policy_opt.step()
        return pack_step(disc_record, StepLosses(p_loss, adversarial, supervised))

    def reward(self, batch: TrainingBatch, actions: Tensor) -> Tensor:
        """f (R, M, B) of (R, M, B, k) action rows at the batch's states (with s' when shaped)."""
        obs = batch.obs[:, None]
        if self.shaped:
            assert batch.next_obs is not None and batch.dones is not None  # __init__ checks
            return self.rewards(obs, actions, batch.next_obs[:, None], batch.dones[:, None])
        return self.rewards(obs, actions)

    def epoch_stats(self, record: Tensor, perm: Tensor) -> dict[str, list[float]]:
        """Epoch means per run of the losses and discriminator accuracies."""
        disc, losses = unpack_steps(record, self.batch)
        f_expert, f_seen = disc.f_expert, disc.f_policy
        lp_expert, lp_seen = disc.log_pi_expert, disc.log_pi_policy
        env = None if self.rows.env is None else self.rows.env[perm]  # (steps, R, B)
        weights = None if self.rows.weights is None else self.rows.weights[perm]
        d_loss, d_airl, d_env = discriminator_loss(
            f_expert, lp_expert, f_seen, lp_seen, beta=self.beta, env_reward=env,
            weights=weights, discriminator=self.discriminator,
        )  # fmt: skip
        logits = self.discriminator.logits
        values = {
            Metric.DISC_LOSS: d_loss.mean(0),
            Metric.DISC_AIRL_LOSS: d_airl.mean(0),
            Metric.DISC_ENV_LOSS: d_env.mean(0),
            # a logit above 0 is D > 1/2
            Metric.DISC_ACC_EXPERT: (logits(f_expert, lp_expert) > 0).float().mean((0, 2)),
            Metric.DISC_ACC_POLICY: (logits(f_seen, lp_seen) < 0).float().mean((0, 2)),
            Metric.REWARD_EXPERT: f_expert.mean((0, 2)),
            Metric.REWARD_POLICY: f_seen.mean((0, 2)),
            Metric.REWARD_GAP: (f_expert - f_seen).mean((0, 2)),  # expert minus policy
            **{name: value.mean(0) for name, value in losses._asdict().items()},  # named as LOSSES
        }
        if not self.adversarial:
            for key in DISCRIMINATOR_METRICS:
                values[key] = torch.zeros(self.runs)
        return {key: value.tolist() for key, value in values.items()}

    # ------------------------------------------------------------------ the loop

    def add_extras(
        self,
        epoch: int,
        seconds: float,
        epoch_metrics: list[dict[str, object]],
        callback: EpochCallback,
    ) -> None:
        """Ask ``callback`` for the epoch's extra metrics and add them, run by run."""
        record = EpochRecord(
            epoch=epoch,
            metrics=tuple(dict(m) for m in epoch_metrics),  # copies: the callback reads only
            rewards=tuple(self.rewards.modules),
            policies=tuple(self.policies.modules),
            seconds=seconds,
        )
        extras = callback(record)
        if extras is None:
            return
        extras = list(extras)
        if len(extras) != self.runs:
            raise ValueError(
                f"the epoch callback returned {len(extras)} metric sets for {self.runs} runs"
            )
        for metrics, extra in zip(epoch_metrics, extras, strict=True):
            clash = sorted(set(extra) & set(metrics))
            if clash:
                raise ValueError(f"the epoch callback's metric {clash[0]!r} is the trainer's")
            metrics.update(extra)

    def train(
        self,
        *,
        progress: bool = True,
        on_epoch: Callable[[list[EpochMetrics]], None] | None = None,
        callback: EpochCallback | None = None,
    ) -> ManyResult:
        """``config.epochs`` epochs; after each, ``callback`` (an :class:`EpochCallback`)
        may add metrics per run, then ``on_epoch`` gets the R runs' metrics."""
        results = [
            TrainResult(
                reward=r,
                policy=p,
                config=replace(self.config, seed=s),
                beta_used=self.beta,
                gradients="hand-derived" if self.hand_derived else "autograd",
                samples_per_epoch=self.steps * self.batch,
            )
            for r, p, s in zip(self.rewards.modules, self.policies.modules, self.seeds, strict=True)
        ]
        many = ManyResult(runs=results, epoch_seconds=[], samples_per_epoch=0)
        many.samples_per_epoch = self.runs * self.steps * self.batch
        # Two bars in one run: the behaviour-cloning baseline's, then the adversarial one's.
        label = "IRL (adversarial)" if self.adversarial else "baseline (behaviour cloning)"
        bar = tqdm(range(1, self.config.epochs + 1), desc=label, unit="epoch", disable=not progress)
        for epoch in bar:
            start = time.perf_counter()
            draw = self.draw_epoch()
            record = torch.empty(self.steps, self.runs, 4 * self.batch + 3, device=self.device)
            batches = self.gather(draw.perm) if self.gather_epoch else None
            for step in range(self.steps):
                if batches is not None:
                    batch = batches.at(step)
                else:
                    batch = self.gather(draw.perm[step])
                record[step] = self.update(batch, draw.at(step))
            if self.device.type == "cuda":
                torch.cuda.synchronize(self.device)  # time the work, not its queueing
            seconds = time.perf_counter() - start
            many.epoch_seconds.append(seconds)
            self.rewards.write_back()
            self.policies.write_back()
            stats = self.epoch_stats(record, draw.perm)
            growing = []
            for r, result in enumerate(results):
                metrics: dict[str, object] = {"epoch": epoch}
                metrics.update({key: values[r] for key, values in stats.items()})
                metrics.update(evaluate(result.reward, result.policy, self.val))
                growing.append(metrics)
            if callback is not None:
                self.add_extras(epoch, seconds, growing, callback)
            epoch_metrics = [EpochMetrics.from_json(metrics) for metrics in growing]
            for result, line in zip(results, epoch_metrics, strict=True):
                result.metrics.append(line)
                result.epoch_seconds.append(seconds / self.runs)
            if on_epoch is not None:
                on_epoch(epoch_metrics)
            unit_progress(epoch, self.config.epochs)  # the driver's bar, when this is a unit
            first = epoch_metrics[0]
            if Metric.VAL_ALIGNMENT in first:
                align, d_loss = Metric.VAL_ALIGNMENT.of(first), Metric.DISC_LOSS.of(first)
                bar.set_postfix(align=f"{align:.3f}", d_loss=f"{d_loss:.3f}")
        bar.close()
        for result in results:
            result.reward.eval()
            result.policy.eval()
        return many


def _stack(per_run: list[Tensor]) -> Tensor | None:
    """(steps, R, ...) from R tensors of (steps, ...); None when nothing was drawn."""
    return torch.stack(per_run, dim=1) if per_run else None


def resolve_device(device: str | torch.device) -> torch.device:
    """``torch.device(device)``, with a clear ``ValueError`` when CUDA isn't available."""
    try:
        resolved = torch.device(device)
    except RuntimeError as error:
        raise ConfigError(f"unknown device {device!r}: {error}") from None
    if resolved.type == "cuda" and not torch.cuda.is_available():
        raise ConfigError("device 'cuda' requested but CUDA is not available on this machine")
    if resolved.type not in ("cpu", "cuda"):
        raise ConfigError(f"unsupported device {device!r}; use cpu or cuda")
    return resolved
