"""Online adversarial IRL: a generator policy acts in its environment on the current learned
reward, and the discriminator sees the states the generator reaches (the ``imitation``
library's AIRL and GAIL; the offline trainer, :mod:`pokerirl.irl.trainer`, draws the policy's
actions at the expert's own states instead).

One round of :meth:`OnlineTrainer.round`, top to bottom:

1. the :class:`Generator` collects N steps with its current policy (a :class:`Rollout`);
2. the discriminator (the reward net f) takes one pass of mini-batches of expert rows
   against generator rows, with the offline trainer's
   :class:`~pokerirl.irl.discriminators.Discriminator` (AIRL: D = exp f / (exp f + π), π the
   generator's probability; GAIL: D = σ(f)) and
   :func:`~pokerirl.irl.losses.discriminator_loss`; H-AIRL's noise (σ decaying along each
   mini-batch, :func:`~pokerirl.irl.losses.noise_schedule`) is added to the generator's
   actions before the discriminator sees them, and β weighs the env-reward term as offline;
3. the generator's transitions are relabelled with the updated f(s, a);
4. the generator learns from them (PPO in :mod:`pokerirl.gym.online`);
5. H-AIRL (α > 0): one extra gradient step on the generator's policy, −α·E_E[log π(a_E|s_E)]
   on an expert mini-batch.

This module knows nothing of Gymnasium or SB3: a :class:`Generator` is anything with these
four methods. Seeded: the discriminator's shuffles and noise come from one
``torch.Generator`` per trainer.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import torch
from torch import Tensor, nn

from pokerirl.errors import ConfigError, InputError
from pokerirl.execution import unit_progress
from pokerirl.irl.config import AIRLConfig, NoiseForm, NoiseSchedule
from pokerirl.irl.discriminators import Discriminator, discriminator_for
from pokerirl.irl.evaluate import evaluate
from pokerirl.irl.losses import discriminator_loss, noise_schedule
from pokerirl.irl.metrics import Metric
from pokerirl.irl.nets import RewardFamily, project_to_simplex
from pokerirl.irl.optim import FlatAdam
from pokerirl.irl.records import EpochCallback, EpochMetrics, EpochRecord
from pokerirl.irl.trainer import TrainResult
from pokerirl.irl.transitions import Transitions


@dataclass(frozen=True, kw_only=True)
class Rollout:
    """N steps of the generator: its ``transitions`` (observations as the reward net sees
    them, actions as the environment executed them) and ``log_probs`` (N,), the generator's
    log π of its own actions when it drew them (for a box, of the draw before the env clipped
    it): the discriminator's π of the generator's rows when no noise is added."""

    transitions: Transitions
    log_probs: Tensor


@runtime_checkable
class Generator(Protocol):
    """A policy that acts in an environment and learns from relabelled transitions."""

    def collect(self, steps: int) -> Rollout:
        """``steps`` environment steps with the current policy."""
        ...

    def log_prob(self, obs: Tensor, actions: Tensor, legal_mask: Tensor | None = None) -> Tensor:
        """The current policy's log π (B,) of action vectors (B, k) at ``obs`` (B, d):
        one-hots or simplex points (Σ_k a_k log π_k) for discrete actions, values for a box;
        π over the legal actions only where ``legal_mask`` (B, k) is given (as the rollout's
        own log-probs are), so that expert and generator rows are scored alike."""
        ...

    def learn(self, rollout: Rollout, rewards: Tensor) -> Mapping[str, float]:
        """Learn from ``rollout`` with ``rewards`` (N,) in place of the environment's; the
        generator's own metrics."""
        ...

    def imitate(
        self, obs: Tensor, actions: Tensor, *, weight: float, legal_mask: Tensor | None = None
    ) -> float:
        """One gradient step on −weight·mean log π(actions|obs) (actions and ``legal_mask``
        as in :meth:`log_prob`); the loss before the step."""
        ...

    def policy_net(self) -> nn.Module:
        """The current policy as a :mod:`pokerirl.irl.nets` policy (what a run saves)."""
        ...


class OnlineTrainer:
    """One run of online AIRL, H-AIRL or GAIL: ``reward`` (f, trained in place) against
    ``generator`` on ``demonstrations``, ``generator_steps`` environment steps a round."""

    def __init__(
        self,
        *,
        demonstrations: Transitions,
        validation: Transitions,
        generator: Generator,
        reward: nn.Module,
        config: AIRLConfig,
        generator_steps: int,
        discriminator: Discriminator | None = None,
    ) -> None:
        if len(demonstrations) == 0 or len(validation) == 0:
            raise InputError("training and validation data must both be non-empty")
        if config.reward_family != RewardFamily.STATE_ACTION:
            raise ConfigError("online IRL learns the state_action reward family only")
        if demonstrations.weights is not None:
            # Offline, a row's weight counts its expert and policy terms at the same state;
            # online the generator's states are its own, so a weight has nothing to pair with.
            raise InputError("online IRL takes demonstrations without row weights")
        if generator_steps < 1:
            raise ConfigError("generator_steps must be at least 1")
        if not isinstance(generator, Generator):
            raise TypeError("generator must have collect, log_prob, learn, imitate, policy_net")
        self.data, self.val, self.config = demonstrations, validation, config
        self.generator, self.reward = generator, reward
        self.steps = generator_steps
        self.discriminator = discriminator or discriminator_for(config.discriminator)
        self.rng = torch.Generator().manual_seed(config.seed)
        self.expert = demonstrations.action_vectors()
        self.beta = config.beta if demonstrations.rewards is not None else 0.0
        self.batch = min(config.batch_size, generator_steps)
        self.sigma = noise_schedule(
            self.batch,
            config.sigma_start,
            config.sigma_end,
            kind=config.noise_schedule,
            decay=config.noise_decay,
        )
        self.noisy = config.sigma_start > 0
        self.reward_opt = FlatAdam(
            reward.parameters(), lr=config.reward_lr, weight_decay=config.reward_weight_decay
        )

    # ------------------------------------------------------------------ one round

    def round(self) -> dict[str, float]:
        """Collect, update the discriminator, relabel, update the generator: the round's
        metrics."""
        rollout = self.generator.collect(self.steps)
        metrics = self.update_discriminator(rollout)
        rewards = self.relabel(rollout)
        metrics.update(self.generator.learn(rollout, rewards))
        if self.config.alpha > 0:
            metrics[Metric.POLICY_SUP_LOSS] = self.imitate()
        metrics["reward_policy_relabelled"] = float(rewards.mean())
        return metrics

    def update_discriminator(self, rollout: Rollout) -> dict[str, float]:
        """One pass over the generator's rows in mini-batches, each against as many expert
        rows drawn at random; the pass's mean losses and accuracies."""
        generated = rollout.transitions
        gen_actions = generated.action_vectors()
        perm = torch.randperm(len(generated), generator=self.rng)
        sums: dict[str, float] = {}
        batches = len(generated) // self.batch  # a ragged tail is left out, as offline
        for b in range(batches):
            rows = perm[b * self.batch : (b + 1) * self.batch]
            picks = torch.randint(len(self.data), (self.batch,), generator=self.rng)
            obs_e, act_e = self.data.obs[picks], self.expert[picks]
            mask_e = None if self.data.legal_mask is None else self.data.legal_mask[picks]
            mask_g = None if generated.legal_mask is None else generated.legal_mask[rows]
            obs_g, act_g = self.discriminator_inputs(generated.obs[rows], gen_actions[rows],
                                                     mask_g)  # fmt: skip
            with torch.no_grad():  # π is the generator's; only f learns here
                log_pi_e = self.generator.log_prob(obs_e, act_e, mask_e)
                if self.noisy:  # π of the noised action the discriminator sees
                    log_pi_g = self.generator.log_prob(obs_g, act_g, mask_g)
                else:  # its own draw's, kept by the rollout (it has not learned since)
                    log_pi_g = rollout.log_probs[rows]
            f_e, f_g = self.reward(obs_e, act_e), self.reward(obs_g, act_g)
            env = None if self.data.rewards is None else self.data.rewards[picks]
            loss, airl, env_loss = discriminator_loss(
                f_e, log_pi_e, f_g, log_pi_g, beta=self.beta, env_reward=env,
                discriminator=self.discriminator,
            )  # fmt: skip
            self.reward_opt.zero_grad()
            loss.backward()
            self.reward_opt.step()
            logits = self.discriminator.logits
            step = {
                Metric.DISC_LOSS: loss, Metric.DISC_AIRL_LOSS: airl,
                Metric.DISC_ENV_LOSS: env_loss,
                Metric.DISC_ACC_EXPERT: (logits(f_e, log_pi_e) > 0).float().mean(),
                Metric.DISC_ACC_POLICY: (logits(f_g, log_pi_g) < 0).float().mean(),
                Metric.REWARD_EXPERT: f_e.mean(), Metric.REWARD_POLICY: f_g.mean(),
                Metric.REWARD_GAP: f_e.mean() - f_g.mean(),
            }  # fmt: skip
            for key, value in step.items():
                sums[key] = sums.get(key, 0.0) + float(value.detach())
        return {key: value / max(batches, 1) for key, value in sums.items()}

    def discriminator_inputs(
        self, obs: Tensor, actions: Tensor, legal_mask: Tensor | None = None
    ) -> tuple[Tensor, Tensor]:
        """The generator's rows as the discriminator sees them: H-AIRL's noise on the actions
        (σ decaying along the mini-batch, the authors' schedule shuffled), as offline: a
        discrete action's one-hot noised and projected back onto the simplex, a box action
        noised in units of the box and clipped (the authors' form: in units of ``high``,
        unclipped)."""
        if not self.noisy:
            return obs, actions
        sigma = self.sigma
        if self.config.noise_schedule == NoiseSchedule.AUTHORS:
            sigma = sigma[torch.rand(len(sigma), generator=self.rng).argsort()]
        noise = sigma[:, None] * torch.randn(actions.shape, generator=self.rng)
        if self.data.discrete:
            return obs, project_to_simplex(actions + noise, legal_mask)  # legal ones, as offline
        low = torch.tensor(self.data.action_low)
        high = torch.tensor(self.data.action_high)
        if self.config.noise_form == NoiseForm.AUTHORS:
            return obs, actions + noise * high
        return obs, torch.maximum(torch.minimum(actions + noise * (high - low), high), low)

    def relabel(self, rollout: Rollout) -> Tensor:
        """The learned reward f(s, a) (N,) of the generator's transitions."""
        generated = rollout.transitions
        with torch.no_grad():
            return self.reward(generated.obs, generated.action_vectors())

    def imitate(self) -> float:
        """H-AIRL's supervised term on the generator: one step on an expert mini-batch."""
        picks = torch.randint(len(self.data), (self.batch,), generator=self.rng)
        mask = None if self.data.legal_mask is None else self.data.legal_mask[picks]
        return self.generator.imitate(
            self.data.obs[picks], self.expert[picks], weight=self.config.alpha, legal_mask=mask
        )

    # ------------------------------------------------------------------ the loop

    def train(
        self,
        rounds: int,
        *,
        on_round: Callable[[EpochMetrics], None] | None = None,
        callback: EpochCallback | None = None,
    ) -> TrainResult:
        """``rounds`` rounds; after each, ``callback`` may add
        metrics (an :class:`EpochCallback`, as offline), then ``on_round`` gets the line."""
        policy = self.generator.policy_net()
        result = TrainResult(
            reward=self.reward,
            policy=policy,
            config=replace(self.config, epochs=rounds),
            beta_used=self.beta,
            samples_per_epoch=self.steps,
        )
        for number in range(1, rounds + 1):
            began = time.perf_counter()
            metrics: dict[str, object] = {"epoch": number, **self.round()}
            seconds = time.perf_counter() - began
            policy.load_state_dict(self.generator.policy_net().state_dict())
            policy.eval()
            self.reward.eval()
            metrics.update(evaluate(self.reward, policy, self.val))
            if callback is not None:
                record = EpochRecord(
                    epoch=number,
                    metrics=(dict(metrics),),
                    rewards=(self.reward,),
                    policies=(policy,),
                    seconds=seconds,
                )
                extras = list(callback(record) or [{}])
                metrics.update(extras[0])
            self.reward.train()
            line = EpochMetrics.from_json(metrics)
            result.metrics.append(line)
            result.epoch_seconds.append(seconds)
            if on_round is not None:
                on_round(line)
            unit_progress(number, rounds)
        self.reward.eval()
        return result


def train_online_run(
    folder: Path,
    *,
    demonstrations: Transitions,
    validation: Transitions,
    val_groups: Sequence[Any],
    baselines: Mapping[str, float],
    config: AIRLConfig,
    make_generator: Callable[..., Generator],
    rounds: int,
    generator_steps: int,
    on_round: Callable[[EpochMetrics], None] | None = None,
    callback: EpochCallback | None = None,
) -> TrainResult:
    """One online run into ``folder``, as both online commands train theirs: the folder begun
    (split, baselines, a live ``metrics.jsonl``), the default nets from ``config.seed``, the
    generator ``make_generator(reward=, policy=)`` makes of them, ``rounds`` rounds. The caller
    saves the result (:func:`~pokerirl.irl.run.save_run`) after what it adds (a fold of the
    observations' map)."""
    from pokerirl.irl.adversarial import default_nets
    from pokerirl.irl.run import begin_run

    log = begin_run(folder, val_groups=val_groups, baselines=baselines)
    reward, policy = default_nets(demonstrations, config, config.seed)
    trainer = OnlineTrainer(
        demonstrations=demonstrations, validation=validation,
        generator=make_generator(reward=reward, policy=policy), reward=reward, config=config,
        generator_steps=generator_steps,
    )  # fmt: skip

    def write(line: EpochMetrics) -> None:
        log.write(line)
        if on_round is not None:
            on_round(line)

    return trainer.train(rounds, on_round=write, callback=callback)
