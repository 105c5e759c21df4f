"""The ``pokerirl`` command group, its one-line error handling and the helpers every command
shares; the commands live beside it, by group (poker, studies, gym)."""

from __future__ import annotations

import sys
import warnings
from collections.abc import Sequence
from typing import Any, NoReturn

import typer
from typer.core import TyperGroup

from pokerirl import execution  # light: tqdm only; ray loads when chosen


def _command_line_errors() -> tuple[type[Exception], ...]:
    """Usage-error base classes: typer's own (recent typer vendors click, and its errors derive
    from TyperException) and click's (older typer runs on click)."""
    bases: list[type[Exception]] = []
    if hasattr(typer, "TyperException"):
        bases.append(typer.TyperException)
    try:
        import click
    except ImportError:
        pass
    else:
        bases.append(click.ClickException)
    return tuple(bases)


_COMMAND_LINE_ERRORS = _command_line_errors()


class OneLineErrors(TyperGroup):
    """The command group, with usage errors as one ``error: ...`` line (exit code 2) instead of
    click's usage text or typer's boxed panel, and warnings (such as the library's warning
    before it unpickles an ``rlcard:`` checkpoint) as one ``warning: ...`` line on stderr.
    Help (``--help``, or no arguments) is unchanged.

    Works wherever the group's ``main`` runs: the ``pokerirl`` script (``pokerirl.cli:app``),
    ``python -m pokerirl`` and typer's ``CliRunner``.
    """

    def main(
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        windows_expand_args: bool = True,
        **extra: Any,
    ) -> Any:
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, False, windows_expand_args, **extra)
        try:
            # Not standalone: click errors come here instead of being printed; typer.Exit(code)
            # and --help come back as the exit code, a command's normal end as its result.
            with warnings.catch_warnings():
                warnings.showwarning = _one_line_warning
                result = super().main(
                    args, prog_name, complete_var, False, windows_expand_args, **extra
                )
        except _COMMAND_LINE_ERRORS as error:
            if type(error).__name__ == "NoArgsIsHelpError":
                # No arguments: show the help, as typer does (rerun standalone).
                return super().main(
                    args, prog_name, complete_var, True, windows_expand_args, **extra
                )
            typer.secho(f"error: {_one_line(error)}", err=True, fg=typer.colors.RED)
            sys.exit(getattr(error, "exit_code", 2))
        except typer.Abort:
            typer.secho("error: aborted", err=True, fg=typer.colors.RED)
            sys.exit(1)
        sys.exit(result if isinstance(result, int) else 0)


def _one_line_warning(message: Warning | str, *_: Any, **__: Any) -> None:
    typer.secho(f"warning: {message}", err=True, fg=typer.colors.YELLOW)


def _one_line(error: Exception) -> str:
    """``pokerirl ingest: Missing option '--out' / '-o' (see pokerirl ingest --help)``"""
    message = " ".join(getattr(error, "format_message", error.__str__)().split())
    ctx = getattr(error, "ctx", None)
    if ctx is None:
        return message
    return f"{ctx.command_path}: {message.rstrip('.')} (see {ctx.command_path} --help)"


app = typer.Typer(
    name="pokerirl",
    help="Learn reward functions from real poker play (AIRL / Hybrid-AIRL on IRC hand histories).",
    cls=OneLineErrors,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def fail(message: str, code: int = 1) -> NoReturn:
    """Print a one-line error to stderr and exit non-zero, without a traceback."""
    typer.secho(f"error: {message}", err=True, fg=typer.colors.RED)
    raise typer.Exit(code)


def _backend(jobs: int, ray: str | None, threads: int = 1) -> execution.Backend:
    """The execution backend of a fan-out command: --ray, else $RAY_ADDRESS, else --jobs."""
    try:
        return execution.choose_backend(jobs=jobs, ray=ray, threads=threads)
    except ValueError as error:
        fail(str(error))


RAY_HELP = (
    "Run the units on the Ray cluster at ADDRESS (default: $RAY_ADDRESS when set), or 'local' "
    "for a private single-machine Ray. Results do not change."
)
INTERRUPTED = "interrupted: finished units are kept; rerun the same command to resume"


@app.command()
def version() -> None:
    """Print the package version."""
    from pokerirl import __version__

    typer.echo(__version__)
