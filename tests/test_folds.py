"""``ingest --folds impute`` (pokerirl/poker/impute.py, docs/folds.md): the posterior over the
hidden hole cards against a brute-force Bayes computation, the imputed table, its summary, and
``--folds drop`` byte for byte."""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import torch

from irc_fixtures import real_month
from pokerirl.datasets.ingest import UNEXPLAINED, IngestSummary, ingest_table
from pokerirl.datasets.table import IMPUTED_SCHEMA, SCHEMA, month_table
from pokerirl.game.encodings import STRENGTH, RawStates, get_encoding
from pokerirl.game.evaluator import hand_strength
from pokerirl.game.synth import write_synthetic_month
from pokerirl.holdem import CARD_INDEX, FOLD, cards_from_text, encode_obs
from pokerirl.irl.nets import DiscretePolicy
from pokerirl.parsers.irc import IngestStats, parse_month
from pokerirl.parsers.irc_sources import iter_months
from pokerirl.poker.folds import ImputeConfig
from pokerirl.poker.impute import (
    NUM_PAIRS,
    PAIRS,
    Behaviour,
    impute,
    ingest_imputed,
    log_likelihoods,
    posterior,
    split_table,
)

torch.set_num_threads(1)
SAMPLE = real_month()
# ``ingest`` of main at 0ccf3f9 (before folds could be kept), pyarrow 26.0.1: the table's and
# the summary's sha256 (the summary's folder written as TMP).
PINNED_PYARROW = "26.0.1"
SYNTH_TABLE = "1896bed7e1e3b059d3720619179a487062446be6bd4d1d0794379e56d8ab9225"
SYNTH_SUMMARY = "dbb6b7cb4533c572d2dcd821d55f9f350e970936ef4cc0986f37d98fb931c360"
REAL_TABLE = "f0b417a1889867191d8989a1771ca15f8b29467a561343ec129b17da15b6c243"
REAL_SUMMARY = "823f0f49c835612eb5a45895c82974afe0854e5994343939b5f21101fa2e7ef3"


@pytest.fixture(scope="module")
def month(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_synthetic_month(tmp_path_factory.mktemp("month"), hands=60, seed=3)


def every_row(month: Path) -> pa.Table:
    """What ingest hands its folds step: every row, the concealed players' with no cards."""
    stats, seen = IngestStats(), {}
    (files,) = list(iter_months([month]))
    return month_table(parse_month(files, stats, seen, keep_concealed=True),
                       keep_concealed=True)[0]  # fmt: skip


def behaviour(encoding: str, seed: int = 0) -> Behaviour:
    """A random policy with sharp preferences (large logits): a peaked posterior."""
    chosen = get_encoding(encoding)
    torch.manual_seed(seed)
    policy = DiscretePolicy(obs_dim=chosen.width, num_actions=4, hidden=(16,))
    with torch.no_grad():
        for parameter in policy.parameters():
            parameter.mul_(4.0)
    return Behaviour(policy.eval(), chosen, "test")


def brute_force(split, player: int, chosen: Behaviour) -> np.ndarray:  # type: ignore[no-untyped-def]
    """P(c | actions) for one hidden player, pair by pair: the test's own Bayes' rule."""
    hidden = split.hidden
    rows = np.flatnonzero(hidden.owner == player)
    hand = hidden.hand_id[player]
    everything = pa.concat_tables([split.observed, split.templates])
    mine = np.array([h == hand for h in everything.column("hand_id").to_pylist()])
    cards = cards_from_text(everything.column("hole_cards").to_pylist(),
                            everything.column("board").to_pylist())[mine]  # fmt: skip
    final_board = cards[:, 2:].max(axis=0)
    rival = cards[:, :2].max(axis=0)  # the shown player's pair, or -1
    known = {int(c) for c in (*final_board, *rival) if c >= 0}
    actions = everything.column("action_id").to_numpy()[mine]
    chips_won = everything.column("chips_won").to_numpy()[mine]
    hole_shown = cards[:, 0] >= 0
    showdown = rival[0] >= 0 and not (actions == FOLD).any()
    log_post = np.full(NUM_PAIRS, -np.inf)
    for index, (a, b) in enumerate(PAIRS):
        if a in known or b in known:
            continue
        seen = np.concatenate([np.tile([a, b], (len(rows), 1)), hidden.board[rows]], axis=1)
        states = RawStates(cards=seen, raise_nums=hidden.raise_nums[rows],
                        legal_mask=hidden.legal_mask[rows])  # fmt: skip
        obs = torch.as_tensor(chosen.encoding.encode(states)).float()
        with torch.no_grad():
            log_pi = chosen.policy(obs, torch.as_tensor(hidden.legal_mask[rows]))
        total = float(log_pi[np.arange(len(rows)), hidden.action[rows]].double().sum())
        if showdown:  # the result against the shown pair: 0 or 1
            board = list(final_board)
            mine_s = hand_strength(np.array([[a, b, *board]]))[0]
            theirs = hand_strength(np.array([[*rival, *board]]))[0]
            lost = chips_won[~hole_shown].max() == 0
            tied = not lost and chips_won[hole_shown].max() > 0
            fits = (mine_s < theirs) if lost else (mine_s == theirs) if tied else (mine_s > theirs)
            if not fits:
                continue
        log_post[index] = total
    return np.exp(log_post - np.logaddexp.reduce(log_post[np.isfinite(log_post)]))


@pytest.mark.parametrize("encoding", ["rlcard", "strength"])
@pytest.mark.slow
def test_posterior_is_bayes_rule(month: Path, encoding: str) -> None:
    """The batched posterior (one forward pass per chunk of decisions over all pairs, the
    strength equities computed once per board) against Bayes' rule computed pair by pair,
    for a folder, a player who won without showing, and a showdown loser whose cards are
    hidden (a shown hand with its hole cards blanked)."""
    table = every_row(month)
    hole = np.array(table.column("hole_cards").to_pylist(), dtype=object)
    hands = np.array(table.column("hand_id").to_pylist(), dtype=object)
    seats = np.array(table.column("position").to_pylist())
    shown_hands = [h for h in dict.fromkeys(hands) if (hole[hands == h] != "").all()]
    loser = next(h for h in shown_hands
                 if (table.column("chips_won").to_numpy()[hands == h] == 0).any())  # fmt: skip
    won = table.column("chips_won").to_numpy()
    blank = (hands == loser) & (won == 0)  # the loser's rows
    assert blank.any() and (seats[blank] == seats[blank][0]).all()
    hole[blank] = ""
    table = table.set_column(SCHEMA.get_field_index("hole_cards"), "hole_cards",
                             pa.array(hole.tolist(), pa.string()))  # fmt: skip
    split = split_table(table)
    hidden = split.hidden
    assert (hidden.outcome >= 0).sum() == 1  # the blanked loser, and only it
    folder = int(np.flatnonzero((hidden.action == FOLD) & (hidden.board[:, 0] >= 0))[0])
    picks = {
        "folder after the flop": hidden.owner[folder],
        "winner without showing": int(np.flatnonzero(
            (hidden.outcome < 0) & ~np.isin(np.arange(hidden.players),
                                            hidden.owner[hidden.action == FOLD]))[0]),
        "showdown loser": int(np.flatnonzero(hidden.outcome >= 0)[0]),
    }  # fmt: skip
    if encoding == "strength":  # its brute force costs seconds a player: the equity's case
        picks = {"folder after the flop": picks["folder after the flop"]}
    chosen = behaviour(encoding)
    players = np.array(list(picks.values()))
    few = hidden.select(players)  # the batched posterior of these players alone
    post = posterior(few, log_likelihoods(few, chosen))
    for index, (name, player) in enumerate(picks.items()):
        expected = brute_force(split, int(player), chosen)
        found = np.exp(post.log_probs[index])
        assert found.sum() == pytest.approx(1.0)
        np.testing.assert_allclose(found, expected, atol=1e-6, rtol=1e-4, err_msg=name)
        entropy = -np.sum(expected[expected > 0] * np.log2(expected[expected > 0]))
        assert post.entropy_bits[index] == pytest.approx(entropy, rel=1e-4)
        assert post.explained[index]


def test_em_rounds_reuse_the_encoded_states(month: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An expansion keeps its encoded chunks for the next round: the same likelihoods as
    encoding them again (and as an expansion that keeps none)."""
    import pokerirl.poker.impute as impute_module

    hidden = split_table(every_row(month)).hidden
    chosen = behaviour("rlcard")
    kept = impute_module.Expansion(hidden, chosen.encoding)
    first = log_likelihoods(hidden, chosen, expansion=kept)
    assert kept._encoded and kept._encoded_bytes > 0
    again = log_likelihoods(hidden, chosen, expansion=kept)
    monkeypatch.setattr(impute_module, "ENCODED_CACHE_BYTES", 0)
    fresh = impute_module.Expansion(hidden, chosen.encoding)
    none_kept = log_likelihoods(hidden, chosen, expansion=fresh)
    assert not fresh._encoded
    assert np.array_equal(first, again) and np.array_equal(first, none_kept)


def test_imputed_table(month: Path, tmp_path: Path) -> None:
    config = ImputeConfig(imputations=5, behaviour_rounds=1, behaviour_epochs=2, seed=1)
    out = tmp_path / "t.parquet"
    summary = ingest_imputed([month], out, config)
    table = pq.read_table(out)
    assert table.schema.equals(IMPUTED_SCHEMA)
    data = table.to_pydict()
    imputed = np.array(data["imputed"])
    weight = np.array(data["weight"])
    assert imputed.any() and (~imputed).any()
    assert (weight[~imputed] == 1).all() and (np.array(data["imputation"])[~imputed] == 0).all()
    # Each hidden decision weighs 1 over its draws; the draws never clash with the board.
    key = [(h, p, s) for h, p, s, i in zip(data["hand_id"], data["player"], data["street"],
                                           data["imputed"], strict=True) if i]  # fmt: skip
    totals: dict[tuple, float] = {}
    for k, w in zip(key, weight[imputed], strict=True):
        totals[k] = totals.get(k, 0.0) + w
    # (a street may hold two decisions of one player: their totals are 2)
    assert set(np.round(list(totals.values()), 5)) <= {1.0, 2.0, 3.0}
    cards = cards_from_text(data["hole_cards"], data["board"]).astype(np.int64)
    shown = cards >= 0
    assert all(len(set(row[s])) == s.sum() for row, s in zip(cards, shown, strict=True))
    obs = np.array(data["obs"], dtype=np.uint8)
    np.testing.assert_array_equal(obs, encode_obs(cards, np.array(data["raise_nums"])))
    # The summary: every hand in one bucket, the fold rows there, the counts consistent.
    assert summary.buckets_add_up and summary.folds is not None
    assert summary.imputed_hands == summary.folds.imputed_hands > 0
    assert summary.dropped["cards_concealed"] == 0 and summary.dropped[UNEXPLAINED] == 0
    assert summary.rows_per_action["fold"] > 0
    assert summary.folds.imputed_decisions_per_action["fold"] == summary.folds.imputed_hands
    assert len(summary.folds.rounds) == 2
    assert IngestSummary.from_json(json.loads(json.dumps(summary.to_json()))) == summary
    # Seeded: the same bytes again; the observed rows are the drop table's rows.
    again = tmp_path / "again.parquet"
    ingest_imputed([month], again, config)
    assert out.read_bytes() == again.read_bytes()
    ingest_table([month], tmp_path / "drop.parquet")
    drop = pq.read_table(tmp_path / "drop.parquet")
    observed = table.filter(pa.array(~imputed)).select(SCHEMA.names)
    assert sorted(map(str, observed.to_pylist())) == sorted(map(str, drop.to_pylist()))


def test_unexplained_hands_are_dropped_and_counted(month: Path, tmp_path: Path) -> None:
    """A behaviour model that never folds explains no fold hand: each is dropped (bucket
    ``unexplained_by_behaviour``), not forced in."""
    chosen = behaviour("rlcard")
    with torch.no_grad():
        chosen.policy.mlp[-1].bias[FOLD] = -1e4
    captured = {}

    def step(table: pa.Table, *, progress: bool):  # type: ignore[no-untyped-def]
        captured["imputation"] = impute(table, ImputeConfig(), behaviour=chosen)
        return captured["imputation"].result()

    summary = ingest_table([month], tmp_path / "t.parquet", folds=step)
    folds = summary.folds
    assert folds is not None and folds.dropped_hands > 0
    assert summary.dropped[UNEXPLAINED] == folds.dropped_hands
    assert summary.buckets_add_up
    table = pq.read_table(tmp_path / "t.parquet")
    assert FOLD not in set(table.column("action_id").to_pylist())  # no fold hand forced in
    assert folds.imputed_hands + folds.dropped_hands == summary.imputed_hands + folds.dropped_hands


def _sha(path: Path, folder: Path | None = None) -> str:
    """A file's digest; a summary's absolute paths (its table, the sample's checkout) are
    neutralized, since CI clones elsewhere."""
    data = path.read_bytes()
    if folder is not None:
        text = data.decode().replace(str(folder), "TMP").replace(str(SAMPLE), "SAMPLE")
        data = text.encode()
    return hashlib.sha256(data).hexdigest()


@pytest.mark.skipif(pa.__version__ != PINNED_PYARROW, reason="digests pinned for pyarrow "
                    f"{PINNED_PYARROW} (Parquet bytes carry the writer's version)")  # fmt: skip
def test_folds_drop_keeps_the_table_of_before(tmp_path: Path) -> None:
    """``--folds drop`` (the default) writes the bytes main wrote before folds could be kept:
    a synthetic month, and the real sample."""
    month = write_synthetic_month(tmp_path / "m", hands=300, seed=5)
    ingest_table([month], tmp_path / "t.parquet")
    assert _sha(tmp_path / "t.parquet") == SYNTH_TABLE
    assert _sha(tmp_path / "t.summary.json", tmp_path) == SYNTH_SUMMARY
    ingest_table([SAMPLE], tmp_path / "r.parquet")
    assert _sha(tmp_path / "r.parquet") == REAL_TABLE
    assert _sha(tmp_path / "r.summary.json", tmp_path) == REAL_SUMMARY


def test_an_imputed_table_reads_with_weights_and_draws(month: Path, tmp_path: Path) -> None:
    from pokerirl.poker.data import read_table

    out = tmp_path / "t.parquet"
    ingest_imputed([month], out, ImputeConfig(behaviour_rounds=0, behaviour_epochs=1))
    for encoding in ("rlcard", "strength"):
        data = read_table(out, encoding=get_encoding(encoding))
        assert data.weights is not None and data.imputed is not None
        assert bool(data.imputed.any()) and math.isclose(
            float(data.weights[~data.imputed].sum()), float((~data.imputed).sum()))
    # A player's next decision stays within its draw: a draw's last row is done.
    table = pq.read_table(out).to_pydict()
    keys = list(zip(table["hand_id"], table["player"], table["imputation"], strict=True))
    assert data.dones is not None
    last = {}
    for row, key in enumerate(keys):
        last[key] = row
    assert int(data.dones.sum()) == len(last)
    assert all(bool(data.dones[row]) for row in last.values())


@pytest.mark.slow
def test_a_run_policy_is_a_behaviour(month: Path, tmp_path: Path) -> None:
    """``--behaviour RUN``: a run's policy, in the run's encoding, imputes a table."""
    from pokerirl.irl import load_config
    from pokerirl.poker import train_table

    month = write_synthetic_month(tmp_path / "m", hands=16, seed=4)  # strength costs
    drop = tmp_path / "drop.parquet"
    ingest_table([month], drop)
    run = tmp_path / "run"
    train_table(drop, run, config=load_config("hairl", overrides={"epochs": 1}),
                progress=False, encoding=STRENGTH)  # fmt: skip
    summary = ingest_imputed([month], tmp_path / "t.parquet", ImputeConfig(behaviour=str(run)))
    assert summary.folds is not None
    assert summary.folds.behaviour == str(run) and summary.folds.behaviour_encoding == "strength-v2"
    assert summary.folds.rounds == ()
    assert CARD_INDEX  # the module's card names are the tables'


@pytest.mark.slow
def test_em_rounds_reimpute_with_the_run_policy(month: Path, tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from pokerirl.cli import app

    table = tmp_path / "t.parquet"
    runner = CliRunner()
    result = runner.invoke(app, ["ingest", str(month), "--out", str(table), "--folds",
                                 "impute", "--imputations", "2", "--behaviour-rounds", "0",
                                 "-q"])  # fmt: skip
    assert result.exit_code == 0, result.output
    out = tmp_path / "em"
    result = runner.invoke(app, ["train", str(table), "--out", str(out), "--epochs", "1",
                                 "--em-rounds", "1", "--quiet"])  # fmt: skip
    assert result.exit_code == 0, result.output
    report = json.loads((out / "em.json").read_text())
    assert [r["round"] for r in report["rounds"]] == [0, 1]
    second = report["rounds"][1]
    assert second["policy_agree_imputed_change"] == pytest.approx(
        second["policy_agree_imputed"] - report["rounds"][0]["policy_agree_imputed"])
    assert 0 <= second["reward_agree_observed"] <= 1 and "mean_entropy_bits" in second
    reimputed = pq.read_table(out / "table-1.parquet")
    assert reimputed.schema.equals(IMPUTED_SCHEMA)
    assert (out / "round-1" / "reward.pt").is_file()
    assert "round 1: policy argmax = imputed actions" in result.output
    # The flags of impute are refused with drop, and EM with several runs.
    refused = runner.invoke(app, ["ingest", str(month), "--out", str(tmp_path / "x.parquet"),
                                  "--imputations", "3"])  # fmt: skip
    assert refused.exit_code == 2 and "only with --folds impute" in refused.stderr
    refused = runner.invoke(app, ["train", str(table), "--out", str(tmp_path / "y"),
                                  "--em-rounds", "1", "--runs", "2"])  # fmt: skip
    assert refused.exit_code == 2 and "--runs 1" in refused.stderr
    refused = runner.invoke(app, ["ingest", str(month), "--out", str(tmp_path / "x.parquet"),
                                  "--folds", "maybe"])  # fmt: skip
    assert refused.exit_code == 2 and "unknown --folds" in refused.stderr


def test_reward_cards_weigh_rows_and_report_the_parts(month: Path, tmp_path: Path) -> None:
    from pokerirl.poker.reward_card import CardStates, RewardCard, reward_card
    from pokerirl.poker.rewards import ObsReward

    out = tmp_path / "t.parquet"
    summary = ingest_imputed([month], out, ImputeConfig(behaviour_rounds=0, behaviour_epochs=1))
    states = CardStates.from_table(out)
    fold_first = ObsReward(lambda obs, a: (a == FOLD).astype(np.float32), name="folds")
    card = reward_card(fold_first, states)
    assert card.by_part is not None and set(card.by_part) == {"observed", "imputed"}
    assert summary.folds is not None
    decisions = summary.rows - summary.folds.imputed_rows + summary.folds.imputed_decisions
    assert card.weighted_states == pytest.approx(decisions, rel=1e-5)
    assert card.by_part["imputed"]["weight"] == pytest.approx(summary.folds.imputed_decisions,
                                                              rel=1e-5)  # fmt: skip
    # The expert's fold share counts each hidden decision once, not once per draw.
    folds = summary.folds.imputed_decisions_per_action["fold"]
    assert card.expert_share is not None
    assert card.expert_share["fold"] == pytest.approx(folds / decisions, rel=1e-5)
    assert card.argmax_share["fold"] == 1.0 and "imputed rows" in card.render()
    assert RewardCard.from_json(card.to_json()) == card
    ingest_table([month], tmp_path / "drop.parquet")
    plain = reward_card(fold_first, CardStates.from_table(tmp_path / "drop.parquet"))
    assert "by_part" not in plain.to_json()  # cards of plain tables as before


def test_study_settings_name_folds_only_when_imputing() -> None:
    from pokerirl.studies.common import StudyError
    from pokerirl.studies.poker.config import preset

    assert "folds" not in preset("quick").settings()  # studies of before keep their records
    assert preset("quick", folds="impute").settings()["folds"] == "impute"
    with pytest.raises(StudyError, match="folds"):
        preset("quick", folds="maybe")


def test_fold_errors_are_one_line(month: Path, tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from pokerirl.cli import app

    runner = CliRunner()
    drop = tmp_path / "drop.parquet"
    ingest_table([month], drop)
    for line, code, words in (
        (["ingest", str(month), "--out", str(tmp_path / "x.parquet"), "--folds", "impute",
          "--behaviour", str(tmp_path / "missing")], 1, "not a training run folder"),
        (["ingest", str(month), "--out", str(tmp_path / "x.parquet"), "--folds", "impute",
          "--behaviour-encoding", "nope"], 2, "unknown behaviour encoding"),
        (["train", str(drop), "--out", str(tmp_path / "em"), "--em-rounds", "1"], 1,
         "needs a table of ingest's fold imputation"),
    ):  # fmt: skip
        result = runner.invoke(app, line)
        errors = [text for text in result.stderr.splitlines() if text.startswith("error: ")]
        assert result.exit_code == code and len(errors) == 1 and words in errors[0], result.stderr
