"""Row weights (``Transitions.weights``) reach every loss, baseline and metric of the IRL core.

The data disagree with themselves on one state: action 0 on 100 rows of weight 3, action 1 on
200 rows of weight 1. Weighted, the expert plays 0 there (300 against 200); unweighted, 1. A
trainer, baseline or metric that ignored the weights would side with 1.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from pokerirl.irl import AIRLConfig, Transitions, baselines, discriminator_loss, evaluate, fast
from pokerirl.irl.adversarial import train
from pokerirl.irl.losses import weighted_mean
from pokerirl.irl.nets import NetSpec, build_nets
from pokerirl.irl.run import run_baselines

torch.set_num_threads(1)
STATE_A, STATE_B = [1.0, 0.0], [0.0, 1.0]


def conflicting(*, weighted: bool) -> Transitions:
    obs = np.array([STATE_A] * 300 + [STATE_B] * 100, dtype=np.float32)
    actions = np.array([0] * 100 + [1] * 200 + [2] * 100)
    weights = np.array([3.0] * 100 + [1.0] * 300, dtype=np.float32)
    imputed = np.arange(400) % 2 == 1  # half the rows "imputed": reported apart
    return Transitions.from_arrays(
        obs, actions, groups=np.arange(400), legal_mask=np.ones((400, 4), bool),
        weights=weights if weighted else None, imputed=imputed if weighted else None,
    )  # fmt: skip


def test_weighted_mean_and_discriminator_loss() -> None:
    values, weights = torch.tensor([1.0, 2.0, 6.0]), torch.tensor([1.0, 0.5, 0.5])
    assert weighted_mean(values, weights).item() == pytest.approx(3.0 / 2.0 + 1.0)
    f_e, lp_e, f_p, lp_p = (torch.randn(5) for _ in range(4))
    w = torch.rand(5) + 0.1
    total = discriminator_loss(f_e, lp_e, f_p, lp_p, weights=w)[0]
    manual = -(
        (torch.nn.functional.logsigmoid(f_e - lp_e) * w).sum()
        + (torch.nn.functional.logsigmoid(lp_p - f_p) * w).sum()
    ) / w.sum()
    torch.testing.assert_close(total, manual)
    ones = discriminator_loss(f_e, lp_e, f_p, lp_p, weights=torch.ones(5))[0]
    torch.testing.assert_close(ones, discriminator_loss(f_e, lp_e, f_p, lp_p)[0])


def test_baselines_count_rows_by_their_weights() -> None:
    weighted, plain = conflicting(weighted=True), conflicting(weighted=False)
    # Weighted: action 0 holds 300 of 600, so majority plays 0 and agrees on half the weight.
    assert baselines(weighted, weighted)["majority"] == pytest.approx(0.5)
    assert baselines(plain, plain)["majority"] == pytest.approx(0.5)  # 1: 200 of 400
    legal = baselines(weighted, weighted)["legal_majority"]
    assert legal == pytest.approx(0.5) and baselines(plain, plain)["legal_majority"] == 0.5


def test_evaluate_weighs_rows_and_reports_parts() -> None:
    data = conflicting(weighted=True)
    reward, policy = build_nets(NetSpec(reward_hidden=(4,), policy_hidden=(4,)), obs_dim=2,
                                action_dim=4, discrete=True)  # fmt: skip
    with torch.no_grad():  # a policy that plays action 1 everywhere
        policy.mlp[-1].weight.zero_()
        policy.mlp[-1].bias.copy_(torch.tensor([0.0, 5.0, 0.0, 0.0]))
    metrics = evaluate(reward, policy, data)
    assert metrics["val_alignment"] == pytest.approx(200 / 600)  # weighted, not 200 / 400
    assert metrics["val_expert_dist"][0] == pytest.approx(300 / 600)
    # The observed rows are the even ones: 50 of action 0 (weight 150), 100 of 1, 50 of 2.
    assert metrics["val_alignment_observed"] == pytest.approx(100 / 300)
    assert metrics["val_alignment_imputed"] == pytest.approx(100 / 300)
    assert "val_reward_alignment_imputed" in metrics
    unweighted = evaluate(reward, policy, conflicting(weighted=False))
    assert unweighted["val_alignment"] == pytest.approx(0.5)
    assert "val_alignment_observed" not in unweighted


@pytest.mark.parametrize("fast_path", [True, False])
def test_behaviour_cloning_follows_the_weights(fast_path: bool) -> None:
    config = AIRLConfig.for_algo("hairl", epochs=30, batch_size=50, alpha=1.0, seed=0)
    for weighted, expected in ((True, 0), (False, 1)):
        data = conflicting(weighted=weighted)
        result = train(data, data, config=config, adversarial=False, fast_path=fast_path,
                       progress=False)  # fmt: skip
        assert result.gradients == ("hand-derived" if fast_path else "autograd")
        with torch.no_grad():
            probs = result.policy(torch.tensor([STATE_A]), None).exp()[0]
        assert int(probs.argmax()) == expected, (weighted, probs)
        if weighted:  # the weighted expert's own shares at A: 0.6 and 0.4
            assert probs[0].item() == pytest.approx(0.6, abs=0.08)


@pytest.mark.parametrize("fast_path", [True, False])
def test_the_reward_follows_the_weights(fast_path: bool) -> None:
    """H-AIRL's reward (the discriminator's loss) reads the weights: its argmax at the state
    both actions share is the weighted expert's."""
    config = AIRLConfig.for_algo("hairl", epochs=40, batch_size=50, seed=0)
    for weighted, expected in ((True, 0), (False, 1)):
        data = conflicting(weighted=weighted)
        result = train(data, data, config=config, fast_path=fast_path, progress=False)
        with torch.no_grad():
            g = result.reward(torch.tensor([STATE_A]), torch.eye(4)[:, None, :]).view(-1)
        assert int(g[:2].argmax()) == expected, (weighted, g)


def test_bc_baseline_reports_the_parts() -> None:
    data = conflicting(weighted=True)
    config = AIRLConfig.for_algo("hairl", epochs=2, batch_size=50, seed=0)
    found = run_baselines(data, data, config=config)
    assert {"bc", "bc_observed", "bc_imputed", "majority", "legal_majority"} <= set(found)


def test_weights_must_be_positive_and_travel_with_subsets() -> None:
    data = conflicting(weighted=True)
    part = data.subset(np.arange(0, 400, 2))
    assert part.weights is not None and part.imputed is not None
    assert part.weights.tolist() == data.weights.tolist()[::2]  # type: ignore[union-attr]
    assert not bool(part.imputed.any())
    with pytest.raises(ValueError, match="positive"):
        dataclasses.replace(data, weights=torch.zeros(400))
    plain = conflicting(weighted=False)
    assert plain.fingerprint() != data.fingerprint()  # the weights are part of the data


@pytest.mark.parametrize("beta", [0.0, 0.4])
@pytest.mark.parametrize("alpha", [0.0, 0.33])
def test_weighted_hand_derived_gradients_match_autograd(alpha: float, beta: float) -> None:
    torch.manual_seed(0)
    reward, policy = build_nets(NetSpec(reward_hidden=(8,), policy_hidden=(8,)), obs_dim=5,
                                action_dim=4, discrete=True)  # fmt: skip
    obs, w = torch.rand(6, 5), torch.rand(6) + 0.2
    expert = torch.eye(4)[[0, 1, 3, 1, 2, 3]]
    seen = torch.softmax(torch.randn(6, 4), -1)
    log_pi = torch.log(torch.rand(12) * 0.9 + 0.05)
    env = torch.randn(6) if beta else None
    f = reward(obs, torch.stack((expert, seen)))
    discriminator_loss(f[0], log_pi[:6], f[1], log_pi[6:], beta=beta, env_reward=env,
                       weights=w)[0].backward()  # fmt: skip
    with torch.no_grad():
        cache = fast.reward_forward(reward, obs, torch.stack((expert, seen)))
        grad_f = fast.discriminator_grad(cache.head_acts[-1].view(-1), log_pi, beta=beta,
                                         env_reward=env, weights=w)  # fmt: skip
        manual = fast.reward_backward(reward, cache, grad_f)
    for a, p in zip(manual, reward.parameters(), strict=True):
        torch.testing.assert_close(a, p.grad, atol=1e-5, rtol=1e-4)

    g = torch.randn(6, 4)
    lp = policy(obs, None)
    probs = lp.exp()
    loss = (1 - alpha) * weighted_mean((probs * (lp - g)).sum(-1), w) + alpha * weighted_mean(
        -(expert * lp).sum(-1), w)  # fmt: skip
    loss.backward()
    with torch.no_grad():
        acts = fast.mlp_forward(policy.mlp, obs)
        grads = fast.policy_backward(policy, acts, torch.log_softmax(acts[-1], -1), g, expert,
                                     alpha, weights=w)  # fmt: skip
    for a, p in zip(grads, policy.parameters(), strict=True):
        torch.testing.assert_close(a, p.grad, atol=1e-5, rtol=1e-4)


def test_runs_in_lock_step_read_the_weights() -> None:
    from pokerirl.irl.adversarial import train_many

    config = AIRLConfig.for_algo("hairl", epochs=30, batch_size=50, alpha=1.0, seed=0)
    data = conflicting(weighted=True)
    many = train_many(data, data, config=config, seeds=[0, 1], adversarial=False,
                      progress=False)  # fmt: skip
    for run in many.runs:
        with torch.no_grad():
            probs = run.policy(torch.tensor([STATE_A]), None).exp()[0]
        assert int(probs.argmax()) == 0, probs
