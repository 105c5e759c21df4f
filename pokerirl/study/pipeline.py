"""The study pipeline: ingest -> irl -> agents -> tournament -> panel -> report.

Each stage writes its outputs under the study folder and a record ``stages/<stage>.json``
holding a fingerprint of its settings and of the fingerprints of the stages it reads. A rerun:

* skips a stage whose record is finished with the same fingerprint (and whose outputs exist);
* resumes a stage that was started with the same fingerprint but not finished (the units
  below skip what is done: finished agent seeds, saved tournament seeds, finished IRL runs);
* refuses a stage whose fingerprint changed (a setting or an input), with one line naming it,
  unless ``overwrite``: then that stage's outputs are deleted and it is recomputed, and so is
  every stage after it, since their fingerprints include its own.

Every call that trains or plays goes through :class:`Execution`, the one place that decides
where units run (processes now; the execution layer's backends later).
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pokerirl.atomic import write_text
from pokerirl.execution import Backend, fingerprint
from pokerirl.study.config import AGENT_KINDS, BUILT_INS, IRL_ALGOS, StudyConfig, StudyError

if TYPE_CHECKING:  # the layers below load lazily: ``pokerirl report`` needs none of them
    from pokerirl.agents.train import TrainConfig
    from pokerirl.irl.config import AIRLConfig
    from pokerirl.tournaments import TournamentReport

STAGES = ("ingest", "irl", "agents", "tournament", "panel", "report")
RECORD_FORMAT = "pokerirl-study-stage/1"
TABLE = "expert.parquet"
AGENT_FOLDERS = {"dqn": "dqn", "airl_dqn": "airl-dqn", "hairl_dqn": "hairl-dqn"}
SHORT_DQN = "dqn-short"  # sparse DQN at the paper's training length

Say = Callable[[str], None]


@dataclass(frozen=True)
class Execution:
    """Where units run. The single place that calls the training and playing entry points, so
    a backend (local processes or a Ray cluster) is threaded through here and nowhere else."""

    backend: Backend = field(default_factory=Backend)
    progress: bool = False

    def train_runs(
        self, table: Path, out: Path, *, algo: str, runs: int, config: AIRLConfig
    ) -> None:
        from pokerirl.irl.run import train_runs

        # The stage record guards the settings; units of other settings are this stage's own
        # earlier attempt, recomputed (finished runs of the same settings are reused).
        train_runs(
            table,
            out,
            runs=runs,
            algo=algo,
            config=config,
            progress=self.progress,
            overwrite=True,
            backend=self.backend,
        )

    def train_seeds(self, out: Path, config: TrainConfig, seeds: Sequence[int]) -> None:
        from pokerirl.agents.train import train_seeds

        train_seeds(out, config, list(seeds), backend=self.backend, progress=self.progress)

    def tournament(
        self,
        matchups: Sequence[tuple[str, str]],
        *,
        hands: int,
        seeds: Sequence[int],
        out: Path,
        duplicate: bool,
    ) -> TournamentReport:
        from pokerirl.tournaments import run_tournament

        return run_tournament(
            matchups,
            hands=hands,
            seeds=seeds,
            out=out,
            duplicate=duplicate,
            backend=self.backend,
            progress=self.progress,
        )


# --------------------------------------------------------------------------- stage records


def _sources_fingerprint(sources: Sequence[str | os.PathLike[str]]) -> dict[str, Any]:
    """Every source file's path, size and modification time (cheap on a large corpus)."""
    files = []
    for source in sources:
        path = Path(source)
        if not path.exists():
            raise StudyError(f"{path}: no such file or folder")
        found = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
        for item in found:
            stat = item.stat()
            files.append([str(item.resolve()), stat.st_size, stat.st_mtime_ns])
    return {"files": files}


@dataclass(frozen=True)
class Study:
    """A study folder, its settings, and how to run units."""

    root: Path
    config: StudyConfig
    execution: Execution
    overwrite: bool = False
    say: Say = lambda message: None

    def stage(
        self,
        name: str,
        settings: dict[str, Any],
        outputs: Sequence[Path],
        compute: Callable[[], dict[str, Any]],
    ) -> dict[str, Any]:
        """Run ``compute`` unless a finished record with the same fingerprint exists; return
        its result (a JSON-ready dict) and the fingerprint under ``"fingerprint"``."""
        number = f"[{STAGES.index(name) + 1}/{len(STAGES)}]"
        wanted = fingerprint({"stage": name, "settings": settings})
        path = self.root / "stages" / f"{name}.json"
        record = _read_record(path)
        if record is not None:
            if record["fingerprint"] == wanted:
                if record.get("finished") and all(p.exists() for p in outputs):
                    self.say(f"{number} {name}: done already, skipped")
                    return {**record["result"], "fingerprint": wanted}
            elif not self.overwrite:
                raise StudyError(
                    f"{path}: stage {name} was run with other settings or inputs; pass "
                    "--overwrite to recompute it and the stages after it, or choose another --out"
                )
            else:
                for output in outputs:
                    if output.is_dir():
                        shutil.rmtree(output)
                    else:
                        output.unlink(missing_ok=True)
        path.parent.mkdir(parents=True, exist_ok=True)
        started = {"format": RECORD_FORMAT, "stage": name, "fingerprint": wanted}
        write_text(path, json.dumps({**started, "settings": settings, "finished": False}) + "\n")
        self.say(f"{number} {name}")
        result = compute()
        body = {**started, "settings": settings, "finished": True, "result": result}
        write_text(path, json.dumps(body, indent=1) + "\n")
        return {**result, "fingerprint": wanted}


def _read_record(path: Path) -> dict[str, Any] | None:
    try:
        record = json.loads(path.read_text())
    except FileNotFoundError:
        return None
    except (OSError, json.JSONDecodeError) as error:
        raise StudyError(f"{path}: cannot read the stage record ({error})") from None
    if not isinstance(record, dict) or record.get("format") != RECORD_FORMAT:
        raise StudyError(f"{path}: not a study stage record")
    return record


# --------------------------------------------------------------------------- stages


def ingest_stage(study: Study, sources: Sequence[str | os.PathLike[str]]) -> dict[str, Any]:
    from pokerirl.datasets.ingest import ingest

    table = study.root / TABLE

    def compute() -> dict[str, Any]:
        return {"summary": ingest(sources, table, progress=study.execution.progress)}

    settings = {"sources": _sources_fingerprint(sources)}
    return study.stage("ingest", settings, [table], compute)


def run_paths(out: Path, runs: int) -> list[Path]:
    """The run folders ``train_runs`` writes: ``out`` itself for one run, else ``run-<k>``."""
    return [out] if runs == 1 else [out / f"run-{k}" for k in range(runs)]


def _read_jsonl(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def mean_std(values: Sequence[float] | np.ndarray, axis: int | None = None) -> dict[str, Any]:
    """Mean and sample std (ddof 1; 0 for one value), as floats or lists."""
    array = np.asarray(values, dtype=float)
    count = array.shape[0] if axis == 0 else array.size
    mean = array.mean(axis=axis)
    std = array.std(axis=axis, ddof=1) if count > 1 else np.zeros_like(mean)
    if axis is None:
        return {"mean": float(mean), "std": float(std)}
    return {"mean": mean.tolist(), "std": std.tolist()}


def summarize_irl(out: Path, runs: int) -> dict[str, Any]:
    """Per-epoch mean/std over runs of the curves the report draws, final values per run,
    mean action distributions and the baselines."""
    metrics = [_read_jsonl(p / "metrics.jsonl") for p in run_paths(out, runs)]
    found_baselines = [json.loads((p / "baselines.json").read_text()) for p in run_paths(out, runs)]
    epochs = min(len(m) for m in metrics)
    curves = {}
    for key in ("val_alignment", "disc_acc_expert", "disc_acc_policy", "val_reward_alignment"):
        if key in metrics[0][0]:
            values = [[line[key] for line in run[:epochs]] for run in metrics]
            curves[key] = mean_std(values, axis=0)
    final = {key: [run[epochs - 1][key] for run in metrics] for key in curves}
    dists = {}
    for key in ("val_expert_dist", "val_policy_dist"):
        if key in metrics[0][-1]:
            dists[key] = mean_std([run[epochs - 1][key] for run in metrics], axis=0)
    return {
        "runs": runs,
        "epochs": epochs,
        "curves": curves,
        "final": {key: {"values": v, **mean_std(v)} for key, v in final.items()},
        "action_dist": dists,
        "baselines": {
            key: {
                "values": [b[key] for b in found_baselines],
                **mean_std([b[key] for b in found_baselines]),
            }
            for key in found_baselines[0]
        },
    }


def irl_stage(study: Study, ingested: dict[str, Any]) -> dict[str, Any]:
    from pokerirl.irl import load_config

    config = study.config
    table = study.root / TABLE
    outputs = [study.root / "irl" / algo for algo in IRL_ALGOS]

    def compute() -> dict[str, Any]:
        found = {}
        for algo, out in zip(IRL_ALGOS, outputs, strict=True):
            settings = load_config(
                algo, overrides={"epochs": config.irl_epochs, "seed": config.irl_seed}
            )
            done = out / ("summary.json" if config.runs > 1 else "config.json")
            if not done.is_file():  # train_runs stages its folder: present means finished
                study.say(f"      {algo}: {config.runs} runs -> {out}")
                out.parent.mkdir(parents=True, exist_ok=True)
                study.execution.train_runs(table, out, algo=algo, runs=config.runs, config=settings)
            found[algo] = summarize_irl(out, config.runs)
        return found

    settings = {
        "runs": config.runs,
        "epochs": config.irl_epochs,
        "seed": config.irl_seed,
        "upstream": ingested["fingerprint"],
    }
    return study.stage("irl", settings, outputs, compute)


def _final_vs_random(agent_set: Path, seeds: Sequence[int]) -> list[float]:
    return [
        _read_jsonl(agent_set / f"seed-{s}" / "metrics.jsonl")[-1]["eval"]["random"]["mbb_per_hand"]
        for s in seeds
    ]


def _curve(agent_set: Path, seeds: Sequence[int]) -> dict[str, Any]:
    lines = [_read_jsonl(agent_set / f"seed-{s}" / "metrics.jsonl") for s in seeds]
    points = min(len(line) for line in lines)
    values = [[line[i]["eval"]["random"]["mbb_per_hand"] for i in range(points)] for line in lines]
    return {"hands": [lines[0][i]["hands"] for i in range(points)], **mean_std(values, axis=0)}


def agents_stage(study: Study, irl: dict[str, Any]) -> dict[str, Any]:
    from pokerirl.agents.train import TrainConfig
    from pokerirl.game import make_agent, play_match

    config = study.config
    folder = study.root / "agents"
    sets = {kind: folder / name for kind, name in AGENT_FOLDERS.items()}

    def train(out: Path, hands: int, algo: str | None) -> None:
        base = TrainConfig(
            hands=hands,
            seed=config.seeds[0],
            eval_every=min(config.eval_every, hands),
            eval_hands=config.eval_hands,
        )
        if algo is None:
            study.execution.train_seeds(out, base, config.seeds)
            return
        runs = run_paths(study.root / "irl" / algo, config.runs)
        # Seed s learns from IRL run s mod runs: one call per run, its seeds side by side.
        for k, run in enumerate(runs):
            group = [s for s in config.seeds if s % config.runs == k]
            if group:
                learned = replace(base, reward="learned", reward_run=str(run))
                study.execution.train_seeds(out, learned, group)

    def compute() -> dict[str, Any]:
        for kind, out in sets.items():
            algo = None if kind == "dqn" else kind.removesuffix("_dqn")
            study.say(
                f"      {kind}: {len(config.seeds)} seeds x {config.agent_hands:,} hands -> {out}"
            )
            train(out, config.agent_hands, algo)
        short = folder / SHORT_DQN
        study.say(
            f"      dqn (short): {len(config.seeds)} seeds x {config.short_agent_hands:,} hands"
        )
        train(short, config.short_agent_hands, None)
        references = {}
        for name in ("call", "raise"):
            result = play_match(
                make_agent(name), make_agent("random"), hands=config.eval_hands,
                seed=TrainConfig.eval_seed,
            )  # fmt: skip
            references[name] = {"mbb_per_hand": result.mbb_per_hand, "std_error": result.std_error}
        return {
            "final_vs_random": {
                kind: _final_vs_random(out, config.seeds) for kind, out in sets.items()
            },
            "curves": {kind: _curve(out, config.seeds) for kind, out in sets.items()},
            "training_length": {
                "agent_hands": config.agent_hands,
                "short_agent_hands": config.short_agent_hands,
                "long": _final_vs_random(sets["dqn"], config.seeds),
                "short": _final_vs_random(short, config.seeds),
            },
            "references": references,
        }

    settings = {
        "seeds": list(config.seeds),
        "runs": config.runs,
        "agent_hands": config.agent_hands,
        "short_agent_hands": config.short_agent_hands,
        "eval_every": config.eval_every,
        "eval_hands": config.eval_hands,
        "upstream": irl["fingerprint"],
    }
    return study.stage("agents", settings, [folder], compute)


def _line(line: Any) -> dict[str, Any]:
    return {
        "mbb_per_hand": line.mbb_per_hand,
        "std_error": line.std_error,
        "p_value": line.p_value,
        "p_bonferroni": line.p_value_bonferroni,
        "p_holm": line.p_value_holm,
        "n": line.n,
    }


def tournament_stage(study: Study, agents: dict[str, Any]) -> dict[str, Any]:
    config = study.config
    out = study.root / "tournament"
    folder = study.root / "agents"
    baseline = str(folder / AGENT_FOLDERS["dqn"])
    names = ("hairl_dqn", "airl_dqn")

    def compute() -> dict[str, Any]:
        matchups = [(str(folder / AGENT_FOLDERS[name]), baseline) for name in names]
        report = study.execution.tournament(
            matchups, hands=config.hands, seeds=config.seeds, out=out, duplicate=config.duplicate
        )
        found = {}
        for name, matchup in zip(names, report.matchups, strict=True):
            found[f"{name}_vs_dqn"] = {
                **_line(matchup.pooled),
                "per_seed": [s.mbb_per_hand for s in matchup.seeds],
                "seeds_significant_bonferroni": matchup.seeds_significant_bonferroni,
            }
        return found

    settings = {
        "hands": config.hands,
        "seeds": list(config.seeds),
        "duplicate": config.duplicate,
        "upstream": agents["fingerprint"],
    }
    return study.stage("tournament", settings, [out], compute)


def panel_agents(root: Path) -> list[tuple[str, str]]:
    """(name, spec) of every panel member: the agent kinds, then the built-ins."""
    kinds = [(kind, str(root / "agents" / AGENT_FOLDERS[kind])) for kind in AGENT_KINDS]
    return kinds + [(name, name) for name in BUILT_INS]


def panel_stage(study: Study, agents: dict[str, Any]) -> dict[str, Any]:
    config = study.config
    out = study.root / "panel"
    members = panel_agents(study.root)

    def compute() -> dict[str, Any]:
        pairs = [(i, j) for i in range(len(members)) for j in range(i + 1, len(members))]
        report = study.execution.tournament(
            [(members[i][1], members[j][1]) for i, j in pairs],
            hands=config.panel_hands,
            seeds=config.seeds,
            out=out / "tournament",
            duplicate=config.duplicate,
        )
        size = len(members)
        mbb: list[list[float | None]] = [[None] * size for _ in range(size)]
        se: list[list[float | None]] = [[None] * size for _ in range(size)]
        for (i, j), matchup in zip(pairs, report.matchups, strict=True):
            mbb[i][j], mbb[j][i] = matchup.pooled.mbb_per_hand, -matchup.pooled.mbb_per_hand
            se[i][j] = se[j][i] = matchup.pooled.std_error
        return {"agents": [name for name, _ in members], "mbb_per_hand": mbb, "std_error": se}

    settings = {
        "hands": config.panel_hands,
        "seeds": list(config.seeds),
        "duplicate": config.duplicate,
        "upstream": agents["fingerprint"],
    }
    return study.stage("panel", settings, [out], compute)
