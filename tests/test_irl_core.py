"""Hand-checked losses, the noise schedule, the simplex projection, nets and FlatAdam."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from pokerirl.irl import (
    AIRLConfig,
    DiscretePolicy,
    GaussianPolicy,
    RewardNet,
    discriminator_grad,
    discriminator_loss,
    log_discriminator,
    noise_schedule,
    policy_loss,
    project_to_simplex,
)
from pokerirl.irl.optim import FlatAdam

torch.set_num_threads(1)


def _t(*values: float) -> torch.Tensor:
    return torch.tensor(values, dtype=torch.float64)


def test_log_discriminator_matches_hand_computed_ratio() -> None:
    # D = e^f / (e^f + π): f = log 2, π = 0.5 gives 2 / 2.5 = 0.8.
    log_d, log_not_d = log_discriminator(_t(math.log(2)), _t(math.log(0.5)))
    assert log_d.item() == pytest.approx(math.log(0.8))
    assert log_not_d.item() == pytest.approx(math.log(0.2))


def test_log_discriminator_is_finite_at_extremes() -> None:
    log_d, log_not_d = log_discriminator(_t(1000.0, -1000.0), _t(-1000.0, 1000.0))
    assert torch.isfinite(log_d).all() and torch.isfinite(log_not_d).all()
    assert log_d[0].item() == pytest.approx(0.0)
    assert log_not_d[1].item() == pytest.approx(0.0)


def test_discriminator_loss_matches_hand_computed_values() -> None:
    f_e, pi_e = [0.5, -1.0], [0.6, 0.3]
    f_p, pi_p = [0.2, 1.5], [0.25, 0.9]
    d = lambda f, p: math.exp(f) / (math.exp(f) + p)  # noqa: E731
    airl = -np.mean([math.log(d(f, p)) for f, p in zip(f_e, pi_e, strict=True)]) - np.mean(
        [math.log(1 - d(f, p)) for f, p in zip(f_p, pi_p, strict=True)]
    )
    args = (_t(*f_e), torch.log(_t(*pi_e)), _t(*f_p), torch.log(_t(*pi_p)))
    total, airl_part = discriminator_loss(*args)
    assert total.item() == pytest.approx(airl) and airl_part.item() == pytest.approx(airl)

    r_env = [1.0, 0.0]
    regression = np.mean([(f - r) ** 2 for f, r in zip(f_e, r_env, strict=True)])
    total, airl_part = discriminator_loss(*args, beta=0.25, env_reward=_t(*r_env))
    assert total.item() == pytest.approx(0.75 * airl + 0.25 * regression)
    assert airl_part.item() == pytest.approx(airl)
    # No environment rewards: β has nothing to weigh, the loss is plain AIRL.
    assert discriminator_loss(*args, beta=0.25)[0].item() == pytest.approx(airl)


def test_policy_loss_matches_hand_computed_values() -> None:
    f, log_pi, sup = _t(1.0, -2.0), _t(-0.5, -0.1), _t(0.7)
    adversarial = ((-0.5 - 1.0) + (-0.1 + 2.0)) / 2
    total, adv = policy_loss(f, log_pi, sup, alpha=0.33)
    assert adv.item() == pytest.approx(adversarial)
    assert total.item() == pytest.approx(0.67 * adversarial + 0.33 * 0.7)


def test_discrete_policy_terms_by_hand() -> None:
    policy = DiscretePolicy(obs_dim=2, num_actions=4, hidden=())
    with torch.no_grad():
        policy.mlp[0].weight.zero_()
        policy.mlp[0].bias.copy_(torch.tensor([0.0, math.log(2), 5.0, 0.0]))
    mask = torch.tensor([[True, True, False, True]])
    log_probs = policy(torch.zeros(1, 2), mask)
    probs = log_probs.exp()
    assert probs.tolist()[0] == pytest.approx([0.25, 0.5, 0.0, 0.25])
    one_hot = torch.tensor([[0.0, 1.0, 0.0, 0.0]])
    assert policy.log_prob(log_probs, one_hot).item() == pytest.approx(math.log(0.5))
    neg_entropy = 0.5 * math.log(0.25) + 0.5 * math.log(0.5)
    assert policy.log_prob(log_probs, probs).item() == pytest.approx(neg_entropy)
    assert policy.supervised_loss(log_probs, one_hot).item() == pytest.approx(-math.log(0.5))


def test_gaussian_policy_log_prob_matches_torch_normal() -> None:
    torch.manual_seed(0)
    policy = GaussianPolicy(obs_dim=3, low=[-1.0, 0.0], high=[1.0, 4.0], hidden=(8,))
    mean = policy(torch.randn(5, 3))
    assert ((mean >= policy.low) & (mean <= policy.high)).all()
    action = torch.randn(5, 2)
    expected = torch.distributions.Normal(mean, policy.log_std.exp()).log_prob(action).sum(-1)
    assert torch.allclose(policy.log_prob(mean, action), expected)
    noisy = policy.perturb(mean, torch.full((5,), 10.0), None)
    assert ((noisy >= policy.low) & (noisy <= policy.high)).all()


def test_reward_net_split_first_layer_equals_concatenation() -> None:
    torch.manual_seed(0)
    net = RewardNet(obs_dim=5, action_dim=3, hidden=(7, 4))
    obs, action = torch.randn(6, 5), torch.randn(6, 3)
    first = torch.nn.Linear(8, 7)
    with torch.no_grad():
        first.weight.copy_(torch.cat([net.obs_layer.weight, net.action_layer.weight], 1))
        first.bias.copy_(net.obs_layer.bias)
    on_concat = net.head(torch.relu(first(torch.cat([obs, action], 1)))).squeeze(-1)
    assert torch.allclose(net(obs, action), on_concat)


def test_noise_schedule_is_monotone_with_exact_endpoints() -> None:
    sigma = noise_schedule(256, 1.0, 0.1)
    assert sigma.shape == (256,)
    assert sigma[0].item() == pytest.approx(1.0) and sigma[-1].item() == pytest.approx(0.1)
    assert (sigma[1:] <= sigma[:-1]).all() and (sigma[1:] < sigma[:-1]).any()
    assert noise_schedule(1, 0.7, 0.1).tolist() == pytest.approx([0.7])
    assert (noise_schedule(10, 0.0, 0.0) == 0).all()


vectors = st.lists(st.floats(-5, 5, allow_nan=False), min_size=2, max_size=6)


@settings(max_examples=200, deadline=None)
@given(vectors)
def test_simplex_projection_is_the_euclidean_projection(values: list[float]) -> None:
    v = torch.tensor([values], dtype=torch.float64)
    p = project_to_simplex(v)
    assert (p >= 0).all() and p.sum().item() == pytest.approx(1.0)
    # Optimality: <v - p, q - p> <= 0 for every q in the simplex; checking the vertices is
    # enough, the simplex being their convex hull.
    for j in range(v.shape[1]):
        vertex = torch.zeros_like(v)
        vertex[0, j] = 1
        assert ((v - p) * (vertex - p)).sum().item() <= 1e-9
    # Projecting again changes nothing.
    assert torch.allclose(project_to_simplex(p), p)


def test_simplex_projection_by_hand_and_with_mask() -> None:
    v = torch.tensor([[0.5, 0.5, 2.0], [0.6, 0.2, 0.2], [0.3, 0.3, 0.3]])
    expected = [[0.0, 0.0, 1.0], [0.6, 0.2, 0.2], [1 / 3, 1 / 3, 1 / 3]]
    assert torch.allclose(project_to_simplex(v), torch.tensor(expected))
    mask = torch.tensor([[True, False, True, True]])
    v = torch.tensor([[0.2, 3.0, 0.9, -0.4]])
    p = project_to_simplex(v, mask)
    assert p[0, 1] == 0
    legal = project_to_simplex(v[:, [0, 2, 3]])
    assert torch.allclose(p[:, [0, 2, 3]], legal)


def test_flat_adam_matches_torch_adam() -> None:
    torch.manual_seed(0)
    net_a = torch.nn.Sequential(torch.nn.Linear(4, 8), torch.nn.ReLU(), torch.nn.Linear(8, 2))
    net_b = torch.nn.Sequential(torch.nn.Linear(4, 8), torch.nn.ReLU(), torch.nn.Linear(8, 2))
    net_b.load_state_dict(net_a.state_dict())
    reference = torch.optim.Adam(net_a.parameters(), lr=0.01, weight_decay=5e-3)
    flat = FlatAdam(net_b.parameters(), lr=0.01, weight_decay=5e-3)
    for step in range(5):
        x = torch.randn(16, 4, generator=torch.Generator().manual_seed(step))
        reference.zero_grad()
        net_a(x).square().mean().backward()
        reference.step()
        flat.step(torch.autograd.grad(net_b(x).square().mean(), flat.params))
    for a, b in zip(net_a.parameters(), net_b.parameters(), strict=True):
        assert torch.allclose(a, b, atol=1e-6)
    assert not torch.allclose(net_a[0].weight, torch.zeros(8, 4))


def test_config_defaults_and_validation() -> None:
    hairl, airl = AIRLConfig.for_algo("hairl"), AIRLConfig.for_algo("airl")
    assert (hairl.alpha, hairl.beta, hairl.sigma_start, hairl.sigma_end) == (0.33, 0.0, 1.0, 0.1)
    assert (airl.alpha, airl.beta, airl.sigma_start, airl.sigma_end) == (0.0, 0.0, 0.0, 0.0)
    for shared in ("reward_hidden", "policy_hidden", "reward_lr", "batch_size", "epochs"):
        assert getattr(hairl, shared) == getattr(airl, shared)
    assert (hairl.reward_hidden, hairl.batch_size, hairl.epochs) == ((64,), 256, 50)
    assert AIRLConfig.for_algo("airl", alpha=0.5).alpha == 0.5
    with pytest.raises(ValueError, match="unknown algo"):
        AIRLConfig.for_algo("gail")
    with pytest.raises(ValueError, match="unknown setting"):
        AIRLConfig.for_algo("hairl", alhpa=0.5)
    with pytest.raises(ValueError, match="alpha"):
        AIRLConfig.for_algo("hairl", alpha=1.5)


# --------------------------------------------------------------------------- hand-derived gradients
# Training skips autograd; these check every hand-derived gradient against autograd applied to
# the documented losses.


def _close(manual: list[torch.Tensor], reference: tuple[torch.Tensor, ...]) -> None:
    assert len(manual) == len(reference)
    for a, b in zip(manual, reference, strict=True):
        assert a.shape == b.shape
        assert torch.allclose(a, b, atol=1e-5, rtol=1e-4), (a, b)


@pytest.mark.parametrize("beta", [0.0, 0.3])
def test_discriminator_grad_matches_autograd(beta: float) -> None:
    g = torch.Generator().manual_seed(1)
    f = torch.randn(12, generator=g, dtype=torch.float64, requires_grad=True)
    log_pi = torch.log(torch.rand(12, generator=g, dtype=torch.float64))
    reward = torch.randn(6, generator=g, dtype=torch.float64)
    loss, _ = discriminator_loss(f[:6], log_pi[:6], f[6:], log_pi[6:], beta=beta, env_reward=reward)
    (expected,) = torch.autograd.grad(loss, f)
    manual = discriminator_grad(f.detach(), log_pi, beta=beta, env_reward=reward)
    assert torch.allclose(manual, expected)


@pytest.mark.parametrize("hidden", [(8,), (8, 5)])
def test_reward_net_backward_matches_autograd(hidden: tuple[int, ...]) -> None:
    torch.manual_seed(0)
    net = RewardNet(obs_dim=5, action_dim=3, hidden=hidden)
    obs = torch.randn(4, 5)
    actions = torch.rand(8, 3, requires_grad=True)  # two action vectors per state
    weights = torch.randn(8)
    f = net(obs, actions)
    expected = torch.autograd.grad((f * weights).sum(), [*net.parameters(), actions])
    with torch.no_grad():
        f_manual, cache = net.forward_cached(obs, actions.detach())
        grads, grad_actions = net.backward(cache, weights)
        _, only_actions = net.backward(cache, weights, params=False)
    assert torch.allclose(f_manual, f.detach())
    _close([*grads, grad_actions], expected)
    assert torch.equal(only_actions, grad_actions)
    only_params, none = net.backward(cache, weights, actions=False)
    assert none is None and all(torch.equal(a, b) for a, b in zip(only_params, grads, strict=True))


def _policy_reference(policy, reward, obs, mask, expert, alpha, noise=None):
    """Autograd through the documented policy loss."""
    dist = policy(obs, mask)
    if policy.discrete:
        action = dist.exp()
    else:
        action = dist + policy.log_std.exp() * noise
    supervised = policy.supervised_loss(dist, expert).mean()
    loss, _ = policy_loss(
        reward(obs, action), policy.log_prob(dist, action), supervised, alpha=alpha
    )
    return torch.autograd.grad(loss, list(policy.parameters()))


def _policy_manual(policy, reward, obs, mask, expert, alpha):
    with torch.no_grad():
        out = policy.act(obs, mask, torch.Generator().manual_seed(3))
        f_pi, cache = reward.forward_cached(obs, out.action)
        _, grad_action = reward.backward(cache, torch.full_like(f_pi, -(1 - alpha) / len(obs)))
        return out, policy.backward(out, grad_action, expert, alpha)


@pytest.mark.parametrize("alpha", [0.0, 0.33, 1.0])
def test_discrete_policy_backward_matches_autograd(alpha: float) -> None:
    torch.manual_seed(0)
    policy = DiscretePolicy(obs_dim=6, num_actions=4, hidden=(16, 8))
    reward = RewardNet(obs_dim=6, action_dim=4, hidden=(8,))
    obs = torch.randn(10, 6)
    mask = torch.rand(10, 4) < 0.7
    mask[:, 1] = True
    expert = torch.nn.functional.one_hot(torch.ones(10, dtype=torch.long), 4).float()
    _, manual = _policy_manual(policy, reward, obs, mask, expert, alpha)
    _close(manual, _policy_reference(policy, reward, obs, mask, expert, alpha))


@pytest.mark.parametrize("alpha", [0.0, 0.33, 1.0])
def test_gaussian_policy_backward_matches_autograd(alpha: float) -> None:
    torch.manual_seed(0)
    policy = GaussianPolicy(obs_dim=6, low=[-1.0, 0.0], high=[1.0, 3.0], hidden=(16,))
    reward = RewardNet(obs_dim=6, action_dim=2, hidden=(8, 4))
    obs = torch.randn(10, 6)
    expert = torch.rand(10, 2)
    out, manual = _policy_manual(policy, reward, obs, None, expert, alpha)
    reference = _policy_reference(policy, reward, obs, None, expert, alpha, noise=out.noise)
    _close(manual, reference)
