"""The poker sweep (``pokerirl sweep``): it resumes after a kill with the same bytes, and the
test split is never read by the choice."""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.studies.poker.sweep import (
    Cell,
    Split,
    SweepConfig,
    choose,
    load_sweep,
    sweep_preset,
)

pytestmark = pytest.mark.slow
MONTH = "holdem/200101"
# Files that hold wall-clock times, not results.
UNTIMED = ("timings.json",)


@pytest.fixture(scope="module")
def month(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("synth")
    result = CliRunner().invoke(app, ["synth", "--hands", "3000", "--seed", "0", "--out",
                                      str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    return out / MONTH


def _sweep(month: Path, out: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-c", "from pokerirl.cli import app; app()", "sweep", str(month),
         "--preset", "smoke", "--out", str(out), "-q"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True,
    )  # fmt: skip


def _files(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name not in UNTIMED and ".new-" not in str(p)
    }


@pytest.fixture(scope="module")
def finished(month: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("sweep") / "s"
    run = _sweep(month, out)
    output, _ = run.communicate(timeout=900)
    assert run.returncode == 0, output
    return out, _files(out)


def test_a_sweep_killed_midway_resumes_to_the_same_bytes(
    finished: tuple[Path, dict], month: Path
) -> None:
    out, before = finished
    assert (out / "choose" / "sweep.json").is_file() and (out / "choose" / "sweep.png").is_file()
    # A rerun reuses everything and rewrites the same bytes.
    again = _sweep(month, out)
    assert again.communicate(timeout=900)[0] is not None and again.returncode == 0
    assert _files(out) == before
    # Killed as the agents train, then resumed: the same bytes as the uninterrupted run.
    shutil.rmtree(out)
    killed = _sweep(month, out)
    assert killed.stdout is not None
    for line in killed.stdout:
        if line.startswith("[3/5] agents"):
            os.killpg(killed.pid, signal.SIGKILL)
            break
    killed.wait(timeout=900)
    assert killed.returncode == -signal.SIGKILL
    assert not (out / "choose" / "sweep.json").exists()
    resumed = _sweep(month, out)
    output, _ = resumed.communicate(timeout=900)
    assert resumed.returncode == 0, output
    assert _files(out) == before


def _late_hands_garbled(month: Path, out: Path, fraction: float) -> Path:
    """A copy of ``month`` whose hands after ``fraction`` of it (by time) have their players'
    lines garbled: the test split, damaged."""
    copy = out / MONTH
    shutil.copytree(month, copy)
    stamps = np.unique([int(line.split()[0]) for line in (month / "hdb").read_text().splitlines()])
    cut = stamps[int(np.floor(fraction * len(stamps)))]
    garbled = 0
    for pdb in (copy / "pdb").iterdir():
        lines = pdb.read_text().splitlines()
        for i, line in enumerate(lines):
            fields = line.split()
            if int(fields[1]) >= cut:
                fields[4] = "Qzz"  # no action is written so
                lines[i] = " ".join(fields)
                garbled += 1
        pdb.write_text("\n".join(lines) + "\n")
    assert garbled > 1_000
    return copy


def test_the_test_split_is_never_read_by_the_choice(
    finished: tuple[Path, dict], month: Path, tmp_path: Path
) -> None:
    out, _ = finished
    config = sweep_preset("smoke")
    damaged = _late_hands_garbled(month, tmp_path / "damaged", config.choose_period[1])
    run = _sweep(damaged, tmp_path / "s")
    output, _ = run.communicate(timeout=900)
    assert run.returncode == 0, output
    clean, other = load_sweep(out / "choose"), load_sweep(tmp_path / "s" / "choose")
    assert other.chosen == clean.chosen
    assert [c.to_json() for c in other.cells] == [c.to_json() for c in clean.cells]
    for table in (out / "choose" / "tables").glob("*.parquet"):
        assert (tmp_path / "s" / "choose" / "tables" / table.name).read_bytes() == (
            table.read_bytes()
        )
    # The damage is real: the whole month's counts differ.
    assert other.tables != clean.tables
    # And the test split reads the later hands, which the damage left with nothing to ingest.
    result = CliRunner().invoke(app, ["sweep", str(damaged), "--preset", "smoke", "--out",
                                      str(tmp_path / "s"), "--test", "-q"])  # fmt: skip
    assert result.exit_code != 0 and "error:" in result.output


def test_the_test_split_runs_the_chosen_cell_on_the_later_hands(
    finished: tuple[Path, dict], month: Path
) -> None:
    out, _ = finished
    result = CliRunner().invoke(app, ["sweep", str(month), "--preset", "smoke", "--out",
                                      str(out), "--test", "-q"])  # fmt: skip
    assert result.exit_code == 0, result.output
    test = load_sweep(out / "test")
    chosen = load_sweep(out / "choose").chosen
    assert test.split == Split.TEST and test.chosen is None
    assert [cell.name for cell in test.cells] == [chosen]
    text = (out / "test" / "sweep.md").read_text()
    assert "**test** split: hands 0.6:1" in text and "read by nothing in the choice" in text


def test_the_choice_rule_counts_targets_then_the_head_to_head() -> None:
    from pokerirl.studies.poker.sweep import AgentEval, CellResult, Targets

    def cell(name: str, met: int, h2h: float) -> CellResult:
        names = [f.name for f in dataclasses.fields(Targets)]
        flags = {name: i < met for i, name in enumerate(names)}
        agent = AgentEval(vs={}, shares={}, agrees_with_call=0.5, lbr=100.0, lbr_se=1.0,
                          vs_sparse=h2h)  # fmt: skip
        return CellResult(name=name, axis="base", cell=Cell(), agents=(agent,), sparse=(agent,),
                          reward_agreement=(0.5,), bc_agreement=(0.6,),
                          targets=Targets(**flags))  # fmt: skip

    assert choose([cell("a", 2, 50.0), cell("b", 3, -10.0), cell("c", 3, 5.0)]).name == "c"


def test_bad_sweep_settings_are_one_line_before_anything_runs(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unknown sweep axis 'colour'"):
        SweepConfig(preset="x", axes={"colour": ("red",)})
    with pytest.raises(ValueError, match="opponent must be one of"):
        SweepConfig(preset="x", axes={"opponent": ("nobody",)})
    result = CliRunner().invoke(app, ["sweep", str(tmp_path), "--preset", "nope", "--out",
                                      str(tmp_path / "o")])  # fmt: skip
    assert result.exit_code == 2 and "nope" in result.output
    assert not (tmp_path / "o").exists()
    assert json.dumps(sweep_preset("sample").to_json())  # the preset serializes


def test_the_real_study_preset_is_the_cell_the_shipped_sweep_chose() -> None:
    from pokerirl.irl.config import AIRLConfig
    from pokerirl.studies.poker.config import preset

    shipped = Path(__file__).parents[1] / "docs" / "results" / "poker-real" / "choose"
    result = load_sweep(shipped)
    cell = next(c.cell for c in result.cells if c.name == result.chosen)
    real = preset("real")
    decay = AIRLConfig.for_algo(cell.algo).reward_weight_decay if real.reward_decay is None else (
        real.reward_decay
    )
    assert (real.encoding, real.folds, real.experts, real.algos) == (
        cell.encoding, cell.folds, str(cell.experts), (cell.algo,)
    )
    assert (real.reward_transform, real.payoff_weight, real.opponent, real.agent_hands) == (
        cell.transform, cell.payoff_weight, cell.opponent, cell.hands
    )
    assert decay == cell.reward_decay
