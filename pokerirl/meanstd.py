"""Mean and sample std over runs or seeds: the one ``MeanStd`` that every summary and report
writes, as ``{"mean": ..., "std": ...}``.

The std is the sample one (ddof 1), and 0 for a single value.

>>> mean_std([1.0, 3.0])
MeanStd(mean=2.0, std=1.4142135623730951)
>>> mean_std([1.0, 3.0]).to_json()
{'mean': 2.0, 'std': 1.4142135623730951}
>>> MeanStd.from_json({"mean": 1.5, "std": None}).to_json()
{'mean': 1.5, 'std': None}
>>> mean_std_curve([[1.0, 2.0], [3.0, 2.0]])
([2.0, 2.0], [1.4142135623730951, 0.0])
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pokerirl.errors import InputError


@dataclass(frozen=True, kw_only=True)
class MeanStd:
    """A value's mean and std over runs or seeds. None: not measured, or (a std) a value the
    authors give as a single line."""

    mean: float | None
    std: float | None = None

    def to_json(self) -> dict[str, float | None]:
        return {"mean": self.mean, "std": self.std}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> MeanStd:
        # A summary.json older than a field may lack its std: .get, not [].
        if not isinstance(data, Mapping):
            raise InputError(f"must be an object with a mean and a std, got {data!r}"[:200])
        return cls(mean=data.get("mean"), std=data.get("std"))

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
