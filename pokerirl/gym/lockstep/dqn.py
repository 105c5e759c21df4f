"""DQN for R runs in lock-step: stacked Q-networks (``pokerirl.stacking``).

Follows SB3 2.9's DQN (dqn/dqn.py, common/off_policy_algorithm.py, common/buffers.py
``ReplayBuffer``, dqn/policies.py) for the settings ``pokerirl.gym.presets.DQNSettings`` holds,
with SB3's defaults for the rest (exploration_initial_eps 1.0, tau 1.0, max_grad_norm 10,
``optimize_memory_usage`` False, ``handle_timeout_termination`` True, n_steps 1, one env per run):

- the loop of ``OffPolicyAlgorithm.learn``: rollouts of ``train_freq`` env steps, then
  ``gradient_steps`` updates once ``timesteps > learning_starts`` (the budget rounds up to a
  whole rollout, as SB3's does);
- actions: uniform (``action_space.sample()``) while ``timesteps < learning_starts``, then
  epsilon-greedy (``rand() < eps``: a uniform action, else argmax Q), eps from the value the
  last ``_on_step`` left (0.0 before the first step, as SB3's ``exploration_rate``);
- ``_on_step`` after every env step: ``_n_calls += 1``, a hard target update (tau 1) when
  ``_n_calls % max(target_update_interval, 1) == 0``, then eps = ``LinearSchedule(1.0,
  final_eps, exploration_fraction)(1 - timesteps / total)``;
- the replay buffer: circular, ``buffer_size`` rows per run, ``next_obs`` the terminal
  observation at an episode's end, the stored done ``terminated`` only (SB3 keeps
  ``done * (1 - timeout)``: the same number), minibatches drawn uniformly from the filled rows;
- the update: TD target ``r + (1 - done) * gamma * max_a Q_target(s', a)``, Huber loss
  (``smooth_l1_loss``, beta 1) averaged over the minibatch, per-run ``clip_grad_norm_`` at 10
  (``max_norm / (norm + 1e-6)`` clamped at 1), Adam (torch defaults, eps 1e-8);
- QNetwork: an MLP with ReLU and torch's default ``Linear`` init (no ortho), built from torch's
  RNG seeded by the run's seed, so a run's initial weights equal SB3's for the same seed.

Where it differs from SB3, and why (see docs/lockstep_dqn.md):
- Random streams. SB3 draws epsilon coins and minibatch indices from numpy's global generator
  and uniform actions from the (seeded) action space. Here each run has its own
  ``np.random.RandomState(seed)`` (what SB3's ``np.random.seed(seed)`` makes) and its own env's
  action space seeded with ``seed``, drawn in SB3's order, so run r of a group equals a group of
  one with seed r and, up to float rounding, SB3 with the same seed.
- Float rounding. Batched matmuls (``baddbmm`` over runs), a fused Adam kernel and the target
  network's maxima computed in bigger batches (cached per buffer row where that is cheaper,
  see ``cache_targets``) round differently from SB3's per-run ``addmm``; one update agrees to
  ~1e-7, but over training the gap grows until a greedy action flips (about 1k steps).
- One Adam over stacked tensors = R per-run Adams (element-wise; every run steps together):
  ``StackedAdam`` with torch.optim.Adam's numbers, its fused kernel where a tensor's per-run
  part fills whole SIMD vectors, so that run r rounds alike in a group of R and of one.
- One summed loss: runs share no parameters, so each run's gradient is its own loss's.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Sequence

import gymnasium as gym
import numpy as np
import torch
import torch.nn.functional as F

from pokerirl.gym.lockstep.ppo import GroupResult, RewardFn
from pokerirl.gym.presets import DQNSettings
from pokerirl.stacking import (
    Product,
    StackedAdam,
    StackedLinear,
    clip_grad_norm_per_run,
    init_linears,
)

# SB3 DQN's defaults for what DQNSettings leaves out.
EXPLORATION_INITIAL_EPS = 1.0
MAX_GRAD_NORM = 10.0  # tau is SB3's default 1.0: the target update is a copy

Callback = Callable[[int], object]


def exploration_rate(settings: DQNSettings, progress_remaining: float) -> float:
    """SB3's ``LinearSchedule(1.0, final_eps, fraction)``, term for term (same rounding)."""
    start, end, fraction = (EXPLORATION_INITIAL_EPS, settings.exploration_final_eps,
                            settings.exploration_fraction)
    if (1 - progress_remaining) > fraction:
        return end
    return start + (1 - progress_remaining) * (end - start) / fraction


def layer_keys(n_layers: int) -> list[str]:
    """The ``nn.Sequential`` indices of QNetwork's linears (ReLUs sit between them)."""
    return [f"q_net.{2 * i}" for i in range(n_layers)]


class StackedQNet(torch.nn.Module):
    """R QNetworks: obs (R, B, obs_dim) -> Q-values (R, B, n_actions)."""

    def __init__(self, layers: Sequence[StackedLinear]) -> None:
        super().__init__()
        self.layers = torch.nn.ModuleList(layers)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for layer in self.layers[:-1]:
            x = torch.relu(layer(x))
        return self.layers[-1](x)

    @classmethod
    def from_state_dicts(cls, runs: Sequence[dict[str, torch.Tensor]], prefix: str,
                         n_layers: int) -> StackedQNet:
        return cls([
            StackedLinear.stack([run[f"{prefix}{key}.weight"].float() for run in runs],
                                [run[f"{prefix}{key}.bias"].float() for run in runs],
                                product=Product.WRITTEN_BACKWARD)  # the fast product layouts
            for key in layer_keys(n_layers)
        ])

    def run_state_dict(self, r: int, prefix: str) -> dict[str, torch.Tensor]:
        out = {}
        for key, layer in zip(layer_keys(len(self.layers)), self.layers, strict=True):
            assert isinstance(layer, StackedLinear) and layer.bias is not None
            out[f"{prefix}{key}.weight"] = layer.run_weight(r)
            out[f"{prefix}{key}.bias"] = layer.bias.data[r].clone()
        return out


class LockstepDQN:
    """R DQN runs of one task, one per seed, each with its own reward (env reward or a callable).

    ``weights``: optional per-run SB3 ``DQNPolicy`` state_dicts to start from (``q_net.*``; the
    target starts from ``q_net_target.*`` where given, else as a copy, as SB3 builds it).
    """

    def __init__(self, env_id: str, settings: DQNSettings, *, seeds: Sequence[int],
                 rewards: Sequence[RewardFn | None] | None = None,
                 weights: Sequence[dict[str, torch.Tensor]] | None = None) -> None:
        self.env_id, self.s, self.seeds = env_id, settings, tuple(int(x) for x in seeds)
        self.R = len(self.seeds)
        if self.R == 0:
            raise ValueError("LockstepDQN: no seeds")
        self.rewards = list(rewards) if rewards is not None else [None] * self.R
        if len(self.rewards) != self.R:
            raise ValueError(f"rewards: {len(self.rewards)} for {self.R} runs")
        if weights is not None and len(weights) != self.R:
            raise ValueError(f"weights: {len(weights)} for {self.R} runs")
        self.envs = [gym.make(env_id) for _ in self.seeds]
        space_a, space_o = self.envs[0].action_space, self.envs[0].observation_space
        if not isinstance(space_a, gym.spaces.Discrete):
            raise ValueError(f"LockstepDQN needs Discrete actions; {env_id} has {space_a}")
        if not isinstance(space_o, gym.spaces.Box) or len(space_o.shape) != 1:
            raise ValueError(f"LockstepDQN needs flat Box observations; {env_id} has {space_o}")
        self.obs_dim, self.n_actions = int(space_o.shape[0]), int(space_a.n)
        self.hidden = tuple(settings.net_arch)
        n_layers = len(self.hidden) + 1
        # SB3: set_random_seed(seed) at construction (numpy global, action space), the env's
        # first reset at learn() with seed; later resets unseeded.
        self.np_rngs = [np.random.RandomState(seed) for seed in self.seeds]
        for env, seed in zip(self.envs, self.seeds, strict=True):
            env.action_space.seed(seed)
        self.obs = np.stack([env.reset(seed=seed)[0] for env, seed
                             in zip(self.envs, self.seeds, strict=True)]).astype(np.float32)
        if weights is None:
            weights = [self._init_weights(seed) for seed in self.seeds]
        weights = [dict(w) for w in weights]
        for r, w in enumerate(weights):
            missing = [f"q_net.{key}.{part}" for key in layer_keys(n_layers)
                       for part in ("weight", "bias") if f"q_net.{key}.{part}" not in w]
            if missing:
                raise ValueError(f"weights[{r}]: not an SB3 DQNPolicy state_dict of net_arch "
                                 f"{self.hidden} (missing {', '.join(missing)})")
        for w in weights:
            for key in layer_keys(n_layers):  # target as SB3 builds it: a copy of q_net
                for part in ("weight", "bias"):
                    w.setdefault(f"q_net_target.{key}.{part}", w[f"q_net.{key}.{part}"])
        self.q_net = StackedQNet.from_state_dicts(weights, "q_net.", n_layers)
        self.q_net_target = StackedQNet.from_state_dicts(weights, "q_net_target.", n_layers)
        self.q_net_target.requires_grad_(False)
        # SB3's Adam (torch's defaults), torch.optim.Adam's numbers (AdamKernel.TORCH)
        self.optimizer = StackedAdam(self.q_net.parameters(), lr=settings.learning_rate,
                                     runs=self.R)
        # Replay buffers, one (R, buffer_size, ...) array each; torch views share the memory.
        N, R = settings.buffer_size, self.R
        self.buf_obs = np.zeros((R, N, self.obs_dim), np.float32)
        self.buf_next_obs = np.zeros((R, N, self.obs_dim), np.float32)
        self.buf_actions = np.zeros((R, N), np.int64)
        self.buf_rewards = np.zeros((R, N), np.float32)
        self.buf_dones = np.zeros((R, N), np.float32)  # terminated (not truncated) only
        self.pos, self.full = 0, False
        # max_a Q_target(next_obs) per buffer row, kept where recomputing the whole buffer once
        # per target update costs less than SB3's forward on every sampled row (MountainCar:
        # 10k rows per 600 steps against 37 x 8 x 128 sampled rows); ``fresh`` marks the rows
        # whose cached value is from the current target network.
        self.cache_targets = (N + settings.target_update_interval
                              < settings.target_update_interval // settings.train_freq
                              * settings.gradient_steps * settings.batch_size)
        self.next_q_max = torch.zeros(R, N)
        self.fresh = np.zeros(N, bool)
        self.timesteps = 0
        self.n_calls = 0
        self.n_updates = 0  # gradient steps per run, SB3's _n_updates
        self.exploration = 0.0  # SB3's exploration_rate before the first _on_step
        self.target_update_steps: list[int] = []
        self.returns = np.zeros(R)
        self.finished: list[list[float]] = [[] for _ in range(R)]
        self.env_seconds = 0.0
        self.update_seconds = 0.0
        self._learned = False

    def _init_weights(self, seed: int) -> dict[str, torch.Tensor]:
        """SB3's QNetwork init for ``seed``: torch.manual_seed(seed), default Linear init."""
        sizes = (self.obs_dim, *self.hidden, self.n_actions)
        out = {}
        built = init_linears(seed, list(itertools.pairwise(sizes)))
        for key, (weight, bias) in zip(layer_keys(len(built)), built, strict=True):
            out[f"q_net.{key}.weight"], out[f"q_net.{key}.bias"] = weight, bias
        return out

    # ------------------------------------------------------------------ acting

    def q_values(self, obs: np.ndarray | torch.Tensor) -> torch.Tensor:
        """Every run's Q-values: obs (R, B, obs_dim) -> (R, B, n_actions)."""
        with torch.inference_mode():
            return self.q_net(torch.as_tensor(obs, dtype=torch.float32))

    def predict(self, obs: np.ndarray) -> np.ndarray:
        """Every run's greedy actions on its own batch: obs (R, B, obs_dim) -> (R, B)."""
        obs = np.asarray(obs)
        if obs.ndim != 3 or obs.shape[0] != self.R or obs.shape[2] != self.obs_dim:
            raise ValueError(f"predict: obs shape {obs.shape}, not ({self.R}, B, {self.obs_dim})")
        return self.q_values(obs).argmax(-1).numpy()

    def _actions(self) -> np.ndarray:
        """SB3's ``_sample_action`` per run, from the run's own streams."""
        if self.timesteps < self.s.learning_starts:
            return np.array([env.action_space.sample() for env in self.envs], np.int64)
        explore = [rng.rand() < self.exploration for rng in self.np_rngs]
        actions = np.zeros(self.R, np.int64)
        if not all(explore):
            actions[:] = self.predict(self.obs[:, None, :])[:, 0]
        for r, env in enumerate(self.envs):
            if explore[r]:
                actions[r] = env.action_space.sample()
        return actions

    def _step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """One env step per run (DummyVecEnv auto-reset): next obs to store, rewards, dones."""
        next_store = np.empty_like(self.obs)
        next_obs = np.empty_like(self.obs)
        rewards = np.zeros(self.R, np.float32)
        terminated = np.zeros(self.R, np.float32)
        for r, env in enumerate(self.envs):
            obs, reward, term, trunc, _ = env.step(int(actions[r]))
            fn = self.rewards[r]
            # The reward sees the observation the action was taken in, as learned_reward_env.
            rewards[r] = reward if fn is None else np.asarray(
                fn(self.obs[r:r + 1], actions[r:r + 1]), np.float32).reshape(())
            self.returns[r] += float(reward)
            next_store[r] = obs  # the terminal observation at an episode's end
            terminated[r] = float(term)
            if term or trunc:
                self.finished[r].append(float(self.returns[r]))
                self.returns[r] = 0.0
                obs, _ = env.reset()
            next_obs[r] = obs
        return next_obs, next_store, rewards, terminated

    def _store(self, next_store: np.ndarray, actions: np.ndarray, rewards: np.ndarray,
               terminated: np.ndarray) -> None:
        p = self.pos
        self.buf_obs[:, p], self.buf_next_obs[:, p] = self.obs, next_store
        self.buf_actions[:, p], self.buf_rewards[:, p], self.buf_dones[:, p] = (
            actions, rewards, terminated)
        self.fresh[p] = False
        self.pos = (p + 1) % self.s.buffer_size
        self.full = self.full or self.pos == 0

    def update_target(self) -> None:
        """Polyak update with tau 1: the target becomes a copy of the online network."""
        with torch.no_grad():
            for target, online in zip(self.q_net_target.parameters(), self.q_net.parameters(),
                                      strict=True):
                target.copy_(online)
        self.fresh[:] = False

    def _on_step(self, total_timesteps: int) -> None:
        """SB3 DQN's ``_on_step``: count the call, maybe update the target, then epsilon."""
        self.n_calls += 1
        if self.n_calls % max(self.s.target_update_interval, 1) == 0:  # n_envs 1
            t0 = time.perf_counter()
            self.update_target()
            self.update_seconds += time.perf_counter() - t0
            self.target_update_steps.append(self.timesteps)
        self.exploration = exploration_rate(self.s, 1.0 - float(self.timesteps)
                                            / float(total_timesteps))

    # ------------------------------------------------------------------ training

    def sample_indices(self, gradient_steps: int) -> np.ndarray:
        """Minibatch rows (gradient_steps, R, batch_size), drawn as SB3's ``ReplayBuffer.sample``.

        SB3 also draws env indices with ``randint(0, 1)``, which consumes nothing from a
        RandomState, so it is left out.
        """
        upper = self.s.buffer_size if self.full else self.pos
        idx = np.empty((gradient_steps, self.R, self.s.batch_size), np.int64)
        for r, rng in enumerate(self.np_rngs):
            for g in range(gradient_steps):
                idx[g, r] = rng.randint(0, upper, size=self.s.batch_size)
        return idx

    def train(self, gradient_steps: int, indices: np.ndarray | None = None) -> np.ndarray:
        """``gradient_steps`` updates of every run; ``indices`` (G, R, B) overrides the draw.

        Returns the Huber losses (G, R).
        """
        s, R, N = self.s, self.R, self.s.buffer_size
        idx = self.sample_indices(gradient_steps) if indices is None else np.asarray(indices)
        G, B = idx.shape[0], idx.shape[2]
        # One gather for all gradient steps: the buffer does not change during train().
        flat = torch.from_numpy((idx + np.arange(R)[None, :, None] * N).reshape(-1))

        def rows(buf: np.ndarray) -> torch.Tensor:
            t = torch.from_numpy(buf).reshape(R * N, *buf.shape[2:])
            return t.index_select(0, flat).reshape(G, R, B, *buf.shape[2:])

        obs, actions = rows(self.buf_obs), rows(self.buf_actions)
        rewards, dones = rows(self.buf_rewards), rows(self.buf_dones)
        with torch.no_grad():
            if self.cache_targets:
                self._refresh_next_q_max()
                next_q = self.next_q_max.reshape(-1).index_select(0, flat).reshape(G, R, B)
            else:  # the target is fixed during train(): one forward for all minibatches
                next_obs = rows(self.buf_next_obs).transpose(0, 1).reshape(R, G * B, -1)
                next_q = self.q_net_target(next_obs).max(-1).values
                next_q = next_q.reshape(R, G, B).transpose(0, 1)
            targets = rewards + (1 - dones) * s.gamma * next_q
        params = list(self.q_net.parameters())
        losses = torch.empty(G, R)
        for g in range(G):
            q = self.q_net(obs[g]).gather(-1, actions[g].unsqueeze(-1)).squeeze(-1)  # (R, B)
            loss = F.smooth_l1_loss(q, targets[g], reduction="none").mean(1)  # (R,)
            self.optimizer.zero_grad()
            loss.sum().backward()
            clip_grad_norm_per_run([p.grad for p in params], MAX_GRAD_NORM, R)
            self.optimizer.step()
            losses[g] = loss.detach()
        self.n_updates += G
        return losses.numpy()

    def _refresh_next_q_max(self, chunk: int = 2048) -> None:
        upper = self.s.buffer_size if self.full else self.pos
        stale = np.flatnonzero(~self.fresh[:upper])
        for start in range(0, len(stale), chunk):
            rows = torch.from_numpy(stale[start:start + chunk])
            next_obs = torch.from_numpy(self.buf_next_obs).index_select(1, rows)
            self.next_q_max[:, rows] = self.q_net_target(next_obs).max(-1).values
        self.fresh[stale] = True

    # ------------------------------------------------------------------ loop

    def learn(self, total_timesteps: int, *, callback: Callback | None = None) -> GroupResult:
        """SB3's ``OffPolicyAlgorithm.learn`` for every run; ``callback(timesteps)`` after each
        env step (where SB3 calls ``callback.on_step``: before storing the transition)."""
        if self._learned:
            raise RuntimeError("LockstepDQN.learn: call it once per group")
        if total_timesteps < 1:
            raise ValueError(f"total_timesteps {total_timesteps} < 1")
        self._learned = True
        s = self.s
        while self.timesteps < total_timesteps:
            for _ in range(s.train_freq):  # one rollout of train_freq steps (unit "step")
                actions = self._actions()
                t0 = time.perf_counter()
                next_obs, next_store, rewards, terminated = self._step(actions)
                self.env_seconds += time.perf_counter() - t0
                self.timesteps += 1
                if callback is not None:
                    callback(self.timesteps)
                self._store(next_store, actions, rewards, terminated)
                self.obs = next_obs
                self._on_step(total_timesteps)
            if self.timesteps > s.learning_starts and s.gradient_steps > 0:
                t0 = time.perf_counter()
                self.train(s.gradient_steps)
                self.update_seconds += time.perf_counter() - t0
        return self.result()

    def result(self) -> GroupResult:
        return GroupResult(
            seeds=self.seeds, state_dicts=tuple(self.run_state_dict(r) for r in range(self.R)),
            episode_returns=tuple(tuple(f) for f in self.finished), timesteps=self.timesteps,
            env_seconds=self.env_seconds, update_seconds=self.update_seconds)

    def run_state_dict(self, r: int) -> dict[str, torch.Tensor]:
        """Run r's networks under SB3 ``DQNPolicy``'s state_dict keys."""
        return {**self.q_net.run_state_dict(r, "q_net."),
                **self.q_net_target.run_state_dict(r, "q_net_target.")}
