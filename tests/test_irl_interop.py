"""The converters to and from the ``imitation`` library's array layout (pokerirl/irl/interop.py):
round trips of flat transitions and trajectories, discrete and continuous, with and without
rewards, and one-line errors on fields that do not fit. imitation itself is not installed
(it pins older Gymnasium and SB3), so its dataclasses are stood in for by plain objects with
the same attributes, which is all the readers ask of them."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import torch

from pokerirl.errors import InputError
from pokerirl.irl import (
    Transitions,
    from_imitation_trajectories,
    from_imitation_transitions,
    to_imitation_trajectories,
    to_imitation_transitions,
)


def episodes(lengths: list[int], *, continuous: bool = False, seed: int = 0) -> Transitions:
    """Chained episodes: each row's next_obs is the next row's obs, the last row done."""
    rng = np.random.default_rng(seed)
    obs, next_obs, acts, dones, groups = [], [], [], [], []
    for group, length in enumerate(lengths):
        states = rng.normal(size=(length + 1, 3)).astype(np.float32)
        obs.append(states[:-1])
        next_obs.append(states[1:])
        acts.append(rng.normal(size=(length, 2)) if continuous else rng.integers(0, 4, length))
        dones.append(np.arange(length) == length - 1)
        groups.append(np.full(length, group))
    return Transitions.from_arrays(
        np.concatenate(obs), np.concatenate(acts).astype(np.float32 if continuous else np.int64),
        groups=np.concatenate(groups), next_obs=np.concatenate(next_obs),
        dones=np.concatenate(dones), rewards=rng.normal(size=sum(lengths)), num_actions=4,
    )  # fmt: skip


def assert_same(a: Transitions, b: Transitions) -> None:
    for name in ("obs", "actions", "next_obs", "dones", "rewards"):
        assert torch.equal(getattr(a, name), getattr(b, name)), name
    assert a.groups.tolist() == b.groups.tolist()
    assert (a.num_actions, a.action_low, a.action_high) == (b.num_actions, b.action_low,
                                                            b.action_high)  # fmt: skip


@pytest.mark.parametrize("continuous", [False, True])
def test_flat_transitions_round_trip(continuous: bool) -> None:
    t = episodes([3, 1, 4], continuous=continuous)
    flat = to_imitation_transitions(t)
    assert set(flat.to_dict()) == {"obs", "acts", "infos", "next_obs", "dones", "rews"}
    assert flat.infos.dtype == object and flat.infos[0] == {} and len(flat) == 8
    # Through an object with imitation's attributes and through a plain dict alike.
    for data in (SimpleNamespace(**flat.to_dict()), flat.to_dict()):
        back = from_imitation_transitions(data, num_actions=t.num_actions,
                                          low=t.action_low, high=t.action_high)  # fmt: skip
        assert_same(back, t)


def test_trajectories_round_trip_and_match_imitations_flattening() -> None:
    t = episodes([2, 5, 1])
    trajectories = to_imitation_trajectories(t)
    assert [len(x.obs) for x in trajectories] == [3, 6, 2]  # T + 1 observations
    assert [x.terminal for x in trajectories] == [True, True, True]
    assert trajectories[1].rews is not None and len(trajectories[1].rews) == 5
    np.testing.assert_array_equal(trajectories[1].obs[-1], t.next_obs[6].numpy())
    assert_same(from_imitation_trajectories(trajectories, num_actions=4), t)
    # Mappings without rewards, and a trajectory cut off by a time limit: not done at its end.
    plain = [{**x.to_dict(), "rews": None} for x in trajectories]
    plain[0]["terminal"] = False
    back = from_imitation_trajectories(plain, num_actions=4)
    assert back.rewards is None
    assert back.dones.tolist() == [False, False, *t.dones[2:].tolist()]
    # The flat layout of the same data: episodes end at the dones, so the groups agree.
    assert_same(from_imitation_transitions(to_imitation_transitions(t), num_actions=4), t)


def test_mismatched_lengths_are_one_line_errors() -> None:
    flat = to_imitation_transitions(episodes([3, 2])).to_dict()
    with pytest.raises(InputError, match=r"^imitation transitions: acts has 4 rows, obs has 5$"):
        from_imitation_transitions({**flat, "acts": flat["acts"][:4]})
    with pytest.raises(InputError, match="imitation transitions: no 'next_obs' field"):
        from_imitation_transitions({**flat, "next_obs": None})
    trajectory = to_imitation_trajectories(episodes([3]))[0].to_dict()
    with pytest.raises(InputError, match=r"trajectory 1: obs has 3 rows, acts 3 \(obs needs T"):
        from_imitation_trajectories([trajectory, {**trajectory, "obs": trajectory["obs"][:3]}])
    with pytest.raises(InputError, match="trajectory 0: rews has 2 rows, acts has 3"):
        from_imitation_trajectories([{**trajectory, "rews": trajectory["rews"][:2]}])
    with pytest.raises(InputError, match=r"trajectory 0: obs must be rows of features \(N, d\)"):
        from_imitation_trajectories([{**trajectory, "obs": np.zeros((4, 2, 2))}])
    with pytest.raises(InputError, match="none given"):
        from_imitation_trajectories([])


def test_what_is_not_a_trajectory_is_refused() -> None:
    t = episodes([3, 2])
    broken = Transitions.from_arrays(t.obs, t.actions, groups=t.groups, dones=t.dones,
                                     next_obs=torch.flip(t.next_obs, [0]))  # fmt: skip
    with pytest.raises(InputError, match="group 0's next_obs is not its next row's obs"):
        to_imitation_trajectories(broken)
    interleaved = t.subset(np.array([0, 3, 1, 4, 2]))
    with pytest.raises(InputError, match="not contiguous"):
        to_imitation_trajectories(interleaved)
    with pytest.raises(InputError, match="without next_obs"):
        to_imitation_transitions(Transitions.from_arrays(t.obs, t.actions, groups=t.groups))
