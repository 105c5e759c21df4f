"""Local best response (LBR) to an agent, under RLCard 1.2.0's limit hold'em rules.

Lisý & Bowling (2017), "Equilibrium Approximation Quality of Current No-Limit Poker Bots";
PokerRL (Steinberger 2019) has the limit version this follows. LBR holds its own cards and
keeps the agent's *range*: a weight for each of the 1,326 hole-card pairs, zero for the pairs
that share a card with LBR's hand or the board shown.

* After each agent action the range is updated by Bayes' rule: each pair's weight times the
  agent's probability of that action with that pair, from one batched ``action_probs`` call
  over the observations of all live pairs (built by :mod:`pokerirl.game.encodings` from the
  engine's own raise counts, exactly as the engine builds the agent's real observation).
* At its own decision LBR takes the best of, in chips beyond those already in (P the pot, q
  the amount to call, b the raise, wp its equity against the range, fp the agent's fold
  probability after a raise and wp' the equity against the pairs that do not fold):

  - u(fold) = 0;
  - u(check/call) = wp P - (1 - wp) q;
  - u(raise) = fp P + (1 - fp) (wp' (P + b) - (1 - wp') (q + b)), when a raise is legal.

  Ties go to check/call, then raise; LBR folds only when both are worth less than 0 (so it
  never folds when checking is free). Before ``check_until`` it only checks or calls.
* Equity is exact on the flop (all 1,081 turn-and-river runouts), turn (46 rivers) and river;
  preflop it is the mean over ``preflop_boards`` boards drawn at random (seeded).
* The agent's own moves are drawn from its ``action_probs`` for its real cards: the same row
  the range update uses, so the model LBR keeps is exactly the policy it faces.
* An empty range cannot follow from the agent's own probabilities (its real pair keeps the
  probability of every move it made); should one arise anyway (an agent whose
  ``action_probs`` underflows to 0), it is reset to every pair LBR cannot rule out by the
  cards, counted in ``range_resets``. Nothing is ever divided by zero.

LBR is a lower bound on the agent's exploitability: it looks one action ahead, assumes the
hand is checked down after its action, and ignores re-raises.

>>> from pokerirl.game.bots import make_agent
>>> from pokerirl.game.deals import deal_cards
>>> deals = np.repeat(deal_cards(seed=0, start=0, count=4), 2, axis=0)
>>> seats = np.arange(8) % 2
>>> found = play_lbr(make_agent("fold"), deals, seats, np.random.default_rng(0), LBRSettings())
>>> found.payoffs.tolist()  # the fold agent gives up its blind: 1 bb, or 0.5 as small blind
[1.0, 0.5, 1.0, 0.5, 1.0, 0.5, 1.0, 0.5]
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np

from pokerirl.errors import ConfigError
from pokerirl.game.bots import Agent, agent_action_probs
from pokerirl.game.encodings import Encoding, RawStates
from pokerirl.game.engine import RAISE_SIZE_BY_ROUND, LimitHoldemBatch
from pokerirl.game.match import agent_encoding
from pokerirl.holdem import CALL, CHECK, FOLD, MAX_RAISES, NUM_ACTIONS, RAISE, pair_cards
from pokerirl.tournaments.equity import (
    CLASH,
    NUM_PAIRS,
    board_strengths,
    pair_index,
)

ROWS_PER_PASS = 16_384  # observations per action_probs call: bounded memory
EQUITY_BOARDS = 2_048  # boards ranked against all 1,326 pairs at once (about 10 MB each)
_BOARD_SHOWN = np.arange(5) < np.array([0, 3, 4, 5, 5])[:, None]  # (round, board card)
_CLASH_OR_NONE = np.vstack([CLASH, np.zeros((1, NUM_PAIRS), dtype=bool)])  # row 52: no card
_RUNOUTS = np.array([(i, j) for i in range(47) for j in range(i + 1, 47)])  # flop: 1,081


class Street(StrEnum):
    """A betting round, by name."""

    PREFLOP = "preflop"
    FLOP = "flop"
    TURN = "turn"
    RIVER = "river"

    @property
    def number(self) -> int:
        """0 preflop .. 3 river, as the engine's ``round``."""
        return list(Street).index(self)


def parse_street(name: str) -> Street:
    """The street called ``name``; :class:`ConfigError` naming the streets otherwise.

    >>> parse_street("turn").number
    2
    """
    if name not in tuple(Street):
        raise ConfigError(f"unknown street {name!r} ({', '.join(Street)})")
    return Street(name)


@dataclass(frozen=True, kw_only=True)
class LBRSettings:
    """How LBR plays.

    ``check_until``: LBR only checks or calls before this street (PokerRL's
    ``lbr_check_to_round``): ``preflop`` is full LBR; ``turn`` skips the costly flop
    enumeration and the preflop estimate, and gives up what betting earlier would win.
    ``preflop_boards``: random boards for the preflop equity.

    >>> LBRSettings(check_until="turn").check_until.number
    2
    """

    check_until: Street = Street.PREFLOP
    preflop_boards: int = 256

    def __post_init__(self) -> None:
        # A street's name is taken too (LBRSettings(check_until="turn")).
        object.__setattr__(self, "check_until", parse_street(self.check_until))
        if not 1 <= self.preflop_boards <= 100_000:
            raise ConfigError(
                f"preflop_boards must be between 1 and 100,000, got {self.preflop_boards}"
            )


@dataclass(frozen=True, kw_only=True)
class LBRBatch:
    """What :func:`play_lbr` found for each hand of a batch.

    ``payoffs`` (B,) LBR's net big blinds; ``end_round`` (B,) the round the hand ended in (0
    preflop .. 3 river by a fold, 4 after a showdown); ``raises`` (B, 4) the raises of each
    round, as the engine counts them; ``range_resets`` how many empty ranges were reset.
    With ``trace``: ``ranges`` (B, 1326), each hand's range when it ended (normalized), and
    ``history``, every step as (hands, acting seats, actions).
    """

    payoffs: np.ndarray
    end_round: np.ndarray
    raises: np.ndarray
    range_resets: int
    ranges: np.ndarray | None = field(default=None, repr=False)
    history: list[tuple[np.ndarray, np.ndarray, np.ndarray]] | None = field(
        default=None, repr=False
    )


def visible_board(cards: np.ndarray, rounds: np.ndarray) -> np.ndarray:
    """(n, 5) the board shown in ``rounds``, ``-1`` for the cards still to come.

    >>> visible_board(np.arange(9)[None], np.array([1])).tolist()
    [[4, 5, 6, -1, -1]]
    """
    return np.where(_BOARD_SHOWN[np.asarray(rounds, dtype=np.int64)], cards[:, 4:9], -1)


def possible_pairs(hole: np.ndarray, board: np.ndarray) -> np.ndarray:
    """(n, 1326) bool: the pairs that share no card with ``hole`` (n, 2) or ``board`` (n, 5,
    ``-1`` for no card)."""
    seen = np.concatenate([hole, np.where(board < 0, 52, board)], axis=1)
    return ~_CLASH_OR_NONE[seen].any(axis=1)


def range_policy(
    agent: Agent,
    encoding: Encoding,
    hands: np.ndarray,
    pairs: np.ndarray,
    board: np.ndarray,
    raise_nums: np.ndarray,
    legal_mask: np.ndarray,
) -> np.ndarray:
    """(R, 4) the agent's action probabilities in R hypothetical states: row r holds pair
    ``pairs[r]`` in hand ``hands[r]`` (a row of ``board``, ``raise_nums``, ``legal_mask``:
    (n, 5), (n, 4), (n, 4)), batched ``ROWS_PER_PASS`` rows to a call."""
    probs = np.empty((hands.size, NUM_ACTIONS))
    no_hole = np.full((len(board), 2), -1)
    states = RawStates(cards=np.concatenate([no_hole, board], axis=1).astype(np.int8),
                       raise_nums=raise_nums, legal_mask=legal_mask)  # fmt: skip
    for start in range(0, hands.size, ROWS_PER_PASS):
        rows = slice(start, start + ROWS_PER_PASS)
        at, held = hands[rows], pairs[rows]
        obs = encoding.encode_pairs(held, states, at)
        cards = functools.partial(_cards_of, held, board[at])  # only for agents that see them
        probs[rows] = agent_action_probs(agent, obs, legal_mask[at], cards)
    return probs


def _cards_of(pairs: np.ndarray, board: np.ndarray) -> np.ndarray:
    return pair_cards(pairs, board).astype(np.int8)


def state_after_raise(raises: np.ndarray, street: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """What the agent would face after LBR's raise on ``street`` (n,): the raise counts
    (n, 4) with one more in that round, and its legal actions (call, raise while fewer than 4,
    fold; no check).

    >>> nums, legal = state_after_raise(np.array([[1, 3, 0, 0]]), np.array([1]))
    >>> nums.tolist(), legal.astype(int).tolist()
    ([[1, 4, 0, 0]], [[1, 0, 1, 0]])
    """
    rows = np.arange(len(street))
    raise_nums = np.array(raises, dtype=np.int8)  # a copy, as the engine keeps them
    raise_nums[rows, street] += 1
    legal = np.zeros((len(street), NUM_ACTIONS), dtype=bool)
    legal[:, CALL] = legal[:, FOLD] = True
    legal[:, RAISE] = raise_nums[rows, street] < MAX_RAISES
    return raise_nums, legal


def _sample(probs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One action per row of (n, 4) probabilities; an action of probability 0 is never drawn."""
    cumulative = np.cumsum(probs, axis=1)
    u = rng.random(len(probs)) * cumulative[:, -1]
    return (cumulative > u[:, None]).argmax(axis=1)


class _LBRHands:
    """One batch of hands between LBR and the agent: the engine, the ranges, the equities."""

    def __init__(
        self,
        agent: Agent,
        deals: np.ndarray,
        lbr_seat: np.ndarray,
        rng: np.random.Generator,
        settings: LBRSettings,
    ) -> None:
        self.agent, self.settings, self.rng = agent, settings, rng
        self.encoding = agent_encoding(agent)
        self.game = LimitHoldemBatch(deals=deals)
        n = self.game.size
        rows = np.arange(n)
        self.lbr_seat = np.asarray(lbr_seat, dtype=np.int64)
        self.agent_seat = 1 - self.lbr_seat
        cards = self.game.cards.astype(np.int64)
        self.lbr_hole = np.stack([cards[rows, 2 * self.lbr_seat + k] for k in (0, 1)], axis=1)
        agent_hole = np.stack([cards[rows, 2 * self.agent_seat + k] for k in (0, 1)], axis=1)
        self.agent_pair = pair_index(agent_hole[:, 0], agent_hole[:, 1])
        self.lbr_pair = pair_index(self.lbr_hole[:, 0], self.lbr_hole[:, 1])
        possible = possible_pairs(self.lbr_hole, np.full((n, 5), -1))
        self.weights = possible / possible.sum(axis=1, keepdims=True)
        self.equity = np.zeros((n, NUM_PAIRS))
        self.equity_round = np.full(n, -1)
        self.range_resets = 0

    # --- the range -----------------------------------------------------------------------

    def live_range(self, hands: np.ndarray) -> np.ndarray:
        """(n, 1326) the normalized range of ``hands``, with the board shown ruled out."""
        board = visible_board(self.game.cards[hands].astype(np.int64), self.game.round[hands])
        possible = possible_pairs(self.lbr_hole[hands], board)
        weights = self.weights[hands] * possible
        total = weights.sum(axis=1, keepdims=True)
        empty = total[:, 0] <= 0
        if empty.any():  # see the module docstring: reset to what the cards allow
            self.range_resets += int(empty.sum())
            weights[empty] = possible[empty]
            total[empty, 0] = possible[empty].sum(axis=1)
        return weights / total

    def _policy(
        self, hands: np.ndarray, live: np.ndarray, raise_nums: np.ndarray, legal: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The agent's probabilities for every live pair of ``hands`` (``live`` (n, 1326)):
        (local hand, pair, probs (R, 4)), rows ordered by hand then pair."""
        local, pairs = np.nonzero(live)
        board = visible_board(self.game.cards[hands].astype(np.int64), self.game.round[hands])
        probs = range_policy(self.agent, self.encoding, local, pairs, board, raise_nums, legal)
        return local, pairs, probs

    # --- the agent -----------------------------------------------------------------------

    def agent_moves(self, hands: np.ndarray) -> np.ndarray:
        """The agent's actions in ``hands`` (drawn from its own probabilities for its real
        pair), with each hand's range updated by Bayes' rule."""
        weights = self.live_range(hands)
        live = weights > 0
        local_rows = np.arange(hands.size)
        live[local_rows, self.agent_pair[hands]] = True  # its real pair, even after a reset
        raise_nums, legal = self.game.raises[hands], self.game.legal_mask(hands)
        local, pairs, probs = self._policy(hands, live, raise_nums, legal)
        real = np.flatnonzero(pairs == self.agent_pair[hands][local])  # one row a hand
        actions = _sample(probs[real], self.rng)
        likelihood = np.zeros(weights.shape)
        likelihood[local, pairs] = probs[np.arange(local.size), actions[local]]
        self.weights[hands] = weights * likelihood
        return actions

    # --- LBR -----------------------------------------------------------------------------

    def lbr_moves(self, hands: np.ndarray) -> np.ndarray:
        """LBR's actions in ``hands``: check or call before ``check_until``, else the best of
        fold, check/call and raise by the utilities of the module docstring."""
        game = self.game
        legal = game.legal_mask(hands)
        actions = np.where(legal[:, CALL], CALL, CHECK)
        street = game.round[hands].astype(np.int64)
        playing = np.flatnonzero(street >= self.settings.check_until.number)
        if playing.size == 0:
            return actions
        hands, legal, street = hands[playing], legal[playing], street[playing]
        self._update_equity(hands)
        weights = self.live_range(hands)
        equity = self.equity[hands]
        wp = (weights * equity).sum(axis=1)
        pot = game.chips[hands].sum(axis=1).astype(np.float64)
        seat = self.lbr_seat[hands]
        to_call = (game.round_chips[hands, 1 - seat] - game.round_chips[hands, seat]).astype(
            np.float64
        )
        u_call = wp * pot - (1 - wp) * to_call
        u_raise = np.full(hands.size, -np.inf)
        can = np.flatnonzero(legal[:, RAISE])
        if can.size:
            u_raise[can] = self._raise_value(
                hands[can], weights[can], equity[can], pot[can], to_call[can], street[can]
            )
        chosen = np.where(legal[:, CALL], CALL, CHECK)
        chosen = np.where(u_raise > u_call, RAISE, chosen)
        chosen = np.where(np.maximum(u_call, u_raise) < 0, FOLD, chosen)
        actions[playing] = chosen
        return actions

    def _raise_value(
        self,
        hands: np.ndarray,
        weights: np.ndarray,
        equity: np.ndarray,
        pot: np.ndarray,
        to_call: np.ndarray,
        street: np.ndarray,
    ) -> np.ndarray:
        """u(raise): the agent's fold probability after the raise over the range (one batched
        call over the hypothetical states), then the equity against the pairs that stay."""
        raise_nums, legal = state_after_raise(self.game.raises[hands], street)
        local, pairs, probs = self._policy(hands, weights > 0, raise_nums, legal)
        folds = np.zeros(weights.shape)
        folds[local, pairs] = probs[:, FOLD]
        fp = (weights * folds).sum(axis=1)
        stays = weights * (1 - folds)
        kept = stays.sum(axis=1)
        # No pair stays (fp = 1): wp' is then never used; 0 keeps the division away.
        wp_after = np.where(kept > 0, (stays * equity).sum(axis=1) / np.where(kept > 0, kept, 1), 0)
        bet = RAISE_SIZE_BY_ROUND[street].astype(np.float64)
        showdown = wp_after * (pot + bet) - (1 - wp_after) * (to_call + bet)
        return fp * pot + (1 - fp) * showdown

    # --- equity ----------------------------------------------------------------------------

    def _update_equity(self, hands: np.ndarray) -> None:
        """LBR's equity against every pair, for the hands whose street changed since."""
        street = self.game.round[hands].astype(np.int64)
        stale = self.equity_round[hands] != street
        for rnd in np.unique(street[stale]):
            todo = hands[stale & (street == rnd)]
            # Boards per call: the turn's 46 a hand, the flop's 1,081, preflop's samples.
            per_call = max(1, EQUITY_BOARDS // (1, 1081, 46, 1)[rnd])
            for start in range(0, todo.size, per_call):
                chunk = todo[start : start + per_call]
                self.equity[chunk] = self._equity(chunk, int(rnd))
            self.equity_round[todo] = rnd

    def _equity(self, hands: np.ndarray, street: int) -> np.ndarray:
        """(n, 1326) LBR's share of the pot against each pair in ``hands`` on ``street``, over
        every runout of the board (preflop: over random boards). Pairs that clash with LBR's
        cards or the board get meaningless values; their weight is 0."""
        cards = self.game.cards[hands].astype(np.int64)
        shown = (0, 3, 4, 5)[street]
        board = cards[:, 4 : 4 + shown]
        known = np.concatenate([self.lbr_hole[hands], board], axis=1)
        taken = np.zeros((hands.size, 52), dtype=bool)
        taken[np.arange(hands.size)[:, None], known] = True
        unseen = np.argsort(taken, axis=1, kind="stable")[:, : 52 - known.shape[1]]
        if street == 3:
            new = np.zeros((hands.size, 1, 0), dtype=np.int64)
        elif street == 2:
            new = unseen[:, :, None]  # every river
        elif street == 1:
            new = unseen[:, _RUNOUTS]  # every turn and river
        else:
            keys = self.rng.random((hands.size, self.settings.preflop_boards, unseen.shape[1]))
            picks = np.argpartition(keys, 5, axis=2)[:, :, :5]
            new = np.take_along_axis(unseen[:, None, :], picks.reshape(hands.size, 1, -1), 2)
            new = new.reshape(hands.size, self.settings.preflop_boards, 5)
        runs = new.shape[1]
        boards = np.concatenate([np.broadcast_to(board[:, None], (len(new), runs, shown)), new], 2)
        strength = board_strengths(boards.reshape(-1, 5)).reshape(hands.size, runs, NUM_PAIRS)
        mine = np.take_along_axis(strength, self.lbr_pair[hands][:, None, None], axis=2)
        # Twice the share (2 win, 1 split, 0 loss) in int8, counted over the runouts a pair
        # leaves possible (none of its cards among the new ones).
        twice = np.add(mine > strength, mine >= strength, dtype=np.int8)
        if new.shape[2] == 0:
            return twice[:, 0] / 2.0
        possible = ~_CLASH_OR_NONE[new[:, :, 0]]
        for k in range(1, new.shape[2]):
            possible &= ~_CLASH_OR_NONE[new[:, :, k]]
        won = np.where(possible, twice, 0).sum(axis=1, dtype=np.int32)
        return won / (2.0 * np.maximum(possible.sum(axis=1, dtype=np.int32), 1))


def play_lbr(
    agent: Agent,
    deals: np.ndarray,
    lbr_seat: np.ndarray,
    rng: np.random.Generator,
    settings: LBRSettings,
    *,
    trace: bool = False,
) -> LBRBatch:
    """Play LBR against ``agent`` in every hand of ``deals`` (B, 9), LBR in seat
    ``lbr_seat`` (B,) (0 small blind, 1 big blind), all hands in lock-step.

    ``rng`` draws the agent's moves and the preflop boards. ``trace`` keeps the final ranges
    and every step (for tests).
    """
    if not hasattr(agent, "action_probs"):
        raise ConfigError(
            f"agent {agent.name!r} has no action_probs: LBR needs the probability of each "
            "of its actions"
        )
    lbr = _LBRHands(agent, deals, lbr_seat, rng, settings)
    game = lbr.game
    history: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    while game.active().size:
        hands = game.active()
        agents_turn = game.to_act[hands] == lbr.agent_seat[hands]
        mine, theirs = hands[agents_turn], hands[~agents_turn]
        moves = []
        if mine.size:
            moves.append((mine, lbr.agent_moves(mine)))
        if theirs.size:
            moves.append((theirs, lbr.lbr_moves(theirs)))
        for at, actions in moves:
            if trace:
                history.append((at.copy(), game.to_act[at].copy(), actions.copy()))
            game.step(actions, at)
    rows = np.arange(game.size)
    resets = lbr.range_resets
    ranges = lbr.live_range(rows) if trace else None  # with the whole board ruled out
    return LBRBatch(
        payoffs=game.payoffs[rows, lbr.lbr_seat].copy(),
        end_round=game.round.astype(np.int64),
        raises=game.raises.astype(np.int64),
        range_resets=resets,
        ranges=ranges,
        history=history if trace else None,
    )
