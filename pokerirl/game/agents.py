"""The agent protocol the engine talks to, the built-in agents and the name registry.

An agent decides for a whole batch at once: one call per decision step, so a network agent
makes one batched forward pass.

>>> agent = make_agent("raise")
>>> mask = np.array([[True, True, True, False], [True, False, True, False]])
>>> agent.act(np.zeros((2, 72), np.uint8), mask, np.random.default_rng(0)).tolist()
[1, 0]
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from pokerirl.encoding import CALL, CHECK, RAISE

# For each of the 16 legal-mask patterns (bit i: action i legal): how many, and the k-th one.
_LEGAL_COUNT = np.array([bin(p).count("1") for p in range(16)])
_KTH_LEGAL = np.array(
    [[a for a in range(4) if p >> a & 1] + [0] * (4 - bin(p).count("1")) for p in range(16)],
    dtype=np.int64,
)


@runtime_checkable
class Agent(Protocol):
    """Anything that picks legal actions for a batch of decisions.

    ``act(obs, legal_mask, rng)``: obs (B, 72) uint8 in RLCard's limit-holdem encoding,
    legal_mask (B, 4) bool over (call, raise, fold, check), ``rng`` the only randomness to use
    (for reproducible matches); returns (B,) int64 action ids, always legal.
    """

    name: str

    def act(
        self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator
    ) -> np.ndarray: ...


@dataclass(frozen=True, kw_only=True)
class RandomAgent:
    """Uniform over the legal actions, like RLCard's ``RandomAgent``."""

    name: str = "random"

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        # The k-th legal action of each row, k uniform in 0 .. (number legal - 1), by table.
        pattern = np.packbits(np.asarray(legal_mask, dtype=bool), axis=1, bitorder="little")[:, 0]
        k = (rng.random(pattern.size) * _LEGAL_COUNT[pattern]).astype(np.int64)
        return _KTH_LEGAL[pattern, k]


@dataclass(frozen=True, kw_only=True)
class RaiseAgent:
    """Raise if legal, else call, else check."""

    name: str = "raise"

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        passive = np.where(legal_mask[:, CALL], CALL, CHECK)
        return np.where(legal_mask[:, RAISE], RAISE, passive).astype(np.int64)


@dataclass(frozen=True, kw_only=True)
class CallAgent:
    """Call if facing a bet, else check: never raises, never folds."""

    name: str = "call"

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return np.where(legal_mask[:, CALL], CALL, CHECK).astype(np.int64)


BUILT_IN_AGENTS: dict[str, Callable[[], Agent]] = {
    "random": RandomAgent,
    "raise": RaiseAgent,
    "call": CallAgent,
}


def make_agent(name: str) -> Agent:
    """The agent called ``name``; raises ``ValueError`` for names it does not know.

    >>> make_agent("call").name
    'call'
    """
    factory = BUILT_IN_AGENTS.get(name)
    if factory is None:
        known = ", ".join(sorted(BUILT_IN_AGENTS))
        raise ValueError(f"unknown agent {name!r} (built-in agents: {known})")
    return factory()
