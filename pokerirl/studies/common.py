"""What every study shares: its error, presets with overrides, reading the units' JSONL
metrics, mean ± std bands and Markdown tables (``mean_std`` is :mod:`pokerirl.meanstd`'s).

>>> print("\\n".join(markdown_table(["", "ours"], [["AIRL", "0.5"]])))
| | ours |
|---|---|
| AIRL | 0.5 |
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from pokerirl.errors import ConfigError, Remedy

# The files the studies read in their units' folders and write in their own.
METRICS_JSONL = "metrics.jsonl"  # an IRL run's epochs, an RL run's or agent's evaluations
BASELINES_JSON = "baselines.json"  # an IRL run's baselines
SUMMARY_JSON = "summary.json"  # a gym irl folder's summary, and the gym study's own
REPORT_MD, REPORT_JSON = "report.md", "report.json"

Preset = TypeVar("Preset")


class StudyError(ConfigError):
    """Bad study settings, or a study folder that does not fit them; the message is one line."""


def with_overrides(presets: Mapping[str, Preset], name: str, **overrides: Any) -> Preset:
    """The preset ``name`` of ``presets`` (frozen dataclasses) with ``overrides`` (None values
    ignored); one-line :class:`StudyError` for an unknown name or a bad value."""
    if name not in presets:
        raise StudyError(f"unknown preset {name!r}; choose one of {', '.join(presets)}")
    changes = {key: value for key, value in overrides.items() if value is not None}
    try:
        return dataclasses.replace(presets[name], **changes)  # type: ignore[type-var]
    except TypeError as error:
        raise StudyError(f"bad study setting: {error}") from None
    except ValueError as error:  # the preset's own checks
        raise StudyError(str(error)) from None


def study_folder(out: str | os.PathLike[str]) -> Path:
    """``out`` as a study's folder (made later, by the study); refused where it is a file."""
    folder = Path(out)
    if folder.exists() and not folder.is_dir():
        raise StudyError(f"{folder} exists and is not a folder", remedy=Remedy.ELSEWHERE)
    return folder


def read_jsonl(path: Path) -> list[dict[str, Any]]:
    """The JSON objects of a ``metrics.jsonl`` (blank lines skipped): a study reading the
    lines of its own units (RL curves are :func:`pokerirl.gym.rl.read_curve`'s)."""
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def band(
    axes: Any,
    x: Sequence[float] | np.ndarray,
    curve: Mapping[str, Any],
    label: str,
    *,
    color: str | None = None,
    alpha: float = 0.25,
) -> None:
    """``curve["mean"]`` as a line and ± ``curve["std"]`` as a shaded band around it."""
    mean, std = np.asarray(curve["mean"]), np.asarray(curve["std"])
    # No color: matplotlib's cycles choose (a color=None would paint every band C0).
    colored = {} if color is None else {"color": color}
    axes.plot(x, mean, label=label, **colored)
    axes.fill_between(x, mean - std, mean + std, alpha=alpha, **colored)


def markdown_table(head: Sequence[str], rows: Iterable[Sequence[str]]) -> list[str]:
    """The lines of a Markdown table; an empty cell is written ``| |``."""

    def line(cells: Sequence[str]) -> str:
        return "|" + "|".join(f" {cell} " if cell else " " for cell in cells) + "|"

    return [line(head), "|" + "---|" * len(head), *(line(row) for row in rows)]
