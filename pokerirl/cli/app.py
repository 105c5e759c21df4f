"""The ``pokerirl`` command group, its one-line error handling and the helpers every command
shares; the commands live beside it, by group (poker, studies, gym)."""

from __future__ import annotations

import os
import re
import sys
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any, NoReturn

import typer
from typer.core import TyperGroup

from pokerirl import execution  # light: tqdm only; ray loads when chosen
from pokerirl.errors import (
    ADVICE,
    PokerIRLError,
    Remedy,
    UsageError,
    describe_os_error,
    report,
)


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
            typer.secho(f"error: {display_error(_one_line(error))}", err=True, fg=typer.colors.RED)
            sys.exit(getattr(error, "exit_code", 2))
        except typer.Abort:
            typer.secho("error: aborted", err=True, fg=typer.colors.RED)
            sys.exit(1)
        sys.exit(result if isinstance(result, int) else 0)


def _one_line_warning(message: Warning | str, *_: Any, **__: Any) -> None:
    typer.secho(f"warning: {display_error(str(message))}", err=True, fg=typer.colors.YELLOW)


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


def fail(message: str, code: int = 1) -> NoReturn:
    """Print a one-line error to stderr and exit non-zero, without a traceback."""
    typer.secho(f"error: {display_error(message)}", err=True, fg=typer.colors.RED)
    raise typer.Exit(code)


def echo(message: str = "", *, nl: bool = True) -> None:
    """``typer.echo`` of a line that may hold paths (see :func:`display`): a name that is
    not UTF-8 cannot stop a command after its work is done."""
    typer.echo(display(message), nl=nl)


def error_line(error: Exception, path: str | os.PathLike[str] | None = None) -> str:
    """An error's one line; an ``OSError`` as ``FILE: reason``, naming ``path`` (the user's)
    when the error names no file."""
    if not isinstance(error, OSError):
        return str(error)
    if error.filename is None and path is not None:
        return f"{os.fsdecode(path)}: {error.strerror or error}"
    return describe_os_error(error)


def advised(error: Exception, advice: Mapping[Remedy, str] = ADVICE) -> str:
    """An error's one line with the command line's advice for its remedy appended: the
    library names no flag (``out/run already holds files``), the command adds its own
    (``; pass --overwrite to replace``). An error without a remedy is its message."""
    found = report(error, advice) if isinstance(error, PokerIRLError) else None
    return str(error) if found is None else found[1]


@contextmanager
def usage_errors() -> Iterator[None]:
    """Settings checked before any work: a ``ValueError`` there is a usage error (exit 2,
    like the parser's own)."""
    try:
        yield
    except ValueError as error:
        fail(str(error), UsageError.exit_code)


MAX_SEED = 2**32 - 1  # the largest seed numpy's and Gymnasium's generators take
MAX_SEEDS = 10_000  # seeds in one --seeds list
SEED_OPTION: dict[str, Any] = {"min": 0, "max": MAX_SEED}  # typer.Option(..., **SEED_OPTION)


def seed_list(text: str | None) -> str | None:
    """Check a ``--seeds`` value (``0-19``, ``0-4,10``) before it is expanded: every seed
    within 0..2^32-1, at most :data:`MAX_SEEDS` of them (a typer callback: exit 2)."""
    if text is None:
        return None
    from pokerirl.seeds import parse_seeds

    count = 0
    for part in text.split(","):
        numbers = [int(n) for n in re.findall(r"\d+", part)]
        if any(n > MAX_SEED for n in numbers):
            raise typer.BadParameter(f"seeds must be at most {MAX_SEED:,}, got {max(numbers):,}")
        count += numbers[-1] - numbers[0] + 1 if len(numbers) == 2 else 1
    if count > MAX_SEEDS:
        raise typer.BadParameter(f"at most {MAX_SEEDS:,} seeds, got {count:,} in {text!r}")
    try:
        parse_seeds(text)
    except ValueError as error:
        raise typer.BadParameter(str(error)) from None
    return text


def _backend(jobs: int, ray: str | None, threads: int = 1) -> execution.Backend:
    """The execution backend of a fan-out command: --ray, else $RAY_ADDRESS, else --jobs."""
    if ray is not None and not ray.strip():
        fail("--ray needs an address (HOST:PORT) or 'local'")
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
