"""Hole cards for the players the logs hide: a posterior over the 1,326 pairs (docs/folds.md).

IRC logs show hole cards only at showdown, so a hand that ends in a fold hides both players'
cards. For each hidden player (a hand and a nick), Bayes' rule over the pairs ``c`` that do not
clash with the cards known in the hand (the board dealt, an opponent's shown pair):

    P(c | actions) ∝ P(c) · Π_t π_B(a_t | obs_t(c))

with a uniform prior P(c) and a behaviour model π_B: a policy over the legal actions, read in
its own :class:`~pokerirl.game.encodings.Encoding`. ``obs_t(c)`` is the decision's state with
the hole cards ``c``, built as the engine and the tables build it (:class:`RawStates` of the
pair, the board shown at that decision, its raise counts and legal actions). Every decision
is one batched forward pass of π_B over all 1,326 pairs, many decisions at a time: no Python
loop over pairs. A player who reached a showdown and lost (or won, or split) against a shown
pair also gets that result as a likelihood factor (0 or 1 per pair).

The posterior is represented in the table by ``K`` draws (systematic resampling, seeded):
equal draws merge into one row set with weight (count / K), so each hidden decision weighs 1
in all. A hand whose actions have, for every pair, likelihood below
``MIN_ACTION_PROBABILITY`` per decision (in effect 0) is not forced in: it is dropped and
counted.

π_B is a run's policy (``--behaviour RUN``) or fitted here (:func:`fit_behaviour`): behaviour
cloning on the rows whose cards were shown, then ``behaviour_rounds`` rounds of (Monte Carlo)
EM on the whole table. Showdown rows alone hold no fold, so a model fitted on them alone
cannot tell which cards fold; EM can, because the prior over the deals is known: the cards
of the players who fold are what the deals hold beyond those who go on.

>>> PAIRS.shape, PAIR_TEXT[0], PAIR_TEXT[-1]
((1326, 2), 'As 2s', 'Qc Kc')
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import torch
from torch import nn
from tqdm.auto import tqdm

from pokerirl.datasets.decisions import table_cards
from pokerirl.datasets.ingest import FoldsResult, FoldsSummary, IngestSummary, ingest_table
from pokerirl.datasets.players import Selection
from pokerirl.datasets.table import IMPUTED_SCHEMA, SCHEMA, fixed_size_list
from pokerirl.errors import InputError
from pokerirl.game.encodings import (
    Encoding,
    RawStates,
    StrengthEncoding,
    get_encoding,
)
from pokerirl.game.evaluator import hand_strength
from pokerirl.holdem import (
    ACTIONS,
    CARD_TEXT,
    FOLD,
    NUM_ACTIONS,
    NUM_CARDS,
    NUM_PAIRS,
    NUM_ROUNDS,
    PAIRS,
    encode_obs,
)
from pokerirl.irl.metrics import Metric, Part
from pokerirl.parquet import fixed_width
from pokerirl.poker.folds import ImputeConfig

PAIR_TEXT = tuple(f"{CARD_TEXT[a]} {CARD_TEXT[b]}" for a, b in PAIRS)
# One forward pass of π_B reads this many states: 49 decisions x 1,326 pairs.
CHUNK_ROWS = 1 << 16
ENCODED_CACHE_BYTES = 1 << 28  # 256 MB of encoded (decision, pair) states kept across EM rounds
# A hand is unexplained when its best pair's actions average less than this per decision.
MIN_ACTION_PROBABILITY = 1e-6
NO_SHOWDOWN, LOST, TIED, WON = -1, 0, 1, 2


# --------------------------------------------------------------------------- hidden players


@dataclass(frozen=True, kw_only=True, eq=False)
class Hidden:
    """The hidden players of a table (P of them) and their decisions (D, one per template row).

    Per player: ``hand_id``, ``player``, ``known`` (P, 52) the cards that cannot be theirs,
    ``outcome`` at a showdown against a shown pair (``LOST``, ``TIED``, ``WON``; else
    ``NO_SHOWDOWN``), ``rival`` (P, 2) that pair and ``final_board`` (P, 5). Per decision:
    ``owner`` (its player), ``board`` (D, 5) as shown then, ``raise_nums``, ``legal_mask``
    and ``action``.
    """

    hand_id: np.ndarray
    player: np.ndarray
    known: np.ndarray
    outcome: np.ndarray
    rival: np.ndarray
    final_board: np.ndarray
    owner: np.ndarray
    board: np.ndarray
    raise_nums: np.ndarray
    legal_mask: np.ndarray
    action: np.ndarray

    @property
    def players(self) -> int:
        return len(self.hand_id)

    @property
    def decisions(self) -> np.ndarray:
        """(P,) decisions per player."""
        return np.bincount(self.owner, minlength=self.players)

    def select(self, players: np.ndarray) -> Hidden:
        """The hidden players ``players`` (indices, in that order) and their decisions."""
        players = np.asarray(players, dtype=np.int64)
        new = np.full(self.players, -1, dtype=np.int64)
        new[players] = np.arange(len(players))
        rows = np.flatnonzero(new[self.owner] >= 0)
        per_player = {name: getattr(self, name)[players] for name in (
            "hand_id", "player", "known", "outcome", "rival", "final_board")}  # fmt: skip
        per_decision = {name: getattr(self, name)[rows] for name in (
            "board", "raise_nums", "legal_mask", "action")}  # fmt: skip
        return Hidden(**per_player, **per_decision, owner=new[self.owner[rows]])


@dataclass(frozen=True, kw_only=True, eq=False)
class SplitTable:
    """A table's observed rows, the template rows of its hidden players (one per hidden
    decision) and those players; ``*_position``: the rows' places in the table."""

    observed: pa.Table
    templates: pa.Table
    hidden: Hidden
    observed_position: np.ndarray
    template_position: np.ndarray


def split_table(table: pa.Table, source: str = "table") -> SplitTable:
    """Split a table into observed rows and hidden players' decisions.

    A table of ingest's folds step holds the hidden decisions with an empty ``hole_cards``;
    an imputed table (``imputed`` column) holds them as draws, whose first draw gives them.
    """
    names = table.column_names
    base = table.select(SCHEMA.names)
    if "imputed" in names and "imputation" in names:
        imputed = table.column("imputed").to_numpy(zero_copy_only=False).astype(bool)
        draw = table.column("imputation").to_numpy()
        template_rows = imputed & (draw == 1)
        observed_rows = ~imputed
    else:
        template_rows = np.asarray(pc.equal(table.column("hole_cards"), "").to_numpy(
            zero_copy_only=False), dtype=bool)  # fmt: skip
        observed_rows = ~template_rows
    observed_position = np.flatnonzero(observed_rows)
    template_position = np.flatnonzero(template_rows)
    observed = base.take(pa.array(observed_position))
    templates = base.take(pa.array(template_position))
    return SplitTable(
        observed=observed,
        templates=templates,
        hidden=_hidden_players(observed, templates, source),
        observed_position=observed_position,
        template_position=template_position,
    )


def _codes(
    column: pa.ChunkedArray, dictionary: pa.Array | None = None
) -> tuple[np.ndarray, pa.Array]:
    """Integer codes of a string column (within ``dictionary`` when given)."""
    if dictionary is None:
        encoded = pc.dictionary_encode(column.combine_chunks())
        return encoded.indices.to_numpy(zero_copy_only=False).astype(np.int64), encoded.dictionary
    found = pc.fill_null(pc.index_in(column, value_set=dictionary), -1)
    return found.to_numpy(zero_copy_only=False).astype(np.int64), dictionary


def _hidden_players(observed: pa.Table, templates: pa.Table, source: str) -> Hidden:
    if templates.num_rows == 0:
        return _no_hidden_players()
    hand_t, hands = _codes(templates.column("hand_id"))
    player_t, players = _codes(templates.column("player"))
    key = hand_t * max(len(players), 1) + player_t
    _, first, owner = np.unique(key, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")  # players in order of first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    owner = rank[owner.reshape(-1)]
    first = first[order]
    num_players = len(first)

    board_t = _cards(templates, source)[:, 2:]
    hand_of_player = hand_t[first]
    final_board = np.full((len(hands), 5), -1, dtype=np.int64)
    np.maximum.at(final_board, hand_t, board_t)  # boards are prefixes of the final one
    rival = np.full((len(hands), 2), -1, dtype=np.int64)
    rival_won = np.zeros(len(hands), dtype=np.int64)
    folded = np.zeros(len(hands), dtype=bool)
    np.logical_or.at(folded, hand_t, templates.column("action_id").to_numpy() == FOLD)
    if observed.num_rows:
        hand_o, _ = _codes(observed.column("hand_id"), hands)
        mine = hand_o >= 0  # observed rows of hands with a hidden player
        if mine.any():
            rows = observed.take(pa.array(np.flatnonzero(mine)))
            hand_o = hand_o[mine]
            cards_o = _cards(rows, source)
            np.maximum.at(final_board, hand_o, cards_o[:, 2:])
            np.maximum.at(rival, hand_o, cards_o[:, :2])
            np.maximum.at(rival_won, hand_o, rows.column("chips_won").to_numpy().astype(np.int64))
            np.logical_or.at(folded, hand_o, rows.column("action_id").to_numpy() == FOLD)
    chips_won = templates.column("chips_won").to_numpy().astype(np.int64)[first]
    shown = rival[hand_of_player, 0] >= 0
    showdown = shown & ~folded[hand_of_player]
    outcome = np.full(num_players, NO_SHOWDOWN, dtype=np.int8)
    theirs = rival_won[hand_of_player]
    outcome[showdown & (chips_won == 0)] = LOST
    outcome[showdown & (chips_won > 0) & (theirs > 0)] = TIED
    outcome[showdown & (chips_won > 0) & (theirs == 0)] = WON

    known = np.zeros((num_players, NUM_CARDS), dtype=bool)
    seen = np.concatenate([final_board[hand_of_player], rival[hand_of_player]], axis=1)
    rows_p, cols = np.nonzero(seen >= 0)
    known[rows_p, seen[rows_p, cols]] = True
    hand_names = np.asarray(hands.to_numpy(zero_copy_only=False), dtype=object)
    player_names = np.asarray(players.to_numpy(zero_copy_only=False), dtype=object)
    return Hidden(
        hand_id=hand_names[hand_of_player],
        player=player_names[player_t[first]],
        known=known,
        outcome=outcome,
        rival=rival[hand_of_player],
        final_board=final_board[hand_of_player],
        owner=owner.astype(np.int64),
        board=board_t,
        raise_nums=fixed_width(templates, "raise_nums", NUM_ROUNDS, source).astype(np.int64),
        legal_mask=fixed_width(templates, "legal_mask", NUM_ACTIONS, source).astype(bool),
        action=templates.column("action_id").to_numpy().astype(np.int64),
    )


def _no_hidden_players() -> Hidden:
    none = np.zeros(0, dtype=np.int64)
    return Hidden(hand_id=np.array([], dtype=object), player=np.array([], dtype=object),
                  known=np.zeros((0, NUM_CARDS), bool), outcome=none.astype(np.int8),
                  rival=none.reshape(0, 2), final_board=none.reshape(0, 5), owner=none,
                  board=none.reshape(0, 5), raise_nums=none.reshape(0, NUM_ROUNDS),
                  legal_mask=np.zeros((0, NUM_ACTIONS), bool), action=none)  # fmt: skip


def _cards(table: pa.Table, source: str) -> np.ndarray:
    """(N, 7) int64 hole cards (``-1`` when concealed) and board of a table's rows."""
    return table_cards(table, source).astype(np.int64)


# --------------------------------------------------------------------------- the behaviour


@dataclass(frozen=True, eq=False)
class Behaviour:
    """π_B: a discrete policy ``policy(obs, legal_mask) -> log π`` read in ``encoding``."""

    policy: nn.Module
    encoding: Encoding
    source: str  # "bc" or a run folder

    @classmethod
    def from_run(cls, run: str | os.PathLike[str]) -> Behaviour:
        """The policy of an IRL run (``pokerirl train``), in the run's own encoding."""
        from pokerirl.irl.run import load_policy, load_run_config
        from pokerirl.poker.rewards import run_encoding

        record = load_run_config(run)
        encoding = run_encoding(Path(run), record)
        return cls(load_policy(run).eval(), encoding, str(run))


class _GivenEquity(StrengthEncoding):
    """The strength encoding with its equity column already computed, by the same
    encoding's :meth:`~StrengthEncoding.equity`, for exactly the states it encodes next: the
    same features, without recomputing one equity per decision and round."""

    def __init__(self, base: StrengthEncoding, values: np.ndarray) -> None:
        super().__init__(version=base.version, equity_samples=base.equity_samples)
        self.values = values

    def equity(self, cards: np.ndarray) -> np.ndarray:
        if len(cards) != len(self.values):
            raise ValueError("the given equities are for other states")
        return self.values


def pair_cards(board: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n·1326, 7) cards of every pair with each of ``board`` (n, 5) and (n, 1326) clash.

    A pair that shares a card with the board is not a state: it is replaced by the board's
    first pair that does not (so every row is a valid state), and flagged in ``clash``.
    """
    board = np.asarray(board, dtype=np.int64)
    clash = ((PAIRS[None, :, :, None] == board[:, None, None, :]) & (board[:, None, None, :]
             >= 0)).any(axis=(2, 3))  # fmt: skip
    filler = np.argmax(~clash, axis=1)
    pair = np.where(clash, filler[:, None], np.arange(NUM_PAIRS)[None, :])
    cards = np.empty((len(board), NUM_PAIRS, 7), dtype=np.int64)
    cards[:, :, :2] = PAIRS[pair]
    cards[:, :, 2:] = board[:, None, :]
    return cards.reshape(-1, 7), clash


class Expansion:
    """The states of every hidden decision with each of the 1,326 pairs, encoded in chunks.

    For an encoding with an equity column (``strength``) the equities are computed once per
    distinct board (a hand's street) and kept, so EM's rounds and both players of a hand
    share them.
    """

    def __init__(self, hidden: Hidden, encoding: Encoding) -> None:
        self.hidden, self.encoding = hidden, encoding
        self.per_chunk = max(1, CHUNK_ROWS // NUM_PAIRS)
        self._board_ids: np.ndarray | None = None
        self._equity: np.ndarray | None = None
        # EM's rounds encode the same states again: the first chunks are kept, up to
        # ENCODED_CACHE_BYTES (the same arrays, so the same likelihoods).
        self._encoded: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._encoded_bytes = 0

    def chunks(self) -> range:
        return range(0, len(self.hidden.owner), self.per_chunk)

    def encode(self, start: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(index of the chunk's decisions, (n·1326, width) features, (n, 1326) clash)."""
        found = self._encoded.get(start)
        if found is None:
            found = self._encode(start)
            size = sum(part.nbytes for part in found)
            if self._encoded_bytes + size <= ENCODED_CACHE_BYTES:
                self._encoded[start] = found
                self._encoded_bytes += size
        return found

    def _encode(self, start: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        hidden = self.hidden
        index = np.arange(start, min(start + self.per_chunk, len(hidden.owner)))
        cards, clash = pair_cards(hidden.board[index])
        states = RawStates(
            cards=cards,
            raise_nums=np.repeat(hidden.raise_nums[index], NUM_PAIRS, axis=0),
            legal_mask=np.repeat(hidden.legal_mask[index], NUM_PAIRS, axis=0),
        )
        encoding = self.encoding
        if isinstance(encoding, StrengthEncoding):
            encoding = _GivenEquity(encoding, self.equity(index))
        return index, encoding.encode(states), clash

    def equity(self, index: np.ndarray) -> np.ndarray:
        """(n·1326,) the equity of each (decision, pair) state of ``index``."""
        assert isinstance(self.encoding, StrengthEncoding)
        if self._equity is None:
            boards, self._board_ids = np.unique(self.hidden.board, axis=0, return_inverse=True)
            self._board_ids = self._board_ids.reshape(-1)
            found = np.empty((len(boards), NUM_PAIRS), dtype=np.float32)
            step = max(1, (1 << 14) // NUM_PAIRS)
            for first in range(0, len(boards), step):
                cards, _ = pair_cards(boards[first : first + step])
                found[first : first + step] = self.encoding.equity(cards).reshape(-1, NUM_PAIRS)
            self._equity = found
        assert self._board_ids is not None
        return self._equity[self._board_ids[index]].reshape(-1).astype(np.float64)


@torch.no_grad()
def log_likelihoods(
    hidden: Hidden,
    behaviour: Behaviour,
    *,
    expansion: Expansion | None = None,
    progress: bool = False,
) -> np.ndarray:
    """(P, 1326) float64: Σ_t log π_B(a_t | obs_t(c)) of each hidden player for each pair
    ``c``; ``-inf`` where a pair clashes with the board of one of its decisions.

    One batched forward pass per chunk of decisions, each over all 1,326 pairs."""
    expansion = expansion or Expansion(hidden, behaviour.encoding)
    if expansion.encoding is not behaviour.encoding:
        raise ValueError("the expansion is of another encoding than the behaviour's")
    found = np.zeros((hidden.players, NUM_PAIRS), dtype=np.float64)
    policy = behaviour.policy.eval()
    chunks = expansion.chunks()
    for start in tqdm(chunks, desc="posterior", unit=" chunks", disable=not progress):
        index, obs, clash = expansion.encode(start)
        mask = torch.from_numpy(np.repeat(hidden.legal_mask[index], NUM_PAIRS, axis=0))
        log_pi = policy(torch.from_numpy(obs).float(), mask)
        action = torch.from_numpy(np.repeat(hidden.action[index], NUM_PAIRS))
        taken = log_pi.gather(1, action[:, None]).view(len(index), NUM_PAIRS).double().numpy()
        taken = np.where(clash, -np.inf, taken)
        np.add.at(found, hidden.owner[index], taken)
    return found


# --------------------------------------------------------------------------- the posterior


@dataclass(frozen=True, kw_only=True, eq=False)
class Posterior:
    """Per hidden player: ``log_probs`` (P, 1326), ``-inf`` off the support; ``explained``
    (whether some pair gives its actions a likelihood above the floor); ``entropy_bits``;
    ``support`` (pairs not clashing with the known cards: the uniform prior's)."""

    log_probs: np.ndarray
    explained: np.ndarray
    entropy_bits: np.ndarray
    support: np.ndarray


def log_prior(hidden: Hidden) -> np.ndarray:
    """(P, 1326): log of the uniform prior over the pairs that do not clash with the known
    cards, and the showdown's result against a shown pair (0 or 1 per pair)."""
    clash = hidden.known[:, PAIRS].any(axis=2)  # (P, 1326)
    found = np.where(clash, -np.inf, 0.0)
    at_showdown = np.flatnonzero(hidden.outcome != NO_SHOWDOWN)
    if at_showdown.size:
        board = hidden.final_board[at_showdown]
        cards, bad = pair_cards(board)
        mine = hand_strength(cards).reshape(-1, NUM_PAIRS)
        theirs = hand_strength(np.concatenate([hidden.rival[at_showdown], board], axis=1))
        order = np.sign(mine - theirs[:, None])  # -1 lost, 0 tie, 1 won
        fits = (order + 1) == hidden.outcome[at_showdown][:, None]
        found[at_showdown] = np.where(fits & ~bad, found[at_showdown], -np.inf)
    support = np.isfinite(found).sum(axis=1)
    return found - np.log(np.maximum(support, 1))[:, None]


def posterior(hidden: Hidden, log_likelihood: np.ndarray) -> Posterior:
    """Bayes' rule: the log prior plus the log likelihood, normalized per player."""
    prior = log_prior(hidden)
    joint = prior + log_likelihood
    best = joint.max(axis=1) if hidden.players else np.zeros(0)
    decisions = hidden.decisions
    floor = decisions * math.log(MIN_ACTION_PROBABILITY) - np.log(NUM_PAIRS)
    explained = np.isfinite(best) & (best >= floor)
    shift = np.where(np.isfinite(best), best, 0.0)[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        weights = np.exp(joint - shift)
        total = weights.sum(axis=1, keepdims=True)
        log_probs = joint - shift - np.log(total)
        probs = weights / total
        entropy = -np.where(probs > 0, probs * np.log2(np.where(probs > 0, probs, 1.0)), 0.0)
    return Posterior(
        log_probs=np.where(explained[:, None], log_probs, -np.inf),
        explained=explained,
        entropy_bits=np.where(explained, entropy.sum(axis=1), np.nan),
        support=np.isfinite(prior).sum(axis=1),
    )


@dataclass(frozen=True, kw_only=True, eq=False)
class Draws:
    """Distinct posterior draws: per draw its ``owner`` (player), ``pair``, ``weight`` (the
    share of the K draws that fell on it) and ``imputation`` (1.. within its player)."""

    owner: np.ndarray
    pair: np.ndarray
    weight: np.ndarray
    imputation: np.ndarray


def draw(post: Posterior, imputations: int, rng: np.random.Generator) -> Draws:
    """K draws per explained player by systematic resampling (one uniform per player, so the
    draws spread over the posterior), equal ones merged."""
    players = np.flatnonzero(post.explained)
    k = imputations
    u = (rng.random(len(players))[:, None] + np.arange(k)[None, :]) / k  # (n, K), increasing
    pair = np.empty((len(players), k), dtype=np.int64)
    block = 4096  # players per search: small offsets keep the uniforms' precision
    for first in range(0, len(players), block):
        rows = players[first : first + block]
        cdf = np.cumsum(np.exp(post.log_probs[rows]), axis=1)
        cdf /= cdf[:, -1:]
        offsets = 2.0 * np.arange(len(rows))[:, None]
        flat = (cdf + offsets).reshape(-1)  # rows apart, so one search covers them all
        # side="right": the first pair whose cdf passes u, never one of zero probability
        where = np.searchsorted(flat, (u[first : first + block] + offsets).reshape(-1),
                                side="right").reshape(len(rows), k)  # fmt: skip
        within = where - NUM_PAIRS * np.arange(len(rows))[:, None]
        pair[first : first + block] = np.minimum(within, NUM_PAIRS - 1)
    new = np.ones_like(pair, dtype=bool)
    new[:, 1:] = pair[:, 1:] != pair[:, :-1]  # sorted per row: equal draws are neighbours
    run_id = np.cumsum(new.reshape(-1)) - 1
    counts = np.bincount(run_id)
    rows, cols = np.nonzero(new)
    return Draws(
        owner=players[rows],
        pair=pair[rows, cols],
        weight=(counts / k).astype(np.float32),
        imputation=(np.cumsum(new, axis=1)[rows, cols]).astype(np.int64),
    )


# --------------------------------------------------------------------------- the table


def imputed_rows(split: SplitTable, post: Posterior, draws: Draws) -> tuple[pa.Table, np.ndarray]:
    """The template rows of each draw's player with its pair (IMPUTED_SCHEMA), and each
    row's place among the table's rows (its template's)."""
    hidden = split.hidden
    order = np.argsort(hidden.owner, kind="stable")  # rows of each player, in decision order
    count = np.bincount(hidden.owner, minlength=hidden.players)
    start = np.cumsum(count) - count
    lengths = count[draws.owner]
    which = np.repeat(np.arange(len(draws.owner)), lengths)
    offset = np.arange(lengths.sum()) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    rows = order[start[draws.owner][which] + offset]
    table = split.templates.take(pa.array(rows))
    pair = draws.pair[which]
    cards = np.concatenate([PAIRS[pair], hidden.board[rows]], axis=1)
    obs = encode_obs(cards, hidden.raise_nums[rows])
    hole = pa.array(PAIR_TEXT, type=pa.string()).take(pa.array(pair))
    table = table.set_column(SCHEMA.get_field_index("hole_cards"), "hole_cards", hole)
    table = table.set_column(SCHEMA.get_field_index("obs"), "obs",
                             fixed_size_list(obs, pa.uint8()))  # fmt: skip
    entropy = post.entropy_bits[draws.owner][which].astype(np.float32)
    columns = {
        "imputed": pa.array(np.ones(len(rows), dtype=bool)),
        "weight": pa.array(draws.weight[which]),
        "imputation": pa.array(draws.imputation[which].astype(np.int16)),
        "posterior_entropy": pa.array(entropy),
    }
    for name, column in columns.items():
        table = table.append_column(name, column)
    return table, split.template_position[rows]


def observed_rows(observed: pa.Table) -> pa.Table:
    """Observed rows with the imputation columns: not imputed, weight 1, draw 0, entropy 0."""
    n = observed.num_rows
    columns = {
        "imputed": pa.array(np.zeros(n, dtype=bool)),
        "weight": pa.array(np.ones(n, dtype=np.float32)),
        "imputation": pa.array(np.zeros(n, dtype=np.int16)),
        "posterior_entropy": pa.array(np.zeros(n, dtype=np.float32)),
    }
    for name, column in columns.items():
        observed = observed.append_column(name, column)
    return observed


def assemble(split: SplitTable, post: Posterior, draws: Draws) -> pa.Table:
    """The table: observed rows and imputed ones, each hand's rows together (the observed
    ones, then draw 1, 2, ...), in the order of the hands' first rows; hidden players who
    were dropped, and hands with one, left out."""
    observed = observed_rows(split.observed)  # a mixed hand keeps its shown player's rows
    imputed, imputed_position = imputed_rows(split, post, draws)
    table = pa.concat_tables([observed, imputed]).cast(IMPUTED_SCHEMA)
    position = np.concatenate([split.observed_position, imputed_position])
    draw_index = table.column("imputation").to_numpy().astype(np.int64)
    hand, _ = _codes(table.column("hand_id"))
    first = np.full(hand.max() + 1 if len(hand) else 0, np.iinfo(np.int64).max)
    np.minimum.at(first, hand, position)
    order = np.lexsort((position, draw_index, first[hand]))
    return table.take(pa.array(order))


def hand_fates(split: SplitTable, post: Posterior) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per hidden player, whether it is imputed (its hand's hidden players are all explained);
    and the imputed and dropped hands' ids. A hand with an unexplained hidden player is
    dropped whole unless it has observed rows (then it stays as it was: those rows only)."""
    hidden = split.hidden
    hands, hand_of = np.unique(hidden.hand_id.astype(str), return_inverse=True)
    hand_of = hand_of.reshape(-1)
    bad = np.zeros(len(hands), dtype=bool)
    np.logical_or.at(bad, hand_of, ~post.explained)
    observed_hands = set(split.observed.column("hand_id").to_pylist())
    has_observed = np.array([h in observed_hands for h in hands], dtype=bool)
    return ~bad[hand_of], hands[~bad], hands[bad & ~has_observed]


# --------------------------------------------------------------------------- fitting π_B


def fit_bc(table: pa.Table, encoding: Encoding, *, epochs: int, seed: int,
           progress: bool = False) -> tuple[nn.Module, dict[str, Any]]:  # fmt: skip
    """Behaviour cloning (the IRL policy net, α = 1, no adversary) on ``table``'s rows,
    weighted; the policy and its final validation metrics (a seeded share of the hands)."""
    from pokerirl.irl.adversarial import train
    from pokerirl.irl.config import AIRLConfig
    from pokerirl.poker.data import transitions_from_arrow

    data = transitions_from_arrow(table, source="the table being imputed", encoding=encoding)
    config = AIRLConfig.for_algo("hairl", epochs=epochs, alpha=1.0, seed=seed)
    train_data, val_data, _ = data.split(val_fraction=config.val_fraction, seed=seed)
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        result = train(train_data, val_data, config=config, adversarial=False, progress=progress)
    return result.policy.eval(), dict(result.metrics[-1])


def fit_behaviour(
    split: SplitTable,
    config: ImputeConfig,
    *,
    expansion: Expansion | None = None,
    progress: bool = False,
    on_round: Callable[[int, Behaviour], None] | None = None,
) -> tuple[Behaviour, list[dict[str, Any]]]:
    """π_B by behaviour cloning on the observed rows, then ``behaviour_rounds`` rounds of
    EM: impute with the last π_B, clone again on the observed and imputed rows (weighted).
    Returns π_B and one record per round (``on_round(r, π_B)`` sees each model)."""
    encoding = get_encoding(config.behaviour_encoding)
    expansion = expansion or Expansion(split.hidden, encoding)
    if split.observed.num_rows == 0:
        raise InputError("no hand with its cards shown: nothing to fit the behaviour model on")
    rounds: list[dict[str, Any]] = []
    policy, metrics = fit_bc(split.observed, encoding, epochs=config.behaviour_epochs,
                             seed=config.seed, progress=progress)  # fmt: skip
    rounds.append(_round_record(0, split.observed.num_rows, metrics, None))
    behaviour = Behaviour(policy, encoding, "bc")
    for r in range(1, config.behaviour_rounds + 1):
        if on_round is not None:
            on_round(r - 1, behaviour)
        post = posterior(split.hidden, log_likelihoods(split.hidden, behaviour,
                                                       expansion=expansion, progress=progress))
        post = dataclasses.replace(post, explained=hand_fates(split, post)[0])
        draws = draw(post, config.imputations, np.random.default_rng([config.seed, r]))
        table = assemble(split, post, draws)
        policy, metrics = fit_bc(table, encoding, epochs=config.behaviour_epochs,
                                 seed=config.seed, progress=progress)  # fmt: skip
        rounds.append(_round_record(r, table.num_rows, metrics, post))
        behaviour = Behaviour(policy, encoding, "bc")
    if on_round is not None:
        on_round(config.behaviour_rounds, behaviour)
    return behaviour, rounds


def _round_record(r: int, rows: int, metrics: dict[str, Any],
                  post: Posterior | None) -> dict[str, Any]:  # fmt: skip
    alignment = Metric.VAL_ALIGNMENT.of(metrics, None)
    found: dict[str, Any] = {"round": r, "rows": rows, "bc_val_alignment": alignment}
    for part in Part:
        if Metric.VAL_ALIGNMENT.on(part) in metrics:
            found[f"bc_val_alignment_{part}"] = Metric.VAL_ALIGNMENT.on(part).of(metrics)
    if post is not None:  # the posterior this round's rows were drawn from
        found["mean_entropy_bits"] = float(np.nanmean(post.entropy_bits)) if len(
            post.entropy_bits) else None  # fmt: skip
    return found


# --------------------------------------------------------------------------- the whole step


@dataclass(frozen=True, kw_only=True, eq=False)
class Imputation:
    """One imputation of a table: what :func:`impute` made and why."""

    table: pa.Table
    split: SplitTable
    behaviour: Behaviour
    posterior: Posterior
    draws: Draws
    summary: FoldsSummary
    dropped_decisions: int

    def result(self) -> FoldsResult:
        return FoldsResult(table=self.table, summary=self.summary,
                           dropped_decisions=self.dropped_decisions)  # fmt: skip


def impute(
    table: pa.Table,
    config: ImputeConfig,
    *,
    behaviour: Behaviour | None = None,
    progress: bool = False,
    source: str = "table",
) -> Imputation:
    """Impute the hidden players of ``table`` (ingest's rows with concealed ones, or an
    imputed table to impute again): π_B is ``behaviour``, else ``config.behaviour`` (a run),
    else fitted on the table (:func:`fit_behaviour`)."""
    split = split_table(table, source)
    rounds: list[dict[str, Any]] = []
    if behaviour is None and config.behaviour is not None:
        behaviour = Behaviour.from_run(config.behaviour)
    expansion = None
    if behaviour is None:
        expansion = Expansion(split.hidden, get_encoding(config.behaviour_encoding))
        behaviour, rounds = fit_behaviour(split, config, expansion=expansion, progress=progress)
    loglik = log_likelihoods(split.hidden, behaviour, expansion=expansion, progress=progress)
    post = posterior(split.hidden, loglik)
    imputed_players, imputed_hands, dropped_hands = hand_fates(split, post)
    post = dataclasses.replace(post, explained=imputed_players)
    draws = draw(post, config.imputations, np.random.default_rng(config.seed))
    result = assemble(split, post, draws)
    hidden = split.hidden
    decisions = hidden.decisions
    entropy = post.entropy_bits[imputed_players]
    hand_has_observed = np.isin(hidden.hand_id.astype(str),
                                np.asarray(split.observed.column("hand_id").to_pylist(),
                                           dtype=str))  # fmt: skip
    dropped_decisions = int(decisions[~imputed_players & hand_has_observed].sum())
    taken = hidden.action[imputed_players[hidden.owner]]
    summary = FoldsSummary(
        behaviour=behaviour.source,
        behaviour_encoding=behaviour.encoding.spec,
        imputations=config.imputations,
        seed=config.seed,
        hidden_players=hidden.players,
        imputed_players=int(imputed_players.sum()),
        dropped_players=int((~imputed_players).sum()),
        imputed_hands=len(imputed_hands),
        dropped_hands=len(dropped_hands),
        imputed_decisions=int(decisions[imputed_players].sum()),
        imputed_rows=int(pc.sum(result.column("imputed").cast(pa.int64())).as_py() or 0),
        imputed_decisions_per_action={
            name: int((taken == a).sum()) for a, name in enumerate(ACTIONS)
        },
        entropy_bits=_quantiles(entropy),
        uniform_bits=float(np.log2(post.support[imputed_players]).mean())
        if imputed_players.any() else 0.0,
        rounds=tuple(rounds),
    )  # fmt: skip
    return Imputation(table=result, split=split, behaviour=behaviour, posterior=post,
                      draws=draws, summary=summary,
                      dropped_decisions=dropped_decisions)  # fmt: skip


def _quantiles(values: np.ndarray) -> dict[str, float]:
    if values.size == 0:
        return {"mean": 0.0, "p10": 0.0, "p50": 0.0, "p90": 0.0}
    p10, p50, p90 = np.percentile(values, [10, 50, 90])
    return {"mean": float(values.mean()), "p10": float(p10), "p50": float(p50),
            "p90": float(p90)}  # fmt: skip


def folds_step(config: ImputeConfig) -> Callable[..., FoldsResult]:
    """The :class:`~pokerirl.datasets.ingest.FoldsStep` of ``ingest --folds impute``."""

    def step(table: pa.Table, *, progress: bool) -> FoldsResult:
        return impute(table, config, progress=progress).result()

    return step


def ingest_imputed(
    sources: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    config: ImputeConfig,
    *,
    strict: bool = False,
    progress: bool = False,
    recorded_as: str | os.PathLike[str] | None = None,
    selection: Selection | None = None,
) -> IngestSummary:
    """``pokerirl ingest --folds impute``: the table with the fold hands' hidden cards
    imputed, and its summary (``recorded_as``, ``selection``: as :func:`ingest_table`'s; the
    selection applies first, so the behaviour model sees the expert's rows alone)."""

    if config.behaviour is not None:
        Behaviour.from_run(config.behaviour)  # a bad run fails before the sources are read
    return ingest_table(sources, out, strict=strict, progress=progress, folds=folds_step(config),
                        recorded_as=recorded_as, selection=selection)
