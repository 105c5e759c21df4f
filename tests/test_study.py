"""``pokerirl study`` end to end at toy sizes: the report's tables, resuming, refusing."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.game.synth import write_synthetic_month
from pokerirl.seeds import seeds_as_written
from pokerirl.studies.poker import StudyError, load_study_report, preset, run_study
from pokerirl.studies.poker.report import FIGURES, render_markdown
from pokerirl.studies.poker.report_types import StudyReport
from pokerirl.tournaments import load_report

TOY = dict(
    runs=2,
    seeds=(0, 1),
    hands=400,
    panel_hands=200,
    agent_hands=600,
    short_agent_hands=300,
    eval_every=300,
    eval_hands=200,
    irl_epochs=2,
    lbr_hands=100,
    jobs=1,
)


@pytest.fixture(scope="module")
def finished(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, list[str]]:
    root = tmp_path_factory.mktemp("study")
    month = write_synthetic_month(root / "irc", hands=600, seed=0)
    said: list[str] = []
    run_study([month], root / "out", preset("quick", **TOY), say=said.append)
    return month, root / "out", said


@pytest.mark.slow
def test_report_json_has_the_issue_names_and_the_tournaments_numbers(
    finished: tuple[Path, Path, list[str]],
) -> None:
    _, out, said = finished
    assert [line[:5] for line in said if line.startswith("[")] == [f"[{k}/6]" for k in range(1, 7)]
    report = json.loads((out / "report.json").read_text())
    assert (report["preset"], report["runs"], report["seeds"], report["hands"]) == (
        "quick",
        2,
        [0, 1],
        400,
    )
    # Table 1 is the tournament stage's own test across training seeds (seed k against seed
    # k: 2 agents per side, independent pairs), with the paper beside.
    tournament = load_report(out / "tournament")
    names = [(Path(m.agent_a).name, Path(m.agent_b).name) for m in tournament.matchups]
    assert names == [("hairl-dqn", "dqn"), ("airl-dqn", "dqn")]
    for key, comparison in zip(
        ("hairl_dqn_vs_dqn", "airl_dqn_vs_dqn"), tournament.comparisons, strict=True
    ):
        row, line = report["table1"][key], comparison.line
        assert row["mbb_per_hand"] == line.mbb_per_hand
        assert row["std_error"] == line.std_error >= comparison.deal_std_error
        assert row["p_value"] == line.p_value
        assert row["p_bonferroni"] == line.p_value_bonferroni
        assert (row["replicated_over"], row["agents_a"], row["agents_b"]) == (
            "training seeds", 2, 2)  # fmt: skip
        assert row["deal_std_error"] == comparison.deal_std_error and row["df"] == 1.0
    assert report["table1"]["hairl_dqn_vs_dqn"]["paper"] == {"mbb_per_hand": 96, "std_error": 14}
    assert report["table1"]["airl_dqn_vs_dqn"]["paper"] == {"mbb_per_hand": -693, "std_error": 34}
    # IRL: mean and std over the runs' own metrics files.
    for algo in ("airl", "hairl"):
        finals = [
            json.loads(
                (out / "irl" / algo / f"run-{k}" / "metrics.jsonl").read_text().split("\n")[-2]
            )["val_alignment"]
            for k in range(2)
        ]
        got = report["irl"][algo]["final_val_alignment"]
        assert got["mean"] == pytest.approx(sum(finals) / 2)
        assert got["std"] == pytest.approx(abs(finals[0] - finals[1]) / 2**0.5)
    assert set(report["irl"]["bc"]["final_val_alignment"]) == {"mean", "std"}
    assert set(report["irl"]["baselines"]) == {"majority", "legal_majority"}
    # RL against random: the last evaluation of every seed.
    for kind, folder in (("dqn", "dqn"), ("airl_dqn", "airl-dqn"), ("hairl_dqn", "hairl-dqn")):
        last = [
            json.loads(
                (out / "agents" / folder / f"seed-{s}" / "metrics.jsonl")
                .read_text()
                .splitlines()[-1]
            )["eval"]["random"]["mbb_per_hand"]
            for s in (0, 1)
        ]
        assert report["rl_vs_random"][kind]["mean"] == pytest.approx(sum(last) / 2)
    # Learned-reward seed k used IRL run k mod runs.
    for seed in (0, 1):
        config = json.loads(
            (out / "agents" / "hairl-dqn" / f"seed-{seed}" / "config.json").read_text()
        )
        assert Path(config["reward"]["run"]).name == f"run-{seed}"
    # The panel: every pair once, antisymmetric, built-ins included.
    panel = report["panel"]
    assert panel["agents"] == ["dqn", "airl_dqn", "hairl_dqn", "random", "call", "raise"]
    matrix = panel["mbb_per_hand"]
    for i in range(6):
        assert matrix[i][i] is None
        for j in range(i + 1, 6):
            assert matrix[i][j] == -matrix[j][i]
            assert panel["std_error"][i][j] == panel["std_error"][j][i] >= 0
    assert matrix[4][5] == 0.0  # call vs raise on duplicate deals: exactly even
    # DQN cells across training seeds; those between two fixed strategies over deals only.
    units = panel["replicated_over"]
    assert units[0][1] == units[1][0] == units[2][5] == "training seeds"
    assert units[3][4] == units[4][5] == "deal seeds only" and units[0][0] is None
    assert matrix[5][3] > 0  # raise beats random
    csv = (out / "panel.csv").read_text().splitlines()
    assert csv[0] == "agent,dqn,airl_dqn,hairl_dqn,random,call,raise" and len(csv) == 7
    for figure in FIGURES.values():
        assert (out / figure).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    markdown = (out / "report.md").read_text()
    head = markdown.split("## Table 1")[0]
    assert "**Unit of replication: training seeds** (2 agents per DQN kind" in head
    assert "for the 12 pairs with a DQN kind" in markdown and "for the 3 between" in markdown
    assert "+96 ± 14" in markdown and "-693 ± 34" in markdown and "Reduced sizes" in markdown
    assert "duplicate" in markdown and "5,000 episodes" in markdown
    # LBR against every member: the mean of its per-seed reports, beside the result vs random.
    from pokerirl.tournaments.exploit import load_lbr_report

    assert panel["lbr_hands"] == 100 and panel["lbr_check_until"] == "turn"
    for k, name in enumerate(panel["agents"]):
        seeds = [load_lbr_report(out / "panel" / "lbr" / name / f"seed-{s}") for s in (0, 1)]
        assert {r.config.hands for r in seeds} == {100}
        assert panel["lbr_mbb_per_hand"][k] == pytest.approx(
            sum(r.lbr_mbb_per_hand for r in seeds) / 2)  # fmt: skip
        assert panel["lbr_std_error"][k] > 0
    assert "How exploitable each agent is" in markdown


def units_of(out: Path) -> dict[Path, tuple[bytes, int]]:
    """Every unit's record and outputs that training or playing writes (bytes, mtime): the
    summaries recomputed from them on every run are left out."""
    names = ("unit.json", "*.unit.json", "seed-*.json", "experiment-*.json", "*.pt", "*.parquet")
    found = {p for name in names for p in out.rglob(name)
             if p.is_file() and "stages" not in p.parts}  # fmt: skip
    return {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(found)}


def every_file(out: Path) -> dict[Path, tuple[bytes, int]]:
    """Every file under ``out``: its bytes and modification time."""
    return {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(out.rglob("*"))
            if p.is_file()}  # fmt: skip


@pytest.mark.slow
def test_rerun_reuses_every_unit_and_a_changed_setting_is_refused(
    finished: tuple[Path, Path, list[str]],
) -> None:
    month, out, _ = finished
    before = (out / "report.json").read_bytes()
    units = units_of(out)
    said: list[str] = []
    run_study([month], out, preset("quick", **TOY), say=said.append)
    assert [line[:5] for line in said if line.startswith("[")] == [f"[{k}/6]" for k in range(1, 7)]
    assert units_of(out) == units  # nothing trained, played or rewritten
    assert not (out / "stages").exists()  # unit records suffice
    assert (out / "report.json").read_bytes() == before  # same inputs, same bytes
    files = every_file(out)
    changed = preset("quick", **{**TOY, "panel_hands": 300})
    refused = r"is a study made with other settings \(panel_hands 200 -> 300\); nothing was"
    with pytest.raises(ValueError, match=refused):
        run_study([month], out, changed)
    # More IRL runs change which run each agent seed learns from (seed s on run s mod runs):
    # refused before the new runs are trained or any summary or figure is rewritten.
    with pytest.raises(ValueError, match=r"\(runs 2 -> 3\); nothing was written"):
        run_study([month], out, preset("quick", **{**TOY, "runs": 3}))
    assert every_file(out) == files
    # --overwrite recomputes the changed units only: the panel's seeds.
    result = run_study([month], out, changed, overwrite=True)
    again = units_of(out)
    assert {p for p in units if again[p] != units[p]} == {
        p for p in units if "panel" in p.relative_to(out).parts}  # fmt: skip
    assert result.report.panel.hands == 300
    assert result.report.to_json()["table1"] == json.loads(before)["table1"]


@pytest.mark.slow
def test_report_command_prints_the_study_report(finished: tuple[Path, Path, list[str]]) -> None:
    _, out, _ = finished
    result = CliRunner().invoke(app, ["report", str(out)])
    assert result.exit_code == 0, result.output
    assert result.output.startswith("# pokerirl study (quick preset)")
    as_json = CliRunner().invoke(app, ["report", str(out), "--format", "json"])
    assert json.loads(as_json.output) == load_study_report(out).to_json()
    # A tournament folder still prints as before.
    tournament = CliRunner().invoke(app, ["report", str(out / "tournament")])
    assert tournament.exit_code == 0 and "hairl-dqn" in tournament.output


MAIN_REPORT = Path(__file__).parent / "data" / "study_report_main.json"  # main's, authors toy


def _round_trips(folder: Path) -> StudyReport:
    """``folder/report.json`` loads typed and writes back the same bytes, key order and all."""
    text = (folder / "report.json").read_text()
    loaded = load_study_report(folder)
    assert json.dumps(loaded.to_json(), indent=2) + "\n" == text
    assert StudyReport.from_json(json.loads(text)) == loaded
    return loaded


def test_a_report_json_written_by_main_round_trips(tmp_path: Path) -> None:
    (tmp_path / "report.json").write_bytes(MAIN_REPORT.read_bytes())
    loaded = _round_trips(tmp_path)
    assert loaded.table1_authors is not None and loaded.reward_cards is not None
    assert render_markdown(loaded).startswith("# pokerirl study (authors preset)")
    # An algorithm a given reward replaced, and a report written before "measured": the same.
    data = json.loads(MAIN_REPORT.read_text())
    data["irl"]["airl"] = {"replaced_by": "authors:reward.pt"}
    del data["rl_vs_random"]["measured"]
    (tmp_path / "report.json").write_text(json.dumps(data, indent=2) + "\n")
    replaced = _round_trips(tmp_path)
    assert "replaced by `authors:reward.pt`" in render_markdown(replaced)
    assert "the last evaluation of training" in render_markdown(replaced)


@pytest.mark.slow
def test_the_study_report_round_trips(finished: tuple[Path, Path, list[str]]) -> None:
    _, out, _ = finished
    loaded = _round_trips(out)
    assert render_markdown(loaded) == (out / "report.md").read_text()


def test_bad_settings_are_one_line() -> None:
    with pytest.raises(StudyError, match="unknown preset 'fast'"):
        preset("fast")
    with pytest.raises(StudyError, match="runs >= 1"):
        preset("quick", runs=0)
    with pytest.raises(StudyError, match=r"LBR hands even and >= 0 \(got 3\)"):
        preset("quick", lbr_hands=3)
    assert preset("quick").lbr_hands == 500 and preset("paper").lbr_hands == 10_000
    with pytest.raises(ValueError, match="bad seed range 'a-b'"):
        seeds_as_written("a-b")
    assert seeds_as_written("5,0-2") == (5, 0, 1, 2)  # the study keeps the order written
    with pytest.raises(StudyError, match="seeds distinct"):
        preset("quick", seeds=seeds_as_written("0-2,1"))


def test_cli_refuses_repeated_seeds_before_any_work(tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = ["study", str(tmp_path / "missing"), "--out", str(out), "--seeds", "0-2,1", "-q"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2
    assert result.output == "error: bad study settings: seeds distinct\n"
    assert not out.exists()


def test_cli_refuses_a_missing_source(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        app, ["study", str(tmp_path / "missing"), "--out", str(tmp_path / "out"), "-q"]
    )
    assert result.exit_code == 1
    assert "missing: no such file or folder" in result.output


AUTHORS_TOY = dict(
    runs=2, hands=400, panel_hands=200, agent_hands=300, short_agent_hands=300,
    eval_every=100, eval_hands=100, irl_epochs=2, authors_repeats=3, authors_games=100, jobs=1,
    lbr_hands=0,
)  # fmt: skip


@pytest.mark.slow
def test_the_authors_preset_reports_both_statistics(tmp_path: Path) -> None:
    month = write_synthetic_month(tmp_path / "irc", hands=400, seed=1)
    said: list[str] = []
    config = preset("authors", **AUTHORS_TOY)
    assert config.seeds == (0, 1) and config.agent_preset == "authors"
    result = run_study([month], tmp_path / "out", config, say=said.append)
    assert [line[:5] for line in said if line.startswith("[")] == [f"[{k}/7]" for k in range(1, 8)]
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    for name in ("hairl_dqn_vs_dqn", "airl_dqn_vs_dqn"):
        row = report["table1_authors"][name]
        for key in ("mean", "paper_style_se", "se_over_experiments", "duplicate_mbb_per_hand",
                    "per_experiment"):  # fmt: skip
            assert key in row
        assert len(row["per_experiment"]) == 2
        assert row["duplicate_mbb_per_hand"] == report["table1"][name]["mbb_per_hand"]
        assert row["mean"] == pytest.approx(sum(row["per_experiment"]) / 2)
    # The IRL runs used the authors' settings; the agents their preset, playing kept.pt.
    irl = json.loads((tmp_path / "out" / "irl" / "hairl" / "run-1" / "config.json").read_text())
    assert irl["hyperparameters"]["disc_action"] == "distribution"
    assert irl["hyperparameters"]["noise_schedule"] == "authors"
    assert irl["hyperparameters"]["activation"] == "leaky_relu"
    assert irl["hyperparameters"]["supervised_form"] == "sum_mse"
    agent = json.loads(
        (tmp_path / "out" / "agents" / "hairl-dqn" / "seed-1" / "config.json").read_text()
    )
    assert agent["plays"] == "kept" and agent["dqn"]["learning_rate"] == 5e-4
    assert Path(agent["reward"]["run"]).name == "run-1"
    for algo in ("airl", "hairl"):
        card = report["reward_cards"][algo]
        assert card["runs"] == 2 and set(card["argmax_share"]) == {"call", "raise", "fold", "check"}
    for figure in report["figures"].values():
        assert (tmp_path / "out" / figure).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "The authors' protocol" in result.markdown and "Reward cards" in result.markdown
    loaded = load_study_report(tmp_path / "out")
    assert loaded.to_json() == report == result.report.to_json()


def _main_stage(root: Path, name: str, settings: dict) -> str:
    """Write ``stages/<name>.json`` as main's ``Study.stage`` finished it; return its print."""
    import hashlib

    identity = {"stage": name, "settings": settings}
    text = json.dumps(identity, sort_keys=True, separators=(",", ":"))
    print_ = f"sha256:{hashlib.sha256(text.encode()).hexdigest()}"
    body = {"format": "pokerirl-study-stage/1", "stage": name, "fingerprint": print_,
            "settings": settings, "finished": True, "result": {}}  # fmt: skip
    (root / "stages").mkdir(exist_ok=True)
    (root / "stages" / f"{name}.json").write_text(json.dumps(body, indent=1) + "\n")
    return print_


@pytest.mark.slow
def test_a_study_folder_of_main_is_reused_or_refused_naming_its_stage_record(
    tmp_path: Path,
) -> None:
    """main kept the table's and a single IRL run's record in stages/*.json, not beside them:
    with those (main's formula), a rerun recomputes no unit; with other settings in them, it
    is refused in one line naming the stage record."""
    month = write_synthetic_month(tmp_path / "irc", hands=600, seed=0)
    out = tmp_path / "out"
    config = preset("quick", **{**TOY, "runs": 1})
    first = run_study([month], out, config)
    # As main left it: no record beside the table or in the single runs, stage records instead.
    (out / "expert.unit.json").unlink()
    for algo in ("airl", "hairl"):
        (out / "irl" / algo / "unit.json").unlink()
    sources = {"files": [
        [str(p.resolve()), p.stat().st_size, p.stat().st_mtime_ns]
        for p in sorted(q for q in month.rglob("*") if q.is_file())]}  # fmt: skip
    ingest_print = _main_stage(out, "ingest", {"sources": sources})
    irl = {"runs": 1, "epochs": 2, "seed": 0, "upstream": ingest_print}
    _main_stage(out, "irl", irl)
    units = units_of(out)
    result = run_study([month], out, config)
    assert units_of(out) == units  # no unit recomputed
    assert result.report == first.report
    # main's irl stage made with other settings: refused, naming its record.
    _main_stage(out, "irl", {**irl, "epochs": 3})
    with pytest.raises(ValueError, match=r"stages/irl.json was made with another configuration "
                                         r"\(settings.epochs 3 -> 2\)"):  # fmt: skip
        run_study([month], out, config)
    assert units_of(out) == units


def test_a_study_folder_takes_more_seeds_and_refuses_other_changes(tmp_path: Path) -> None:
    """claim_folder: the settings recorded at the first run; growing seeds is an extension,
    anything else a one-line refusal that writes nothing; settings added since an older
    folder was made are not compared, and an older folder's finished report speaks for it."""
    from pokerirl.studies.common import STUDY_JSON, claim_folder

    root = tmp_path / "study"
    settings = {"runs": 2, "seeds": [0, 1], "hands": 400}
    claim_folder(root, settings, overwrite=False, grows=("seeds",))
    recorded = (root / STUDY_JSON).read_bytes()
    for change, named in (({"runs": 3}, "runs 2 -> 3"), ({"seeds": [1, 2]}, "seeds"),
                          ({"hands": 500, "seeds": [0, 1, 2]}, "hands 400 -> 500")):  # fmt: skip
        with pytest.raises(StudyError, match=rf"made with other settings \({named}"):
            claim_folder(root, {**settings, **change}, overwrite=False, grows=("seeds",))
        assert (root / STUDY_JSON).read_bytes() == recorded
    grown = {**settings, "seeds": [0, 1, 2], "lbr_hands": 20}  # lbr_hands: added since
    claim_folder(root, grown, overwrite=False, grows=("seeds",))
    assert json.loads((root / STUDY_JSON).read_text())["settings"] == grown
    claim_folder(root, {**grown, "runs": 3}, overwrite=True, grows=("seeds",))
    assert json.loads((root / STUDY_JSON).read_text())["settings"]["runs"] == 3
    older = tmp_path / "older"  # no study.json: its report's settings
    with pytest.raises(StudyError, match=r"\(runs 2 -> 3\)"):
        claim_folder(older, {**settings, "runs": 3}, overwrite=False, before=lambda: settings)
    assert not older.exists()


def strict_json_files(folder: Path) -> int:
    """Parse every JSON and JSON-lines file under ``folder`` refusing NaN and Infinity (which
    Python writes by default and no other JSON reader accepts); the number of files read."""

    def refuse(constant: str) -> None:
        raise ValueError(f"bare {constant}")

    count = 0
    for path in sorted(folder.rglob("*.json*")):
        if path.suffix not in (".json", ".jsonl"):
            continue
        text = path.read_text()
        for line in text.splitlines() if path.suffix == ".jsonl" else [text]:
            if line.strip():
                try:
                    json.loads(line, parse_constant=refuse)
                except ValueError as error:
                    raise AssertionError(f"{path}: {error}") from None
        count += 1
    return count


@pytest.mark.slow
def test_every_json_file_of_a_study_is_strict_json(finished: tuple[Path, Path, list[str]]) -> None:
    _, out, _ = finished
    assert strict_json_files(out) > 20


def test_two_studies_of_the_same_sources_ingest_the_same_bytes(tmp_path: Path) -> None:
    """The summary names the table by its place in the study folder, not by the unit's staging
    folder (a random suffix), so two study folders hold the same bytes."""
    from pokerirl.execution import Backend
    from pokerirl.studies.poker.pipeline import Execution, Study, ingest_stage

    month = write_synthetic_month(tmp_path / "irc", hands=60, seed=0)
    written = {}
    for name in ("first", "second"):
        root = tmp_path / name
        root.mkdir()
        study = Study(root, preset("quick", **TOY), Execution(Backend(jobs=1), progress=False))
        summary = ingest_stage(study, [month]).summary
        assert summary["table"] == "expert.parquet"
        written[name] = {p.name: p.read_bytes() for p in root.iterdir()}
    assert sorted(written["first"]) == [
        "expert.parquet", "expert.summary.json", "expert.unit.json"]  # fmt: skip
    assert written["first"] == written["second"]
