"""SIGTERM (SLURM, ``timeout``, ``docker stop``) is Ctrl-C for a real ``pokerirl`` process:
the same one line, exit code 143, finished units kept, workers gone, and a rerun resumes.

Sent to the driver alone (``docker stop``, ``kill PID``) and to its whole process group
(``timeout``, SLURM), where the local workers get it too."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
from processes import alive, command, descendants, environment

from pokerirl.store import Fate, Unit, check

pytestmark = pytest.mark.slow

# Four seeds of about a second each, two local workers.
TRAIN = ["--seeds", "0-3", "--jobs", "2", "--hands", "1536", "--eval-every", "1536"]
SMALL = ["--eval-hands", "100", "--concurrent-hands", "64", "-q"]
LINE = "error: interrupted: finished units are kept; rerun the same command to resume\n"






def _finished(out: Path) -> dict[str, bytes]:
    return {p.parent.name: p.read_bytes() for p in sorted(out.glob("seed-*/unit.json"))}


@pytest.mark.parametrize("to", ["driver", "group"])
def test_sigterm_is_ctrl_c_exit_143_and_a_rerun_resumes(to: str, tmp_path: Path) -> None:
    out = tmp_path / "set"
    args = command("agent", "train", "--out", str(out), *TRAIN, *SMALL)
    driver = subprocess.Popen(
        args,
        env=environment(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # a group of its own, as timeout and SLURM give it
    )
    workers: set[int] = set()
    deadline = time.monotonic() + 180
    while not _finished(out):
        workers.update(descendants(driver.pid))
        assert driver.poll() is None, driver.communicate()[1]
        assert time.monotonic() < deadline, "no seed finished in time"
        time.sleep(0.05)
    if to == "group":
        os.killpg(driver.pid, signal.SIGTERM)
    else:
        driver.send_signal(signal.SIGTERM)
    stdout, stderr = driver.communicate(timeout=60)

    assert driver.returncode == 143
    assert stderr == LINE  # the whole of it: no traceback, from the driver or a worker
    assert stdout == ""
    done = _finished(out)
    assert 1 <= len(done) < 4, "signalled too late to test anything"
    assert len(workers) >= 2
    deadline = time.monotonic() + 10
    while any(alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not [pid for pid in workers if alive(pid)], "a worker outlived the driver"
    record = json.loads(next(iter(done.values())))
    for name in done:  # finished seeds are whole units of these settings
        config = {**record["config"], "seed": int(name[5:])}
        unit = Unit(key=name, target=out / name, config=config, inputs=record["inputs"])
        assert check(unit).fate is Fate.REUSED
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # nothing half-written

    rerun = subprocess.run(args, env=environment(), capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stderr
    assert rerun.stdout.count("already finished with these settings, reused") == len(done)
    for name, data in done.items():  # kept as they were
        assert (out / name / "unit.json").read_bytes() == data
    assert len(_finished(out)) == 4
