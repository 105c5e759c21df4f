"""Issue 21, part A: the low layers' promises, through the commands that rely on them.

Errors name the user's path (never a hidden temporary one); ingest refuses what is not IRC
data in one line, reads at most its caps and counts every corrupt line as ``malformed_line``;
tournaments give the same bytes for the same seeds, with timings apart.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pokerirl.cli import app


def run_cli(*args: str) -> tuple[int, list[str]]:
    """Exit code and the non-empty lines printed (stdout and stderr)."""
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, [line for line in result.output.splitlines() if line.strip()]


def one_error_line(lines: list[str]) -> str:
    errors = [line for line in lines if line.startswith("error:")]
    assert len(errors) == 1, lines
    assert not any("Traceback" in line for line in lines), lines
    return errors[0]


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
    from pokerirl.irl.airl import TrainResult
    from pokerirl.irl.config import AIRLConfig
    from pokerirl.irl.nets import build_nets
    from pokerirl.irl.run import save_run

    config = AIRLConfig.for_algo("hairl", reward_hidden=(4,), policy_hidden=(4,))
    reward, policy = build_nets(config.net_spec(), obs_dim=2, action_dim=3, discrete=True)
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
