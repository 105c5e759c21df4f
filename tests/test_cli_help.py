"""``--help`` reads in an 80-column terminal: nothing cut or wider, every option explained,
and an option of fixed values lists them (``[rlcard|strength]``) instead of ``<str>``."""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Any

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


@pytest.mark.parametrize(
    ("path", "configs"),
    [(("train",), ("AIRLConfig",)), (("agent", "train"), ("TrainConfig", "DQNConfig"))],
)
def test_settings_options_are_the_config_fields_with_their_help(
    path: tuple[str, ...], configs: tuple[str, ...]
) -> None:
    import dataclasses

    from pokerirl.agents import config as agents
    from pokerirl.irl import config as irl

    command: Any = typer.main.get_command(app)
    for name in path:
        command = command.commands[name]
    options = {p.name: p for p in command.params}
    offered = [
        item
        for config in configs
        for item in dataclasses.fields(getattr(agents, config, None) or getattr(irl, config))
        if "help" in item.metadata
    ]
    assert len(offered) >= 11
    for item in offered:  # declared once, in the dataclass: the flag's help is the field's
        assert options[item.name].help == item.metadata["help"], item.name


def test_settings_options_pass_only_what_the_command_line_gave() -> None:
    import dataclasses

    from pokerirl.cli.options import NO_SETTINGS, Settings, settings_options
    from pokerirl.settings import setting

    @dataclasses.dataclass(frozen=True, kw_only=True)
    class Toy:
        epochs: int = setting(5, help="Epochs.", show_default=True)
        hidden: tuple[int, ...] = setting((8,), help="Widths.")
        seed: int = setting(0, help="Seed.")
        gamma: float = 0.9  # no help: not offered

    toy = typer.Typer()
    seen: list[dict[str, object]] = []

    @toy.command()
    @settings_options(toy=Toy)
    def run(ctx: typer.Context, toy: Settings = NO_SETTINGS) -> None:
        seen.append(dict(toy))

    runner = CliRunner()
    assert runner.invoke(toy, []).exit_code == 0
    assert runner.invoke(toy, ["--epochs", "5", "--hidden", "4,2", "--seed", "3"]).exit_code == 0
    assert seen == [{}, {"epochs": 5, "hidden": (4, 2), "seed": 3}]  # a default is not given
    text = runner.invoke(toy, ["--help"], terminal_width=80).output
    assert "[default: 5" in text and "WIDTHS" in text and "--gamma" not in text
    assert runner.invoke(toy, ["--seed", "-1"]).exit_code == 2  # a seed's bounds
