"""The map of the action a learned reward prefers over a 2-d state space (the paper's Figure 4).

For a task with a 2-d observation and discrete actions (MountainCar-v0: position, velocity;
push left, no push, push right), :func:`reward_map` evaluates the learned reward f(s, a) for
every action on a ``grid × grid`` lattice spanning the observation bounds, averages f over the
runs of each IRL folder (every ``run-<k>`` in it, or one run folder), and takes the argmax over
actions per cell. With an expert (by default the shipped one), it also draws the expert's
greedy action on the same lattice as a reference panel and measures, for each folder, the
share of cells where the preferred action equals the expert's.

f is the transferable reward g(s, a) of :func:`pokerirl.irl.load_reward` (all of f for the
paper's ``state_action`` family). Averaging f across runs, not voting, keeps one run's strong
preference from being outvoted by others' near-ties; per-run agreements give the spread.

:func:`plot_reward_map` writes the PNG atomically, with the same bytes for the same inputs
(matplotlib's Agg canvas, no timestamp or version in the metadata).
"""

from __future__ import annotations

import io
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pokerirl.atomic import write_bytes
from pokerirl.errors import ConfigError, InputError
from pokerirl.irl.config import Algo
from pokerirl.irl.run import CONFIG_FILE, RunError, load_reward, load_run_config

# Names of the actions and of the observation's two coordinates, where the task is known.
ACTION_NAMES: dict[str, tuple[str, ...]] = {
    "MountainCar-v0": ("push left", "no push", "push right"),
}
AXIS_NAMES: dict[str, tuple[str, str]] = {"MountainCar-v0": ("position", "velocity")}
ALGO_LABELS: dict[str, str] = {Algo.AIRL: "AIRL", Algo.HAIRL: "H-AIRL", Algo.GAIL: "GAIL"}
# One colour per action id (colour-blind safe: blue, grey, vermilion, then more).
COLOURS = ("#0072B2", "#BBBBBB", "#D55E00", "#009E73", "#CC79A7", "#F0E442")
RUN_FOLDER = re.compile(r"run-(\d+)")


@dataclass(frozen=True, kw_only=True)
class Panel:
    """One IRL folder's map: the action its runs' mean f prefers in each cell."""

    folder: Path
    label: str  # e.g. "H-AIRL: hairl (3 runs)"
    runs: tuple[Path, ...]
    preferred: np.ndarray  # (grid, grid) action ids, [velocity index, position index]
    agreement: float | None  # share of cells equal to the expert's action (None: no expert)
    run_agreements: tuple[float, ...]  # the same for each run's own f (empty: no expert)


@dataclass(frozen=True, kw_only=True)
class RewardMap:
    """The lattice, the expert's greedy actions on it, and one :class:`Panel` per folder.

    ``xs`` are the first observation coordinate's values (columns), ``ys`` the second's (rows).
    """

    env_id: str
    xs: np.ndarray  # (grid,)
    ys: np.ndarray  # (grid,)
    axis_names: tuple[str, str]
    action_names: tuple[str, ...]
    expert: np.ndarray | None  # (grid, grid) action ids, or None
    expert_label: str | None
    panels: tuple[Panel, ...]

    @property
    def constant_agreement(self) -> tuple[str, float] | None:
        """The baseline for agreement: the one action that matches the expert on the most
        cells, and that share (what a reward preferring it everywhere would score)."""
        if self.expert is None:
            return None
        shares = np.bincount(self.expert.ravel(), minlength=len(self.action_names))
        best = int(shares.argmax())
        return self.action_names[best], float(shares[best] / self.expert.size)


def task_space(env_id: str) -> tuple[np.ndarray, np.ndarray, int]:
    """(low, high, number of actions) of a task with a bounded 2-d observation and discrete
    actions; a one-line ``ValueError`` for any other task."""
    from pokerirl.gym.envs import make_env

    env = make_env(env_id)
    try:
        obs_space: Any = env.observation_space  # a Box here, checked below
        action_space = env.action_space
    finally:
        env.close()
    shape = getattr(obs_space, "shape", None)
    if shape != (2,) or not hasattr(action_space, "n"):
        raise ConfigError(
            f"{env_id}: the reward map needs a 2-d observation and discrete actions; "
            f"it has observations of shape {shape} and {type(action_space).__name__} actions"
        )
    low, high = obs_space.low.astype(np.float64), obs_space.high.astype(np.float64)
    if not (np.isfinite(low).all() and np.isfinite(high).all()):
        raise ConfigError(f"{env_id}: the observation space is unbounded; no lattice to draw")
    return low, high, int(action_space.n)


def run_folders(folder: str | os.PathLike[str]) -> tuple[Path, ...]:
    """The run folders in ``folder``: itself if it is one run, else its ``run-<k>`` in order
    of k. A one-line :class:`RunError` when there are none."""
    folder = Path(folder)
    if not folder.is_dir():
        raise RunError(f"{folder}: no such folder")
    if (folder / CONFIG_FILE).is_file():
        return (folder,)
    found = sorted(
        (int(m.group(1)), p)
        for p in folder.iterdir()
        if (m := RUN_FOLDER.fullmatch(p.name)) and p.is_dir()
    )
    if not found:
        raise RunError(f"{folder}: not an IRL run folder (no {CONFIG_FILE}, no run-<k> folders)")
    return tuple(p for _, p in found)


def lattice(low: np.ndarray, high: np.ndarray, grid: int) -> tuple[np.ndarray, np.ndarray]:
    """``grid`` evenly spaced values per coordinate, ends included.

    >>> xs, ys = lattice(np.array([0.0, -1.0]), np.array([1.0, 1.0]), 3)
    >>> xs.tolist(), ys.tolist()
    ([0.0, 0.5, 1.0], [-1.0, 0.0, 1.0])
    """
    if grid < 2:
        raise ConfigError(f"grid must be at least 2, got {grid}")
    return np.linspace(low[0], high[0], grid), np.linspace(low[1], high[1], grid)


def grid_states(xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """The lattice's states, row-major with rows along ``ys``: (len(ys) * len(xs), 2) float32.

    >>> grid_states(np.array([0.0, 1.0]), np.array([5.0, 6.0])).tolist()
    [[0.0, 5.0], [1.0, 5.0], [0.0, 6.0], [1.0, 6.0]]
    """
    x, y = np.meshgrid(xs, ys)  # (len(ys), len(xs)) each
    return np.stack((x.ravel(), y.ravel()), axis=1).astype(np.float32)


def reward_table(run: Path, states: np.ndarray, num_actions: int) -> np.ndarray:
    """f(s, a) of one run for every state and action: (n_states, num_actions), one call."""
    reward = load_reward(run)
    n = len(states)
    obs = np.tile(states, (num_actions, 1))  # action-major: rows k*n .. (k+1)*n - 1 take a = k
    actions = np.repeat(np.arange(num_actions), n)
    return np.asarray(reward(obs, actions), dtype=np.float64).reshape(num_actions, n).T


def check_run(run: Path, env_id: str, num_actions: int) -> str:
    """The run's algorithm; a one-line :class:`RunError` unless it is an IRL run on
    ``env_id`` with its 2-d observation and ``num_actions`` discrete actions."""
    record = load_run_config(run)
    trained_on = (record.get("data") or {}).get("env")
    if trained_on is None:
        raise RunError(f"{run}: not a Gymnasium IRL run (its {CONFIG_FILE} names no env)")
    if trained_on != env_id:
        raise RunError(f"{run}: a run on {trained_on}, not {env_id}")
    arch = record["architecture"]
    space = arch["action_space"]
    if arch["obs_dim"] != 2 or space.get("num_actions") != num_actions:
        raise RunError(
            f"{run}: its nets do not fit {env_id}'s 2-d states and {num_actions} actions"
        )
    return str(record.get("algo", "?"))


def expert_actions(expert: str | os.PathLike[str], env_id: str, states: np.ndarray) -> np.ndarray:
    """The expert's greedy actions on ``states`` (``shipped`` or an expert folder)."""
    from pokerirl.gym.expert_policies import load_expert, resolve_expert_dir

    loaded = load_expert(resolve_expert_dir(expert, env_id))
    if loaded.env_id != env_id:
        raise InputError(f"{expert}: an expert for {loaded.env_id}, not {env_id}")
    return np.asarray(loaded.act(states, deterministic=True), dtype=np.int64).reshape(-1)


def reward_map(
    env_id: str,
    folders: Sequence[str | os.PathLike[str]],
    *,
    grid: int = 101,
    expert: str | os.PathLike[str] | None = "shipped",
) -> RewardMap:
    """The preferred action of each folder's mean f over a ``grid × grid`` lattice of states.

    ``expert``: ``shipped`` (the package's expert for ``env_id``), an expert folder, or None
    (no reference panel, no agreement). Every bad input is a one-line ``ValueError`` (a
    missing folder, a run on another task, a task without 2-d states and discrete actions).
    """
    if not folders:
        raise ConfigError("give at least one IRL run folder")
    low, high, num_actions = task_space(env_id)
    xs, ys = lattice(low, high, grid)
    states = grid_states(xs, ys)
    shape = (len(ys), len(xs))
    checked = []
    for folder in folders:  # check every folder before the (slower) evaluation
        runs = run_folders(folder)
        algos = sorted({check_run(run, env_id, num_actions) for run in runs})
        checked.append((Path(folder), runs, algos))
    reference = None
    if expert is not None:
        reference = expert_actions(expert, env_id, states)
    panels = []
    for folder, runs, algos in checked:
        tables = np.stack([reward_table(run, states, num_actions) for run in runs])
        preferred = tables.mean(axis=0).argmax(axis=1)  # over actions, per state
        agreement: float | None = None
        per_run: tuple[float, ...] = ()
        if reference is not None:
            agreement = float((preferred == reference).mean())
            per_run = tuple(float((t.argmax(axis=1) == reference).mean()) for t in tables)
        name = "/".join(ALGO_LABELS.get(a, a) for a in algos)
        plural = "run" if len(runs) == 1 else "runs"
        panels.append(
            Panel(
                folder=folder,
                label=f"{name}: {folder.name or folder} ({len(runs)} {plural})",
                runs=runs,
                preferred=preferred.reshape(shape),
                agreement=agreement,
                run_agreements=per_run,
            )
        )
    default_names = tuple(f"action {k}" for k in range(num_actions))
    return RewardMap(
        env_id=env_id,
        xs=xs,
        ys=ys,
        axis_names=AXIS_NAMES.get(env_id, ("obs[0]", "obs[1]")),
        action_names=ACTION_NAMES.get(env_id, default_names),
        expert=None if reference is None else reference.reshape(shape),
        expert_label=None if expert is None else f"expert ({expert})",
        panels=tuple(panels),
    )


def plot_reward_map(result: RewardMap, path: str | os.PathLike[str]) -> Path:
    """Draw the expert's panel (if any) and one panel per folder side by side; write the PNG
    atomically, the same bytes for the same ``result``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    k = len(result.action_names)
    colours = [COLOURS[i % len(COLOURS)] for i in range(k)]
    cmap = ListedColormap(colours)
    maps: list[tuple[str, np.ndarray]] = []
    if result.expert is not None and result.constant_agreement is not None:
        action, share = result.constant_agreement
        title = f"{result.expert_label}: greedy action\na constant {action!r} matches "
        maps.append((title + f"{100 * share:.1f}% of cells", result.expert))
    for panel in result.panels:
        title = panel.label
        if panel.agreement is not None:
            title += f"\nagrees with the expert on {100 * panel.agreement:.1f}% of cells"
        maps.append((title, panel.preferred))

    figure = Figure(figsize=(4.2 * len(maps), 4.4), dpi=100)
    FigureCanvasAgg(figure)
    extent = (result.xs[0], result.xs[-1], result.ys[0], result.ys[-1])
    for i, (title, actions) in enumerate(maps):
        axes = figure.add_subplot(1, len(maps), i + 1)
        axes.imshow(
            actions,
            cmap=cmap,
            vmin=-0.5,
            vmax=k - 0.5,
            origin="lower",  # row 0 is the lowest value of the second coordinate
            extent=extent,
            aspect="auto",
            interpolation="nearest",
        )
        axes.set_title(title, fontsize=9)
        axes.set_xlabel(result.axis_names[0])
        if i == 0:
            axes.set_ylabel(result.axis_names[1])
    handles = [
        Patch(color=c, label=name) for c, name in zip(colours, result.action_names, strict=True)
    ]
    figure.legend(handles=handles, loc="lower center", ncol=k, frameon=False)
    first = "the expert's greedy action, then " if result.expert is not None else ""
    figure.suptitle(
        f"{result.env_id}: {first}the action each learned reward's f(s, a) prefers, on a "
        f"{len(result.xs)} × {len(result.ys)} grid of states (one panel per IRL folder: the argmax "
        "of f averaged over its runs)", fontsize=10
    )
    figure.tight_layout(rect=(0, 0.07, 1, 1))
    buffer = io.BytesIO()
    # No "Software" entry (matplotlib's version): same inputs, same bytes, across upgrades too.
    figure.savefig(buffer, format="png", metadata={"Software": None})
    path = Path(path)
    write_bytes(path, buffer.getvalue())
    return path
