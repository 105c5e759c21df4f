"""The ``pokerirl`` command group, its error contract and the helpers every command shares;
the commands live beside it, by group (poker, studies, gym).

The error contract (:mod:`pokerirl.errors`) is applied once, by the group, around every
command: a command raises (:class:`~pokerirl.errors.UsageError` for a command line that
cannot be run, the library's :class:`~pokerirl.errors.PokerIRLError` for the rest) and never
catches to print. :func:`on_error` gives a command its own Ctrl-C line or advice.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import os
import re
import sys
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, Literal, ParamSpec, TypeVar

import typer
from typer.core import TyperGroup

from pokerirl import execution  # light: tqdm only; ray loads when chosen
from pokerirl.errors import (
    DEBUG_VARIABLE,
    ConfigError,
    Remedy,
    UsageError,
    one_line_errors,
    sigterm_as_interrupt,
)
from pokerirl.game.encodings import EncodingName  # numpy only: the values help lists

P = ParamSpec("P")
T = TypeVar("T")

# The command line's words for each remedy (every command that writes has --out and
# --overwrite); the library's messages never hold them.
ADVICE: Mapping[Remedy, str] = {
    Remedy.RECOMPUTE: "use another --out, or --overwrite to recompute it",
    Remedy.REPLACE: "use another --out, or --overwrite to replace it",
    Remedy.ELSEWHERE: "use another --out",
}


def choices(values: Iterable[str]) -> str:
    """An option's metavar that lists its values, as ``--help`` shows them.

    >>> choices(("rlcard", "strength"))
    '[rlcard|strength]'
    """
    return f"[{'|'.join(values)}]"


ENCODING_CHOICES = choices(EncodingName)


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


class Default:
    """A typer option's default, read from a config dataclass's field: declared once, in the
    dataclass, and shown by ``--help``. Lazy: the module is imported when the default is used
    or shown, never when the command line starts. A tuple is given as the command line
    writes it (``raw,centered``).

    >>> Default("pokerirl.studies.poker.transfer:TransferConfig", "hands")()
    50000
    >>> str(Default("pokerirl.studies.poker.transfer:TransferConfig", "transforms"))
    'raw,centered,log_softmax,advantage'
    """

    def __init__(self, config: str, field: str) -> None:
        self.config, self.field = config, field

    def __call__(self) -> Any:
        module, _, name = self.config.partition(":")
        config = getattr(importlib.import_module(module), name)
        field = {f.name: f for f in dataclasses.fields(config)}[self.field]
        if field.default is dataclasses.MISSING:
            value = field.default_factory()  # type: ignore[operator]  # has one: no default
        else:
            value = field.default
        return ",".join(map(str, value)) if isinstance(value, tuple) else value

    def __str__(self) -> str:
        return str(self())

    def __repr__(self) -> str:
        return f"Default({self.config!r}, {self.field!r})"


def given(ctx: typer.Context, **options: T) -> dict[str, T]:
    """The ``options`` the command line set (not left at their default), for settings that
    a preset or a ``--config`` file gives otherwise."""
    left = ("DEFAULT", "DEFAULT_MAP")  # by name: typer's click or click's ParameterSource
    return {
        name: value
        for name, value in options.items()
        if getattr(ctx.get_parameter_source(name), "name", "DEFAULT") not in left
    }


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
    rich_markup_mode=None,  # plain help: fits 80 columns, no boxes cutting flag names
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


def echo(message: str = "", *, nl: bool = True) -> None:
    """``typer.echo`` of a line that may hold paths (see :func:`display`): a name that is
    not UTF-8 cannot stop a command after its work is done."""
    typer.echo(display(message), nl=nl)


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
        raise UsageError("--ray needs an address (HOST:PORT) or 'local'")
    backend = execution.choose_backend(jobs=jobs, ray=ray, threads=threads)
    if backend.kind == "ray" and backend.address != execution.LOCAL_RAY:
        # Before any work: a study would otherwise build its data first, then fail.
        execution.check_reachable(backend.address or "")
    return backend


RAY_HELP = (
    "Run the units on the Ray cluster at ADDRESS (default: $RAY_ADDRESS when set), or 'local' "
    "for a private single-machine Ray. Results do not change."
)
# --log-dir DIR, one option for every command that trains runs (typer options may be shared).
LOG_DIR = typer.Option(
    None,
    "--log-dir",
    metavar="DIR",
    help="Also write each run's scalars into DIR as TensorBoard event files and progress.csv "
    "(SB3's layout; needs pip install 'pokerirl[logs]'). metrics.jsonl stays the record.",
)


def write_logs(out: Path, log_dir: Path | None) -> None:
    """``--log-dir``: the scalars of the runs under ``out``, copied into ``log_dir``."""
    if log_dir is None:
        return
    from pokerirl.scalars import export_scalars

    written = export_scalars(out, log_dir)
    echo(f"scalars of {len(written)} runs -> {log_dir} (tensorboard --logdir {log_dir})")


INTERRUPTED = "interrupted: finished units are kept; rerun the same command to resume"
# The words of train and gym expert, rl and irl for the remedies of their run folders (their
# lines from before the library stopped naming flags).
RUN_ADVICE = {
    **ADVICE,
    Remedy.REPLACE: "pass --overwrite to replace",
    Remedy.ELSEWHERE: "choose another --out",
}


@app.callback()
def main(
    debug: bool = typer.Option(
        False, "--debug", help=f"Print the traceback of any error (as {DEBUG_VARIABLE}=1 does)."
    ),
) -> None:
    if debug:  # the environment: worker processes and every command's contract read it
        os.environ[DEBUG_VARIABLE] = "1"


@app.command()
def version() -> None:
    """Print the package version."""
    from pokerirl import __version__

    typer.echo(__version__)
