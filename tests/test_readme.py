"""The README's command block, run top to bottom on tiny sizes, so that it cannot drift.

Each line runs as written in a fresh folder, with only its sizes shrunk (:data:`TINY`); a
line the table does not know fails the test, so a new README command must be added here.
"""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pokerirl.cli import app

README = Path(__file__).resolve().parents[1] / "README.md"
GYM = ["--runs", "1", "--transitions", "400", "--epochs", "1", "--eval-episodes", "1"]
GYM += ["--timesteps", "400", "--jobs", "1"]
AGENT = ["--hands", "256", "--eval-every", "256", "--eval-hands", "50", "--replay-init", "64"]

# Command prefix -> (replacements in the line, flags added): tiny sizes, nothing else.
TINY: dict[str, tuple[dict[str, str], list[str]]] = {
    "data list": ({}, []),
    "synth": ({"--hands 10000": "--hands 300"}, []),
    "ingest": ({}, []),
    "train": ({}, ["--epochs", "1"]),
    "reward-card": ({}, []),
    "agent train": ({}, AGENT),
    "match": ({"--hands 400000": "--hands 1000"}, []),
    "tournament": ({"--seeds 0-19": "--seeds 0-1"}, ["--hands", "200", "--jobs", "1"]),
    "study": ({"--preset quick": "--preset smoke"}, ["--jobs", "1"]),
    "sweep": ({}, ["--preset", "smoke", "--jobs", "1"]),
    "gym study": ({}, GYM),
}
# Lines too long to run here, and the test that runs them at toy sizes instead.
ELSEWHERE = {"demo": "tests/test_demo.py::test_demo_is_the_study_on_synthetic_data"}


def command_block(path: Path = README, after: str = "## The commands") -> list[str]:
    """The commands of ``path``'s first bash block after ``after``, comments stripped."""
    section = path.read_text().split(after, 1)[1]
    block = re.search(r"```bash\n(.*?)```", section, re.S)
    assert block is not None, f"{path.name}: no ```bash block after {after!r}"
    lines = [line.split("  #", 1)[0].strip() for line in block.group(1).splitlines()]
    return [line for line in lines if line]


def _command(words: list[str]) -> str:
    """The longest known command at the start of a line's words (``agent train``)."""
    known = [name for name in (*TINY, *ELSEWHERE) if words[: len(name.split())] == name.split()]
    assert known, f"README: {' '.join(words)!r} is not in tests/test_readme.py's TINY table"
    return max(known, key=len)


def test_the_block_is_the_papers_pipeline_with_every_command_known() -> None:
    lines = command_block()
    assert all(line.startswith("pokerirl ") for line in lines)
    commands = [_command(shlex.split(line)[1:]) for line in lines]
    assert commands[:4] == ["synth", "ingest", "train", "reward-card"]
    # docs/cli.md opens with the same block, less the Gymnasium line.
    assert set(command_block(README.parent / "docs" / "cli.md", "# ")) <= set(lines)
    for where in ELSEWHERE.values():
        path, test = where.split("::")
        assert f"def {test}(" in (README.parent / path).read_text(), where


def _run(lines: list[str]) -> list[str]:
    """Run each line at its tiny size (:data:`TINY`); the commands run, in order."""
    ran = []
    for line in lines:
        words = shlex.split(line)[1:]
        name = _command(words)
        if name in ELSEWHERE:
            continue
        replaced, added = TINY[name]
        for old, new in replaced.items():
            assert old in line, f"README: {line!r} no longer says {old!r}"
            line = line.replace(old, new)
        result = CliRunner().invoke(app, [*shlex.split(line)[1:], *added])
        assert result.exit_code == 0, f"{line}\n{result.output}"
        ran.append(name)
    return ran


@pytest.mark.slow
def test_the_readme_command_block_runs_top_to_bottom(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    ran = _run(command_block())
    assert len(ran) == len(command_block()) - len(ELSEWHERE)
    # What the block promises exists: the agents its tournament line plays, the reports.
    assert (tmp_path / "agents" / "dqn" / "seed-2" / "model.pt").is_file()
    # The tournament is the several-agents form: 3 x 3 agents, tested across training seeds.
    report = json.loads((tmp_path / "report" / "report.json").read_text())
    (comparison,) = report["comparisons"]
    assert comparison["replication"] == "training seeds"
    assert (comparison["agents_a"], comparison["agents_b"]) == (3, 3)
    assert (tmp_path / "runs" / "hairl" / "reward_card.json").is_file()
    assert (tmp_path / "report" / "report.md").is_file()
    assert (tmp_path / "study" / "report.md").is_file()
    assert (tmp_path / "sweep" / "choose" / "sweep.md").is_file()
    assert (tmp_path / "gym" / "report.md").is_file()


def test_the_readme_names_no_path_beside_the_clone() -> None:
    text = README.read_text()
    assert "../shared" not in text and "irc-sample" not in text
    # The first screen says how to reach pokerirl after make demo.
    quick_start = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    assert "source .venv/bin/activate" in quick_start and "irc-199504" in quick_start


@pytest.mark.slow
def test_the_real_data_block_runs_with_nothing_beside_the_clone(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The README's real-hands block, from a folder with no ../shared, an empty home and an
    empty data cache: the shipped irc-199504 is all it reads."""
    work = tmp_path / "fresh" / "clone"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("POKERIRL_DATA", str(tmp_path / "cache"))
    assert not any((parent / "shared").exists() for parent in work.parents[:3])
    lines = command_block(after="## Real hands")
    assert any("irc-199504" in line for line in lines)
    assert _run(lines) == ["data list", "ingest", "train", "study"]
    assert (work / "hands.parquet").is_file()
    assert (work / "runs" / "real" / "reward.pt").is_file()
    assert (work / "study-real" / "report.md").is_file()
