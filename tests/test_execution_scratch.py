"""Workers' scratch folders (issue 21): what a unit leaves in the temporary folder goes with
its worker, a worker killed with a real SIGKILL included, and a later run removes what a
killed driver's workers left; folders of live processes, or that another process holds, and
anything not named as ours, stay."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from pokerirl import atomic
from pokerirl.execution import Backend, map_units

REPO = Path(__file__).resolve().parents[1]


def leave_a_folder_then_die_once(k: int, marks: str) -> str:
    """Leave a folder in the temporary folder, as units do (agents landed for a seed), and
    kill its own worker the first time unit k runs."""
    made = tempfile.mkdtemp(prefix="pokerirl-seed-")
    mark = Path(marks) / f"unit-{k}"
    if not mark.exists():
        mark.write_text(made)
        os.kill(os.getpid(), signal.SIGKILL)
    return made


def ours(folder: Path) -> list[Path]:
    """What is in ``folder`` but multiprocessing's own (``pymp-*``, this process's)."""
    return sorted(p for p in folder.iterdir() if not p.name.startswith("pymp-"))


def running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


@pytest.fixture
def temp(monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A temporary folder of this test's own, for the driver and (through it) its workers.

    A short path, not under ``tmp_path``: the fork server's socket goes in it, and an AF_UNIX
    path must fit in 107 characters (``tmp_path`` under a pytest-xdist worker did not)."""
    short = "/tmp" if os.path.isdir("/tmp") else None
    folder = Path(tempfile.mkdtemp(prefix="pokerirl-test-", dir=short))
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def test_a_killed_workers_scratch_goes_with_it(tmp_path: Path, temp: Path) -> None:
    marks = tmp_path / "marks"
    marks.mkdir()
    units = [(k, str(marks)) for k in range(3)]
    made = map_units(leave_a_folder_then_die_once, units, backend=Backend(jobs=2))
    left_by_the_dead = [Path((marks / f"unit-{k}").read_text()) for k in range(3)]
    for folder in map(Path, made + left_by_the_dead):  # every unit worked in a scratch folder
        assert folder.parent.parent == temp and folder.parent.name.startswith("pokerirl-scratch-")
    assert len({Path(p).parent for p in left_by_the_dead}) == 3  # three workers died
    assert ours(temp) == []


def test_a_later_run_removes_what_a_killed_drivers_workers_left(temp: Path) -> None:
    script = (
        "import time; from pokerirl.execution import Backend, map_units; "
        "map_units(time.sleep, [(60,), (60,)], backend=Backend(jobs=2))"
    )
    environment = {**os.environ, "PYTHONPATH": str(REPO), "TMPDIR": str(temp)}
    driver = subprocess.Popen([sys.executable, "-c", script], env=environment)
    deadline = time.monotonic() + 60
    while len(list(temp.glob("pokerirl-scratch-*"))) < 2:
        assert driver.poll() is None and time.monotonic() < deadline
        time.sleep(0.05)
    driver.kill()
    driver.wait()
    left = sorted(temp.glob("pokerirl-scratch-*"))
    workers = [int(folder.name.split("-")[2]) for folder in left]
    while any(map(running, workers)):  # they die with the driver, within a second
        assert time.monotonic() < deadline
        time.sleep(0.05)
    assert sorted(temp.glob("pokerirl-scratch-*")) == left  # and could not tidy up
    assert len(left) == 2

    gone = subprocess.Popen(["true"])
    gone.wait()
    held = temp / f"pokerirl-scratch-{gone.pid}-held"  # its owner is gone, another holds it
    live = temp / f"pokerirl-scratch-{os.getpid()}-live"  # its owner runs
    others = [temp / "pokerirl-seed-x", temp / "pokerirl-scratch-notapid-x"]  # not ours
    for folder in (held, live, *others):
        folder.mkdir()
    private_ray = temp / f"pokerirl-ray-{gone.pid}-r"  # a private Ray's, its driver gone
    (private_ray / "session").mkdir(parents=True)
    lock = atomic.lock_folder(held)
    try:
        assert map_units(pow, [(2, 3), (3, 2)], backend=Backend(jobs=2)) == [8, 9]
        assert ours(temp) == sorted([held, live, *others])
    finally:
        if lock is not None:
            os.close(lock)
