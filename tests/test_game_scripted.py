"""The synthetic months' scripted players as engine agents (tightbot, loosebot)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from pokerirl.game import make_agent, play_match
from pokerirl.game.bots import ScriptedAgent, seat_cards
from pokerirl.game.match import DecisionLog
from pokerirl.game.synth import DEFAULT_PLAYERS, ScriptedPlayer, write_synthetic_month
from pokerirl.holdem import CALL, CHECK, RAISE, parse_card


def _cards(hole: str, board: str) -> list[int]:
    cards = [parse_card(c) for c in f"{hole} {board}".split()]
    return cards + [-1] * (7 - len(cards))


def test_the_rule_is_the_generators_own_on_every_decision_it_wrote(tmp_path: Path) -> None:
    """With no noise, the engine agent's rule reproduces every decision of the synthetic
    month's players (the month is written with synth's own code, then ingested)."""
    from pokerirl.datasets.ingest import ingest_table

    players = tuple(ScriptedPlayer(**{**vars(p), "noise": 0.0}) for p in DEFAULT_PLAYERS)
    month = write_synthetic_month(tmp_path, hands=400, seed=3, players=players)
    ingest_table([month], tmp_path / "table.parquet")
    table = pq.read_table(tmp_path / "table.parquet").to_pydict()
    obs = np.array(table["obs"], np.uint8)
    legal = np.array(table["legal_mask"], bool)
    cards = np.array(
        [_cards(*pair) for pair in zip(table["hole_cards"], table["board"], strict=True)]
    )
    actions = np.array(table["action_id"])
    for player in players:
        rows = np.array(table["player"]) == player.nick
        agent = ScriptedAgent(name=player.nick, player=player)
        assert rows.sum() > 300
        rule = agent.rule(obs[rows], legal[rows], cards[rows])
        np.testing.assert_array_equal(rule, actions[rows])
    assert {RAISE, CALL, CHECK} <= set(actions.tolist())  # folds hide their cards: no rows


def test_scripted_agents_play_legally_with_their_noise() -> None:
    tight, loose = make_agent("tightbot"), make_agent("loosebot")
    log: list[DecisionLog] = []
    result = play_match(tight, make_agent("random"), hands=4_000, seed=2, log=log)
    decisions = DecisionLog.concatenate(log)
    assert result.mbb_per_hand > 0 and len(decisions.actions) > 4_000
    assert decisions.legal_mask[np.arange(len(decisions.actions)), decisions.actions].all()
    off_rule = decisions.actions != tight.rule(decisions.obs, decisions.legal_mask, decisions.cards)
    assert 0.005 < off_rule.mean() < tight.player.noise  # noise picks the rule's action too
    raise_share = {}
    for agent in (tight, loose):
        parts: list[DecisionLog] = []
        play_match(agent, make_agent("call"), hands=2_000, seed=1, log=parts)
        raise_share[agent.name] = (DecisionLog.concatenate(parts).actions == RAISE).mean()
    assert raise_share["loosebot"] > raise_share["tightbot"] > 0.05


def test_seat_cards_are_hole_cards_then_the_board_shown() -> None:
    deals = np.arange(18, dtype=np.int8).reshape(2, 9)
    cards = seat_cards(deals, np.array([0, 3]), np.array([1, 0]))
    assert cards.tolist() == [[2, 3, -1, -1, -1, -1, -1], [9, 10, 13, 14, 15, 16, 17]]
