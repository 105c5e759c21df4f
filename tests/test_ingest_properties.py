"""Property tests: corrupted input never crashes the reader, and every hand stays accounted for."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from irc_fixtures import HDB, HROSTER, PDB, write_month
from pokerirl.datasets.ingest import ingest_table

_GARBAGE = st.text(
    alphabet=st.sampled_from(list("0123456789 /-BkcbrAfQKshdcAKQJT2\t\r.[]`\\x")), max_size=40
)


@st.composite
def corrupted_month(draw: st.DrawFn) -> tuple[list[str], list[str], dict[str, list[str]]]:
    """The fixture month with random lines replaced, truncated, duplicated or deleted."""

    def corrupt(lines: list[str]) -> list[str]:
        out = list(lines)
        for _ in range(draw(st.integers(0, 3))):
            if not out:
                break
            index = draw(st.integers(0, len(out) - 1))
            kind = draw(st.sampled_from(["replace", "truncate", "duplicate", "delete", "swap"]))
            if kind == "replace":
                out[index] = draw(_GARBAGE)
            elif kind == "truncate":
                out[index] = out[index][: draw(st.integers(0, len(out[index])))]
            elif kind == "duplicate":
                out.insert(index, out[index])
            elif kind == "delete":
                del out[index]
            else:
                fields = out[index].split()
                if len(fields) > 1:
                    position = st.integers(0, len(fields) - 1)
                    i, j = draw(position), draw(position)
                    fields[i], fields[j] = fields[j], fields[i]
                    out[index] = " ".join(fields)
        return out

    return corrupt(HDB), corrupt(HROSTER), {name: corrupt(lines) for name, lines in PDB.items()}


@pytest.mark.slow
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(corrupted_month())
def test_corrupted_lines_never_crash_and_every_hand_is_counted(
    month: tuple[list[str], list[str], dict[str, list[str]]],
) -> None:
    hdb, hroster, pdb = month
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        folder = write_month(root / "irc", hdb=hdb, hroster=hroster, pdb=pdb)
        summary = ingest_table([folder], root / "t.parquet").to_json()
    assert summary["hands_read_total"] == len(hdb)
    assert summary["kept_hands"] + sum(summary["dropped"].values()) == len(hdb)
    assert summary["buckets_add_up"]
    assert sum(summary["rows_per_action"].values()) == summary["rows"]
