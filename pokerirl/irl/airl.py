"""AIRL and Hybrid-AIRL, offline over an expert table, on plain tensors.

The whole algorithm is :func:`train`, top to bottom; the losses, their gradient and the
noise schedule are small pure functions above it so they can be checked by hand.

Per shuffled mini-batch of expert rows (s, a_E):

1. the policy acts at s: its distribution π(·|s) for discrete actions, a reparameterized
   sample μ(s) + σε for continuous ones;
2. discriminator step: D(s, a) = exp f(s,a) / (exp f(s,a) + π(a|s)) learns to call
   (s, a_E) expert and (s, ã) policy. ã is the policy's action — for discrete actions the
   one-hot of an action drawn from π, like the expert's one-hots — plus Gaussian noise whose
   σ decays along the batch (projected back onto the simplex, or clipped to the box); H-AIRL
   mixes in β·(f(s, a_E) − r_env)². For a point ã of the simplex,
   log π(ã|s) = Σ_k ã_k log π(k|s), exact on one-hots;
3. policy step, against the just-updated reward:
   (1−α)·E_{a∼π}[−f(s, a) + log π(a|s)] + α·(CE(π(·|s), a_E) or MSE(μ(s), a_E)).
   For discrete actions the expectation is exact, Σ_k π(k|s)·f(s, e_k), from scoring every
   one-hot at each state; for continuous ones it is the reparameterized sample.

Why one-hots, not the distribution π(·|s) itself, go to the discriminator: against the
expert's one-hots a soft vector gives itself away by its softness alone, so f learns to score
"one-hot-ness" instead of which action the expert prefers, and the noise (which turns most
soft vectors into near-vertices) stops helping. On the synthetic demo table this choice moved
H-AIRL's validation alignment from 0.856 to 0.877 and put it above AIRL's (0.856), as the
paper reports.

AIRL is α = 0, β = 0 and no noise; ``AIRLConfig.for_algo`` only picks defaults, both run
this same code. Gradients are hand-derived (see :mod:`pokerirl.irl.nets`), which makes the
loop several times faster than autograd for nets this small; tests check them against
autograd on the loss functions below.

>>> import torch
>>> g = torch.Generator().manual_seed(0)
>>> obs = torch.rand(512, 6, generator=g)
>>> actions = (obs[:, 0] > 0.5).long()            # a toy expert: act 1 when s_0 > 1/2
>>> data = ExpertData.from_action_ids(obs, actions, num_actions=2)
>>> config = AIRLConfig.for_algo("hairl", epochs=20, batch_size=64, alpha=1.0)
>>> result = train(data, data, config=config, progress=False)
>>> result.metrics[-1]["val_alignment"] > 0.9
True
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import torch
from torch import Tensor
from tqdm.auto import tqdm

from pokerirl.irl.nets import DiscretePolicy, GaussianPolicy, Policy, PolicyOutput, RewardNet
from pokerirl.irl.optim import FlatAdam

ALGOS: tuple[str, ...] = ("airl", "hairl")


@dataclass(frozen=True, kw_only=True)
class AIRLConfig:
    """Hyperparameters. The defaults are the H-AIRL paper's reference poker settings.

    >>> AIRLConfig.for_algo("airl").alpha, AIRLConfig.for_algo("hairl").alpha
    (0.0, 0.33)
    """

    reward_hidden: tuple[int, ...] = (64,)
    policy_hidden: tuple[int, ...] = (64,)
    reward_lr: float = 1e-3
    policy_lr: float = 1e-3
    reward_weight_decay: float = 5e-3
    batch_size: int = 256
    epochs: int = 50
    alpha: float = 0.33  # weight of the supervised term in the policy loss
    beta: float = 0.0  # weight of the (f - r_env)² term in the discriminator loss
    sigma_start: float = 1.0  # noise σ on the first sample of a batch (in action ranges)
    sigma_end: float = 0.1  # ... and on the last
    val_fraction: float = 0.1  # share of hands held out (used by the table front end)
    seed: int = 0

    def __post_init__(self) -> None:
        # TOML and JSON give lists; keep the dataclass hashable and comparable.
        object.__setattr__(self, "reward_hidden", tuple(int(w) for w in self.reward_hidden))
        object.__setattr__(self, "policy_hidden", tuple(int(w) for w in self.policy_hidden))
        checks = {
            "batch_size >= 1": self.batch_size >= 1,
            "epochs >= 1": self.epochs >= 1,
            "0 <= alpha <= 1": 0 <= self.alpha <= 1,
            "0 <= beta <= 1": 0 <= self.beta <= 1,
            "sigma_start >= sigma_end >= 0": self.sigma_start >= self.sigma_end >= 0,
            "0 < val_fraction < 1": 0 < self.val_fraction < 1,
            "learning rates > 0": self.reward_lr > 0 and self.policy_lr > 0,
            "reward_weight_decay >= 0": self.reward_weight_decay >= 0,
            "hidden widths >= 1": all(w >= 1 for w in self.reward_hidden + self.policy_hidden),
            "a reward hidden layer": len(self.reward_hidden) >= 1,
        }
        broken = [name for name, ok in checks.items() if not ok]
        if broken:
            raise ValueError(f"invalid AIRL config: need {', '.join(broken)}")

    @classmethod
    def for_algo(cls, algo: str, **overrides: Any) -> AIRLConfig:
        """Defaults for ``"airl"`` (α = β = 0, no noise) or ``"hairl"``, then ``overrides``.

        Unknown keys raise ``ValueError`` naming them.
        """
        if algo not in ALGOS:
            raise ValueError(f"unknown algo {algo!r}; choose one of {', '.join(ALGOS)}")
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(overrides) - known)
        if unknown:
            raise ValueError(f"unknown setting(s) {', '.join(unknown)}; known: {sorted(known)}")
        base: dict[str, Any] = {}
        if algo == "airl":
            base = {"alpha": 0.0, "beta": 0.0, "sigma_start": 0.0, "sigma_end": 0.0}
        return cls(**{**base, **overrides})


@dataclass(frozen=True, kw_only=True)
class ExpertData:
    """Expert rows as tensors: the trainer knows nothing about poker.

    ``actions`` are action *vectors*: one-hots for discrete actions, values for continuous
    ones. ``legal_mask`` (discrete only) and ``rewards`` are optional.
    """

    obs: Tensor  # (N, obs_dim), any dtype; converted to float per batch
    actions: Tensor  # (N, action_dim) float
    legal_mask: Tensor | None = None  # (N, num_actions) bool
    rewards: Tensor | None = None  # (N,) float
    discrete: bool = True
    action_low: tuple[float, ...] | None = None  # continuous bounds
    action_high: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        n = len(self.obs)
        if self.obs.ndim != 2 or self.actions.ndim != 2 or len(self.actions) != n:
            raise ValueError("ExpertData needs obs (N, d) and action vectors (N, k)")
        for name in ("legal_mask", "rewards"):
            value = getattr(self, name)
            if value is not None and len(value) != n:
                raise ValueError(f"ExpertData.{name} has {len(value)} rows, obs has {n}")

    @classmethod
    def from_action_ids(
        cls,
        obs: Tensor,
        action_ids: Tensor,
        *,
        num_actions: int,
        legal_mask: Tensor | None = None,
        rewards: Tensor | None = None,
    ) -> ExpertData:
        """Discrete actions given as ids (N,)."""
        one_hot = torch.nn.functional.one_hot(action_ids.long(), num_actions).float()
        return cls(obs=obs, actions=one_hot, legal_mask=legal_mask, rewards=rewards)

    @classmethod
    def from_continuous(
        cls,
        obs: Tensor,
        actions: Tensor,
        *,
        low: Sequence[float],
        high: Sequence[float],
        rewards: Tensor | None = None,
    ) -> ExpertData:
        """Continuous actions (N, k) inside the box [low, high]."""
        return cls(
            obs=obs,
            actions=actions.float().reshape(len(actions), -1),
            rewards=rewards,
            discrete=False,
            action_low=tuple(float(x) for x in low),
            action_high=tuple(float(x) for x in high),
        )

    def __len__(self) -> int:
        return len(self.obs)

    @property
    def obs_dim(self) -> int:
        return self.obs.shape[1]

    @property
    def action_dim(self) -> int:
        return self.actions.shape[1]

    def subset(self, index: Tensor) -> ExpertData:
        """Rows ``index`` (a long tensor or bool mask)."""
        pick = lambda t: None if t is None else t[index]  # noqa: E731
        return dataclasses.replace(
            self,
            obs=self.obs[index],
            actions=self.actions[index],
            legal_mask=pick(self.legal_mask),
            rewards=pick(self.rewards),
        )

    def to(self, device: torch.device | str) -> ExpertData:
        move = lambda t: None if t is None else t.to(device)  # noqa: E731
        return dataclasses.replace(
            self,
            obs=self.obs.to(device),
            actions=self.actions.to(device),
            legal_mask=move(self.legal_mask),
            rewards=move(self.rewards),
        )


# --------------------------------------------------------------------------- losses


def noise_schedule(batch_size: int, sigma_start: float, sigma_end: float) -> Tensor:
    """σ_i for the i-th sample of a shuffled batch: linear from σ_start down to σ_end.

    >>> noise_schedule(5, 1.0, 0.2)
    tensor([1.0000, 0.8000, 0.6000, 0.4000, 0.2000])
    """
    if batch_size == 1:
        return torch.tensor([sigma_start])
    return torch.linspace(sigma_start, sigma_end, batch_size)


def log_discriminator(f: Tensor, log_pi: Tensor) -> tuple[Tensor, Tensor]:
    """(log D, log(1 − D)) for D = e^f / (e^f + π), via a two-term logsumexp.

    >>> log_d, log_not_d = log_discriminator(torch.tensor([0.0]), torch.tensor([0.0]))
    >>> round(log_d.exp().item(), 3), round(log_not_d.exp().item(), 3)
    (0.5, 0.5)
    """
    log_norm = torch.logaddexp(f, log_pi)
    return f - log_norm, log_pi - log_norm


def discriminator_loss(
    f_expert: Tensor,
    log_pi_expert: Tensor,
    f_policy: Tensor,
    log_pi_policy: Tensor,
    *,
    beta: float = 0.0,
    env_reward: Tensor | None = None,
) -> tuple[Tensor, Tensor]:
    """(1−β)·L_AIRL + β·E_E[(f(s, a_E) − r_env)²]; returns (total, L_AIRL).

    L_AIRL = −E_E[log D(s, a_E)] − E_π[log(1 − D(s, ã))].
    """
    log_d_expert, _ = log_discriminator(f_expert, log_pi_expert)
    _, log_not_d_policy = log_discriminator(f_policy, log_pi_policy)
    airl = -log_d_expert.mean() - log_not_d_policy.mean()
    if beta == 0.0 or env_reward is None:
        return airl, airl
    regression = (f_expert - env_reward).square().mean()
    return (1 - beta) * airl + beta * regression, airl


def policy_loss(
    f_policy: Tensor, log_pi_policy: Tensor, supervised: Tensor, *, alpha: float
) -> tuple[Tensor, Tensor]:
    """(1−α)·E_π[−f(s, a) + log π(a|s)] + α·supervised; returns (total, adversarial part).

    ``f_policy`` and ``log_pi_policy`` are per-state expectations under π.
    """
    adversarial = (log_pi_policy - f_policy).mean()
    return (1 - alpha) * adversarial + alpha * supervised, adversarial


def discriminator_grad(
    f: Tensor, log_pi: Tensor, *, beta: float = 0.0, env_reward: Tensor | None = None
) -> Tensor:
    """dL/df of :func:`discriminator_loss` for ``f`` = (expert rows, then as many policy rows).

    With D = σ(f − log π) (the log-space form of the ratio): d/df of −log D is D − 1 and
    of −log(1 − D) is D.
    """
    batch = len(f) // 2
    grad = torch.sigmoid(f - log_pi)
    grad[:batch] -= 1
    if beta == 0.0 or env_reward is None:
        return grad / batch
    grad *= (1 - beta) / batch
    grad[:batch] += (2 * beta / batch) * (f[:batch] - env_reward)
    return grad


def _expected_reward_and_grad(
    reward_net: RewardNet, policy: Policy, obs: Tensor, out: PolicyOutput, grad_f: Tensor
) -> tuple[Tensor, Tensor]:
    """E_{a∼π}[f(s, a)] per state, and ``grad_f``-weighted d/d(action vector) of it.

    Discrete: f on every one-hot e_k, so E = Σ_k π_k f(s, e_k) and d/dπ_k = f(s, e_k).
    Continuous: f at the reparameterized sample, differentiated through f's input.
    """
    if policy.discrete:
        f_each = reward_net.forward_each_action(obs)
        return (f_each * out.action).sum(dim=1), f_each * grad_f[:, None]
    f_pi, cache = reward_net.forward_cached(obs, out.action)
    _, grad_action = reward_net.backward(cache, grad_f, params=False)
    assert grad_action is not None
    return f_pi, grad_action


# --------------------------------------------------------------------------- training


@dataclass
class TrainResult:
    """What :func:`train` returns: the trained nets and one metrics dict per epoch."""

    reward_net: RewardNet
    policy: Policy
    config: AIRLConfig
    beta_used: float  # β actually used: 0 when the data has no rewards
    metrics: list[dict[str, Any]] = field(default_factory=list)
    epoch_seconds: list[float] = field(default_factory=list)  # optimization only, no evaluation
    samples_per_epoch: int = 0

    @property
    def samples_per_second(self) -> float:
        """Training throughput: expert samples per second of optimization steps."""
        seconds = sum(self.epoch_seconds)
        return self.samples_per_epoch * len(self.epoch_seconds) / seconds if seconds else math.nan


def build_nets(data: ExpertData, config: AIRLConfig) -> tuple[RewardNet, Policy]:
    """A fresh reward net and a policy matching ``data``'s action space."""
    reward_net = RewardNet(
        obs_dim=data.obs_dim, action_dim=data.action_dim, hidden=config.reward_hidden
    )
    policy: Policy
    if data.discrete:
        policy = DiscretePolicy(
            obs_dim=data.obs_dim, num_actions=data.action_dim, hidden=config.policy_hidden
        )
    else:
        assert data.action_low is not None and data.action_high is not None
        policy = GaussianPolicy(
            obs_dim=data.obs_dim,
            low=data.action_low,
            high=data.action_high,
            hidden=config.policy_hidden,
        )
    return reward_net, policy


@torch.no_grad()  # gradients are hand-derived (see pokerirl.irl.nets), not autograd's
def train(
    train_data: ExpertData,
    val_data: ExpertData,
    *,
    config: AIRLConfig,
    device: str | torch.device = "cpu",
    progress: bool = True,
    on_epoch: Callable[[dict[str, Any]], None] | None = None,
) -> TrainResult:
    """Train a reward net and a policy on ``train_data``; evaluate on ``val_data`` each epoch.

    Deterministic on CPU for a given config (seed) and data. ``on_epoch`` gets each epoch's
    metrics dict as soon as it is ready (for live logging).
    """
    device = resolve_device(device)
    if len(train_data) == 0 or len(val_data) == 0:
        raise ValueError("training and validation data must both be non-empty")
    torch.manual_seed(config.seed)  # network initialization
    gen = torch.Generator(device=device).manual_seed(config.seed)  # shuffling and noise
    reward_net, policy = build_nets(train_data, config)
    reward_net.to(device)
    policy.to(device)
    # Created after .to(device): FlatAdam moves the parameters into one buffer.
    reward_opt = FlatAdam(
        reward_net.parameters(), lr=config.reward_lr, weight_decay=config.reward_weight_decay
    )
    policy_opt = FlatAdam(policy.parameters(), lr=config.policy_lr)

    data = train_data.to(device)
    val = val_data.to(device)
    beta = config.beta if data.rewards is not None else 0.0
    alpha = config.alpha
    n, batch = len(data), min(config.batch_size, len(data))
    steps = n // batch  # drop the ragged tail; the next shuffle covers it
    sigma = noise_schedule(batch, config.sigma_start, config.sigma_end).to(device)
    grad_f_pi = torch.full((batch,), -(1 - alpha) / batch, device=device)  # d policy loss/d f
    result = TrainResult(
        reward_net=reward_net,
        policy=policy,
        config=config,
        beta_used=beta,
        samples_per_epoch=steps * batch,
    )
    # Per-step values for the epoch's metrics, written in place: no .item() sync per step.
    # Row layout: f (expert, policy), log π (expert, policy), f(s, π), log π(π), supervised.
    record = torch.empty(steps, 7 * batch, device=device)

    # Inference mode skips autograd's bookkeeping on every small op (about 15% faster here).
    # The nets, the optimizer buffers and ``record`` were made outside it, so they stay
    # ordinary tensors, updated in place, that autograd can still use after training.
    with torch.inference_mode():
        bar = tqdm(range(1, config.epochs + 1), desc="train", unit="epoch", disable=not progress)
        for epoch in bar:
            start = time.perf_counter()
            # Shuffle once per epoch with one gather; batches are then contiguous slices.
            shuffled = data.subset(torch.randperm(n, generator=gen, device=device))
            for step in range(steps):
                rows = slice(step * batch, (step + 1) * batch)
                obs = shuffled.obs[rows].float()
                expert_action = shuffled.actions[rows]
                mask = None if shuffled.legal_mask is None else shuffled.legal_mask[rows]
                env_reward = None if shuffled.rewards is None else shuffled.rewards[rows]

                # 1. the policy at s: π(·|s), or a reparameterized sample
                out = policy.act(obs, mask, gen)

                # 2. discriminator step: expert (s, a_E) against the regularized policy (s, ã)
                noisy = policy.sample_action(out, gen)
                if config.sigma_start > 0:
                    noisy = policy.perturb(noisy, sigma, mask, gen)
                both = torch.cat((expert_action, noisy))
                log_pi = policy.log_prob(out.dist, both.view(2, batch, -1)).view(-1)
                f, cache = reward_net.forward_cached(obs, both)
                grad_f = discriminator_grad(f, log_pi, beta=beta, env_reward=env_reward)
                reward_opt.step(reward_net.backward(cache, grad_f, actions=False)[0])

                # 3. policy step against the updated reward:
                #    (1−α)·E_π[−f(s, a) + log π] + α·supervised
                f_pi, grad_action = _expected_reward_and_grad(
                    reward_net, policy, obs, out, grad_f_pi
                )
                policy_opt.step(policy.backward(out, grad_action, expert_action, alpha))

                supervised = policy.supervised_loss(out.dist, expert_action)
                torch.cat((f, log_pi, f_pi, out.log_prob, supervised), out=record[step])

            if device.type == "cuda":
                torch.cuda.synchronize(device)  # time the work, not its queueing
            result.epoch_seconds.append(time.perf_counter() - start)
            metrics: dict[str, Any] = {"epoch": epoch}
            metrics.update(_step_metrics(record, shuffled.rewards, beta=beta, alpha=alpha))
            metrics.update(evaluate(policy, val, majority_from=data))
            result.metrics.append(metrics)
            if on_epoch is not None:
                on_epoch(metrics)
            if "val_alignment" in metrics:
                bar.set_postfix(
                    align=f"{metrics['val_alignment']:.3f}", d_loss=f"{metrics['disc_loss']:.3f}"
                )
    bar.close()
    reward_net.eval()
    policy.eval()
    return result


def _step_metrics(
    record: Tensor, rewards: Tensor | None, *, beta: float, alpha: float
) -> dict[str, float]:
    """Epoch means of the training losses and discriminator accuracies, from ``record``."""
    steps, width = record.shape
    f_expert, f_policy, log_pi_expert, log_pi_policy, f_pi, log_pi_pi, supervised = (
        part.reshape(-1) for part in record.view(steps, 7, width // 7).unbind(dim=1)
    )
    env_reward = None if rewards is None else rewards[: len(f_expert)]
    d_loss, d_airl = discriminator_loss(
        f_expert, log_pi_expert, f_policy, log_pi_policy, beta=beta, env_reward=env_reward
    )
    p_loss, p_adv = policy_loss(f_pi, log_pi_pi, supervised.mean(), alpha=alpha)
    values = {
        "disc_loss": d_loss,
        "disc_airl_loss": d_airl,
        "policy_loss": p_loss,
        "policy_adv_loss": p_adv,
        "policy_sup_loss": supervised.mean(),
        "disc_acc_expert": (f_expert > log_pi_expert).float().mean(),  # D > 1/2
        "disc_acc_policy": (f_policy < log_pi_policy).float().mean(),  # D < 1/2
        "reward_expert": f_expert.mean(),
        "reward_policy": f_policy.mean(),
    }
    return dict(zip(values, torch.stack(list(values.values())).tolist(), strict=True))


@torch.inference_mode()
def evaluate(
    policy: Policy, val: ExpertData, *, majority_from: ExpertData, chunk: int = 65536
) -> dict[str, Any]:
    """Validation metrics.

    Discrete: ``val_alignment`` (share of states where argmax π is the expert's action),
    ``majority_alignment`` (always the training set's most common expert action), and the
    validation action distributions: ``val_policy_dist`` (mean π), ``val_policy_argmax_dist``
    and ``val_expert_dist``. Continuous: ``val_mse`` of the mean action.
    """
    policy.eval()
    outs = [
        policy(
            val.obs[i : i + chunk].float(),
            None if val.legal_mask is None else val.legal_mask[i : i + chunk],
        )
        for i in range(0, len(val), chunk)
    ]
    out = torch.cat(outs)
    if not policy.discrete:
        mse = (policy.predict(out) - val.actions).square().sum(dim=-1).mean()
        return {"val_mse": mse.item()}
    num_actions = val.actions.shape[1]
    expert_ids = val.actions.argmax(dim=-1)
    predicted = policy.predict(out)
    majority = majority_from.actions.sum(dim=0).argmax()
    return {
        "val_alignment": (predicted == expert_ids).float().mean().item(),
        "majority_alignment": (expert_ids == majority).float().mean().item(),
        "val_policy_dist": out.exp().mean(dim=0).tolist(),
        "val_policy_argmax_dist": _histogram(predicted, num_actions),
        "val_expert_dist": _histogram(expert_ids, num_actions),
    }


def _histogram(ids: Tensor, num_actions: int) -> list[float]:
    return (torch.bincount(ids, minlength=num_actions).float() / max(len(ids), 1)).tolist()


def resolve_device(device: str | torch.device) -> torch.device:
    """``torch.device(device)``, with a clear ``ValueError`` when CUDA isn't available."""
    try:
        resolved = torch.device(device)
    except RuntimeError as error:
        raise ValueError(f"unknown device {device!r}: {error}") from None
    if resolved.type == "cuda" and not torch.cuda.is_available():
        raise ValueError("device 'cuda' requested but CUDA is not available on this machine")
    if resolved.type not in ("cpu", "cuda"):
        raise ValueError(f"unsupported device {device!r}; use cpu or cuda")
    return resolved
