"""The named IRC data (pokerirl/datasets/catalog.py, ``pokerirl data``): the shipped April 1995
sample by name wherever a month is taken, and ``data fetch`` against a local HTTP server."""

from __future__ import annotations

import hashlib
import io
import tarfile
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from irc_fixtures import SHARED_SAMPLE, real_month
from pokerirl.cli import app
from pokerirl.datasets import catalog
from pokerirl.datasets.ingest import ingest_table


@pytest.fixture
def fresh(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A folder with no ../shared beside it, an empty home and cache, as the working folder."""
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv(catalog.DATA_VARIABLE, str(tmp_path / "cache"))
    assert not (work.parent / "shared").exists() and not (work / ".." / ".." / "shared").exists()
    return work


def invoke(*words: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, list(words))
    return result.exit_code, result.stdout, result.stderr


def test_the_shipped_archive_is_what_the_catalog_says() -> None:
    path = catalog.SAMPLE.path()
    data = path.read_bytes()
    assert len(data) == catalog.SAMPLE.size
    assert hashlib.sha256(data).hexdigest() == catalog.SAMPLE.sha256
    with tarfile.open(path) as tar:
        names = tar.getnames()
        readme = tar.extractfile("README.md")
        assert readme is not None and b"jalonzoajordan/Project-4" in readme.read()  # provenance
    assert names[:3] == ["README.md", "holdem/199504/hdb", "holdem/199504/hroster"]
    assert names[3:] == sorted(names[3:]) and len(names) == 3 + 455


def test_packing_a_month_twice_gives_the_same_bytes(tmp_path: Path) -> None:
    month = real_month()
    first, second = io.BytesIO(), io.BytesIO()
    catalog.pack_month(month, first, readme=b"r")
    (tmp_path / "later").write_bytes(b"")  # another second, another mtime: nothing changes
    catalog.pack_month(month, second, readme=b"r")
    assert first.getvalue() == second.getvalue()


@pytest.mark.skipif(not SHARED_SAMPLE.is_dir(), reason="the CI checkout's ../shared is absent")
def test_the_shipped_sample_is_the_shared_folder_byte_for_byte() -> None:
    mine = real_month()
    theirs = sorted(p.relative_to(SHARED_SAMPLE) for p in SHARED_SAMPLE.rglob("*") if p.is_file())
    assert sorted(p.relative_to(mine) for p in mine.rglob("*") if p.is_file()) == theirs
    for name in theirs:
        assert (mine / name).read_bytes() == (SHARED_SAMPLE / name).read_bytes(), name
    # And packing the shared folder again makes the shipped archive (same zlib).
    packed = io.BytesIO()
    readme = (SHARED_SAMPLE.parents[1] / "README.md").read_bytes()
    catalog.pack_month(SHARED_SAMPLE, packed, readme=readme)
    assert packed.getvalue() == catalog.SAMPLE.path().read_bytes()


@pytest.mark.slow
def test_ingest_by_name_writes_the_rows_of_the_month_folder(fresh: Path) -> None:
    code, _, err = invoke("ingest", "irc-199504", "--out", "t.parquet", "-q")
    assert code == 0, err
    ingest_table([real_month()], fresh / "folder.parquet", progress=False)
    by_name, by_folder = pq.read_table("t.parquet"), pq.read_table(fresh / "folder.parquet")
    assert by_name.num_rows == by_folder.num_rows > 4000
    assert by_name.equals(by_folder)
    assert (fresh / "t.parquet").read_bytes() == (fresh / "folder.parquet").read_bytes()
    assert not (fresh.parent / "cache").exists()  # the shipped sample needs no cache


def test_a_folder_of_that_name_wins_over_the_dataset(fresh: Path) -> None:
    (fresh / "irc-199504").mkdir()
    assert catalog.resolve_source("irc-199504") == Path("irc-199504")
    assert catalog.resolve_source("elsewhere/x") == Path("elsewhere/x")


def test_a_name_not_fetched_is_one_line_saying_how_to_fetch_it(fresh: Path) -> None:
    code, _, err = invoke("ingest", "irc-holdem-199601", "--out", "t.parquet")
    assert code == 1 and err.count("\n") == 1
    assert "irc-holdem-199601: not fetched yet" in err
    assert err.rstrip().endswith("pokerirl data fetch irc-holdem-199601")
    code, _, err = invoke("study", "irc", "--out", "s")
    assert code == 1 and "pokerirl data fetch irc" in err and not (fresh / "s").exists()


def test_data_list_names_the_shipped_sample_and_the_archive(fresh: Path) -> None:
    code, out, err = invoke("data", "list")
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0].split()[:3] == ["name", "size", "hands"]
    sample = next(line for line in lines if line.startswith("irc-199504 "))
    assert "1.1 MB" in sample and "13,426" in sample and "holdem" in sample
    assert sample.endswith(str(catalog.SAMPLE.path()))
    archive = next(line for line in lines if line.startswith("irc "))
    assert "17 channels" in archive and archive.endswith("not fetched")
    assert str(fresh.parent.parent / "cache") in lines[-1]
