"""The command line's side of the error contract (:mod:`pokerirl.errors`), and how its lines
are shown.

The contract is applied once, by the ``pokerirl`` group (:class:`OneLineErrors`, the class of
:data:`pokerirl.cli.app.app`), around every command: a command raises
(:class:`~pokerirl.errors.UsageError` for a command line that cannot be run, the library's
:class:`~pokerirl.errors.PokerIRLError` for the rest) and never catches to print.
:func:`on_error` gives a command its own Ctrl-C line or advice (:data:`INTERRUPTED`,
:data:`RUN_ADVICE`); :data:`ADVICE` holds the command line's words for the library's remedies,
which name no flag. :func:`display` and :func:`echo` show a line holding paths whose bytes are
not UTF-8.
"""

from __future__ import annotations

import functools
import os
import re
import sys
import warnings
from collections.abc import Callable, Mapping, Sequence
from types import TracebackType
from typing import Any, Literal, ParamSpec, TypeVar

import typer
from typer.core import TyperGroup

from pokerirl.errors import (
    ConfigError,
    Remedy,
    UsageError,
    one_line_errors,
    sigterm_as_interrupt,
)

P = ParamSpec("P")
T = TypeVar("T")

# The command line's words for each remedy (every command that writes has --out and
# --overwrite); the library's messages never hold them.
ADVICE: Mapping[Remedy, str] = {
    Remedy.RECOMPUTE: "use another --out, or --overwrite to recompute it",
    Remedy.REPLACE: "use another --out, or --overwrite to replace it",
    Remedy.ELSEWHERE: "use another --out",
}

INTERRUPTED = "interrupted: finished units are kept; rerun the same command to resume"
# The words of train and gym expert, rl and irl for the remedies of their run folders (their
# lines from before the library stopped naming flags).
RUN_ADVICE = {
    **ADVICE,
    Remedy.REPLACE: "pass --overwrite to replace",
    Remedy.ELSEWHERE: "choose another --out",
}


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
    """The command group: every command runs under the error contract (:func:`command_errors`,
    applied once here, around every command's invoke); the parser's usage errors are one
    ``error: ...`` line (exit code 2) instead of click's usage text or typer's boxed panel;
    warnings (such as the library's warning before it unpickles an ``rlcard:`` checkpoint)
    are one ``warning: ...`` line on stderr; SIGTERM is Ctrl-C (its line, exit code 143).
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
            # SIGTERM (SLURM, timeout, docker stop) takes Ctrl-C's path: its line, exit 143.
            with warnings.catch_warnings(), sigterm_as_interrupt():
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
            typer.secho(f"error: {display_error(_one_line(error))}", err=True, fg=typer.colors.RED)
            sys.exit(getattr(error, "exit_code", 2))
        except typer.Abort:
            typer.secho("error: aborted", err=True, fg=typer.colors.RED)
            sys.exit(1)
        sys.exit(result if isinstance(result, int) else 0)

    def invoke(self, ctx: Any) -> Any:
        # Around the callback (--debug) and the command, nested groups included; the parser's
        # own errors pass through to main.
        with command_errors():
            return super().invoke(ctx)


class command_errors(one_line_errors):  # lower case: a decorator
    """:class:`~pokerirl.errors.one_line_errors` as the command line shows it: paths'
    undecodable bytes as ``\\xff``; a closed stdout (``pokerirl report DIR | head``) is left
    to click, which exits quietly."""

    def __init__(
        self, *, interrupted: str = "interrupted", advice: Mapping[Remedy, str] = ADVICE
    ) -> None:
        super().__init__(interrupted=interrupted, advice=advice, display=display_error)

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> Literal[False]:
        if isinstance(error, BrokenPipeError):
            return False
        return super().__exit__(kind, error, trace)


def on_error(
    *, interrupted: str = "interrupted", advice: Mapping[Remedy, str] = ADVICE
) -> Callable[[Callable[P, T]], Callable[P, T]]:
    """A command's own error contract: its Ctrl-C line (a resumable command says how to
    resume: :data:`INTERRUPTED`) or its words for the remedies. Put it below
    ``@app.command()``; the group's contract covers every other command."""

    def decorate(command: Callable[P, T]) -> Callable[P, T]:
        @functools.wraps(command)
        def run(*args: P.args, **kwargs: P.kwargs) -> T:
            with command_errors(interrupted=interrupted, advice=advice):
                return command(*args, **kwargs)

        return run

    return decorate


def settings_from_options(make: Callable[..., T], /, *args: Any, **options: Any) -> T:
    """``make(*args, **options)``: a frozen config dataclass (or the function that builds
    one) from a command's options, checked before any work. Its :class:`ConfigError` is a
    usage error (exit code 2, like the parser's own).

    >>> from pokerirl.studies.poker.transfer import TransferConfig
    >>> settings_from_options(TransferConfig, hands=10).hands
    10
    >>> settings_from_options(TransferConfig, hands=0)
    Traceback (most recent call last):
    ...
    pokerirl.errors.UsageError: need seeds, hands >= 1 and an even eval_hands >= 2
    """
    try:
        return make(*args, **options)
    except ConfigError as error:
        raise UsageError(str(error)) from error


def _one_line_warning(message: Warning | str, *_: Any, **__: Any) -> None:
    typer.secho(f"warning: {display_error(str(message))}", err=True, fg=typer.colors.YELLOW)


def _one_line(error: Exception) -> str:
    """``pokerirl ingest: Missing option '--out' / '-o' (see pokerirl ingest --help)``"""
    message = " ".join(getattr(error, "format_message", error.__str__)().split())
    ctx = getattr(error, "ctx", None)
    if ctx is None:
        return message
    return f"{ctx.command_path}: {message.rstrip('.')} (see {ctx.command_path} --help)"


def display(text: str) -> str:
    r"""``text`` as a terminal shows it: the bytes of a path that are not UTF-8 (which Python
    holds as surrogates) as ``\xff``. JSON text is unchanged (it escapes them itself).

    >>> display(os.fsdecode(b"runs/caf\xe9") + ": Permission denied")
    'runs/caf\\xe9: Permission denied'
    """
    try:
        return os.fsencode(text).decode("utf-8", "backslashreplace")
    except UnicodeError:  # a surrogate no file name holds
        return text.encode("utf-8", "backslashreplace").decode("utf-8")


def display_error(text: str) -> str:
    r"""An error line as :func:`display` shows it, with the undecodable bytes of a path
    quoted by ``repr`` (``'caf\udce9'``, as Python's own messages quote paths) as ``\xe9`` too.

    >>> display_error("unknown agent " + repr(os.fsdecode(b"caf\xe9")))
    "unknown agent 'caf\\xe9'"
    """
    return display(_REPR_SURROGATE.sub(r"\\x\1", text))


_REPR_SURROGATE = re.compile(r"\\udc([89a-f][0-9a-f])")  # an undecodable byte, as repr shows it


def echo(message: str = "", *, nl: bool = True) -> None:
    """``typer.echo`` of a line that may hold paths (see :func:`display`): a name that is
    not UTF-8 cannot stop a command after its work is done."""
    typer.echo(display(message), nl=nl)
