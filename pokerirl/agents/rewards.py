"""Rewards a DQN learns from, batched over decisions, and where they come from.

A reward is a :class:`PokerReward`: called with a batch of :class:`Decisions` (what the
learner saw) and the actions it took, it returns one float per decision. Three kinds:

* :class:`ObsReward` wraps any ``f(obs, actions)`` on RLCard's 72-d observation, such as the
  learned reward of an AIRL / H-AIRL run folder (``pokerirl.irl.load_reward``);
* :class:`pokerirl.agents.authors_reward.AuthorsReward`, one of the authors' published
  rewards (``authors:FILE``), which reads the cards in the order they were dealt;
* :class:`TransformedReward`: f minus its mean (``centered``) or its logsumexp
  (``log_softmax``) over the legal actions of the state; ``raw`` is f.

:func:`load_reward_source` resolves what a user typed (a run folder or ``authors:FILE``);
:func:`reward_source_files` and :func:`reward_source_fingerprint` give the bytes a worker needs
and their identity.

>>> reward = ObsReward(lambda obs, actions: actions.astype(np.float32), name="id")
>>> decisions = Decisions(obs=np.zeros((2, 72), np.uint8),
...                       legal_mask=np.array([[1, 1, 1, 0], [0, 1, 1, 1]], bool))
>>> reward.action_values(decisions).tolist()
[[0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 2.0, 3.0]]
>>> TransformedReward(reward, "centered")(decisions, np.array([1, 3])).tolist()
[0.0, 1.0]
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path

import numpy as np

from pokerirl.encoding import MAX_RAISES, NUM_ACTIONS, NUM_ROUNDS, OBS_SIZE, RAISE_OFFSET
from pokerirl.errors import ConfigError, InputError


class Transform(StrEnum):
    """What f becomes over each state's legal actions before the learner sees it."""

    RAW = "raw"
    CENTERED = "centered"  # minus its mean over the legal actions
    LOG_SOFTMAX = "log_softmax"


class RaiseCounts(StrEnum):
    """Which raise counts f reads: the state's at the decision, or the hand's at its end."""

    DECISION = "decision"
    END_OF_HAND = "end-of-hand"


TRANSFORMS: tuple[str, ...] = tuple(Transform)
RAISE_COUNTS: tuple[str, ...] = tuple(RaiseCounts)
AUTHORS_PREFIX = "authors:"
AUTHORS_FILE = "authors.model"  # a shipped authors: file's name in a worker's folder


@dataclass(frozen=True, kw_only=True)
class Decisions:
    """A batch of decisions as the learner saw them.

    ``cards`` (hole cards, then the board shown, -1 beyond; see
    :func:`pokerirl.game.agents.seat_cards`) is there when the reward reads cards in order
    (``needs_cards``); the 72-d observation cannot tell hole cards from the board.
    """

    obs: np.ndarray  # (N, 72) uint8
    legal_mask: np.ndarray  # (N, 4) bool
    cards: np.ndarray | None = None  # (N, 7) int8

    def __len__(self) -> int:
        return len(self.obs)

    def raise_counts(self) -> np.ndarray:
        """(N, 4) raises per round, read from the observation's one-hot slots."""
        slots = RAISE_OFFSET + (MAX_RAISES + 1) * np.arange(NUM_ROUNDS)[:, None] + np.arange(5)
        return np.asarray(self.obs)[:, slots].argmax(axis=2)


class PokerReward:
    """A batched reward over decisions; subclasses define :meth:`__call__`.

    ``fingerprint`` identifies it by content; ``needs_cards`` asks the trainer for
    :attr:`Decisions.cards`.
    """

    name: str = "reward"
    fingerprint: str = ""
    needs_cards: bool = False

    def __call__(self, decisions: Decisions, actions: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def action_values(self, decisions: Decisions) -> np.ndarray:
        """(N, 4) float32: the reward of every action in every state (legal or not)."""
        columns = [
            self(decisions, np.full(len(decisions), action, np.int64))
            for action in range(NUM_ACTIONS)
        ]
        return np.stack(columns, axis=1).astype(np.float32)


class ObsReward(PokerReward):
    """``f(obs, actions)`` on the 72-d observation (e.g. ``pokerirl.irl.load_reward``)."""

    def __init__(
        self,
        fn: Callable[[np.ndarray, np.ndarray], np.ndarray],
        *,
        name: str = "reward",
        fingerprint: str = "",
    ) -> None:
        self.fn, self.name, self.fingerprint = fn, name, fingerprint

    def __call__(self, decisions: Decisions, actions: np.ndarray) -> np.ndarray:
        return np.asarray(self.fn(decisions.obs, np.asarray(actions)), np.float32)

    def action_values(self, decisions: Decisions) -> np.ndarray:
        # One call on the four actions of every state, stacked: one forward pass, not four.
        n = len(decisions)
        obs = np.tile(np.asarray(decisions.obs), (NUM_ACTIONS, 1))
        actions = np.repeat(np.arange(NUM_ACTIONS, dtype=np.int64), n)
        return np.asarray(self.fn(obs, actions), np.float32).reshape(NUM_ACTIONS, n).T.copy()


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
    return values.astype(np.float32)


class TransformedReward(PokerReward):
    """``base`` after a transform over the legal actions of each state (see :data:`TRANSFORMS`)."""

    def __init__(self, base: PokerReward, transform: str) -> None:
        if transform not in TRANSFORMS:
            raise ConfigError(f"unknown reward transform {transform!r} ({', '.join(TRANSFORMS)})")
        self.base, self.transform = base, transform
        self.name = base.name if transform == Transform.RAW else f"{base.name} ({transform})"
        self.fingerprint, self.needs_cards = base.fingerprint, base.needs_cards

    def __call__(self, decisions: Decisions, actions: np.ndarray) -> np.ndarray:
        if self.transform == Transform.RAW:
            return self.base(decisions, actions)
        values = transform_values(self.base.action_values(decisions), decisions.legal_mask,
                                  self.transform)  # fmt: skip
        return values[np.arange(len(values)), np.asarray(actions)]

    def action_values(self, decisions: Decisions) -> np.ndarray:
        values = self.base.action_values(decisions)
        if self.transform == Transform.RAW:
            return values
        return transform_values(values, decisions.legal_mask, self.transform)


# --------------------------------------------------------------------------- sources


def is_authors_spec(spec: str | os.PathLike[str]) -> bool:
    return str(spec).startswith(AUTHORS_PREFIX)


def _authors_path(spec: str | os.PathLike[str]) -> Path:
    return Path(str(spec).removeprefix(AUTHORS_PREFIX))


def reward_source_files(spec: str | os.PathLike[str]) -> dict[str, bytes]:
    """The bytes of a reward source, to carry to a worker (checked first, in one line)."""
    from pokerirl.irl.run import REWARD_RUN_FILES

    reward_source_fingerprint(spec)
    if is_authors_spec(spec):
        return {AUTHORS_FILE: _authors_path(spec).read_bytes()}
    return {name: (Path(spec) / name).read_bytes() for name in REWARD_RUN_FILES}


def landed_spec(spec: str | os.PathLike[str], folder: str | os.PathLike[str]) -> str:
    """The spec of a source's copy written (by :func:`reward_source_files`) into ``folder``."""
    if is_authors_spec(spec):
        return f"{AUTHORS_PREFIX}{Path(folder) / AUTHORS_FILE}"
    return str(folder)


def reward_source_fingerprint(spec: str | os.PathLike[str]) -> str:
    """``sha256:<hex>`` of an ``authors:`` file, or of a run's ``reward.pt`` and
    ``config.json``; ``ValueError`` (one line) when ``spec`` is neither."""
    from pokerirl.agents.checkpoint import files_fingerprint
    from pokerirl.irl.run import REWARD_RUN_FILES

    if is_authors_spec(spec):
        path = _authors_path(spec)
        if not path.is_file():
            raise InputError(f"{spec}: no such file (authors:FILE names an authors' reward)")
        return files_fingerprint(path.parent, (path.name,))
    for name in REWARD_RUN_FILES:
        if not (Path(spec) / name).is_file():
            raise InputError(f"{spec}: not a reward run (no {name}) nor authors:FILE")
    _check_poker_run(Path(spec))
    return files_fingerprint(spec, REWARD_RUN_FILES)


def _check_poker_run(run: Path) -> None:
    """``ValueError`` (one line) for a run whose reward is not on poker decisions: a
    Gymnasium run (its task named), or one on other observations or actions. What cannot be
    read is left to :func:`pokerirl.irl.load_reward`, which names the problem."""
    from pokerirl.irl.run import CONFIG_FILE

    try:
        record = json.loads((run / CONFIG_FILE).read_bytes())
        data, architecture = record.get("data") or {}, record.get("architecture") or {}
        task = data.get("env")
        sizes = architecture.get("obs_dim"), architecture["action_space"].get("num_actions")
    except (OSError, ValueError, AttributeError, KeyError, TypeError):
        return
    if task is not None:
        raise InputError(
            f"{run}: a Gymnasium IRL run (reward of {task}), not a poker reward; "
            "give a run of pokerirl train"
        )
    if sizes != (OBS_SIZE, NUM_ACTIONS):
        raise InputError(
            f"{run}: a reward on {sizes[0]}-d observations and {sizes[1]} actions, not "
            f"poker's {OBS_SIZE}-d observation and {NUM_ACTIONS} actions"
        )


def load_reward_source(spec: str | os.PathLike[str]) -> PokerReward:
    """The reward of a run folder (via ``pokerirl.irl.load_reward``) or of ``authors:FILE``."""
    fingerprint = reward_source_fingerprint(spec)  # a clear error before anything loads
    if is_authors_spec(spec):
        from pokerirl.agents.authors_reward import AuthorsReward

        return AuthorsReward.from_file(_authors_path(spec))
    from pokerirl.irl import load_reward

    return ObsReward(load_reward(spec), name=str(spec), fingerprint=fingerprint)
