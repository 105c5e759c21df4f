"""The error contract of every command (pokerirl/errors.py, pokerirl/cli/errors.py).

Every command of ``pokerirl`` (the click tree, hidden commands included) runs with a bad
input of each kind: a usage error (exit 2), a missing input file (exit 1, the line names it)
and a setting or file the library refuses (``ConfigError``, ``InputError``: exit 1); each is
one ``error: ...`` line on stderr, without a traceback. A bug keeps its traceback; ``--debug``
and ``POKERIRL_DEBUG=1`` print the traceback of a user's error too. A command added without
its cases fails :func:`test_every_command_has_its_cases`.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.errors import DEBUG_VARIABLE

ROOT = Path(__file__).resolve().parents[1]


def _tree(command: Any, path: tuple[str, ...] = ()) -> list[str]:
    """The command paths under ``command`` (``gym rl``), hidden ones included."""
    children = getattr(command, "commands", None)
    if children is None:
        return [" ".join(path)]
    return [p for name, child in children.items() for p in _tree(child, (*path, name))]


COMMANDS = sorted(_tree(typer.main.get_command(app)))

# Placeholders: {F} a path that does not exist, {G} a file of garbage, {E} an empty folder,
# {A} a plain file, {O} an output folder (it exists, empty), {T} a file that is not TOML,
# {R} a folder whose report.json is corrupt.
USAGE: dict[str, str] = {  # a command line that cannot be run: exit 2
    "version": "version --bogus",
    "data list": "data list --bogus",
    "data fetch": "data fetch irc --sha256 nope",
    "data turn-table": "data turn-table --bogus",
    "ingest": "ingest {G}",  # no --out
    "synth": "synth --out {O} --hands lots",
    "match": "match random call --hands lots",
    "tournament": "tournament random call --out {O} --alpha 2",
    "exploit": "exploit random --out {O} --check-until nope",
    "train": "train {G} --out {O} --epochs 0",
    "reward-card": "reward-card {E} --table {G} --out {O} --transform nope",
    "demo": "demo --out {O} --jobs 0",
    "study": "study {G} --out {O} --preset nope",
    "transfer": "transfer {E} --out {O} --transforms nope",
    "report": "report {E} --format xml",
    "sweep": "sweep {E} --out {O} --preset nope",
    "agent train": "agent train --out {O} --config {T}",
    "gym expert": "gym expert Nope-v0 --out {O}",
    "gym experts": "gym experts --format xml",
    "gym collect": "gym collect MountainCar-v0 -n 0 --out {O}/x.parquet",
    "gym rl": "gym rl MountainCar-v0 --out {O}",  # neither --reward-run nor --env-reward
    "gym irl": "gym irl MountainCar-v0 --out {O} --algo nope",
    "gym reward-map": "gym reward-map MountainCar-v0 --out {O}/x.png",  # no folders
    "gym study": "gym study MountainCar-v0 --out {O} --rl-backend nope",
    "gym sweep": "gym sweep MountainCar-v0 --param alpha=0 --out {O} --seed 4294967295 --runs 2",
    "leduc solve": "leduc solve --rules nope --out {O}",
    "leduc exploit": "leduc exploit {G} --bogus",
    "leduc agreement": "leduc agreement {G}",  # no B.json
    "leduc synth": "leduc synth --expert {G} --out {O}/d.npz --hands lots",
    "leduc study": "leduc study --out {O} --preset nope",
}
MISSING: dict[str, str | None] = {  # an input that is not there: exit 1, naming it
    "version": None,  # reads nothing
    "data list": None,  # reads the catalog and the cache's listing
    "data fetch": "data fetch irc --url {F}",
    "data turn-table": None,  # reads nothing but its own cache file
    "ingest": "ingest {F} --out {O}/t.parquet",
    "synth": None,
    "match": "match {F} random --hands 10",
    "tournament": "tournament {F} random --out {O} --hands 4 --seeds 0-1",
    "exploit": "exploit {F} --out {O} --hands 2",
    "train": "train {F} --out {O}",
    "reward-card": "reward-card {F} --table {G} --out {O}",
    "demo": None,
    "study": "study {F} --out {O}",
    "transfer": "transfer {F} --out {O}",
    "report": "report {F}",
    "sweep": "sweep {F} --out {O}",
    "agent train": "agent train --out {O} --reward learned --reward-run {F}",
    "gym expert": None,
    "gym experts": None,
    "gym collect": "gym collect MountainCar-v0 --expert {F} -n 5 --out {O}/x.parquet",
    "gym rl": "gym rl MountainCar-v0 --reward-run {F} --out {O}",
    "gym irl": "gym irl MountainCar-v0 --data {F} --out {O}",
    "gym reward-map": "gym reward-map MountainCar-v0 --runs {F} --out {O}/x.png",
    "gym study": None,
    "gym sweep": None,
    "leduc solve": None,  # reads nothing
    "leduc exploit": "leduc exploit {F}",
    "leduc agreement": "leduc agreement {F} {G}",
    "leduc synth": "leduc synth --expert {F} --out {O}/d.npz",
    "leduc study": "leduc study --out {O} --expert {F}",
}
REFUSED: dict[str, str | None] = {  # a setting or a file the library refuses: exit 1
    "version": None,
    "data list": None,
    "data fetch": "data fetch irc --url {E}",  # a folder: nothing to copy
    "data turn-table": None,  # no input; a corrupt cache file: tests/test_equity.py
    "ingest": "ingest {G} --out {O}/t.parquet",
    "synth": "synth --out {A}/x",  # an OSError: the path, and why
    "match": "match random nope --hands 10",
    "tournament": "tournament random nope --out {O} --hands 4 --seeds 0-1",
    "exploit": "exploit random --out {O} --hands 2 --epsilon 0.1",  # no epsilon to set
    "train": "train {G} --out {O}",
    "reward-card": "reward-card {E} --table {G} --out {O}",
    "demo": "demo --out {A}",
    "study": "study {G} --out {O}",
    "transfer": "transfer {E} --out {O}",
    "report": "report {R}",
    "sweep": "sweep {G} --out {O} --preset smoke",
    "agent train": "agent train --out {O} --opponent nope",
    "gym expert": "gym expert MountainCar-v0 --out {O} --hyper nope",
    "gym experts": None,  # reads only the shipped manifest
    "gym collect": "gym collect MountainCar-v0 --expert {E} -n 5 --out {O}/x.parquet",
    "gym rl": "gym rl MountainCar-v0 --reward-run {E} --out {O}",
    "gym irl": "gym irl MountainCar-v0 --data {G} --out {O}",
    "gym reward-map": "gym reward-map MountainCar-v0 --runs {E} --out {O}/x.png",
    "gym study": "gym study Nope-v0 --out {O}",
    "gym sweep": "gym sweep MountainCar-v0 --param bogus=1 --out {O}",
    "leduc solve": "leduc solve -n 1 --out {A}",  # a file, not a folder
    "leduc exploit": "leduc exploit {G}",
    "leduc agreement": "leduc agreement {R}/report.json {R}/report.json",
    "leduc synth": "leduc synth --expert {G} --out {O}/d.npz",  # not a strategy file
    "leduc study": "leduc study --out {O} --expert {G}",
}


@pytest.fixture
def places(tmp_path: Path) -> dict[str, str]:
    (tmp_path / "garbage.txt").write_text("not a table, not IRC data\n")
    (tmp_path / "empty").mkdir()
    (tmp_path / "afile").write_text("x")
    (tmp_path / "bad.toml").write_text("= not toml")
    (tmp_path / "out").mkdir()
    (tmp_path / "report").mkdir()
    (tmp_path / "report" / "report.json").write_text('{"truncated')
    names = {"F": "missing", "G": "garbage.txt", "E": "empty", "A": "afile", "O": "out"}
    return {
        **{key: str(tmp_path / name) for key, name in names.items()},
        "T": str(tmp_path / "bad.toml"),
        "R": str(tmp_path / "report"),
    }


def run(line: str, places: dict[str, str]) -> tuple[int, str]:
    """Exit code and the one error line of ``pokerirl LINE`` (a bug fails here)."""
    result = CliRunner().invoke(app, [word.format(**places) for word in line.split()])
    assert isinstance(result.exception, SystemExit), result.exception  # not a bug
    assert "Traceback" not in result.stderr + result.stdout
    errors = [text for text in result.stderr.splitlines() if not text.startswith("warning: ")]
    assert len(errors) == 1 and errors[0].startswith("error: "), result.stderr
    return result.exit_code, errors[0]


@pytest.fixture(autouse=True)
def no_debug(monkeypatch: pytest.MonkeyPatch) -> None:
    # --debug sets the variable in this process: monkeypatch puts it back after each test.
    monkeypatch.setenv(DEBUG_VARIABLE, "0")


def test_every_command_has_its_cases() -> None:
    assert len(COMMANDS) > 15 and "sweep" in COMMANDS
    for cases in (USAGE, MISSING, REFUSED):
        assert sorted(cases) == COMMANDS


@pytest.mark.parametrize("command", COMMANDS)
def test_a_usage_error_is_one_line_and_exit_2(command: str, places: dict[str, str]) -> None:
    code, _ = run(USAGE[command], places)
    assert code == 2


@pytest.mark.parametrize("command", [c for c in COMMANDS if MISSING[c] is not None])
def test_a_missing_input_is_one_line_naming_it_and_exit_1(
    command: str, places: dict[str, str]
) -> None:
    code, line = run(str(MISSING[command]), places)
    assert code == 1 and places["F"] in line


@pytest.mark.parametrize("command", [c for c in COMMANDS if REFUSED[c] is not None])
def test_a_refused_setting_or_file_is_one_line_and_exit_1(
    command: str, places: dict[str, str]
) -> None:
    code, _ = run(str(REFUSED[command]), places)
    assert code == 1


def _boom(*_: object, **__: object) -> None:
    raise KeyError("a bug")


def test_a_bug_keeps_its_traceback(monkeypatch: pytest.MonkeyPatch) -> None:
    # pokerirl match plays through the AIVAT module (raw and corrected results).
    monkeypatch.setattr("pokerirl.tournaments.aivat.play_corrected_match", _boom)
    result = CliRunner().invoke(app, ["match", "random", "call", "--hands", "10"])
    assert isinstance(result.exception, KeyError)  # not turned into SystemExit
    assert "error:" not in result.stderr
    # The script: Python prints the traceback.
    script = (
        "import sys, pokerirl.tournaments.aivat as aivat\n"
        "def boom(*a, **k):\n    raise KeyError('a bug')\n"
        "aivat.play_corrected_match = boom\n"
        "from pokerirl.cli import app\n"
        "sys.argv = ['pokerirl', 'match', 'random', 'call', '--hands', '10']\n"
        "app()\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT), DEBUG_VARIABLE: "0"}, timeout=300,
    )  # fmt: skip
    assert "Traceback" in done.stderr and "KeyError: 'a bug'" in done.stderr
    assert "error:" not in done.stderr


@pytest.mark.parametrize("how", ["--debug", DEBUG_VARIABLE])
def test_debug_prints_the_traceback_of_a_user_error(
    how: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    args = ["match", "random", "nope", "--hands", "10"]
    if how == "--debug":
        args.insert(0, "--debug")
    else:
        monkeypatch.setenv(DEBUG_VARIABLE, "1")
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1
    assert "Traceback" in result.stderr and "ConfigError: unknown agent 'nope'" in result.stderr
    assert result.stderr.splitlines()[-1].startswith("error: unknown agent 'nope'")


def _interrupt(*_: object, **__: object) -> None:
    raise KeyboardInterrupt


@pytest.mark.parametrize(
    ("line", "target", "says"),
    [
        (
            "match random call --hands 10",
            "pokerirl.tournaments.aivat.play_corrected_match",
            "error: interrupted",
        ),
        (
            "exploit random --hands 2 --out {O}",
            "pokerirl.tournaments.exploit.run_lbr",
            "error: interrupted: finished units are kept; rerun the same command to resume",
        ),
        (
            "tournament random call --hands 4 --seeds 0-1 --out {O}",
            "pokerirl.tournaments.run_tournament",
            "error: interrupted: finished units are kept; rerun the same command to resume",
        ),
    ],
)
def test_ctrl_c_is_one_line_and_exit_130(
    line: str, target: str, says: str, places: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(target, _interrupt)
    result = CliRunner().invoke(app, [word.format(**places) for word in line.split()])
    assert result.exit_code == 130 and result.stderr.splitlines() == [says]


def _terminate(*_: object, **__: object) -> None:
    os.kill(os.getpid(), signal.SIGTERM)  # a real SIGTERM, as SLURM or docker stop sends
    time.sleep(30)  # the handler interrupts this


@pytest.mark.parametrize(
    ("line", "target", "says"),
    [
        (
            "match random call --hands 10",
            "pokerirl.tournaments.aivat.play_corrected_match",
            "error: interrupted",
        ),
        (
            "tournament random call --hands 4 --seeds 0-1 --out {O}",
            "pokerirl.tournaments.run_tournament",
            "error: interrupted: finished units are kept; rerun the same command to resume",
        ),
    ],
)
def test_sigterm_is_ctrl_c_with_exit_143(
    line: str, target: str, says: str, places: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(target, _terminate)
    before = signal.getsignal(signal.SIGTERM)
    started = time.monotonic()
    result = CliRunner().invoke(app, [word.format(**places) for word in line.split()])
    assert result.exit_code == 143 and result.stderr.splitlines() == [says]
    assert time.monotonic() - started < 20  # stopped at once, not after the sleep
    assert signal.getsignal(signal.SIGTERM) == before  # the command put the handler back


def test_help_imports_no_heavy_module() -> None:
    script = (
        "import sys\n"
        "from pokerirl.cli import app\n"
        "sys.argv = ['pokerirl', '--help']\n"
        "try:\n    app()\nexcept SystemExit:\n    pass\n"
        "print(sorted(m for m in ('torch', 'gymnasium', 'pyarrow') if m in sys.modules))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=300,
    )  # fmt: skip
    assert "--debug" in done.stdout and done.stdout.splitlines()[-1] == "[]", done.stdout


@pytest.mark.parametrize(
    ("command", "shown"),
    [
        (["train"], ("--epochs", "50")),  # AIRLConfig.epochs
        (["transfer"], ("--eval-hands", "20000")),  # TransferConfig.eval_hands
        (["agent", "train"], ("--raise-counts", "decision")),  # TrainConfig.raise_counts
    ],
)
def test_help_shows_the_config_dataclass_default(
    command: list[str], shown: tuple[str, str]
) -> None:
    result = CliRunner().invoke(app, [*command, "--help"], env={"COLUMNS": "200"})
    option, default = shown
    text = " ".join(result.stdout.replace("│", " ").split())  # the help, unwrapped
    entry = text.split(f" {option} ", 1)[1].split(" --", 1)[0]  # up to the next option
    assert re.search(rf"\[default: {default}[];]", entry), entry  # [default: 50; x>=1]


# `gym irl --mode online` and poker's `train --mode online` (issue 43): a bad mode or an
# online-only option without it is a usage error; online sizes the library refuses are exit 1;
# a command that cannot learn online (the sweeps, leduc study) has no --mode and refuses it in
# one line; the studies take it (an online option offline, a bad mode: one usage line).
ONLINE_MODE: dict[str, tuple[str, int]] = {
    "bad mode": ("gym irl MountainCar-v0 --out {O} --mode nope", 2),
    "online option, offline mode": ("gym irl MountainCar-v0 --out {O} --rounds 3", 2),
    "steps not a multiple of envs": (
        "gym irl MountainCar-v0 --out {O} --mode online --generator-steps 3 --generator-envs 2",
        1,
    ),
    "poker train bad mode": ("train {G} --out {O} --mode nope", 2),
    "poker online option, offline mode": ("train {G} --out {O} --generator-steps 3", 2),
    "poker online, an offline option": ("train {G} --out {O} --mode online --em-rounds 1", 2),
    # The studies take --mode since (issue 43): an online option offline is refused instead.
    "poker study": ("study {G} --out {O} --rounds 3", 2),
    "gym study": ("gym study MountainCar-v0 --out {O} --generator-envs 2", 2),
    "poker study bad mode": ("study {G} --out {O} --mode nope", 2),
    "gym study bad mode": ("gym study MountainCar-v0 --out {O} --mode nope", 2),
    "poker study, an online option offline": ("study {G} --out {O} --generator-opponent call", 2),
    "poker study, an unknown generator opponent": (
        "study {G} --out {O} --mode online --generator-opponent nope", 2),
    "poker study, online on imputed folds": ("study {G} --out {O} --mode online --folds impute",
                                             2),
    "gym study, steps not a multiple of envs": (
        "gym study MountainCar-v0 --out {O} --mode online --generator-steps 3 "
        "--generator-envs 2", 1),
    "gym sweep cannot learn online": (
        "gym sweep MountainCar-v0 --param alpha=0 --out {O} --mode online", 2),
    "poker sweep cannot learn online": ("sweep {E} --out {O} --mode online", 2),
    "leduc study cannot learn online": ("leduc study --out {O} --mode online", 2),
    "leduc game, online": ("study --game leduc --out {O} --mode online", 2),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(ONLINE_MODE))
def test_online_mode_refusals_are_one_line(case: str, places: dict[str, str]) -> None:
    line, expected = ONLINE_MODE[case]
    code, error = run(line, places)
    assert code == expected and ("mode" in error or "envs" in error), error


# `study --game leduc` (issue 43): the Leduc study; each game's options refused with the other.
GAME: dict[str, tuple[str, int]] = {
    "bad game": ("study --game chess --out {O}", 2),
    "leduc, a hold'em source": ("study {G} --game leduc --out {O}", 2),
    "leduc, a hold'em option": ("study --game leduc --out {O} --runs 2", 2),
    "leduc, a hold'em preset": ("study --game leduc --out {O} --preset paper", 2),
    "leduc, a bad rule set": ("study --game leduc --out {O} --rules nope", 2),
    "hold'em, a Leduc option": ("study {G} --out {O} --rl tabular", 2),
    "hold'em without a source": ("study --out {O}", 2),
    "transfer on leduc": ("transfer {E} --out {O} --game leduc", 2),
}


@pytest.mark.parametrize("case", sorted(GAME))
def test_game_refusals_are_one_line(case: str, places: dict[str, str]) -> None:
    line, expected = GAME[case]
    code, error = run(line, places)
    assert code == expected and ("game" in error or "SOURCE" in error), error


# --game leduc on the main commands (issue 42): a hold'em option with it, --rules or a Leduc
# option without it, an agent of the other game: one line (exit 2 for the command line, 1 for
# an agent or a file), naming what is wrong.
LEDUC_GAME: dict[str, tuple[str, int, str]] = {
    "bad game": ("match random call --game chess", 2, "--game"),
    "match hold'em option": ("match random call --game leduc --hands 10", 2, "--hands"),
    "match rules on hold'em": ("match random call --rules openspiel", 2, "--rules"),
    "match hold'em bot": ("match tightbot call --game leduc", 1, "tightbot"),
    "match Leduc agent on hold'em": ("match cfr call --hands 10", 1, "cfr"),
    "match unknown Leduc agent": ("match nope call --game leduc", 1, "nope"),
    "match cfr iterations": ("match cfr:0 call --game leduc", 1, "cfr:0"),
    "exploit hold'em option": ("exploit random --game leduc --out {O}", 2, "--out"),
    "exploit exact on hold'em": ("exploit random --exact --out {O}", 2, "--exact"),
    "exploit pair on hold'em": ("exploit random --pair call --out {O}", 2, "--pair"),
    "exploit hold'em without out": ("exploit random", 2, "--out"),
    "tournament hold'em option": (
        "tournament random call --game leduc --out {O} --seeds 0-1",
        2,
        "--seeds",
    ),
    "tournament one agent": ("tournament random --game leduc --out {O}", 2, "two agents"),
    "tournament Leduc agent on hold'em": (
        "tournament cfr random --out {O} --hands 4 --seeds 0",
        1,
        "cfr",
    ),
    "synth reveal-all": ("synth --game leduc --out {O}/d.npz --reveal-all", 2, "--reveal-all"),
    "synth expert on hold'em": ("synth --out {O} --expert cfr", 2, "--expert"),
    "synth hold'em bot": ("synth --game leduc --out {O}/d.npz --expert loosebot", 1, "loosebot"),
    "agent train hold'em option": (
        "agent train --game leduc --out {O} --threads 2",
        2,
        "--threads",
    ),
    "agent train rl on hold'em": ("agent train --out {O} --rl tabular", 2, "--rl"),
    "agent train run alone": ("agent train --game leduc --out {O} --reward-run {E}", 2, "--reward"),
    "agent train not a run": (
        "agent train --game leduc --out {O} --reward learned --reward-run {E}",
        1,
        "empty",
    ),
    "train game of the data": ("train {G} --out {O} --game leduc", 1, "hold'em decision table"),
}


@pytest.mark.parametrize("case", sorted(LEDUC_GAME))
def test_leduc_game_refusals_are_one_line(case: str, places: dict[str, str]) -> None:
    line, expected, named = LEDUC_GAME[case]
    code, error = run(line, places)
    assert code == expected and named in error, error
