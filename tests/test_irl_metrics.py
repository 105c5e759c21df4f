"""The named epoch metrics (``pokerirl.irl.metrics``) and the one trainer of runs into folders
(``pokerirl.irl.run.train_runs_into``) with its hooks."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest
import torch

from pokerirl.irl import AIRLConfig, Transitions
from pokerirl.irl.adversarial import train
from pokerirl.irl.metrics import Metric, Part
from pokerirl.irl.records import EpochRecord
from pokerirl.irl.run import (
    CONFIG_FILE,
    ObsMap,
    RunHooks,
    load_policy,
    read_baselines,
    read_epochs,
    train_runs_into,
)

torch.set_num_threads(1)


def _discrete(rows: int = 96) -> Transitions:
    rng = np.random.default_rng(0)
    obs = rng.integers(0, 2, size=(rows, 5)).astype(np.float32)
    actions = (obs[:, 0] + 2 * obs[:, 1]).astype(np.int64)
    return Transitions.from_arrays(obs, actions, groups=np.arange(rows) // 2)


def _keys(data: Transitions, **config: object) -> set[str]:
    config = {"epochs": 1, "batch_size": 16, **config}
    result = train(data, data, config=AIRLConfig.for_algo("hairl", **config), progress=False)
    return set(result.metrics[-1]) - {"epoch"}


def test_every_metric_the_trainer_writes_is_named_once() -> None:
    """Discrete (with weights and imputed rows: the per-part alignments) and continuous runs:
    a key the trainer or the evaluation writes without a Metric member fails here."""
    data = _discrete()
    imputed = torch.arange(len(data)) % 3 == 0
    weighted = Transitions.from_arrays(
        data.obs.numpy(), data.actions.numpy(), groups=data.groups,
        weights=np.full(len(data), 0.5), imputed=imputed.numpy(),
    )  # fmt: skip
    rng = np.random.default_rng(1)
    obs = rng.random((64, 3)).astype(np.float32)
    box = Transitions.from_arrays(obs, obs[:, :2] - 0.5, groups=np.arange(64), low=[-1, -1],
                                  high=[1, 1])  # fmt: skip
    written = _keys(data) | _keys(weighted) | _keys(box)
    assert written <= set(Metric), sorted(written - set(Metric))
    assert {Metric.VAL_ALIGNMENT.on(Part.IMPUTED), Metric.VAL_MSE} <= written


def test_a_metric_is_read_through_its_member_from_any_line() -> None:
    line = {"epoch": 2, "val_alignment": 0.5, "val_alignment_observed": 0.25}  # an old line
    assert Metric.VAL_ALIGNMENT.of(line) == 0.5
    assert Metric.VAL_ALIGNMENT.on("observed").of(line) == 0.25
    assert Metric.VAL_MSE.of(line, None) is None
    with pytest.raises(KeyError, match="'val_reward_alignment'"):
        Metric.VAL_REWARD_ALIGNMENT.of(line)
    assert json.dumps({Metric.DISC_LOSS: 0.5}) == '{"disc_loss": 0.5}'  # its key's bytes


class _Returns:
    """An epoch callback: the epoch as each run's "return", and a copy of each policy as
    trained (on mapped observations), to compare with the saved one."""

    def __init__(self) -> None:
        self.policies: list[torch.nn.Module] = []

    def __call__(self, record: EpochRecord) -> list[dict[str, float]]:
        self.policies = [copy.deepcopy(policy).eval() for policy in record.policies]
        return [{Metric.EVAL_RETURN: float(record.epoch), Metric.EVAL_RETURN_STD: 0.0}
                for _ in record.policies]  # fmt: skip


def test_train_runs_into_calls_each_hook_in_its_place(tmp_path: Path) -> None:
    data = _discrete()
    config = AIRLConfig.for_algo("hairl", epochs=2, batch_size=16, seed=3)
    seen: dict[str, object] = {}

    def fit(train_rows: Transitions) -> ObsMap:
        seen["fit_rows"] = len(train_rows)
        shift = train_rows.obs.mean(0)
        return ObsMap(shift=shift, scale=torch.ones(5), record={"shift": shift.tolist()})

    returns = _Returns()

    def callback(obs_map: ObsMap | None) -> _Returns:
        seen["map"] = obs_map
        return returns

    finished: list[Path] = []

    def finish(folder: Path) -> None:  # after the folder is written
        assert (folder / CONFIG_FILE).is_file()
        finished.append(folder)

    hooks = RunHooks(obs_map=fit, baselines=lambda: {"expert": 1.0}, callback=callback,
                     finish=finish)  # fmt: skip
    folders = [tmp_path / "run-0", tmp_path / "run-1"]
    trained = train_runs_into(data, folders, algo="hairl", config=config, hooks=hooks,
                              data_lead={"env": "toy"}, data_notes={"note": 1})  # fmt: skip
    assert finished == folders
    assert [r.seed for r in trained.results] == [3, 4]
    assert seen["fit_rows"] == trained.results[0].train_rows < len(data)  # training rows only
    assert isinstance(seen["map"], ObsMap)
    assert list(read_baselines(folders[1])) == ["majority", "legal_majority", "bc", "expert"]
    assert "expert" not in trained.drawn and "legal_majority" not in trained.drawn  # no mask
    record = json.loads((folders[0] / CONFIG_FILE).read_text())
    keys = list(record["data"])
    assert keys[0] == "env" and keys[-2:] == ["note", "obs_standardization"]
    assert record["hyperparameters"]["seed"] == 3
    lines = read_epochs(folders[1])
    assert [Metric.EVAL_RETURN.of(line) for line in lines] == [1.0, 2.0]
    # The saved policy takes raw observations: the map was folded into its first layer.
    obs_map = seen["map"]
    with torch.no_grad():
        trained_on_mapped = returns.policies[1](obs_map.rows(data).obs, None)
        saved = load_policy(folders[1])(data.obs, None)
    torch.testing.assert_close(saved, trained_on_mapped, atol=1e-5, rtol=1e-5)
    assert not torch.allclose(returns.policies[1](data.obs, None), trained_on_mapped)
