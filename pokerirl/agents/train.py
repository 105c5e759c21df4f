"""Train DQN agents into agent folders: evaluation, metrics, learning curve, many seeds.

:func:`train_agent` trains one agent (see :func:`pokerirl.agents.dqn.train_dqn`) and every
``eval_every`` hands plays its greedy policy against random and against the training opponent
(:func:`pokerirl.game.play_match`, duplicate, a fixed evaluation seed), appending a line to
``metrics.jsonl`` and redrawing ``learning_curve.png``. :func:`train_seeds` trains one agent
per seed into ``<out>/seed-<k>``.

Both run through :func:`pokerirl.execution.map_units`: each agent is a unit, trained with
torch on ``threads`` threads (one by default) in a private folder from its own seed, from the
bytes of its reward run and opponent; the driver writes the folder. So the weights do not
depend on the backend, the job count or the machine's cores. A folder is written beside its
target and swapped in at the end, with ``unit.json`` (the fingerprint of everything that
determines the agent, and the sha256 of each file) and ``timings.json`` (wall-clock figures,
kept out of ``config.json`` so that fingerprints never cover them). A rerun reuses an agent
whose fingerprint matches, retrains one whose files are corrupt, and refuses one trained
with other settings unless ``overwrite``.

>>> import tempfile
>>> out = Path(tempfile.mkdtemp()) / "dqn"
>>> config = TrainConfig(hands=512, seed=0, eval_every=512, eval_hands=200,
...                      dqn=DQNConfig(concurrent_hands=128))
>>> summary = train_agent(out, config)
>>> sorted(p.name for p in out.iterdir())
['config.json', 'learning_curve.png', 'metrics.jsonl', 'model.pt', 'timings.json', 'unit.json']
>>> train_agent(out, config) is None  # finished with these settings: reused
True
"""

from __future__ import annotations

import dataclasses
import json
import os
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pokerirl import __version__
from pokerirl.agents import ShippedAgent, land_agent, ship_agent
from pokerirl.agents.checkpoint import (
    CONFIG_FILE,
    CURVE_FILE,
    METRICS_FILE,
    MODEL_FILE,
    files_fingerprint,
    save_agent,
)
from pokerirl.agents.dqn import (
    SELF_PLAY,
    DQNConfig,
    DQNLearner,
    RewardFn,
    epsilon_at,
    train_dqn,
)
from pokerirl.agents.registry import agent_fingerprint, resolve_agent
from pokerirl.atomic import atomic_path
from pokerirl.execution import (
    Backend,
    load_unit_folder,
    map_units,
    read_files,
    save_unit_folder,
    write_files,
)
from pokerirl.game import make_agent, play_match
from pokerirl.game.agents import Agent

REWARD_MODES = ("sparse", "learned")
REWARD_RUN_FILES = ("reward.pt", "config.json")  # what identifies a learned-reward run
TIMINGS_FILE = "timings.json"
AGENT_OUTPUTS = (MODEL_FILE, CONFIG_FILE, METRICS_FILE, CURVE_FILE)


@dataclass(frozen=True, kw_only=True)
class TrainConfig:
    """One training run: what to learn from, against whom, for how long, how to evaluate.

    ``reward``: ``sparse`` (the payoff at the end of a hand) or ``learned`` (f_θ of
    ``reward_run``, mixed with the payoff by ``payoff_weight``). ``opponent``: an agent spec
    (:func:`pokerirl.agents.resolve_agent`) or ``self``. The evaluation plays ``eval_hands``
    duplicate hands of seed ``eval_seed`` every ``eval_every`` training hands and at the end.
    """

    hands: int
    seed: int
    reward: str = "sparse"
    reward_run: str | None = None
    payoff_weight: float = 0.0
    opponent: str = "random"
    eval_every: int = 10_000
    eval_hands: int = 20_000
    eval_seed: int = 1_000_003
    dqn: DQNConfig = field(default_factory=DQNConfig)

    def __post_init__(self) -> None:
        if self.reward not in REWARD_MODES:
            raise ValueError(f"unknown reward mode {self.reward!r} (sparse or learned)")
        if self.reward == "sparse" and self.reward_run is not None:
            raise ValueError("--reward-run needs --reward learned")
        if self.reward == "sparse" and self.payoff_weight != 0.0:
            raise ValueError("--payoff-weight needs --reward learned")
        if not 0.0 <= self.payoff_weight <= 1.0:
            raise ValueError(f"payoff weight must be in [0, 1], got {self.payoff_weight}")
        if self.hands < 1 or self.eval_every < 1:
            raise ValueError("hands and eval_every must be at least 1")
        if self.seed < 0 or self.eval_seed < 0:
            raise ValueError("seeds must be non-negative")
        if self.eval_hands < 2 or self.eval_hands % 2:
            raise ValueError(f"eval_hands must be even and at least 2, got {self.eval_hands}")


def reward_run_fingerprint(run_dir: str | os.PathLike[str]) -> str:
    """``sha256:<hex>`` over a reward run's ``reward.pt`` and ``config.json``."""
    for name in REWARD_RUN_FILES:
        if not (Path(run_dir) / name).is_file():
            raise ValueError(f"{run_dir}: not a reward run (no {name})")
    return files_fingerprint(run_dir, REWARD_RUN_FILES)


def load_reward_fn(run_dir: str | os.PathLike[str]) -> RewardFn:
    """f_θ of a learned-reward run, via ``pokerirl.irl.load_reward`` (imported here only)."""
    reward_run_fingerprint(run_dir)  # a clear error before the irl package is touched
    from pokerirl.irl import load_reward

    return load_reward(run_dir)


def _evaluate(
    learner: DQNLearner, opponents: dict[str, Any], config: TrainConfig
) -> dict[str, dict[str, float]]:
    greedy = learner.greedy_agent()
    results = {}
    for label, opponent in opponents.items():
        result = play_match(greedy, opponent, hands=config.eval_hands, seed=config.eval_seed)
        results[label] = {"mbb_per_hand": result.mbb_per_hand, "std_error": result.std_error}
    return results


def plot_learning_curve(metrics: list[dict[str, Any]], path: Path) -> None:
    """mbb/h (± one standard error) of every evaluation against training hands, as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(6, 4))
    for label in metrics[0]["eval"]:
        hands = [m["hands"] for m in metrics]
        mbb = np.array([m["eval"][label]["mbb_per_hand"] for m in metrics])
        error = np.array([m["eval"][label]["std_error"] for m in metrics])
        axes.plot(hands, mbb, marker="o", label=f"vs {label}")
        axes.fill_between(hands, mbb - error, mbb + error, alpha=0.25)
    axes.axhline(0.0, color="grey", linewidth=0.8)
    axes.set_xlabel("training hands")
    axes.set_ylabel("mbb/hand (greedy, duplicate)")
    axes.legend()
    figure.tight_layout()
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format="png", dpi=100)
    plt.close(figure)


def train_agent(
    out: str | os.PathLike[str],
    config: TrainConfig,
    *,
    reward_fn: RewardFn | None = None,
    progress: bool = False,
    overwrite: bool = False,
    backend: Backend | None = None,
) -> dict[str, Any] | None:
    """Train one agent into the folder ``out``; return its last evaluation's metrics line,
    or None when ``out`` already holds this agent (same fingerprint).

    In learned mode, ``reward_fn`` is f_θ (then the agent trains in this process); without
    it, f_θ is loaded from ``config.reward_run``. ``out`` is replaced only at the end, whole;
    a finished agent of other settings is refused unless ``overwrite``. ``backend``: where
    it trains and on how many torch threads (default: here, on one).
    """
    return _train_many(
        {config.seed: (Path(out), config)},
        backend=backend or Backend(),
        reward_fn=reward_fn,
        overwrite=overwrite,
        progress=progress,
    )[config.seed]


def train_seeds(
    out: str | os.PathLike[str],
    config: TrainConfig,
    seeds: list[int],
    *,
    jobs: int = 1,
    progress: bool = False,
    overwrite: bool = False,
    backend: Backend | None = None,
) -> dict[int, dict[str, Any] | None]:
    """Train one agent per seed into ``<out>/seed-<k>``, as units on ``backend`` (default:
    ``jobs`` local processes).

    Seeds already finished with the same settings are reused (their value is ``None``); the
    others map to their last evaluation. One progress bar counts seeds.
    """
    if jobs < 1:
        raise ValueError(f"jobs must be at least 1, got {jobs}")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out} exists and is not a folder")
    units = {s: (out / f"seed-{s}", dataclasses.replace(config, seed=s)) for s in seeds}
    return _train_many(
        units,
        backend=backend or Backend(jobs=jobs),
        reward_fn=None,
        overwrite=overwrite,
        progress=progress,
    )


@dataclass(frozen=True, kw_only=True)
class _TrainUnit:
    """What a worker needs to train one agent: settings and the bytes of its inputs."""

    config: TrainConfig
    reward_files: tuple[tuple[str, bytes], ...]
    reward_fingerprint: str | None
    opponent: ShippedAgent | None  # None: self-play
    threads: int
    progress: bool


@dataclass(frozen=True, kw_only=True)
class TrainedAgent:
    """A unit's output, returned to the driver: the folder's files, timings, last metrics."""

    files: dict[str, bytes]
    timings: dict[str, Any]
    summary: dict[str, Any]


def agent_unit_config(
    config: TrainConfig, *, reward_fingerprint: str | None, opponent: str, threads: int
) -> dict[str, Any]:
    """Everything that determines an agent's bytes, fingerprinted in its ``unit.json``.

    Inputs count by content (the reward run's and the opponent's fingerprints), not by path.
    """
    return {
        "kind": "pokerirl-dqn-agent",
        "seed": config.seed,
        "hands": config.hands,
        "reward": config.reward,
        "reward_run": reward_fingerprint,
        "payoff_weight": config.payoff_weight,
        "opponent": opponent,
        "evaluation": [config.eval_every, config.eval_hands, config.eval_seed],
        "dqn": dataclasses.asdict(config.dqn),
        "threads": threads,
    }


def _train_many(
    units: dict[int, tuple[Path, TrainConfig]],
    *,
    backend: Backend,
    reward_fn: RewardFn | None,
    overwrite: bool,
    progress: bool,
) -> dict[int, dict[str, Any] | None]:
    """Train the agents not already finished, each into its folder; reused ones map to None."""
    if not units:
        return {}
    first = next(iter(units.values()))[1]  # every unit shares these settings but the seed
    # Bad input fails here, in one line, before any worker starts.
    reward_files: dict[str, bytes] = {}
    reward_print = None
    if first.reward == "learned":
        if first.reward_run is None:
            raise ValueError("--reward learned needs --reward-run RUN_DIR")
        reward_print = reward_run_fingerprint(first.reward_run)
        if reward_fn is None:
            load_reward_fn(first.reward_run)  # errors name the user's files, not a worker's copy
            reward_files = read_files(first.reward_run, REWARD_RUN_FILES)
    if first.opponent == SELF_PLAY:
        opponent, opponent_print = None, SELF_PLAY
    else:
        opponent_print = agent_fingerprint(resolve_agent(first.opponent))
        opponent = ship_agent(first.opponent)
    if reward_fn is not None:
        backend = dataclasses.replace(backend, kind="local", address=None, jobs=1)

    results: dict[int, dict[str, Any] | None] = {}
    todo: list[tuple[int, Path, dict[str, Any], _TrainUnit]] = []
    for key, (folder, config) in units.items():
        unit_config = agent_unit_config(
            config, reward_fingerprint=reward_print, opponent=opponent_print,
            threads=backend.threads,
        )  # fmt: skip
        if load_unit_folder(folder, unit_config, overwrite=overwrite) is not None:
            results[key] = None
            continue
        unit = _TrainUnit(
            config=config,
            reward_files=tuple(reward_files.items()),
            reward_fingerprint=reward_print,
            opponent=opponent,
            threads=backend.threads,
            progress=progress and len(units) == 1 and backend.kind == "local",
        )
        todo.append((key, folder, unit_config, unit))

    def save(index: int, trained: TrainedAgent) -> None:
        key, folder, unit_config, _ = todo[index]
        timings = (json.dumps(trained.timings, indent=2) + "\n").encode()
        save_unit_folder(folder, trained.files, unit_config, unhashed={TIMINGS_FILE: timings})
        results[key] = trained.summary

    map_units(
        _train_unit,
        [(unit, reward_fn) for *_, unit in todo],
        backend=backend,
        progress=progress and len(units) > 1,
        desc="agents",
        reused=len(results),
        on_result=save,
        labels=[str(folder) for _, folder, _, _ in todo],
    )
    return {key: results[key] for key in units}


def _train_unit(unit: _TrainUnit, reward_fn: RewardFn | None = None) -> TrainedAgent:
    """Train one agent in a private folder and return its files (runs in a worker)."""
    config = unit.config
    with tempfile.TemporaryDirectory(prefix="pokerirl-agent-") as private:
        if config.reward == "learned" and reward_fn is None:
            reward_fn = load_reward_fn(
                write_files(Path(private, "reward-run"), dict(unit.reward_files))
            )
        opponent = (
            SELF_PLAY
            if unit.opponent is None
            else land_agent(unit.opponent, Path(private, "opponent"))
        )
        out = Path(private, "agent")
        summary, timings = _train_into(
            out,
            config,
            reward_fn=reward_fn if config.reward == "learned" else None,
            reward_fingerprint=unit.reward_fingerprint,
            opponent=opponent,
            threads=unit.threads,
            progress=unit.progress,
        )
        files = read_files(out, AGENT_OUTPUTS)
    return TrainedAgent(files=files, timings=timings, summary=summary)


def _train_into(
    out: Path,
    config: TrainConfig,
    *,
    reward_fn: RewardFn | None,
    reward_fingerprint: str | None,
    opponent: Agent | str,
    threads: int,
    progress: bool,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Train into the new folder ``out``; return the last metrics line and the timings."""
    self_play = opponent == SELF_PLAY
    # The frozen self-play copy changes all the time: evaluate against random only then.
    opponents: dict[str, Any] = {"random": make_agent("random")}
    if not self_play and config.opponent != "random":
        opponents[config.opponent] = opponent

    out.mkdir(parents=True)
    metrics_path = out / METRICS_FILE
    metrics_path.write_text("")
    metrics: list[dict[str, Any]] = []
    seconds: list[float] = []
    started = time.perf_counter()
    next_eval = min(config.eval_every, config.hands)

    def evaluate(hands_done: int, learner: DQNLearner) -> None:
        nonlocal next_eval
        if hands_done < next_eval:
            return
        next_eval = min((hands_done // config.eval_every + 1) * config.eval_every, config.hands)
        seconds.append(round(time.perf_counter() - started, 3))  # timings.json, not here
        line = {
            "hands": hands_done,
            "transitions": learner.total_t,
            "updates": learner.train_t,
            "epsilon": epsilon_at(config.dqn, learner.total_t),
            "loss": None if np.isnan(learner.last_loss) else learner.last_loss,  # JSON has no NaN
            "eval": _evaluate(learner, opponents, config),
        }
        metrics.append(line)
        with metrics_path.open("a") as stream:
            stream.write(json.dumps(line) + "\n")
        plot_learning_curve(metrics, out / CURVE_FILE)

    learner = train_dqn(
        config.dqn,
        hands=config.hands,
        seed=config.seed,
        opponent=opponent,
        reward_fn=reward_fn,
        payoff_weight=config.payoff_weight,
        progress=progress,
        on_hands=evaluate,
    )
    record = {
        "hidden": list(config.dqn.hidden),
        "source": {"kind": "pokerirl-dqn", "version": __version__, "torch": torch.__version__},
        "reward": {
            "mode": config.reward,
            "run": config.reward_run,
            "fingerprint": reward_fingerprint,
            "payoff_weight": config.payoff_weight,
        },
        "opponent": {
            "spec": config.opponent,
            "fingerprint": SELF_PLAY if self_play else agent_fingerprint(opponent),
        },
        "seed": config.seed,
        "hands": config.hands,
        "threads": threads,
        "evaluation": {
            "every": config.eval_every,
            "hands": config.eval_hands,
            "seed": config.eval_seed,
        },
        "dqn": dataclasses.asdict(config.dqn),
        "final": metrics[-1],
    }
    save_agent(out, learner.q_net, record)
    total = time.perf_counter() - started
    timings = {
        "seconds": round(total, 3),
        "hands_per_second": round(config.hands / total, 1) if total > 0 else None,
        "evaluations": [
            {"hands": m["hands"], "seconds": t} for m, t in zip(metrics, seconds, strict=True)
        ],
    }
    return metrics[-1], timings
