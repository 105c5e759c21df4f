"""``pokerirl ingest``: IRC hand histories in, one Parquet state-action table out.

>>> # ingest(["holdem/199504"], "table.parquet")  # writes table.parquet and table.summary.json
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from tqdm import tqdm

from pokerirl.datasets.table import SCHEMA, month_table
from pokerirl.encoding import ACTIONS, FOLD
from pokerirl.parsers.irc import (
    DROP_REASONS,
    KEPT,
    IngestError,
    IngestStats,
    check_sources,
    iter_months,
    parse_month,
)
from pokerirl.store import staged_files

# Dictionary encoding and statistics only where they pay: the obs and mask lists are most of
# the bytes, and encoding them is most of the write time.
_STRING_COLUMNS = ["hand_id", "player", "action", "hole_cards", "board", "channel"]
PARQUET_OPTIONS: Mapping[str, Any] = {
    "compression": "zstd",
    "compression_level": 1,
    "use_dictionary": _STRING_COLUMNS,
    "write_statistics": ["hand_id", "timestamp", "player", "street", "action_id", "channel"],
}
SPILL_BYTES = 512 * 1024 * 1024  # months held in memory before they go to temporary parts


@dataclass(frozen=True, kw_only=True)
class IngestSummary:
    """Where every hand went: ``TABLE.summary.json``, keys in this order."""

    table: str
    sources: tuple[str, ...]
    months: tuple[str, ...]
    hands_read: Mapping[str, int]  # per channel
    hands_read_total: int
    heads_up_hands: int
    kept_hands: int
    rows: int
    rows_per_action: Mapping[str, int]
    dropped: Mapping[str, int]  # per reason
    buckets_total: int
    buckets_add_up: bool
    inconsistent_reasons: Mapping[str, int]
    skipped_channels: Mapping[str, int]
    malformed_lines: int
    malformed_examples: tuple[str, ...]
    decisions_dropped_concealed: int
    single_blind_hands: int
    chips_mismatch_hands: int
    orphan_pdb_lines: int
    kept_fold_hands: int = 0  # kept hands that ended in a fold (cards shown: synth --reveal-all)

    def to_json(self) -> dict[str, object]:
        return {
            "table": self.table,
            "sources": list(self.sources),
            "months": list(self.months),
            "hands_read": dict(self.hands_read),
            "hands_read_total": self.hands_read_total,
            "heads_up_hands": self.heads_up_hands,
            "kept_hands": self.kept_hands,
            "rows": self.rows,
            "rows_per_action": dict(self.rows_per_action),
            "dropped": dict(self.dropped),
            "buckets_total": self.buckets_total,
            "buckets_add_up": self.buckets_add_up,
            "inconsistent_reasons": dict(self.inconsistent_reasons),
            "skipped_channels": dict(self.skipped_channels),
            "malformed_lines": self.malformed_lines,
            "malformed_examples": list(self.malformed_examples),
            "decisions_dropped_concealed": self.decisions_dropped_concealed,
            "single_blind_hands": self.single_blind_hands,
            "chips_mismatch_hands": self.chips_mismatch_hands,
            "orphan_pdb_lines": self.orphan_pdb_lines,
            "kept_fold_hands": self.kept_fold_hands,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> IngestSummary:
        listed = ("sources", "months", "malformed_examples")
        found: dict[str, Any] = {k: tuple(v) if k in listed else v for k, v in data.items()}
        return cls(**found)


def summary_path(table_path: str | os.PathLike[str]) -> Path:
    """``TABLE.parquet`` -> ``TABLE.summary.json``."""
    path = Path(table_path)
    return path.with_name(path.name.removesuffix(".parquet") + ".summary.json")


def ingest_table(
    sources: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    *,
    strict: bool = False,
    progress: bool = False,
) -> IngestSummary:
    """Read IRC sources, write the table to ``out`` and its summary beside it; return the summary.

    Months are parsed one at a time; their tables are held until they pass ``SPILL_BYTES``,
    then spilled to temporary Parquet parts, so memory stays bounded. Months are joined in
    (channel, month) order at the end.

    The table and its summary are written through the store (:func:`staged_files`, key: the
    table's name): nothing changes at ``out`` unless the whole ingest succeeds, and a kill
    leaves the old pair or, once the next writer has tidied, the new one. The old summary is
    removed just before the swap, so a table is never seen beside another ingest's summary.
    """
    out_path = Path(out)
    if out_path.is_dir():
        raise IngestError(f"{out_path}: is a folder; give a file name such as table.parquet")
    if not out_path.parent.is_dir():
        raise IngestError(f"{out_path.parent}: output folder does not exist")
    check_sources(sources)
    try:
        with staged_files(out_path.parent, key=out_path.name, make_parent=False) as new:
            scratch = new / _SPILL_FOLDER  # inside the staging folder; gone before the swap
            scratch.mkdir()
            summary = _ingest(sources, out_path, new, scratch, strict=strict, progress=progress)
            shutil.rmtree(scratch)
            summary_path(out_path).unlink(missing_ok=True)
    except OSError as error:  # sources' read errors are IngestErrors: this is a write
        raise IngestError(f"{out_path}: cannot write ({error.strerror or error})") from None
    return summary


_SPILL_FOLDER = ".spill"  # month parts, within the staged entries until just before the swap


def _ingest(
    sources: Sequence[str | os.PathLike[str]],
    out_path: Path,
    new: Path,
    scratch: Path,
    *,
    strict: bool,
    progress: bool,
) -> IngestSummary:
    stats = IngestStats(strict=strict)
    seen: dict[str, np.ndarray] = {}
    # (month key, arrival order, table in memory or spilled part file)
    months: list[tuple[str, int, pa.Table | Path]] = []
    in_memory = 0
    # Showdown hands hold no fold; a fold row (a hand with its cards revealed) adds the key.
    counts = {action: 0 for action in ACTIONS if action != ACTIONS[FOLD]}
    with tqdm(desc="ingest", unit=" hands", disable=not progress, smoothing=0) as bar:
        for order, month in enumerate(iter_months(sources)):
            hands = parse_month(month, stats, seen, on_hands=bar.update)
            table, concealed = month_table(hands)
            stats.decisions_concealed += concealed
            for action, count in zip(*_value_counts(table.column("action")), strict=True):
                counts[action] = counts.get(action, 0) + count
            if table.num_rows == 0:
                continue
            months.append((month.key, order, table))
            in_memory += table.nbytes
            if in_memory > SPILL_BYTES:
                months = [_spill(item, scratch) for item in months]
                in_memory = 0
    summary = _summary(stats, sources, out_path, counts)
    table_file, summary_file = new / out_path.name, new / summary_path(out_path).name
    with (
        _file(table_file, "wb") as sink,
        pq.ParquetWriter(sink, SCHEMA, **PARQUET_OPTIONS) as writer,
    ):
        for _, _, data in sorted(months, key=lambda item: item[:2]):
            if isinstance(data, Path):
                with _file(data, "rb") as part:
                    data = pq.read_table(part)
            writer.write_table(data)
    summary_file.write_text(json.dumps(summary.to_json(), indent=2) + "\n", encoding="utf-8")
    return summary


def _spill(
    item: tuple[str, int, pa.Table | Path], scratch: Path
) -> tuple[str, int, pa.Table | Path]:
    key, order, data = item
    if isinstance(data, Path):
        return item
    part = scratch / f"part-{order:06d}.parquet"
    with _file(part, "wb") as sink:
        pq.write_table(data, sink, compression="lz4")
    return key, order, part


def _file(path: Path, mode: str) -> pa.OSFile:
    """A native Arrow file at ``path``, named by its bytes: Arrow takes a text path as UTF-8
    and fails on a folder name that is not (which ``os.fsdecode`` keeps as surrogates)."""
    return pa.OSFile(os.fsencode(path), mode)


def _value_counts(column: pa.ChunkedArray) -> tuple[list[str], list[int]]:
    counted = column.value_counts()
    if len(counted) == 0:
        return [], []
    return counted.field("values").to_pylist(), counted.field("counts").to_pylist()


def _summary(
    stats: IngestStats,
    sources: Sequence[str | os.PathLike[str]],
    out_path: Path,
    rows_per_action: dict[str, int],
) -> IngestSummary:
    hands_total = sum(stats.hands_read.values())
    buckets = {KEPT: stats.buckets[KEPT]} | {r: stats.buckets[r] for r in DROP_REASONS}
    return IngestSummary(
        table=str(out_path),
        sources=tuple(str(s) for s in sources),
        months=tuple(stats.months),
        hands_read=dict(sorted(stats.hands_read.items())),
        hands_read_total=hands_total,
        heads_up_hands=stats.heads_up_hands,
        kept_hands=stats.buckets[KEPT],
        rows=sum(rows_per_action.values()),
        rows_per_action=rows_per_action,
        dropped={reason: stats.buckets[reason] for reason in DROP_REASONS},
        buckets_total=sum(buckets.values()),
        buckets_add_up=sum(buckets.values()) == hands_total,
        inconsistent_reasons=dict(stats.inconsistent_reasons.most_common()),
        skipped_channels=dict(sorted(stats.skipped_channels.items())),
        malformed_lines=stats.malformed_lines,
        malformed_examples=tuple(stats.malformed_examples),
        decisions_dropped_concealed=stats.decisions_concealed,
        single_blind_hands=stats.single_blind_hands,
        chips_mismatch_hands=stats.chips_mismatch_hands,
        orphan_pdb_lines=stats.orphan_pdb_lines,
        kept_fold_hands=stats.kept_fold_hands,
    )
