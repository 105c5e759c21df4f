"""Training throughput of `pokerirl.irl.train` on a synthesized 300k-row table.

Prints expert samples per second of optimization (batch 256, hidden 64) for our trainer and,
in the same run, for a peer: the same model and losses driven by a per-row
``torch.utils.data.DataLoader``, autograd and ``torch.optim.Adam``, the way reference
implementations are usually written. Threads default to 1, as in `pokerirl train`; pass
``--threads 2`` for the reference's setting. The machine may be shared, so each figure is
the best and the median of several timed windows.

    python benchmarks/train.py [--rows 300000] [--epochs 3] [--threads 1] [--peer-batches 200]
"""

from __future__ import annotations

import argparse
import statistics
import time

import torch
from torch.utils.data import DataLoader, Dataset

from pokerirl.irl import AIRLConfig, ExpertData, train
from pokerirl.irl.airl import build_nets, discriminator_loss, noise_schedule, policy_loss
from pokerirl.irl.table import expert_table_from_arrow
from pokerirl.irl.toy import toy_expert_table


class RowDataset(Dataset):
    """One expert row per ``__getitem__``, as tensors."""

    def __init__(self, data: ExpertData) -> None:
        self.data = data

    def __len__(self) -> int:
        return len(self.data)

    def __getitem__(self, i: int) -> tuple[torch.Tensor, ...]:
        d = self.data
        assert d.legal_mask is not None and d.rewards is not None
        return d.obs[i].float(), d.actions[i], d.legal_mask[i], d.rewards[i]


def peer_samples_per_second(data: ExpertData, config: AIRLConfig, batches: int) -> list[float]:
    """Per-row DataLoader + torch.optim.Adam + backward(); samples/s per window of batches."""
    torch.manual_seed(config.seed)
    reward_net, policy = build_nets(data, config)
    reward_opt = torch.optim.Adam(
        reward_net.parameters(), lr=config.reward_lr, weight_decay=config.reward_weight_decay
    )
    policy_opt = torch.optim.Adam(policy.parameters(), lr=config.policy_lr)
    sigma = noise_schedule(config.batch_size, config.sigma_start, config.sigma_end)
    loader = DataLoader(RowDataset(data), batch_size=config.batch_size, shuffle=True)
    window, rates, start, seen = max(batches // 4, 1), [], time.perf_counter(), 0
    for step, (obs, expert_action, mask, env_reward) in enumerate(loader, start=1):
        out = policy(obs, mask)
        pi_action = out.exp()  # the discrete policy's action vector: its distribution
        with torch.no_grad():
            noisy = policy.perturb(pi_action.detach(), sigma[: len(obs)], mask)
            log_pi_expert = policy.log_prob(out.detach(), expert_action)
            log_pi_noisy = policy.log_prob(out.detach(), noisy)
        d_loss, _ = discriminator_loss(
            reward_net(obs, expert_action),
            log_pi_expert,
            reward_net(obs, noisy),
            log_pi_noisy,
            beta=config.beta,
            env_reward=env_reward,
        )
        reward_opt.zero_grad()
        d_loss.backward()
        reward_opt.step()
        supervised = policy.supervised_loss(out, expert_action).mean()
        p_loss, _ = policy_loss(
            reward_net(obs, pi_action),
            policy.log_prob(out, pi_action),
            supervised,
            alpha=config.alpha,
        )
        policy_opt.zero_grad()
        p_loss.backward()
        policy_opt.step()
        d_loss.item(), p_loss.item()  # per-step logging, as reference loops do
        seen += len(obs)
        if step % window == 0:
            now = time.perf_counter()
            rates.append(seen / (now - start))
            start, seen = now, 0
        if step >= batches:
            break
    return rates


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=300_000)
    parser.add_argument("--epochs", type=int, default=3)
    parser.add_argument("--threads", type=int, default=1, help="as `pokerirl train` (default 1)")
    parser.add_argument("--peer-batches", type=int, default=200)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)

    table = toy_expert_table(num_hands=args.rows // 2 + 1, seed=0).slice(0, args.rows)
    expert = expert_table_from_arrow(table)
    data = expert.to_expert_data()
    val = data.subset(torch.arange(min(10_000, len(data))))
    config = AIRLConfig.for_algo("hairl", epochs=args.epochs, batch_size=256)
    print(
        f"{len(data):,} rows, batch {config.batch_size}, hidden {config.reward_hidden}, "
        f"{torch.get_num_threads()} threads, torch {torch.__version__}"
    )

    result = train(data, val, config=config, progress=False)
    ours = [result.samples_per_epoch / s for s in result.epoch_seconds]
    print(
        f"pokerirl.irl.train : best {max(ours):>9,.0f}  median {statistics.median(ours):>9,.0f}"
        f"  samples/s  ({len(ours)} epochs of {result.samples_per_epoch:,} samples)"
    )

    peer = peer_samples_per_second(data, config, args.peer_batches)
    print(
        f"per-row DataLoader : best {max(peer):>9,.0f}  median {statistics.median(peer):>9,.0f}"
        f"  samples/s  ({len(peer)} windows, {args.peer_batches} batches)"
    )
    print(f"ratio (median)     : {statistics.median(ours) / statistics.median(peer):.1f}x")


if __name__ == "__main__":
    main()
