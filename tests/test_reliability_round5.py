"""Reliability 5 (issue 46): hostile input of the four kinds the audit found, on each reader
and each public name. 1. sizes with no upper bound (the bounded JSON reader, bounds on every
width and count); 2. the public API checks its arguments at the door (and ``Transitions``
validates itself); 3. damaged archives are refused whole; 4. lines that blamed the wrong
thing. Each case is one line naming the option, file or argument (exit 2 usage, 1 bad file),
never a traceback, a silent success, or gigabytes of memory."""

from __future__ import annotations

import gzip
import io
import json
import math
import os
import shutil
import subprocess
import sys
import tarfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from test_reliability import MINIMAL, one_error_line, run_cli

import pokerirl
from pokerirl.agents.checkpoint import save_agent
from pokerirl.agents.config import DQNConfig
from pokerirl.agents.dqn import QNetwork
from pokerirl.errors import ConfigError, InputError
from pokerirl.irl.config import AIRLConfig
from pokerirl.irl.run import RunError, load_run_config, read_epochs, read_split
from pokerirl.jsonio import MAX_JSON_BYTES, check_format, read_json, read_json_lines
from pokerirl.settings import MAX_LBR_HANDS, MAX_WIDTH
from pokerirl.store import read_record

REPO = Path(__file__).resolve().parents[1]
HUGE = 2 << 30  # a 2 GiB sparse file: a reader that reads it whole takes 2 GB and more


# --------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def poker_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    import pyarrow.parquet as pq

    from pokerirl.datasets.toy import toy_expert_table
    from pokerirl.irl import load_config
    from pokerirl.poker import train_table

    root = tmp_path_factory.mktemp("round5")
    pq.write_table(toy_expert_table(num_hands=80, seed=1), root / "table.parquet")
    train_table(root / "table.parquet", root / "run", progress=False,
                config=load_config("hairl", overrides={"epochs": 1, "batch_size": 32}))  # fmt: skip
    return root / "run"


@pytest.fixture
def run_copy(poker_run: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(poker_run, tmp_path / "run"))


@pytest.fixture
def agent(tmp_path: Path) -> Path:
    folder = tmp_path / "agent"
    save_agent(folder, QNetwork(hidden=(8,)), {"hidden": [8]})
    return folder


def _edit_json(path: Path, **changes: Any) -> None:
    record = json.loads(path.read_text())
    record.update(changes)
    path.write_text(json.dumps(record))


def _sparse(path: Path, size: int = HUGE) -> Path:
    path.unlink(missing_ok=True)
    with path.open("wb") as handle:
        handle.truncate(size)  # no disk used: a hole
    return path


def _dev_zero(path: Path) -> Path:
    path.unlink(missing_ok=True)
    path.symlink_to("/dev/zero")
    return path


def _one_line(error: BaseException, *needles: str) -> str:
    text = str(error)
    assert "\n" not in text, text
    for needle in needles:
        assert needle in text, (needle, text)
    return text


# --------------------------------------------------------------------------- 1. sizes


HOSTILE_FILES: dict[str, Callable[[Path], Path]] = {
    "dev-zero": _dev_zero,
    "sparse-2GiB": _sparse,
    "5000-digits": lambda p: (p.write_text('{"hidden": [' + "9" * 5000 + "]}"), p)[1],
    "deep": lambda p: (p.write_text("[" * 100_000 + "]" * 100_000), p)[1],
    "folder": lambda p: (p.mkdir(), p)[1],
}
REASONS = {
    "dev-zero": "not a regular file",
    "sparse-2GiB": f"at most {MAX_JSON_BYTES} are read",
    "5000-digits": "an integer of 5000 digits",
    "deep": "not JSON",
    "folder": "not a regular file",
}


@pytest.mark.parametrize("kind", HOSTILE_FILES)
def test_the_bounded_reader_refuses_each_hostile_file_in_one_line(
    tmp_path: Path, kind: str
) -> None:
    path = HOSTILE_FILES[kind](tmp_path / "x.json")
    with pytest.raises(InputError) as error:
        read_json(path)
    _one_line(error.value, str(path), REASONS[kind])
    with pytest.raises(InputError) as error:
        read_json_lines(path)
    _one_line(error.value, str(path))


def test_a_fifo_is_refused_at_once_not_waited_on(tmp_path: Path) -> None:
    fifo = tmp_path / "config.json"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match="not a regular file"):
        read_json(fifo)


def test_a_2_gib_file_is_refused_within_a_small_memory_limit(tmp_path: Path) -> None:
    """In a child limited to 1.5 GB of address space: reading the file whole would die."""
    big = _sparse(tmp_path / "report.json")
    code = (
        "import resource, sys\n"
        "resource.setrlimit(resource.RLIMIT_AS, (1536 << 20, 1536 << 20))\n"
        "from pokerirl.jsonio import read_json\n"
        "from pokerirl.errors import InputError\n"
        "try:\n    read_json(sys.argv[1])\nexcept InputError as e:\n    print(e)\n"
    )
    environ = {**os.environ, "PYTHONPATH": str(REPO)}
    done = subprocess.run([sys.executable, "-c", code, str(big)], capture_output=True,
                          text=True, timeout=120, env=environ)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert f"{big}: {HUGE} bytes; at most" in done.stdout


def test_version_and_kind_are_checked() -> None:
    kind, version = ("format", "pokerirl-dqn"), ("version", (1,))
    check_format({"format": "pokerirl-dqn"}, where="c.json", kind=kind, version=version)
    for record, needle in [
        ({"format": "pokerirl-dqn", "version": 99}, "version is 99"),
        ({"format": "pokerirl-dqn", "version": True}, "version is True"),
        ({"format": "other", "version": 1}, "format is 'other'"),
    ]:
        with pytest.raises(InputError, match=needle):
            check_format(record, where="c.json", kind=kind, version=version)


AGENT_CASES: dict[str, tuple[Callable[[Path], Any], str]] = {
    "version 99": (lambda c: _edit_json(c, version=99), "version is 99"),
    "width 10^9": (lambda c: _edit_json(c, hidden=[10**9]), "hidden must be a list"),
    "5000 digits": (
        lambda c: c.write_text('{"format": "pokerirl-dqn", "hidden": [' + "9" * 5000 + "]}"),
        "an integer of 5000 digits",
    ),
    "2 GiB": (_sparse, "at most"),
    "dev-zero": (_dev_zero, "not an agent folder"),  # is_file() refuses it before any read
}


@pytest.mark.parametrize("case", AGENT_CASES)
def test_an_agent_config_json_is_read_bounded_and_versioned(agent: Path, case: str) -> None:
    damage, needle = AGENT_CASES[case]
    damage(agent / "config.json")
    with pytest.raises(InputError) as error:
        pokerirl.load_agent(agent)
    _one_line(error.value, str(agent), needle)
    code, lines = run_cli("match", str(agent), "random", "--hands", "10")
    assert code == 1 and needle in one_error_line(lines)


RUN_CASES: dict[str, tuple[Callable[[Path], Any], str]] = {
    "width 10^9": (
        lambda c: _edit_json(c, architecture={**json.loads(c.read_text())["architecture"],
                                              "reward_hidden": [10**9]}),
        "'reward_hidden' must be a list of 1 to 16 integers in 1..4096",
    ),
    "obs_dim 10^9": (
        lambda c: _edit_json(c, architecture={**json.loads(c.read_text())["architecture"],
                                              "obs_dim": 10**9}),
        "'obs_dim' must be an integer in 1..65536",
    ),
    "data a string": (lambda c: _edit_json(c, data="table.parquet"), "'data' must be a JSON"),
    "version 99": (lambda c: _edit_json(c, format_version=99), "unsupported format_version 99"),
    "5000 digits": (lambda c: c.write_text('{"format_version": ' + "9" * 5000 + "}"), "5000"),
    "2 GiB": (_sparse, "at most"),
}


@pytest.mark.parametrize("case", RUN_CASES)
def test_a_run_config_json_is_read_bounded_before_any_net_is_built(
    run_copy: Path, case: str
) -> None:
    damage, needle = RUN_CASES[case]
    damage(run_copy / "config.json")
    for reader in (load_run_config, pokerirl.load_reward, pokerirl.load_policy):
        with pytest.raises(RunError) as error:
            reader(run_copy)
        _one_line(error.value, str(run_copy / "config.json"), needle)


def test_report_unit_metrics_and_exploit_files_are_read_bounded(tmp_path: Path) -> None:
    from pokerirl.tournaments.exploit import ExploitError, load_lbr_report

    folder = tmp_path / "study"
    folder.mkdir()
    _dev_zero(folder / "report.json")
    code, lines = run_cli("report", str(folder))
    assert code == 1 and "report.json: corrupt: not a regular file" in one_error_line(lines)
    _sparse(folder / "report.json")
    code, lines = run_cli("report", str(folder))
    assert code == 1 and "at most" in one_error_line(lines)
    # a unit record that is /dev/zero is unreadable (recomputed), never read whole
    assert read_record(_dev_zero(tmp_path / "unit.json")) is None
    run = tmp_path / "run"
    run.mkdir()
    _sparse(run / "metrics.jsonl")
    with pytest.raises(InputError, match=r"metrics\.jsonl: .* at most"):
        read_epochs(run)
    _dev_zero(tmp_path / "report.json")
    with pytest.raises(ExploitError, match="not a regular file"):
        load_lbr_report(tmp_path)


def test_split_json_of_wrong_types_names_the_file_not_the_table(run_copy: Path) -> None:
    table = run_copy.parent / "table.parquet"
    bad = ('{"validation_groups": "abc"}', '{"validation_groups": [{"a": 1}]}',
           '{"validation_groups": []}', "[1, 2]", '{"validation_groups": [true]}')  # fmt: skip
    for content in bad:
        (run_copy / "split.json").write_text(content)
        with pytest.raises(RunError) as error:
            read_split(run_copy)
        _one_line(error.value, str(run_copy / "split.json"), "validation_groups")
    code, lines = run_cli("reward-card", str(run_copy), "--table", str(table),
                          "--out", str(run_copy / "card"), "--validation")  # fmt: skip
    assert code == 1 and "split.json: validation_groups must be" in one_error_line(lines)


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["train", "{table}", "--hidden", "1000000000"], "--hidden takes at most 16 widths"),
        (["agent", "train", "--hands", "10", "--hidden", "1000000000"], "--hidden takes"),
        (["agent", "train", "--hands", "10", "--replay-size", str(10**12)], "'--replay-size'"),
        (["agent", "train", "--hands", str(10**13)], "'--hands'"),
        (["study", "{root}", "--lbr-hands", str(10**15)], "'--lbr-hands'"),
        (["study", "{root}", "--hands", str(10**12)], "'--hands'"),
        (["gym", "study", "MountainCar-v0", "--epochs", str(10**12)], "'--epochs'"),
        (["gym", "study", "MountainCar-v0", "--timesteps", str(10**15)], "'--timesteps'"),
    ],
)
def test_sizes_beyond_their_bound_are_usage_errors_naming_the_option(
    poker_run: Path, tmp_path: Path, args: list[str], needle: str
) -> None:
    out = tmp_path / "out"
    root = poker_run.parent
    given = [a.format(table=root / "table.parquet", root=root) for a in args]
    code, lines = run_cli(*given, "--out", str(out))
    assert code == 2, lines
    assert needle in one_error_line(lines)
    assert not out.exists()


def test_configs_check_every_bound_before_anything_is_built() -> None:
    from pokerirl.studies.gym.config import study_preset as gym_preset
    from pokerirl.studies.poker import preset

    for make, needle in [
        (lambda: AIRLConfig(reward_hidden=(10**9,)), "reward_hidden must be at most 4096"),
        (lambda: AIRLConfig(policy_hidden=(64,) * 17), "at most 16 entries"),
        (lambda: AIRLConfig(reward_lr=math.inf), "reward_lr must be a finite number"),
        (lambda: AIRLConfig(seed=-1), "seed must be at least 0"),
        (lambda: AIRLConfig(epochs=10**12), "epochs must be at most"),
        (lambda: DQNConfig(replay_size=10**12), "replay_size must be at most"),
        (lambda: DQNConfig(hidden=(MAX_WIDTH + 1,)), "hidden must be at most"),
        (lambda: preset("quick", lbr_hands=10**15), f"lbr_hands <= {MAX_LBR_HANDS:,}"),
        (lambda: preset("quick", hands=10**12), "hands <= 100,000,000"),
        (lambda: preset("quick", agent_hands=10**13), "agent_hands <="),
        (lambda: gym_preset("quick", tasks=("MountainCar-v0",), epochs=10**12), "epochs <="),
    ]:
        with pytest.raises(ConfigError) as error:
            make()
        _one_line(error.value, needle)


# --------------------------------------------------------------------------- 2. the public API


def _data() -> pokerirl.Transitions:
    return pokerirl.Transitions.from_arrays(
        np.eye(4, 3), np.array([0, 1, 2, 0]), groups=np.array([0, 0, 1, 1])
    )


def _raise() -> Any:
    return pokerirl.resolve_agent("raise")


# Each public name with wrong arguments: (call, the error type, words of its one line).
PUBLIC_CASES: dict[str, list[tuple[Callable[[], Any], type[Exception], str]]] = {
    "Transitions": [
        (lambda: pokerirl.Transitions(obs=np.eye(4, 3), actions=torch.zeros(4, dtype=torch.long),
                                      groups=np.arange(4), num_actions=3),
         TypeError, "Transitions.obs must be a torch.Tensor"),
        (lambda: pokerirl.Transitions.from_arrays(np.eye(4, 3), np.array([0, 1, 5, 0]),
                                                  groups=np.arange(4), num_actions=3),
         InputError, "Transitions.actions must lie in 0..2"),
        (lambda: pokerirl.Transitions.from_arrays(np.eye(4, 3), np.zeros(4, int),
                                                  groups=np.arange(4), num_actions=0),
         InputError, "num_actions, an integer in 1.."),
        (lambda: pokerirl.Transitions.from_arrays(np.eye(4, 3), np.zeros(4, int),
                                                  groups=np.arange(4), num_actions=3,
                                                  legal_mask=np.ones((4, 2), bool)),
         InputError, "legal_mask is 2 wide, num_actions 3"),
        (lambda: pokerirl.Transitions.from_arrays(np.eye(4, 3), np.zeros(4, int),
                                                  groups=np.arange(4), next_obs=np.eye(4, 5),
                                                  dones=np.zeros(4, bool)),
         InputError, "next_obs is 5 wide, obs 3"),
        (lambda: pokerirl.Transitions.from_arrays(np.where(np.eye(4, 3), np.nan, 0),
                                                  np.zeros(4, int), groups=np.arange(4)),
         InputError, "Transitions.obs holds NaN or infinity"),
        (lambda: pokerirl.Transitions.from_arrays(np.eye(4, 3), np.zeros(4, int),
                                                  groups=np.arange(4),
                                                  rewards=[0, math.inf, 0, 0]),
         InputError, "Transitions.rewards holds NaN or infinity"),
    ],
    "AIRLConfig": [
        (lambda: AIRLConfig(reward_lr=math.inf), ConfigError, "reward_lr"),
        (lambda: AIRLConfig(seed=-1), ConfigError, "seed"),
        (lambda: AIRLConfig(batch_size="256"), ConfigError, "batch_size must be an integer"),
    ],
    "train": [
        (lambda: pokerirl.train(5, _data(), config=AIRLConfig()), TypeError, "train_data"),
        (lambda: pokerirl.train(_data(), _data(), config=None), TypeError, "config must be"),
    ],
    "train_into": [
        (lambda: pokerirl.train_into(_data(), Path("x"), algo="nope", config=AIRLConfig()),
         ConfigError, "algo must be one of airl, hairl, gail, got 'nope'"),
        (lambda: pokerirl.train_into(5, Path("x"), algo="airl", config=AIRLConfig()),
         TypeError, "data must be Transitions"),
    ],
    "load_reward": [(lambda: pokerirl.load_reward(5), TypeError, "run_dir")],
    "load_policy": [(lambda: pokerirl.load_policy(None), TypeError, "run_dir")],
    "from_imitation_transitions": [
        (lambda: pokerirl.from_imitation_transitions(5), InputError, "'obs'"),
    ],
    "to_imitation_transitions": [
        (lambda: pokerirl.to_imitation_transitions(5), TypeError, "transitions must be"),
    ],
    "from_imitation_trajectories": [
        (lambda: pokerirl.from_imitation_trajectories(5), TypeError, "trajectories must be"),
    ],
    "to_imitation_trajectories": [
        (lambda: pokerirl.to_imitation_trajectories("t"), TypeError, "transitions must be"),
    ],
    "play_match": [
        (lambda: pokerirl.play_match("raise", "random", hands=10, seed=0),
         TypeError, "agent_a must be an Agent"),
        (lambda: pokerirl.play_match(_raise(), _raise(), hands="10", seed=0),
         TypeError, "hands must be an integer, got str '10'"),
        (lambda: pokerirl.play_match(_raise(), _raise(), hands=10, seed=None),
         TypeError, "seed must be an integer"),
    ],
    "load_agent": [(lambda: pokerirl.load_agent(5), TypeError, "folder must be")],
    "resolve_agent": [
        (lambda: pokerirl.resolve_agent(5), TypeError, "spec must be"),
        (lambda: pokerirl.resolve_agent("no-such-agent"), ConfigError, "no-such-agent"),
    ],
    "RLCardAgent": [
        (lambda: pokerirl.RLCardAgent(agent="raise"), TypeError, "agent must be"),
        (lambda: pokerirl.RLCardAgent(agent=_raise(), seed=-1), ConfigError, "seed must be"),
    ],
    "learned_reward_env": [
        (lambda: pokerirl.learned_reward_env(5, lambda o, a: o), TypeError, "venv must be"),
    ],
    "load_expert": [(lambda: pokerirl.load_expert(5), TypeError, "folder must be")],
    "get_encoding": [(lambda: pokerirl.get_encoding("nope"), ConfigError, "unknown encoding")],
    # A protocol and a base class: nothing to call with wrong arguments; play_match and
    # get_encoding check what is given in their place (above).
    "Agent": [],
    "Encoding": [],
}


def test_every_public_name_has_its_hostile_cases() -> None:
    assert set(PUBLIC_CASES) == set(pokerirl.__all__)


@pytest.mark.parametrize(
    ("name", "index"),
    [(name, k) for name, cases in PUBLIC_CASES.items() for k in range(len(cases))],
)
def test_a_public_name_names_its_bad_argument(
    name: str, index: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    call, kind, needle = PUBLIC_CASES[name][index]
    monkeypatch.chdir(tmp_path)  # train_into's folder "x", if a check were missing
    with pytest.raises(kind) as error:
        call()
    _one_line(error.value, needle)
    assert not (tmp_path / "x").exists()


# --------------------------------------------------------------------------- 3. archives


def _month_archive(path: Path) -> Path:
    """The minimal month as a .tgz whose deflate blocks are stored (level 0): a flipped byte
    is then a changed hand, which only the gzip CRC catches."""
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w") as tar:
        for name, line in MINIMAL.items():
            data = line + b"\r\n"
            info = tarfile.TarInfo(f"holdem/199504/{name}")
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    path.write_bytes(gzip.compress(buffer.getvalue(), compresslevel=0, mtime=0))
    return path


def _flip(data: bytes, needle: bytes) -> bytes:
    at = data.index(needle) + 1  # inside a pdb line: a digit of its chips
    return data[:at] + bytes([data[at] ^ 0x01]) + data[at + 1 :]


@pytest.mark.parametrize("damage", ["flipped", "no trailer", "truncated member"])
def test_a_damaged_archive_is_one_line_and_nothing_is_written(tmp_path: Path, damage: str) -> None:
    (tmp_path / "good").mkdir()
    good = _month_archive(tmp_path / "good" / "holdem.199504.tgz")
    code, lines = run_cli("ingest", str(good), "--out", str(tmp_path / "ok.parquet"))
    assert code == 0, lines
    data = good.read_bytes()
    bad = {
        "flipped": _flip(data, b"1015 80"),
        "no trailer": data[:-8],
        "truncated member": data[: data.index(b"horseplay 797241924") + 10],
    }[damage]
    broken = tmp_path / "holdem.199504.tgz"
    broken.write_bytes(bad)
    for folds in ("drop", "impute"):
        out = tmp_path / folds / "t.parquet"
        out.parent.mkdir()
        code, lines = run_cli("ingest", str(broken), "--out", str(out), "--folds", folds)
        line = one_error_line(lines)
        assert code == 1, lines
        assert f"{broken}: not a readable tar archive" in line
        assert list(out.parent.iterdir()) == []


# --------------------------------------------------------------------------- 4. wrong blame


def test_a_run_whose_data_is_a_string_is_blamed_not_a_traceback(
    run_copy: Path, tmp_path: Path
) -> None:
    _edit_json(run_copy / "config.json", data="table.parquet")
    code, lines = run_cli("agent", "train", "--hands", "10", "--reward", "learned",
                          "--reward-run", str(run_copy), "--out", str(tmp_path / "a"))  # fmt: skip
    assert code == 1
    assert f"{run_copy / 'config.json'}: 'data' must be a JSON object" in one_error_line(lines)


def test_ingest_refuses_fitted_model_options_with_a_behaviour_run(
    poker_run: Path, tmp_path: Path
) -> None:
    month = _month_archive(tmp_path / "holdem.199504.tgz")
    for flag, value in (("--behaviour-rounds", "3"), ("--behaviour-encoding", "strength")):
        args = ["--folds", "impute", "--behaviour", str(poker_run), flag, value]
        code, lines = run_cli("ingest", str(month), "--out", str(tmp_path / "t.parquet"), *args)
        assert code == 2
        assert f"{flag} apply only without --behaviour" in one_error_line(lines)


gym = pytest.importorskip  # the gym cases need the [gym] extra


def test_gym_study_names_the_users_expert_folder_and_algos_are_usage_errors(
    agent: Path, tmp_path: Path
) -> None:
    gym("gymnasium")
    gym("stable_baselines3")
    code, lines = run_cli("gym", "study", "MountainCar-v0", "--out", str(tmp_path / "s"),
                          "--expert", str(agent))  # fmt: skip
    line = one_error_line(lines)
    assert code == 1
    assert f"{agent / 'config.json'}: not a gym expert's config" in line
    assert "pokerirl-collect" not in line
    for algos in ("airl,nope", "gail", ""):
        code, lines = run_cli("gym", "study", "MountainCar-v0", "--out", str(tmp_path / "s2"),
                              "--algos", algos)  # fmt: skip
        assert code == 2, (algos, lines)
        assert "algos" in one_error_line(lines)
    assert not (tmp_path / "s2").exists()


def test_shipping_an_agent_and_a_damaged_study_json_read_bounded(
    agent: Path, tmp_path: Path
) -> None:
    from pokerirl.agents import ship_agent
    from pokerirl.studies.common import claim_folder

    _sparse(agent / "config.json")
    with pytest.raises(InputError) as error:
        ship_agent(str(agent))  # a tournament ships its agents' bytes to the workers
    _one_line(error.value, str(agent / "config.json"), "at most")
    study = tmp_path / "study"
    study.mkdir()
    _dev_zero(study / "study.json")  # damage: the units' records still guard the outputs
    claim_folder(study, {"runs": 1}, overwrite=False)
    assert json.loads((study / "study.json").read_text())["settings"] == {"runs": 1}
