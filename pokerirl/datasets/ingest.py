"""``pokerirl ingest``: IRC hand histories in, one Parquet state-action table out.

With a ``folds`` step (``ingest --folds impute``, :mod:`pokerirl.poker.impute`; this layer
knows nothing of how it imputes), the hands that ended in a fold with nobody's cards shown
are kept too: the step gets every row, concealed ones with an empty ``hole_cards``, and
returns the table to write (with the columns of
:data:`~pokerirl.datasets.table.IMPUTED_SCHEMA`) and what it did. Without it, the table and
its summary are exactly what they were before folds could be kept.

>>> # ingest(["holdem/199504"], "table.parquet")  # writes table.parquet and table.summary.json
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
from tqdm import tqdm

from pokerirl.datasets.players import (
    NOT_THE_EXPERT,
    OUTSIDE_PERIOD,
    Filter,
    Selection,
    SelectionSummary,
    Selector,
)
from pokerirl.datasets.table import IMPUTED_SCHEMA, SCHEMA, month_table
from pokerirl.holdem import ACTIONS, FOLD
from pokerirl.parsers.irc import DROP_REASONS, KEPT, IngestStats, heads_up_results, parse_month
from pokerirl.parsers.irc_sources import IngestError, check_sources, iter_months
from pokerirl.serial import Omit, Serializable, meta
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
# The drop reason of a hand whose actions no hole cards explain (impute mode only).
UNEXPLAINED = "unexplained_by_behaviour"


@dataclass(frozen=True, kw_only=True)
class FoldsSummary(Serializable):
    """What ``--folds impute`` did: the ``folds`` key of the summary, keys in this order.

    ``hidden_players``: (hand, player) pairs whose cards were concealed; each is imputed or
    dropped (its actions have likelihood ~0 under π_B for every pair of cards). A hand with a
    dropped player is dropped whole (``unexplained_by_behaviour``) unless the other player's
    cards were shown, in which case it keeps that player's rows as before.
    ``entropy_bits``: quantiles of the imputed players' posterior entropies, beside
    ``uniform_bits`` (a posterior that learnt nothing). ``rounds``: the behaviour model's
    fitting rounds (BC on the observed rows, then EM with imputed ones)."""

    behaviour: str  # where π_B came from: "bc" (fitted on this table) or a run folder
    behaviour_encoding: str
    imputations: int  # K posterior draws per hidden player (equal draws merge, weight count/K)
    seed: int
    hidden_players: int
    imputed_players: int
    dropped_players: int
    imputed_hands: int
    dropped_hands: int
    imputed_decisions: int
    imputed_rows: int
    imputed_decisions_per_action: Mapping[str, int]
    entropy_bits: Mapping[str, float]  # mean, p10, p50, p90 over imputed players
    uniform_bits: float  # mean entropy of the uniform posterior over the same players
    rounds: tuple[Mapping[str, Any], ...] = ()


@dataclass(frozen=True, kw_only=True, eq=False)
class FoldsResult:
    """What a :class:`FoldsStep` returns: the table to write and its summary."""

    table: pa.Table  # IMPUTED_SCHEMA
    summary: FoldsSummary
    dropped_decisions: int  # concealed decisions left out (their players were dropped)


class FoldsStep(Protocol):
    """Turns every row of an ingest (concealed players' rows with an empty ``hole_cards``)
    into the table to write."""

    def __call__(self, table: pa.Table, *, progress: bool) -> FoldsResult: ...


@dataclass(frozen=True, kw_only=True)
class IngestSummary(Serializable):
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
    # --folds impute only (absent from the JSON otherwise): hands kept with imputed cards.
    imputed_hands: int | None = field(default=None, metadata=meta(omit=Omit.NONE))
    folds: FoldsSummary | None = field(default=None, metadata=meta(omit=Omit.NONE))
    # A selection only (absent otherwise): the period and the expert's players, and what
    # each filter kept. kept_hands, rows and the buckets then count the table written
    # (kept_fold_hands and the parser's counts stay those of the hands read).
    selection: SelectionSummary | None = field(default=None, metadata=meta(omit=Omit.NONE))


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
    folds: FoldsStep | None = None,
    recorded_as: str | os.PathLike[str] | None = None,
    selection: Selection | None = None,
) -> IngestSummary:
    """Read IRC sources, write the table to ``out`` and its summary beside it; return the summary.

    ``selection`` keeps a period of each month and the decisions of the players chosen as
    the expert (:mod:`pokerirl.datasets.players`), before any ``folds`` step; the summary
    records it and what each filter kept. None: every kept hand, as before.

    ``recorded_as`` is the table's path that the summary records, when ``out`` is a staging
    path that is moved into place afterwards (a study's unit); its file name must be ``out``'s.

    Months are parsed one at a time; their tables are held until they pass ``SPILL_BYTES``,
    then spilled to temporary Parquet parts, so memory stays bounded. Months are joined in
    (channel, month) order at the end. With ``folds`` (see the module docstring), the fold
    hands nobody showed are kept for it, and the whole table is held in memory for it.

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
    named = out_path if recorded_as is None else Path(recorded_as)
    if named.name != out_path.name:
        raise ValueError(f"recorded_as {named} must keep the file name {out_path.name}")
    check_sources(sources)
    try:
        with staged_files(out_path.parent, key=out_path.name, make_parent=False) as new:
            scratch = new / _SPILL_FOLDER  # inside the staging folder; gone before the swap
            scratch.mkdir()
            summary = _ingest(sources, named, new, scratch, strict=strict, progress=progress,
                              folds=folds, selection=selection)  # fmt: skip
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
    folds: FoldsStep | None = None,
    selection: Selection | None = None,
) -> IngestSummary:
    stats = IngestStats(strict=strict)
    keep = folds is not None
    selector = None if selection is None else Selector(selection)
    seen: dict[str, np.ndarray] = {}
    # (month key, arrival order, table in memory or spilled part file)
    months: list[tuple[str, int, pa.Table | Path]] = []
    in_memory = 0
    with tqdm(desc="ingest", unit=" hands", disable=not progress, smoothing=0) as bar:
        for order, month in enumerate(iter_months(sources)):
            hands = parse_month(month, stats, seen, on_hands=bar.update, keep_concealed=keep)
            table, concealed = month_table(hands, keep_concealed=keep)
            stats.decisions_concealed += concealed
            if selector is not None:
                table = selector.month(month.key, seen.get(month.key, np.zeros(0, np.int64)),
                                       heads_up_results(month), table)  # fmt: skip
            if table.num_rows == 0:
                continue
            months.append((month.key, order, table))
            in_memory += table.nbytes
            if in_memory > SPILL_BYTES and not keep:
                months = [_spill(item, scratch) for item in months]
                in_memory = 0
    table_file, summary_file = new / out_path.name, new / summary_path(out_path).name
    ordered = [data for _, _, data in sorted(months, key=lambda item: item[:2])]
    extra_drops: dict[str, int] = {}
    chosen: SelectionSummary | None = None
    expert: frozenset[str] | None = None
    if selector is not None:
        expert, chosen = selector.finish()
        _account_for(chosen, stats, extra_drops)
        if folds is not None and expert is not None:  # the step sees the expert's rows only
            ordered = [_of_players(data, expert) for data in ordered]
            expert = None
    if folds is not None:
        summary = _write_with_folds(folds, ordered, stats, sources, out_path, table_file,
                                    progress=progress, extra_drops=extra_drops)  # fmt: skip
    else:
        counts = _write_table(ordered, expert, table_file)
        summary = _summary(stats, sources, out_path, counts, extra_drops=extra_drops)
    if chosen is not None:
        if summary.rows == 0:
            steps = ", ".join(f"{step.filter}: {step.decisions}" for step in chosen.steps)
            raise IngestError(f"no decision is left after the selection (decisions {steps})")
        summary = dataclasses.replace(summary, selection=chosen)
    summary_file.write_text(json.dumps(summary.to_json(), indent=2) + "\n", encoding="utf-8")
    return summary


def _write_table(
    months: list[pa.Table | Path], players: frozenset[str] | None, table_file: Path
) -> dict[str, int]:
    """Write the rows of ``players`` (None: all) of ``months``, in order; their counts per
    action."""
    counts = _action_counts()
    with (
        _file(table_file, "wb") as sink,
        pq.ParquetWriter(sink, SCHEMA, **PARQUET_OPTIONS) as writer,
    ):
        for data in months:
            rows = _of_players(data, players)
            _action_counts(rows, counts)
            writer.write_table(rows)
    return counts


def _action_counts(
    table: pa.Table | None = None, counts: dict[str, int] | None = None
) -> dict[str, int]:
    """``counts`` plus the rows of ``table`` per action. Showdown hands hold no fold: the
    key starts absent, and a fold row (a hand with its cards revealed) adds it."""
    if counts is None:
        counts = {action: 0 for action in ACTIONS if action != ACTIONS[FOLD]}
    if table is not None:
        for action, count in zip(*_value_counts(table.column("action")), strict=True):
            counts[action] = counts.get(action, 0) + count
    return counts


def _write_with_folds(
    folds: FoldsStep,
    months: list[pa.Table | Path],
    stats: IngestStats,
    sources: Sequence[str | os.PathLike[str]],
    out_path: Path,
    table_file: Path,
    *,
    progress: bool,
    extra_drops: Mapping[str, int],
) -> IngestSummary:
    """Run the folds step on every row and write its table; the summary's buckets move the
    hands it imputed or dropped out of ``kept``."""
    tables = [data for data in months if isinstance(data, pa.Table)]  # never spilled here
    every = pa.concat_tables(tables) if tables else SCHEMA.empty_table()
    result = folds(every, progress=progress)
    folds_summary = result.summary
    stats.buckets[KEPT] -= folds_summary.imputed_hands + folds_summary.dropped_hands
    stats.decisions_concealed += result.dropped_decisions
    counts = _action_counts(result.table)
    summary = _summary(stats, sources, out_path, counts,
                       extra_drops={**extra_drops,
                                    UNEXPLAINED: folds_summary.dropped_hands})  # fmt: skip
    summary = dataclasses.replace(
        summary,
        imputed_hands=folds_summary.imputed_hands,
        folds=folds_summary,
        buckets_total=summary.buckets_total + folds_summary.imputed_hands,
        buckets_add_up=summary.buckets_total + folds_summary.imputed_hands
        == summary.hands_read_total,
    )
    with _file(table_file, "wb") as sink:
        pq.write_table(result.table.cast(IMPUTED_SCHEMA), sink, **PARQUET_OPTIONS)
    return summary


def _account_for(chosen: SelectionSummary, stats: IngestStats, drops: dict[str, int]) -> None:
    """Move the kept hands that a selection leaves out into its two buckets."""
    hands = {step.filter: step.hands for step in chosen.steps}
    in_period = hands.get(Filter.PERIOD, hands[Filter.ALL])
    drops[OUTSIDE_PERIOD] = hands[Filter.ALL] - in_period
    drops[NOT_THE_EXPERT] = in_period - chosen.steps[-1].hands
    stats.buckets[KEPT] -= drops[OUTSIDE_PERIOD] + drops[NOT_THE_EXPERT]


def _of_players(data: pa.Table | Path, players: frozenset[str] | None) -> pa.Table:
    """The rows of ``players`` (all rows: None) of a month, read back if it was spilled."""
    if isinstance(data, Path):
        with _file(data, "rb") as part:
            data = pq.read_table(part)
    if players is None:
        return data
    wanted = pa.array(sorted(players), type=pa.string())
    return data.filter(pc.is_in(data.column("player"), value_set=wanted))


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
    extra_drops: Mapping[str, int] | None = None,
) -> IngestSummary:
    hands_total = sum(stats.hands_read.values())
    dropped = {reason: stats.buckets[reason] for reason in DROP_REASONS} | dict(extra_drops or {})
    buckets = {KEPT: stats.buckets[KEPT]} | dropped
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
        dropped=dropped,
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
