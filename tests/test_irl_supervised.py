"""The supervised term's two forms on discrete actions (issue 20): ours is the cross-entropy of
π at the expert's action; the authors' (``supervised_form="sum_mse"``) is
``mse_loss(π's probabilities, one-hot a_E, reduction="sum")`` over the batch."""

from __future__ import annotations

import numpy as np
import torch

from pokerirl.irl.adversarial import train
from pokerirl.irl.config import AIRLConfig
from pokerirl.irl.transitions import Transitions

torch.set_num_threads(1)


def toy(n: int, seed: int) -> Transitions:
    """a = 1 if s0 > 0 else 0, with 3 actions (action 2 never taken)."""
    rng = np.random.default_rng(seed)
    obs = rng.uniform(-1, 1, (n, 4)).astype(np.float32)
    return Transitions.from_arrays(obs, (obs[:, 0] > 0).astype(np.int64), groups=np.arange(n),
                                   num_actions=3)  # fmt: skip


def supervised_only(form: str, data: Transitions) -> list[dict]:
    config = AIRLConfig.for_algo("hairl", epochs=3, batch_size=64, alpha=1.0, policy_lr=3e-3,
                                 supervised_form=form, seed=0)  # fmt: skip
    return train(data, data, config=config, progress=False, adversarial=False).metrics


def test_sum_mse_is_the_summed_squared_error_of_the_probabilities() -> None:
    data = toy(1024, 0)
    ours, theirs = supervised_only("mean_mse", data), supervised_only("sum_mse", data)
    # Three actions, nearly uniform π at the start: per row ≈ (1 - 1/3)² + 2 (1/3)² = 2/3
    # summed over a batch of 64, against a cross-entropy of ≈ ln 3 per row (a mean).
    assert 64 * 0.5 < theirs[0]["policy_sup_loss"] < 64 * 0.7
    assert 0.9 < ours[0]["policy_sup_loss"] < 1.2
    # Both fit the rule; the summed form's loss falls by a large factor too.
    assert theirs[-1]["policy_sup_loss"] < 0.5 * theirs[0]["policy_sup_loss"]
    assert theirs[-1]["val_alignment"] > 0.9 and ours[-1]["val_alignment"] > 0.9


def test_sum_mse_trains_a_different_policy_than_the_cross_entropy() -> None:
    data = toy(512, 1)
    ours, theirs = supervised_only("mean_mse", data), supervised_only("sum_mse", data)
    assert ours[0]["policy_loss"] != theirs[0]["policy_loss"]
