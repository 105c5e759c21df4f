"""Ingest throughput: hands per second on a large synthetic month, pinned to one core.

    python benchmarks/ingest.py [--hands 200000] [--repeats 3]

Prints the best of ``--repeats`` runs of the full ``ingest`` (read, parse, build rows, write
Parquet), and the time of each stage. Peers: the issue's target of 50,000 hands/s, and the
public jcottas/PokerHandsDataset parser, quoted at about 820 hands/s on this machine.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from pokerirl.datasets.ingest import PARQUET_OPTIONS, ingest_table
from pokerirl.datasets.table import month_table
from pokerirl.game.synth import write_synthetic_month
from pokerirl.parsers.irc import IngestStats, parse_month
from pokerirl.parsers.irc_sources import iter_months

TARGET_HANDS_PER_SECOND = 50_000
JCOTTAS_HANDS_PER_SECOND = 820  # quoted in the issue: 27,508 hands in about 33 s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hands", type=int, default=200_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    pa.set_cpu_count(1)
    pa.set_io_thread_count(1)

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        started = time.perf_counter()
        folder = write_synthetic_month(root / "irc", hands=args.hands, seed=args.seed)
        print(f"synthesized {args.hands:,} hands in {time.perf_counter() - started:.1f} s")

        best = best_cpu = float("inf")
        for _ in range(args.repeats):
            started, started_cpu = time.perf_counter(), time.process_time()
            summary = ingest_table([folder], root / "table.parquet").to_json()
            best = min(best, time.perf_counter() - started)
            best_cpu = min(best_cpu, time.process_time() - started_cpu)
        hands = summary["hands_read_total"]
        rows = summary["rows"]
        rate = hands / best
        print(f"ingest: {hands:,} hands, {summary['kept_hands']:,} kept, {rows:,} rows")
        print(
            f"best of {args.repeats}: {best:.2f} s = {rate:,.0f} hands/s, {rows / best:,.0f} rows/s"
        )
        # CPU time is what one core spent; it holds steady when other work shares the core.
        print(f"CPU time: {best_cpu:.2f} s = {hands / best_cpu:,.0f} hands/CPU-second")
        print(f"vs target {TARGET_HANDS_PER_SECOND:,}/s: {rate / TARGET_HANDS_PER_SECOND:.2f}x")
        print(
            f"vs jcottas parser ({JCOTTAS_HANDS_PER_SECOND} hands/s): "
            f"{rate / JCOTTAS_HANDS_PER_SECOND:,.0f}x"
        )

        stages = {}
        started = time.perf_counter()
        month = next(iter_months([folder]))
        stages["read files"] = time.perf_counter() - started
        started = time.perf_counter()
        hands_parsed = parse_month(month, IngestStats(), {})
        stages["parse"] = time.perf_counter() - started
        started = time.perf_counter()
        table, _ = month_table(hands_parsed)
        stages["build rows"] = time.perf_counter() - started
        started = time.perf_counter()
        pq.write_table(table, root / "stage.parquet", **PARQUET_OPTIONS)
        stages["write parquet"] = time.perf_counter() - started
        for name, seconds in stages.items():
            print(f"  {name:<14} {seconds:6.2f} s  ({seconds / hands * 1e6:5.1f} us/hand)")


if __name__ == "__main__":
    main()
