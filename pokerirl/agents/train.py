"""Train DQN agents into agent folders: evaluation, metrics, learning curve, many seeds.

:func:`train_agent` trains one agent (see :func:`pokerirl.agents.dqn.train_dqn`) and every
``eval_every`` hands plays its greedy policy against random and against the training opponent
(:func:`pokerirl.game.play_match`, duplicate, a fixed evaluation seed), appending a line to
``metrics.jsonl`` and redrawing ``learning_curve.png``. :func:`train_seeds` trains one agent
per seed into ``<out>/seed-<k>``, skipping seeds already finished.

>>> import tempfile
>>> out = Path(tempfile.mkdtemp()) / "dqn"
>>> config = TrainConfig(hands=512, seed=0, eval_every=512, eval_hands=200,
...                      dqn=DQNConfig(concurrent_hands=128))
>>> summary = train_agent(out, config)
>>> sorted(p.name for p in out.iterdir())
['config.json', 'learning_curve.png', 'metrics.jsonl', 'model.pt']
"""

from __future__ import annotations

import dataclasses
import json
import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from pokerirl import __version__
from pokerirl.agents.checkpoint import (
    CONFIG_FILE,
    CURVE_FILE,
    METRICS_FILE,
    files_fingerprint,
    is_finished,
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
from pokerirl.game import make_agent, play_match

REWARD_MODES = ("sparse", "learned")
REWARD_RUN_FILES = ("reward.pt", "config.json")  # what identifies a learned-reward run


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
) -> dict[str, Any]:
    """Train one agent into the folder ``out``; return the last evaluation's metrics line.

    In learned mode, ``reward_fn`` is f_θ; without it, f_θ is loaded from
    ``config.reward_run``. The checkpoint and ``config.json`` are written last, atomically.
    """
    out = Path(out)
    if config.reward == "sparse":
        reward_fn = None
    elif reward_fn is None:
        if config.reward_run is None:
            raise ValueError("--reward learned needs --reward-run RUN_DIR")
        reward_fn = load_reward_fn(config.reward_run)
    run_fingerprint = (
        reward_run_fingerprint(config.reward_run) if config.reward_run is not None else None
    )
    self_play = config.opponent == SELF_PLAY
    opponent = SELF_PLAY if self_play else resolve_agent(config.opponent)
    # The frozen self-play copy changes all the time: evaluate against random only then.
    opponents: dict[str, Any] = {"random": make_agent("random")}
    if not self_play and config.opponent != "random":
        opponents[config.opponent] = opponent

    out.mkdir(parents=True, exist_ok=True)
    (out / CONFIG_FILE).unlink(missing_ok=True)  # unfinished until the new one is written
    metrics_path = out / METRICS_FILE
    metrics_path.write_text("")  # a restarted run starts its metrics afresh
    metrics: list[dict[str, Any]] = []
    started = time.perf_counter()
    next_eval = min(config.eval_every, config.hands)

    def evaluate(hands_done: int, learner: DQNLearner) -> None:
        nonlocal next_eval
        if hands_done < next_eval:
            return
        next_eval = min((hands_done // config.eval_every + 1) * config.eval_every, config.hands)
        line = {
            "hands": hands_done,
            "transitions": learner.total_t,
            "updates": learner.train_t,
            "epsilon": epsilon_at(config.dqn, learner.total_t),
            "loss": None if np.isnan(learner.last_loss) else learner.last_loss,  # JSON has no NaN
            "seconds": round(time.perf_counter() - started, 3),
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
            "fingerprint": run_fingerprint,
            "payoff_weight": config.payoff_weight,
        },
        "opponent": {
            "spec": config.opponent,
            "fingerprint": "self" if self_play else agent_fingerprint(opponent),
        },
        "seed": config.seed,
        "hands": config.hands,
        "evaluation": {
            "every": config.eval_every,
            "hands": config.eval_hands,
            "seed": config.eval_seed,
        },
        "dqn": dataclasses.asdict(config.dqn),
        "final": metrics[-1],
    }
    save_agent(out, learner.q_net, record)
    return metrics[-1]


def _train_seed(out: str, config: TrainConfig) -> tuple[int, dict[str, Any]]:
    torch.set_num_threads(1)  # one process per core: no intra-op threads fighting
    return config.seed, train_agent(out, config)


def train_seeds(
    out: str | os.PathLike[str],
    config: TrainConfig,
    seeds: list[int],
    *,
    jobs: int = 1,
    progress: bool = False,
) -> dict[int, dict[str, Any] | None]:
    """Train one agent per seed into ``<out>/seed-<k>`` with up to ``jobs`` processes.

    Seeds whose folder is finished are skipped (their value is ``None``); the others map to
    their last evaluation. With one job, a progress bar per seed counts hands; with more, one
    bar counts seeds.
    """
    if jobs < 1:
        raise ValueError(f"jobs must be at least 1, got {jobs}")
    out = Path(out)
    todo = [s for s in seeds if not is_finished(out / f"seed-{s}")]
    results: dict[int, dict[str, Any] | None] = {s: None for s in seeds if s not in todo}
    # Fail on bad input before any process starts.
    if config.reward == "learned":
        if config.reward_run is None:
            raise ValueError("--reward learned needs --reward-run RUN_DIR")
        reward_run_fingerprint(config.reward_run)
    if config.opponent != SELF_PLAY:
        resolve_agent(config.opponent)
    if jobs == 1 or len(todo) <= 1:
        for seed in todo:
            seed_config = dataclasses.replace(config, seed=seed)
            results[seed] = train_agent(out / f"seed-{seed}", seed_config, progress=progress)
        return {s: results[s] for s in seeds}
    with (
        # spawn, not fork: a forked child can deadlock on the parent's torch thread pools.
        ProcessPoolExecutor(
            max_workers=min(jobs, len(todo)), mp_context=multiprocessing.get_context("spawn")
        ) as pool,
        tqdm(total=len(todo), unit="seed", disable=not progress) as bar,
    ):
        futures = [
            pool.submit(_train_seed, str(out / f"seed-{s}"), dataclasses.replace(config, seed=s))
            for s in todo
        ]
        for future in as_completed(futures):
            seed, summary = future.result()
            results[seed] = summary
            bar.update(1)
    return {s: results[s] for s in seeds}
