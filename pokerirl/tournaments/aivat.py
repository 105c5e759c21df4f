"""Variance-reduced match results: AIVAT-style chance corrections on top of duplicate deals.

Burch, Schmid, Moravčík, Morrill & Bowling (2018), "AIVAT: A New Variance Reduction
Technique for Agent Evaluation in Imperfect Information Games": subtracting, at each chance
event, ``v(state after it) - E[v over its outcomes]`` leaves the expected result unchanged for
*any* fixed value function v, and removes the luck of the cards that v explains. In our
matches both players' hole cards are known, so the expectations can be computed exactly.

The value function, fixed here before any run (never fitted to the hands it corrects):

    v = c x (2 e - 1) chips for seat 0, where c is the chips each player has committed when
    the card comes (both are level then) and e is seat 0's share of the pot at a showdown
    with the board rolled out from there (its equity against seat 1's actual hole cards).

So the correction at the flop, turn and river card is ``c_s x 2 (e_s - e_{s-1})`` chips: the
equity swing of that card times the money committed before it. The corrected result of a hand
is its payoff minus the corrections of the cards it reached (from each agent's side).

How each e is computed (each expectation is exact or an unbiased estimate; either keeps
the corrected mean unbiased, and the estimates' randomness is drawn apart from the deals and
the agents' draws, so it cannot correlate with the play):

* river e_3: the showdown of the actual board; its expectation e_2 exactly over the 44
  rivers;
* turn: e_2 (exact) against e_1, the equity on the flop, estimated from
  :data:`FLOP_RUNOUTS` random turn-and-river runouts (the same estimate is the flop's value:
  its noise then enters only with the flop's betting, ``c_1 - c_2``);
* flop: e_1 against e_0, the preflop equity, estimated from :data:`PREFLOP_BOARDS` random
  boards (exact preflop equity would cost 1.7 million boards a deal).

``tests/test_aivat.py`` checks that the corrections have mean zero (also between agents
whose betting depends on their cards) and that the corrected standard error is smaller.

>>> from pokerirl.game.bots import make_agent
>>> from pokerirl.game.match import play_match
>>> agents = make_agent("tightbot"), make_agent("call")
>>> found = play_corrected_match(*agents, hands=2_000, seed=0)
>>> found.match.mbb_per_hand == play_match(*agents, hands=2_000, seed=0).mbb_per_hand
True
>>> bool(found.corrected.std_error < found.raw.std_error)
True
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pokerirl.game.bots import Agent
from pokerirl.game.engine import LimitHoldemBatch
from pokerirl.game.match import (
    DEFAULT_BATCH_SIZE,
    MatchResult,
    independent_units,
    play_match,
)
from pokerirl.tournaments.equity import showdown_shares
from pokerirl.tournaments.stats import Estimate, estimate

PREFLOP_BOARDS = 32  # random boards per deal for the preflop equity e_0
FLOP_RUNOUTS = 32  # random turn-and-river runouts per deal for the flop equity e_1
AIVAT_STREAM = 4  # spawn-key word of the estimates' draws (deals 0, agents 1, DQN 2, LBR 3)
BET_BY_STREET = np.array([2, 2, 4, 4])  # chips a raise adds, by round
CHUNK = 4096  # deals whose equities are computed together


@dataclass(frozen=True, kw_only=True)
class CorrectedMatch:
    """A match's raw result (:class:`~pokerirl.game.match.MatchResult`, the same numbers
    :func:`~pokerirl.game.match.play_match` gives) and its chance-corrected twin: A's mean
    and standard error in mbb/h over the same independent units (NaN with one unit).

    ``corrected_bb``: A's corrected net big blinds in every hand, in hand order.
    """

    match: MatchResult
    corrected_mbb_per_hand: float
    corrected_std_error: float
    corrected_bb: np.ndarray = field(repr=False, compare=False)

    @property
    def raw(self) -> Estimate:
        """A's raw mbb/h over the match's independent units (at least two)."""
        return estimate(1000.0 * self.match.units_bb)

    @property
    def corrected(self) -> Estimate:
        """A's corrected mbb/h over the same units (at least two)."""
        return estimate(
            1000.0 * independent_units(self.corrected_bb, duplicate=self.match.duplicate)
        )


def _mean_and_error(units_bb: np.ndarray) -> tuple[float, float]:
    """1000 x (mean, standard error) of independent units, the error NaN for one unit (as
    :func:`~pokerirl.game.match.play_match` reports it)."""
    error = float(units_bb.std(ddof=1) / np.sqrt(units_bb.size)) if units_bb.size > 1 else np.nan
    return 1000.0 * float(units_bb.mean()), 1000.0 * error


def committed(raises: np.ndarray, street: int) -> np.ndarray:
    """(N,) chips each player has in when the card(s) of ``street`` (1 flop .. 3 river) come:
    both are level then, at 2 + the raises of the rounds before, times their size.

    >>> committed(np.array([[1, 2, 0, 0]]), 2).tolist()  # a raise preflop, two on the flop
    [8]
    """
    raises = np.asarray(raises, dtype=np.int64)
    return 2 + (raises[:, :street] * BET_BY_STREET[:street]).sum(axis=1)


def _sample_cards(
    rng: np.random.Generator, unseen: np.ndarray, samples: int, count: int
) -> np.ndarray:
    """(N, samples, count) distinct cards drawn uniformly from each row of ``unseen`` (N, U):
    positions drawn with replacement, the samples with a repeat drawn again."""
    n, size = unseen.shape
    positions = rng.integers(0, size, (count, n * samples), dtype=np.int16)
    todo = None  # the samples to check: all, then those drawn again
    while True:
        drawn = positions if todo is None else positions[:, todo]
        repeat = np.zeros(drawn.shape[1], dtype=bool)
        for i in range(count):
            for j in range(i + 1, count):
                repeat |= drawn[i] == drawn[j]
        todo = np.flatnonzero(repeat) if todo is None else todo[repeat]
        if not todo.size:
            break
        positions[:, todo] = rng.integers(0, size, (count, todo.size), dtype=np.int16)
    chosen = np.take_along_axis(unseen, positions.T.reshape(n, samples * count), axis=1)
    return chosen.reshape(n, samples, count)


def _unseen(known: np.ndarray) -> np.ndarray:
    """(N, 52 - k) the cards not in each row of ``known`` (N, k), ascending."""
    free = np.ones((len(known), 52), dtype=bool)
    free[np.arange(len(known))[:, None], known] = False
    # Row-major nonzero lists each row's free cards in ascending order (no sort needed).
    return np.nonzero(free)[1].reshape(len(known), 52 - known.shape[1])


def deal_equities(deals: np.ndarray, reached: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(D, 4) seat 0's equity e_0 .. e_3 in each deal (see the module docstring), NaN where no
    hand of the deal reached that street's card (``reached`` (D,), 0 .. 3: the last street
    whose card any hand of the deal saw)."""
    deals = np.asarray(deals, dtype=np.int64)
    if len(deals) > CHUNK:  # a few thousand deals at a time: the arrays stay in cache
        return np.concatenate(
            [
                deal_equities(deals[i : i + CHUNK], reached[i : i + CHUNK], rng)
                for i in range(0, len(deals), CHUNK)
            ]
        )
    found = np.full((len(deals), 4), np.nan)
    holes = deals[:, :4].reshape(-1, 2, 2)
    rows = np.flatnonzero(reached >= 1)
    if rows.size:  # e_0 from random boards, e_1 from random runouts of the flop
        boards = _sample_cards(rng, _unseen(deals[rows, :4]), PREFLOP_BOARDS, 5)
        found[rows, 0] = showdown_shares(holes[rows], boards).mean(axis=1)
        runouts = _sample_cards(rng, _unseen(deals[rows, :7]), FLOP_RUNOUTS, 2)
        flop = np.broadcast_to(deals[rows, None, 4:7], (rows.size, FLOP_RUNOUTS, 3))
        boards = np.concatenate([flop, runouts], axis=2)
        found[rows, 1] = showdown_shares(holes[rows], boards).mean(axis=1)
    rows = np.flatnonzero(reached >= 2)
    if rows.size:  # e_2 exactly: every river
        rivers = _unseen(deals[rows, :8])  # (n, 44)
        turn = np.broadcast_to(deals[rows, None, 4:8], (rows.size, rivers.shape[1], 4))
        boards = np.concatenate([turn, rivers[:, :, None]], axis=2)
        found[rows, 2] = showdown_shares(holes[rows], boards).mean(axis=1)
    rows = np.flatnonzero(reached >= 3)
    if rows.size:  # e_3: the showdown
        found[rows, 3] = showdown_shares(holes[rows], deals[rows, None, 4:9])[:, 0]
    return found


def chance_corrections(
    deals: np.ndarray, raises: np.ndarray, rounds: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """(B,) seat 0's correction in big blinds for each finished hand: ``sum over the cards it
    reached of c_s (e_s - e_{s-1})`` (chips x 2 / 2 chips a big blind).

    Args:
        deals: (B, 9) the hands' deals; equal rows (duplicate pairs) share their estimates
            only if they are adjacent, as the two hands of a pair are.
        raises: (B, 4) raises per round at the end (``LimitHoldemBatch.raises``).
        rounds: (B,) the round each hand ended in (4 after a showdown).
        rng: the estimates' randomness.
    """
    deals, rounds = np.asarray(deals), np.asarray(rounds, dtype=np.int64)
    # One row per run of equal adjacent deals: a duplicate pair's two hands, else one hand.
    first = np.ones(len(deals), dtype=bool)
    first[1:] = (deals[1:] != deals[:-1]).any(axis=1)
    group = np.cumsum(first) - 1
    reached = np.minimum(rounds, 3)
    most = np.zeros(int(first.sum()), dtype=np.int64)
    np.maximum.at(most, group, reached)
    equity = deal_equities(deals[first], most, rng)[group]
    correction = np.zeros(len(deals))
    for street in (1, 2, 3):
        hands = reached >= street
        swing = equity[hands, street] - equity[hands, street - 1]
        correction[hands] += committed(raises[hands], street) * swing
    return correction


def play_corrected_match(
    agent_a: Agent,
    agent_b: Agent,
    *,
    hands: int,
    seed: int,
    duplicate: bool = True,
    batch_size: int = DEFAULT_BATCH_SIZE,
    progress: bool = False,
    report_progress: bool = False,
) -> CorrectedMatch:
    """:func:`pokerirl.game.match.play_match` (seats alternating), which plays and reports
    the raw result, with each hand's chance correction computed from the finished batches.

    Raises:
        ConfigError: as :func:`~pokerirl.game.match.check_match_size`, or a negative seed.
    """
    estimates = np.random.Generator(
        np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(AIVAT_STREAM, 0)))
    )
    corrected = np.empty(hands, dtype=np.float64)

    def correct(start: int, game: LimitHoldemBatch, seat_of_a: np.ndarray) -> None:
        mine = game.payoffs[np.arange(game.size), seat_of_a]
        correction = chance_corrections(game.cards, game.raises, game.round, estimates)
        # Seat 0's correction, from A's side: minus where A sat in seat 1.
        sign = np.where(seat_of_a == 0, 1, -1)
        corrected[start : start + game.size] = mine - sign * correction

    match = play_match(agent_a, agent_b, hands=hands, seed=seed, duplicate=duplicate,
                       batch_size=batch_size, progress=progress, on_batch=correct,
                       report_progress=report_progress)  # fmt: skip
    fixed_mean, fixed_error = _mean_and_error(independent_units(corrected, duplicate=duplicate))
    return CorrectedMatch(
        match=match,
        corrected_mbb_per_hand=fixed_mean,
        corrected_std_error=fixed_error,
        corrected_bb=corrected,
    )
