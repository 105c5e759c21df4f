"""gym/episodes.py: one core plays every caller's episodes; only the batching differs."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from pokerirl.gym.episodes import Batching, episode_steps, play_episodes


def pole_policy(sign: float):
    """A deterministic CartPole policy (push towards the pole's lean, or against it) that
    records the shapes it was asked about."""
    shapes: list[tuple[int, ...]] = []

    def act(obs: np.ndarray) -> np.ndarray:
        shapes.append(obs.shape)
        return (sign * obs[..., 2] > 0).astype(np.int64)

    return act, shapes


@pytest.mark.parametrize("batching", [Batching.RUNNING, Batching.SINGLE])
def test_one_policy_gets_the_same_returns_whatever_the_batching(batching: Batching) -> None:
    act, _ = pole_policy(1.0)
    (reference,) = play_episodes("CartPole-v1", act, episodes=3, seed=5, batching=Batching.ALL)
    act, shapes = pole_policy(1.0)
    (evaluation,) = play_episodes("CartPole-v1", act, episodes=3, seed=5, batching=batching)
    assert evaluation == reference
    # CartPole pays 1 a step: a return is its episode's length
    assert evaluation.returns == tuple(float(n) for n in evaluation.lengths)
    assert len(set(evaluation.lengths)) > 1  # the seeds start differently
    if batching == Batching.SINGLE:  # one episode after another, a batch of one
        assert set(shapes) == {(1, 4)} and len(shapes) == sum(evaluation.lengths)
    else:  # the running episodes only: the batch shrinks as episodes end
        assert shapes[0] == (3, 4) and shapes[-1] == (1, 4)
        assert sum(s[0] for s in shapes) == sum(evaluation.lengths)


def test_a_batch_of_policies_plays_each_run_as_it_would_alone() -> None:
    towards, _ = pole_policy(1.0)
    away, _ = pole_policy(-1.0)
    shapes: list[tuple[int, ...]] = []

    def both(obs: np.ndarray) -> np.ndarray:  # run 0 pushes towards the lean, run 1 away
        shapes.append(obs.shape)
        return np.stack([towards(obs[0]), away(obs[1])])

    group = play_episodes("CartPole-v1", both, episodes=2, seed=7, runs=2, batching=Batching.ALL)
    alone = [play_episodes("CartPole-v1", policy, episodes=2, seed=7)[0]
             for policy in (towards, away)]  # fmt: skip
    assert list(group) == alone
    assert group[0].mean > group[1].mean  # the rows really are different policies
    assert set(shapes) == {(2, 2, 4)}  # every episode every step: the shape never changes
    assert len(shapes) == max(group[0].lengths + group[1].lengths)


def test_steps_are_numbered_by_run_and_episode() -> None:
    act, _ = pole_policy(1.0)
    steps = list(episode_steps("CartPole-v1", act, episodes=2, seed=3, runs=2,
                               batching=Batching.ALL))  # fmt: skip
    (evaluation,) = play_episodes("CartPole-v1", act, episodes=2, seed=3)
    counts = np.bincount([s.slot for s in steps], minlength=4)
    assert list(counts) == list(evaluation.lengths) * 2  # both runs play the same seeds
    first = steps[0]
    assert np.array_equal(first.next_obs, steps[4].obs)  # slot 0's second step goes on from it


def test_a_batch_of_policies_needs_every_row() -> None:
    act, _ = pole_policy(1.0)
    with pytest.raises(ValueError, match=r"Batching\.ALL"):
        play_episodes("CartPole-v1", act, episodes=1, runs=2)
