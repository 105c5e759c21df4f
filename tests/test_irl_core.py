"""Hand-checked losses, the noise schedules, the simplex projection, nets and configs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from pokerirl.irl import (
    AIRLConfig,
    ConfigError,
    NetSpec,
    StateActionReward,
    Transitions,
    build_nets,
    discriminator_loss,
    load_config,
    noise_schedule,
    project_to_simplex,
    train,
    train_many,
)
from pokerirl.irl.adversarial import gaussian_log_prob, sample_one_hot

torch.set_num_threads(1)


def _t(*values: float) -> torch.Tensor:
    return torch.tensor(values, dtype=torch.float64)


def test_discriminator_loss_matches_hand_computed_values() -> None:
    f_e, pi_e = [0.5, -1.0], [0.6, 0.3]
    f_p, pi_p = [0.2, 1.5], [0.25, 0.9]
    d = lambda f, p: math.exp(f) / (math.exp(f) + p)  # noqa: E731
    airl = -np.mean([math.log(d(f, p)) for f, p in zip(f_e, pi_e, strict=True)]) - np.mean(
        [math.log(1 - d(f, p)) for f, p in zip(f_p, pi_p, strict=True)]
    )
    args = (_t(*f_e), torch.log(_t(*pi_e)), _t(*f_p), torch.log(_t(*pi_p)))
    total, airl_part, _ = discriminator_loss(*args)
    assert total.item() == pytest.approx(airl) and airl_part.item() == pytest.approx(airl)

    r_env = [1.0, 0.0]
    regression = np.mean([(f - r) ** 2 for f, r in zip(f_e, r_env, strict=True)])
    total, airl_part, env = discriminator_loss(*args, beta=0.25, env_reward=_t(*r_env))
    assert total.item() == pytest.approx(0.75 * airl + 0.25 * regression)
    assert airl_part.item() == pytest.approx(airl) and env.item() == pytest.approx(regression)
    # Extreme logits stay finite (log-space form).
    big = discriminator_loss(_t(1000.0), _t(-1000.0), _t(-1000.0), _t(1000.0))[0]
    assert big.item() == pytest.approx(0.0)


def test_gaussian_log_prob_matches_torch_normal() -> None:
    mean, log_std, action = torch.randn(5, 2), torch.randn(5, 2), torch.randn(5, 2)
    expected = torch.distributions.Normal(mean, log_std.exp()).log_prob(action).sum(-1)
    assert torch.allclose(gaussian_log_prob(action, mean, log_std), expected, atol=1e-6)


def test_sampled_one_hots_are_legal_with_the_policy_frequencies() -> None:
    probs = torch.tensor([0.2, 0.5, 0.0, 0.3]).expand(40_000, 4)
    u = torch.rand(40_000, generator=torch.Generator().manual_seed(1))
    sampled = sample_one_hot(probs, u)
    assert (sampled.sum(-1) == 1).all() and (sampled[:, 2] == 0).all()
    torch.testing.assert_close(sampled.mean(0), probs[0], atol=0.01, rtol=0)


def test_reward_net_split_first_layer_equals_concatenation_and_broadcasts() -> None:
    torch.manual_seed(0)
    net = StateActionReward(obs_dim=5, action_dim=3, hidden=(7, 4), activation="tanh")
    obs, action = torch.randn(6, 5), torch.randn(6, 3)
    first = torch.nn.Linear(8, 7)
    with torch.no_grad():
        first.weight.copy_(torch.cat([net.obs_layer.weight, net.action_layer.weight], 1))
        first.bias.copy_(net.obs_layer.bias)
    on_concat = net.head(torch.tanh(first(torch.cat([obs, action], 1)))).squeeze(-1)
    assert torch.allclose(net(obs, action), on_concat)
    several = net(obs, torch.stack([action, -action]))  # (2, B): two actions per state
    assert torch.allclose(several[1], net(obs, -action))


@pytest.mark.parametrize("activation", ["relu", "tanh", "leaky_relu"])
@pytest.mark.parametrize("layer_norm", [False, True])
def test_configured_nets_are_what_trains_and_what_evaluates(
    activation: str, layer_norm: bool
) -> None:
    spec = NetSpec(reward_hidden=(8, 8), activation=activation, layer_norm=layer_norm)
    reward, policy = build_nets(spec, obs_dim=3, action_dim=2, discrete=True)
    kinds = {type(m).__name__ for m in [*reward.modules(), *policy.modules()]}
    expected = {"relu": "ReLU", "tanh": "Tanh", "leaky_relu": "LeakyReLU"}[activation]
    assert expected in kinds and ("LayerNorm" in kinds) == layer_norm
    assert not ({"ReLU", "Tanh", "LeakyReLU"} - {expected}) & kinds
    # Training moves exactly these modules (no separate training path).
    rng = np.random.default_rng(0)
    obs = rng.random((128, 3)).astype(np.float32)
    data = Transitions.from_arrays(obs, (obs[:, 0] > 0.5).astype(np.int64), groups=np.arange(128))
    before = [p.detach().clone() for p in reward.parameters()]
    config = AIRLConfig.for_algo("hairl", epochs=1, batch_size=32, activation=activation)
    train(data, data, config=config, reward=reward, policy=policy, progress=False)
    assert all(not torch.equal(a, b) for a, b in zip(before, reward.parameters(), strict=True))


def test_noise_schedules() -> None:
    sigma = noise_schedule(256, 1.0, 0.1)
    assert sigma.shape == (256,)
    assert sigma[0].item() == pytest.approx(1.0) and sigma[-1].item() == pytest.approx(0.1)
    assert (sigma[1:] <= sigma[:-1]).all() and (sigma[1:] < sigma[:-1]).any()
    assert noise_schedule(1, 0.7, 0.1).tolist() == pytest.approx([0.7])
    assert (noise_schedule(10, 0.0, 0.0) == 0).all()
    # The authors': σ_i = σ_start / (1 + k b i), b = (σ_start − σ_end) / (σ_end B).
    authors = noise_schedule(256, 1.0, 0.1, kind="authors", decay=0.1)
    b = (1.0 - 0.1) / (0.1 * 256)
    expected = [1.0 / (1 + 0.1 * b * i) for i in range(256)]
    assert authors.tolist() == pytest.approx(expected, rel=1e-6)
    assert authors[-1].item() == pytest.approx(1 / (1 + 0.1 * 9 * 255 / 256))  # ~0.53
    # With k = 1 it ends at σ_end one step past the batch.
    assert (1.0 / (1 + b * 256)) == pytest.approx(0.1)


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


def test_config_defaults_and_validation() -> None:
    hairl, airl = AIRLConfig.for_algo("hairl"), AIRLConfig.for_algo("airl")
    assert (hairl.alpha, hairl.beta, hairl.sigma_start, hairl.sigma_end) == (0.33, 0.0, 1.0, 0.1)
    assert (airl.alpha, airl.beta, airl.sigma_start, airl.sigma_end) == (0.0, 0.0, 0.0, 0.0)
    for shared in ("reward_hidden", "policy_hidden", "reward_lr", "batch_size", "epochs"):
        assert getattr(hairl, shared) == getattr(airl, shared)
    assert (hairl.reward_hidden, hairl.batch_size, hairl.epochs) == ((64,), 256, 50)
    assert (hairl.reward_family, hairl.activation, hairl.disc_action) == (
        "state_action",
        "relu",
        "sample",
    )
    assert AIRLConfig.for_algo("airl", alpha=0.5).alpha == 0.5
    with pytest.raises(ValueError, match="unknown algo"):
        AIRLConfig.for_algo("sqil")
    with pytest.raises(ValueError, match="unknown setting"):
        AIRLConfig.for_algo("hairl", alhpa=0.5)
    with pytest.raises(ValueError, match="alpha"):
        AIRLConfig.for_algo("hairl", alpha=1.5)
    with pytest.raises(ValueError, match="activation"):
        AIRLConfig.for_algo("hairl", activation="sigmoid")


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("epochs = 1.5", "epochs must be an integer, got 1.5"),
        ("epochs = true", "epochs must be an integer, got True"),
        ('epochs = "ten"', "epochs must be an integer, got 'ten'"),
        ("alpha = false", "alpha must be a number"),
        ('reward_hidden = [64, "x"]', "reward_hidden must be a list of integers"),
        ('layer_norm = "yes"', "layer_norm must be true or false"),
        ("reward_family = 3", "reward_family must be one of state_action, shaped, got 3"),
    ],
)
def test_toml_type_errors_are_one_line_naming_key_and_file(
    tmp_path: Path, line: str, message: str
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(line + "\n")
    with pytest.raises(ConfigError) as info:
        load_config("hairl", config_file=path)
    text = str(info.value)
    assert "\n" not in text and text.startswith(str(path)) and message in text


def test_toml_config_of_the_issue_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "c.toml"
    path.write_text(
        'reward_hidden = [64, 64]\npolicy_hidden = [64, 64]\nactivation = "tanh"\n'
        'layer_norm = true\nreward_family = "shaped"\ngamma = 0.99\nalpha = 1\n'
    )
    config = load_config("hairl", config_file=path)
    assert (config.reward_hidden, config.policy_hidden) == ((64, 64), (64, 64))
    assert (config.activation, config.layer_norm, config.reward_family) == ("tanh", True, "shaped")
    assert config.alpha == 1.0 and isinstance(config.alpha, float)


@pytest.mark.parametrize("discrete", [True, False])
def test_lock_step_runs_equal_separate_runs(discrete: bool) -> None:
    """train_many's run r (vmap over stacked parameters) is train(seed r), up to rounding."""
    rng = np.random.default_rng(0)
    obs = rng.random((192, 4)).astype(np.float32)
    if discrete:
        actions = (obs[:, 0] > 0.5).astype(np.int64) + (obs[:, 1] > 0.5)
        mask = np.ones((192, 3), bool)
        data = Transitions.from_arrays(obs, actions, groups=np.arange(192), legal_mask=mask)
    else:
        data = Transitions.from_arrays(
            obs, (obs[:, :2] - 0.5).astype(np.float32), groups=np.arange(192), low=[-1, -1],
            high=[1, 1],
        )  # fmt: skip
    config = AIRLConfig.for_algo(
        "hairl", epochs=2, batch_size=32, layer_norm=True, noise_schedule="authors"
    )
    many = train_many(data, data, config=config, seeds=[3, 4], progress=False)
    for run, seed in zip(many.runs, [3, 4], strict=True):
        alone = train(data, data, config=AIRLConfig(**{**config.to_dict(), "seed": seed}),
                      progress=False)  # fmt: skip
        for a, b in zip(run.reward.parameters(), alone.reward.parameters(), strict=True):
            torch.testing.assert_close(a, b, atol=1e-4, rtol=1e-4)
        for a, b in zip(run.policy.parameters(), alone.policy.parameters(), strict=True):
            torch.testing.assert_close(a, b, atol=1e-4, rtol=1e-4)
        assert run.metrics[-1]["disc_loss"] == pytest.approx(alone.metrics[-1]["disc_loss"],
                                                               rel=1e-4)  # fmt: skip
    first = next(iter(many.runs[0].reward.parameters()))
    assert not torch.allclose(first, next(iter(many.runs[1].reward.parameters())))


def test_shaped_family_needs_next_obs() -> None:
    data = Transitions.from_arrays(np.zeros((8, 2)), np.zeros(8, np.int64), groups=np.arange(8))
    config = AIRLConfig.for_algo("hairl", epochs=1, reward_family="shaped")
    with pytest.raises(ValueError, match="next_obs"):
        train(data, data, config=config, progress=False)


class ConcatReward(torch.nn.Module):
    """A reward net the lock-step stacking does not know: runs go through vmap instead."""

    def __init__(self, obs_dim: int, action_dim: int) -> None:
        super().__init__()
        self.net = torch.nn.Sequential(
            torch.nn.Linear(obs_dim + action_dim, 8), torch.nn.ELU(), torch.nn.Linear(8, 1)
        )

    def forward(self, obs, action, next_obs=None, done=None):
        rows = torch.broadcast_shapes(obs.shape[:-1], action.shape[:-1])
        both = (obs.expand(*rows, obs.shape[-1]), action.expand(*rows, action.shape[-1]))
        return self.net(torch.cat(both, dim=-1)).squeeze(-1)


def test_lock_step_with_an_unknown_architecture_uses_vmap_and_matches() -> None:
    from pokerirl.irl import default_nets
    from pokerirl.irl.adversarial import stack_modules

    rng = np.random.default_rng(1)
    obs = rng.random((128, 4)).astype(np.float32)
    data = Transitions.from_arrays(obs, (obs[:, 0] > 0.5).astype(np.int64), groups=np.arange(128))
    config = AIRLConfig.for_algo("hairl", epochs=2, batch_size=32)

    def nets(seed: int) -> tuple[torch.nn.Module, torch.nn.Module]:
        torch.manual_seed(seed)
        return ConcatReward(4, 2), default_nets(data, config, seed)[1]

    assert stack_modules([nets(0)[0], nets(1)[0]]) is None  # ELU is not a known layer
    pairs = [nets(s) for s in (0, 1)]
    many = train_many(
        data, data, config=config, seeds=[0, 1], rewards=[p[0] for p in pairs],
        policies=[p[1] for p in pairs], progress=False,
    )  # fmt: skip
    for run, seed in zip(many.runs, [0, 1], strict=True):
        reward, policy = nets(seed)
        alone = train(
            data, data, config=AIRLConfig(**{**config.to_dict(), "seed": seed}),
            reward=reward, policy=policy, progress=False,
        )  # fmt: skip
        for a, b in zip(run.reward.parameters(), alone.reward.parameters(), strict=True):
            torch.testing.assert_close(a, b, atol=1e-4, rtol=1e-4)


def test_flat_adam_matches_torch_adam_with_autograd_gradients() -> None:
    from pokerirl.irl.optim import FlatAdam

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
        flat.zero_grad()
        net_b(x).square().mean().backward()  # accumulates into the flat gradient buffer
        flat.step()
    for a, b in zip(net_a.parameters(), net_b.parameters(), strict=True):
        torch.testing.assert_close(a, b, atol=1e-6, rtol=1e-5)
    assert not torch.allclose(net_a[0].weight, net_b[0].weight.detach() * 0)


@pytest.mark.parametrize("family", ["state_action", "shaped"])
@pytest.mark.parametrize("discrete", [True, False])
def test_folding_a_standardization_keeps_every_default_net_the_same_function(
    family: str, discrete: bool
) -> None:
    from pokerirl.irl.nets import fold_obs_standardization

    torch.manual_seed(0)
    spec = NetSpec(reward_hidden=(8, 4), policy_hidden=(8,), reward_family=family)
    action_dim = 3 if discrete else 2
    reward, policy = build_nets(
        spec, obs_dim=4, action_dim=action_dim, discrete=discrete, low=[-1, -2], high=[1, 2]
    )
    x, x2 = torch.randn(6, 4) * 5 + 3, torch.randn(6, 4) * 5 + 3
    actions = torch.rand(2, 6, action_dim)
    done = torch.tensor([True, False] * 3)
    shift, scale = torch.tensor([3.0, -1.0, 0.5, 2.0]), torch.tensor([5.0, 0.07, 1.0, 2.0])
    z, z2 = (x - shift) / scale, (x2 - shift) / scale
    f_before = reward(z, actions, z2, done)
    pi_before = policy(z, None) if discrete else policy(z)[0]
    fold_obs_standardization(reward, shift, scale)
    fold_obs_standardization(policy, shift, scale)
    torch.testing.assert_close(reward(x, actions, x2, done), f_before, atol=1e-5, rtol=1e-5)
    pi_after = policy(x, None) if discrete else policy(x)[0]
    torch.testing.assert_close(pi_after, pi_before, atol=1e-5, rtol=1e-5)
    with pytest.raises(TypeError, match="not one of the default nets"):
        fold_obs_standardization(torch.nn.Linear(4, 1), shift, scale)
