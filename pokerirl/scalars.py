"""Runs' scalars for the tools people watch training with (``--log-dir DIR``).

Every run folder keeps its ``metrics.jsonl`` (the record). :func:`export_scalars` copies
each one found under a command's output into ``DIR/<the run's path>/``: as TensorBoard event
files, written by torch's ``SummaryWriter`` (needs the ``tensorboard`` package: ``pip install
'pokerirl[logs]'``), and as ``progress.csv``, the layout SB3's CSV logger writes (a header of
scalar names, one row per step). Nested values are named by their path
(``eval/random/mbb_per_hand``); the step is the line's ``epoch``, ``hands`` or ``timesteps``.
A rerun writes the copies again, so they always match the records.

>>> lines = [{"epoch": 1, "disc_loss": 0.7, "eval": {"random": {"mbb": 3}}, "note": "x"}]
>>> scalar_rows(lines)
[(1, {'disc_loss': 0.7, 'eval/random/mbb': 3.0})]
"""

from __future__ import annotations

import csv
import io
import math
import os
import shutil
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from pokerirl.atomic import write_text
from pokerirl.errors import InputError, MissingExtra
from pokerirl.jsonio import read_json_lines

METRICS = "metrics.jsonl"
CSV_FILE = "progress.csv"  # SB3's name for the same table
STEP_KEYS = ("epoch", "hands", "timesteps")  # what counts a run's lines, first found wins


def _numbers(value: Any, prefix: str = "") -> Iterator[tuple[str, float]]:
    if isinstance(value, bool):
        yield prefix, float(value)
    elif isinstance(value, int | float):
        if math.isfinite(value):
            yield prefix, float(value)
    elif isinstance(value, Mapping):
        for key, item in value.items():
            yield from _numbers(item, f"{prefix}/{key}" if prefix else str(key))


def scalar_rows(lines: Sequence[Mapping[str, Any]]) -> list[tuple[int, dict[str, float]]]:
    """Each metrics line as (step, {name: value}): its finite numbers, nested ones by path,
    the step key itself left out (lists and text are not scalars)."""
    rows = []
    for index, line in enumerate(lines):
        key = next((k for k in STEP_KEYS if isinstance(line.get(k), int)), None)
        step = int(line[key]) if key is not None else index
        rows.append((step, {name: value for name, value in _numbers(line) if name != key}))
    return rows


def _csv(rows: Sequence[tuple[int, Mapping[str, float]]]) -> str:
    names = sorted({name for _, scalars in rows for name in scalars})
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["step", *names])
    for step, scalars in rows:
        writer.writerow([step, *(scalars.get(name, "") for name in names)])
    return buffer.getvalue()


def _summary_writer() -> Any:
    try:
        from torch.utils.tensorboard import SummaryWriter
    except ImportError as error:  # torch's writer needs the tensorboard package
        raise MissingExtra(
            f"TensorBoard scalars need tensorboard (pip install 'pokerirl[logs]'): {error}"
        ) from None
    return SummaryWriter


def export_scalars(out: str | os.PathLike[str], log_dir: str | os.PathLike[str]) -> list[Path]:
    """Copy the scalars of every run under ``out`` (each folder with a ``metrics.jsonl``,
    ``out`` itself included) into ``log_dir``, mirroring their paths; returns the folders
    written. A run's folder there is replaced whole: no stale events from a run before."""
    out, log_dir = Path(out), Path(log_dir)
    if log_dir.exists() and not log_dir.is_dir():
        raise InputError(f"{log_dir} exists and is not a folder")
    runs = sorted(p.parent for p in out.rglob(METRICS) if not _hidden(p.relative_to(out)))
    if not runs:
        return []
    writer_class = _summary_writer()
    written = []
    for run in runs:
        lines = read_json_lines(run / METRICS)
        target = log_dir / run.relative_to(out)
        shutil.rmtree(target, ignore_errors=True)
        target.mkdir(parents=True)
        rows = scalar_rows(lines)
        writer = writer_class(log_dir=str(target))
        try:
            for step, scalars in rows:
                for name, value in scalars.items():
                    writer.add_scalar(name, value, global_step=step)
        finally:
            writer.close()
        write_text(target / CSV_FILE, _csv(rows))
        written.append(target)
    return written


def _hidden(relative: Path) -> bool:
    """A staging folder's (``.run-0.new-*``): not a finished run."""
    return any(part.startswith(".") for part in relative.parts)
