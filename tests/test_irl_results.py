"""The typed results of reward learning: epoch metrics, run results and summaries, as JSON
and back (the files keep every key, in order)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import torch

from pokerirl.datasets.toy import toy_expert_table
from pokerirl.irl import EpochMetrics, RunResult, RunsSummary, load_config
from pokerirl.irl.run import CurveStats, MeanStd, summarize
from pokerirl.poker import train_runs

torch.set_num_threads(1)

LINE = (
    '{"epoch": 3, "disc_loss": 1.25, "policy_adv_loss": 0.5, "val_alignment": 0.625, '
    '"val_policy_dist": [0.25, 0.75], "eval_return": -120.5}'
)


def test_epoch_metrics_round_trip_to_the_same_bytes() -> None:
    line = EpochMetrics.from_json(json.loads(LINE))
    assert json.dumps(line.to_json()) == LINE
    assert line.epoch == 3 and line["val_alignment"] == 0.625
    assert list(line) == list(json.loads(LINE))  # epoch first, then the order written
    assert line == json.loads(LINE) and EpochMetrics.from_json(line.to_json()) == line
    assert line.scalars() == {
        "disc_loss": 1.25, "policy_adv_loss": 0.5, "val_alignment": 0.625, "eval_return": -120.5
    }  # fmt: skip
    with pytest.raises(TypeError):
        line["val_alignment"] = 0.0  # type: ignore[index]
    with pytest.raises(ValueError, match="another 'epoch'"):
        EpochMetrics(epoch=1, metrics={"epoch": 2})


def _result(seed: int, alignments: list[float], bc: float) -> RunResult:
    return RunResult(
        out=f"runs/run-{seed}",
        seed=seed,
        metrics=tuple(
            EpochMetrics(epoch=e + 1, metrics={"val_alignment": a, "dist": [a, 1 - a]})
            for e, a in enumerate(alignments)
        ),
        baselines={"bc": bc},
        samples_per_second=100.0 + seed,
        train_rows=90,
        val_rows=10,
    )


def test_run_results_round_trip() -> None:
    result = _result(0, [0.5, 0.75], 0.5)
    data = result.to_json()
    assert list(data) == [
        "out", "seed", "metrics", "baselines", "samples_per_second", "train_rows", "val_rows"
    ]  # fmt: skip
    assert RunResult.from_json(json.loads(json.dumps(data))) == result


def test_summarize_is_typed_and_writes_what_it_always_wrote() -> None:
    summary = summarize([_result(0, [0.5, 0.75], 0.5), _result(1, [0.25, 0.25], 1.0)])
    assert summary.seeds == (0, 1) and summary.epochs == (1, 2)
    assert list(summary.metrics) == ["val_alignment"]  # lists are not averaged
    assert summary.metrics["val_alignment"].mean == [0.375, 0.5]
    assert summary.baselines["bc"] == MeanStd(mean=0.75, std=pytest.approx(np.sqrt(0.125)))
    stds = list(summary.metrics["val_alignment"].std)
    assert summary.to_json() == {
        "runs": 2,
        "seeds": [0, 1],
        "epochs": [1, 2],
        "metrics": {"val_alignment": {"mean": [0.375, 0.5], "std": stds}},
        "baselines": {"bc": {"mean": 0.75, "std": summary.baselines["bc"].std}},
    }
    assert RunsSummary.from_json(summary.to_json()) == summary
    assert CurveStats.from_json({"mean": [1.0], "std": [0.0]}).to_json() == {
        "mean": [1.0], "std": [0.0]
    }  # fmt: skip


def test_train_runs_files_read_back_typed(tmp_path: Path) -> None:
    table = tmp_path / "table.parquet"
    pq.write_table(toy_expert_table(num_hands=40, seed=5), table)
    config = load_config("hairl", overrides={"epochs": 2, "batch_size": 64})
    summary = train_runs(table, tmp_path / "runs", runs=2, config=config, progress=False)
    text = (tmp_path / "runs" / "summary.json").read_text()
    assert json.dumps(RunsSummary.from_json(json.loads(text)).to_json(), indent=2) + "\n" == text
    assert [r.seed for r in summary.results] == [0, 1]
    first = summary.results[0]
    lines = (tmp_path / "runs" / "run-0" / "metrics.jsonl").read_text().splitlines()
    assert [json.dumps(m.to_json()) for m in first.metrics] == lines
    assert summary.metrics == list(first.metrics) and summary.baselines == first.baselines
    assert summary.results[1].metrics[-1]["epoch"] == 2 and summary.results[1].out


def test_the_settings_enums_are_their_names_in_json_and_fingerprints() -> None:
    from pokerirl.irl import AIRLConfig
    from pokerirl.irl.config import ALGOS, Algo, NoiseSchedule
    from pokerirl.irl.nets import RewardFamily
    from pokerirl.store import fingerprint

    assert json.dumps(Algo.AIRL) == '"airl"' and ALGOS == ("airl", "hairl", "gail")
    config = AIRLConfig(noise_schedule="authors", reward_family="shaped")
    assert config.noise_schedule is NoiseSchedule.AUTHORS
    assert config.reward_family is RewardFamily.SHAPED
    assert json.dumps(config.to_dict()) == json.dumps(
        {k: str(v) if isinstance(v, str) else v for k, v in config.to_dict().items()}
    )
    # `pokerirl train`'s unit identity, as main fingerprinted it before the enums (with the
    # reward weight decay of the time: the default is 0 since issue 31).
    settings = AIRLConfig.for_algo("hairl", reward_weight_decay=5e-3).to_dict()
    unit = {"algo": Algo.HAIRL, "device": "cpu", "settings": settings}
    assert fingerprint(unit) == (
        "sha256:ccea3d3748da9efb737962c9362b235fe8a291d38c79b7d2ec3492b7dd8082d8"
    )
