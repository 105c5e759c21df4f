"""Killed drivers, through the real command line: workers never outlive the driver, a rerun
completes a set with the bytes of an uninterrupted run, Ctrl-C stops cleanly, and a killed
`agent train` into a finished agent leaves that agent byte for byte."""

from __future__ import annotations

import json
import multiprocessing
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from processes import alive, as_from_a_shell, command, descendants, environment
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.store import Fate, Unit, check

pytestmark = [pytest.mark.slow, pytest.mark.serial]  # signals and timing: run alone

SMALL = ["--eval-hands", "100", "--concurrent-hands", "64", "-q"]
SET = ["--hands", "1536", "--eval-every", "1536", *SMALL]  # about a second a seed






def _wait_for(condition, process: subprocess.Popen, seconds: float = 120) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        assert process.poll() is None, process.stderr.read() if process.stderr else ""
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.05)


def _finished_seeds(out: Path) -> list[Path]:
    return sorted(p.parent for p in out.glob("seed-*/unit.json"))


def _weights(out: Path) -> dict[str, bytes]:
    return {p.parent.name: p.read_bytes() for p in sorted(out.glob("seed-*/model.pt"))}


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The reference set: seeds 0-7 in this process, one job."""
    out = tmp_path_factory.mktemp("reference") / "set"
    result = CliRunner().invoke(app, ["agent", "train", "--out", str(out), "--seeds", "0-7", *SET])
    assert result.exit_code == 0, result.output
    return out


def test_killing_the_driver_kills_its_workers_and_a_rerun_completes_the_set(
    tmp_path: Path, uninterrupted: Path
) -> None:
    out = tmp_path / "set"
    args = ["agent", "train", "--out", str(out), "--seeds", "0-7", "--jobs", "2", *SET]
    driver = subprocess.Popen(
        command(*args), env=environment(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    workers: set[int] = set()

    def first_seed_done() -> bool:
        workers.update(descendants(driver.pid))
        return bool(_finished_seeds(out))

    _wait_for(first_seed_done, driver)
    driver.send_signal(signal.SIGKILL)
    driver.wait()
    done = {p.name: (p / "unit.json").read_bytes() for p in _finished_seeds(out)}
    assert 1 <= len(done) < 8, "the driver was killed too late to test anything"
    assert len(workers) >= 2  # two workers (and multiprocessing's resource tracker)
    deadline = time.monotonic() + 15
    while any(alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not [pid for pid in workers if alive(pid)], "workers outlived their driver"

    rerun = subprocess.run(command(*args), env=environment(), capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stderr
    assert rerun.stdout.count("already finished with these settings, reused") == len(done)
    for name, record in done.items():  # finished seeds were kept as they were
        assert (out / name / "unit.json").read_bytes() == record
    # Local --jobs 2, killed and resumed == --jobs 1 in one go, byte for byte.
    assert _weights(out) == _weights(uninterrupted) and len(_weights(out)) == 8
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # nothing half-written


def test_workers_busy_with_long_units_die_with_the_driver(tmp_path: Path) -> None:
    script = (
        "import time\n"
        "from pokerirl.execution import Backend, map_units\n"
        "map_units(time.sleep, [(120,)] * 4, backend=Backend(jobs=2))\n"
    )
    driver = subprocess.Popen([sys.executable, "-c", script], env=environment())
    workers: set[int] = set()

    # Two workers, and with the fork server the server itself (it has the same command line).
    need = 3 if "forkserver" in multiprocessing.get_all_start_methods() else 2

    def two_workers() -> bool:
        for pid in descendants(driver.pid):
            if any(word in _cmdline(pid) for word in (b"spawn_main", b"forkserver")):
                workers.add(pid)
        return len(workers) >= need

    _wait_for(two_workers, driver, seconds=60)
    time.sleep(1)  # both are inside their two-minute unit now
    driver.send_signal(signal.SIGKILL)
    driver.wait()
    deadline = time.monotonic() + 5
    while any(alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not [pid for pid in workers if alive(pid)], "a busy worker outlived its driver"


def _cmdline(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""


def test_ctrl_c_stops_cleanly_and_keeps_finished_seeds(tmp_path: Path) -> None:
    out = tmp_path / "set"
    # Enough seeds that, under load, the set cannot finish between the first seed and the signal.
    args = ["agent", "train", "--out", str(out), "--seeds", "0-31", "--jobs", "2", *SET]
    inherited = signal.getsignal(signal.SIGINT)  # said if the command ignores Ctrl-C
    driver = subprocess.Popen(
        command(*args),
        env=environment(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=as_from_a_shell,
    )
    workers: set[int] = set()

    def first_seed_done() -> bool:
        workers.update(descendants(driver.pid))
        return bool(_finished_seeds(out))

    _wait_for(first_seed_done, driver)
    driver.send_signal(signal.SIGINT)
    _, stderr = driver.communicate(timeout=60)
    assert driver.returncode == 130, f"SIGINT here: {inherited}; stderr: {stderr[-2000:]}"
    assert stderr.strip().splitlines()[-1].startswith("error: interrupted: finished units")
    deadline = time.monotonic() + 5  # the fork server and resource tracker leave on EOF
    while any(alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not [pid for pid in workers if alive(pid)]
    record = json.loads((_finished_seeds(out)[0] / "unit.json").read_text())
    for folder in _finished_seeds(out):
        config = {**record["config"], "seed": int(folder.name[5:])}
        unit = Unit(key=folder.name, target=folder, config=config, inputs=record["inputs"])
        assert check(unit).fate is Fate.REUSED


def test_a_killed_overwrite_leaves_the_finished_agent_byte_for_byte(tmp_path: Path) -> None:
    agent = tmp_path / "agent"
    first = CliRunner().invoke(
        app,
        ["agent", "train", "--out", str(agent), "--hands", "256", "--eval-every", "256", *SMALL],
    )
    assert first.exit_code == 0, first.output
    before = {p.name: p.read_bytes() for p in agent.iterdir()}
    # Retrain it with other settings, long enough to be killed in the middle.
    args = ["agent", "train", "--out", str(agent), "--hands", "200000", "--overwrite", *SMALL]
    driver = subprocess.Popen(
        command(*args), env=environment(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    time.sleep(8)
    assert driver.poll() is None, "finished before it could be killed"
    driver.send_signal(signal.SIGKILL)
    driver.wait()
    assert {p.name: p.read_bytes() for p in agent.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["agent"]  # nothing beside it either
