"""The learned reward itself: it must encode the expert's rule, and recover a known reward.

These fail when the reward is not learned (checked by hand: with ``self.reward_opt.step()``
removed from ``pokerirl/irl/adversarial.py`` both tests fail).
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from pokerirl.datasets.toy import toy_expert_table
from pokerirl.irl import AIRLConfig, Transitions, baselines, train
from pokerirl.poker import transitions_from_arrow

torch.set_num_threads(1)


@pytest.mark.slow
def test_reward_argmax_beats_the_legal_majority_rule_on_a_known_expert() -> None:
    """The toy expert raises with strong cards: the legal-action rule cannot see that, a
    reward that encodes the expert's preferences must."""
    data = transitions_from_arrow(toy_expert_table(num_hands=1500, seed=7))
    train_data, val_data, _ = data.split(val_fraction=0.25, seed=0)
    rules = baselines(train_data, val_data)
    config = AIRLConfig.for_algo("hairl", epochs=15, batch_size=64, reward_lr=3e-3, policy_lr=3e-3)
    result = train(train_data, val_data, config=config, progress=False)
    reward_alignment = result.metrics[-1]["val_reward_alignment"]
    assert reward_alignment > rules["legal_majority"] + 0.05, (reward_alignment, rules)


def soft_optimal_chain(
    *, states: int = 6, actions: int = 3, gamma: float = 0.9, episodes: int = 200, seed: int = 0
) -> tuple[Transitions, np.ndarray, np.ndarray]:
    """Expert rollouts of the max-entropy optimal policy of a deterministic MDP with a random
    reward r(s, a): s' = (s + a) mod S. Returns (transitions, r, next state table)."""
    rng = np.random.default_rng(seed)
    reward = rng.normal(0, 1, (states, actions))
    following = (np.arange(states)[:, None] + np.arange(actions)[None, :]) % states
    value = np.zeros(states)
    for _ in range(500):  # soft value iteration
        q = reward + gamma * value[following]
        value = np.log(np.exp(q).sum(1))
    policy = np.exp(q - value[:, None])
    obs, act, group = [], [], []
    for episode in range(episodes):
        s = rng.integers(states)
        for _ in range(20):
            a = rng.choice(actions, p=policy[s])
            obs.append(s), act.append(a), group.append(episode)
            s = following[s, a]
    obs_ids, act_ids = np.array(obs), np.array(act)
    eye = np.eye(states, dtype=np.float32)
    data = Transitions.from_arrays(
        eye[obs_ids],
        act_ids,
        groups=np.array(group),
        next_obs=eye[following[obs_ids, act_ids]],
        dones=np.zeros(len(obs_ids), bool),  # time limits, not terminal states
        num_actions=actions,
    )
    return data, reward, following


def explained_up_to_shaping(
    g: np.ndarray, reward: np.ndarray, following: np.ndarray, gamma: float
) -> float:
    """R² of g − r explained by γ·Φ(s') − Φ(s) + c, with the best Φ and c (least squares)."""
    states, actions = reward.shape
    rows, target = [], []
    for s in range(states):
        for a in range(actions):
            x = np.zeros(states + 1)
            x[following[s, a]] += gamma
            x[s] -= 1
            x[states] = 1
            rows.append(x)
            target.append(g[s, a] - reward[s, a])
    design, y = np.array(rows), np.array(target)
    residual = y - design @ np.linalg.lstsq(design, y, rcond=None)[0]
    return 1 - residual.var() / reward.var()


@pytest.mark.slow
def test_shaped_family_recovers_a_known_reward_up_to_shaping() -> None:
    gamma = 0.9
    data, reward, following = soft_optimal_chain(gamma=gamma)
    train_data, val_data, _ = data.split(val_fraction=0.2, seed=0)
    config = AIRLConfig.for_algo(
        "airl",
        epochs=30,
        batch_size=64,
        reward_family="shaped",
        gamma=gamma,
        reward_hidden=(32,),
        policy_hidden=(32,),
        reward_lr=1e-2,
        policy_lr=1e-2,
        reward_weight_decay=0.0,
    )
    result = train(train_data, val_data, config=config, progress=False)
    with torch.no_grad():  # g(s, a) on every state and action
        g = result.reward(torch.eye(6), torch.eye(3)[:, None, :]).T.numpy()
    assert explained_up_to_shaping(g, reward, following, gamma) > 0.9
    # Shaping is needed: g itself is not r plus a constant.
    plain = 1 - ((g - g.mean()) - (reward - reward.mean())).var() / reward.var()
    assert plain < 0.5
