"""Issue 21, part B: the poker and study commands and the shared command line.

Bad option values are usage errors (exit 2) refused before any work; a study refuses what is
not IRC data as ingest does; a Gymnasium run is named as such where a poker reward is
expected; a corrupt report file is named; error lines show a path's undecodable bytes as
``\\xff``; and every command, given an unwritable ``--out`` or a path that is not UTF-8, says
so in one line naming the path and writes nothing elsewhere.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest
from test_reliability import one_error_line, run_cli
from test_reliability_io import _gym_run, read_only

from pokerirl.agents.checkpoint import save_agent
from pokerirl.agents.dqn import QNetwork
from pokerirl.cli.errors import display, display_error
from pokerirl.datasets.ingest import ingest_table
from pokerirl.game.synth import write_synthetic_month

REPO = Path(__file__).resolve().parents[1]
ODD = os.fsdecode(b"\xff")  # a name's byte that is not UTF-8, as Python holds it
BIG_SEED = str(2**32)


@dataclass(frozen=True)
class Inputs:
    """What the commands read: an IRC month, its table, a poker reward run, a gym IRL run,
    an agent folder."""

    month: Path
    table: Path
    run: Path
    gym_run: Path
    agent: Path


def _poker_run(folder: Path) -> Path:
    """An untrained poker reward run (72-d observations, 4 actions), as ``pokerirl train``
    saves one."""
    from pokerirl.irl.adversarial import TrainResult
    from pokerirl.irl.config import AIRLConfig
    from pokerirl.irl.nets import NetSpec, build_nets
    from pokerirl.irl.run import save_run

    config = AIRLConfig.for_algo("hairl", reward_hidden=(4,), policy_hidden=(4,))
    reward, policy = build_nets(NetSpec.of(config), obs_dim=72, action_dim=4, discrete=True)
    result = TrainResult(reward=reward, policy=policy, config=config, beta_used=0.0)
    save_run(result, folder, algo="hairl", data={"path": None})
    return folder


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> Inputs:
    root = tmp_path_factory.mktemp("inputs")
    month = write_synthetic_month(root / "irc", hands=200, seed=0)
    ingest_table([month], root / "table.parquet")
    agent = root / "agent"
    save_agent(agent, QNetwork(hidden=(8,)), {"hidden": [8]})
    return Inputs(
        month=month,
        table=root / "table.parquet",
        run=_poker_run(root / "run"),
        gym_run=_gym_run(root / "gym-run"),
        agent=agent,
    )


def _files(folder: Path) -> set[Path]:
    return {p for p in folder.rglob("*")}


# --- 1. a study on what is not IRC data --------------------------------------------------------


@pytest.mark.parametrize("kind", ["empty folder", "plain file"])
def test_study_on_what_is_not_irc_data_is_one_line_like_ingest(tmp_path: Path, kind: str) -> None:
    source = tmp_path / "notes"
    if kind == "empty folder":
        source.mkdir()
        (source / "readme.txt").write_text("hello")
        expected = f"error: {source}: no IRC data here (no hdb file and no .tgz archive)"
    else:
        source.write_text("hello")
        expected = (
            f"error: {source}: not IRC data (expected a month folder, a folder of months, "
            "or a .tgz archive)"
        )
    code, lines = run_cli("ingest", str(source), "--out", str(tmp_path / "t.parquet"), "-q")
    assert (code, one_error_line(lines)) == (1, expected)
    out = tmp_path / "study"
    code, lines = run_cli("study", str(source), "--out", str(out), "-q", "--jobs", "1")
    assert (code, one_error_line(lines)) == (1, expected)
    # No stage record is left to refuse the corrected command ("run with other settings").
    assert not (out / "stages" / "ingest.json").exists()
    if kind == "plain file":
        assert not out.exists()  # refused before anything is written


# --- 2. bad option values: exit 2, before any work ----------------------------------------------


def _bad_values(i: Inputs, out: Path) -> list[tuple[list[str], str]]:
    """Each command with a value it cannot run, and what its one line says."""
    month, table, run = str(i.month), str(i.table), str(i.run)
    agent = ["agent", "train", "--out", str(out), "-q", "--hands", "10"]
    tournament = ["tournament", "call", "raise", "--out", str(out), "-q", "--hands", "4"]
    study = ["study", month, "--out", str(out), "-q", "--jobs", "1"]
    transfer = ["transfer", run, "--out", str(out), "-q", "--jobs", "1"]
    return [
        (["train", table, "--out", str(out), "--runs", "0"], "'--runs'"),
        (["train", table, "--out", str(out), "--runs", "-1"], "'--runs'"),
        (["train", table, "--out", str(out), "--seed", BIG_SEED], "'--seed'"),
        (["train", table, "--out", str(out), "--epochs", "0"], "'--epochs'"),
        (["train", table, "--out", str(out), "--threads", "0"], "'--threads'"),
        (["train", table, "--out", str(out), "--jobs", "0"], "'--jobs'"),
        (["train", table, "--out", str(out), "--reward-lr", "-1"], "need learning rates > 0"),
        (["train", table, "--out", str(out), "--algo", "sqil"], "unknown algo 'sqil'"),
        (["train", table, "--out", str(out), "--hidden", "8,x"], "--hidden must be"),
        (["train", table, "--out", str(out), "--device", "tpu"], "device 'tpu'"),
        ([*agent, "--seed", BIG_SEED], "'--seed'"),
        ([*agent, "--eval-seed", "-1"], "'--eval-seed'"),
        ([*agent, "--seeds", f"0-{BIG_SEED}"], "seeds must be at most 4,294,967,295"),
        ([*agent, "--seeds", "0-99999"], "at most 10,000 seeds, got 100,000"),
        ([*agent, "--seeds", "5-3"], "empty seed range '5-3'"),
        ([*agent, "--jobs", "0"], "'--jobs'"),
        ([*agent, "--threads", "0"], "'--threads'"),
        ([*agent, "--epsilon-start", "2"], "epsilon_start and epsilon_end must lie in [0, 1]"),
        ([*agent, "--eval-hands", "3"], "eval_hands must be even"),
        ([*agent, "--train-every", "0"], "train_every must be at least 1"),
        ([*agent, "--payoff-weight", "0.5"], "payoff_weight needs reward 'learned'"),
        ([*agent, "--preset", "fast"], "unknown agent preset 'fast'"),
        ([*tournament, "--seeds", BIG_SEED], "seeds must be at most 4,294,967,295"),
        ([*tournament, "--seeds", "-1"], "bad seed range '-1'"),
        ([*tournament[:-1], "0"], "'--hands'"),
        ([*tournament[:-1], "2"], "at least 4 with duplicate deals"),
        ([*tournament, "--alpha", "1.5"], "--alpha must be between 0 and 1, got 1.5"),
        ([*tournament, "--batch-size", "3"], "even batch_size"),
        ([*tournament, "--jobs", "0"], "'--jobs'"),
        (["tournament", "call", "--out", str(out)], "give two agents"),
        (["match", "call", "raise", "--hands", "0"], "'--hands'"),
        (["match", "call", "raise", "--hands", "99999999999998"], "at most 100,000,000"),
        (["match", "call", "raise", "--seed", BIG_SEED], "'--seed'"),
        (["match", "call", "raise", "--format", "xml"], "unknown --format 'xml'"),
        ([*study, "--seeds", BIG_SEED], "seeds must be at most 4,294,967,295"),
        ([*study, "--seeds", "x"], "bad seed range 'x'"),
        ([*study, "--preset", "fast"], "unknown preset 'fast'"),
        ([*study, "--reward-transform", "x"], "reward transform in raw"),
        ([*study, "--runs", "0"], "'--runs'"),
        (["synth", "--out", str(out), "--seed", "-1"], "'--seed'"),
        (["synth", "--out", str(out), "--seed", BIG_SEED], "'--seed'"),
        (["synth", "--out", str(out), "--hands", "1000001"], "at most 1,000,000 (one month)"),
        (["reward-card", run, "--table", table, "--out", str(out), "--transform", "x"], "'x'"),
        ([*transfer, "--transforms", "x"], "transforms must be some of"),
        ([*transfer, "--payoff-weights", "x"], "'x': not a list of float values"),
        ([*transfer, "--payoff-weights", "2"], "payoff weights must lie in [0, 1]"),
        ([*transfer, "--preset", "fast"], "unknown agent preset 'fast'"),
        ([*transfer, "--hands", "0"], "'--hands'"),
        ([*transfer, "--seeds", "0-99999"], "at most 10,000 seeds"),
        (["demo", "--out", str(out), "--seed", BIG_SEED, "--no-gym"], "'--seed'"),
        (["report", str(out), "--format", "xml"], "unknown --format 'xml'"),
    ]


@pytest.mark.slow
def test_bad_option_values_are_usage_errors_before_any_work(inputs: Inputs, tmp_path: Path) -> None:
    out = tmp_path / "out"
    before = _files(inputs.month.parents[2])
    for args, needle in _bad_values(inputs, out):
        code, lines = run_cli(*args)
        assert code == 2, (args, lines)
        line = one_error_line(lines)
        assert needle in line, (args, line)
        assert not out.exists(), args  # refused before anything is written
    assert _files(inputs.month.parents[2]) == before


# --- 3. a Gymnasium run where a poker reward is expected ---------------------------------------


def test_a_gymnasium_run_is_named_where_a_poker_reward_is_expected(
    inputs: Inputs, tmp_path: Path
) -> None:
    gym, out = str(inputs.gym_run), tmp_path / "out"
    expected = (
        f"error: {gym}: a Gymnasium IRL run (reward of MountainCar-v0), not a poker reward; "
        "give a run of pokerirl train"
    )
    commands = [
        ["agent", "train", "--out", str(out), "--reward", "learned", "--reward-run", gym, "-q"],
        ["reward-card", gym, "--table", str(inputs.table), "--out", str(out)],
        ["transfer", gym, "--out", str(out), "-q", "--jobs", "1"],
        ["study", str(inputs.month), "--out", str(out), "--reward-run", gym, "-q", "--jobs", "1"],
    ]
    for command in commands:
        code, lines = run_cli(*command)
        assert (code, one_error_line(lines)) == (1, expected), command
        assert not out.exists(), command  # refused before any work


def test_a_reward_on_other_observations_is_named(inputs: Inputs, tmp_path: Path) -> None:
    run = tmp_path / "run"
    (run).mkdir()
    for name in ("reward.pt", "config.json"):
        (run / name).write_bytes((inputs.run / name).read_bytes())
    record = json.loads((run / "config.json").read_text())
    record["architecture"]["obs_dim"] = 8
    (run / "config.json").write_text(json.dumps(record))
    out = tmp_path / "card"
    code, lines = run_cli("reward-card", str(run), "--table", str(inputs.table), "--out", str(out))
    assert (code, one_error_line(lines)) == (
        1,
        f"error: {run}: a reward on 8-d observations and 4 actions, not the rlcard encoding's "
        "72-d states and 4 actions",
    )


# --- 4. report on a corrupt summary.json or report.json ---------------------------------------


@pytest.mark.parametrize(
    ("name", "content", "reason"),
    [
        ("summary.json", b'{"format": "pokerirl-gym-study/1", "tasks": {', "Expecting"),
        ("summary.json", b"", "Expecting value"),
        ("summary.json", b'{"format": "\xff"}', "not UTF-8 text"),
        ("report.json", b'{"format": "pokerirl-study-report/1", "tab', "Unterminated string"),
    ],
)
def test_report_names_a_corrupt_summary_or_report(
    tmp_path: Path, name: str, content: bytes, reason: str
) -> None:
    (tmp_path / "report.md").write_text("# an old report\n")
    (tmp_path / name).write_bytes(content)
    code, lines = run_cli("report", str(tmp_path))
    line = one_error_line(lines)
    assert code == 1
    assert line.startswith(f"error: {tmp_path / name}: corrupt: not JSON ({reason}"), line


# --- 5. error lines show a path's undecodable bytes as \xff ------------------------------------


def test_display_shows_undecodable_bytes_as_hex() -> None:
    assert display(f"runs/caf{ODD}: Permission denied") == "runs/caf\\xff: Permission denied"
    assert display("runs/café") == "runs/café"
    assert display("\ud800") == "\\ud800"  # a surrogate no file name holds
    assert display(json.dumps(f"caf{ODD}")) == '"caf\\udcff"'  # JSON stays JSON
    assert display_error(f"no such file: {f'caf{ODD}'!r}") == "no such file: 'caf\\xff'"


def test_a_real_process_prints_hex_not_surrogates(tmp_path: Path) -> None:
    # The real standard streams (CliRunner's are not the terminal's), as a user sees them.
    missing = tmp_path / f"nothing{ODD}"
    environment = {**os.environ, "PYTHONPATH": str(REPO), "PYTHONUTF8": "0", "LC_ALL": "C.UTF-8"}
    command = [sys.executable, "-m", "pokerirl", "report", os.fsencode(missing)]
    done = subprocess.run(command, env=environment, capture_output=True, timeout=120)
    assert done.returncode == 1 and done.stdout == b""
    assert (
        done.stderr
        == (
            f"error: {os.fsencode(tmp_path).decode()}/nothing\\xff: no report.json "
            "(run pokerirl tournament first)\n"
        ).encode()
    )


# --- 6. every command: an unwritable --out, a path that is not UTF-8 -----------------------------


@dataclass(frozen=True)
class Command:
    """A command as a row: ``argv(inputs, target)`` aims it at ``target``, the path its one
    line must name: its ``--out`` (``writes``: made unwritable) or, for a command without
    one, an input that does not exist."""

    name: str
    argv: Callable[[Inputs, Path], list[str]]
    writes: bool = True


AGENT_FAST = "-q --hands 8 --eval-every 8 --eval-hands 8 --hidden 4 --concurrent-hands 4"
GAMES_FAST = "-q --hands 4 --seeds 0 --jobs 1"
TRANSFER_FAST = "-q --jobs 1 --seeds 0 --hands 8 --eval-hands 8 --transforms raw"
GYM_EXPERT_FAST = "--timesteps 50 --eval-episodes 1 --final-episodes 1".split()
GYM_RL_FAST = "--runs 1 --timesteps 50 --evaluations 1 --eval-episodes 1".split()
GYM_IRL_FAST = "--preset quick --runs 1 --epochs 1".split()
GYM_STUDY_FAST = (
    "-q --jobs 1 --runs 1 --transitions 200 --epochs 1 --eval-episodes 1 --timesteps 50".split()
)
COMMANDS = [
    Command("ingest", lambda i, t: ["ingest", str(i.month), "--out", str(t), "-q"]),
    Command("synth", lambda i, t: ["synth", "--out", str(t), *"--hands 10".split()]),
    Command(
        "train",
        lambda i, t: ["train", str(i.table), "--out", str(t), *"--quiet --epochs 1".split()],
    ),
    Command(
        "agent train",
        lambda i, t: ["agent", "train", "--out", str(t), *AGENT_FAST.split()],
    ),
    Command(
        "tournament",
        lambda i, t: ["tournament", "call", "raise", "--out", str(t), *GAMES_FAST.split()],
    ),
    Command("study", lambda i, t: ["study", str(i.month), "--out", str(t), *"-q --jobs 1".split()]),
    Command(
        "reward-card",
        lambda i, t: ["reward-card", str(i.run), "--table", str(i.table), "--out", str(t)],
    ),
    Command(
        "transfer",
        lambda i, t: ["transfer", str(i.run), "--out", str(t), *TRANSFER_FAST.split()],
    ),
    Command("demo", lambda i, t: ["demo", "--out", str(t), *"-q --no-gym --jobs 1".split()]),
    Command("report", lambda i, t: ["report", str(t)], writes=False),
    Command("match", lambda i, t: ["match", str(t), "raise", "--hands", "8"], writes=False),
    Command(
        "gym expert",
        lambda i, t: ["gym", "expert", "MountainCar-v0", "--out", str(t), *GYM_EXPERT_FAST],
    ),
    Command(
        "gym collect",
        lambda i, t: ["gym", "collect", "MountainCar-v0", "-n", "20", "--out", str(t)],
    ),
    Command(
        "gym rl",
        lambda i, t: ["gym", "rl", "MountainCar-v0", "--env-reward", "--out", str(t), *GYM_RL_FAST],
    ),
    Command(
        "gym irl", lambda i, t: ["gym", "irl", "MountainCar-v0", "--out", str(t), *GYM_IRL_FAST]
    ),
    Command(
        "gym reward-map",
        lambda i, t: [
            "gym",
            "reward-map",
            "MountainCar-v0",
            "--runs",
            str(i.gym_run),
            "--grid",
            "3",
            "--expert",
            "none",
            "--out",
            str(t),
        ],
    ),
    Command(
        "gym study",
        lambda i, t: ["gym", "study", "MountainCar-v0", "--out", str(t), *GYM_STUDY_FAST],
    ),
    Command(
        "gym sweep",
        lambda i, t: [
            "gym",
            "sweep",
            "MountainCar-v0",
            "--param",
            "alpha=0.5",
            "--out",
            str(t),
            *GYM_STUDY_FAST,
        ],
    ),
]


@pytest.mark.parametrize("name", ["out", f"out{ODD}"], ids=["plain", "not-utf8"])
@pytest.mark.parametrize("command", COMMANDS, ids=[c.name for c in COMMANDS])
def test_every_command_names_an_unwritable_or_odd_path_in_one_line(
    inputs: Inputs, tmp_path: Path, command: Command, name: str
) -> None:
    locked = tmp_path / name
    locked.mkdir()
    target = locked / "target" if command.writes else tmp_path / f"missing-{name}"
    before = _files(tmp_path), _files(inputs.month.parents[2])
    with read_only(locked):
        code, lines = run_cli(*command.argv(inputs, target))
    line = one_error_line(lines)
    assert code == 1, lines
    assert line.startswith(f"error: {display(str(target))}"), line
    assert "\\udc" not in line and ".tmp" not in line
    assert (_files(tmp_path), _files(inputs.month.parents[2])) == before  # nothing written
