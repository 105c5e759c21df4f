"""The named IRC data (pokerirl/datasets/catalog.py, ``pokerirl data``): the shipped April 1995
sample by name wherever a month is taken, and ``data fetch`` against a local HTTP server."""

from __future__ import annotations

import hashlib
import http.server
import io
import json
import socket
import tarfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import ClassVar

import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from irc_fixtures import SHARED_SAMPLE, real_month
from pokerirl.cache import DATA_VARIABLE
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
    monkeypatch.setenv(DATA_VARIABLE, str(tmp_path / "cache"))
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
    assert lines[-1].endswith("the turn-equity table: not built (pokerirl data turn-table)")


# --------------------------------------------------------------------------- data fetch


def _ircdata() -> bytes:
    """An IRCdata.tgz as the University of Alberta lays it out: month archives in a folder;
    the month is the shipped sample's archive (1.1 MB, so a download takes many reads)."""
    out = io.BytesIO()
    with tarfile.open(fileobj=out, mode="w:gz") as tar:
        for name, data in [("IRCdata/README.TXT", b"IRC Poker Logs\n"),
                           ("IRCdata/holdem.199504.tgz", catalog.SAMPLE.path().read_bytes())]:
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))  # fmt: skip
    return out.getvalue()


IRCDATA = _ircdata()
GOOD = hashlib.sha256(IRCDATA).hexdigest()


class Archive(http.server.BaseHTTPRequestHandler):
    """Serves :data:`IRCDATA` with HTTP Range; ``cut`` closes the first response halfway."""

    cut = False
    ranges: ClassVar[list[str | None]] = []
    served: ClassVar[list[int]] = []

    def do_GET(self) -> None:
        asked = self.headers.get("Range")
        type(self).ranges.append(asked)
        start = int(asked.removeprefix("bytes=").rstrip("-")) if asked else 0
        body = IRCDATA[start:]
        self.send_response(206 if start else 200)
        if start:
            self.send_header("Content-Range", f"bytes {start}-{len(IRCDATA) - 1}/{len(IRCDATA)}")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if type(self).cut:
            type(self).cut = False
            body = body[: len(body) // 2]
            self.close_connection = True
        # Recorded before the write: once the client has the last byte, the test may read
        # `served` before this thread would have appended after the write (a race CI hit).
        type(self).served.append(len(body))
        self.wfile.write(body)
        self.wfile.flush()

    def log_message(self, *_: object) -> None:  # quiet
        pass


@pytest.fixture
def server() -> Iterator[str]:
    """The URL of IRCdata.tgz on a server on 127.0.0.1, started and stopped by the test."""
    Archive.cut, Archive.ranges, Archive.served = False, [], []
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Archive)
    thread = threading.Thread(target=httpd.serve_forever, kwargs={"poll_interval": 0.05})
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}/IRCdata.tgz"
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join(timeout=10)


def _files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.rglob("*")) if folder.exists() else []


@pytest.mark.slow
def test_fetch_checks_the_sum_then_a_month_out_of_it_is_a_month_everywhere(
    fresh: Path, server: str
) -> None:
    cache = fresh.parent.parent / "cache"
    code, out, err = invoke("data", "fetch", "irc", "--url", server, "--sha256", GOOD.upper())
    assert code == 0, err
    assert f"SHA-256 {GOOD} matches --sha256" in out and "%" in err  # the progress bar
    assert (cache / "IRCdata.tgz").read_bytes() == IRCDATA
    code, out, err = invoke("data", "fetch", "irc-holdem-199504", "-q")
    assert code == 0, err
    month = cache / "holdem.199504.tgz"
    assert month.read_bytes() == catalog.SAMPLE.path().read_bytes()
    assert Archive.ranges == [None]  # the month came out of the cached archive: no download
    code, _, err = invoke("ingest", "irc-holdem-199504", "--out", "t.parquet", "-q")
    assert code == 0, err
    ingest_table([real_month()], fresh / "folder.parquet", progress=False)
    assert pq.read_table("t.parquet").equals(pq.read_table(fresh / "folder.parquet"))
    code, out, _ = invoke("data", "list")
    listed = {line.split()[0]: line for line in out.splitlines()[1:-1]}
    assert listed["irc"].endswith(str(cache / "IRCdata.tgz"))
    assert listed["irc-holdem-199504"].endswith(str(month))
    # Where nobody publishes a sum, the first fetch records one and later fetches keep to it.
    recorded = json.loads((cache / catalog.RECORDED_SUMS).read_text())
    assert recorded["IRCdata.tgz"]["sha256"] == GOOD
    (cache / "IRCdata.tgz").write_bytes(IRCDATA[:-1] + b"!")  # a cached file gone bad
    code, _, err = invoke("data", "fetch", "irc")
    assert code == 1 and f"not the recorded {GOOD}" in err and err.count("\n") == 1


def test_a_wrong_sum_is_one_line_and_leaves_nothing_in_the_cache(
    fresh: Path, server: str
) -> None:
    cache = fresh.parent.parent / "cache"
    code, out, err = invoke("data", "fetch", "irc", "--url", server, "--sha256", "0" * 64, "-q")
    assert code == 1 and out == ""
    assert err.count("\n") == 1 and f"SHA-256 is {GOOD}, not the given {'0' * 64}" in err
    assert _files(cache) == []
    assert Archive.served == [len(IRCDATA)]  # it was downloaded whole, then refused


def test_a_fetch_cut_halfway_resumes_where_it_stopped(fresh: Path, server: str) -> None:
    cache = fresh.parent.parent / "cache"
    Archive.cut = True
    code, _, err = invoke("data", "fetch", "irc", "--url", server, "-q")
    half = len(IRCDATA) // 2
    assert code == 1 and f"cut after {half:,} of {len(IRCDATA):,} bytes" in err
    assert (cache / ".IRCdata.tgz.part").stat().st_size == half
    assert not (cache / "IRCdata.tgz").exists()
    code, out, err = invoke("data", "fetch", "irc", "--url", server, "-q")
    assert code == 0, err
    assert Archive.ranges == [None, f"bytes={half}-"]
    assert Archive.served == [half, len(IRCDATA) - half]  # the rest only
    assert (cache / "IRCdata.tgz").read_bytes() == IRCDATA
    assert "not verified (no sum is published)" in out
    assert _files(cache) == ["IRCdata.tgz", catalog.RECORDED_SUMS]


def test_offline_is_one_line_with_the_url_to_download_by_hand(fresh: Path) -> None:
    with socket.socket() as probe:  # a port nothing listens on
        probe.bind(("127.0.0.1", 0))
        url = f"http://127.0.0.1:{probe.getsockname()[1]}/IRCdata.tgz"
    code, _, err = invoke("data", "fetch", "irc", "--url", url)
    assert code == 1 and err.count("\n") == 1
    assert f"download {url} by hand, then: pokerirl data fetch irc --url FILE" in err
    assert _files(fresh.parent.parent / "cache") == []


def test_a_file_downloaded_by_hand_is_fetched_from_its_path(fresh: Path) -> None:
    (fresh / "IRCdata.tgz").write_bytes(IRCDATA)
    code, out, err = invoke("data", "fetch", "irc", "--url", "IRCdata.tgz", "--sha256", GOOD)
    assert code == 0 and "matches --sha256" in out, err
    assert (fresh.parent.parent / "cache" / "IRCdata.tgz").read_bytes() == IRCDATA
    code, out, err = invoke("data", "fetch", "irc")  # there already: checked, not fetched
    assert code == 0 and "matches the sum recorded at its first fetch" in out, err
    code, _, err = invoke("data", "fetch", "irc", "--url", "missing.tgz")
    assert code == 1 and err == "error: missing.tgz: no such file\n"
