"""Mean and sample std over runs or seeds: the one ``MeanStd`` that every summary and report
writes, as ``{"mean": ..., "std": ...}``, and the one :class:`Curve` (a mean and a std at each
point).

The std is the sample one (ddof 1), and 0 for a single value.

>>> mean_std([1.0, 3.0])
MeanStd(mean=2.0, std=1.4142135623730951)
>>> mean_std([1.0, 3.0]).to_json()
{'mean': 2.0, 'std': 1.4142135623730951}
>>> MeanStd.from_json({"mean": 1.5, "std": None}).to_json()
{'mean': 1.5, 'std': None}
>>> mean_std_curve([[1.0, 2.0], [3.0, 2.0]])
([2.0, 2.0], [1.4142135623730951, 0.0])
>>> Curve.of([[1.0, 2.0], [3.0, 2.0]], timesteps=[10, 20]).to_json()
{'timesteps': [10, 20], 'mean': [2.0, 2.0], 'std': [1.4142135623730951, 0.0]}
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pokerirl.serial import Omit, Serializable, meta


@dataclass(frozen=True, kw_only=True)
class MeanStd(Serializable):
    """A value's mean and std over runs or seeds. None: not measured, or (a std) a value the
    authors give as a single line (or a summary.json older than the field lacks)."""

    mean: float | None
    std: float | None = None

    @property
    def measured(self) -> tuple[float, float]:
        """``(mean, std)`` of a value measured over runs, where both are known."""
        assert self.mean is not None and self.std is not None, self
        return self.mean, self.std


def mean_and_std(values: Sequence[float] | np.ndarray) -> tuple[float, float]:
    """The mean and sample std of ``values``, as floats."""
    array = np.asarray(values, dtype=float)
    std = float(array.std(ddof=1)) if array.size > 1 else 0.0
    return float(array.mean()), std


def mean_std(values: Sequence[float] | np.ndarray) -> MeanStd:
    """The mean and sample std of ``values``."""
    mean, std = mean_and_std(values)
    return MeanStd(mean=mean, std=std)


def mean_std_curve(
    rows: Sequence[Sequence[float]] | np.ndarray,
) -> tuple[list[float], list[float]]:
    """Mean and sample std at each point over the rows (one row per run or seed)."""
    array = np.asarray(rows, dtype=float)
    mean = array.mean(axis=0)
    std = array.std(axis=0, ddof=1) if array.shape[0] > 1 else np.zeros_like(mean)
    return mean.tolist(), std.tolist()


@dataclass(frozen=True, kw_only=True)
class Curve(Serializable):
    """Mean and sample std over runs or seeds at each point: an epoch, an action, or (where
    ``timesteps`` is given) the training steps or hands at which each run was evaluated."""

    timesteps: list[int] | None = field(default=None, metadata=meta(omit=Omit.NONE))
    mean: list[float]
    std: list[float]

    @classmethod
    def of(
        cls, rows: Sequence[Sequence[float]] | np.ndarray, *, timesteps: list[int] | None = None
    ) -> Curve:
        """Over the first axis of ``rows`` (one row per run or seed)."""
        mean, std = mean_std_curve(rows)
        return cls(timesteps=timesteps, mean=mean, std=std)
