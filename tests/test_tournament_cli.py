"""`pokerirl tournament` and `pokerirl report`: both matchup forms, the report files agree with
each other and with `pokerirl match`, and bad input is a one-line error."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread
from testkit import folder_bytes
from typer.testing import CliRunner

from pokerirl.cli import app

runner = CliRunner()


def _tournament(*args: str) -> dict:
    result = runner.invoke(app, ["tournament", *args, "--quiet"])
    assert result.exit_code == 0, result.output
    out = Path(args[args.index("--out") + 1])
    return json.loads((out / "report.json").read_text())


@pytest.fixture(scope="module")
def two_matchups(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("report")
    _tournament(
        "--vs",
        "random",
        "raise",
        "call",
        "--hands",
        "2000",
        "--seeds",
        "0-2",
        "--out",
        str(out),
        "--jobs",
        "1",
    )
    return out


def test_vs_plays_each_agent_against_the_base(two_matchups: Path) -> None:
    data = json.loads((two_matchups / "report.json").read_text())
    pairs = [(m["agent_a"], m["agent_b"]) for m in data["matchups"]]
    assert pairs == [("raise", "random"), ("call", "random")]
    assert data["family"]["per_seed_tests"] == 6 and data["family"]["pooled_tests"] == 2
    assert data["config"] == {
        "hands": 2000,
        "seeds": [0, 1, 2],
        "duplicate": True,
        "batch_size": 65536,
        "alpha": 0.05,
    }
    assert data["versions"]["rlcard"] == "1.2.0"
    for key in (
        "mbb_per_hand",
        "std_error",
        "ci95",
        "p_value",
        "p_value_bonferroni",
        "p_value_holm",
    ):
        assert key in data["matchups"][0]["pooled"] and key in data["matchups"][0]["seeds"][0]


def _markdown_rows(text: str, columns: int) -> list[list[str]]:
    rows = [
        [cell.strip() for cell in line.strip("|").split("|")]
        for line in text.splitlines()
        if line.startswith("| ") and not line.startswith("| Model")
    ]
    return [row for row in rows if len(row) == columns]


def _payoff(cell: str) -> tuple[float, float]:
    mean, se = cell.split("±")
    return float(mean), float(se)


def test_markdown_json_and_csv_agree(two_matchups: Path) -> None:
    data = json.loads((two_matchups / "report.json").read_text())
    markdown = (two_matchups / "report.md").read_text()
    with open(two_matchups / "per_seed.csv", newline="") as file:
        rows = list(csv.DictReader(file))
    seeds = [(m, s) for m in data["matchups"] for s in m["seeds"]]
    assert len(rows) == len(seeds) == 6
    for row, (m, s) in zip(rows, seeds, strict=True):
        assert (row["agent_a"], row["agent_b"], int(row["seed"])) == (
            m["agent_a"],
            m["agent_b"],
            s["seed"],
        )
        for key in ("mbb_per_hand", "std_error", "p_value", "p_value_bonferroni", "p_value_holm"):
            assert float(row[key]) == s[key]  # full precision in both
        assert [float(row["ci95_low"]), float(row["ci95_high"])] == s["ci95"]
        assert row["significant_bonferroni"] == str(s["significant_bonferroni"])
    per_seed_md = _markdown_rows(markdown, 9)
    assert len(per_seed_md) == 6
    for cells, (m, s) in zip(per_seed_md, seeds, strict=True):
        assert cells[:3] == [m["agent_a"], m["agent_b"], str(s["seed"])]
        mean, se = _payoff(cells[3])
        assert mean == pytest.approx(s["mbb_per_hand"], abs=0.005)
        assert se == pytest.approx(s["std_error"], abs=0.005)
        assert cells[8] == ("yes" if s["significant_bonferroni"] else "no")
    # Results: one comparison per matchup (one agent per side: its pooled line, deal seeds).
    pooled_md = _markdown_rows(markdown, 12)
    assert len(pooled_md) == 2
    for cells, m in zip(pooled_md, data["matchups"], strict=True):
        assert cells[2:4] == ["1, 1", "deal seeds only"]
        mean, se = _payoff(cells[4])
        assert mean == pytest.approx(m["pooled"]["mbb_per_hand"], abs=0.005)
        assert se == pytest.approx(m["pooled"]["std_error"], abs=0.005)
        assert float(cells[7]) == pytest.approx(m["pooled"]["p_value"], rel=5e-3)
        assert cells[11] == f"{m['seeds_significant_bonferroni']}/3"
    assert "p < 0.05/6 = 0.008333" in markdown and "p < 0.05/2 = 0.025" in markdown


def test_png_is_an_image(two_matchups: Path) -> None:
    image = imread(two_matchups / "per_seed.png")
    assert image.ndim == 3 and image.shape[0] > 100 and image.shape[1] > 100
    assert np.unique(image.reshape(-1, image.shape[2]), axis=0).shape[0] > 10  # not blank


def test_report_prints_markdown_and_json(two_matchups: Path) -> None:
    xml = runner.invoke(app, ["report", str(two_matchups), "--format", "xml"])
    assert xml.exit_code == 2 and "unknown --format 'xml'" in xml.stderr
    text = runner.invoke(app, ["report", str(two_matchups)])
    assert text.exit_code == 0 and text.output == (two_matchups / "report.md").read_text()
    as_json = runner.invoke(app, ["report", str(two_matchups), "--format", "json"])
    assert as_json.exit_code == 0
    assert json.loads(as_json.output) == json.loads((two_matchups / "report.json").read_text())


def test_tournament_agrees_with_match_and_reruns_identically(tmp_path: Path) -> None:
    first = _tournament(
        "random",
        "call",
        "--hands",
        "2000",
        "--seeds",
        "4",
        "--no-duplicate",
        "--out",
        str(tmp_path / "a"),
    )
    again = _tournament(
        "random",
        "call",
        "--hands",
        "2000",
        "--seeds",
        "4",
        "--no-duplicate",
        "--out",
        str(tmp_path / "b"),
    )
    match = runner.invoke(
        app,
        [
            "match",
            "random",
            "call",
            "--hands",
            "2000",
            "--seed",
            "4",
            "--no-duplicate",
            "--format",
            "json",
        ],
    )
    summary = json.loads(match.stdout.strip().splitlines()[-1])
    seed = first["matchups"][0]["seeds"][0]
    assert seed["mbb_per_hand"] == pytest.approx(summary["mbb_per_hand"], rel=1e-12)
    assert seed["std_error"] == pytest.approx(summary["std_error"], rel=1e-9)
    assert first == again  # timings are in timings.json, not the report


@pytest.mark.parametrize(
    ("args", "code", "message"),
    [
        (["raise", "call", "--hands", "2"], 2, "hands must be at least 4"),
        (["raise", "call", "--seeds", "5-3"], 2, "empty seed range"),
        (["raise", "runs/missing-dqn"], 1, "runs/missing-dqn: no such agent folder"),
        (["raise"], 2, "give two agents"),
        (["raise", "call", "random"], 2, "give two agents"),
        (["--vs", "call"], 2, "needs at least one agent"),
    ],
)
def test_bad_input_is_a_one_line_error(
    tmp_path: Path, args: list[str], code: int, message: str
) -> None:
    result = runner.invoke(app, ["tournament", *args, "--out", str(tmp_path), "-q"])
    assert result.exit_code == code and result.stdout == ""
    assert re.fullmatch(rf"error: .*{re.escape(message)}.*\n", result.stderr)


def test_report_errors(tmp_path: Path) -> None:
    missing = runner.invoke(app, ["report", str(tmp_path)])
    assert missing.exit_code == 1 and "no report.json" in missing.output
    (tmp_path / "report.json").write_text('{"format": "something else"}')
    other = runner.invoke(app, ["report", str(tmp_path)])
    assert other.exit_code == 1 and "not a pokerirl-tournament/2 report" in other.output


SMALL = ["--hands", "4", "--seeds", "0-1", "--jobs", "1", "-q"]


def test_other_matchups_into_a_report_folder_are_refused_unless_overwrite(tmp_path: Path) -> None:
    out = tmp_path / "t"
    first = runner.invoke(app, ["tournament", "random", "call", "--out", str(out), *SMALL])
    assert first.exit_code == 0, first.output
    before = folder_bytes(out)
    assert {"report.md", "report.json", "per_seed.csv", "per_seed.png"} <= before.keys()

    for other, theirs in [  # another matchup, or more of them
        (["raise", "call"], "raise-vs-call"),
        (["--vs", "call", "random", "raise"], "random-vs-call, raise-vs-call"),
    ]:
        second = runner.invoke(app, ["tournament", *other, "--out", str(out), *SMALL])
        assert second.exit_code == 1 and second.stdout == ""
        assert second.stderr == (
            f"error: {out}: holds the report of random-vs-call, not {theirs}; "
            "use another --out, or --overwrite to replace it\n"
        )
        assert folder_bytes(out) == before  # every file of the first, byte for byte; nothing new

    again = runner.invoke(app, ["tournament", "random", "call", "--out", str(out), *SMALL])
    assert again.exit_code == 0, again.output  # the same matchup resumes as before
    replaced = runner.invoke(
        app, ["tournament", "raise", "call", "--out", str(out), "--overwrite", *SMALL]
    )
    assert replaced.exit_code == 0, replaced.output
    data = json.loads((out / "report.json").read_text())
    assert [(m["agent_a"], m["agent_b"]) for m in data["matchups"]] == [("raise", "call")]


def test_saved_seeds_of_other_matchups_are_refused_too(tmp_path: Path) -> None:
    out = tmp_path / "t"
    first = runner.invoke(app, ["tournament", "random", "call", "--out", str(out), *SMALL])
    assert first.exit_code == 0, first.output
    for name in ("report.json", "report.md", "per_seed.csv", "per_seed.png", "timings.json"):
        (out / name).unlink()  # as a run stopped before its report leaves it
    before = folder_bytes(out)
    second = runner.invoke(app, ["tournament", "raise", "call", "--out", str(out), *SMALL])
    assert second.exit_code == 1
    assert second.stderr == (
        f"error: {out}: holds the saved seeds of random-vs-call, not raise-vs-call; "
        "use another --out, or --overwrite to replace it\n"
    )
    assert folder_bytes(out) == before
