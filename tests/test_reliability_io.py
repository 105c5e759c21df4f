"""Issue 21, part A: the low layers' promises, through the commands that rely on them.

Errors name the user's path (never a hidden temporary one); ingest refuses what is not IRC
data in one line, reads at most its caps and counts every corrupt line as ``malformed_line``;
tournaments give the same bytes for the same seeds, with timings apart.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tarfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from test_reliability import MINIMAL, one_error_line, run_cli, write_minimal
from testkit import folder_bytes

from irc_fixtures import real_month
from pokerirl.datasets.ingest import ingest_table, summary_path
from pokerirl.parsers import irc_sources

REPO = Path(__file__).resolve().parents[1]
SAMPLE = real_month()


@contextlib.contextmanager
def read_only(folder: Path) -> Iterator[None]:
    """``folder`` made unwritable: immutable for root (which ignores modes), else mode 0555."""
    if os.geteuid() == 0:
        if shutil.which("chattr") is None:
            pytest.skip("running as root without chattr: cannot make a folder read-only")
        made = subprocess.run(["chattr", "+i", str(folder)], capture_output=True)
        if made.returncode != 0:
            pytest.skip(f"chattr +i not supported here: {made.stderr.decode().strip()}")
        try:
            yield
        finally:
            subprocess.run(["chattr", "-i", str(folder)], check=True)
    else:
        folder.chmod(0o555)
        try:
            yield
        finally:
            folder.chmod(0o755)


# --- atomic writes name the user's path -----------------------------------------------------


def _gym_run(folder: Path) -> Path:
    """A MountainCar IRL run folder (the project's own ``save_run``), untrained."""
    from pokerirl.irl.adversarial import TrainResult
    from pokerirl.irl.config import AIRLConfig
    from pokerirl.irl.nets import NetSpec, build_nets
    from pokerirl.irl.run import save_run

    config = AIRLConfig.for_algo("hairl", reward_hidden=(4,), policy_hidden=(4,))
    reward, policy = build_nets(NetSpec.of(config), obs_dim=2, action_dim=3, discrete=True)
    result = TrainResult(reward=reward, policy=policy, config=config, beta_used=0.0)
    save_run(result, folder, algo="hairl", data={"env": "MountainCar-v0"})
    return folder


def _gym_writes(tmp_path: Path, out: Path) -> list[list[str]]:
    """The commands that write one file through :mod:`pokerirl.atomic`, aimed at ``out``."""
    collect = ["gym", "collect", "MountainCar-v0", "-n", "50", "--out", str(out)]
    runs = str(_gym_run(tmp_path / "run"))
    reward_map = ["gym", "reward-map", "MountainCar-v0", "--runs", runs, "--grid", "3"]
    return [collect, [*reward_map, "--expert", "none", "--out", str(out)]]


def test_gym_out_that_is_a_folder_names_the_folder(tmp_path: Path) -> None:
    pytest.importorskip("gymnasium")
    folder = tmp_path / "adir"
    folder.mkdir()
    for command in _gym_writes(tmp_path, folder):
        code, lines = run_cli(*command)
        assert code == 1, (command, lines)
        assert one_error_line(lines) == f"error: {folder}: is a folder, not a file"
        assert list(folder.iterdir()) == []
    assert not list(tmp_path.glob(".adir.*"))


def test_gym_out_in_a_read_only_folder_names_the_file(tmp_path: Path) -> None:
    pytest.importorskip("gymnasium")
    folder = tmp_path / "locked"
    folder.mkdir()
    target = folder / "out.parquet"
    commands = _gym_writes(tmp_path, target)
    with read_only(folder):
        for command in commands:
            code, lines = run_cli(*command)
            assert code == 1, (command, lines)
            line = one_error_line(lines)
            assert re.fullmatch(
                rf"error: {re.escape(str(target))}: (Permission denied|Operation not permitted)",
                line,
            ), line
    assert list(folder.iterdir()) == []


# --- ingest: paths that are not UTF-8 -------------------------------------------------------


def _pokerirl(*args: str | bytes, cwd: Path) -> subprocess.CompletedProcess[bytes]:
    """The real command, with its real standard streams (CliRunner's are not the terminal's)."""
    environment = {**os.environ, "PYTHONPATH": str(REPO), "PYTHONUTF8": "0", "LC_ALL": "C.UTF-8"}
    command = [sys.executable, "-m", "pokerirl", *args]
    return subprocess.run(command, cwd=cwd, env=environment, capture_output=True, timeout=120)


def test_ingest_with_non_utf8_names_writes_the_table_or_names_the_path(tmp_path: Path) -> None:
    odd = os.fsdecode(b"\xff")
    month = write_minimal(tmp_path / f"in{odd}")  # in<odd>/holdem/199504
    month = month.rename(month.with_name(f"1995{odd}04"))
    out_folder = tmp_path / f"out{odd}"
    out_folder.mkdir()
    out = out_folder / "t.parquet"
    done = _pokerirl("ingest", os.fsencode(month.parent), "--out", os.fsencode(out), cwd=tmp_path)
    assert done.returncode == 0 and b"Traceback" not in done.stderr, done.stderr[-300:]
    summary = json.loads(done.stdout)  # the summary JSON escapes what is not text
    assert summary["kept_hands"] == 1 and summary["table"] == str(out)
    assert json.loads(summary_path(out).read_text()) == summary
    table = pq.read_table(pa.OSFile(os.fsencode(out)))
    assert table.column("hand_id")[0].as_py() == "holdem/1995\\xff04/797241924"

    missing = tmp_path / f"nothing{odd}"
    failed = _pokerirl("ingest", os.fsencode(missing), "--out", "t.parquet", cwd=tmp_path)
    lines = failed.stderr.decode("utf-8", "backslashreplace").splitlines()
    assert failed.returncode == 1 and failed.stdout == b""
    assert lines == [f"error: {tmp_path}/nothing\\xff: no such file or folder"], lines


# --- ingest: bounded reads ------------------------------------------------------------------


@contextlib.contextmanager
def unblocked_after(fifo: Path, seconds: float) -> Iterator[None]:
    """If something still waits on ``fifo`` after ``seconds``, open and close its other end
    (the test then fails on time, instead of hanging)."""
    stop = threading.Event()

    def release() -> None:
        if stop.wait(seconds):
            return
        while not stop.is_set():
            with contextlib.suppress(OSError):  # ENXIO: nobody reads it right now
                os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
            time.sleep(0.05)

    thread = threading.Thread(target=release, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


def _special(path: Path, kind: str) -> str:
    """Make ``path`` a FIFO without a writer, or a link to /dev/zero; the kind's words."""
    path.unlink(missing_ok=True)
    if kind == "fifo":
        os.mkfifo(path)
        return "a FIFO"
    path.symlink_to("/dev/zero")
    return "a character device"


@pytest.mark.parametrize("kind", ["fifo", "zero"])
@pytest.mark.parametrize("file", ["hdb", "hroster", "pdb/pdb.MrX"])
def test_ingest_refuses_a_file_that_is_not_regular_at_once(
    tmp_path: Path, file: str, kind: str
) -> None:
    month = write_minimal(tmp_path)
    words = _special(month / file, kind)
    started = time.monotonic()
    with unblocked_after(month / file, 20):
        code, lines = run_cli("ingest", str(month), "--out", str(tmp_path / "t.parquet"), "-q")
    assert time.monotonic() - started < 10
    assert code == 1
    assert one_error_line(lines) == (
        f"error: {month / file}: not a regular file ({words}); IRC data is plain files"
    )
    assert not (tmp_path / "t.parquet").exists()


@pytest.mark.parametrize("kind", ["fifo", "zero"])
def test_ingest_refuses_an_archive_that_is_not_regular_at_once(tmp_path: Path, kind: str) -> None:
    archive = tmp_path / "holdem.199504.tgz"
    words = _special(archive, kind)
    with unblocked_after(archive, 20):
        started = time.monotonic()
        code, lines = run_cli("ingest", str(archive), "--out", str(tmp_path / "t.parquet"))
    assert time.monotonic() - started < 10 and code == 1
    assert one_error_line(lines) == (
        f"error: {archive}: not a regular file ({words}); IRC data is plain files"
    )


def _archive(path: Path, members: list[tuple[tarfile.TarInfo, bytes]]) -> Path:
    with tarfile.open(path, "w:gz", format=tarfile.PAX_FORMAT) as tar:
        for info, data in members:
            info.size = len(data) if info.isfile() else 0
            tar.addfile(info, io.BytesIO(data) if info.isfile() else None)
    return path


def _member(name: str, data: bytes = b"", **fields: object) -> tuple[tarfile.TarInfo, bytes]:
    info = tarfile.TarInfo(name)
    for key, value in fields.items():
        setattr(info, key, value)
    return info, data


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"type": tarfile.SYMTYPE, "linkname": "/dev/zero"}, "a symbolic link"),
        ({"type": tarfile.FIFOTYPE}, "a FIFO"),
        ({"type": tarfile.CHRTYPE, "devmajor": 1, "devminor": 5}, "a character device"),
    ],
)
def test_ingest_refuses_an_archive_member_that_is_not_regular(
    tmp_path: Path, fields: dict, words: str
) -> None:
    archive = _archive(
        tmp_path / "holdem.199504.tgz",
        [
            _member("holdem/199504/hdb", **fields),
            _member("holdem/199504/hroster", MINIMAL["hroster"] + b"\r\n"),
        ],
    )
    code, lines = run_cli("ingest", str(archive), "--out", str(tmp_path / "t.parquet"))
    assert code == 1
    assert one_error_line(lines) == (
        f"error: {archive}:holdem/199504/hdb: not a regular file in the archive ({words}); "
        "IRC data is plain files"
    )


def test_ingest_refuses_a_huge_tar_header_before_reading_it(tmp_path: Path) -> None:
    # 2 MiB of pax header (a few KB compressed): tarfile alone would read it whole.
    info, data = _member("holdem/199504/hdb", MINIMAL["hdb"] + b"\r\n")
    info.pax_headers = {"comment": "x" * (2 * 1024 * 1024)}
    archive = _archive(tmp_path / "holdem.199504.tgz", [(info, data)])
    assert archive.stat().st_size < 100_000
    code, lines = run_cli("ingest", str(archive), "--out", str(tmp_path / "t.parquet"))
    assert code == 1
    line = one_error_line(lines)
    assert re.fullmatch(
        rf"error: {re.escape(str(archive))}: a tar header of 2,097,\d{{3}} bytes, more than "
        r"the 1,048,576 an IRC archive's names need \(not IRC data\?\)",
        line,
    ), line


def test_ingest_reads_at_most_the_cap_of_a_file_that_grows(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # hdb is small when its size is checked and 50,000 bytes when read: the read stops one
    # byte past the cap, and the file is refused.
    month = write_minimal(tmp_path)
    monkeypatch.setattr(irc_sources, "MAX_FILE_BYTES", 1_000)
    opened = irc_sources._open_regular

    @contextlib.contextmanager
    def grows(path: Path) -> Iterator[tuple[io.BufferedReader, int]]:
        with opened(path) as (handle, size):
            path.write_bytes(b"7" * 50_000)  # the same inode: the handle reads the new bytes
            yield handle, size

    monkeypatch.setattr(irc_sources, "_open_regular", grows)
    with pytest.raises(irc_sources.IngestError, match=r"hdb: 1,001 bytes, more than the 1,000"):
        ingest_table([month], tmp_path / "t.parquet")


# --- ingest: a corrupt timestamp anywhere is a malformed line --------------------------------


@pytest.mark.parametrize(
    ("file", "old", "new"),
    [
        ("hdb", b"797241924", b"79724x924"),
        ("hroster", b"797241924", b"79724x924"),
        ("hroster", b"797241924", b"9999999999999999999"),  # beyond int64
        ("pdb/pdb.MrX", b"797241924", b"79724x924"),
        ("pdb/pdb.horseplay", b"797241924", b"9999999999999999999"),
        ("pdb/pdb.MrX", b" kc kc 1015 80 0 Ad Ts", b""),  # timestamp fine, line cut short
    ],
)
def test_a_corrupt_line_in_any_file_is_a_malformed_line(
    tmp_path: Path, file: str, old: bytes, new: bytes
) -> None:
    month = write_minimal(tmp_path, file, old, new)
    summary = ingest_table([month], tmp_path / "t.parquet").to_json()
    assert summary["malformed_lines"] == 1 and summary["buckets_add_up"]
    assert summary["dropped"]["malformed_line"] == 1, summary["dropped"]
    assert summary["dropped"]["missing_pdb_line"] == summary["dropped"]["roster_mismatch"] == 0
    assert summary["malformed_examples"][0].startswith(f"{month}/{file}:1: not a")


def test_only_the_hand_of_a_corrupt_line_is_malformed_in_a_real_month(tmp_path: Path) -> None:
    # Hand A loses player X's pdb timestamp to corruption; hand B of other players loses a pdb
    # line outright. A is malformed, B is missing a line, every other hand is as it was.
    month = tmp_path / "holdem" / "199504"
    shutil.copytree(SAMPLE, month)
    before = ingest_table([month], tmp_path / "before.parquet").to_json()
    kept = pq.read_table(tmp_path / "before.parquet", columns=["hand_id", "player"])
    players: dict[str, set[str]] = {}
    for hand, player in zip(
        *(kept.column(c).to_pylist() for c in ("hand_id", "player")), strict=True
    ):
        players.setdefault(hand.rsplit("/", 1)[1], set()).add(player)
    (hand_a, (x, *_)), *others = sorted((t, sorted(p)) for t, p in players.items())
    hand_b, (y, _) = next((t, p) for t, p in others if x not in p)

    def edit(nick: str, stamp: str, line_to: bytes | None) -> None:
        path = month / "pdb" / f"pdb.{nick}"
        lines = path.read_bytes().split(b"\n")
        (i,) = [i for i, line in enumerate(lines) if line.split()[1:2] == [stamp.encode()]]
        lines[i : i + 1] = [] if line_to is None else [line_to]
        path.write_bytes(b"\n".join(lines))

    edit(x, hand_a, f"{x} 79x{hand_a[3:]} 2 1 Bc k k k 1000 10 20\r".encode())
    edit(y, hand_b, None)
    after = ingest_table([month], tmp_path / "after.parquet").to_json()
    assert after["kept_hands"] == before["kept_hands"] - 2
    assert after["malformed_lines"] == 1
    expected = {**before["dropped"], "malformed_line": 1, "missing_pdb_line": 1}
    assert after["dropped"] == expected


# --- tournaments: the same seeds, the same bytes ----------------------------------------------


def test_tournament_same_seeds_same_bytes_with_timings_apart(tmp_path: Path) -> None:
    games = ["tournament", "--vs", "random", "call", "raise", "--hands", "2000", "--seeds", "0-2"]
    for out, jobs in (("a", "1"), ("b", "2")):
        code, lines = run_cli(*games, "--out", str(tmp_path / out), "--jobs", jobs, "-q")
        assert code == 0, lines
    first, second = folder_bytes(tmp_path / "a"), folder_bytes(tmp_path / "b")
    timings = [json.loads(files.pop("timings.json", b"{}")) for files in (first, second)]
    assert sorted(first) == [
        "per_seed.csv",
        "per_seed.png",
        "report.json",
        "report.md",
        *(f"seeds/{m}-vs-random/seed-{k}.json" for m in ("call", "raise") for k in range(3)),
    ]
    assert first == second
    text = b"".join(data for name, data in first.items() if not name.endswith(".png"))
    assert not re.search(rb"seconds|hands_per_second|hands/s", text)
    assert [t["jobs"] for t in timings] == [1, 2] and timings[0]["seeds_reused"] == 0
    assert timings[0]["wall_seconds"] > 0 and len(timings[0]["seeds_played"]) == 6
    assert all(s["seconds"] > 0 and s["hands_per_second"] > 0 for s in timings[0]["seeds_played"])


def test_tournament_reuses_a_seed_saved_with_timings_by_an_older_pokerirl(tmp_path: Path) -> None:
    games = ["tournament", "call", "random", "--hands", "2000", "--seeds", "0-1", "-q"]
    code, lines = run_cli(*games, "--out", str(tmp_path))
    assert code == 0, lines
    report = (tmp_path / "report.json").read_bytes()
    saved = tmp_path / "seeds" / "call-vs-random" / "seed-1.json"
    record = json.loads(saved.read_text())  # the layout before: timings in the result
    record["result"].update(seconds=0.25, hands_per_second=8000.0)
    record["result"]["estimate"]["mbb_per_hand"] += 1.0  # proof that the file is what is read
    saved.write_text(json.dumps(record, indent=2))
    old = saved.read_bytes()
    code, lines = run_cli(*games, "--out", str(tmp_path))
    assert code == 0, lines
    timings = json.loads((tmp_path / "timings.json").read_text())
    assert timings["seeds_reused"] == 2 and timings["hands_played"] == 0
    assert saved.read_bytes() == old  # reused as it is, not rewritten
    seeds = json.loads((tmp_path / "report.json").read_text())["matchups"][0]["seeds"]
    before = json.loads(report)["matchups"][0]["seeds"]
    assert seeds[1]["mbb_per_hand"] == before[1]["mbb_per_hand"] + 1.0
    assert seeds[0] == before[0]
