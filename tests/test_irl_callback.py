"""The trainer's EpochCallback, its typed records and the RewardNet protocol."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from pokerirl.irl import (
    AIRLConfig,
    EpochRecord,
    RewardNet,
    ShapedReward,
    StateActionReward,
    StepLosses,
    TrainingBatch,
    Transitions,
    train,
    train_many,
)
from pokerirl.irl.records import DISCRIMINATOR_METRICS, pack_step, unpack_steps


def _data(n: int = 192) -> Transitions:
    rng = np.random.default_rng(3)
    obs = rng.random((n, 4)).astype(np.float32)
    return Transitions.from_arrays(obs, (obs[:, 0] * 3).astype(np.int64), groups=np.arange(n))


def _config(alpha: float = 0.5) -> AIRLConfig:
    return AIRLConfig.for_algo("hairl", epochs=2, batch_size=64, alpha=alpha)


def test_callback_extras_join_each_runs_metrics_without_changing_training() -> None:
    data = _data()
    seen: list[EpochRecord] = []
    logged: list[list[dict]] = []

    def callback(record: EpochRecord) -> list[dict[str, float]]:
        seen.append(record)
        return [{"extra": 10.0 * record.epoch + r} for r in range(record.runs)]

    config = _config()

    def log(metrics: list[dict]) -> None:
        logged.append([dict(m) for m in metrics])

    with_cb = train_many(
        data, data, config=config, seeds=[1, 2], progress=False, callback=callback, on_epoch=log
    )
    plain = train_many(data, data, config=config, seeds=[1, 2], progress=False)
    assert [r.epoch for r in seen] == [1, 2]
    assert all(r.runs == 2 for r in seen)
    for r, (run, base) in enumerate(zip(with_cb.runs, plain.runs, strict=True)):
        assert [m["extra"] for m in run.metrics] == [10.0 + r, 20.0 + r]
        assert list(run.metrics[0])[-1] == "extra"  # after the trainer's own metrics
        assert [{k: v for k, v in m.items() if k != "extra"} for m in run.metrics] == base.metrics
        after, before = run.policy.state_dict(), base.policy.state_dict()
        assert all(torch.equal(after[name], before[name]) for name in before)
        assert seen[-1].policies[r] is run.policy and seen[-1].rewards[r] is run.reward
    assert logged[0][1]["extra"] == 11.0  # on_epoch sees the extras


def test_callback_reads_copies_of_the_metrics() -> None:
    def vandal(record: EpochRecord) -> None:
        record.metrics[0]["val_alignment"] = -1.0  # type: ignore[index]

    result = train(_data(), _data(), config=_config(), progress=False, callback=vandal)
    assert all(m["val_alignment"] >= 0 for m in result.metrics)


@pytest.mark.parametrize(
    ("extras", "message"),
    [
        (lambda record: [{"x": 1.0}] * (record.runs + 1), "metric sets for 1 runs"),
        (lambda record: [{"disc_loss": 1.0}], "'disc_loss' is the trainer's"),
    ],
)
def test_bad_callback_results_are_one_clear_error(extras, message) -> None:
    with pytest.raises(ValueError, match=message):
        train(_data(), _data(), config=_config(), progress=False, callback=extras)


def test_step_rows_round_trip_by_name() -> None:
    disc = torch.arange(8.0).view(1, 8)  # B = 2: f_E, f_π, log π_E, log π_π
    row = pack_step(disc, StepLosses(torch.tensor([7.0]), torch.tensor([8.0]), torch.tensor([9.0])))
    parts, losses = unpack_steps(row, 2)
    assert parts.f_policy.tolist() == [[2.0, 3.0]]
    assert parts.log_pi_policy.tolist() == [[6.0, 7.0]]
    assert losses.policy_adv_loss.tolist() == [8.0]
    assert losses.policy_sup_loss.tolist() == [9.0]


def test_behaviour_cloning_zeroes_exactly_the_discriminator_metrics() -> None:
    result = train(_data(), _data(), config=_config(alpha=1.0), adversarial=False, progress=False)
    last = result.metrics[-1]
    # Spelled out, not DISCRIMINATOR_METRICS itself: a key dropped there must fail here.
    off = ("disc_loss", "disc_airl_loss", "disc_env_loss", "disc_acc_expert",
           "disc_acc_policy", "reward_expert", "reward_policy", "reward_gap")  # fmt: skip
    assert set(DISCRIMINATOR_METRICS) == set(off)
    assert {key: last[key] for key in off} == dict.fromkeys(off, 0.0)
    assert last["policy_loss"] > 0 and last["policy_sup_loss"] == last["policy_loss"]


def test_batch_at_indexes_every_present_tensor() -> None:
    batch = TrainingBatch(
        obs=torch.zeros(3, 2, 4), expert=torch.ones(3, 2, 5), env=torch.arange(6.0).view(3, 2)
    )
    one = batch.at(2)
    assert one.obs.shape == (2, 4) and one.mask is None and one.env.tolist() == [4.0, 5.0]


def test_default_reward_nets_are_reward_nets_with_explicit_f_and_g() -> None:
    torch.manual_seed(0)
    plain = StateActionReward(obs_dim=3, action_dim=2, hidden=(4,))
    shaped = ShapedReward(obs_dim=3, action_dim=2, hidden=(4,), gamma=0.9)
    assert isinstance(plain, RewardNet) and isinstance(shaped, RewardNet)
    assert not isinstance(torch.nn.Linear(2, 2), RewardNet)
    obs, action = torch.randn(5, 3), torch.randn(5, 2)
    next_obs, done = torch.randn(5, 3), torch.tensor([False, True, False, False, True])
    f = shaped(obs, action, next_obs, done)
    g = shaped.transferable(obs, action)
    assert torch.equal(g, shaped.g(obs, action))
    assert not torch.allclose(f, g)  # the shaping terms γh(s') − h(s)
    assert torch.equal(plain.transferable(obs, action), plain(obs, action))
    predicted = shaped.predict(obs.numpy(), action.numpy(), next_obs.numpy(), done.numpy())
    assert predicted.dtype == np.float32
    np.testing.assert_allclose(predicted, f.detach().numpy(), rtol=0, atol=0)
    np.testing.assert_allclose(shaped.predict(obs.numpy(), action.numpy()), g.detach().numpy())
