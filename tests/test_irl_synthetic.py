"""H-AIRL against AIRL on the synthetic IRC demo data, whose expert rule is known."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from pokerirl.datasets.ingest import ingest
from pokerirl.game.synth import write_synthetic_month
from pokerirl.irl import load_config, train_table
from pokerirl.irl.airl import _expected_reward_and_grad
from pokerirl.irl.nets import DiscretePolicy, RewardNet


@pytest.fixture(scope="module")
def synthetic_tables(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    tables = []
    for seed in (0, 1, 2):
        root = tmp_path_factory.mktemp(f"synth{seed}")
        folder = write_synthetic_month(root / "irc", hands=6000, seed=seed)
        ingest([folder], root / "expert.parquet")
        tables.append(root / "expert.parquet")
    return tables


def test_hairl_beats_majority_and_airl_on_synthetic_demo_data(
    synthetic_tables: list[Path], tmp_path: Path
) -> None:
    torch.set_num_threads(1)
    alignment: dict[str, list[float]] = {"hairl": [], "airl": []}
    majority = []
    for seed, table in enumerate(synthetic_tables):
        for algo in alignment:
            config = load_config(algo, overrides={"epochs": 8, "seed": seed})
            summary = train_table(
                str(table),
                str(tmp_path / f"{algo}{seed}"),
                algo=algo,
                config=config,
                device="cpu",
                progress=False,
            )
            alignment[algo].append(summary.metrics[-1]["val_alignment"])
        majority.append(summary.metrics[-1]["majority_alignment"])
    hairl, airl = np.array(alignment["hairl"]), np.array(alignment["airl"])
    assert (hairl > np.array(majority) + 0.15).all(), (hairl, majority)
    assert hairl.mean() > airl.mean() + 0.01, (hairl, airl)


def test_expected_reward_gradient_matches_autograd() -> None:
    torch.manual_seed(0)
    reward_net = RewardNet(obs_dim=5, action_dim=4, hidden=(8,))
    policy = DiscretePolicy(obs_dim=5, num_actions=4, hidden=(8,))
    obs = torch.rand(6, 5)
    mask = torch.tensor([[True, True, True, False]] * 3 + [[False, True, True, True]] * 3)
    out = policy.act(obs, mask)
    weight = torch.linspace(-1.0, 1.0, 6)
    with torch.no_grad():
        expected, grad = _expected_reward_and_grad(reward_net, policy, obs, out, weight)
    probs = out.action.detach().clone().requires_grad_(True)
    by_action = torch.stack([reward_net(obs, torch.eye(4)[k].expand(6, 4)) for k in range(4)], 1)
    reference = (probs * by_action).sum(dim=1)
    (reference * weight).sum().backward()
    torch.testing.assert_close(expected, reference.detach())
    torch.testing.assert_close(grad, probs.grad)


def test_sampled_actions_are_legal_one_hots_with_the_policy_frequencies() -> None:
    torch.manual_seed(0)
    policy = DiscretePolicy(obs_dim=5, num_actions=4, hidden=(8,))
    obs = torch.rand(1, 5).expand(40_000, 5)
    mask = torch.tensor([True, True, False, True]).expand(40_000, 4)
    out = policy.act(obs, mask)
    sampled = policy.sample_action(out, torch.Generator().manual_seed(1))
    assert ((sampled == 0) | (sampled == 1)).all() and (sampled.sum(dim=1) == 1).all()
    assert (sampled[:, 2] == 0).all()  # the illegal action is never drawn
    frequencies = sampled.mean(dim=0)
    torch.testing.assert_close(frequencies, out.action[0], atol=0.01, rtol=0)


def test_trained_nets_stay_usable_by_autograd() -> None:
    from pokerirl.irl.airl import AIRLConfig, ExpertData, train

    torch.manual_seed(0)
    obs = torch.rand(300, 6)
    data = ExpertData.from_action_ids(obs, (obs[:, 0] > 0.5).long(), num_actions=2)
    result = train(data, data, config=AIRLConfig.for_algo("hairl", epochs=2), progress=False)
    assert not any(p.is_inference() for p in result.reward_net.parameters())
    loss = result.reward_net(obs, torch.eye(2)[(obs[:, 1] > 0.5).long()]).sum()
    loss.backward()  # fine-tuning after training must work
    assert all(p.grad is not None for p in result.reward_net.parameters())
