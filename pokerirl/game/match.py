"""Play two agents against each other for many hands and summarise agent A's result.

Hand ``i`` seats agent A as the small blind (seat 0) when ``i`` is even and as the big blind
when ``i`` is odd. Without duplicate, hand ``i`` uses deal ``i`` of the seed; with duplicate,
hands ``2j`` and ``2j + 1`` both use deal ``j``, so each agent plays each deal from both seats
(with each seat's cards), and the pair's mean is the independent unit for the standard error.

>>> from pokerirl.game.bots import make_agent
>>> result = play_match(make_agent("raise"), make_agent("call"), hands=1_000, seed=1)
>>> result.hands, result.duplicate, round(result.mbb_per_hand) == round(result.mbb_per_hand)
(1000, True, True)
"""

from __future__ import annotations

import functools
import numbers
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from tqdm import tqdm

from pokerirl.errors import ConfigError, check_argument, check_protocol
from pokerirl.execution import unit_progress
from pokerirl.game.bots import Agent, agent_actions, seat_cards
from pokerirl.game.deals import deal_cards
from pokerirl.game.encodings import Encoding, EncodingName, RawStates, get_encoding
from pokerirl.game.engine import (
    IllegalActionError,
    LimitHoldemBatch,
    legal_mask_of,
    whole_actions,
)
from pokerirl.game.evaluator import prepare_tables

DEFAULT_BATCH_SIZE = 65_536
# A match keeps 8 bytes per hand (results_bb) and a batch about 1 KB per hand in lock-step;
# these caps keep both under about 1 GB. 10^8 hands give a standard error near 0.5 mbb/h.
MAX_HANDS = 100_000_000
MAX_BATCH_SIZE = 1_048_576
AGENT_STREAM = 1  # spawn-key word for agents' randomness (deals use 0)
SEATINGS = ("alternate", "random")
_NO_OBS = np.empty((MAX_BATCH_SIZE, 0), dtype=np.uint8)  # what an agent that reads none gets


@dataclass(frozen=True, kw_only=True)
class MatchResult:
    """Agent A's result against agent B; money in big blinds, rates in milli-big-blinds."""

    agent_a: str
    agent_b: str
    hands: int
    seed: int
    duplicate: bool
    mbb_per_hand: float  # 1000 x A's mean net big blinds per hand
    std_error: float  # of mbb_per_hand: over duplicate pairs, or over hands
    seconds: float  # of play: the deals, the agents and the engine
    hands_per_second: float
    # A's net big blinds in every hand, in hand order (duplicate pairs are adjacent).
    results_bb: np.ndarray = field(repr=False, compare=False)
    # Time in ``on_batch`` (e.g. the AIVAT corrections), apart from ``seconds``.
    on_batch_seconds: float = 0.0

    @property
    def units_bb(self) -> np.ndarray:
        """The independent units of A's result: duplicate pairs' means, or single hands."""
        return independent_units(self.results_bb, duplicate=self.duplicate)


def independent_units(results_bb: np.ndarray, *, duplicate: bool) -> np.ndarray:
    """Per-hand results as independent units: each duplicate pair's mean, or the hands."""
    return results_bb.reshape(-1, 2).mean(axis=1) if duplicate else results_bb


def _agent_rng(seed: int, which: int) -> np.random.Generator:
    return np.random.Generator(
        np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(AGENT_STREAM, which)))
    )


def turn_cards(game: LimitHoldemBatch, hands: np.ndarray) -> np.ndarray:
    """(n, 7) cards of the seat to act in ``hands``, hole cards first (see ``seat_cards``)."""
    return seat_cards(game.cards[hands], game.round[hands], game.to_act[hands])


def agent_encoding(agent: Agent) -> Encoding:
    """The encoding ``agent`` reads its observations in: its ``encoding`` attribute, else
    RLCard's 72-d observation."""
    return get_encoding(getattr(agent, "encoding", None))


def observe(game: LimitHoldemBatch, hands: np.ndarray, encoding: Encoding) -> np.ndarray:
    """The observations of the seat to act in ``hands``, in ``encoding`` (the engine's own
    72-d one for ``rlcard``)."""
    if encoding.name == EncodingName.RLCARD:
        return game.observe(hands)
    states = RawStates(cards=turn_cards(game, hands), raise_nums=game.raises[hands],
                    legal_mask=game.legal_mask(hands))  # fmt: skip
    return encoding.encode(states)


@dataclass(frozen=True, kw_only=True)
class DecisionLog:
    """Every decision one agent took in a match: what it saw and what it did, in play order
    (``obs`` is RLCard's 72-d observation, whatever the agent's own encoding)."""

    obs: np.ndarray  # (N, 72) uint8
    legal_mask: np.ndarray  # (N, 4) bool
    cards: np.ndarray  # (N, 7) int8: hole cards, then the board shown (-1 beyond)
    actions: np.ndarray  # (N,) int64

    @classmethod
    def concatenate(cls, parts: list[DecisionLog]) -> DecisionLog:
        return cls(
            **{
                name: np.concatenate([getattr(p, name) for p in parts])
                for name in ("obs", "legal_mask", "cards", "actions")
            }
        )


def play_batch(
    agents: tuple[Agent, Agent],
    deals: np.ndarray,
    seat_of_first: np.ndarray,
    rngs: tuple[np.random.Generator, np.random.Generator],
    *,
    log: list[DecisionLog] | None = None,
) -> np.ndarray:
    """Play one batch of hands to the end; return the first agent's net big blinds per hand.

    Args:
        agents: the two agents.
        deals: (B, 9) deals.
        seat_of_first: (B,) seat (0 small blind, 1 big blind) of ``agents[0]`` in each hand.
        rngs: each agent's generator.
        log: when given, the first agent's decisions are appended to it, one part per step.
    """
    game = play_game(agents, deals, seat_of_first, rngs, log=log)
    return game.payoffs[np.arange(game.size), seat_of_first]


def play_game(
    agents: tuple[Agent, Agent],
    deals: np.ndarray,
    seat_of_first: np.ndarray,
    rngs: tuple[np.random.Generator, np.random.Generator],
    *,
    log: list[DecisionLog] | None = None,
) -> LimitHoldemBatch:
    """:func:`play_batch`, returning the finished game itself (its payoffs, raises and
    rounds, for callers that read more than the result: the chance corrections)."""
    game = LimitHoldemBatch(deals=deals)
    encodings = tuple(agent_encoding(agent) for agent in agents)
    # Agents that decide from the legal mask alone get an empty obs: building (n, 72)
    # observations nobody reads was half of a built-in match's time.
    reads = tuple(getattr(agent, "reads_obs", True) for agent in agents)
    while game.active().size:
        hands = game.active()
        # Each decision's state is gathered once for the legal masks and the step; the two
        # agents' hands are disjoint, so both decide on the state before either acts and
        # one step applies all their actions (two steps on halves cost twice the calls).
        turn = game.turn(hands)
        words = turn.legal_words
        first_to_act = turn.seat == seat_of_first[hands]
        actions = np.empty(hands.size, dtype=np.int64)
        # Each agent decides for all hands where it is to act: one batched call per agent.
        # (Indices, not boolean masks: a masked gather costs several times one by index.)
        for which, agent, encoding, reads_obs, rng, at in zip(
            (0, 1), agents, encodings, reads, rngs,
            (np.flatnonzero(first_to_act), np.flatnonzero(~first_to_act)), strict=True,
        ):  # fmt: skip
            if at.size == 0:
                continue
            mine = hands[at]
            obs = observe(game, mine, encoding) if reads_obs else _NO_OBS[: mine.size]
            legal = legal_mask_of(words[at])
            cards = functools.partial(turn_cards, game, mine)
            chosen = whole_actions(agent_actions(agent, obs, legal, rng, cards))
            if chosen.shape != mine.shape:
                raise ValueError(f"agent {agent.name!r}: got {chosen.shape} actions for "
                                 f"{mine.shape} hands")  # fmt: skip
            if log is not None and which == 0:
                plain = reads_obs and encoding.name == EncodingName.RLCARD
                seen = obs if plain else game.observe(mine)
                log.append(DecisionLog(obs=seen, legal_mask=legal, cards=cards(), actions=chosen))
            actions[at] = chosen
        try:
            game.apply(turn, actions)
        except IllegalActionError as error:
            which = 0 if error.position is None or first_to_act[error.position] else 1
            raise IllegalActionError(f"agent {agents[which].name!r}: {error}") from error
    return game


def check_match_size(hands: int, *, duplicate: bool, batch_size: int = DEFAULT_BATCH_SIZE) -> None:
    """Check a match's sizes before anything is allocated; ConfigError (a ValueError, one
    line) if bad.

    ``hands`` must lie in [1, :data:`MAX_HANDS`] and ``batch_size`` in [2,
    :data:`MAX_BATCH_SIZE`]; with ``duplicate`` both must be even.

    >>> check_match_size(99_999_999_999_998, duplicate=True)
    Traceback (most recent call last):
    pokerirl.errors.ConfigError: hands must be at most 100,000,000 per match, got 99,999,999,999,998
    """
    if hands < 1:
        raise ConfigError(f"hands must be at least 1, got {hands}")
    if hands > MAX_HANDS:
        raise ConfigError(f"hands must be at most {MAX_HANDS:,} per match, got {hands:,}")
    if not 2 <= batch_size <= MAX_BATCH_SIZE:
        raise ConfigError(
            f"batch_size must be between 2 and {MAX_BATCH_SIZE:,}, got {batch_size:,}"
        )
    if duplicate and hands % 2:
        raise ConfigError(
            f"duplicate matches play every deal twice: hands must be even, got {hands}"
        )
    if duplicate and batch_size % 2:
        raise ConfigError(f"duplicate matches need an even batch_size, got {batch_size}")


def play_match(
    agent_a: Agent,
    agent_b: Agent,
    *,
    hands: int,
    seed: int,
    duplicate: bool = True,
    batch_size: int = DEFAULT_BATCH_SIZE,
    progress: bool = False,
    log: list[DecisionLog] | None = None,
    seating: str = "alternate",
    on_batch: Callable[[int, LimitHoldemBatch, np.ndarray], None] | None = None,
    report_progress: bool = False,
) -> MatchResult:
    """Play ``hands`` hands of A against B, ``batch_size`` hands in lock-step at a time.

    The same arguments give the same result; deals do not depend on ``batch_size``, but the
    agents' random draws do. ``progress`` shows a tqdm bar on stderr; ``log`` collects A's
    decisions (see :func:`play_batch`). ``seating="random"`` (without duplicate) draws A's
    seat for every hand, as RLCard draws the small blind for every game; the default
    alternates it. ``on_batch(start, game, seat_of_a)`` is called with each finished batch
    (hands ``start`` ..), for what a caller reads beyond the result (the chance corrections
    of :mod:`pokerirl.tournaments.aivat`); its time is ``on_batch_seconds``, not part of
    ``seconds`` and ``hands_per_second`` (the play's). ``report_progress``: the match is a
    unit of its own (a tournament seed), whose hands move the driver's bar
    (:func:`pokerirl.execution.unit_progress`).

    Raises:
        ValueError: as :func:`check_match_size`, or on a negative seed.
    """
    _check_arguments(agent_a, agent_b, hands=hands, seed=seed, batch_size=batch_size)
    check_match_size(hands, duplicate=duplicate, batch_size=batch_size)
    if seed < 0:
        raise ConfigError(f"seed must be non-negative, got {seed}")
    if seating not in SEATINGS or (seating == "random" and duplicate):
        raise ConfigError(f"seating must be alternate, or random without duplicate: {seating!r}")

    rngs = (_agent_rng(seed, 0), _agent_rng(seed, 1))
    seat_rng = _agent_rng(seed, 2)
    results = np.empty(hands, dtype=np.float64)
    prepare_tables()  # one-time setup, kept out of hands_per_second
    started = time.perf_counter()
    on_batch_seconds = 0.0
    with tqdm(total=hands, unit="hand", unit_scale=True, disable=not progress) as bar:
        for start in range(0, hands, batch_size):
            count = min(batch_size, hands - start)
            if duplicate:
                deals = np.repeat(
                    deal_cards(seed=seed, start=start // 2, count=count // 2), 2, axis=0
                )
            else:
                deals = deal_cards(seed=seed, start=start, count=count)
            if seating == "random":
                seat_of_a = seat_rng.integers(0, 2, count).astype(np.int8)
            else:
                seat_of_a = (np.arange(start, start + count) % 2).astype(np.int8)
            game = play_game((agent_a, agent_b), deals, seat_of_a, rngs, log=log)
            results[start : start + count] = game.payoffs[np.arange(count), seat_of_a]
            if on_batch is not None:
                before = time.perf_counter()
                on_batch(start, game, seat_of_a)
                on_batch_seconds += time.perf_counter() - before
            bar.update(count)
            if report_progress:
                unit_progress(start + count, hands)
    seconds = time.perf_counter() - started - on_batch_seconds

    units = independent_units(results, duplicate=duplicate)
    std_error = float(units.std(ddof=1) / np.sqrt(units.size)) if units.size > 1 else float("nan")
    return MatchResult(
        agent_a=agent_a.name,
        agent_b=agent_b.name,
        hands=hands,
        seed=seed,
        duplicate=duplicate,
        mbb_per_hand=1000.0 * float(units.mean()),
        std_error=1000.0 * std_error,
        seconds=seconds,
        hands_per_second=hands / seconds if seconds > 0 else float("inf"),
        results_bb=results,
        on_batch_seconds=on_batch_seconds,
    )


def _check_arguments(agent_a: object, agent_b: object, **counts: object) -> None:
    """play_match's arguments at the door (issue 46): specs where agents were meant, a count
    given as a string or None, each named."""
    agent = "an Agent (pokerirl.resolve_agent(spec) makes one)"
    check_protocol("agent_a", agent_a, ("act",), agent)
    check_protocol("agent_b", agent_b, ("act",), agent)
    for name, value in counts.items():
        check_argument(name, value, numbers.Integral, "an integer")
