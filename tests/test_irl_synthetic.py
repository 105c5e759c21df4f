"""H-AIRL against AIRL on the synthetic IRC demo data, whose expert rule is known."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from pokerirl.datasets.ingest import ingest_table
from pokerirl.game.synth import write_synthetic_month
from pokerirl.irl import load_config
from pokerirl.poker import train_table


@pytest.fixture(scope="module")
def synthetic_tables(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    tables = []
    for seed in (0, 1, 2):
        root = tmp_path_factory.mktemp(f"synth{seed}")
        folder = write_synthetic_month(root / "irc", hands=6000, seed=seed)
        ingest_table([folder], root / "expert.parquet")
        tables.append(root / "expert.parquet")
    return tables


def test_hairl_beats_majority_and_airl_on_synthetic_demo_data(
    synthetic_tables: list[Path], tmp_path: Path
) -> None:
    torch.set_num_threads(1)
    alignment: dict[str, list[float]] = {"hairl": [], "airl": []}
    majority = []
    for seed, table in enumerate(synthetic_tables):
        for algo in alignment:
            config = load_config(algo, overrides={"epochs": 8, "seed": seed})
            summary = train_table(
                str(table),
                str(tmp_path / f"{algo}{seed}"),
                algo=algo,
                config=config,
                device="cpu",
                progress=False,
            )
            alignment[algo].append(summary.metrics[-1]["val_alignment"])
        majority.append(summary.baselines["majority"])
    hairl, airl = np.array(alignment["hairl"]), np.array(alignment["airl"])
    assert (hairl > np.array(majority) + 0.15).all(), (hairl, majority)
    assert hairl.mean() > airl.mean() + 0.01, (hairl, airl)
