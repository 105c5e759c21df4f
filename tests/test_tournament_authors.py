"""The authors' tournament protocol: 50 x 1,000 non-duplicate games, RLCard's seat rule."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import pokerirl.tournaments.authors as authors
from pokerirl.game import make_agent, play_match
from pokerirl.tournaments import TournamentError, load_authors_tournament, run_authors_tournament


def test_statistics_are_the_authors_and_ours(tmp_path: Path) -> None:
    found = run_authors_tournament(
        [("raise", "random"), ("call", "random")], experiments=[0, 1, 2], out=tmp_path,
        repeats=4, games=300, names=["raise", "call"], duplicate={"raise": 1.5},
    )  # fmt: skip
    m = found["raise"]
    everything = np.concatenate([e.repeats_mbb for e in m.experiments])
    assert everything.size == 12 and m.mean == pytest.approx(everything.mean())
    # Theirs: np.std over all repeats / sqrt(games); ours: SE over the experiments' means.
    assert m.paper_style_se == pytest.approx(everything.std() / math.sqrt(300))
    means = [everything[4 * k : 4 * k + 4].mean() for k in range(3)]
    assert m.per_experiment == pytest.approx(means)
    assert m.se_over_experiments == pytest.approx(np.std(means, ddof=1) / math.sqrt(3))
    summary = m.summary().to_json()
    for key in ("mean", "paper_style_se", "se_over_experiments", "duplicate_mbb_per_hand",
                "per_experiment"):  # fmt: skip
        assert key in summary
    assert summary["duplicate_mbb_per_hand"] == 1.5 and found["call"].duplicate_mbb_per_hand is None
    assert load_authors_tournament(tmp_path)["raise"] == m
    # Repeat r of experiment k: its own fresh deals, seats drawn per game.
    seed = authors.repeat_seed(1, 2)
    again = play_match(make_agent("raise"), make_agent("random"), hands=300, seed=seed,
                       duplicate=False, seating="random")  # fmt: skip
    assert m.experiments[1].repeats_mbb[2] == again.mbb_per_hand


def test_seats_are_drawn_per_game_as_rlcard_does() -> None:
    # Two deterministic opposite styles cancel exactly on duplicate deals, not here.
    duplicate = play_match(make_agent("raise"), make_agent("call"), hands=2_000, seed=0)
    drawn = play_match(make_agent("raise"), make_agent("call"), hands=2_000, seed=0,
                       duplicate=False, seating="random")  # fmt: skip
    assert duplicate.mbb_per_hand == 0.0 and drawn.mbb_per_hand != 0.0
    with pytest.raises(ValueError, match="seating"):
        play_match(make_agent("raise"), make_agent("call"), hands=10, seed=0, seating="random")


def test_saved_experiments_are_reused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    first = run_authors_tournament([("raise", "call")], experiments=[0, 1], out=tmp_path,
                                   repeats=2, games=100)  # fmt: skip

    def refuse(*args: object) -> list[float]:
        raise AssertionError("replayed a saved experiment")

    monkeypatch.setattr(authors, "_play_experiment", refuse)
    assert run_authors_tournament([("raise", "call")], experiments=[0, 1], out=tmp_path,
                                  repeats=2, games=100) == first  # fmt: skip
    with pytest.raises(TournamentError, match="another configuration"):
        run_authors_tournament([("raise", "call")], experiments=[0], out=tmp_path, repeats=3,
                               games=100)  # fmt: skip


def test_the_study_report_keeps_the_authors_summary_field_by_field() -> None:
    # AuthorsRow repeats AuthorsSummary's fields (the report must load no tournament code):
    # the same names and order, then the paper's line.
    from dataclasses import fields

    from pokerirl.studies.poker.report_types import AuthorsRow
    from pokerirl.tournaments.authors import AuthorsSummary

    row = [(f.name, f.type) for f in fields(AuthorsRow)]
    assert row[:-1] == [(f.name, f.type) for f in fields(AuthorsSummary)]
    assert row[-1][0] == "paper"
