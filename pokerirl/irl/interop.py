"""Converters between :class:`Transitions` and the array layout of the ``imitation`` library.

``imitation`` (the HumanCompatibleAI library) keeps demonstrations as flat transitions
(``obs``, ``acts``, ``infos``, ``next_obs``, ``dones``; ``rews`` too for
``TransitionsWithRew``) or as trajectories (``obs`` of length T + 1, ``acts`` of T,
``infos``, ``terminal``; ``rews`` for ``TrajectoryWithRew``). This module reads and writes
that layout **without importing imitation** (it pins older Gymnasium and SB3 than
pokerirl's): the readers take any object with those attributes, or a mapping of arrays; the
writers return :class:`ImitationTransitions` and :class:`ImitationTrajectory`, frozen
dataclasses of numpy arrays with the same field names, whose :meth:`~ImitationTransitions.
to_dict` feeds imitation's own constructors (``imitation.data.types.Transitions(**t.to_dict())``).

Episodes become :class:`Transitions` groups: a flat layout's episode ends where ``dones`` is
true (or a new one starts after each trajectory). What imitation has no field for (legal
masks, row weights, imputed flags, group ids) is not written; ``infos`` are only counted.

>>> flat = {"obs": np.array([[0.0], [1.0], [5.0]]), "acts": np.array([0, 1, 1]),
...         "next_obs": np.array([[1.0], [2.0], [6.0]]), "dones": np.array([False, True, True])}
>>> t = from_imitation_transitions(flat)
>>> t.groups.tolist(), t.num_actions
([0, 0, 1], 2)
>>> [len(trajectory.acts) for trajectory in to_imitation_trajectories(t)]
[2, 1]
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pokerirl.errors import InputError, check_argument
from pokerirl.irl.transitions import Transitions


@dataclass(frozen=True, kw_only=True, eq=False)
class ImitationTransitions:
    """Flat transitions in imitation's layout: N rows of each field (``rews`` optional)."""

    obs: np.ndarray  # (N, d)
    acts: np.ndarray  # (N,) int64 discrete, (N, k) float32 continuous
    infos: np.ndarray  # (N,) object array of dicts (empty)
    next_obs: np.ndarray  # (N, d)
    dones: np.ndarray  # (N,) bool
    rews: np.ndarray | None = None  # (N,) float32, as TransitionsWithRew

    def __len__(self) -> int:
        return len(self.obs)

    def to_dict(self) -> dict[str, np.ndarray]:
        """The fields as a dict, without ``rews`` when there are none (the keyword arguments
        of imitation's ``Transitions``, or of ``TransitionsWithRew`` with ``rews``)."""
        fields = {"obs": self.obs, "acts": self.acts, "infos": self.infos,
                  "next_obs": self.next_obs, "dones": self.dones}  # fmt: skip
        return fields if self.rews is None else {**fields, "rews": self.rews}


@dataclass(frozen=True, kw_only=True, eq=False)
class ImitationTrajectory:
    """One episode in imitation's layout: ``obs`` T + 1 rows, ``acts`` and ``infos`` T."""

    obs: np.ndarray  # (T + 1, d): every state, the last one after the last action
    acts: np.ndarray  # (T,) or (T, k)
    infos: np.ndarray  # (T,) object array of dicts (empty)
    terminal: bool  # the episode ended (False: cut off, e.g. by a time limit)
    rews: np.ndarray | None = None  # (T,) float32, as TrajectoryWithRew

    def __len__(self) -> int:
        return len(self.acts)

    def to_dict(self) -> dict[str, Any]:
        """The fields as a dict, without ``rews`` when there are none (the keyword arguments
        of imitation's ``Trajectory``, or of ``TrajectoryWithRew`` with ``rews``)."""
        fields = {"obs": self.obs, "acts": self.acts, "infos": self.infos,
                  "terminal": self.terminal}  # fmt: skip
        return fields if self.rews is None else {**fields, "rews": self.rews}


def _field(data: Any, name: str, what: str, *, required: bool = True) -> Any:
    # A mapping's key or an object's attribute: imitation's dataclasses and plain dicts alike.
    value = data.get(name) if isinstance(data, Mapping) else getattr(data, name, None)
    if value is None and required:
        raise InputError(f"{what}: no {name!r} field (imitation's layout needs it)")
    return value


def _check_rows(what: str, expected: int, against: str, **arrays: Any) -> None:
    for name, value in arrays.items():
        if value is not None and len(value) != expected:
            raise InputError(f"{what}: {name} has {len(value)} rows, {against}")


def _check_obs(what: str, obs: np.ndarray) -> None:
    # Transitions hold flat feature rows; an image or dict observation needs flattening first.
    if obs.ndim != 2:
        raise InputError(f"{what}: obs must be rows of features (N, d), got shape {obs.shape}")


def _actions(acts: np.ndarray) -> np.ndarray:
    # imitation stores discrete actions as integers and continuous ones as floats; keep that.
    acts = np.asarray(acts)
    return acts.astype(np.int64) if np.issubdtype(acts.dtype, np.integer) else acts


def _empty_infos(n: int) -> np.ndarray:
    infos = np.empty(n, dtype=object)
    infos[:] = [{} for _ in range(n)]
    return infos


def from_imitation_transitions(
    data: Any,
    *,
    num_actions: int | None = None,
    low: Sequence[float] | None = None,
    high: Sequence[float] | None = None,
) -> Transitions:
    """:class:`Transitions` from imitation's flat layout (an object or a mapping with
    ``obs``, ``acts``, ``next_obs``, ``dones`` and optionally ``rews``).

    Group ``g`` is the g-th episode: rows up to and including each true ``done``; rows after
    the last one form a last, unfinished episode. ``num_actions``, ``low`` and ``high`` as
    :meth:`Transitions.from_arrays`.

    Raises:
        InputError: a missing field, or fields of different lengths (one line).
    """
    what = "imitation transitions"
    obs = np.asarray(_field(data, "obs", what))
    acts, next_obs, dones = (np.asarray(_field(data, name, what))
                             for name in ("acts", "next_obs", "dones"))  # fmt: skip
    rews = _field(data, "rews", what, required=False)
    infos = _field(data, "infos", what, required=False)
    _check_rows(what, len(obs), f"obs has {len(obs)}", acts=acts, next_obs=next_obs,
                dones=dones, rews=rews, infos=infos)  # fmt: skip
    if len(obs) == 0:
        raise InputError(f"{what}: no rows")
    _check_obs(what, obs)
    dones = dones.astype(bool).reshape(-1)
    groups = np.concatenate([[0], np.cumsum(dones)[:-1]]).astype(np.int64)
    return Transitions.from_arrays(
        obs, _actions(acts), groups=groups, next_obs=next_obs, dones=dones,
        rewards=None if rews is None else np.asarray(rews, dtype=np.float32),
        num_actions=num_actions, low=low, high=high,
    )  # fmt: skip


def to_imitation_transitions(transitions: Transitions) -> ImitationTransitions:
    """``transitions`` in imitation's flat layout (``rews`` when it has rewards).

    Raises:
        InputError: ``transitions`` has no ``next_obs`` and ``dones``, which imitation needs.
    """
    check_argument("transitions", transitions, Transitions, "Transitions")
    if transitions.next_obs is None or transitions.dones is None:
        raise InputError("Transitions without next_obs and dones have no imitation layout")
    rewards = transitions.rewards
    return ImitationTransitions(
        obs=transitions.obs.cpu().numpy(),
        acts=transitions.actions.cpu().numpy(),
        infos=_empty_infos(len(transitions)),
        next_obs=transitions.next_obs.cpu().numpy(),
        dones=transitions.dones.cpu().numpy(),
        rews=None if rewards is None else rewards.cpu().numpy(),
    )


def from_imitation_trajectories(
    trajectories: Iterable[Any],
    *,
    num_actions: int | None = None,
    low: Sequence[float] | None = None,
    high: Sequence[float] | None = None,
) -> Transitions:
    """:class:`Transitions` from imitation trajectories (objects or mappings with ``obs``
    of T + 1 rows, ``acts`` of T, ``terminal``, optionally ``rews``), as imitation's own
    ``flatten_trajectories``: row t is (obs[t], acts[t], obs[t + 1]), the last row of a
    trajectory is done when it is ``terminal``; trajectory i is group i. Rewards are kept
    when every trajectory has them.

    Raises:
        InputError: no trajectories, an empty one, a missing field, or lengths that do not
            fit (one line naming the trajectory).
    """
    parts: dict[str, list[np.ndarray]] = {"obs": [], "acts": [], "next_obs": [], "dones": [],
                                          "rews": [], "groups": []}  # fmt: skip
    check_argument("trajectories", trajectories, Iterable, "an iterable of trajectories")
    count = 0
    for index, trajectory in enumerate(trajectories):
        what = f"imitation trajectory {index}"
        obs = np.asarray(_field(trajectory, "obs", what))
        acts = np.asarray(_field(trajectory, "acts", what))
        terminal = _field(trajectory, "terminal", what)
        rews = _field(trajectory, "rews", what, required=False)
        infos = _field(trajectory, "infos", what, required=False)
        if len(acts) == 0:
            raise InputError(f"{what}: no actions")
        _check_obs(what, obs)
        if len(obs) != len(acts) + 1:
            raise InputError(f"{what}: obs has {len(obs)} rows, acts {len(acts)} (obs needs T + 1)")
        _check_rows(what, len(acts), f"acts has {len(acts)}", rews=rews, infos=infos)
        dones = np.zeros(len(acts), dtype=bool)
        dones[-1] = bool(terminal)
        parts["obs"].append(obs[:-1])
        parts["next_obs"].append(obs[1:])
        parts["acts"].append(acts)
        parts["dones"].append(dones)
        parts["groups"].append(np.full(len(acts), index, dtype=np.int64))
        if rews is not None:
            parts["rews"].append(np.asarray(rews, dtype=np.float32))
        count += 1
    if count == 0:
        raise InputError("imitation trajectories: none given")
    rewards = np.concatenate(parts["rews"]) if len(parts["rews"]) == count else None
    joined = {name: np.concatenate(parts[name]) for name in ("obs", "acts", "next_obs",
                                                            "dones", "groups")}  # fmt: skip
    return Transitions.from_arrays(
        joined["obs"], _actions(joined["acts"]), groups=joined["groups"],
        next_obs=joined["next_obs"], dones=joined["dones"], rewards=rewards,
        num_actions=num_actions, low=low, high=high,
    )  # fmt: skip


def to_imitation_trajectories(transitions: Transitions) -> list[ImitationTrajectory]:
    """One trajectory per group of ``transitions``, in order of appearance: ``obs`` is the
    group's observations and its last ``next_obs``, ``terminal`` its last ``done``.

    Raises:
        InputError: no ``next_obs`` and ``dones``; a group whose rows are not contiguous; or
            a group whose ``next_obs`` is not the following row's ``obs`` (not a trajectory).
    """
    check_argument("transitions", transitions, Transitions, "Transitions")
    if transitions.next_obs is None or transitions.dones is None:
        raise InputError("Transitions without next_obs and dones have no imitation layout")
    flat = to_imitation_transitions(transitions)
    groups = transitions.groups
    starts = np.flatnonzero(np.concatenate([[True], groups[1:] != groups[:-1]]))
    ends = np.append(starts[1:], len(groups))
    if len(set(groups[starts].tolist())) != len(starts):
        raise InputError("Transitions: a group's rows are not contiguous, so not a trajectory")
    trajectories = []
    for start, end in zip(starts.tolist(), ends.tolist(), strict=True):
        obs, next_obs = flat.obs[start:end], flat.next_obs[start:end]
        if not np.array_equal(next_obs[:-1], obs[1:]):
            raise InputError(
                f"Transitions: group {groups[start].item()!r}'s next_obs is not its next row's "
                "obs, so not a trajectory"
            )
        trajectories.append(
            ImitationTrajectory(
                obs=np.concatenate([obs, next_obs[-1:]]),
                acts=flat.acts[start:end],
                infos=flat.infos[start:end],
                terminal=bool(flat.dones[end - 1]),
                rews=None if flat.rews is None else flat.rews[start:end],
            )
        )
    return trajectories
