"""The reward card: f per action, the per-decision bonus, the argmax over legal actions."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pokerirl.holdem import CALL, CHECK, FOLD, RAISE, encode_obs, parse_card
from pokerirl.poker.reward_card import (
    CARD_FIGURE,
    CARD_FILE,
    CardStates,
    RewardCard,
    equity,
    read_card,
    reward_card,
)
from pokerirl.poker.rewards import ObsReward


def _cards(text: str) -> list[int]:
    cards = [parse_card(c) for c in text.split()]
    return cards + [-1] * (7 - len(cards))


FACING = [True, True, True, False]  # call, raise, fold legal; check not
LEVEL = [False, True, True, True]


def _states(rows: list[tuple[str, list[bool], int]]) -> CardStates:
    cards = np.array([_cards(text) for text, _, _ in rows])
    return CardStates.from_arrays(
        obs=encode_obs(cards, np.zeros((len(rows), 4), int)),
        legal_mask=np.array([legal for _, legal, _ in rows]),
        cards=cards,
        expert=np.array([expert for _, _, expert in rows]),
    )


def test_the_argmax_is_over_legal_actions_only() -> None:
    """A reward that pays most for check, even where check is illegal: there the card's
    argmax must be the best legal action (raise), never check."""
    table = {CALL: 1.0, RAISE: 2.0, FOLD: -5.0, CHECK: 9.0}
    reward = ObsReward(lambda obs, actions: np.vectorize(table.get)(actions).astype(np.float32))
    states = _states(
        [("As Ah", FACING, CALL), ("7c 2d", FACING, RAISE), ("Kd Qd 2c 7h 9s", LEVEL, CHECK)]
    )
    card = reward_card(reward, states)
    assert card.argmax_share == pytest.approx(
        {"call": 0.0, "raise": 2 / 3, "fold": 0.0, "check": 1 / 3}
    )
    assert card.argmax_share_by_street[0] == {"call": 0.0, "raise": 1.0, "fold": 0.0, "check": 0.0}
    assert card.argmax_share_by_street[1]["check"] == 1.0
    assert card.agree_expert == pytest.approx(2 / 3)  # raise on the 7-2, check on the flop
    assert card.agree_legal_majority == pytest.approx(1 / 3)  # the rule calls facing a bet
    assert card.legal_majority_agree_expert == pytest.approx(2 / 3)
    # f over the states where each action is legal; the bonus leaves fold out.
    assert card.mean_f == {"call": 1.0, "raise": 2.0, "fold": -5.0, "check": 9.0}
    assert card.decision_bonus == pytest.approx(((1 + 2) / 2 * 2 + (2 + 9) / 2) / 3)
    assert card.decision_bonus_sign == 1 and card.prediction.startswith("pays +")
    assert "raise-heavy" in card.prediction and "folding costs 5.00" in card.prediction


def test_strength_buckets_follow_equity() -> None:
    rows = [
        ("As Ah", FACING, CALL),
        ("7c 2d", FACING, CALL),
        ("As Ks Qs Js Ts 2c 3d", LEVEL, CHECK),
    ]
    strength = equity(np.array([_cards(text) for text, _, _ in rows]))
    assert 0.8 < strength[0] < 0.9 and 0.28 < strength[1] < 0.42 and strength[2] == 1.0
    card = reward_card(ObsReward(lambda obs, a: (a == RAISE).astype(np.float32)), _states(rows))
    assert card.states_by_strength == [0, 1, 0, 2]  # 7-2 offsuit, then the aces and the royal
    assert card.strength_buckets == ["<25%", "25-50%", "50-75%", ">=75%"]
    np.testing.assert_array_equal(equity(np.array([_cards("As Ah")])), strength[:1])  # seeded


def test_card_round_trips_and_a_train_run_writes_one(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from pokerirl.cli import app
    from pokerirl.datasets.ingest import ingest_table
    from pokerirl.game.synth import write_synthetic_month

    month = write_synthetic_month(tmp_path, hands=300, seed=0)
    ingest_table([month], tmp_path / "table.parquet")
    result = CliRunner().invoke(
        app, ["train", str(tmp_path / "table.parquet"), "--out", str(tmp_path / "run"),
              "--epochs", "2", "--quiet"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "reward card:" in result.output and "legal majority" in result.output
    card = read_card(tmp_path / "run")
    assert card is not None and (tmp_path / "run" / CARD_FIGURE).is_file()
    split = json.loads((tmp_path / "run" / "split.json").read_text())
    assert card.states == sum(card.states_by_street) and card.states < 1_000
    assert len(split["validation_groups"]) > 0
    assert RewardCard.from_text(card.to_text()) == card
    record = json.loads((tmp_path / "run" / CARD_FILE).read_text())
    for name in ("mean_f", "decision_bonus", "argmax_share", "argmax_share_by_street",
                 "argmax_share_by_strength", "agree_expert", "agree_legal_majority"):  # fmt: skip
        assert name in record
    assert (
        len(record["argmax_share_by_street"]) == 4 and len(record["argmax_share_by_strength"]) >= 4
    )

    out = tmp_path / "card"
    result = CliRunner().invoke(
        app, ["reward-card", str(tmp_path / "run"), "--table", str(tmp_path / "table.parquet"),
              "--out", str(out), "--transform", "centered", "--validation"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    centered = read_card(out)
    assert centered is not None and centered.argmax_share == card.argmax_share  # same order
    assert "prediction:" in result.output
    bad = CliRunner().invoke(app, ["reward-card", str(tmp_path), "--table", "x", "--out", "y"])
    assert bad.exit_code == 1 and "not a reward run" in bad.output


@pytest.mark.slow
def test_fan_out_runs_write_the_same_card_bytes_naming_the_real_table(tmp_path: Path) -> None:
    # A fan-out run trains on a worker's scratch copy of the table; its card must name the
    # table given, not the copy, so the same inputs give the same bytes.
    from pokerirl.datasets.ingest import ingest_table
    from pokerirl.game.synth import write_synthetic_month
    from pokerirl.irl import AIRLConfig
    from pokerirl.poker import train_runs

    month = write_synthetic_month(tmp_path, hands=200, seed=1)
    table = tmp_path / "table.parquet"
    ingest_table([month], table)
    config = AIRLConfig.for_algo("hairl", epochs=1)
    for name in ("a", "b"):
        train_runs(table, tmp_path / name, runs=2, config=config, progress=False)
    for k in range(2):
        first = (tmp_path / "a" / f"run-{k}" / CARD_FILE).read_bytes()
        assert first == (tmp_path / "b" / f"run-{k}" / CARD_FILE).read_bytes()
        assert str(table) in json.loads(first)["source"]
