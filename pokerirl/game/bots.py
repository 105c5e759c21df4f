"""The agent protocol the engine talks to, the built-in bots and the name registry.

The bots are the fixed, hand-written agents (``random``, ``call``, ``raise``, ...);
:mod:`pokerirl.poker.run_agents` holds the agents made of an IRL run, and
:mod:`pokerirl.agents` the learned (DQN) agents and the resolution of every agent name.

An agent decides for a whole batch at once: one call per decision step, so a network agent
makes one batched forward pass. An agent whose ``sees_cards`` is true also gets ``cards``:
its hole cards and the board shown so far, in the order they were dealt (the observation's
card bits cannot tell hole cards from board cards); :func:`agent_actions` passes them.

An agent whose ``reads_obs`` is false (the built-ins that decide from the legal mask alone)
gets an empty (B, 0) ``obs``: the engine skips building observations nobody reads.

An agent that can say how likely each of its actions is (every built-in, the DQN agents)
also has ``action_probs(obs, legal_mask)`` (:class:`PolicyAgent`): what local best response
(:mod:`pokerirl.tournaments.lbr`) needs to keep the agent's range.
:func:`agent_action_probs` calls it, with the cards for an agent that sees them.

>>> agent = make_agent("raise")
>>> mask = np.array([[True, True, True, False], [True, False, True, False]])
>>> agent.act(np.zeros((2, 72), np.uint8), mask, np.random.default_rng(0)).tolist()
[1, 0]
>>> make_agent("random").action_probs(np.zeros((2, 72), np.uint8), mask).round(3).tolist()
[[0.333, 0.333, 0.333, 0.0], [0.5, 0.0, 0.5, 0.0]]
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar, Protocol, runtime_checkable

import numpy as np

from pokerirl.errors import ConfigError
from pokerirl.game.synth import DEFAULT_PLAYERS, ScriptedPlayer, visible_strength
from pokerirl.holdem import (
    BOARD_SIZE_BY_ROUND,
    CALL,
    CHECK,
    FOLD,
    NUM_ACTIONS,
    RAISE,
    RAISE_OFFSET,
)

# For each of the 16 legal-mask patterns (bit i: action i legal): how many, and the k-th one.
_LEGAL_COUNT = np.array([bin(p).count("1") for p in range(16)])
_KTH_LEGAL = np.array(
    [[a for a in range(4) if p >> a & 1] + [0] * (4 - bin(p).count("1")) for p in range(16)],
    dtype=np.int64,
)
_KTH_LEGAL_FLAT = _KTH_LEGAL.reshape(-1)  # [4 * pattern + k]: one 1-D gather
_PATTERN_MULTIPLIER = np.uint32(0x01020408)


def legal_patterns(legal_mask: np.ndarray) -> np.ndarray:
    """(B,) int64 bit patterns of (B, 4) legal masks (bit i: action i legal).

    A row's four bytes (0 or 1) read as one little-endian word ``b0 + b1 << 8 + ...``; times
    0x01020408 its top byte is ``b0 + 2 b1 + 4 b2 + 8 b3`` (no carries: every byte sum stays
    below 16). Several times faster than ``np.packbits`` over the rows.

    >>> legal_patterns(np.array([[True, True, True, False], [False, False, True, True]])).tolist()
    [7, 12]
    """
    mask = np.ascontiguousarray(legal_mask, dtype=np.bool_)
    if mask.ndim != 2 or mask.shape[1] != NUM_ACTIONS:
        raise ValueError(f"legal masks must have shape (B, {NUM_ACTIONS}), got {mask.shape}")
    words = mask.view("<u4").reshape(-1)
    return ((words * _PATTERN_MULTIPLIER) >> np.uint32(24)).astype(np.int64)


@runtime_checkable
class Agent(Protocol):
    """Anything that picks legal actions for a batch of decisions.

    ``act(obs, legal_mask, rng)``: obs (B, 72) uint8 in RLCard's limit-holdem encoding (or,
    for an agent with an ``encoding`` attribute, in that encoding of
    :mod:`pokerirl.game.encodings`: the engine builds each agent's own), legal_mask (B, 4)
    bool over (call, raise, fold, check), ``rng`` the only randomness to use (for
    reproducible matches); returns (B,) int64 action ids, always legal.
    """

    @property
    def name(self) -> str: ...  # read-only, so frozen dataclasses qualify

    def act(
        self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator
    ) -> np.ndarray: ...


@runtime_checkable
class PolicyAgent(Agent, Protocol):
    """An :class:`Agent` that also gives the probability of each of its actions.

    ``action_probs(obs, legal_mask)``: the same obs and legal_mask as ``act``; returns (B, 4)
    float64 over (call, raise, fold, check), zero on illegal actions, each row summing to 1:
    the distribution ``act`` draws from. An agent with ``sees_cards`` takes ``cards=`` too
    (see :func:`agent_action_probs`).
    """

    def action_probs(self, obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray: ...


def one_hot_actions(actions: np.ndarray) -> np.ndarray:
    """(B, 4) float64 probabilities of a deterministic choice of (B,) action ids.

    >>> one_hot_actions(np.array([3, 0])).tolist()
    [[0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0]]
    """
    actions = np.asarray(actions, dtype=np.int64)
    probs = np.zeros((actions.size, NUM_ACTIONS))
    probs[np.arange(actions.size), actions] = 1.0
    return probs


@dataclass(frozen=True, kw_only=True)
class RandomAgent:
    """Uniform over the legal actions, like RLCard's ``RandomAgent``."""

    name: str = "random"
    reads_obs: ClassVar[bool] = False  # decides from the legal mask alone

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        # The k-th legal action of each row, k uniform in 0 .. (number legal - 1), by table.
        pattern = legal_patterns(legal_mask)
        k = (rng.random(pattern.size) * _LEGAL_COUNT[pattern]).astype(np.int64)
        return _KTH_LEGAL_FLAT[NUM_ACTIONS * pattern + k]

    def action_probs(self, obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
        legal = np.asarray(legal_mask, dtype=np.float64)
        return legal / legal.sum(axis=1, keepdims=True)


@dataclass(frozen=True, kw_only=True)
class RaiseAgent:
    """Raise if legal, else call, else check."""

    name: str = "raise"
    reads_obs: ClassVar[bool] = False  # decides from the legal mask alone

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        passive = np.where(legal_mask[:, CALL], CALL, CHECK)
        return np.where(legal_mask[:, RAISE], RAISE, passive).astype(np.int64)

    def action_probs(self, obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
        return one_hot_actions(self.act(obs, legal_mask, _NO_RNG))


@dataclass(frozen=True, kw_only=True)
class CallAgent:
    """Call if facing a bet, else check: never raises, never folds."""

    name: str = "call"
    reads_obs: ClassVar[bool] = False  # decides from the legal mask alone

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return np.where(legal_mask[:, CALL], CALL, CHECK).astype(np.int64)

    def action_probs(self, obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
        return one_hot_actions(self.act(obs, legal_mask, _NO_RNG))


@dataclass(frozen=True, kw_only=True)
class FoldAgent:
    """Fold, always: even when checking is free, which RLCard's rules allow (the folder loses
    what it has put in). The weakest agent there is: local best response wins 1 big blind
    against it from the small blind and 0.5 from the big blind."""

    name: str = "fold"
    reads_obs: ClassVar[bool] = False

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return np.full(len(legal_mask), FOLD, dtype=np.int64)

    def action_probs(self, obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
        return one_hot_actions(self.act(obs, legal_mask, _NO_RNG))


# Deterministic agents draw nothing; their action_probs call act with this placeholder.
_NO_RNG = np.random.default_rng(0)


# Cards a seat sees, by round (4 is after the river): its 2 hole cards, then the board.
_SHOWN = np.arange(7) < 2 + np.array((*BOARD_SIZE_BY_ROUND, 5))[:, None]


def seat_cards(deals: np.ndarray, rounds: np.ndarray, seats: np.ndarray) -> np.ndarray:
    """(n, 7) int8: each seat's hole cards then the board shown in ``rounds``, -1 for the rest.

    Args:
        deals: (n, 9) deals (seat 0 hole, seat 1 hole, board), e.g. ``LimitHoldemBatch.cards``
            of the hands.
        rounds: (n,) betting round of each hand (0 preflop .. 3 river, 4 after the river).
        seats: (n,) whose view (0 small blind, 1 big blind).

    >>> deal = np.arange(9)[None]
    >>> seat_cards(deal, np.array([1]), np.array([1])).tolist()
    [[2, 3, 4, 5, 6, -1, -1]]
    """
    deals = np.asarray(deals)
    seats = np.asarray(seats, dtype=np.int64)
    hole = np.stack([deals[np.arange(len(seats)), 2 * seats + k] for k in (0, 1)], axis=1)
    cards = np.concatenate([hole, deals[:, 4:9]], axis=1).astype(np.int8)
    return np.where(_SHOWN[np.asarray(rounds, dtype=np.int64)], cards, np.int8(-1))


def street_of(obs: np.ndarray) -> np.ndarray:
    """(B,) betting round of (B, 72) observations, from how many cards they show."""
    shown = np.asarray(obs)[:, :RAISE_OFFSET].sum(axis=1)
    return np.searchsorted(np.array((2, 5, 6, 7)), shown).astype(np.int64)


def raises_this_round(obs: np.ndarray) -> np.ndarray:
    """(B,) raises so far in the current round, read from the observation's one-hot slots."""
    obs = np.asarray(obs)
    street = street_of(obs)
    slots = RAISE_OFFSET + 5 * street[:, None] + np.arange(5)
    return obs[np.arange(len(obs))[:, None], slots].argmax(axis=1)


@dataclass(frozen=True, kw_only=True)
class ScriptedAgent:
    """A scripted player of the synthetic months (:mod:`pokerirl.game.synth`) on the engine.

    Its score ``s`` is :func:`~pokerirl.game.synth.visible_strength` of its hole cards and
    the board shown. With probability ``1 - noise`` it raises when ``s > raise_above`` and
    fewer than ``max_raises`` raises were made this round (and raising is legal), else
    calls a bet when ``s > call_above``, else checks or folds; with probability ``noise`` it
    picks uniformly among those options (check or call; fold when facing a bet; raise when
    allowed). :meth:`rule` is the noiseless choice.
    """

    name: str
    player: ScriptedPlayer
    sees_cards: bool = True

    def _options(
        self, obs: np.ndarray, legal_mask: np.ndarray, cards: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        legal_mask = np.asarray(legal_mask, dtype=bool)
        cards = np.asarray(cards, dtype=np.int64)
        street = street_of(obs)
        score = visible_strength(cards[:, :2], cards[:, 2:7])[np.arange(len(street)), street]
        facing = legal_mask[:, CALL]
        can_raise = legal_mask[:, RAISE] & (raises_this_round(obs) < self.player.max_raises)
        return score, facing, can_raise, np.where(facing, CALL, CHECK)

    def rule(self, obs: np.ndarray, legal_mask: np.ndarray, cards: np.ndarray) -> np.ndarray:
        """(B,) the noiseless action of each decision."""
        score, facing, can_raise, passive = self._options(obs, legal_mask, cards)
        stays = ~facing | (score > self.player.call_above)
        action = np.where(stays, passive, FOLD)
        return np.where(can_raise & (score > self.player.raise_above), RAISE, action).astype(
            np.int64
        )

    def act(
        self,
        obs: np.ndarray,
        legal_mask: np.ndarray,
        rng: np.random.Generator,
        *,
        cards: np.ndarray | None = None,
    ) -> np.ndarray:
        if cards is None:  # an Agent's act, called without what this agent must see
            raise ValueError(f"{self.name} sees the cards: pass cards= (see agent_actions)")
        _score, facing, can_raise, passive = self._options(obs, legal_mask, cards)
        action = self.rule(obs, legal_mask, cards)
        noisy = rng.random(len(action)) < self.player.noise
        # Options in synth's order: check or call, fold when facing, raise when allowed.
        count = 1 + facing + can_raise
        pick = (rng.random(len(action)) * count).astype(np.int64)
        options = np.stack([passive, np.where(facing, FOLD, RAISE), np.full_like(passive, RAISE)])
        random_pick = options[pick, np.arange(len(action))]
        return np.where(noisy, random_pick, action).astype(np.int64)

    def action_probs(
        self, obs: np.ndarray, legal_mask: np.ndarray, *, cards: np.ndarray | None = None
    ) -> np.ndarray:
        """What :meth:`act` draws from: the rule with probability ``1 - noise``, else uniform
        over its options (check or call; fold when facing a bet; raise when allowed)."""
        if cards is None:
            raise ValueError(f"{self.name} sees the cards: pass cards= (see agent_action_probs)")
        _score, facing, can_raise, passive = self._options(obs, legal_mask, cards)
        rows = np.arange(len(passive))
        noise = self.player.noise
        probs = (1.0 - noise) * one_hot_actions(self.rule(obs, legal_mask, cards))
        share = noise / (1 + facing + can_raise)  # options as act counts them
        np.add.at(probs, (rows, passive), share)
        probs[rows[facing], FOLD] += share[facing]
        probs[rows[can_raise], RAISE] += share[can_raise]
        return probs


def agent_actions(
    agent: Agent,
    obs: np.ndarray,
    legal_mask: np.ndarray,
    rng: np.random.Generator,
    cards: Callable[[], np.ndarray],
) -> np.ndarray:
    """``agent.act``, given the cards (``cards()``, computed only then) if it sees them."""
    if getattr(agent, "sees_cards", False):
        return agent.act(obs, legal_mask, rng, cards=cards())  # type: ignore[call-arg]
    return agent.act(obs, legal_mask, rng)


def agent_action_probs(
    agent: Agent,
    obs: np.ndarray,
    legal_mask: np.ndarray,
    cards: np.ndarray | Callable[[], np.ndarray] | None = None,
) -> np.ndarray:
    """``agent.action_probs``: (B, 4) float64 over (call, raise, fold, check), zero on illegal
    actions, rows summing to 1; given the cards (an array, or ``cards()`` computed only then)
    if the agent sees them.

    Raises:
        ConfigError: the agent has no ``action_probs`` (it cannot say how it plays).

    >>> mask = np.array([[True, True, True, False]])
    >>> agent_action_probs(make_agent("fold"), np.zeros((1, 72), np.uint8), mask).tolist()
    [[0.0, 0.0, 1.0, 0.0]]
    """
    action_probs = getattr(agent, "action_probs", None)
    if action_probs is None:
        raise ConfigError(
            f"agent {agent.name!r} has no action_probs: it cannot say how likely its actions "
            "are"
        )
    if getattr(agent, "sees_cards", False):
        if cards is None:
            raise ValueError(f"{agent.name} sees the cards: pass cards")
        seen = cards() if callable(cards) else cards
        return np.asarray(action_probs(obs, legal_mask, cards=seen), dtype=np.float64)
    return np.asarray(action_probs(obs, legal_mask), dtype=np.float64)


def _scripted(index: int) -> Callable[[], Agent]:
    player = DEFAULT_PLAYERS[index]
    return lambda: ScriptedAgent(name=player.nick.lower(), player=player)


BUILT_IN_AGENTS: dict[str, Callable[[], Agent]] = {
    "random": RandomAgent,
    "raise": RaiseAgent,
    "call": CallAgent,
    "fold": FoldAgent,
    "tightbot": _scripted(0),  # the synthetic months' experts, with their noise
    "loosebot": _scripted(1),
}


def make_agent(name: str) -> Agent:
    """The agent called ``name``; raises ``ValueError`` for names it does not know.

    >>> make_agent("call").name
    'call'
    """
    factory = BUILT_IN_AGENTS.get(name)
    if factory is None:
        known = ", ".join(sorted(BUILT_IN_AGENTS))
        raise ConfigError(f"unknown agent {name!r} (built-in agents: {known})")
    return factory()
