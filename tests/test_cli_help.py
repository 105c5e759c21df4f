"""``--help`` reads in an 80-column terminal: nothing cut or wider, every option explained,
and an option of fixed values lists them (``[rlcard|strength]``) instead of ``<str>``."""

from __future__ import annotations

import re
from collections.abc import Iterator

import pytest
import typer
from typer.testing import CliRunner

from pokerirl.cli import app


def _commands(command: object, path: tuple[str, ...] = ()) -> Iterator[tuple[str, ...]]:
    yield path
    for name, sub in getattr(command, "commands", {}).items():
        if not getattr(sub, "hidden", False):
            yield from _commands(sub, (*path, name))


COMMANDS = list(_commands(typer.main.get_command(app)))


def test_every_command_is_listed() -> None:
    assert {("study",), ("agent", "train"), ("gym", "irl"), ("exploit",)} <= set(COMMANDS)


@pytest.mark.parametrize("path", COMMANDS, ids=lambda path: " ".join(path) or "pokerirl")
def test_help_fits_80_columns_and_names_every_options_values(path: tuple[str, ...]) -> None:
    result = CliRunner().invoke(app, [*path, "--help"], terminal_width=80)
    assert result.exit_code == 0, result.output
    text = result.output
    assert [line for line in text.splitlines() if len(line) > 80] == []
    assert not re.findall(r"(--[\w-]+)[ =]<str>", text), "an option without its values or noun"
    options = text.split("\nOptions:\n", 1)[-1].splitlines() if "\nOptions:\n" in text else []
    # "  --name METAVAR  help", or a long "  --name METAVAR" whose help is on the next lines.
    bare = [line.strip() for k, line in enumerate(options)
            if re.match(r"  -", line) and not re.search(r"\S {2,}\S", line)
            and not (k + 1 < len(options) and re.match(r" {3,}\S", options[k + 1]))]  # fmt: skip
    assert bare == [], f"options without a help line: {bare}"
