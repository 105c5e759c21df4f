"""No long silence: a command's stderr, read over time as a user watches it, never pauses
for more than 10 s, and once its units run, their own progress keeps the bar moving every
few seconds even though each unit takes longer than that (issue 34: a study sat at "0/N" for
40-75 s)."""

from __future__ import annotations

import itertools
import os
import re
import subprocess
import threading
import time
from pathlib import Path

import pytest
from processes import command, environment

SILENCE = 10.0  # seconds: the longest pause allowed anywhere
IN_UNITS = 3.0  # seconds: the longest pause once the units report their progress
# Pauses are timed: with another test beside it on the same cores, a pause measures the other
# test. `make test` runs these alone.
pytestmark = pytest.mark.serial


def watch(args: list[str]) -> list[tuple[float, bytes]]:
    """Run ``pokerirl ARGS``; every chunk of its stderr with the time it arrived."""
    process = subprocess.Popen(command(*args), env=environment(), stdout=subprocess.DEVNULL,
                               stderr=subprocess.PIPE)  # fmt: skip
    chunks: list[tuple[float, bytes]] = []

    def read() -> None:
        assert process.stderr is not None
        while data := os.read(process.stderr.fileno(), 4096):
            chunks.append((time.monotonic(), data))

    reader = threading.Thread(target=read)
    started = time.monotonic()
    reader.start()
    assert process.wait(timeout=600) == 0, b"".join(c for _, c in chunks).decode()[-2000:]
    reader.join()
    return [(started, b""), *chunks, (time.monotonic(), b"")]


@pytest.mark.slow
def test_an_agent_set_reports_from_inside_its_seeds(tmp_path: Path) -> None:
    # Two seeds of about 6-10 s each on two workers: without progress from inside them the
    # bar would wait at 0/2 for a whole seed.
    args = ["agent", "train", "--out", str(tmp_path / "set"), "--seeds", "0-1", "--jobs", "2",
            "--hands", "12000", "--eval-every", "12000", "--eval-hands", "100"]  # fmt: skip
    chunks = watch(args)
    times = [t for t, _ in chunks]
    gaps = [b - a for a, b in itertools.pairwise(times)]
    assert max(gaps) < SILENCE, gaps
    # The bar's counts over time ("0.43/2"): fractions of a seed while the seeds run.
    counts = [(t, float(n)) for t, data in chunks
              for n in re.findall(rb"\| (\d+\.\d\d)/2 ", data)]  # fmt: skip
    inside = [t for t, n in counts if 0 < n < 2 and n != 1]
    assert inside, "no progress from inside the seeds"
    reported = [t for t in times if inside[0] <= t <= inside[-1]]
    assert max(b - a for a, b in itertools.pairwise(reported)) < IN_UNITS
    assert counts[-1][1] == 2.0
