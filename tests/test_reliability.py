"""Issue 13: bad input gives one clear line and a non-zero exit, and changes nothing written.

Most ingest cases start from the issue's minimal month: one real kept hand (CRLF endings), with
one field changed.
"""

from __future__ import annotations

import fcntl
import io
import json
import os
import re
import signal
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import torch
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from irc_fixtures import real_month, write_month
from pokerirl.agents.checkpoint import save_agent
from pokerirl.agents.dqn import QNetwork
from pokerirl.agents.rlcard_import import UntrustedCheckpointWarning, load_rlcard_dqn
from pokerirl.cli import app
from pokerirl.datasets.ingest import ingest_table, summary_path
from pokerirl.game.bots import make_agent
from pokerirl.game.match import MAX_HANDS, check_match_size, play_match
from pokerirl.game.synth import write_synthetic_month
from pokerirl.parsers import irc_sources
from pokerirl.parsers.irc_sources import IngestError
from pokerirl.store import tidy

REPO = Path(__file__).resolve().parents[1]
SAMPLE = real_month()

MINIMAL: dict[str, bytes] = {
    "hdb": b"797241924 1 600 2 2/60 2/80 2/120 2/160 5c 9h 4h 6c 6s",
    "hroster": b"797241924 2 MrX horseplay",
    "pdb/pdb.MrX": b"MrX 797241924 2 1 Bcr b kc kc 1015 80 0 Ad Ts",
    "pdb/pdb.horseplay": b"horseplay 797241924 2 2 Brc c b b 1340 80 160 9s 9c",
}


def write_minimal(root: Path, file: str = "", old: bytes = b"", new: bytes = b"") -> Path:
    """The minimal month as ``root/holdem/199504``, with ``old`` replaced by ``new`` in
    ``file``."""
    folder = root / "holdem" / "199504"
    (folder / "pdb").mkdir(parents=True, exist_ok=True)
    for name, line in MINIMAL.items():
        if name == file:
            assert old in line
            line = line.replace(old, new, 1)
        (folder / name).write_bytes(line + b"\r\n")
    return folder


def run_cli(*args: str) -> tuple[int, list[str]]:
    """Exit code and the non-empty lines printed (stdout and stderr)."""
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, [line for line in result.output.splitlines() if line.strip()]


def one_error_line(lines: list[str]) -> str:
    errors = [line for line in lines if line.startswith("error:")]
    assert len(errors) == 1, lines
    assert not any("Traceback" in line or "weights_only" in line for line in lines), lines
    return errors[0]


# --- ingest ---------------------------------------------------------------------------------


def test_minimal_month_ingests_cleanly(tmp_path: Path) -> None:
    summary = ingest_table([write_minimal(tmp_path / "irc")], tmp_path / "t.parquet").to_json()
    assert summary["kept_hands"] == 1 and summary["malformed_lines"] == 0
    table = pq.read_table(tmp_path / "t.parquet").to_pydict()
    assert set(table["chips_in"]) == {80}
    assert {(p, b) for p, b in zip(table["player"], table["payoff_bb"], strict=True)} == {
        ("MrX", -8.0),
        ("horseplay", 8.0),
    }


@pytest.mark.parametrize(
    ("file", "old", "new", "bucket"),
    [
        # str.isdigit() is true for these Latin-1 digits; int() then fails on them.
        ("hdb", b"797241924", b"79724192\xb2", "malformed_line"),
        ("hdb", b"797241924", b"79724192\xb3", "malformed_line"),
        ("hdb", b"797241924", b"\xb97241924", "malformed_line"),
        ("hroster", b"797241924", b"79724192\xb2", "malformed_line"),
        ("pdb/pdb.MrX", b"797241924", b"79724192\xb2", "malformed_line"),
        # Beyond the table's int64 timestamp and int32 chips.
        ("hdb", b"797241924", b"9999999999999999999", "malformed_line"),
        ("hdb", b"797241924", b"12345678901234567890", "malformed_line"),
        ("pdb/pdb.MrX", b" 80 0 ", b" 4294967376 0 ", "malformed_line"),
        ("pdb/pdb.horseplay", b" 80 160 ", b" 80 4294967456 ", "malformed_line"),
        ("pdb/pdb.MrX", b" 80 0 ", b" 2147483648 0 ", "malformed_line"),
    ],
)
def test_corrupt_number_is_a_malformed_line(
    tmp_path: Path, file: str, old: bytes, new: bytes, bucket: str
) -> None:
    folder = write_minimal(tmp_path / "irc", file, old, new)
    out = tmp_path / "t.parquet"
    summary = ingest_table([folder], out).to_json()
    assert summary["malformed_lines"] == 1
    assert summary["kept_hands"] == 0
    assert summary["dropped"][bucket] == 1 and summary["buckets_add_up"]
    where = f"{file}:1"
    assert summary["malformed_examples"][0].startswith(f"{folder}/{where}: ")
    with pytest.raises(IngestError, match=re.escape(f"malformed line at {folder}/{where}")):
        ingest_table([folder], tmp_path / "strict.parquet", strict=True)


def test_cli_strict_corrupt_chips_is_one_line(tmp_path: Path) -> None:
    folder = write_minimal(tmp_path / "irc", "pdb/pdb.MrX", b" 80 0 ", b" 4294967376 0 ")
    code, lines = run_cli("ingest", str(folder), "--out", str(tmp_path / "t.parquet"), "--strict")
    assert code == 1
    assert "pdb.MrX:1: chips 4294967376 and 0 not within 0 and 2147483647" in one_error_line(lines)


def test_raises_beyond_int16_are_a_malformed_line(tmp_path: Path) -> None:
    n = 16_384  # both players raise n times preflop: 2n = 32,768 raises, beyond int16
    hdb = ["800000001 1 1 2 2/20 2/20 2/20 2/20 2c 7d 9h Ts Js"]
    pdb = {
        "pdb.Amy": [f"Amy 800000001 2 1 B{'r' * n}c k k k 1000 40 80 Kc Qc"],
        "pdb.Zed": [f"Zed 800000001 2 2 B{'r' * n} k k k 1000 40 0 As Ad"],
    }
    folder = write_month(tmp_path / "irc", hdb=hdb, hroster=["800000001 2 Amy Zed"], pdb=pdb)
    summary = ingest_table([folder], tmp_path / "t.parquet").to_json()
    assert summary["dropped"]["malformed_line"] == 1 and summary["kept_hands"] == 0
    assert "32768 raises in a round" in summary["malformed_examples"][0]


def test_archive_without_irc_data_is_an_error_and_keeps_the_table(tmp_path: Path) -> None:
    out = tmp_path / "t.parquet"
    ingest_table([write_minimal(tmp_path / "irc")], out)
    table, summary = out.read_bytes(), summary_path(out).read_bytes()
    archive = tmp_path / "notes.tgz"
    with tarfile.open(archive, "w:gz") as tar:
        info = tarfile.TarInfo("notes/readme.txt")
        info.size = 5
        tar.addfile(info, io.BytesIO(b"hello"))
    code, lines = run_cli("ingest", str(archive), "--out", str(out))
    assert code == 1
    assert one_error_line(lines) == f"error: {archive}: no IRC data here " + (
        "(no <channel>/<month>/hdb inside)"
    )
    assert out.read_bytes() == table and summary_path(out).read_bytes() == summary
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


def test_oversized_member_is_refused_before_it_is_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The caps are module settings; small ones stand in for a 200 MB member of a tiny .tgz.
    monkeypatch.setattr(irc_sources, "MAX_FILE_BYTES", 1_000)
    archive = tmp_path / "holdem.199504.tgz"
    line = MINIMAL["hdb"] + b"\r\n"
    with tarfile.open(archive, "w:gz") as tar:
        info = tarfile.TarInfo("holdem/199504/hdb")
        info.size = 20 * len(line)
        tar.addfile(info, io.BytesIO(line * 20))
    with pytest.raises(IngestError, match=r"holdem/199504/hdb: 1,120 bytes, more than the 1,000"):
        ingest_table([archive], tmp_path / "t.parquet")
    folder = write_minimal(tmp_path / "irc")
    (folder / "hdb").write_bytes(line * 20)
    with pytest.raises(IngestError, match=rf"{re.escape(str(folder))}/hdb: 1,120 bytes"):
        ingest_table([folder], tmp_path / "t.parquet")
    monkeypatch.setattr(irc_sources, "MAX_FILE_BYTES", 10_000)
    monkeypatch.setattr(irc_sources, "MAX_MONTH_BYTES", 1_150)
    with pytest.raises(IngestError, match=r"its month holds .* more than the 1,150"):
        ingest_table([folder], tmp_path / "t.parquet")


def test_unwritable_output_names_the_output_not_the_temporary(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = write_minimal(tmp_path / "irc")
    out = tmp_path / "t.parquet"

    def refuse(*_: object, **kwargs: object) -> str:
        raise PermissionError(13, "Permission denied", f"{kwargs['dir']}/.t.parquet.ingest-x")

    monkeypatch.setattr(tempfile, "mkdtemp", refuse)
    code, lines = run_cli("ingest", str(folder), "--out", str(out))
    assert code == 1
    assert one_error_line(lines) == f"error: {out}: cannot write (Permission denied)"


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_output_folder_names_the_output(tmp_path: Path) -> None:
    folder = write_minimal(tmp_path / "irc")
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    code, lines = run_cli("ingest", str(folder), "--out", str(locked / "t.parquet"))
    assert code == 1
    assert (
        one_error_line(lines) == f"error: {locked / 't.parquet'}: cannot write (Permission denied)"
    )


class _Killed(BaseException):
    """Stands for a kill at a given step."""


@pytest.mark.parametrize("killed_at", [1, 2])
def test_table_and_summary_never_mismatch(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, killed_at: int
) -> None:
    out = tmp_path / "t.parquet"
    ingest_table([write_minimal(tmp_path / "minimal")], out)  # 1 kept hand
    real_replace, calls = os.replace, []

    def replace(source: str | os.PathLike[str], target: str | os.PathLike[str]) -> None:
        calls.append(target)
        if len(calls) == killed_at:
            raise _Killed
        real_replace(source, target)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(_Killed):  # the swap is committed: its renames are the only os.replace
        ingest_table([write_month(tmp_path / "fixture")], out)  # 5 kept hands
    monkeypatch.undo()

    def kept() -> int:
        hands = len(set(pq.read_table(out).column("hand_id").to_pylist()))
        if summary_path(out).exists():  # never another ingest's summary beside the table
            assert json.loads(summary_path(out).read_text())["kept_hands"] == hands
        return hands

    assert kept() == (1 if killed_at == 1 else 5)
    tidy(tmp_path, key=out.name)  # what the next writer does first: the swap is finished
    assert kept() == 5 and summary_path(out).exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_stale_work_folder_is_removed_and_a_live_one_kept(tmp_path: Path) -> None:
    out = tmp_path / "t.parquet"
    stale = tmp_path / ".t.parquet.new-deadbeef"
    stale_before_the_store = tmp_path / ".t.parquet.ingest-deadbeef"  # ingest's own, earlier
    live = tmp_path / ".t.parquet.new-livelive"
    for folder in (stale, stale_before_the_store, live):
        folder.mkdir()
    descriptor = os.open(live, os.O_RDONLY)
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)  # as a running ingest holds it
        ingest_table([write_minimal(tmp_path / "irc")], out)
        assert not stale.exists() and not stale_before_the_store.exists() and live.is_dir()
    finally:
        os.close(descriptor)


@pytest.mark.slow
def test_killed_ingest_keeps_the_old_pair_and_its_folder_is_cleaned_next_time(
    tmp_path: Path,
) -> None:
    out = tmp_path / "out" / "t.parquet"
    out.parent.mkdir()
    ingest_table([write_minimal(tmp_path / "minimal")], out)
    table, summary = out.read_bytes(), summary_path(out).read_bytes()
    big = write_synthetic_month(tmp_path / "synth", hands=60_000, seed=0)
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
    }
    process = subprocess.Popen(
        [sys.executable, "-m", "pokerirl", "ingest", str(big), "--out", str(out), "-q"], env=env
    )
    try:
        deadline = time.monotonic() + 60
        while not [p for p in out.parent.iterdir() if p.name.startswith(".")]:
            assert process.poll() is None, "ingest ended before it could be killed"
            assert time.monotonic() < deadline
            time.sleep(0.002)
        os.kill(process.pid, signal.SIGKILL)
    finally:
        process.wait()
    assert process.returncode == -signal.SIGKILL
    leftovers = [p for p in out.parent.iterdir() if p.name.startswith(".")]
    assert leftovers  # a kill cannot clean up...
    assert out.read_bytes() == table and summary_path(out).read_bytes() == summary
    ingest_table([write_minimal(tmp_path / "minimal")], out)
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]  # ...the next run does


# --- byte flips of the real sample ----------------------------------------------------------

_PLANTED = [b"\xb2", b"\xb3", b"\xb9", b"12345678901234567890", b"9999999999999999999"]


def _sample_month(hands: int = 120) -> dict[str, bytes]:
    """The first ``hands`` hdb lines of the real sample, with their roster and pdb lines."""
    hdb = (SAMPLE / "hdb").read_bytes().split(b"\n")[:hands]
    stamps = {line.split()[0] for line in hdb}
    files = {"hdb": b"\n".join(hdb) + b"\n"}
    roster = [x for x in (SAMPLE / "hroster").read_bytes().split(b"\n") if x[:9] in stamps]
    files["hroster"] = b"\n".join(roster) + b"\n"
    for path in sorted((SAMPLE / "pdb").iterdir()):
        lines = [
            x for x in path.read_bytes().split(b"\n") if x.split()[1:2] and x.split()[1] in stamps
        ]
        if lines:
            files[f"pdb/{path.name}"] = b"\n".join(lines) + b"\n"
    return files


_SAMPLE_FILES = _sample_month()


@st.composite
def byte_flips(draw: st.DrawFn, files: dict[str, bytes]) -> dict[str, bytes]:
    """``files`` with 1 to 6 corruptions: flipped bits, random bytes, deleted bytes, new line
    breaks, and planted ``²``, ``³``, ``¹`` and 19- or 20-digit numbers over digit runs."""
    out = dict(files)
    names = sorted(out)
    for _ in range(draw(st.integers(1, 6))):
        name = draw(st.sampled_from(names[:2] + names[2:][:6]))  # hdb, hroster and some pdb
        data = out[name]
        if not data:
            continue
        kind = draw(st.sampled_from(["flip", "byte", "delete", "newline", "plant", "number"]))
        at = draw(st.integers(0, len(data) - 1))
        if kind == "flip":
            data = data[:at] + bytes([data[at] ^ (1 << draw(st.integers(0, 7)))]) + data[at + 1 :]
        elif kind == "byte":
            data = data[:at] + bytes([draw(st.integers(0, 255))]) + data[at + 1 :]
        elif kind == "delete":
            data = data[:at] + data[at + 1 :]
        elif kind == "newline":
            data = data[:at] + b"\n" + data[at:]
        else:
            runs = [m.span() for m in re.finditer(rb"[0-9]+", data)]
            start, end = runs[draw(st.integers(0, len(runs) - 1))]
            planted = draw(st.sampled_from(_PLANTED))
            if kind == "plant" and len(planted) == 1:  # a Latin-1 digit inside the number
                at = draw(st.integers(start, end - 1))
                data = data[:at] + planted + data[at + 1 :]
            else:
                data = data[:start] + planted + data[end:]
        out[name] = data
    return out


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_byte_flips_of_the_real_sample_never_crash_and_every_line_is_counted(
    data: st.DataObject,
) -> None:
    files = data.draw(byte_flips(_SAMPLE_FILES))
    lines = files["hdb"].split(b"\n")
    hdb_lines = len(lines) - (lines[-1] == b"")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "holdem" / "199504"
        (folder / "pdb").mkdir(parents=True)
        for name, content in files.items():
            (folder / name).write_bytes(content)
        summary = ingest_table([folder], Path(tmp) / "t.parquet").to_json()
        try:
            ingest_table([folder], Path(tmp) / "strict.parquet", strict=True)
        except IngestError as error:
            assert "\n" not in str(error)
    assert summary["hands_read_total"] == hdb_lines
    assert summary["kept_hands"] + sum(summary["dropped"].values()) == hdb_lines
    assert summary["buckets_add_up"]


# --- other commands -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--seed", "-1"], "error: pokerirl synth: Invalid value for '--seed'"),
        (["--hands", "1000001"], "error: --hands must be at most 1,000,000 (one month)"),
    ],
)
def test_synth_bad_values_are_one_line(tmp_path: Path, args: list[str], message: str) -> None:
    code, lines = run_cli("synth", "--out", str(tmp_path / "s"), *args)
    assert code == 2
    assert one_error_line(lines).startswith(message)
    assert not (tmp_path / "s").exists()


def test_huge_match_is_refused_before_allocating() -> None:
    code, lines = run_cli("match", "raise", "call", "--hands", "99999999999998")
    assert code == 2
    assert one_error_line(lines) == (
        f"error: hands must be at most {MAX_HANDS:,} per match, got 99,999,999,999,998"
    )
    with pytest.raises(ValueError, match="at most"):
        play_match(make_agent("raise"), make_agent("call"), hands=MAX_HANDS + 2, seed=0)
    with pytest.raises(ValueError, match="batch_size must be between 2 and"):
        check_match_size(10, duplicate=True, batch_size=10**12)
    check_match_size(MAX_HANDS, duplicate=True)


def test_huge_tournament_is_one_line_and_writes_nothing(tmp_path: Path) -> None:
    out = tmp_path / "report"
    code, lines = run_cli(
        "tournament", "raise", "call", "--hands", "99999999999998", "--seeds", "0-1",
        "--out", str(out), "--jobs", "1", "-q",
    )  # fmt: skip
    assert code == 2
    assert one_error_line(lines).startswith(f"error: hands must be at most {MAX_HANDS:,}")
    assert not out.exists()


@pytest.fixture
def agent(tmp_path: Path) -> Path:
    folder = tmp_path / "agent"
    save_agent(folder, QNetwork(hidden=(8,)), {"hidden": [8]})
    return folder


@pytest.mark.parametrize(
    ("file", "content", "message"),
    [
        ("config.json", b"[]", "config.json: cannot load agent: not an agent config"),
        ("config.json", b'{"format": "pokerirl-dqn", "hidden": "8"}', "config.json: cannot"),
        ("config.json", b"\xff\xfe{", "config.json: cannot load agent: not JSON"),
        ("model.pt", b"", "model.pt: cannot load agent: empty file"),
        ("model.pt", os.urandom(3000), "model.pt: cannot load agent: corrupt or truncated"),
        ("model.pt", None, "model.pt: cannot load agent: corrupt or truncated"),  # truncated
    ],
)
def test_bad_agent_folder_is_one_line_naming_the_file(
    agent: Path, file: str, content: bytes | None, message: str
) -> None:
    path = agent / file
    path.write_bytes(path.read_bytes()[:500] if content is None else content)
    code, lines = run_cli("match", str(agent), "raise", "--hands", "10", "--no-duplicate")
    assert code == 1
    line = one_error_line(lines)
    assert line.startswith(f"error: {agent / file}: cannot load agent: ") and message in line


def test_rlcard_checkpoint_without_q_estimator_is_one_line_and_warns(tmp_path: Path) -> None:
    path = tmp_path / "checkpoint_dqn.pt"
    torch.save({"agent_type": "DQNAgent", "num_actions": 4}, path)
    with (
        pytest.warns(UntrustedCheckpointWarning, match="runs any code"),
        pytest.raises(ValueError, match=r"not an RLCard DQNAgent checkpoint .no q_estimator."),
    ):
        load_rlcard_dqn(path)
    code, lines = run_cli("match", f"rlcard:{path}", "raise", "--hands", "10")
    assert code == 1
    assert one_error_line(lines) == (
        f"error: {path}: not an RLCard DQNAgent checkpoint (no q_estimator)"
    )
    warnings_printed = [line for line in lines if line.startswith("warning:")]
    assert warnings_printed == [
        f"warning: rlcard:{path}: unpickling an RLCard checkpoint runs any code it holds; "
        "load only files you trust"
    ]


def test_match_help_says_rlcard_runs_code() -> None:
    result = CliRunner().invoke(app, ["match", "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0
    assert "runs any code" in " ".join(result.output.split())


@pytest.mark.parametrize("content", ["[]", '"report"', "{}"])
def test_report_that_is_not_a_report_is_one_line(tmp_path: Path, content: str) -> None:
    (tmp_path / "report.json").write_text(content)
    code, lines = run_cli("report", str(tmp_path))
    assert code == 1
    assert one_error_line(lines).startswith(f"error: {tmp_path / 'report.json'}: not a")


# --- usage errors -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("args", "line"),
    [
        (["ingest"], "error: pokerirl ingest: Missing argument"),
        (["ingest", "x", "--out"], "error: Option '--out' requires an argument"),
        (["match", "a", "b", "--hands", "x"], "error: pokerirl match: Invalid value for '--hands'"),
        (["bogus"], "error: pokerirl: No such command 'bogus' (see pokerirl --help)"),
        (["agent", "train", "--bogus"], "error: pokerirl agent train: No such option: --bogus"),
    ],
)
def test_usage_errors_are_one_line(args: list[str], line: str) -> None:
    result = CliRunner().invoke(app, args, prog_name="pokerirl")
    assert result.exit_code == 2
    assert result.output.count("\n") == 1 and result.output.startswith(line), result.output


@pytest.mark.slow
def test_python_m_gives_the_same_one_line_and_help_still_works() -> None:
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
    }
    command = [sys.executable, "-m", "pokerirl"]
    done = subprocess.run([*command, "ingest"], env=env, capture_output=True, text=True)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr == (
        "error: pokerirl ingest: Missing argument 'sources' (see pokerirl ingest --help)\n"
    )
    helped = subprocess.run([*command, "ingest", "--help"], env=env, capture_output=True, text=True)
    assert helped.returncode == 0 and "Usage" in helped.stdout
    bare = subprocess.run(command, env=env, capture_output=True, text=True)
    assert bare.returncode == 2 and "Usage" in bare.stdout + bare.stderr
