"""Rewards a DQN learns from, batched over decisions.

A reward is a :class:`PokerReward`: called with a batch of :class:`ObservedDecisions` (what the
learner saw) and the actions it took, it returns one float per decision. Three kinds:

* :class:`ObsReward` wraps any ``f(obs, actions)`` on RLCard's 72-d observation, such as the
  learned reward of an AIRL / H-AIRL run folder (``pokerirl.irl.load_reward``);
* :class:`pokerirl.poker.authors_reward.AuthorsReward`, one of the authors' published
  rewards (``authors:FILE``), which reads the cards in the order they were dealt;
* :class:`TransformedReward`: f minus its mean (``centered``) or its logsumexp
  (``log_softmax``) over the legal actions of the state; ``raw`` is f.

:class:`~pokerirl.poker.reward_sources.RewardSource` resolves what a user typed (a run
folder or ``authors:FILE``) into one of these; here are only the spec's prefix, the capped
reading of a reward's files and the encoding a run records, which both sides use.

>>> reward = ObsReward(lambda obs, actions: actions.astype(np.float32), name="id")
>>> decisions = ObservedDecisions(obs=np.zeros((2, 72), np.uint8),
...                       legal_mask=np.array([[1, 1, 1, 0], [0, 1, 1, 1]], bool))
>>> reward.action_values(decisions).tolist()
[[0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 2.0, 3.0]]
>>> TransformedReward(reward, "centered")(decisions, np.array([1, 3])).tolist()
[0.0, 1.0]
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from pokerirl.errors import ConfigError, InputError
from pokerirl.game.encodings import (
    Encoding,
    EncodingName,
    RawStates,
    get_encoding,
    recorded_encoding,
)
from pokerirl.game.spec import GameName, recorded_game
from pokerirl.holdem import MAX_RAISES, NUM_ACTIONS, NUM_ROUNDS, RAISE_OFFSET


class Transform(StrEnum):
    """What f becomes over each state's legal actions before the learner sees it."""

    RAW = "raw"
    CENTERED = "centered"  # minus its mean over the legal actions
    LOG_SOFTMAX = "log_softmax"
    # f minus its max over the legal actions, floored: 0 for f's argmax, negative otherwise, so
    # following f's argmax earns the most any policy can (0), whatever the horizon.
    ADVANTAGE = "advantage"


class RaiseCounts(StrEnum):
    """Which raise counts f reads: the state's at the decision, or the hand's at its end."""

    DECISION = "decision"
    END_OF_HAND = "end-of-hand"


TRANSFORMS: tuple[str, ...] = tuple(Transform)
ADVANTAGE_FLOOR = 10.0  # in units of f: far below the spread of the actions the expert takes
RAISE_COUNTS: tuple[str, ...] = tuple(RaiseCounts)
AUTHORS_PREFIX = "authors:"


@dataclass(frozen=True, kw_only=True)
class ObservedDecisions:
    """A batch of decisions as the learner saw them.

    ``cards`` (hole cards, then the board shown, -1 beyond; see
    :func:`pokerirl.game.bots.seat_cards`) is there when the reward reads cards in order
    (``needs_cards``); the 72-d observation cannot tell hole cards from the board.
    ``encoded`` holds the states already computed in other encodings (name -> rows), so a
    learner and its reward on the same encoding compute it once.
    """

    obs: np.ndarray  # (N, 72) uint8
    legal_mask: np.ndarray  # (N, 4) bool
    cards: np.ndarray | None = None  # (N, 7) int8
    encoded: dict[str, np.ndarray] = field(default_factory=dict, repr=False)

    def __len__(self) -> int:
        return len(self.obs)

    def raise_counts(self) -> np.ndarray:
        """(N, 4) raises per round, read from the observation's one-hot slots."""
        slots = RAISE_OFFSET + (MAX_RAISES + 1) * np.arange(NUM_ROUNDS)[:, None] + np.arange(5)
        return np.asarray(self.obs)[:, slots].argmax(axis=2)

    def states(self) -> RawStates:
        """The decisions as :class:`~pokerirl.game.encodings.RawStates` (needs ``cards``)."""
        if self.cards is None:
            raise ValueError("these decisions carry no cards: ObservedDecisions.cards is missing")
        return RawStates(
            cards=self.cards, raise_nums=self.raise_counts(), legal_mask=self.legal_mask
        )

    def encode(self, encoding: Encoding) -> np.ndarray:
        """The states in ``encoding`` (the 72-d ``obs`` as it is for ``rlcard``)."""
        if encoding.name == EncodingName.RLCARD:
            return self.obs
        if encoding.spec not in self.encoded:  # by spec: versions encode differently
            self.encoded[encoding.spec] = encoding.encode(self.states())
        return self.encoded[encoding.spec]


class PokerReward:
    """A batched reward over decisions; subclasses define :meth:`__call__`.

    ``fingerprint`` identifies it by content; ``needs_cards`` asks the trainer for
    :attr:`ObservedDecisions.cards`.
    """

    name: str = "reward"
    fingerprint: str = ""
    needs_cards: bool = False

    def __call__(self, decisions: ObservedDecisions, actions: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def action_values(self, decisions: ObservedDecisions) -> np.ndarray:
        """(N, 4) float32: the reward of every action in every state (legal or not)."""
        columns = [
            self(decisions, np.full(len(decisions), action, np.int64))
            for action in range(NUM_ACTIONS)
        ]
        return np.stack(columns, axis=1).astype(np.float32)


class ObsReward(PokerReward):
    """``f(obs, actions)`` on the states in ``encoding`` (default RLCard's 72-d observation),
    e.g. ``pokerirl.irl.load_reward`` of a run."""

    def __init__(
        self,
        fn: Callable[[np.ndarray, np.ndarray], np.ndarray],
        *,
        name: str = "reward",
        fingerprint: str = "",
        encoding: str | Encoding | None = None,
    ) -> None:
        self.fn, self.name, self.fingerprint = fn, name, fingerprint
        self.encoding = get_encoding(encoding)
        self.needs_cards = self.encoding.needs_cards

    def __call__(self, decisions: ObservedDecisions, actions: np.ndarray) -> np.ndarray:
        obs = decisions.encode(self.encoding)
        return np.asarray(self.fn(obs, np.asarray(actions)), np.float32)

    def action_values(self, decisions: ObservedDecisions) -> np.ndarray:
        # One call on the four actions of every state, stacked: one forward pass, not four.
        n = len(decisions)
        obs = np.tile(np.asarray(decisions.encode(self.encoding)), (NUM_ACTIONS, 1))
        actions = np.repeat(np.arange(NUM_ACTIONS, dtype=np.int64), n)
        return np.asarray(self.fn(obs, actions), np.float32).reshape(NUM_ACTIONS, n).T.copy()


def legal_argmax(values: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
    """Argmax of (N, 4) ``values`` over the legal actions (the first on ties), as int64.

    >>> legal_argmax(np.array([[5.0, 1.0, 2.0, 0.0]]), np.array([[False, True, True, True]]))
    array([2])
    """
    legal = np.asarray(legal_mask, dtype=bool)
    return np.where(legal, values, -np.inf).argmax(axis=1).astype(np.int64)


def follow_share(reward: PokerReward, decisions: ObservedDecisions, actions: np.ndarray) -> float:
    """The share of ``decisions`` where ``actions`` is f's best legal action (an action
    tied with the best counts): how closely an agent trained on f follows it. NaN for none.

    A DQN that ignores its reward (always-call on a reward that prefers raising) scores low:

    >>> prefers_raise = ObsReward(lambda obs, actions: (actions == 1) * 1.0)
    >>> legal = np.array([[True, True, True, False]] * 4)
    >>> decisions = ObservedDecisions(obs=np.zeros((4, 72), np.uint8), legal_mask=legal)
    >>> follow_share(prefers_raise, decisions, np.array([1, 1, 0, 0]))
    0.5
    """
    actions = np.asarray(actions, dtype=np.int64)
    if not len(actions):
        return float("nan")
    values = np.where(decisions.legal_mask, reward.action_values(decisions), -np.inf)
    taken = values[np.arange(len(actions)), actions]
    return float((taken >= values.max(axis=1)).mean())


def as_poker_reward(reward: PokerReward | Callable[..., np.ndarray] | None) -> PokerReward | None:
    """``reward`` itself, or a plain ``f(obs, actions)`` wrapped as an :class:`ObsReward`."""
    if reward is None or isinstance(reward, PokerReward):
        return reward
    return ObsReward(reward)


def transform_values(values: np.ndarray, legal_mask: np.ndarray, transform: str) -> np.ndarray:
    """(N, 4) values after ``transform`` over each row's legal actions (illegal ones: NaN).

    >>> values = np.array([[1.0, 3.0, 0.0, 9.0]]); legal = np.array([[1, 1, 0, 0]], bool)
    >>> transform_values(values, legal, "centered").tolist()
    [[-1.0, 1.0, nan, nan]]
    >>> round(float(np.exp(transform_values(values, legal, "log_softmax")[0, :2]).sum()), 6)
    1.0
    >>> transform_values(np.array([[1.0, 3.0, -200.0, 9.0]]), np.array([[1, 1, 1, 0]], bool),
    ...                  "advantage").tolist()
    [[-2.0, 0.0, -10.0, nan]]
    """
    if transform not in TRANSFORMS:
        raise ConfigError(f"unknown reward transform {transform!r} ({', '.join(TRANSFORMS)})")
    legal_mask = np.asarray(legal_mask, dtype=bool)
    values = np.where(legal_mask, np.asarray(values, dtype=np.float64), np.nan)
    if transform == Transform.CENTERED:
        values = values - np.nanmean(values, axis=1, keepdims=True)
    elif transform == Transform.LOG_SOFTMAX:
        top = np.nanmax(values, axis=1, keepdims=True)
        values = values - top - np.log(np.nansum(np.exp(values - top), axis=1, keepdims=True))
    elif transform == Transform.ADVANTAGE:
        # The floor: an action the expert never takes (fold, in showdown-only data) sits at
        # f = -200 and would swamp a q-network's squared error; -ADVANTAGE_FLOOR still rules it
        # out (issue 31).
        values = np.maximum(values - np.nanmax(values, axis=1, keepdims=True), -ADVANTAGE_FLOOR)
    return values.astype(np.float32)


class TransformedReward(PokerReward):
    """``base`` after a transform over the legal actions of each state (see :data:`TRANSFORMS`)."""

    def __init__(self, base: PokerReward, transform: str) -> None:
        if transform not in TRANSFORMS:
            raise ConfigError(f"unknown reward transform {transform!r} ({', '.join(TRANSFORMS)})")
        self.base, self.transform = base, transform
        self.name = base.name if transform == Transform.RAW else f"{base.name} ({transform})"
        self.fingerprint, self.needs_cards = base.fingerprint, base.needs_cards

    def __call__(self, decisions: ObservedDecisions, actions: np.ndarray) -> np.ndarray:
        if self.transform == Transform.RAW:
            return self.base(decisions, actions)
        values = transform_values(self.base.action_values(decisions), decisions.legal_mask,
                                  self.transform)  # fmt: skip
        return values[np.arange(len(values)), np.asarray(actions)]

    def action_values(self, decisions: ObservedDecisions) -> np.ndarray:
        values = self.base.action_values(decisions)
        if self.transform == Transform.RAW:
            return values
        return transform_values(values, decisions.legal_mask, self.transform)


# --------------------------------------------------------------------------- sources


def is_authors_spec(spec: str | os.PathLike[str]) -> bool:
    return str(spec).startswith(AUTHORS_PREFIX)


def read_capped(path: Path, cap: int, *, where: str) -> bytes:
    """The bytes of the regular file ``path``, refused in one line naming ``where`` when it
    is missing, not a regular file (a folder, a device, a FIFO) or larger than ``cap``: its
    kind and size are checked before a byte is read."""
    import stat

    try:
        info = path.stat()
    except FileNotFoundError:
        raise InputError(f"{where}: no such file") from None
    except OSError as error:
        raise InputError(f"{where}: cannot read ({error.strerror or error})") from None
    if stat.S_ISDIR(info.st_mode):
        raise InputError(f"{where}: is a folder, not a file")
    if not stat.S_ISREG(info.st_mode):
        raise InputError(f"{where}: not a regular file (a device, a FIFO or a socket)")
    if info.st_size > cap:
        raise InputError(f"{where}: {info.st_size:,} bytes, more than the {cap:,} it may hold")
    try:
        with path.open("rb") as stream:
            data = stream.read(cap + 1)
    except OSError as error:
        raise InputError(f"{where}: cannot read ({error.strerror or error})") from None
    if len(data) > cap:  # it grew since the check
        raise InputError(f"{where}: more than the {cap:,} bytes it may hold")
    return data


def run_encoding(run: Path, record: Mapping[str, Any]) -> Encoding:
    """The encoding a poker run's ``config.json`` records (``data.encoding``; ``rlcard`` for
    runs made before encodings), checked against the reward's input width.

    :class:`~pokerirl.errors.InputError` (one line naming the run) for a Gymnasium run, a run
    of another game (Leduc: ``data.game``), an unknown encoding, or a width or action count
    that does not fit it.
    """
    data = record.get("data") or {}
    data = data if isinstance(data, dict) else {}
    task = data.get("env")
    if task is not None:
        raise InputError(
            f"{run}: a Gymnasium IRL run (reward of {task}), not a poker reward; "
            "give a run of pokerirl train"
        )
    if recorded_game(data) is not GameName.HOLDEM:  # a run of another game reads other states
        raise InputError(
            f"{run}: a reward learned on the game {str(data.get('game'))[:40]!r}, not on "
            "heads-up limit hold'em"
        )
    try:  # a bare "strength" (before versions) is strength-v1
        encoding = recorded_encoding(data.get("encoding", EncodingName.RLCARD))
    except ConfigError as error:
        raise InputError(f"{run}: {error}") from None
    architecture = record["architecture"]
    sizes = architecture["obs_dim"], architecture["action_space"].get("num_actions")
    if sizes != (encoding.width, NUM_ACTIONS):
        raise InputError(
            f"{run}: a reward on {sizes[0]}-d observations and {sizes[1]} actions, not the "
            f"{encoding.spec} encoding's {encoding.width}-d states and {NUM_ACTIONS} actions"
        )
    return encoding
