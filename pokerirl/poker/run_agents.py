"""Agents made of an IRL run: its reward's argmax, and its policy played greedily.

(Not the built-in bots of :mod:`pokerirl.game.bots`, nor the learned DQN agents of
:mod:`pokerirl.agents`, which resolves all three kinds by name.)

They separate the two ways a learned reward can fail to teach: if f's argmax already plays
like the expert but a DQN trained on f does not, the RL failed; if f's argmax does not, the
reward did. Both follow the engine's :class:`~pokerirl.game.bots.Agent` protocol (with
``action_probs``, for local best response) and are named by specs that
:func:`pokerirl.agents.resolve_agent` understands:

* ``reward:RUN`` (or ``reward:authors:FILE``): argmax over the legal actions of f(s, ·);
* ``policy:RUN``: argmax over the legal actions of the run's π(·|s), read in the run's
  encoding (the engine builds the observations in it).

>>> import numpy as np
>>> from pokerirl.poker.rewards import ObsReward
>>> agent = RewardArgmaxAgent(name="f", reward=ObsReward(lambda o, a: (a == 1) * 1.0))
>>> legal = np.array([[True, True, True, False], [True, False, True, False]])
>>> agent.act(np.zeros((2, 72), np.uint8), legal, np.random.default_rng(0)).tolist()
[1, 0]
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pokerirl.errors import InputError
from pokerirl.game.encodings import EncodingName
from pokerirl.holdem import NUM_ACTIONS
from pokerirl.poker.agent_specs import POLICY_PREFIX, REWARD_PREFIX
from pokerirl.poker.reward_sources import RewardSource
from pokerirl.poker.rewards import ObservedDecisions, PokerReward, legal_argmax, run_encoding
from pokerirl.store import digest


def _one_hot(actions: np.ndarray) -> np.ndarray:
    return np.eye(NUM_ACTIONS)[actions]


@dataclass(frozen=True, kw_only=True)
class RewardArgmaxAgent:
    """Plays the legal action f(s, ·) rates highest; deterministic."""

    name: str
    reward: PokerReward = field(repr=False)
    fingerprint: str = ""

    @property
    def sees_cards(self) -> bool:
        return self.reward.needs_cards

    def _values(self, obs: np.ndarray, legal_mask: np.ndarray, cards: Any) -> np.ndarray:
        decisions = ObservedDecisions(obs=np.asarray(obs), legal_mask=np.asarray(legal_mask, bool),
                              cards=None if cards is None else np.asarray(cards))  # fmt: skip
        return self.reward.action_values(decisions)

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator,
            *, cards: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
        return legal_argmax(self._values(obs, legal_mask, cards), legal_mask)

    def action_probs(self, obs: np.ndarray, legal_mask: np.ndarray,
                     *, cards: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
        return _one_hot(self.act(obs, legal_mask, np.random.default_rng(0), cards=cards))


@dataclass(frozen=True, kw_only=True)
class PolicyAgent:
    """Plays the legal action the run's policy π(·|s) makes most likely; deterministic."""

    name: str
    policy: torch.nn.Module = field(repr=False)
    encoding: str = EncodingName.RLCARD
    fingerprint: str = ""

    def log_probs(self, obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
        """(B, 4) log π over the legal actions (illegal ones masked)."""
        with torch.inference_mode():
            found = self.policy(torch.as_tensor(np.asarray(obs)).float(),
                                torch.as_tensor(np.asarray(legal_mask, bool)))  # fmt: skip
        return np.asarray(found.numpy(), dtype=np.float64)

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return legal_argmax(self.log_probs(obs, legal_mask), legal_mask)

    def action_probs(self, obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
        return _one_hot(self.act(obs, legal_mask, np.random.default_rng(0)))


def reward_agent(spec: str | os.PathLike[str]) -> RewardArgmaxAgent:
    """The agent ``reward:SOURCE`` names (SOURCE: a run folder or ``authors:FILE``)."""
    source = RewardSource.resolve(str(spec).removeprefix(REWARD_PREFIX))
    return RewardArgmaxAgent(name=f"{REWARD_PREFIX}{source.spec}", reward=source.load(),
                             fingerprint=source.fingerprint)  # fmt: skip


def policy_files(run: str | os.PathLike[str]) -> dict[str, bytes]:
    """The bytes of a run's policy and record, checked to exist (one line if not)."""
    from pokerirl.irl.run import POLICY_RUN_FILES

    folder = Path(run)
    missing = [name for name in POLICY_RUN_FILES if not (folder / name).is_file()]
    if missing:
        raise InputError(f"{folder}: not an IRL run folder (no {missing[0]})")
    return {name: (folder / name).read_bytes() for name in POLICY_RUN_FILES}


def policy_agent(spec: str | os.PathLike[str], files: dict[str, bytes] | None = None,
                 *, name: str | None = None) -> PolicyAgent:  # fmt: skip
    """The agent ``policy:RUN`` names, from the run's files (or their bytes, ``files``)."""
    from pokerirl.irl.run import CONFIG_FILE, POLICY_FILE, parse_run_config, policy_from_bytes

    run = Path(str(spec).removeprefix(POLICY_PREFIX))
    files = policy_files(run) if files is None else files
    record = parse_run_config(files[CONFIG_FILE], where=run / CONFIG_FILE)
    encoding = run_encoding(run, record)
    policy = policy_from_bytes(record, files[POLICY_FILE], where=run / POLICY_FILE)
    return PolicyAgent(
        name=name or f"{POLICY_PREFIX}{run}",
        policy=policy.eval(),
        encoding=encoding.spec,
        fingerprint=digest(b"".join(files.values())),
    )
