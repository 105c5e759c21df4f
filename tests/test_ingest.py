"""Ingest on hand-written IRC months: one test per quirk of the format."""

from __future__ import annotations

import io
import json
import tarfile
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from irc_fixtures import (
    ALL_IN,
    LONE_BLIND,
    NO_CAP,
    ODD,
    ODD_NICK,
    ZED_FIRST,
    write_month,
)
from pokerirl.cli import app
from pokerirl.datasets.ingest import IngestSummary, ingest_table, summary_path
from pokerirl.datasets.table import REQUIRED_COLUMNS
from pokerirl.holdem import CALL, CHECK, RAISE
from pokerirl.parsers.irc_sources import IngestError


def rows_of(table_path: Path, timestamp: int) -> dict[str, list]:
    table = pq.read_table(table_path)
    picked = table.filter(np.asarray(table.column("timestamp")) == timestamp)
    return picked.to_pydict()


@pytest.fixture
def month(tmp_path: Path) -> Path:
    return write_month(tmp_path / "irc")


@pytest.fixture
def ingested(month: Path, tmp_path: Path) -> tuple[Path, dict]:
    out = tmp_path / "table.parquet"
    return out, ingest_table([month], out).to_json()


def test_every_hand_lands_in_exactly_one_bucket(ingested: tuple[Path, dict]) -> None:
    _, summary = ingested
    assert summary["hands_read_total"] == 12
    assert summary["kept_hands"] == 5
    assert summary["dropped"] == {
        "not_heads_up": 1,
        "missing_pdb_line": 1,
        "roster_mismatch": 1,
        "cards_concealed": 2,
        "malformed_line": 1,
        "skipped_channel": 0,
        "duplicate_hand": 1,
        "inconsistent_hand": 0,
    }
    assert summary["buckets_add_up"] and summary["buckets_total"] == 12
    assert summary["malformed_examples"] == [f"{summary['sources'][0]}/hdb:10: not an hdb line"]


def test_summary_file_matches_and_schema_has_required_columns(
    ingested: tuple[Path, dict],
) -> None:
    out, summary = ingested
    assert json.loads(summary_path(out).read_text()) == summary
    schema = pq.read_schema(out)
    assert set(REQUIRED_COLUMNS) <= set(schema.names)
    assert str(schema.field("obs").type) == "fixed_size_list<element: uint8>[72]"
    assert str(schema.field("legal_mask").type) == "fixed_size_list<element: bool>[4]"
    assert str(schema.field("raise_nums").type) == "fixed_size_list<element: int8>[4]"
    assert summary["rows"] == pq.read_metadata(out).num_rows
    assert sum(summary["rows_per_action"].values()) == summary["rows"]


def test_the_summary_reads_back_typed_and_writes_the_same_bytes(
    ingested: tuple[Path, dict], tmp_path: Path
) -> None:
    out, summary = ingested
    text = summary_path(out).read_text()
    typed = IngestSummary.from_json(json.loads(text))
    assert json.dumps(typed.to_json(), indent=2) + "\n" == text
    assert typed.kept_hands == 5 and typed.dropped["duplicate_hand"] == 1
    assert typed.to_json() == summary
    again = ingest_table(typed.sources, tmp_path / "again.parquet")
    assert again.months == typed.months and again.rows == typed.rows


def test_seat_comes_from_pdb_not_roster_order(ingested: tuple[Path, dict]) -> None:
    rows = rows_of(ingested[0], ZED_FIRST)
    # Amy comes first in hroster, but Zed sits in position 1 and acts first on every street.
    assert rows["player"][0] == "Zed" and rows["position"][0] == 1
    first_by_street = {}
    for player, street in zip(rows["player"], rows["street"], strict=True):
        first_by_street.setdefault(street, player)
    assert first_by_street == {0: "Zed", 1: "Zed", 2: "Zed", 3: "Zed"}


def test_kth_character_is_kth_pass(ingested: tuple[Path, dict]) -> None:
    rows = rows_of(ingested[0], ZED_FIRST)
    sequence = list(zip(rows["player"], rows["street"], rows["action"], strict=True))
    assert sequence == [
        ("Zed", 0, "call"),
        ("Amy", 0, "check"),
        ("Zed", 1, "check"),
        ("Amy", 1, "raise"),
        ("Zed", 1, "call"),
        ("Zed", 2, "raise"),
        ("Amy", 2, "call"),
        ("Zed", 3, "check"),
        ("Amy", 3, "check"),
    ]
    assert rows["board"][:3] == ["", "", "2c 7d 9h"]
    assert rows["board"][-1] == "2c 7d 9h Ts Js"
    assert rows["payoff_bb"][0] == -4.0 and rows["payoff_bb"][1] == 4.0
    # The reward is the payoff on each player's last decision only.
    assert rows["is_last"] == [False] * 7 + [True, True]
    assert rows["reward"] == [0.0] * 7 + [-4.0, 4.0]


def test_no_raise_cap_counts_capped_but_keeps_the_raise(ingested: tuple[Path, dict]) -> None:
    rows = rows_of(ingested[0], NO_CAP)
    preflop = [i for i, s in enumerate(rows["street"]) if s == 0]
    assert [rows["action_id"][i] for i in preflop] == [RAISE] * 5 + [CALL]
    fifth = preflop[4]
    assert rows["raises_uncapped"][fifth] == 4 and rows["raise_nums"][fifth][0] == 4
    # RLCard would forbid a fifth raise; the mask still shows the action taken.
    assert rows["legal_mask"][fifth][RAISE]
    assert rows["raise_nums"][preflop[5]] == [4, 0, 0, 0]
    assert rows["raise_nums"][-1] == [4, 0, 0, 0]  # later rounds still see the capped count


def test_all_in_facing_a_bet_is_a_call_and_ends_the_betting(
    ingested: tuple[Path, dict],
) -> None:
    out, summary = ingested
    rows = rows_of(out, ALL_IN)
    assert list(zip(rows["player"], rows["action"], strict=True)) == [
        ("Zed", "call"),
        ("Amy", "check"),
        ("Zed", "raise"),
        ("Amy", "call"),
    ]
    # Zed put in 20 and got 5 back; Amy put in 15 and won 30.
    assert rows["payoff_bb"] == [-1.5, 1.5, -1.5, 1.5]
    assert summary["chips_mismatch_hands"] == 1  # all-in for less than a full bet


def test_lone_blind_lets_position_two_act_first(ingested: tuple[Path, dict]) -> None:
    out, summary = ingested
    rows = rows_of(out, LONE_BLIND)
    assert (rows["player"][0], rows["action_id"][0]) == ("Amy", CALL)
    assert rows["legal_mask"][0] == [True, True, True, False]  # facing the blind
    assert (rows["player"][1], rows["action_id"][1]) == ("Zed", CHECK)
    assert summary["single_blind_hands"] == 1


def test_odd_nick_is_read_from_the_line(ingested: tuple[Path, dict]) -> None:
    rows = rows_of(ingested[0], ODD_NICK)
    assert ODD in rows["player"]
    assert rows["hand_id"][0] == f"holdem/199504/{ODD_NICK}"


def test_no_fold_rows_and_obs_invariants(ingested: tuple[Path, dict]) -> None:
    table = pq.read_table(ingested[0])
    assert "fold" not in table.column("action").to_pylist()
    obs = np.asarray(table.column("obs").combine_chunks().flatten()).reshape(-1, 72)
    street = np.asarray(table.column("street"))
    assert (obs[:, :52].sum(axis=1) == 2 + np.array([0, 3, 4, 5])[street]).all()
    assert (obs[:, 52:].reshape(-1, 4, 5).sum(axis=2) == 1).all()


def test_crlf_and_lf_give_identical_tables(tmp_path: Path) -> None:
    crlf = write_month(tmp_path / "a", newline="\r\n")
    lf = write_month(tmp_path / "b", newline="\n")
    ingest_table([crlf], tmp_path / "crlf.parquet")
    ingest_table([lf], tmp_path / "lf.parquet")
    assert (tmp_path / "crlf.parquet").read_bytes() == (tmp_path / "lf.parquet").read_bytes()


def test_same_input_gives_byte_identical_table(month: Path, tmp_path: Path) -> None:
    ingest_table([month], tmp_path / "one.parquet")
    ingest_table([month], tmp_path / "two.parquet")
    assert (tmp_path / "one.parquet").read_bytes() == (tmp_path / "two.parquet").read_bytes()


def test_same_month_twice_is_all_duplicates(month: Path, tmp_path: Path) -> None:
    summary = ingest_table([month, month], tmp_path / "t.parquet").to_json()
    assert summary["kept_hands"] == 5
    assert summary["dropped"]["duplicate_hand"] == 1 + 11  # 11 valid hdb lines seen again
    assert summary["buckets_add_up"]


def test_skipped_channel_is_counted(month: Path, tmp_path: Path) -> None:
    nolimit = write_month(
        tmp_path / "irc", channel="nolimit", hdb=["797000000 1 1 2 0/0 0/0 0/0 1/15"]
    )
    summary = ingest_table([tmp_path / "irc"], tmp_path / "t.parquet").to_json()
    assert nolimit.exists()
    assert summary["dropped"]["skipped_channel"] == 1
    assert summary["skipped_channels"] == {"nolimit": 1}
    assert summary["hands_read"] == {"holdem": 12, "nolimit": 1}
    assert summary["buckets_add_up"]


def _tgz(members: dict[str, bytes]) -> bytes:
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tar:
        for name, data in members.items():
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    return buffer.getvalue()


def _month_members(folder: Path, prefix: str) -> dict[str, bytes]:
    return {
        f"{prefix}{path.relative_to(folder).as_posix()}": path.read_bytes()
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


def test_month_archive_and_nested_archive_match_the_folder(month: Path, tmp_path: Path) -> None:
    ingest_table([month], tmp_path / "folder.parquet")
    month_tgz = _tgz(_month_members(month, "holdem/199504/"))
    (tmp_path / "holdem.199504.tgz").write_bytes(month_tgz)
    ingest_table([tmp_path / "holdem.199504.tgz"], tmp_path / "archive.parquet")
    # IRCdata.tgz: month archives inside an archive, with a channel we skip.
    nolimit_tgz = _tgz({"nolimit/199504/hdb": b"797000000 1 1 2 0/0 0/0 0/0 1/15\r\n"})
    (tmp_path / "IRCdata.tgz").write_bytes(
        _tgz({"holdem.199504.tgz": month_tgz, "nolimit.199504.tgz": nolimit_tgz})
    )
    summary = ingest_table([tmp_path / "IRCdata.tgz"], tmp_path / "nested.parquet").to_json()
    folder_bytes = (tmp_path / "folder.parquet").read_bytes()
    assert (tmp_path / "archive.parquet").read_bytes() == folder_bytes
    assert (tmp_path / "nested.parquet").read_bytes() == folder_bytes
    assert summary["dropped"]["skipped_channel"] == 1 and summary["buckets_add_up"]


def test_archive_without_folders_takes_channel_from_its_name(month: Path, tmp_path: Path) -> None:
    (tmp_path / "holdem.199504.tgz").write_bytes(_tgz(_month_members(month, "./")))
    summary = ingest_table([tmp_path / "holdem.199504.tgz"], tmp_path / "t.parquet").to_json()
    assert summary["months"] == ["holdem/199504"] and summary["kept_hands"] == 5


def test_strict_turns_malformed_lines_into_an_error(month: Path, tmp_path: Path) -> None:
    with pytest.raises(IngestError, match=r"hdb:10"):
        ingest_table([month], tmp_path / "t.parquet", strict=True)
    assert not (tmp_path / "t.parquet").exists()


def test_failed_ingest_leaves_existing_output_untouched(month: Path, tmp_path: Path) -> None:
    out = tmp_path / "t.parquet"
    ingest_table([month], out)
    before = out.read_bytes()
    (tmp_path / "broken.tgz").write_bytes(b"not a tar archive at all")
    with pytest.raises(IngestError, match="not a readable tar archive"):
        ingest_table([month, tmp_path / "broken.tgz"], out)
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["/definitely/missing"], "no such file or folder"),
        (["{tmp}/notes.txt"], "not IRC data"),
        (["{tmp}/empty"], "no IRC data here"),
        (["{tmp}/broken.tgz"], "not a readable tar archive"),
    ],
)
def test_cli_bad_source_is_one_line_error(
    tmp_path: Path, arguments: list[str], message: str
) -> None:
    (tmp_path / "notes.txt").write_text("hello")
    (tmp_path / "broken.tgz").write_bytes(b"\x1f\x8b garbage")
    (tmp_path / "empty").mkdir()
    args = [a.format(tmp=tmp_path) for a in arguments]
    result = CliRunner().invoke(app, ["ingest", *args, "--out", str(tmp_path / "t.parquet")])
    assert result.exit_code == 1
    assert message in result.output
    assert "Traceback" not in result.output
    assert not (tmp_path / "t.parquet").exists()


def test_cli_ingest_prints_summary(month: Path, tmp_path: Path) -> None:
    out = tmp_path / "t.parquet"
    result = CliRunner().invoke(app, ["ingest", str(month), "--out", str(out)])
    assert result.exit_code == 0, result.output
    printed = json.loads(result.stdout[result.stdout.index("{") :])
    assert printed == json.loads(summary_path(out).read_text())


@pytest.mark.parametrize(
    ("amy_line", "reason"),
    [
        ("Bk  b     c     k         1000   40   80 As Qc", "a card dealt twice"),
        ("Bk  b     c     k         1000   40   70 Kc Qc", "chips won differ from chips put in"),
        ("Bk  b     k     k         1000   40   80 Kc Qc", "actions: check facing a bet"),
    ],
)
def test_inconsistent_hands_are_counted_with_a_reason(
    tmp_path: Path, amy_line: str, reason: str
) -> None:
    from irc_fixtures import PDB

    pdb = dict(PDB)
    pdb["pdb.Amy"] = [f"Amy       {ZED_FIRST}  2  2 {amy_line}", *PDB["pdb.Amy"][1:]]
    folder = write_month(tmp_path / "irc", pdb=pdb)
    summary = ingest_table([folder], tmp_path / "t.parquet").to_json()
    assert summary["dropped"]["inconsistent_hand"] == 1
    assert summary["inconsistent_reasons"] == {reason: 1}
    assert summary["kept_hands"] == 4 and summary["buckets_add_up"]


def test_stakes_come_from_the_channel(tmp_path: Path) -> None:
    folder = write_month(tmp_path / "irc", channel="holdem2")  # 20-40: big blind of 20 chips
    out = tmp_path / "t.parquet"
    ingest_table([folder], out)
    rows = rows_of(out, ZED_FIRST)
    assert rows["hand_id"][0] == f"holdem2/199504/{ZED_FIRST}"
    assert rows["big_blind"][0] == 20
    assert rows["payoff_bb"][:2] == [-2.0, 2.0]  # 40 chips lost at 20 a big blind


def test_cli_output_that_is_a_folder_is_one_line_error(month: Path, tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["ingest", str(month), "--out", str(tmp_path)])
    assert result.exit_code == 1
    assert "is a folder" in result.output and "Traceback" not in result.output
    assert not list(tmp_path.glob(".*"))  # no temporary files left behind


def test_months_spilled_to_parts_give_the_same_table(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from pokerirl.datasets import ingest as ingest_module
    from pokerirl.game.synth import write_synthetic_month

    months = [write_synthetic_month(tmp_path / f"m{k}", hands=40, seed=k) for k in range(3)]
    held = tmp_path / "held.parquet"
    ingest_table(months, held)
    monkeypatch.setattr(ingest_module, "SPILL_BYTES", 0)  # every month goes to a part file
    spilled = tmp_path / "spilled.parquet"
    ingest_table(months, spilled)
    assert spilled.read_bytes() == held.read_bytes()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # parts gone too
