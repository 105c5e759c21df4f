"""Helpers shared by the test files, importable at module level (``from testkit import …``);
:mod:`conftest` offers the same as fixtures. The command line run in-process, folder
snapshots, and the tiny gym study budget."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from click.testing import Result
from typer.testing import CliRunner

# `pokerirl gym study` at tiny budgets: IRL and RL on real environments in seconds.
TINY_GYM_STUDY = ["--runs", "2", "--transitions", "1500", "--epochs", "2", "--eval-episodes", "2"]
TINY_GYM_STUDY += ["--timesteps", "2000", "--jobs", "2", "--quiet"]


@dataclass(frozen=True)
class Cli:
    """``pokerirl`` run in this process, as the tests' user types it.

    ``cli(*args)`` is click's ``Result``; ``cli.ok(*args)`` asserts exit code 0 (showing
    the output when not) and returns the output.
    """

    runner: CliRunner = field(default_factory=CliRunner)

    def __call__(self, *args: str | os.PathLike[str], **kwargs: object) -> Result:
        from pokerirl.cli import app  # the CLI's imports: only for the tests that run it

        return self.runner.invoke(app, [os.fspath(a) for a in args], **kwargs)

    def invoke(self, args: Sequence[str | os.PathLike[str]], **kwargs: object) -> Result:
        """``cli.invoke([...])``: :meth:`CliRunner.invoke`'s form, the app given."""
        return self(*args, **kwargs)

    def ok(self, *args: str | os.PathLike[str]) -> str:
        result = self(*args)
        assert result.exit_code == 0, result.output
        return result.output


def folder_bytes(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` by its relative path: what a byte comparison compares."""
    return {
        str(path.relative_to(folder)): path.read_bytes()
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


def folder_snapshot(folder: Path) -> dict[str, tuple[bytes, int]]:
    """Every file's bytes and inode: a file rewritten, even to the same bytes, shows."""
    return {
        str(path.relative_to(folder)): (path.read_bytes(), path.stat().st_ino)
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }
