"""PPO for R runs in lock-step: stacked parameters (R, in, out) (``pokerirl.stacking``).

Follows SB3 2.9's PPO (ppo.py, on_policy_algorithm.py, buffers.py, policies.py) for the settings
``pokerirl.gym.presets.PPOSettings`` uses: GAE(lambda) as ``RolloutBuffer``, advantage
normalisation per minibatch (``(a - mean) / (std + 1e-8)``, unbiased std), clipped surrogate,
value loss ``mse(returns, values)`` (``clip_range_vf`` None), ent_coef, vf_coef, per-run
``clip_grad_norm_`` (``max_norm / (norm + 1e-6)`` clamped at 1), Adam with eps 1e-5, separate
pi/vf MLPs, tanh or leaky_relu, ``log_std_init``, ortho init (gains sqrt(2), 0.01, 1), Box
actions clipped at the env but not in the log-prob, and the timeout bootstrap
(``reward += gamma * V(terminal_obs)`` where an episode was truncated, not terminated).
Envs are stepped as SB3's DummyVecEnv steps them (auto-reset, ``terminal_observation``).

Where it differs from SB3, and why:
- Random streams. Each run draws actions, minibatch permutations and initial weights from its
  own generators seeded by its seed, not from torch's and numpy's global ones, so that run r of a
  group equals a group of one with seed r. Same distributions, different draws: a lock-step
  run with seed s is not bit-equal to SB3 with seed s.
- Action sampling uses inverse-CDF (discrete) or ``mean + std * normal`` (Box) from numpy draws;
  the same distributions as SB3's ``Categorical`` / ``Normal`` samplers.
- Adam over the stacked tensors (``pokerirl.stacking.StackedAdam``): Adam is element-wise, so
  one Adam over (R, ...) tensors is R per-run Adams (same step counts: every run steps at every
  minibatch). All parameters live in one (R, P) buffer (``Flat.RUNS``: the layers' weights are
  views into it, their grads views into a second one), so the per-run grad norm and the clip
  are two ops, and torch's fused Adam one, per minibatch, whatever the number of layers (the
  update's speed, issue 19). The per-run norm is taken over the whole buffer, not as
  ``clip_grad_norm_``'s norm of per-layer norms: equal up to float rounding.
- One loss, the sum of the R runs' losses: runs share no parameters, so each run's gradient is
  its own loss's gradient.
- Only ``MlpPolicy`` on flat Box observations, Discrete or Box actions, a constant learning rate,
  no target_kl, no SDE, no observation normalisation: what the presets use.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
import torch

from pokerirl.gym.presets import PPOSettings
from pokerirl.irl.reward import RewardFn
from pokerirl.stacking import (
    Flat,
    Product,
    StackedAdam,
    StackedLinear,
    clip_grad_norm_per_run,
    init_linears,
)


class _Tanh(torch.autograd.Function):
    """tanh as ``2 sigmoid(2x) - 1``: equal to ``torch.tanh`` within 2e-7, and several times
    faster on CPU, where torch's tanh kernel was a fifth of the update (issue 19)."""

    @staticmethod
    def forward(ctx: Any, x: torch.Tensor) -> torch.Tensor:
        y = torch.sigmoid(x * 2).mul_(2).sub_(1)
        ctx.save_for_backward(y)
        return y

    @staticmethod
    def backward(ctx: Any, grad: torch.Tensor) -> torch.Tensor:
        (y,) = ctx.saved_tensors
        return torch.ops.aten.tanh_backward(grad, y)


def fast_tanh(x: torch.Tensor) -> torch.Tensor:
    return _Tanh.apply(x)


@dataclass(frozen=True, kw_only=True)
class _Arch:
    obs_dim: int
    hidden: tuple[int, ...]
    discrete: bool
    act_dim: int  # number of actions (discrete) or action dims (Box)


def _layer_names(arch: _Arch) -> list[tuple[str, int, int, float]]:
    """SB3 state_dict prefixes, sizes and ortho gains, in SB3's construction order."""
    names = []
    for net in ("policy_net", "value_net"):
        n_in = arch.obs_dim
        for i, h in enumerate(arch.hidden):
            names.append((f"mlp_extractor.{net}.{2 * i}", n_in, h, math.sqrt(2)))
            n_in = h
    last = arch.hidden[-1] if arch.hidden else arch.obs_dim
    names.append(("action_net", last, arch.act_dim, 0.01))
    names.append(("value_net", last, 1, 1.0))
    return names


class StackedPolicy(torch.nn.Module):
    """R actor-critics with SB3 MlpPolicy's layout (separate pi and vf MLPs).

    ``ordered``: the parameters in SB3's order, the order of the optimizer's flat buffer.
    """

    def __init__(self, arch: _Arch, *, activation: str, weights: list[dict[str, torch.Tensor]],
                 log_std: torch.Tensor | None) -> None:
        super().__init__()
        self.arch = arch
        self.act = fast_tanh if activation == "tanh" else torch.nn.functional.leaky_relu
        self.names = [name for name, *_ in _layer_names(arch)]
        self.layers = torch.nn.ModuleDict()
        for name in self.names:
            # (R, in, out) weights; one output as a row-wise dot product (see Product).
            self.layers[name.replace(".", "_")] = StackedLinear(
                torch.stack([run[f"{name}.weight"].T for run in weights]).float(),
                torch.stack([run[f"{name}.bias"] for run in weights]).float(),
                out_in=False, product=Product.ONE_OUTPUT_DOT)
        # (R, act_dim), None for discrete actions
        self.log_std = None if log_std is None else torch.nn.Parameter(log_std.float())
        self.ordered = [param for layer in self.layers.values() for param in layer.parameters()]
        if self.log_std is not None:
            self.ordered.append(self.log_std)

        # The layers' forwards in order, called directly: nn.Module's __call__ and ModuleDict
        # lookups were a fifth of a rollout step's Python time.
        self._pi = [self.layers[f"mlp_extractor_policy_net_{2 * i}"].forward
                    for i in range(len(arch.hidden))]
        self._vf = [self.layers[f"mlp_extractor_value_net_{2 * i}"].forward
                    for i in range(len(arch.hidden))]
        self._action = self.layers["action_net"].forward
        self._value = self.layers["value_net"].forward

    def _mlp(self, layers: list[Callable[[torch.Tensor], torch.Tensor]], x: torch.Tensor
             ) -> torch.Tensor:
        for layer in layers:
            x = self.act(layer(x))
        return x

    def forward(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """obs (R, B, obs_dim) -> (logits or means (R, B, act_dim), values (R, B))."""
        return self.head(obs), self.values(obs)

    def values(self, obs: torch.Tensor) -> torch.Tensor:
        return self._value(self._mlp(self._vf, obs)).squeeze(-1)

    def head(self, obs: torch.Tensor) -> torch.Tensor:
        """Logits or means (R, B, act_dim) only: what acting deterministically needs."""
        return self._action(self._mlp(self._pi, obs))

    def log_prob_entropy(self, head: torch.Tensor, actions: torch.Tensor
                         ) -> tuple[torch.Tensor, torch.Tensor]:
        if self.arch.discrete:
            logp_all = torch.log_softmax(head, dim=-1)
            logp = logp_all.gather(-1, actions.long().unsqueeze(-1)).squeeze(-1)
            entropy = -(logp_all.exp() * logp_all).sum(-1)
            return logp, entropy
        assert self.log_std is not None
        log_std = self.log_std[:, None, :].expand_as(head)
        var = torch.exp(2 * log_std)
        logp = (-((actions - head) ** 2) / (2 * var) - log_std - math.log(math.sqrt(2 * math.pi)))
        entropy = 0.5 + 0.5 * math.log(2 * math.pi) + log_std
        return logp.sum(-1), entropy.sum(-1)

    def run_state_dict(self, r: int) -> dict[str, torch.Tensor]:
        """Run r's parameters under SB3 MlpPolicy's state_dict keys."""
        out: dict[str, torch.Tensor] = {}
        for name in self.names:
            layer: Any = self.layers[name.replace(".", "_")]
            out[f"{name}.weight"] = layer.run_weight(r)
            out[f"{name}.bias"] = layer.bias.data[r].clone()
        if self.log_std is not None:
            out["log_std"] = self.log_std.data[r].clone()
        return out


def sb3_state_dict(policy: StackedPolicy, r: int) -> dict[str, torch.Tensor]:
    """Run r's policy as a state_dict for SB3 ``MlpPolicy`` with net_arch dict(pi=h, vf=h)."""
    return policy.run_state_dict(r)


@dataclass(frozen=True, kw_only=True)
class GroupResult:
    """A lock-step group's outcome (PPO or DQN): per run its seed, SB3-loadable policy
    state_dict and finished-episode returns (env reward); the steps and the time split."""

    seeds: tuple[int, ...]
    state_dicts: tuple[dict[str, torch.Tensor], ...]
    episode_returns: tuple[tuple[float, ...], ...]
    timesteps: int
    env_seconds: float
    update_seconds: float


class _RunEnvs:
    """One run's n envs, stepped as SB3's DummyVecEnv (auto-reset, terminal_observation)."""

    def __init__(self, env_id: str, n_envs: int, seed: int) -> None:
        from pokerirl.gym.envs import make_env  # its warnings filter: the v4 tasks

        self.envs = [make_env(env_id) for _ in range(n_envs)]
        self.obs = np.stack([e.reset(seed=seed + i)[0] for i, e in enumerate(self.envs)])
        for i, e in enumerate(self.envs):
            e.action_space.seed(seed + i)
        self.returns = np.zeros(n_envs)
        self.finished: list[float] = []

    def step(self, actions: np.ndarray):
        n = len(self.envs)
        next_obs = np.empty_like(self.obs)
        rewards = np.zeros(n, dtype=np.float32)
        dones = np.zeros(n, dtype=bool)
        truncated_obs: dict[int, np.ndarray] = {}
        for i, env in enumerate(self.envs):
            obs, reward, term, trunc, _ = env.step(actions[i])
            rewards[i] = reward
            self.returns[i] += reward
            dones[i] = term or trunc
            if dones[i]:
                if trunc and not term:  # SB3's TimeLimit.truncated
                    truncated_obs[i] = np.asarray(obs)
                self.finished.append(float(self.returns[i]))
                self.returns[i] = 0.0
                obs, _ = env.reset()
            next_obs[i] = obs
        self.obs = next_obs
        return next_obs, rewards, dones, truncated_obs


StepCallback = Callable[[int], None]


class LockstepPPO:
    """R PPO runs of one task, one per seed, each with its own reward (env reward or a callable).

    ``weights``: optional per-run SB3 state_dicts to start from (the equivalence test uses it).
    """

    def __init__(self, env_id: str, settings: PPOSettings, *, seeds: Sequence[int],
                 n_envs: int = 1, rewards: Sequence[RewardFn | None] | None = None,
                 weights: Sequence[dict[str, torch.Tensor]] | None = None) -> None:
        self.env_id, self.s, self.seeds, self.n_envs = env_id, settings, tuple(seeds), n_envs
        self.R = len(self.seeds)
        if self.R < 1:
            raise ValueError("LockstepPPO needs at least one seed")
        self.rewards = list(rewards) if rewards is not None else [None] * self.R
        if len(self.rewards) != self.R:
            raise ValueError(f"rewards: {len(self.rewards)} for {self.R} runs")
        self.envs = [_RunEnvs(env_id, n_envs, seed) for seed in self.seeds]
        space_a: Any = self.envs[0].envs[0].action_space  # Discrete or Box
        space_o: Any = self.envs[0].envs[0].observation_space
        self.discrete = isinstance(space_a, gym.spaces.Discrete)
        act_dim = int(space_a.n) if self.discrete else int(np.prod(space_a.shape))
        self.low = None if self.discrete else space_a.low
        self.high = None if self.discrete else space_a.high
        hidden = settings.net_arch if settings.net_arch is not None else (64, 64)
        self.arch = _Arch(obs_dim=int(np.prod(space_o.shape)), hidden=tuple(hidden),
                          discrete=self.discrete, act_dim=act_dim)
        self.rngs = [np.random.default_rng(seed) for seed in self.seeds]
        if weights is None:
            weights = [self._init_weights(seed) for seed in self.seeds]
        log_std = None
        if not self.discrete:
            log_std = torch.stack([w.get("log_std", torch.full((act_dim,), settings.log_std_init))
                                   for w in weights]).clone()
        self.policy = StackedPolicy(self.arch, activation=settings.activation,
                                    weights=list(weights), log_std=log_std)
        # SB3's ActorCriticPolicy: Adam with eps 1e-5; one (R, P) buffer (module docstring)
        self.optimizer = StackedAdam(self.policy.ordered, lr=settings.learning_rate, eps=1e-5,
                                     runs=self.R, flat=Flat.RUNS)
        self.timesteps = 0
        self.episode_starts = np.ones((self.R, n_envs), dtype=np.float32)
        self.env_seconds = 0.0
        self.update_seconds = 0.0

    def _init_weights(self, seed: int) -> dict[str, torch.Tensor]:
        """Run ``seed``'s layers as SB3 builds them (ortho init where the settings say)."""
        layers = _layer_names(self.arch)
        built = init_linears(seed, [(n_in, n_out) for _, n_in, n_out, _ in layers],
                             [gain if self.s.ortho_init else None for *_, gain in layers])
        out = {}
        for (name, *_), (weight, bias) in zip(layers, built, strict=True):
            out[f"{name}.weight"], out[f"{name}.bias"] = weight, bias
        return out

    def _obs(self) -> np.ndarray:
        return np.stack([e.obs for e in self.envs]).astype(np.float32)  # (R, n_envs, obs_dim)

    def _sample(self, head: torch.Tensor) -> np.ndarray:
        """Per-run numpy draws, so a run's actions do not depend on the other runs."""
        h = head.numpy().astype(np.float64)
        if self.discrete:
            u = np.stack([rng.random(self.n_envs) for rng in self.rngs])[..., None]
            p = np.exp(h - h.max(-1, keepdims=True))
            cdf = np.cumsum(p / p.sum(-1, keepdims=True), -1)
            return np.minimum((cdf < u).sum(-1), self.arch.act_dim - 1)
        noise = np.stack([rng.standard_normal((self.n_envs, self.arch.act_dim))
                          for rng in self.rngs])
        assert self.policy.log_std is not None  # continuous actions have a log σ
        std = np.exp(self.policy.log_std.detach().numpy())[:, None, :]
        return (h + std * noise).astype(np.float32)

    def predict(self, obs: np.ndarray) -> np.ndarray:
        """Deterministic actions of every run, as SB3's ``predict(deterministic=True)``: obs
        (R, B, obs_dim) -> argmax (R, B) or the mean clipped to the action bounds (R, B, dim)."""
        obs = np.asarray(obs, dtype=np.float32)
        if obs.ndim != 3 or obs.shape[0] != self.R or obs.shape[2] != self.arch.obs_dim:
            raise ValueError(f"predict: observations of shape {obs.shape}, not "
                             f"({self.R}, batch, {self.arch.obs_dim})")
        with torch.no_grad():
            head = self.policy.head(torch.from_numpy(obs))
        if self.discrete:
            return head.argmax(-1).numpy()
        return np.clip(head.numpy(), self.low, self.high)

    def collect(self, callback: StepCallback | None = None) -> dict[str, torch.Tensor]:
        """One rollout of n_steps per env for every run, GAE as SB3's RolloutBuffer;
        ``callback(timesteps)`` after every env step, as SB3 calls ``on_step``."""
        s, R, n, T = self.s, self.R, self.n_envs, self.s.n_steps
        obs_b = np.zeros((T, R, n, self.arch.obs_dim), np.float32)
        act_shape = (T, R, n) if self.discrete else (T, R, n, self.arch.act_dim)
        act_b = np.zeros(act_shape, np.float32)
        rew_b = np.zeros((T, R, n), np.float32)
        start_b = np.zeros((T, R, n), np.float32)
        val_b = np.zeros((T, R, n), np.float32)
        logp_b = np.zeros((T, R, n), np.float32)
        dones = np.zeros((R, n), dtype=bool)
        for t in range(T):
            obs = self._obs()
            with torch.no_grad():
                head, values = self.policy(torch.from_numpy(obs))
                actions = self._sample(head)
                logp, _ = self.policy.log_prob_entropy(head, torch.from_numpy(actions))
            t0 = time.perf_counter()
            env_actions = actions if self.discrete else np.clip(actions, self.low, self.high)
            rewards = np.zeros((R, n), np.float32)
            truncs = []
            for r, envs in enumerate(self.envs):
                prev = envs.obs
                _, rew, dones[r], trunc = envs.step(env_actions[r])
                fn = self.rewards[r]
                # The reward sees the action taken (SB3 trains on unclipped; the learned-reward
                # wrapper sees what was passed to the VecEnv, i.e. the clipped action).
                rewards[r] = rew if fn is None else np.asarray(fn(prev.astype(np.float32),
                                                                  env_actions[r]), np.float32)
                truncs.append(trunc)
            self.env_seconds += time.perf_counter() - t0
            self.timesteps += n
            if any(truncs):  # SB3's timeout bootstrap
                for r, trunc in enumerate(truncs):
                    for i, term_obs in trunc.items():
                        with torch.no_grad():
                            v = self.policy.values(torch.from_numpy(
                                term_obs.astype(np.float32)).view(1, 1, -1).expand(R, 1, -1))
                        rewards[r, i] += s.gamma * float(v[r, 0])
            obs_b[t], act_b[t], rew_b[t] = obs, actions, rewards
            start_b[t], val_b[t], logp_b[t] = self.episode_starts, values.numpy(), logp.numpy()
            self.episode_starts = dones.astype(np.float32)
            if callback is not None:
                callback(self.timesteps)
        with torch.no_grad():
            last_values = self.policy.values(torch.from_numpy(self._obs())).numpy()
        adv = gae(rew_b, val_b, start_b, last_values, dones, s.gamma, s.gae_lambda)
        returns = adv + val_b

        def flat(x: np.ndarray) -> torch.Tensor:
            # (T, R, n, ...) -> (R, n * T, ...), env-major as SB3's swap_and_flatten
            x = np.moveaxis(x, 0, 2)
            return torch.from_numpy(np.ascontiguousarray(x.reshape(R, n * T, *x.shape[3:])))

        return {"obs": flat(obs_b), "actions": flat(act_b), "values": flat(val_b),
                "log_prob": flat(logp_b), "advantages": flat(adv), "returns": flat(returns)}

    def train(self, batch: dict[str, torch.Tensor],
              permutations: Sequence[Sequence[np.ndarray]] | None = None) -> dict[str, np.ndarray]:
        """n_epochs over the batch; ``permutations[epoch][r]`` overrides run r's draw (tests)."""
        s, R = self.s, self.R
        N = batch["obs"].shape[1]
        rows = torch.arange(R)[:, None]
        policy, grad = self.policy, self.optimizer.grad
        last: dict[str, torch.Tensor] = {}
        for epoch in range(s.n_epochs):
            if permutations is None:
                perm = np.stack([rng.permutation(N) for rng in self.rngs])
            else:
                perm = np.stack(permutations[epoch])
            # One gather per epoch; the minibatches are then slices (views) of it.
            shuffled = {k: v[rows, torch.from_numpy(perm)] for k, v in batch.items()}
            for start in range(0, N, s.batch_size):
                mb = {k: v[:, start:start + s.batch_size] for k, v in shuffled.items()}
                head, values = policy(mb["obs"])
                logp, entropy = policy.log_prob_entropy(head, mb["actions"])
                adv = mb["advantages"]
                if adv.shape[1] > 1:
                    adv = (adv - adv.mean(1, keepdim=True)) / (adv.std(1, keepdim=True) + 1e-8)
                ratio = torch.exp(logp - mb["log_prob"])
                pg = -torch.min(adv * ratio,
                                adv * torch.clamp(ratio, 1 - s.clip_range, 1 + s.clip_range)
                                ).mean(1)
                vloss = ((mb["returns"] - values) ** 2).mean(1)
                ent_loss = -entropy.mean(1)
                loss = pg + s.ent_coef * ent_loss + s.vf_coef * vloss  # (R,)
                self.optimizer.zero_grad()
                with warnings.catch_warnings():
                    # The grads are strided views into the optimizer's buffer, by design.
                    warnings.filterwarnings("ignore", message=".*gradient layout contract")
                    loss.sum().backward()
                clip_grad_norm_per_run([grad], s.max_grad_norm, R)  # one norm per row
                self.optimizer.step()
                last = {"policy_loss": pg, "value_loss": vloss, "entropy_loss": ent_loss,
                        "loss": loss}
        return {key: value.detach().numpy() for key, value in last.items()}

    def learn(self, total_timesteps: int, *, callback: StepCallback | None = None
              ) -> GroupResult:
        """SB3's loop: rollouts of n_steps until total_timesteps (rounded up to a rollout);
        ``callback(timesteps)`` after every env step (timesteps per run so far)."""
        while self.timesteps < total_timesteps:
            batch = self.collect(callback)
            t0 = time.perf_counter()
            self.train(batch)
            self.update_seconds += time.perf_counter() - t0
        return self.result()

    def result(self) -> GroupResult:
        """Every run's state so far."""
        return GroupResult(
            seeds=self.seeds,
            state_dicts=tuple(self.policy.run_state_dict(r) for r in range(self.R)),
            episode_returns=tuple(tuple(e.finished) for e in self.envs),
            timesteps=self.timesteps, env_seconds=self.env_seconds,
            update_seconds=self.update_seconds)


def gae(rewards: np.ndarray, values: np.ndarray, starts: np.ndarray, last_values: np.ndarray,
        dones: np.ndarray, gamma: float, lam: float) -> np.ndarray:
    """SB3 RolloutBuffer.compute_returns_and_advantage over (T, ...) arrays (float32)."""
    T = len(rewards)
    adv = np.zeros_like(rewards)
    last = np.zeros_like(rewards[0])
    for t in reversed(range(T)):
        if t == T - 1:
            nonterm = 1.0 - dones.astype(np.float32)
            nxt = last_values
        else:
            nonterm = 1.0 - starts[t + 1]
            nxt = values[t + 1]
        delta = rewards[t] + gamma * nxt * nonterm - values[t]
        last = delta + gamma * lam * nonterm * last
        adv[t] = last
    return adv
