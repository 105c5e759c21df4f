"""Local best response (pokerirl/tournaments/lbr.py, equity.py, exploit.py).

The checks the issue asks for: LBR wins exactly 750 mbb/h against the fold agent; against
always-call it matches the exact best response, computed here by another route (the game's
own evaluator and preflop table, no LBR code); its range is Bayes' rule, checked against a
brute force that replays each hand once per possible pair through the engine. Beside them:
the fast evaluator ranks as ``hand_strength``, the range's observations are the engine's own,
and the same settings give the same bytes on any backend.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from pokerirl.agents.dqn import GreedyQAgent, QNetwork
from pokerirl.errors import ConfigError
from pokerirl.execution import Backend
from pokerirl.game.bots import agent_action_probs, make_agent
from pokerirl.game.deals import deal_cards
from pokerirl.game.encodings import get_encoding
from pokerirl.game.engine import LimitHoldemBatch
from pokerirl.game.evaluator import hand_strength
from pokerirl.game.match import agent_encoding, observe, turn_cards
from pokerirl.game.preflop import preflop_equity
from pokerirl.holdem import NUM_CARDS, RAISE
from pokerirl.tournaments.equity import (
    CLASH,
    PAIRS,
    board_strengths,
    hole_strengths,
    pair_index,
    showdown_shares,
    win_share,
)
from pokerirl.tournaments.exploit import (
    ExploitConfig,
    LBRRun,
    lbr_of,
    load_lbr_report,
    run_lbr,
    run_lbr_many,
)
from pokerirl.tournaments.lbr import (
    LBRSettings,
    _LBRHands,
    play_lbr,
    range_policy,
    state_after_raise,
    visible_board,
)


def _duplicate(seed: int, hands: int) -> tuple[np.ndarray, np.ndarray]:
    return np.repeat(deal_cards(seed=seed, start=0, count=hands // 2), 2, 0), np.arange(hands) % 2


def _q_agent(encoding: str = "rlcard", epsilon: float = 0.0, seed: int = 0) -> GreedyQAgent:
    torch.manual_seed(seed)
    network = QNetwork(hidden=(16,), obs_size=get_encoding(encoding).width).eval()
    return GreedyQAgent(name=f"q-{encoding}", network=network, encoding=encoding, epsilon=epsilon)


# --- the evaluator ---------------------------------------------------------------------------


def _boards(rng: np.random.Generator, count: int, flushy: bool) -> np.ndarray:
    if flushy:  # three to five cards of one suit: the flush paths
        suited = rng.permutation(13)[: rng.integers(3, 6)]
        cards = list(suited + 13 * rng.integers(4))
        rest = [c for c in rng.permutation(NUM_CARDS) if c not in cards]
        return np.array([(cards + rest)[:5] for _ in range(1)] * count)[:count]
    return np.argsort(rng.random((count, NUM_CARDS)), axis=1)[:, :5]


@pytest.mark.parametrize("flushy", [False, True])
def test_board_strengths_rank_every_pair_like_hand_strength(flushy: bool) -> None:
    rng = np.random.default_rng(7 + flushy)
    boards = np.vstack([_boards(rng, 1, flushy) for _ in range(40)])
    found = board_strengths(boards)
    for board, row in zip(boards, found, strict=True):
        pairs = PAIRS[~CLASH[board].any(axis=0)]
        seven = np.concatenate([pairs, np.repeat(board[None], len(pairs), 0)], axis=1)
        assert (row[~CLASH[board].any(axis=0)] == hand_strength(seven)).all()


def test_hole_strengths_and_showdown_shares_match_hand_strength() -> None:
    rng = np.random.default_rng(3)
    cards = np.argsort(rng.random((20_000, NUM_CARDS)), axis=1)[:, :9]
    cards[:5000, 4:9] = np.array([0, 1, 2, 3, 9])  # flush and straight flush boards
    cards[:5000, :4] = np.argsort(rng.random((5000, 40)), axis=1)[:, :4] + 12
    mine = hand_strength(np.concatenate([cards[:, :2], cards[:, 4:]], axis=1))
    theirs = hand_strength(cards[:, 2:])
    assert (hole_strengths(cards[:, 4:], cards[:, :2]) == mine).all()
    shares = showdown_shares(cards[:, :4].reshape(-1, 2, 2), cards[:, None, 4:])[:, 0]
    assert (shares == win_share(mine, theirs)).all()


# --- the range -------------------------------------------------------------------------------


class _Recorder:
    """An agent that records what action_probs was shown and answers uniformly."""

    name = "recorder"

    def __init__(self, encoding: str) -> None:
        self.encoding, self.seen = encoding, []

    def act(self, obs, legal_mask, rng):
        raise AssertionError

    def action_probs(self, obs: np.ndarray, legal_mask: np.ndarray) -> np.ndarray:
        self.seen.append(obs.copy())
        return legal_mask / legal_mask.sum(axis=1, keepdims=True)


@pytest.mark.parametrize("encoding", ["rlcard", "strength"])
def test_the_range_is_observed_exactly_as_the_engine_observes(encoding: str) -> None:
    game = LimitHoldemBatch(deals=deal_cards(seed=4, start=0, count=300))
    rng, steps = np.random.default_rng(0), 0
    random = make_agent("random")
    while game.active().size:
        hands = game.active()
        cards = turn_cards(game, hands)  # the actor's hole cards then the board
        pairs = pair_index(cards[:, 0], cards[:, 1])
        recorder = _Recorder(encoding)
        board = visible_board(game.cards[hands].astype(np.int64), game.round[hands])
        range_policy(recorder, get_encoding(encoding), np.arange(hands.size), pairs, board,
                     game.raises[hands], game.legal_mask(hands))  # fmt: skip
        expected = observe(game, hands, get_encoding(encoding))
        assert np.array_equal(np.concatenate(recorder.seen), expected)
        game.step(random.act(game.observe(hands), game.legal_mask(hands), rng), hands)
        steps += 1
    assert steps >= 6  # every street was seen


def _clone(game: LimitHoldemBatch) -> LimitHoldemBatch:
    """A copy to step apart (deepcopy would cut the engine's flat views from its arrays)."""
    twin = LimitHoldemBatch(deals=game.cards)
    for name in ("round", "raises", "chips", "round_chips", "to_act", "done", "folded",
                 "payoffs", "_unraised"):  # fmt: skip
        getattr(twin, name)[...] = getattr(game, name)
    twin._active = game.active().copy()
    return twin


def test_the_state_after_a_raise_is_the_engines() -> None:
    game = LimitHoldemBatch(deals=deal_cards(seed=5, start=0, count=400))
    rng, random, checked = np.random.default_rng(1), make_agent("random"), 0
    while game.active().size:
        hands = game.active()
        can = hands[game.legal_mask(hands)[:, RAISE]]
        if can.size:
            raised = _clone(game)
            raised.step(np.full(can.size, RAISE), can)
            open_ = can[~raised.done[can]]
            nums, legal = state_after_raise(game.raises[open_], game.round[open_].astype(int))
            assert np.array_equal(nums, raised.raises[open_])
            assert np.array_equal(legal, raised.legal_mask(open_))
            checked += open_.size
        game.step(random.act(game.observe(hands), game.legal_mask(hands), rng), hands)
    assert checked > 1000


def _brute_force_range(agent, deal: np.ndarray, lbr_seat: int, moves: list, end: int) -> np.ndarray:
    """The agent's range at the end of one hand by Bayes' rule, pair by pair: the hand is
    replayed on the engine once per possible pair (that pair as the agent's hole cards), and
    each agent move multiplies in its probability there, from the engine's own observation."""
    agent_seat = 1 - lbr_seat
    lbr_hole = deal[2 * lbr_seat : 2 * lbr_seat + 2]
    board = deal[4 : 4 + (0, 3, 4, 5, 5)[end]]
    possible = ~CLASH[np.concatenate([lbr_hole, board])].any(axis=0)
    pairs = np.flatnonzero(possible)
    deals = np.repeat(deal[None], pairs.size, 0)
    deals[:, 2 * agent_seat : 2 * agent_seat + 2] = PAIRS[pairs]
    game = LimitHoldemBatch(deals=deals)
    weight = np.ones(pairs.size)
    everyone = np.arange(pairs.size)
    for seat, action in moves:
        if seat == agent_seat:
            obs = observe(game, everyone, agent_encoding(agent))
            probs = agent_action_probs(agent, obs, game.legal_mask(everyone),
                                       lambda: turn_cards(game, everyone))  # fmt: skip
            weight *= probs[:, action]
        game.step(np.full(pairs.size, action), everyone)
    full = np.zeros(len(PAIRS))
    full[pairs] = weight / weight.sum()
    return full


@pytest.mark.parametrize(
    "agent",
    [make_agent("tightbot"), _q_agent(epsilon=0.2), _q_agent("strength", epsilon=0.1)],
    ids=["tightbot", "dqn-epsilon", "dqn-strength"],
)
def test_the_range_update_is_bayes_rule(agent) -> None:
    deals, seats = _duplicate(seed=11, hands=8)
    found = play_lbr(agent, deals, seats, np.random.default_rng(2),
                     LBRSettings(check_until="turn"), trace=True)  # fmt: skip
    assert found.ranges is not None and found.history is not None
    narrowed = 0
    for hand in range(len(deals)):
        moves = [
            (int(seat[at == hand][0]), int(action[at == hand][0]))
            for at, seat, action in found.history
            if (at == hand).any()
        ]
        expected = _brute_force_range(agent, deals[hand].astype(np.int64), int(seats[hand]),
                                      moves, int(found.end_round[hand]))  # fmt: skip
        np.testing.assert_allclose(found.ranges[hand], expected, rtol=1e-9, atol=1e-15)
        support = expected[expected > 0]
        narrowed += support.max() > 1.5 * support.min()
    assert narrowed >= 2  # the agents' moves did tell LBR something


def test_a_deterministic_agent_leaves_a_0_1_range() -> None:
    deals, seats = _duplicate(seed=12, hands=20)
    found = play_lbr(_q_agent(), deals, seats, np.random.default_rng(0),
                     LBRSettings(check_until="river"), trace=True)  # fmt: skip
    assert found.ranges is not None
    for row in found.ranges:
        support = row[row > 0]
        assert np.allclose(support, support[0])
    assert min((row > 0).sum() for row in found.ranges) < 900  # some hands were narrowed


def test_an_agent_without_action_probabilities_is_refused() -> None:
    class Blind:
        name = "blind"

        def act(self, obs, legal_mask, rng):
            return np.zeros(len(obs), dtype=np.int64)

    deals, seats = _duplicate(seed=0, hands=2)
    with pytest.raises(ConfigError, match="'blind' has no action_probs"):
        play_lbr(Blind(), deals, seats, np.random.default_rng(0), LBRSettings())


@pytest.mark.parametrize("street", [1, 2, 3])
def test_lbr_equity_is_exact_after_the_flop(street: int) -> None:
    """LBR's equity against a pair, every runout enumerated, against the game's evaluator
    over the same runouts written out one by one."""
    deals, seats = _duplicate(seed=13, hands=4)
    lbr = _LBRHands(make_agent("call"), deals, seats, np.random.default_rng(0), LBRSettings())
    lbr.game.round[:] = street  # the equity reads only the cards and the street
    found = lbr._equity(np.arange(4), street)
    rng = np.random.default_rng(street)
    for hand in range(4):
        deal = deals[hand].astype(np.int64)
        hole, board = lbr.lbr_hole[hand], deal[4 : 4 + (0, 3, 4, 5)[street]]
        possible = np.flatnonzero(~CLASH[np.concatenate([hole, board])].any(axis=0))
        for pair in rng.choice(possible, 6, replace=False):
            rest = np.setdiff1d(np.arange(NUM_CARDS), np.concatenate([hole, board, PAIRS[pair]]))
            runs = [()] if street == 3 else (
                [(c,) for c in rest] if street == 2
                else [(a, b) for i, a in enumerate(rest) for b in rest[i + 1 :]]
            )  # fmt: skip
            full = np.array([np.concatenate([board, run]) for run in runs], dtype=np.int64)
            mine = hand_strength(np.concatenate([np.repeat(hole[None], len(full), 0), full], 1))
            theirs = hand_strength(np.concatenate([np.repeat(PAIRS[pair][None], len(full), 0),
                                                   full], 1))  # fmt: skip
            share = ((mine > theirs) + 0.5 * (mine == theirs)).mean()
            assert found[hand, pair] == pytest.approx(share, abs=1e-12)


# --- LBR's value -----------------------------------------------------------------------------


@pytest.mark.parametrize("check_until", ["preflop", "turn"])
def test_lbr_wins_exactly_750_against_fold(check_until: str) -> None:
    report = lbr_of("fold", hands=200, seed=3, check_until=check_until)
    assert (report.lbr_mbb_per_hand, report.lbr_std_error) == (750.0, 0.0)
    assert (report.small_blind_mbb_per_hand, report.big_blind_mbb_per_hand) == (1000.0, 500.0)
    assert report.streets[0].share_of_winnings == 1.0


def _river_equity(hole: np.ndarray, board: np.ndarray) -> float:
    """Share of the pot against a uniformly random hand on a full board: every one of them."""
    rest = np.setdiff1d(np.arange(NUM_CARDS), np.concatenate([hole, board]))
    theirs = np.array([(a, b) for i, a in enumerate(rest) for b in rest[i + 1 :]])
    mine = hand_strength(np.concatenate([hole, board])[None])[0]
    other = hand_strength(np.concatenate([theirs, np.repeat(board[None], len(theirs), 0)], 1))
    return float(((mine > other) + 0.5 * (mine == other)).mean())


def _sampled_equity(hole: np.ndarray, board: np.ndarray, samples: int, rng) -> float:
    """Share of the pot against a random hand, the board rolled out: ``samples`` draws."""
    rest = np.setdiff1d(np.arange(NUM_CARDS), np.concatenate([hole, board]))
    draws = rest[np.argsort(rng.random((samples, rest.size)), axis=1)[:, : 7 - board.size]]
    full = np.concatenate([np.repeat(board[None], samples, 0), draws[:, 2:]], axis=1)
    mine = hand_strength(np.concatenate([np.repeat(hole[None], samples, 0), full], axis=1))
    other = hand_strength(np.concatenate([draws[:, :2], full], axis=1))
    return float(((mine > other) + 0.5 * (mine == other)).mean())


def _exact_best_response_to_call(configs: int, samples: int) -> tuple[float, float]:
    """The best response to always-call, in mbb/h ± SE, by a route that shares no LBR code:
    bet Δ = 2, 2, 4, 4 chips on a street iff the equity against a random hand (it never
    narrows) is above 1/2, worth Δ (2 EHS - 1). EHS: the shipped preflop table, sampled
    runouts on the flop and turn (``samples`` each), every opponent hand on the river."""
    rng = np.random.default_rng(123)
    values = np.empty(configs)
    for k in range(configs):
        cards = rng.permutation(NUM_CARDS)[:7]
        hole, board = cards[:2], cards[2:]
        equity = [
            float(preflop_equity(hole[None])[0]),
            _sampled_equity(hole, board[:3], samples, rng),
            _sampled_equity(hole, board[:4], samples, rng),
            _river_equity(hole, board),
        ]
        values[k] = sum(d * max(0.0, 2 * e - 1) for d, e in zip((2, 2, 4, 4), equity, strict=True))
    mbb = 1000.0 * values / 2  # chips -> big blinds -> mbb
    return float(mbb.mean()), float(mbb.std(ddof=1) / np.sqrt(configs))


@pytest.mark.slow
def test_lbr_against_call_is_the_exact_best_response() -> None:
    expected, expected_se = _exact_best_response_to_call(configs=1200, samples=800)
    deals, seats = _duplicate(seed=21, hands=600)
    found = play_lbr(make_agent("call"), deals, seats, np.random.default_rng(0), LBRSettings())
    assert (found.end_round == 4).all()  # call never folds, and LBR never needs to
    assert found.raises.max() == 1  # only LBR bets, and the caller never raises back
    # LBR's value, estimated from its own bets: street s's bet wins Δ (2 EHS_s - 1) in
    # expectation, EHS_s from LBR's cards alone (the caller's are uniform given them, its
    # moves say nothing), by the same independent route as the reference; the blinds' part
    # has mean 0. Unbiased for LBR's mbb/h and far less noisy than the payoffs.
    rng = np.random.default_rng(5)
    holes = deals[np.arange(len(deals))[:, None], 2 * seats[:, None] + np.arange(2)]
    value, equities = np.zeros(len(deals)), np.zeros((len(deals), 4))
    for hand, (hole, deal) in enumerate(zip(holes.astype(np.int64), deals.astype(np.int64),
                                            strict=True)):  # fmt: skip
        board = deal[4:9]
        equity = [
            float(preflop_equity(hole[None])[0]),
            _sampled_equity(hole, board[:3], 800, rng),
            _sampled_equity(hole, board[:4], 800, rng),
            _river_equity(hole, board),
        ]
        equities[hand] = equity
        value[hand] = sum(d * bet * (2 * e - 1) for d, bet, e in
                          zip((2, 2, 4, 4), found.raises[hand], equity, strict=True))  # fmt: skip
    # Every bet is the best response's: bet iff the equity is above 1/2, wherever the
    # equity is clear of 1/2 by more than its sampling noise (LBR's preflop boards, the
    # reference's flop and turn runouts: sd about 0.02).
    clear = np.abs(equities - 0.5) > np.array([0.08, 0.06, 0.06, 1e-9])
    assert ((found.raises == 1) == (equities > 0.5))[clear].all()
    pairs = 1000.0 * (value / 2).reshape(-1, 2).mean(axis=1)  # chips -> mbb
    lbr, lbr_se = pairs.mean(), pairs.std(ddof=1) / np.sqrt(pairs.size)
    assert abs(lbr - expected) < 3 * np.hypot(lbr_se, expected_se), (lbr, lbr_se, expected)
    # And the payoffs themselves (noisier) agree.
    paid = 1000.0 * found.payoffs.reshape(-1, 2).mean(axis=1)
    paid_se = paid.std(ddof=1) / np.sqrt(paid.size)
    assert abs(paid.mean() - expected) < 3 * np.hypot(paid_se, expected_se)
    assert 1_000 < expected < 1_300  # the independent estimate: 1,135 ± 32


# --- the run ---------------------------------------------------------------------------------


@pytest.mark.slow
def test_same_bytes_on_any_backend_and_a_rerun_reuses_the_units(tmp_path: Path) -> None:
    config = ExploitConfig(hands=120, seed=2, lbr=LBRSettings(check_until="turn"), unit_hands=40)
    one = run_lbr("loosebot", config, tmp_path / "one")
    two = run_lbr("loosebot", config, tmp_path / "two", backend=Backend(jobs=2))
    for name in ("report.json", "report.md"):
        assert (tmp_path / "one" / name).read_bytes() == (tmp_path / "two" / name).read_bytes()
    assert one == two == load_lbr_report(tmp_path / "one")
    data = json.loads((tmp_path / "one" / "report.json").read_text())
    assert {"lbr_mbb_per_hand", "lbr_std_error", "streets", "config"} <= set(data)
    again = run_lbr("loosebot", config, tmp_path / "one")
    assert again == one
    timing = json.loads((tmp_path / "one" / "timings.json").read_text())
    assert timing["units_reused"] == 3 and timing["hands_played"] == 0



def test_runs_in_one_fan_out_are_the_runs_alone(tmp_path: Path) -> None:
    """``run_lbr_many`` (a study's panel: every agent and seed at once) writes each run's
    report as ``run_lbr`` alone writes it, whatever the order its units are played in."""
    settings = LBRSettings(check_until="turn")
    runs = [LBRRun(spec=spec, config=ExploitConfig(hands=80, seed=seed, lbr=settings,
                                                   unit_hands=40),
                   out=tmp_path / "many" / f"{spec}-{seed}")
            for spec, seed in (("loosebot", 1), ("call", 1), ("loosebot", 4))]  # fmt: skip
    many = run_lbr_many(runs, backend=Backend(jobs=2))
    for run, report in zip(runs, many, strict=True):
        alone = run_lbr(run.spec, run.config, tmp_path / "alone" / run.out.name)
        assert report == alone
        assert (run.out / "report.md").read_bytes() == (
            tmp_path / "alone" / run.out.name / "report.md").read_bytes()  # fmt: skip
        assert json.loads((run.out / "timings.json").read_text())["runs_in_fan_out"] == 3
    assert many[0] != many[2]  # other seeds, other hands

def test_other_settings_in_the_same_folder_are_refused(tmp_path: Path) -> None:
    config = ExploitConfig(hands=20, lbr=LBRSettings(check_until="river"))
    run_lbr("call", config, tmp_path)
    other = ExploitConfig(hands=20, lbr=LBRSettings(check_until="turn"))
    with pytest.raises(ValueError, match="check_until 'river' -> 'turn'"):
        run_lbr("call", other, tmp_path)
    assert run_lbr("call", other, tmp_path, overwrite=True).config == other


def test_epsilon_needs_an_agent_that_has_one() -> None:
    with pytest.raises(ValueError, match="'random' has no epsilon"):
        lbr_of("random", hands=2, seed=0, epsilon=0.1)
