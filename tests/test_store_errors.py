"""The error contract (pokerirl.errors): library errors and OSErrors are one line and exit 1,
usage errors exit 2, Ctrl-C 130, bugs keep their traceback, POKERIRL_DEBUG shows every
traceback; through a real typer command too, and across a worker process."""

from __future__ import annotations

import io

import pytest
import typer
from typer.testing import CliRunner

from pokerirl.cli.errors import ADVICE
from pokerirl.errors import (
    PokerIRLError,
    Remedy,
    UsageError,
    debug_enabled,
    describe_os_error,
    one_line_errors,
)
from pokerirl.execution import Backend, map_units
from pokerirl.store import UnitConflict


class TableError(PokerIRLError, ValueError):
    """A library error as round 2 declares them: the package's class, on the base."""


def run(error: BaseException, **options: object) -> tuple[int | str | None, str]:
    stream = io.StringIO()
    with pytest.raises(SystemExit) as done, one_line_errors(stream=stream, **options):  # type: ignore[arg-type]
        raise error
    return done.value.code, stream.getvalue()


def test_library_errors_are_one_line_with_the_command_lines_advice() -> None:
    assert run(TableError("out/t.parquet: not a table\n  (row 3)"), debug=False) == (
        1,
        "error: out/t.parquet: not a table (row 3)\n",
    )
    conflict = UnitConflict("runs/run-0 was made with another configuration (seed 1 -> 2)",
                            remedy=Remedy.RECOMPUTE)  # fmt: skip
    assert run(conflict, debug=False) == (1, f"error: {conflict}\n")  # no words: the message
    assert run(conflict, debug=False, advice=ADVICE) == (
        1,
        "error: runs/run-0 was made with another configuration (seed 1 -> 2); "
        "use another --out, or --overwrite to recompute it\n",
    )
    advice = {Remedy.RECOMPUTE: "pass overwrite=True"}
    assert run(conflict, debug=False, advice=advice)[1].endswith("; pass overwrite=True\n")


def test_usage_errors_exit_2_os_errors_name_their_file_and_ctrl_c_exits_130() -> None:
    assert run(UsageError("--runs must be at least 1"), debug=False) == (
        2,
        "error: --runs must be at least 1\n",
    )
    denied = PermissionError(13, "Permission denied", "out/runs")
    assert run(denied, debug=False) == (1, "error: out/runs: Permission denied\n")
    moved = OSError(18, "Invalid cross-device link", "a", None, "b")  # as os.rename raises
    assert describe_os_error(moved) == "a -> b: Invalid cross-device link"
    assert describe_os_error(OSError("no details")) == "no details"
    resume = "interrupted: finished units are kept; rerun the same command to resume"
    assert run(KeyboardInterrupt(), debug=False, interrupted=resume) == (130, f"error: {resume}\n")


def test_a_bug_keeps_its_traceback() -> None:
    stream = io.StringIO()
    with pytest.raises(KeyError), one_line_errors(stream=stream, debug=False):
        raise KeyError("epochs")
    with pytest.raises(ValueError):  # a plain ValueError is a bug too, from round 2 on
        with one_line_errors(stream=stream, debug=False):
            raise ValueError("no such thing")
    assert stream.getvalue() == ""


def test_pokerirl_debug_shows_the_traceback_of_any_error(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("POKERIRL_DEBUG", "1")
    assert debug_enabled()
    code, text = run(TableError("bad table"))
    assert code == 1 and text.startswith("Traceback (most recent call last):")
    assert "TableError: bad table" in text and text.endswith("error: bad table\n")
    for value, enabled in (("0", False), ("", False), ("yes", True), ("TRUE", True)):
        assert debug_enabled({"POKERIRL_DEBUG": value}) is enabled


def test_a_typer_command_under_the_decorator() -> None:
    app = typer.Typer(pretty_exceptions_enable=False)

    @app.command()
    @one_line_errors()
    def train(runs: int = typer.Option(1, "--runs"), debug: bool = False) -> None:
        if runs < 1:
            raise UsageError("--runs must be at least 1")
        if runs == 2:
            raise FileNotFoundError(2, "No such file or directory", "table.parquet")
        if runs == 3:
            raise KeyError("a bug")
        typer.echo(f"{runs} runs")

    runner = CliRunner()
    assert runner.invoke(app, ["--runs", "4"]).output == "4 runs\n"
    usage = runner.invoke(app, ["--runs", "0"])
    assert (usage.exit_code, usage.output) == (2, "error: --runs must be at least 1\n")
    missing = runner.invoke(app, ["--runs", "2"])
    assert missing.exit_code == 1
    assert missing.output == "error: table.parquet: No such file or directory\n"
    bug = runner.invoke(app, ["--runs", "3"])
    assert bug.exit_code == 1 and isinstance(bug.exception, KeyError)  # not turned into a line
    assert "--runs" in runner.invoke(app, ["--help"]).output  # the signature is typer's still


def refuse(n: int) -> None:
    raise UnitConflict(f"unit {n} was made with another configuration", remedy=Remedy.RECOMPUTE)


def test_a_library_error_raised_in_a_worker_arrives_whole() -> None:
    with pytest.raises(UnitConflict) as refused:
        map_units(refuse, [(1,), (2,)], backend=Backend(jobs=2))
    assert refused.value.remedy is Remedy.RECOMPUTE
    assert str(refused.value).startswith("unit ")
