"""The DQN: masked Double-DQN targets, the update, rewards per decision, learning."""

from __future__ import annotations

import dataclasses
from collections import Counter

import numpy as np
import pytest
import torch
from torch import nn

from pokerirl.agents.dqn import (
    DQNConfig,
    DQNLearner,
    ReplayMemory,
    double_dqn_targets,
    epsilon_at,
    train_dqn,
)
from pokerirl.game import make_agent, play_match
from pokerirl.holdem import NUM_ACTIONS, OBS_SIZE

torch.set_num_threads(1)
SMALL = DQNConfig(concurrent_hands=64, replay_init=32)


def test_the_replay_memory_is_a_ring_buffer_across_its_wrap() -> None:
    """Adds that fit before the end and adds that wrap put each transition where a ring
    buffer does (slot = its number modulo the capacity): the last ``capacity`` are kept."""
    memory = ReplayMemory(capacity=10)
    number = 0
    for count in (4, 5, 3, 8, 10, 1):  # the third wraps, the fifth fills it exactly
        numbers = np.arange(number, number + count)
        obs = np.broadcast_to(numbers[:, None] % 256, (count, OBS_SIZE)).astype(np.uint8)
        memory.add(obs, numbers, numbers.astype(np.float32), obs, np.ones((count, 4), bool),
                   numbers % 2 == 0)  # fmt: skip
        number += count
        kept = np.arange(max(0, number - 10), number)
        assert memory.size == kept.size and memory.position == number % 10
        slots = kept % 10
        assert memory.actions[slots].tolist() == kept.tolist()
        assert (memory.obs[slots] == (kept % 256)[:, None]).all()
        assert (memory.next_obs[slots] == (kept % 256)[:, None]).all()
        assert memory.rewards[slots].tolist() == kept.tolist()
        assert memory.done[slots].tolist() == (kept % 2 == 0).tolist()


def test_double_dqn_targets_match_hand_computed_values() -> None:
    legal = torch.tensor(
        [
            [True, True, True, False],  # online's best overall (check, 9) is illegal
            [False, True, True, True],  # online's best overall (call, 5) is illegal
            [True, True, True, True],  # terminal: reward only
            [False, False, True, True],
        ]
    )
    q_online = torch.tensor(
        [[1.0, 4.0, 2.0, 9.0], [5.0, -1.0, 0.0, 3.0], [7.0, 0.0, 0.0, 0.0], [9.0, 9.0, -2.0, -3.0]]
    )
    q_target = torch.tensor(
        [[10.0, 20.0, 30.0, 40.0], [1.0, 2.0, 3.0, 4.0], [5.0, 5.0, 5.0, 5.0], [8.0, 8.0, 6.0, 7.0]]
    )
    rewards = torch.tensor([0.5, -1.0, 2.5, 0.0])
    done = torch.tensor([False, False, True, False])
    targets = double_dqn_targets(
        rewards=rewards,
        done=done,
        next_legal=legal,
        q_next_online=q_online,
        q_next_target=q_target,
        gamma=0.9,
    )
    # Row 0: online picks raise (4) among legal -> target's raise 20 -> 0.5 + 0.9 * 20.
    # Row 1: online picks check (3) -> target's check 4. Row 3: online picks fold (-2) -> 6.
    expected = [0.5 + 0.9 * 20.0, -1.0 + 0.9 * 4.0, 2.5, 0.0 + 0.9 * 6.0]
    np.testing.assert_allclose(targets.numpy(), expected, rtol=1e-6)


def test_update_regresses_onto_the_masked_target_and_copies_the_target_net() -> None:
    torch.manual_seed(0)
    config = dataclasses.replace(SMALL, batch_size=8, replay_init=1, target_update_every=2)
    learner = DQNLearner.create(config)
    rng = np.random.default_rng(1)
    obs = rng.integers(0, 2, (1, OBS_SIZE)).astype(np.uint8)
    next_obs = rng.integers(0, 2, (1, OBS_SIZE)).astype(np.uint8)
    with torch.no_grad():
        q_next = learner.q_net(torch.from_numpy(next_obs).float())[0]
    # Make the online network's overall favourite at s' illegal, so masking matters.
    next_legal = np.ones((1, NUM_ACTIONS), bool)
    next_legal[0, int(q_next.argmax())] = False
    learner.replay.add(obs, np.array([2]), np.array([1.5], np.float32), next_obs, next_legal, False)
    with torch.no_grad():
        best = max((a for a in range(NUM_ACTIONS) if next_legal[0, a]), key=lambda a: q_next[a])
        target = 1.5 + config.gamma * float(
            learner.target_net(torch.from_numpy(next_obs).float())[0, best]
        )
        learner.q_net.norm.train()  # the update's forward pass uses batch statistics
        q_taken = float(learner.q_net(torch.from_numpy(np.repeat(obs, 8, 0)).float())[0, 2])
        learner.q_net.norm.eval()
    loss = learner.update(rng)  # every sampled row is the one transition
    assert loss == pytest.approx((q_taken - target) ** 2, rel=1e-5)
    # The target network is copied at update 0 and 2, not at update 1.
    learner.update(rng)
    stale = [p.clone() for p in learner.target_net.parameters()]
    assert any(
        not torch.equal(a, b) for a, b in zip(stale, learner.q_net.parameters(), strict=True)
    )
    learner.update(rng)
    assert all(
        torch.equal(a, b)
        for a, b in zip(learner.target_net.parameters(), learner.q_net.parameters(), strict=True)
    )


class RecordingReward(nn.Module):
    """A small reward net f(s, a) = MLP([obs, one_hot(a)]) that remembers what it was asked."""

    def __init__(self) -> None:
        super().__init__()
        self.net = nn.Sequential(nn.Linear(OBS_SIZE + NUM_ACTIONS, 16), nn.Tanh(), nn.Linear(16, 1))
        self.calls: list[tuple[np.ndarray, np.ndarray]] = []

    def __call__(self, obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        self.calls.append((obs.copy(), actions.copy()))
        return self.value(obs, actions)

    def value(self, obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        one_hot = np.eye(NUM_ACTIONS, dtype=np.float32)[actions]
        features = torch.from_numpy(np.concatenate([obs.astype(np.float32), one_hot], axis=1))
        with torch.inference_mode():
            return self.net(features)[:, 0].numpy()


def test_learned_reward_is_evaluated_on_exactly_the_pairs_the_agent_took() -> None:
    torch.manual_seed(3)
    reward = RecordingReward()
    hands, weight = 300, 0.25
    # The raise agent never folds, so the learner acts in every hand and every hand ends with
    # exactly one terminal transition of the learner.
    learner = train_dqn(
        SMALL,
        hands=hands,
        seed=5,
        opponent=make_agent("raise"),
        reward_fn=reward,
        payoff_weight=weight,
    )
    replay = learner.replay
    n = replay.size
    assert n == learner.total_t < replay.capacity
    called_obs = np.concatenate([c[0] for c in reward.calls])
    called_actions = np.concatenate([c[1] for c in reward.calls])
    assert called_obs.shape == (n, OBS_SIZE)  # one f value per decision, nothing more
    assert len(reward.calls) < n / 4  # batched: one call per lock-step, not per decision

    def pairs(obs: np.ndarray, actions: np.ndarray) -> Counter:
        return Counter(zip(map(bytes, obs), actions.tolist(), strict=True))

    assert pairs(called_obs, called_actions) == pairs(replay.obs[:n], replay.actions[:n])

    f = reward.value(replay.obs[:n], replay.actions[:n])
    payoff_part = (replay.rewards[:n] - (1 - weight) * f) / weight
    done = replay.done[:n]
    assert done.sum() == hands
    np.testing.assert_allclose(payoff_part[~done], 0.0, atol=1e-4)
    # Terminal rows carry the payoff: whole chips (half big blinds), at most 24 big blinds.
    chips = payoff_part[done] * 2
    np.testing.assert_allclose(chips, np.round(chips), atol=1e-3)
    assert np.abs(payoff_part[done]).max() <= 24 + 1e-3
    assert (payoff_part[done] != 0).any()


def test_sparse_reward_is_the_payoff_on_the_last_decision_only() -> None:
    torch.manual_seed(0)
    learner = train_dqn(SMALL, hands=200, seed=2, opponent=make_agent("raise"))
    replay = learner.replay
    rewards, done = replay.rewards[: replay.size], replay.done[: replay.size]
    assert done.sum() == 200
    assert (rewards[~done] == 0).all() and (rewards[done] != 0).any()
    assert (replay.next_legal[: replay.size][~done].any(axis=1)).all()  # s' has legal actions


def test_same_seed_same_weights_and_self_play_runs() -> None:
    def weights(seed: int, opponent: object) -> list[torch.Tensor]:
        learner = train_dqn(
            dataclasses.replace(SMALL, self_play_every=5), hands=256, seed=seed, opponent=opponent
        )
        assert learner.train_t > 5
        return list(learner.q_net.state_dict().values())

    first, again = weights(4, "self"), weights(4, "self")
    assert all(torch.equal(a, b) for a, b in zip(first, again, strict=True))
    other = weights(5, "self")
    assert not all(torch.equal(a, b) for a, b in zip(first, other, strict=True))
    with pytest.raises(ValueError, match="opponent"):
        train_dqn(SMALL, hands=10, seed=0, opponent="nobody")


def test_epsilon_follows_rlcards_linear_schedule() -> None:
    config = DQNConfig(epsilon_decay_steps=11)
    assert [round(epsilon_at(config, t), 6) for t in (0, 5, 10, 99)] == [1.0, 0.55, 0.1, 0.1]


def test_a_short_sparse_run_beats_random() -> None:
    torch.manual_seed(0)
    learner = train_dqn(DQNConfig(), hands=12_288, seed=0, opponent=make_agent("random"))
    result = play_match(learner.greedy_agent(), make_agent("random"), hands=10_000, seed=99)
    assert result.mbb_per_hand > 5 * result.std_error
