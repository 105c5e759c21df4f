"""Training throughput of `pokerirl.irl` against a re-implementation of the authors' loop.

Prints, in one run, expert samples per second of optimization:

1. poker config (batch 256, hidden 64, 72-dim observations, 4 masked actions), one run:
   ``pokerirl.irl.train`` as it runs (the hand-derived path of ``pokerirl.irl.fast``), and
   with ``fast_path=False`` (autograd only);
2. the peer, the authors' style of loop: a per-row ``Dataset`` behind a ``DataLoader`` that
   collates every batch, autograd, ``torch.optim.Adam``, a ``.item()`` per step, one run at
   a time, same nets and losses;
3. Gymnasium config (hidden (64, 64), batch 64, 17-dim observations, 6-dim continuous
   actions as in HalfCheetah): 10 runs in lock-step with ``train_many`` against 10
   sequential runs of the peer (its time per batch, times 10).

Targets (issue 9): poker >= 250,000 samples/s on one idle core; Gymnasium 10 runs >= 10x the
peer's 10 sequential runs. The machine may be shared: compare the ratios, which are measured
in the same run, and read absolute figures with the load in mind (printed).

    python benchmarks/train.py [--rows 60000] [--epochs 3] [--threads 1] [--peer-batches 120]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np
import torch
from torch.utils.data import DataLoader, Dataset

from pokerirl.datasets.toy import toy_expert_table
from pokerirl.irl import AIRLConfig, Transitions, default_nets, train, train_many
from pokerirl.irl.adversarial import discriminator_loss, gaussian_log_prob, noise_schedule
from pokerirl.irl.nets import project_to_simplex
from pokerirl.poker import transitions_from_arrow


class RowDataset(Dataset):
    """One expert row per ``__getitem__``, as tensors (the DataLoader collates batches)."""

    def __init__(self, data: Transitions) -> None:
        self.data = data
        self.vectors = data.action_vectors()
        self.mask = data.legal_mask
        self.rewards = data.rewards

    def __len__(self) -> int:
        return len(self.data)

    def __getitem__(self, i: int) -> tuple[torch.Tensor, ...]:
        mask = self.mask[i] if self.mask is not None else torch.ones(1, dtype=torch.bool)
        return self.data.obs[i], self.vectors[i], mask, self.rewards[i]


def peer_seconds_per_batch(data: Transitions, config: AIRLConfig, batches: int) -> list[float]:
    """The authors' style of loop; seconds per batch in windows of batches."""
    reward_net, policy = default_nets(data, config)
    reward_opt = torch.optim.Adam(
        reward_net.parameters(), lr=config.reward_lr, weight_decay=config.reward_weight_decay
    )
    policy_opt = torch.optim.Adam(policy.parameters(), lr=config.policy_lr)
    sigma = noise_schedule(config.batch_size, config.sigma_start, config.sigma_end)
    loader = DataLoader(RowDataset(data), batch_size=config.batch_size, shuffle=True)
    window, times, start = max(batches // 4, 1), [], time.perf_counter()
    for step, (obs, expert, mask, env) in enumerate(loader, start=1):
        s = sigma[: len(obs), None]
        if data.discrete:
            log_pi = policy(obs, mask)
            pi = log_pi.exp()
            noisy = project_to_simplex(pi.detach() + s * torch.randn_like(pi), mask)
            lp_expert = (expert * log_pi.detach()).sum(-1)
            lp_noisy = (noisy * log_pi.detach()).sum(-1)
        else:
            mean, log_std = policy(obs)
            pi = mean + log_std.exp() * torch.randn_like(mean)
            noisy = pi.detach() + s * torch.randn_like(pi)
            lp_expert = gaussian_log_prob(expert, mean.detach(), log_std.detach())
            lp_noisy = gaussian_log_prob(noisy, mean.detach(), log_std.detach())
        d_loss = discriminator_loss(
            reward_net(obs, expert), lp_expert, reward_net(obs, noisy), lp_noisy,
            beta=config.beta, env_reward=env,
        )[0]  # fmt: skip
        reward_opt.zero_grad()
        d_loss.backward()
        reward_opt.step()
        if data.discrete:
            supervised = -(expert * log_pi).sum(-1).mean()
            adversarial = (pi * log_pi).sum(-1) - reward_net(obs, pi)
        else:
            supervised = (mean - expert).square().sum(-1).mean()
            adversarial = gaussian_log_prob(pi, mean, log_std) - reward_net(obs, pi)
        p_loss = (1 - config.alpha) * adversarial.mean() + config.alpha * supervised
        policy_opt.zero_grad()
        p_loss.backward()
        policy_opt.step()
        d_loss.item(), p_loss.item()  # per-step logging, as reference loops do
        if step % window == 0:
            now = time.perf_counter()
            times.append((now - start) / window)
            start = now
        if step >= batches:
            break
    return times


def gym_like(rows: int, seed: int = 0) -> Transitions:
    """HalfCheetah-shaped transitions: 17-dim observations, 6-dim actions in [-1, 1]."""
    rng = np.random.default_rng(seed)
    obs = rng.normal(size=(rows, 17)).astype(np.float32)
    weights = rng.normal(size=(17, 6)).astype(np.float32) / 4
    actions = np.tanh(obs @ weights).astype(np.float32)
    return Transitions.from_arrays(
        obs,
        actions,
        groups=np.arange(rows) // 1000,
        rewards=rng.normal(size=rows).astype(np.float32),
        low=[-1.0] * 6,
        high=[1.0] * 6,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=60_000)
    parser.add_argument("--epochs", type=int, default=3)
    parser.add_argument("--threads", type=int, default=1, help="as `pokerirl train` (default 1)")
    parser.add_argument("--peer-batches", type=int, default=120)
    parser.add_argument("--runs", type=int, default=10)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    print(
        f"torch {torch.__version__}, {torch.get_num_threads()} thread(s), "
        f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
    )

    # 1-2. poker config, one run, against the peer
    table = toy_expert_table(num_hands=args.rows // 2 + 1, seed=0).slice(0, args.rows)
    data = transitions_from_arrow(table)
    val = data.subset(np.arange(min(5_000, len(data))))
    config = AIRLConfig.for_algo("hairl", epochs=args.epochs, batch_size=256)
    rates = {}
    for fast_path in (True, False):
        result = train(data, val, config=config, fast_path=fast_path, progress=False)
        rates[result.gradients] = [result.samples_per_epoch / s for s in result.epoch_seconds]
    peer = [config.batch_size / s for s in peer_seconds_per_batch(data, config, args.peer_batches)]
    print(f"\npoker config: {len(data):,} rows, batch 256, hidden (64,), one run")
    for name, ours in rates.items():
        print(
            f"  pokerirl.irl.train ({name:>12}): median {statistics.median(ours):>9,.0f}  "
            f"best {max(ours):>9,.0f} samples/s ({len(ours)} epochs), "
            f"{statistics.median(ours) / statistics.median(peer):.1f}x the peer"
        )
    print(
        f"  authors' loop (peer)              : median {statistics.median(peer):>9,.0f}  "
        f"best {max(peer):>9,.0f} samples/s ({len(peer)} windows)"
    )

    # 3. Gymnasium config, R runs in lock-step, against R sequential peer runs
    gym = gym_like(max(args.rows // 3, 2_000))
    gym_val = gym.subset(np.arange(1_000))
    gym_config = AIRLConfig.for_algo(
        "hairl",
        epochs=args.epochs,
        batch_size=64,
        reward_hidden=(64, 64),
        policy_hidden=(64, 64),
        noise_schedule="authors",
        noise_decay=0.01,
    )
    many = train_many(gym, gym_val, config=gym_config, seeds=range(args.runs), progress=False)
    lock_step = [many.samples_per_epoch / s for s in many.epoch_seconds]
    peer_batch = statistics.median(peer_seconds_per_batch(gym, gym_config, args.peer_batches))
    sequential = gym_config.batch_size / peer_batch  # R runs one after another: same rate
    single = train(gym, gym_val, config=gym_config, progress=False)
    print(f"\nGymnasium config: {len(gym):,} rows, batch 64, hidden (64, 64), 6-dim actions")
    print(
        f"  train_many, {args.runs} runs lock-step: median "
        f"{statistics.median(lock_step):>9,.0f} samples/s (all runs together)"
    )
    print(f"  train, one run               : {single.samples_per_second:>9,.0f} samples/s")
    print(
        f"  authors' loop, runs in sequence: {sequential:>9,.0f} samples/s "
        f"({peer_batch * 1e3:.2f} ms per batch of 64)"
    )
    print(
        f"  ratio {args.runs} runs lock-step / {args.runs} sequential peer runs: "
        f"{statistics.median(lock_step) / sequential:.1f}x"
    )


if __name__ == "__main__":
    main()
