"""AIVAT-style chance corrections (pokerirl/tournaments/aivat.py) and where they are reported.

The corrected mean must be unbiased (the corrections have mean zero, even between agents
whose betting depends on their cards, which is where committing the wrong chips would show)
and its standard error smaller; the raw result must stay play_match's to the byte.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
import torch

from pokerirl.agents.dqn import GreedyQAgent, QNetwork
from pokerirl.game.bots import make_agent
from pokerirl.game.deals import deal_cards
from pokerirl.game.encodings import get_encoding
from pokerirl.game.engine import LimitHoldemBatch
from pokerirl.game.match import play_match
from pokerirl.tournaments import load_report, run_tournament
from pokerirl.tournaments.aivat import committed, deal_equities, play_corrected_match


def _q_agent(encoding: str = "rlcard") -> GreedyQAgent:
    torch.manual_seed(3)
    network = QNetwork(hidden=(8,), obs_size=get_encoding(encoding).width).eval()
    return GreedyQAgent(name=f"q-{encoding}", network=network, encoding=encoding)


@pytest.mark.parametrize(
    ("a", "b", "duplicate"),
    [("random", "tightbot", True), ("loosebot", "random", False), ("q", "q-strength", True)],
)
def test_the_raw_result_is_play_matchs_to_the_byte(a: str, b: str, duplicate: bool) -> None:
    agents = {"q": _q_agent(), "q-strength": _q_agent("strength")}
    first, second = (agents.get(n) or make_agent(n) for n in (a, b))
    kwargs = {"hands": 600, "seed": 5, "duplicate": duplicate, "batch_size": 128}
    found = play_corrected_match(first, second, **kwargs)
    expected = play_match(first, second, **kwargs)
    assert found.match.results_bb.tobytes() == expected.results_bb.tobytes()
    assert (found.match.mbb_per_hand, found.match.std_error) == (
        expected.mbb_per_hand,
        expected.std_error,
    )


def test_committed_is_what_each_player_has_in_when_a_card_comes() -> None:
    game = LimitHoldemBatch(deals=deal_cards(seed=1, start=0, count=3000))
    rng, agent, checked = np.random.default_rng(0), make_agent("loosebot"), 0
    while game.active().size:
        hands = game.active()
        before = game.round[hands].copy()
        from pokerirl.game.match import turn_cards

        actions = agent.act(game.observe(hands), game.legal_mask(hands), rng,
                            cards=turn_cards(game, hands))  # fmt: skip
        game.step(actions, hands)
        new = hands[(game.round[hands] > before) & (game.round[hands] <= 3)]
        for street in (1, 2, 3):
            at = new[game.round[new] == street]
            assert (game.chips[at, 0] == game.chips[at, 1]).all()
            assert (committed(game.raises[at], street) == game.chips[at, 0]).all()
            checked += at.size
    assert checked > 3000


def test_the_equities_are_exact_where_the_docstring_says() -> None:
    deals = deal_cards(seed=2, start=0, count=40).astype(np.int64)
    found = deal_equities(deals, np.full(40, 3), np.random.default_rng(0))
    from pokerirl.game.evaluator import hand_strength

    for deal, (e0, e1, e2, e3) in zip(deals, found, strict=True):
        rivers = np.setdiff1d(np.arange(52), deal[:8])
        boards = np.concatenate([np.repeat(deal[None, 4:8], rivers.size, 0), rivers[:, None]], 1)
        mine = hand_strength(np.concatenate([np.repeat(deal[None, :2], rivers.size, 0), boards], 1))
        theirs = hand_strength(
            np.concatenate([np.repeat(deal[None, 2:4], rivers.size, 0), boards], 1)
        )
        assert e2 == pytest.approx(((mine > theirs) + 0.5 * (mine == theirs)).mean(), abs=1e-12)
        assert e3 in (0.0, 0.5, 1.0) and 0 <= e0 <= 1 and 0 <= e1 <= 1


def test_a_mirror_match_stays_exactly_even() -> None:
    found = play_corrected_match(make_agent("tightbot"), make_agent("tightbot"), hands=400, seed=1)
    # tightbot is noisy: the two hands of a pair differ, but each correction is seat 0's,
    # turned around for seat 1, so the corrections of a pair cancel when the play repeats.
    deterministic = play_corrected_match(make_agent("raise"), make_agent("call"), hands=400,
                                         seed=1)  # fmt: skip
    assert deterministic.corrected_mbb_per_hand == 0.0 and deterministic.corrected_std_error == 0
    assert np.isfinite(found.corrected_mbb_per_hand)


@pytest.mark.slow
def test_the_corrections_have_mean_zero_where_betting_follows_the_cards() -> None:
    # tightbot and loosebot raise with strong hands: the chips committed before a card are
    # correlated with the equity, so a correction that used chips known only after the card
    # (or a wrong expectation) would have a non-zero mean here.
    found = play_corrected_match(make_agent("tightbot"), make_agent("loosebot"), hands=120_000,
                                 seed=8, duplicate=False)  # fmt: skip
    correction = 1000.0 * (found.match.results_bb - found.corrected_bb)
    mean, error = correction.mean(), correction.std(ddof=1) / np.sqrt(correction.size)
    assert abs(mean) < 3 * error, (mean, error)
    assert found.corrected_std_error < 0.85 * found.match.std_error


@pytest.mark.parametrize(
    ("a", "b", "tighter"),
    [("tightbot", "tightbot", True), ("call", "raise", True), ("random", "random", False)],
)
@pytest.mark.slow
def test_unbiased_over_seeds_where_the_truth_is_known(a: str, b: str, tighter: bool) -> None:
    # Each matchup is even in expectation (a mirror; raise vs call plays the same pot for
    # both). Without duplicate deals the raw means are noisy; over 16 seeds both estimates
    # must find 0 within their standard errors, and, where the value function fits the
    # play, the corrected one is the tighter. (Random folds a third of its bets, ending
    # hands that v prices at showdown: there the corrections add a little noise instead.)
    raw, fixed = [], []
    for seed in range(16):
        found = play_corrected_match(make_agent(a), make_agent(b), hands=4000, seed=seed,
                                     duplicate=False)  # fmt: skip
        raw.append(found.match.mbb_per_hand)
        fixed.append(found.corrected_mbb_per_hand)
    for means in (np.array(raw), np.array(fixed)):
        assert abs(means.mean()) < 3 * means.std(ddof=1) / np.sqrt(means.size)
    if tighter:
        assert np.std(fixed) < 0.8 * np.std(raw)


def test_the_tournament_reports_raw_and_corrected_side_by_side(tmp_path: Path) -> None:
    report = run_tournament([("tightbot", "call")], hands=2000, seeds=[0, 1], out=tmp_path)
    m = report.matchups[0]
    assert m.aivat is not None and all(s.aivat is not None for s in m.seeds)
    assert m.aivat.std_error < m.pooled.std_error or m.aivat.n == 2
    markdown = (tmp_path / "report.md").read_text()
    assert "## Variance-reduced (AIVAT chance corrections)" in markdown
    assert f"{m.aivat.mbb_per_hand:+.2f} ± {m.aivat.std_error:.2f}" in markdown
    with open(tmp_path / "per_seed.csv", newline="") as file:
        rows = list(csv.DictReader(file))
    assert [float(r["aivat_mbb_per_hand"]) for r in rows] == [s.aivat.mbb_per_hand for s in m.seeds]
    assert load_report(tmp_path) == report
    data = json.loads((tmp_path / "report.json").read_text())
    assert data["matchups"][0]["aivat"]["mbb_per_hand"] == m.aivat.mbb_per_hand


def test_a_tournament_without_the_corrections_reports_only_the_raw_line(tmp_path: Path) -> None:
    report = run_tournament([("tightbot", "call")], hands=400, seeds=[0], out=tmp_path,
                            aivat=False)  # fmt: skip
    assert report.matchups[0].aivat is None and report.matchups[0].seeds[0].aivat is None
    assert "AIVAT" not in (tmp_path / "report.md").read_text()
    again = run_tournament([("tightbot", "call")], hands=400, seeds=[0], out=tmp_path)
    assert again.timing["seeds_reused"] == 1 and again.matchups[0].aivat is None
