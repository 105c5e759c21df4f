"""ingest's selection: a period of the month by time, and the expert's players by name, hands
played and winnings, checked against a hand-written month and on the real sample."""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from irc_fixtures import write_month
from pokerirl.cli import app
from pokerirl.datasets.ingest import IngestSummary, ingest_table, summary_path
from pokerirl.datasets.players import Filter, Period, Selection
from pokerirl.errors import ConfigError
from pokerirl.parsers.irc import heads_up_results
from pokerirl.parsers.irc_sources import IngestError, iter_months

T0 = 900000000
BOARD = "2d 5h 9c Jd Ks"
HOLE = {"A": "Ah Kh", "B": "Qd Qh", "C": "7s 7d"}

# The month, hand by hand: (kind, position 1, position 2, winner). A showdown is a check-down
# (position 1 "Bc k k k", position 2 "Bk k k k": 10 chips each, 4 decisions each, both kept);
# a fold is position 1 folding its small blind (-5 / +5 chips, nobody's cards: not in the
# table, but in the players' results); hand 4 is three-handed.
HANDS = [
    ("showdown", "A", "B", "A"),  # 1
    ("fold", "A", "C", "C"),  # 2
    ("showdown", "B", "C", "B"),  # 3
    ("three", "A", "B", "C"),  # 4
    ("showdown", "A", "B", "B"),  # 5
    ("showdown", "C", "A", "C"),  # 6
    ("fold", "B", "A", "A"),  # 7
    ("showdown", "A", "C", "A"),  # 8
    ("showdown", "B", "C", "C"),  # 9
    ("showdown", "A", "B", "A"),  # 10
]

# Worked out by hand from HANDS (a big blind is 10 chips). Hands 1-6 are the first 60%.
#            heads-up hands  chips won  bb/100
# early  A   1 2 5 6   4     -15        -37.5
#        B   1 3 5     3     +10        +33.3
#        C   2 3 6     3      +5        +16.7
# month  A   7 hands         +10        +14.29
#        B   6 hands         -15        -25.0
#        C   5 hands          +5        +10.0 (exactly: a threshold of 10 keeps C)
# Showdowns (the table): hands 1 3 5 6 8 9 10, 8 decisions each, 4 per player.


def month_lines(hands: list[tuple[str, str, str, str]]) -> tuple[list, list, dict]:
    """hdb, hroster and pdb lines of ``hands``; hdb written latest first, so that only the
    timestamps can put it in order."""
    hdb, roster = [], []
    pdb: dict[str, list[str]] = defaultdict(list)
    for number, (kind, first, second, winner) in enumerate(hands, start=1):
        stamp = T0 + number
        if kind == "three":
            hdb.append(f"{stamp}   1  {number}  3  3/30    3/30    3/30     3/30     {BOARD}")
            roster.append(f"{stamp}  3 A B C")
            for position, nick in enumerate("ABC", start=1):
                won = 30 if nick == winner else 0
                pdb[nick].append(
                    f"{nick}  {stamp}  3  {position} Bk  k     k     k   1000   10 {won:4d} "
                    + HOLE[nick]
                )
            continue
        roster.append(f"{stamp}  2 {' '.join(sorted((first, second)))}")
        if kind == "fold":
            hdb.append(f"{stamp}   1  {number}  2  0/0     0/0     0/0      1/15     ")
            pdb[first].append(f"{first}  {stamp}  2  1 Bf  -     -     -   1000    5    0 ")
            pdb[second].append(f"{second}  {stamp}  2  2 B   -     -     -   1000   10   15 ")
            continue
        hdb.append(f"{stamp}   1  {number}  2  2/20    2/20    2/20     2/20     {BOARD}")
        for position, nick, line in (
            (1, first, "Bc  k     k     k"),
            (2, second, "Bk  k     k     k"),
        ):
            won = 20 if nick == winner else 0
            pdb[nick].append(
                f"{nick}  {stamp}  2  {position} {line}   1000   10 {won:4d} {HOLE[nick]}"
            )
    return hdb[::-1], roster, {f"pdb.{nick}": lines for nick, lines in pdb.items()}


def write(root: Path, hands: list[tuple[str, str, str, str]] = HANDS) -> Path:
    hdb, roster, pdb = month_lines(hands)
    return write_month(root, hdb=hdb, hroster=roster, pdb=pdb)


@pytest.fixture
def month(tmp_path: Path) -> Path:
    return write(tmp_path / "irc")


def ingest(month: Path, out: Path, **selection: object) -> tuple[IngestSummary, dict]:
    summary = ingest_table([month], out, selection=Selection(**selection) if selection else None)
    return summary, pq.read_table(out).to_pydict()


def kept(rows: dict) -> set[tuple[int, str]]:
    """(hand number, player) of every row."""
    return {(t - T0, p) for t, p in zip(rows["timestamp"], rows["player"], strict=True)}


def steps(summary: IngestSummary) -> list[tuple[str, int, int, int]]:
    assert summary.selection is not None
    return [(s.filter, s.players, s.hands, s.decisions) for s in summary.selection.steps]


def test_the_month_without_a_selection_is_the_hand_written_table(
    month: Path, tmp_path: Path
) -> None:
    summary, rows = ingest(month, tmp_path / "t.parquet")
    assert summary.kept_hands == 7 and summary.rows == 56
    assert {hand for hand, _ in kept(rows)} == {1, 3, 5, 6, 8, 9, 10}
    assert summary.dropped["cards_concealed"] == 2 and summary.dropped["not_heads_up"] == 1
    assert summary.selection is None and "outside_period" not in summary.dropped


def test_heads_up_results_are_every_heads_up_pdb_line(month: Path) -> None:
    (files,) = iter_months([month])
    results = heads_up_results(files)
    per_player: dict[str, list[float]] = defaultdict(list)
    for player, net in zip(results.players, results.net_bb, strict=True):
        per_player[player].append(net)
    assert {p: len(v) for p, v in per_player.items()} == {"A": 7, "B": 6, "C": 5}
    assert {p: round(sum(v), 6) for p, v in per_player.items()} == {"A": 1.0, "B": -1.5, "C": 0.5}
    assert T0 + 4 not in results.timestamps  # three-handed


def test_winners_in_the_early_period_match_the_hand_written_table(
    month: Path, tmp_path: Path
) -> None:
    summary, rows = ingest(
        month, tmp_path / "t.parquet", period=Period(end=0.6), min_hands=3, min_bb_per_100=0
    )
    assert steps(summary) == [
        (Filter.ALL, 3, 7, 56),
        (Filter.PERIOD, 3, 4, 32),
        (Filter.MIN_HANDS, 3, 4, 32),
        (Filter.MIN_BB_PER_100, 2, 4, 20),
    ]
    assert kept(rows) == {(1, "B"), (3, "B"), (3, "C"), (5, "B"), (6, "C")}
    assert summary.selection is not None and summary.selection.expert == ("B", "C")
    assert [
        (r.player, r.hands, r.net_bb, round(r.bb_per_100, 2))
        for r in summary.selection.expert_results
    ] == [("B", 3, 1.0, 33.33), ("C", 3, 0.5, 16.67)]
    assert summary.rows == 20 and summary.kept_hands == 4
    assert summary.dropped["outside_period"] == 3 and summary.dropped["not_the_expert"] == 0
    assert summary.buckets_add_up


def test_a_higher_bar_and_more_hands_keep_fewer(month: Path, tmp_path: Path) -> None:
    summary, rows = ingest(
        month, tmp_path / "t.parquet", period=Period(end=0.6), min_hands=3, min_bb_per_100=20
    )
    assert kept(rows) == {(1, "B"), (3, "B"), (5, "B")}
    assert summary.dropped["not_the_expert"] == 1  # hand 6: A and C, neither kept
    summary, rows = ingest(month, tmp_path / "t.parquet", period=Period(end=0.6), min_hands=4)
    assert kept(rows) == {(1, "A"), (5, "A"), (6, "A")}


def test_over_the_whole_month_the_threshold_is_inclusive(month: Path, tmp_path: Path) -> None:
    summary, rows = ingest(month, tmp_path / "t.parquet", min_hands=5, min_bb_per_100=10)
    assert steps(summary) == [
        (Filter.ALL, 3, 7, 56),
        (Filter.MIN_HANDS, 3, 7, 56),
        (Filter.MIN_BB_PER_100, 2, 7, 36),
    ]
    assert {player for _, player in kept(rows)} == {"A", "C"}
    summary, _ = ingest(month, tmp_path / "t.parquet", min_hands=6)
    assert summary.selection is not None and summary.selection.expert == ("A", "B")


def test_players_by_name_then_by_hands(month: Path, tmp_path: Path) -> None:
    summary, rows = ingest(month, tmp_path / "t.parquet", players=("C",))
    assert kept(rows) == {(3, "C"), (6, "C"), (8, "C"), (9, "C")}
    assert steps(summary)[-1] == (Filter.PLAYERS, 1, 4, 16)
    summary, rows = ingest(month, tmp_path / "t.parquet", players=("C", "B"), min_hands=6)
    assert {player for _, player in kept(rows)} == {"B"}
    assert [s[0] for s in steps(summary)] == [Filter.ALL, Filter.PLAYERS, Filter.MIN_HANDS]


def test_the_period_cuts_by_time_and_its_parts_are_disjoint_and_cover_the_month(
    month: Path, tmp_path: Path
) -> None:
    _, whole = ingest(month, tmp_path / "whole.parquet")
    parts = []
    for start, end in ((0, 0.25), (0.25, 0.6), (0.6, 1)):  # 2.5 hands: floor, both sides
        summary, rows = ingest(month, tmp_path / "p.parquet", period=Period(start=start, end=end))
        parts.append(rows)
        assert summary.rows == len(rows["timestamp"]) and summary.buckets_add_up
    hands = [{hand for hand, _ in kept(rows)} for rows in parts]
    # Hands 1-2, 3-6, 7-10 of the month by time (the hdb lists them latest first).
    assert hands == [{1}, {3, 5, 6}, {8, 9, 10}]

    def decisions(rows: dict) -> list[tuple]:
        return sorted(zip(rows["timestamp"], rows["player"], rows["street"], strict=True))

    assert sorted(row for rows in parts for row in decisions(rows)) == decisions(whole)


def test_the_choice_never_reads_the_hands_after_the_period(month: Path, tmp_path: Path) -> None:
    """Hands 7-10 change: B wins all of them. The early choice (B and C) stays the same,
    byte for byte; over the whole month it does not (A and C before, B alone after)."""
    changed = [
        *HANDS[:6],
        ("fold", "C", "B", "B"),
        ("showdown", "A", "B", "B"),
        ("showdown", "B", "C", "B"),
        ("showdown", "A", "B", "B"),
    ]
    other = write(tmp_path / "other", changed)
    early = {"period": Period(end=0.6), "min_hands": 3, "min_bb_per_100": 0.0}
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    a, _ = ingest(month, tmp_path / "a" / "t.parquet", **early)
    b, _ = ingest(other, tmp_path / "b" / "t.parquet", **early)
    assert (tmp_path / "a" / "t.parquet").read_bytes() == (
        tmp_path / "b" / "t.parquet"
    ).read_bytes()
    assert a.selection == b.selection and a.selection.expert == ("B", "C")
    whole = {"min_hands": 3, "min_bb_per_100": 0.0}
    a, _ = ingest(month, tmp_path / "a" / "t.parquet", **whole)
    b, _ = ingest(other, tmp_path / "b" / "t.parquet", **whole)
    assert a.selection is not None and b.selection is not None
    assert (a.selection.expert, b.selection.expert) == (("A", "C"), ("B",))


def test_same_options_same_bytes_and_names_in_any_order(month: Path, tmp_path: Path) -> None:
    first, second = tmp_path / "1", tmp_path / "2"
    first.mkdir()
    second.mkdir()
    ingest(month, first / "t.parquet", players=("B", "C"), period=Period(end=0.6))
    ingest(month, second / "t.parquet", players=("C", "B", "C"), period=Period(end=0.6))
    for name in ("t.parquet", "t.summary.json"):
        assert (first / name).read_bytes().replace(b"/1/", b"/") == (second / name).read_bytes(
        ).replace(b"/2/", b"/")  # fmt: skip
    summary = json.loads(summary_path(first / "t.parquet").read_text())
    assert summary["selection"]["settings"] == {
        "period": {"start": 0.0, "end": 0.6},
        "players": ["B", "C"],
    }
    assert IngestSummary.from_json(summary).to_json() == summary
    ingest(month, second / "t.parquet", players=("B",), period=Period(end=0.6))
    assert (first / "t.summary.json").read_bytes() != (second / "t.summary.json").read_bytes()


def test_a_selection_that_keeps_nothing_writes_nothing(month: Path, tmp_path: Path) -> None:
    out = tmp_path / "t.parquet"
    ingest(month, out)
    before = out.read_bytes(), summary_path(out).read_bytes()
    with pytest.raises(IngestError, match="no decision is left after the selection"):
        ingest(month, out, players=("nobody",))
    assert (out.read_bytes(), summary_path(out).read_bytes()) == before


@pytest.mark.parametrize(
    ("text", "message"),
    [("0.6", "START:END"), ("0.7:0.3", "START < END"), ("0:1.5", "END <= 1"), ("a:b", "START:END"),
     ("nan:1", "START < END")],
)  # fmt: skip
def test_a_bad_period_is_one_line(text: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        Period.parse(text)


def test_winnings_need_a_number_of_hands() -> None:
    with pytest.raises(ConfigError, match="min_bb_per_100 needs min_hands"):
        Selection(min_bb_per_100=0)
    with pytest.raises(ConfigError, match="min_hands must be"):
        Selection(min_hands=0)


def test_cli_options(month: Path, tmp_path: Path) -> None:
    runner = CliRunner()
    out = tmp_path / "t.parquet"
    result = runner.invoke(app, ["ingest", str(month), "-o", str(out), "--period", "0:0.6",
                                 "--min-hands", "3", "--min-bb-per-100", "20", "-q"])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert kept(pq.read_table(out).to_pydict()) == {(1, "B"), (3, "B"), (5, "B")}
    result = runner.invoke(app, ["ingest", str(month), "-o", str(out), "--player", "C",
                                 "--player", "A", "-q"])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert json.loads(summary_path(out).read_text())["selection"]["expert"] == ["A", "C"]
    for bad in (["--period", "0.6"], ["--min-bb-per-100", "1"], ["--min-hands", "0"]):
        result = runner.invoke(app, ["ingest", str(month), "-o", str(out), *bad])
        assert result.exit_code == 2, (bad, result.output)
    result = runner.invoke(app, ["ingest", str(month), "-o", str(out), "--player", "nobody"])
    assert result.exit_code == 1
    assert result.output.strip().splitlines()[-1].startswith("error: no decision is left")


# ------------------------------------------------------------------------------- real sample

_HERE = Path(__file__).resolve()
SAMPLE = next(
    (
        path
        for path in (root / "shared" / "irc-sample" / "holdem" / "199504" for root in
                     (_HERE.parents[2], _HERE.parents[3]))
        if path.is_dir()
    ),
    None,
)  # fmt: skip
real_sample = pytest.mark.skipif(SAMPLE is None, reason="real IRC sample not present")


def pdb_results(folder: Path, before: int | None) -> dict[str, tuple[int, int]]:
    """Heads-up hands and chips won per player before ``before``, straight from the pdb
    files (every line with 11 or 13 fields, once per player and hand)."""
    seen, out = set(), defaultdict(lambda: [0, 0])
    for path in sorted((folder / "pdb").iterdir()):
        for line in path.read_bytes().decode("latin-1").splitlines():
            fields = line.split()
            if len(fields) not in (11, 13) or fields[2] != "2":
                continue
            stamp = int(fields[1])
            if (before is not None and stamp >= before) or (fields[0], stamp) in seen:
                continue
            seen.add((fields[0], stamp))
            out[fields[0]][0] += 1
            out[fields[0]][1] += int(fields[10]) - int(fields[9])
    return {player: (hands, chips) for player, (hands, chips) in out.items()}


@real_sample
@pytest.mark.parametrize("bar", [0.0, 5.0])
def test_real_winners_in_the_early_60_percent(tmp_path: Path, bar: float) -> None:
    assert SAMPLE is not None
    whole, rows = ingest(SAMPLE, tmp_path / "whole.parquet")
    summary, chosen = ingest(
        SAMPLE, tmp_path / "early.parquet", period=Period(end=0.6), min_hands=200,
        min_bb_per_100=bar,
    )  # fmt: skip
    assert summary.selection is not None
    (period,) = summary.selection.months
    assert period.hands == 13426 and period.period_hands == 8055  # floor(0.6 * 13,426)
    assert period.after_timestamp is not None
    results = pdb_results(SAMPLE, period.after_timestamp)
    winners = {
        p
        for p, (hands, chips) in results.items()
        if hands >= 200 and chips / 10 / hands * 100 >= bar
    }
    assert winners and set(summary.selection.expert) <= winners
    stamps, players = np.array(rows["timestamp"]), np.array(rows["player"], dtype=object)
    expected = (stamps < period.after_timestamp) & np.isin(players, list(winners))
    assert len(chosen["timestamp"]) == summary.rows == expected.sum() > 0
    assert set(summary.selection.expert) == set(players[expected])
    assert steps(summary)[0] == (Filter.ALL, len(set(rows["player"])), whole.kept_hands, whole.rows)
    assert summary.buckets_add_up and summary.buckets_total == whole.buckets_total


@real_sample
def test_real_parts_are_disjoint_and_cover_the_month(tmp_path: Path) -> None:
    assert SAMPLE is not None
    _, whole = ingest(SAMPLE, tmp_path / "whole.parquet")
    early, first = ingest(SAMPLE, tmp_path / "early.parquet", period=Period(end=0.6))
    late, second = ingest(SAMPLE, tmp_path / "late.parquet", period=Period(start=0.6))
    assert max(first["timestamp"]) < min(second["timestamp"])
    assert len(first["timestamp"]) + len(second["timestamp"]) == len(whole["timestamp"])
    assert first["timestamp"] + second["timestamp"] == whole["timestamp"]
    assert early.selection is not None and late.selection is not None
    assert early.selection.months[0].period_hands + late.selection.months[0].period_hands == 13426


def test_with_imputed_folds_the_selection_comes_first(tmp_path: Path) -> None:
    """--folds impute on a synthetic month: the behaviour model and the draws see the
    expert's rows of the period alone, and the buckets still add up."""
    from pokerirl.game.synth import write_synthetic_month
    from pokerirl.poker.folds import ImputeConfig
    from pokerirl.poker.impute import ingest_imputed

    month = write_synthetic_month(tmp_path / "irc", hands=300, seed=3)
    selection = Selection(period=Period(end=0.5), players=("TightBot",))
    out = tmp_path / "t.parquet"
    config = ImputeConfig(behaviour_rounds=0, behaviour_epochs=1)
    summary = ingest_imputed([month], out, config, selection=selection)
    rows = pq.read_table(out).to_pydict()
    assert summary.selection is not None and summary.folds is not None
    (period,) = summary.selection.months
    assert period.period_hands == 150 and period.after_timestamp is not None
    assert set(rows["player"]) == {"TightBot"} and any(rows["imputed"])
    assert max(rows["timestamp"]) < period.after_timestamp
    assert summary.dropped["outside_period"] > 0 and summary.dropped["not_the_expert"] > 0
    assert summary.buckets_add_up


def test_each_month_is_cut_apart_and_the_statistics_add_up(tmp_path: Path) -> None:
    """Two months of the same hands: each cut at its own 60%; over both, A has 8 early hands,
    B and C 6 each, so --min-hands 8 keeps A alone."""
    hdb, roster, pdb = month_lines(HANDS)
    april = write_month(tmp_path / "irc", month="199504", hdb=hdb, hroster=roster, pdb=pdb)
    may = write_month(tmp_path / "irc", month="199505", hdb=hdb, hroster=roster, pdb=pdb)
    out = tmp_path / "t.parquet"
    summary = ingest_table(
        [april, may], out, selection=Selection(period=Period(end=0.6), min_hands=8)
    )
    assert summary.selection is not None
    assert [(m.month, m.hands, m.period_hands) for m in summary.selection.months] == [
        ("holdem/199504", 10, 6),
        ("holdem/199505", 10, 6),
    ]
    assert summary.selection.expert == ("A",)
    rows = pq.read_table(out).to_pydict()
    assert sorted({hand_id.rsplit("/", 1)[0] for hand_id in rows["hand_id"]}) == [
        "holdem/199504",
        "holdem/199505",
    ]
    assert kept(rows) == {(1, "A"), (5, "A"), (6, "A")} and summary.rows == 24


def test_months_spilled_to_parts_give_the_same_selection(
    month: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from pokerirl.datasets import ingest as ingest_module

    (tmp_path / "held").mkdir()
    (tmp_path / "spilled").mkdir()
    early = {"period": Period(end=0.6), "min_hands": 3, "min_bb_per_100": 0.0}
    held, _ = ingest(month, tmp_path / "held" / "t.parquet", **early)
    monkeypatch.setattr(ingest_module, "SPILL_BYTES", 0)  # every month goes to a part file
    spilled, _ = ingest(month, tmp_path / "spilled" / "t.parquet", **early)
    assert (tmp_path / "spilled" / "t.parquet").read_bytes() == (
        tmp_path / "held" / "t.parquet"
    ).read_bytes()
    assert spilled.selection == held.selection and spilled.rows == held.rows == 20
