"""TrainResult.save: a result trained in the library becomes a run folder that every reader
takes, without training again (issue 34: the public API)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import torch

import pokerirl
from pokerirl.irl import Transitions, load_config


def test_a_trained_result_saves_as_a_run_folder_that_loads_back(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(80, 5)).astype(np.float32)
    data = Transitions.from_arrays(obs, (obs[:, 0] > 0).astype(np.int64), groups=np.arange(80))
    train_data, val_data, _ = data.split(val_fraction=0.25, seed=0)
    config = load_config("airl", overrides={"epochs": 2, "batch_size": 16})
    result = pokerirl.train(train_data, val_data, config=config, progress=False)
    folder = result.save(tmp_path / "run", algo="airl")
    assert json.loads((folder / "config.json").read_text())["algo"] == "airl"
    lines = (folder / "metrics.jsonl").read_text().splitlines()
    assert [json.loads(line)["epoch"] for line in lines] == [1, 2]
    states = torch.as_tensor(obs[:8])
    actions = torch.as_tensor(np.arange(8) % 2)
    with torch.no_grad():
        expected = result.reward(states, torch.nn.functional.one_hot(actions, 2).float())
        policy = result.policy.eval()(states)
    found = pokerirl.load_reward(folder)(obs[:8], np.arange(8) % 2)
    assert np.allclose(np.asarray(found).ravel(), expected.numpy().ravel(), atol=1e-6)
    with torch.no_grad():
        assert torch.allclose(pokerirl.load_policy(folder)(states), policy, atol=1e-6)
