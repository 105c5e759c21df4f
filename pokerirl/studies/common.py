"""What every study shares: its error, presets with overrides, reading the units' JSONL
metrics, mean ± std bands and Markdown tables (``mean_std`` is :mod:`pokerirl.meanstd`'s).

>>> print("\\n".join(markdown_table(["", "ours"], [["AIRL", "0.5"]])))
| | ours |
|---|---|
| AIRL | 0.5 |
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from pokerirl.errors import ConfigError, Remedy
from pokerirl.jsonio import parse_json, read_bytes, read_json_lines
from pokerirl.settings import with_overrides as _with_overrides

# The files the studies read in their units' folders and write in their own.
METRICS_JSONL = "metrics.jsonl"  # an IRL run's epochs, an RL run's or agent's evaluations
BASELINES_JSON = "baselines.json"  # an IRL run's baselines
SUMMARY_JSON = "summary.json"  # a gym irl folder's summary, and the gym study's own
REPORT_MD, REPORT_JSON = "report.md", "report.json"

Preset = TypeVar("Preset")


class StudyError(ConfigError):
    """Bad study settings, or a study folder that does not fit them; the message is one line."""


def with_overrides(presets: Mapping[str, Preset], name: str, **overrides: Any) -> Preset:
    """:func:`pokerirl.settings.with_overrides`, its one-line errors as :class:`StudyError`."""
    try:
        return _with_overrides(presets, name, **overrides)
    except ValueError as error:  # ConfigError, or the preset's own checks
        raise StudyError(str(error)) from None


def study_folder(out: str | os.PathLike[str]) -> Path:
    """``out`` as a study's folder (made later, by the study); refused where it is a file."""
    folder = Path(out)
    if folder.exists() and not folder.is_dir():
        raise StudyError(f"{folder} exists and is not a folder", remedy=Remedy.ELSEWHERE)
    return folder


STUDY_JSON = "study.json"  # the settings a study folder was made with
STUDY_FORMAT = "pokerirl-study-settings/1"


def claim_folder(
    root: Path,
    settings: Mapping[str, Any],
    *,
    overwrite: bool,
    grows: Sequence[str] = (),
    before: Callable[[], Mapping[str, Any] | None] = lambda: None,
    implied: Mapping[str, Any] | None = None,
) -> None:
    """Check, before a study writes anything in ``root``, that it holds no study made with
    other ``settings`` (JSON); then record them in ``root/study.json``.

    A folder's settings are its ``study.json``'s, or for a folder of an older pokerirl
    ``before()``'s (its finished report's). A rerun may change only the lists named in
    ``grows``, and only by adding to them (more seeds: new units beside the finished ones);
    settings added since the folder was made are not compared, except those of ``implied``:
    settings a record leaves out when they have these values (so that the folders of before
    keep their bytes), compared as if written. Any other change is refused in one line naming
    it, unless ``overwrite``: then the units it changes are recomputed.
    """
    path = root / STUDY_JSON
    try:
        recorded: str | None = read_bytes(path).decode("utf-8")  # bounded: /dev/zero is damage
    except FileNotFoundError:
        recorded = None
    except (OSError, ValueError):  # unreadable, or not text: damaged
        recorded = ""
    old = before() if recorded is None else _recorded_settings(recorded)
    new = json.loads(json.dumps(settings))  # as JSON reads it back: tuples are lists
    if isinstance(old, Mapping) and not overwrite:
        filled = json.loads(json.dumps(implied or {}))
        old, compared = {**filled, **old}, {**filled, **new}
        kept = {key: compared[key] for key in old if key in compared}
        if any(key not in compared for key in old):
            kept = compared  # a setting this pokerirl no longer has: a change
        for key in grows:
            if key in kept and key in old and set(old[key]) <= set(kept[key]):
                kept[key] = old[key]
        if kept != dict(old):
            from pokerirl.store import describe_changes

            raise StudyError(
                f"{root} is a study made with other settings "
                f"({describe_changes(dict(old), kept)}); nothing was written",
                remedy=Remedy.RECOMPUTE,
            )
    text = json.dumps({"format": STUDY_FORMAT, "settings": new}, indent=2) + "\n"
    if recorded != text:
        from pokerirl.atomic import write_text

        root.mkdir(parents=True, exist_ok=True)
        write_text(path, text)


def _recorded_settings(text: str) -> Any:
    """The settings a ``study.json`` holds; None when it is damaged (the units' own records
    still guard every output)."""
    try:
        found = parse_json(text, where="study.json")
        return found["settings"] if found.get("format") == STUDY_FORMAT else None
    except (ValueError, TypeError, KeyError, AttributeError):
        return None


def read_jsonl(path: Path) -> list[dict[str, Any]]:
    """The JSON objects of a ``metrics.jsonl`` (blank lines skipped): a study reading the
    lines of its own units (RL curves are :func:`pokerirl.gym.rl.read_curve`'s)."""
    return read_json_lines(path)


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
