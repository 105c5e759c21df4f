"""AIRL, Hybrid-AIRL and GAIL on :class:`Transitions`, for one run or R runs in lock-step.

Per shuffled mini-batch of expert rows (s, a_E[, s', done, r_env]):

1. the policy acts at s: π(·|s) for discrete actions, a reparameterized sample μ(s) + σε
   for continuous ones (one forward pass, kept for step 3);
2. discriminator step: D = exp f / (exp f + π) learns to call (s, a_E) expert and (s, ã)
   policy, with loss (1−β)·L_AIRL + β·mean (f(s, a_E) − r_env)². ã is what the discriminator
   sees of the policy (``disc_action``): a one-hot drawn from π (default), or π itself; then
   Gaussian noise with σ_i along the batch (``noise_schedule``), projected back onto the
   legal simplex (or clipped to the box). log π(ã|s) = Σ_k ã_k log π(k|s), exact on one-hots;
3. policy step against the just-updated reward:
   (1−α)·E_{a∼π}[log π(a|s) − g(s, a)] + α·(CE(π, a_E) or ‖μ(s) − a_E‖²). For discrete
   actions the expectation is exact, Σ_k π_k (log π_k − g(s, e_k)); for continuous ones it is
   the reparameterized sample. g is the reward's action-dependent part: all of f for the
   ``state_action`` family; for ``shaped`` the γh(s') − h(s) terms do not depend on a.

AIRL is α = β = 0 and no noise. GAIL is AIRL with another discriminator, D = σ(f): the
loop asks its :class:`~pokerirl.irl.discriminators.Discriminator` for the logits
log D − log(1 − D) wherever it needs them (AIRL's f − log π above, GAIL's f); the policy
step is the same for both (GAIL's causal-entropy weight is 1). ``docs/method.md`` says
which choice comes from where.

Gradients are autograd's, except on the one architecture :mod:`pokerirl.irl.fast` covers
(the default poker nets, one run on CPU), where hand-derived gradients, tested against
autograd, make a step about twice as fast; ``fast_path=False`` turns that off.

R runs in lock-step (:func:`train_many`) stack the R nets' parameters (batched products for
the default nets' layers, ``torch.func.vmap`` for other architectures); every run has its
own seed, shuffle and noise, and its own Adam state (Adam is elementwise, so one optimizer
over stacked parameters is R independent ones).

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> obs = rng.random((512, 6)).astype(np.float32)
>>> data = Transitions.from_arrays(obs, (obs[:, 0] > 0.5).astype(np.int64), groups=np.arange(512))
>>> config = AIRLConfig.for_algo("hairl", epochs=20, batch_size=64, alpha=1.0)
>>> result = train(data, data, config=config, progress=False)
>>> result.metrics[-1]["val_alignment"] > 0.9
True
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import torch
from torch import Tensor, nn
from tqdm.auto import tqdm

from pokerirl.errors import ConfigError, InputError
from pokerirl.execution import unit_progress
from pokerirl.irl import fast
from pokerirl.irl.baselines import baselines
from pokerirl.irl.config import AIRLConfig, NoiseForm, NoiseSchedule
from pokerirl.irl.discriminators import discriminator_for
from pokerirl.irl.evaluate import evaluate
from pokerirl.irl.losses import (
    LOG_2PI,
    LOSS_KEYS,
    discriminator_loss,
    gaussian_log_prob,
    noise_schedule,
    sample_one_hot,
    weighted_mean,
)
from pokerirl.irl.nets import MASKED_LOGIT, RewardFamily, build_nets, project_to_simplex
from pokerirl.irl.optim import FlatAdam
from pokerirl.irl.records import (
    DISCRIMINATOR_METRICS,
    Batch,
    EpochCallback,
    EpochMetrics,
    EpochRecord,
    StepLosses,
    pack_step,
    unpack_steps,
)
from pokerirl.irl.stacked import (
    StackedLayerNorm,
    StackedLinear,
    StackedNets,
    stack_modules,
)
from pokerirl.irl.transitions import Transitions

# Importable from here as before the split (losses, stacked nets, evaluation, baselines).
__all__ = [
    "LOG_2PI",
    "LOSS_KEYS",
    "Batch",
    "EpochCallback",
    "EpochRecord",
    "ManyResult",
    "StackedLayerNorm",
    "StackedLinear",
    "StackedNets",
    "StepLosses",
    "TrainResult",
    "baselines",
    "default_nets",
    "discriminator_loss",
    "evaluate",
    "gaussian_log_prob",
    "noise_schedule",
    "resolve_device",
    "sample_one_hot",
    "stack_modules",
    "train",
    "train_many",
]

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
        from pokerirl.irl.run import MetricsLog, save_run

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


# --------------------------------------------------------------------------- training


def default_nets(
    data: Transitions, config: AIRLConfig, seed: int | None = None
) -> tuple[nn.Module, nn.Module]:
    """The default (reward, policy) for ``data``'s spaces, initialized from ``seed``
    (default ``config.seed``) without touching torch's global generator."""
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(config.seed if seed is None else seed)
        return build_nets(
            config.net_spec(),
            obs_dim=data.obs_dim,
            action_dim=data.action_dim,
            discrete=data.discrete,
            low=data.action_low,
            high=data.action_high,
        )


def train(
    train_data: Transitions,
    val_data: Transitions,
    *,
    config: AIRLConfig,
    reward: nn.Module | None = None,
    policy: nn.Module | None = None,
    adversarial: bool = True,
    fast_path: bool = True,
    device: str | torch.device = "cpu",
    progress: bool = True,
    on_epoch: Callable[[EpochMetrics], None] | None = None,
    callback: EpochCallback | None = None,
) -> TrainResult:
    """Train ``reward`` and ``policy`` (default: :func:`default_nets`) on ``train_data``;
    evaluate on ``val_data`` each epoch. Deterministic on CPU for a given seed and data.

    ``adversarial=False`` skips the discriminator (behaviour cloning when α = 1).
    ``fast_path``: use the hand-derived gradients of :mod:`pokerirl.irl.fast` where they
    cover the nets (the default poker nets, one run, on CPU); autograd otherwise.
    ``on_epoch`` gets each epoch's metrics as soon as they are ready; ``callback`` (an
    :class:`EpochCallback`) may add metrics to it first.
    """
    if reward is None or policy is None:
        default_reward, default_policy = default_nets(train_data, config)
        reward = default_reward if reward is None else reward
        policy = default_policy if policy is None else policy
    many = train_many(
        train_data,
        val_data,
        config=config,
        seeds=[config.seed],
        rewards=[reward],
        policies=[policy],
        adversarial=adversarial,
        fast_path=fast_path,
        device=device,
        progress=progress,
        on_epoch=None if on_epoch is None else (lambda ms: on_epoch(ms[0])),
        callback=callback,
    )
    return many.runs[0]


def train_many(
    train_data: Transitions,
    val_data: Transitions,
    *,
    config: AIRLConfig,
    seeds: Sequence[int],
    rewards: Sequence[nn.Module] | None = None,
    policies: Sequence[nn.Module] | None = None,
    adversarial: bool = True,
    fast_path: bool = True,
    device: str | torch.device = "cpu",
    progress: bool = True,
    on_epoch: Callable[[list[EpochMetrics]], None] | None = None,
    callback: EpochCallback | None = None,
) -> ManyResult:
    """R = len(seeds) runs of ``config`` on the same data, in lock-step.

    Run r uses ``seeds[r]`` for its shuffles and noise (and, with default nets, its
    initialization), so it is the run ``train`` would make with that seed, up to floating
    point. The nets must share one architecture. After each epoch ``callback`` (an
    :class:`EpochCallback`) may add metrics per run; then ``on_epoch`` gets the R runs' metrics.
    """
    device = resolve_device(device)
    if len(train_data) == 0 or len(val_data) == 0:
        raise InputError("training and validation data must both be non-empty")
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("train_many needs at least one seed")
    if rewards is None or policies is None:
        built = [default_nets(train_data, config, seed) for seed in seeds]
        rewards = [b[0] for b in built] if rewards is None else rewards
        policies = [b[1] for b in built] if policies is None else policies
    if not len(rewards) == len(policies) == len(seeds):
        raise ValueError("give one reward net and one policy per seed")
    if config.reward_family == RewardFamily.SHAPED and train_data.next_obs is None:
        raise ConfigError("the shaped reward family needs transitions with next_obs and done")
    for module in (*rewards, *policies):
        module.to(device).train()
    return _Loop(
        train_data,
        val_data,
        config=config,
        seeds=seeds,
        rewards=StackedNets(rewards),
        policies=StackedNets(policies),
        adversarial=adversarial,
        device=device,
        fast_path=fast_path,
    ).run(progress=progress, on_epoch=on_epoch, callback=callback)


class _Loop:
    """The training loop's state; :meth:`run` is the algorithm, :meth:`step` one batch."""

    def __init__(
        self,
        data: Transitions,
        val: Transitions,
        *,
        config: AIRLConfig,
        seeds: list[int],
        rewards: StackedNets,
        policies: StackedNets,
        adversarial: bool,
        device: torch.device,
        fast_path: bool = False,
    ) -> None:
        self.data, self.val, self.config, self.device = data, val, config, device
        self.rewards, self.policies, self.adversarial = rewards, policies, adversarial
        self.runs = len(seeds)
        self.seeds = seeds
        self.generators = [torch.Generator(device=device).manual_seed(s) for s in seeds]
        self.discrete = data.discrete
        self.beta = config.beta if data.rewards is not None else 0.0
        self.alpha = config.alpha
        self.disc = discriminator_for(config.discriminator)  # how logits come from f and log π
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
        self.obs = data.obs.to(device)
        self.actions = data.actions.to(device)
        self.action_vectors = data.action_vectors().to(device)
        self.mask = None if data.legal_mask is None else data.legal_mask.to(device)
        self.env = None if data.rewards is None else data.rewards.to(device)
        self.next_obs = None if data.next_obs is None else data.next_obs.to(device)
        self.dones = None if data.dones is None else data.dones.to(device)
        self.weights = None if data.weights is None else data.weights.to(device)
        if self.discrete:
            eye = torch.eye(data.action_dim, device=device)
            self.each_action = eye[:, None, :]  # (K, 1, K): every one-hot, broadcast over B
        else:
            self.low = torch.tensor(data.action_low, device=device)
            self.high = torch.tensor(data.action_high, device=device)
        # One Adam over stacked parameters is R independent Adams (it is elementwise).
        self.reward_opt = FlatAdam(
            rewards.params, lr=config.reward_lr, weight_decay=config.reward_weight_decay
        )
        self.policy_opt = FlatAdam(policies.params, lr=config.policy_lr)
        # Gather a whole epoch's batches at once when that is small (one index per tensor
        # per epoch instead of per step); else per step.
        self.gather_epoch = self.runs * len(data) * (data.obs_dim + 8) <= 2**25
        self.fast = (
            fast_path
            and self.runs == 1
            and device.type == "cpu"
            and config.reward_family == RewardFamily.STATE_ACTION
            and config.supervised_form == "mean_mse"  # the hand-derived gradients' term
            and fast.supports(rewards.modules[0], policies.modules[0])
        )

    # ------------------------------------------------------------------ one epoch's randomness

    def draw_epoch(self) -> dict[str, Tensor]:
        """All of an epoch's random numbers, per run from its own generator."""
        n, steps, batch = len(self.obs), self.steps, self.batch
        width = self.action_vectors.shape[1]
        draws: dict[str, list[Tensor]] = {"perm": [], "u": [], "eps": [], "pi_eps": [], "sig": []}
        for gen in self.generators:
            kw: dict[str, Any] = {"generator": gen, "device": self.device}
            draws["perm"].append(torch.randperm(n, **kw)[: steps * batch].view(steps, batch))
            if self.discrete:
                if self.adversarial:  # behaviour cloning draws its shuffles only
                    draws["u"].append(torch.rand(steps, batch, **kw))
            else:
                draws["pi_eps"].append(torch.randn(steps, batch, width, **kw))
            if self.noisy:
                draws["eps"].append(torch.randn(steps, batch, width, **kw))
                if self.config.noise_schedule == NoiseSchedule.AUTHORS:
                    order = torch.rand(steps, batch, **kw).argsort(dim=1)
                    draws["sig"].append(self.sigma[order])
        return {k: torch.stack(v, dim=1) for k, v in draws.items() if v}  # (steps, R, ...)

    # ------------------------------------------------------------------ one batch

    def gather(self, rows: Tensor) -> Batch:
        """The training tensors at ``rows`` (any shape of indices)."""
        optional = {
            name: None if value is None else value[rows]
            for name, value in (
                ("mask", self.mask),
                ("env", self.env),
                ("next_obs", self.next_obs),
                ("dones", self.dones),
                ("weights", self.weights),
            )
        }
        return Batch(obs=self.obs[rows], expert=self.action_vectors[rows], **optional)

    def step(self, batch: Batch, draw: dict[str, Tensor], step: int) -> Tensor:
        """One discriminator and one policy update on a batch of (R, B) rows.

        Returns (R, 4B + 3), :func:`~pokerirl.irl.records.pack_step`'s row: f on expert and
        policy rows, log π of both, then the :class:`StepLosses`.
        """
        obs, expert, mask, env = batch.obs, batch.expert, batch.mask, batch.env
        weights = batch.weights  # (R, B) or None: every row once
        zero = obs.new_zeros(self.runs)

        # 1. the policy at s (kept with its graph for step 3)
        if self.discrete:
            log_pi = self.policies(obs, mask)
            probs = log_pi.exp()
        else:
            mean, log_std = self.policies(obs)
            log_std = log_std.clamp(self.config.log_std_min, self.config.log_std_max)
            sample = mean + log_std.exp() * draw["pi_eps"][step]

        # 2. discriminator step
        if self.adversarial:
            with torch.no_grad():
                if self.discrete:
                    lp = log_pi.detach()
                    seen = self.discrete_seen(probs.detach(), mask, draw, step)
                    log_pi_expert = (expert * lp).sum(-1)
                    log_pi_seen = (seen * lp).sum(-1)
                else:
                    m, ls = mean.detach(), log_std.detach()
                    seen = sample.detach() if self.config.disc_action == "sample" else m
                    log_pi_seen = None
                    if self.noisy:
                        sigma = draw["sig"][step] if "sig" in draw else self.sigma
                        if self.config.noise_form == NoiseForm.AUTHORS:
                            # σ in units of high, no clipping, log π of the clean sample.
                            log_pi_seen = gaussian_log_prob(seen, m, ls)
                            seen = seen + sigma[..., None] * self.high * draw["eps"][step]
                        else:
                            noise = sigma[..., None] * (self.high - self.low) * draw["eps"][step]
                            seen = torch.maximum(torch.minimum(seen + noise, self.high), self.low)
                    log_pi_expert = gaussian_log_prob(expert, m, ls)
                    if log_pi_seen is None:
                        log_pi_seen = gaussian_log_prob(seen, m, ls)
            both = torch.stack((expert, seen), dim=1)  # (R, 2, B, k)
            if self.shaped:
                assert batch.next_obs is not None and batch.dones is not None  # train_many checks
                f = self.rewards(obs[:, None], both, batch.next_obs[:, None], batch.dones[:, None])
            else:
                f = self.rewards(obs[:, None], both)
            d_loss, _d_airl, _d_env = discriminator_loss(
                f[:, 0], log_pi_expert, f[:, 1], log_pi_seen, beta=self.beta, env_reward=env,
                weights=weights, discriminator=self.disc,
            )  # fmt: skip
            self.reward_opt.zero_grad()
            d_loss.sum().backward()
            self.reward_opt.step()
            # What the epoch's metrics need, computed once per epoch from these rows.
            disc_record = torch.cat((f.detach().flatten(1), log_pi_expert, log_pi_seen), dim=1)
        else:
            disc_record = obs.new_zeros(self.runs, 4 * self.batch)

        # 3. policy step against the updated reward
        if self.discrete:
            if self.config.supervised_form == "sum_mse":
                # The authors': mse_loss(π's probabilities, one-hot a_E, reduction="sum").
                supervised = _summed((probs - expert).square(), weights)
            else:
                supervised = weighted_mean(-(expert * log_pi).sum(-1), weights)
            if self.alpha < 1:
                with torch.no_grad():
                    g = self.rewards(obs[:, None], self.each_action, shared=(False, True))
                    g = g.transpose(1, 2)
                adversarial = weighted_mean((probs * (log_pi - g)).sum(-1), weights)
            else:
                adversarial = zero
        else:
            if self.config.supervised_form == "sum_mse":  # authors': summed
                supervised = _summed((sample - expert).square(), weights)
            else:
                supervised = weighted_mean((mean - expert).square().sum(-1), weights)
            if self.alpha < 1:
                g = self.rewards(obs[:, None], sample[:, None])[:, 0]
                adversarial = weighted_mean(gaussian_log_prob(sample, mean, log_std) - g, weights)
            else:
                adversarial = zero
        p_loss = (1 - self.alpha) * adversarial + self.alpha * supervised
        self.policy_opt.zero_grad()
        p_loss.sum().backward(inputs=self.policies.params)
        self.policy_opt.step()
        return pack_step(disc_record, StepLosses(p_loss, adversarial, supervised))

    def discrete_seen(
        self, probs: Tensor, mask: Tensor | None, draw: dict[str, Tensor], step: int
    ) -> Tensor:
        """What the discriminator sees of a discrete policy: a sample (or π), plus noise."""
        if self.config.disc_action == "sample":
            seen = sample_one_hot(probs, draw["u"][step])
        else:
            seen = probs
        if self.noisy:
            sigma = draw["sig"][step] if "sig" in draw else self.sigma
            seen = project_to_simplex(seen + sigma[..., None] * draw["eps"][step], mask)
        return seen

    def fast_step(self, batch: Batch, draw: dict[str, Tensor], step: int) -> Tensor:
        """:meth:`step` with the hand-derived gradients of :mod:`pokerirl.irl.fast`."""
        reward: Any = self.rewards.modules[0]  # fast.supports() checked their types
        policy: Any = self.policies.modules[0]
        one = batch.at(0)  # the one run
        obs, expert, mask, env, weights = one.obs, one.expert, one.mask, one.env, one.weights
        acts = fast.mlp_forward(policy.mlp, obs)
        logits = acts[-1] if mask is None else acts[-1].masked_fill(~mask, MASKED_LOGIT)
        log_pi = torch.log_softmax(logits, dim=-1)
        probs = log_pi.exp()
        if self.adversarial:
            seen = self.discrete_seen(probs[None], None if mask is None else mask[None], draw,
                                      step)[0]  # fmt: skip
            lp = torch.cat(((expert * log_pi).sum(-1), (seen * log_pi).sum(-1)))
            cache = fast.reward_forward(reward, obs, torch.stack((expert, seen)))
            f = cache.head_acts[-1].view(-1)
            grad_f = fast.discriminator_grad(f, lp, beta=self.beta, env_reward=env,
                                             weights=weights, discriminator=self.disc)  # fmt: skip
            self.reward_opt.set_grad(fast.reward_backward(reward, cache, grad_f))
            self.reward_opt.step()
            disc_record = torch.cat((f, lp))
        else:
            disc_record = obs.new_zeros(4 * self.batch)
        if self.alpha < 1:
            each = fast.reward_forward(reward, obs, self.each_action).head_acts[-1]
            g = each.view(-1, len(obs)).T
        else:
            g = torch.zeros_like(log_pi)
        self.policy_opt.set_grad(
            fast.policy_backward(policy, acts, log_pi, g, expert, self.alpha, weights=weights)
        )
        self.policy_opt.step()
        supervised = weighted_mean(-(expert * log_pi).sum(-1), weights)
        adversarial = (
            weighted_mean((probs * (log_pi - g)).sum(-1), weights) if self.alpha < 1 else g[0, 0]
        )
        p_loss = (1 - self.alpha) * adversarial + self.alpha * supervised
        return pack_step(disc_record, StepLosses(p_loss, adversarial, supervised))[None]

    def epoch_stats(self, record: Tensor, perm: Tensor) -> dict[str, list[float]]:
        """Epoch means per run of the losses and discriminator accuracies."""
        disc, losses = unpack_steps(record, self.batch)
        f_expert, f_seen = disc.f_expert, disc.f_policy
        lp_expert, lp_seen = disc.log_pi_expert, disc.log_pi_policy
        env = None if self.env is None else self.env[perm]  # (steps, R, B)
        weights = None if self.weights is None else self.weights[perm]
        d_loss, d_airl, d_env = discriminator_loss(
            f_expert, lp_expert, f_seen, lp_seen, beta=self.beta, env_reward=env,
            weights=weights, discriminator=self.disc,
        )  # fmt: skip
        values = {
            "disc_loss": d_loss.mean(0),
            "disc_airl_loss": d_airl.mean(0),
            "disc_env_loss": d_env.mean(0),
            # a logit above 0 is D > 1/2
            "disc_acc_expert": (self.disc.logits(f_expert, lp_expert) > 0).float().mean((0, 2)),
            "disc_acc_policy": (self.disc.logits(f_seen, lp_seen) < 0).float().mean((0, 2)),
            "reward_expert": f_expert.mean((0, 2)),
            "reward_policy": f_seen.mean((0, 2)),
            "reward_gap": (f_expert - f_seen).mean((0, 2)),  # expert minus policy
            **{name: value.mean(0) for name, value in losses._asdict().items()},
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

    def run(
        self,
        *,
        progress: bool,
        on_epoch: Callable[[list[EpochMetrics]], None] | None,
        callback: EpochCallback | None = None,
    ) -> ManyResult:
        results = [
            TrainResult(
                reward=r,
                policy=p,
                config=replace(self.config, seed=s),
                beta_used=self.beta,
                gradients="hand-derived" if self.fast else "autograd",
                samples_per_epoch=self.steps * self.batch,
            )
            for r, p, s in zip(self.rewards.modules, self.policies.modules, self.seeds, strict=True)
        ]
        many = ManyResult(runs=results, epoch_seconds=[], samples_per_epoch=0)
        many.samples_per_epoch = self.runs * self.steps * self.batch
        # Two bars in one run: the behaviour-cloning baseline's, then the adversarial one's.
        label = "IRL (adversarial)" if self.adversarial else "baseline (behaviour cloning)"
        bar = tqdm(
            range(1, self.config.epochs + 1), desc=label, unit="epoch", disable=not progress
        )
        for epoch in bar:
            start = time.perf_counter()
            draw = self.draw_epoch()
            record = torch.empty(self.steps, self.runs, 4 * self.batch + 3, device=self.device)
            batches = self.gather(draw["perm"]) if self.gather_epoch else None
            for step in range(self.steps):
                if batches is not None:
                    batch = batches.at(step)
                else:
                    batch = self.gather(draw["perm"][step])
                if self.fast:
                    with torch.no_grad():
                        record[step] = self.fast_step(batch, draw, step)
                else:
                    record[step] = self.step(batch, draw, step)
            if self.device.type == "cuda":
                torch.cuda.synchronize(self.device)  # time the work, not its queueing
            seconds = time.perf_counter() - start
            many.epoch_seconds.append(seconds)
            self.rewards.write_back()
            self.policies.write_back()
            stats = self.epoch_stats(record, draw["perm"])
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
            if "val_alignment" in first:
                bar.set_postfix(
                    align=f"{first['val_alignment']:.3f}", d_loss=f"{first['disc_loss']:.3f}"
                )
        bar.close()
        for result in results:
            result.reward.eval()
            result.policy.eval()
        return many


def _summed(squares: Tensor, weights: Tensor | None) -> Tensor:
    """(..., B, k) squared errors summed over the batch and k (the authors'
    ``reduction="sum"``); with ``weights``, the weighted mean over the batch times B, so
    that the scale stays a sum's."""
    if weights is None:
        return squares.sum((-2, -1))
    return weighted_mean(squares.sum(-1), weights) * squares.shape[-2]


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
