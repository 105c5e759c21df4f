"""Fixtures shared by the test files: the command line (``cli``), folder snapshots
(``folder_bytes``, ``folder_snapshot``), small tables (``small_table``, ``small_table_path``)
and the MountainCar gym study (``mountaincar_study``, built once per session). The helpers
behind them are in :mod:`testkit`, for module-scoped fixtures and module-level code.

The suite runs in two tiers: ``make test-fast`` (``-m "not slow"``, the edit-test loop) and
``make test`` (everything, over ``pytest-xdist`` workers with ``--dist loadfile``: a file's
tests on one worker, so that its module fixtures are built once; a session fixture is built
at most once per worker). Tests stay isolated side by side: each writes in its own
``tmp_path``, starts its own processes on free ports, stops only those (by pid), and changes
its folder or environment only through ``monkeypatch`` (each xdist worker is a process of its
own). ``--dist loadgroup`` is not used: with pytest 9.2 and pytest-xdist 3.8 its groups are
not honoured (pytest-xdist issue 1386), and the suite ran 36 s longer that way.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from testkit import TINY_GYM_STUDY, Cli, folder_bytes, folder_snapshot

if TYPE_CHECKING:
    import pyarrow as pa

@pytest.fixture
def cli() -> Cli:
    """``cli(*args)``: click's result of ``pokerirl ARGS``; ``cli.ok(*args)``: its output,
    asserting exit code 0."""
    return Cli()


@pytest.fixture(name="folder_bytes")
def folder_bytes_fixture() -> Callable[[Path], dict[str, bytes]]:
    """``folder_bytes(folder)``: every file's bytes by relative path."""
    return folder_bytes


@pytest.fixture(name="folder_snapshot")
def folder_snapshot_fixture() -> Callable[[Path], dict[str, tuple[bytes, int]]]:
    """``folder_snapshot(folder)``: every file's bytes and inode (a rewrite shows)."""
    return folder_snapshot


@functools.cache
def _toy_table(num_hands: int, seed: int) -> pa.Table:
    from pokerirl.datasets.toy import toy_expert_table

    return toy_expert_table(num_hands=num_hands, seed=seed)


@pytest.fixture(scope="session")
def small_table() -> Callable[..., pa.Table]:
    """``small_table(num_hands=200, seed=0)``: the toy expert table, built once per session
    and size (an Arrow table is immutable: sharing it is safe)."""

    def build(num_hands: int = 200, seed: int = 0) -> pa.Table:
        return _toy_table(num_hands, seed)

    return build


@pytest.fixture
def small_table_path(tmp_path: Path, small_table: Callable[..., pa.Table]) -> Path:
    """The 200-hand toy table as ``table.parquet`` in the test's own folder."""
    import pyarrow.parquet as pq

    path = tmp_path / "table.parquet"
    pq.write_table(small_table(), path)
    return path


@pytest.fixture(scope="session")
def mountaincar_study(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``pokerirl gym study MountainCar-v0`` at ``TINY_GYM_STUDY``, built once per session.
    A test may change it only to put it back as it was."""
    pytest.importorskip("gymnasium")
    pytest.importorskip("stable_baselines3")
    out = tmp_path_factory.mktemp("study") / "mc"
    output = Cli().ok("gym", "study", "MountainCar-v0", "--out", out, *TINY_GYM_STUDY)
    assert "# pokerirl gym study (quick preset)" in output
    return out
