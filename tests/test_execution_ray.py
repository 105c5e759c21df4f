"""The Ray backend on a real cluster: `ray start --head` with 2 CPUs, a temporary folder and
free ports of its own, started once for this module and stopped by the process ids it
recorded (never Ray's stop-everything command). If Ray cannot start, these tests fail with
the reason.

Agent sets and tournaments through `--ray ADDRESS` give the numbers and the model bytes of
local processes, from a driver whose working directory differs from the workers', and a
worker killed in the middle of a run is retried with identical results."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.execution import _descendants, ray_head

pytestmark = pytest.mark.slow

SET = ["--hands", "1024", "--eval-every", "1024", "--eval-hands", "100"]
SET += ["--concurrent-hands", "64", "-q"]


@pytest.fixture(scope="module")
def cluster() -> Iterator[str]:
    with ray_head(num_cpus=2) as address:  # raises ExecutionError with Ray's reason
        yield address


def invoke(*args: str) -> str:
    result = CliRunner().invoke(app, list(args))
    assert result.exit_code == 0, result.output
    return result.output


def weights(folder: Path) -> dict[str, bytes]:
    return {p.parent.name: p.read_bytes() for p in sorted(folder.glob("seed-*/model.pt"))}


def per_seed(folder: Path) -> list[tuple[str, int, float, float, float]]:
    report = json.loads((folder / "report.json").read_text())
    return [
        (m["agent_a"], s["seed"], s["mbb_per_hand"], s["std_error"], s["p_value"])
        for m in report["matchups"]
        for s in m["seeds"]
    ]


def test_agent_sets_and_tournaments_on_ray_equal_local_processes(
    cluster: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Relative paths from the driver's folder: Ray's workers run elsewhere and get bytes.
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    invoke("agent", "train", "--out", "ray-set", "--seeds", "0-3", "--ray", cluster, *SET)
    invoke("agent", "train", "--out", "local-set", "--seeds", "0-3", "--jobs", "1", *SET)
    assert (
        weights(Path("ray-set")) == weights(Path("local-set"))
        and len(weights(Path("ray-set"))) == 4
    )
    for name in ("unit.json", "config.json", "metrics.jsonl"):
        assert (
            Path("ray-set/seed-2", name).read_bytes() == Path("local-set/seed-2", name).read_bytes()
        )

    games = ["--vs", "random", "ray-set", "raise", "--hands", "20000", "--seeds", "0-3", "-q"]
    invoke("tournament", *games, "--out", "t-ray", "--ray", cluster)
    invoke("tournament", *games, "--out", "t-one", "--jobs", "1")
    invoke("tournament", *games, "--out", "t-two", "--jobs", "2")
    assert per_seed(Path("t-ray")) == per_seed(Path("t-one")) == per_seed(Path("t-two"))
    assert len({line[2] for line in per_seed(Path("t-ray"))}) == 8  # all different numbers
    timing = json.loads(Path("t-ray/timings.json").read_text())
    assert timing["backend"] == f"ray at {cluster}" and timing["seeds_reused"] == 0

    # The check, and RAY_ADDRESS picks Ray; a rerun reuses every seed.
    games = ["raise", "random", "--hands", "200000", "--seeds", "0-3", "-q"]
    monkeypatch.setenv("RAY_ADDRESS", cluster)
    invoke("tournament", *games, "--out", "big-ray")
    timing = json.loads(Path("big-ray/timings.json").read_text())
    monkeypatch.delenv("RAY_ADDRESS")
    invoke("tournament", *games, "--out", "big-local")
    assert per_seed(Path("big-ray")) == per_seed(Path("big-local"))
    assert timing["backend"].startswith("ray at")


def test_a_ray_worker_killed_mid_run_is_retried_with_identical_results(
    cluster: str, tmp_path: Path
) -> None:
    root = str(Path(__file__).resolve().parents[1])
    environment = {**os.environ, "PYTHONPATH": root, "RAY_ADDRESS": cluster}
    out = tmp_path / "set"
    command = [sys.executable, "-m", "pokerirl", "agent", "train", "--out", str(out)]
    driver = subprocess.Popen(
        [*command, "--seeds", "0-3", *SET],
        env=environment,
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    killed = None
    deadline = time.monotonic() + 120
    while killed is None:  # the cluster's processes are this test process's descendants
        assert driver.poll() is None and time.monotonic() < deadline, driver.communicate()
        for pid in _descendants(os.getpid()):
            try:
                title = Path(f"/proc/{pid}/cmdline").read_bytes()
            except OSError:
                continue
            if title.startswith(b"ray::run_unit"):  # a worker running a unit right now
                os.kill(pid, signal.SIGKILL)
                killed = pid
                break
        time.sleep(0.02)
    stdout, stderr = driver.communicate(timeout=300)
    assert driver.returncode == 0, stderr
    assert stdout.count("1,024 hands") == 4 and not list(out.glob("seed-*/.*"))
    invoke("agent", "train", "--out", str(tmp_path / "local"), "--seeds", "0-3", *SET)
    assert weights(out) == weights(tmp_path / "local")


def test_gym_study_on_ray_equals_local_processes(
    cluster: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("gymnasium")
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    tiny = ["--runs", "2", "--transitions", "1000", "--epochs", "1", "--eval-episodes", "1"]
    tiny += ["--timesteps", "600", "-q"]
    invoke("gym", "study", "MountainCar-v0", "--out", "ray-study", "--ray", cluster, *tiny)
    invoke("gym", "study", "MountainCar-v0", "--out", "local-study", "--jobs", "1", *tiny)
    for pattern in ("irl/*/run-*/reward.pt", "rl/*/run-*/model.pt", "summary.json"):
        ray = {p.relative_to("ray-study"): p.read_bytes() for p in Path("ray-study").glob(pattern)}
        local = {
            p.relative_to("local-study"): p.read_bytes() for p in Path("local-study").glob(pattern)
        }
        assert ray == local and ray, pattern
