"""IRL on Leduc demonstrations through the IRL core's public entry points: the decisions as
:class:`~pokerirl.irl.Transitions` (36-d observations, four actions, the legal mask), AIRL,
H-AIRL, GAIL and BC (the same policy net with α = 1 and no adversary, as the IRL core's
``bc`` baseline) runs in lock-step, and what each run learned as tables over every
information set: the reward g(s, a) and the policy's probabilities.

The 36-d observation of an information set does not depend on the deal (RLCard's ranks; under
OpenSpiel's rules the suits of a key are not observed), so one row of
:attr:`~pokerirl.game.leduc.infosets.InfoSets.observations` per set is exact.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import StrEnum

import numpy as np

from pokerirl.agents.leduc_specs import policy_table, reward_table
from pokerirl.game.leduc.demos import Demonstrations
from pokerirl.game.leduc.infosets import info_sets

SPLIT_SEED = 0  # one train/validation split of the hands for every run


class Learner(StrEnum):
    """What learns from the demonstrations."""

    AIRL = "airl"
    HAIRL = "hairl"
    GAIL = "gail"
    BC = "bc"  # supervised only: no reward


@dataclass(frozen=True, kw_only=True, eq=False)
class Learned:
    """One run: its reward g (rows x 4; None for BC) and policy (rows x 4 probabilities) at
    every information set, and its last validation alignment."""

    learner: Learner
    seed: int
    reward: np.ndarray | None
    policy: np.ndarray
    val_alignment: float


def transitions(demos: Demonstrations):  # type: ignore[no-untyped-def]  # torch: lazily
    """The decisions as discrete :class:`~pokerirl.irl.Transitions` (one group per hand), as
    ``pokerirl train`` reads a demonstrations file."""
    from pokerirl.datasets.decisions import demos_table
    from pokerirl.poker.data import as_transitions

    return as_transitions(demos_table(demos))


def learn(
    demos: Demonstrations, learner: Learner, *, seeds: tuple[int, ...], epochs: int
) -> list[Learned]:
    """``len(seeds)`` runs of ``learner`` (one split of the hands), each as tables; torch on
    one thread (small nets train fastest on one, and the count is part of the result)."""
    import torch

    from pokerirl.execution import pinned_threads
    from pokerirl.irl import AIRLConfig, train
    from pokerirl.irl.metrics import Metric

    algo = Learner.AIRL if learner is Learner.BC else learner
    config = AIRLConfig.for_algo(algo, epochs=epochs, seed=seeds[0])
    if learner is Learner.BC:
        config = replace(config, alpha=1.0)  # the IRL core's bc baseline
    data, val, _ = transitions(demos).split(val_fraction=config.val_fraction, seed=SPLIT_SEED)
    sets = info_sets(demos.rules)
    found = []
    for seed in seeds:
        # One run at a time: train's hand-derived gradients cover one run, not R in lock-step.
        with pinned_threads(1):
            run = train(data, val, config=replace(config, seed=seed), progress=False,
                        adversarial=learner is not Learner.BC)  # fmt: skip
        with torch.inference_mode():
            reward = None if learner is Learner.BC else reward_table(run.reward, sets)
            found.append(Learned(
                learner=learner, seed=seed, reward=reward, policy=policy_table(run.policy, sets),
                val_alignment=float(Metric.VAL_ALIGNMENT.of(run.metrics[-1])),
            ))  # fmt: skip
    return found


def counted_policy(demos: Demonstrations) -> np.ndarray:
    """Tabular BC: the demonstrations' action frequencies at each information set (uniform
    over the legal actions where a set was never seen)."""
    sets = info_sets(demos.rules)
    counts = np.zeros(sets.legal.shape)
    np.add.at(counts, (demos.row, demos.action), 1.0)
    unseen = counts.sum(axis=1) == 0
    counts[unseen] = sets.legal[unseen]
    return counts / counts.sum(axis=1, keepdims=True)
