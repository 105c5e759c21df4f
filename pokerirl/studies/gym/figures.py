"""The gym study's figures: IRL-phase returns (Figure 1), validation alignment (Figure 2), RL-phase
returns (Figure 3), each a mean ± std band over runs, and the reward map (Figure 4)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pokerirl.figures import finish
from pokerirl.gym.presets import TASKS
from pokerirl.studies.common import band
from pokerirl.studies.gym.report import FIGURES
from pokerirl.studies.gym.results import Agreement, RewardMapSummary, TaskSummary

LABELS = {"airl": "AIRL", "hairl": "H-AIRL", "gail": "GAIL", "env": "env reward"}
COLORS = {"airl": "C0", "hairl": "C1", "env": "C2", "gail": "C3"}  # the same in every figure
MAP_GRID = 101  # cells per axis of the reward map


def draw_reward_map(root: Path, env: str, algos: Sequence[str]) -> RewardMapSummary | None:
    """Figure 4 for a task with a bounded 2-d observation and discrete actions (MountainCar):
    the action each algorithm's mean f prefers over the state lattice, beside the shipped
    expert's; returns the agreements (None for other tasks)."""
    from pokerirl.gym.reward_map import plot_reward_map, reward_map, task_space

    if env not in TASKS:  # its reference panel is the shipped expert's
        return None
    try:
        task_space(env)
    except ValueError:
        return None
    result = reward_map(env, [root / "irl" / algo for algo in algos], grid=MAP_GRID)
    path = root / FIGURES["reward_map"]
    path.parent.mkdir(parents=True, exist_ok=True)
    plot_reward_map(result, path)
    constant = result.constant_agreement
    assert constant is not None  # the shipped expert's panel is drawn
    panels = dict(zip(algos, result.panels, strict=True))
    return RewardMapSummary(
        grid=MAP_GRID,
        agreement={
            algo: Agreement(mean_f=panel.agreement, runs=list(panel.run_agreements))
            for algo, panel in panels.items()
        },
        constant_action=constant[0],
        constant_agreement=constant[1],
    )


def draw_figures(root: Path, summary: TaskSummary) -> None:
    """IRL-phase returns, alignment (discrete tasks) and RL-phase returns, mean ± std bands."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from pokerirl.atomic import atomic_path

    def figure() -> tuple[Figure, Any]:
        fig = Figure(figsize=(6.4, 4), dpi=100)
        FigureCanvasAgg(fig)
        return fig, fig.add_subplot()

    spread = f"lines: mean of {summary.runs} runs; bands: ± 1 std (sample) over runs"

    def save(fig: Figure, axes: Any, name: str, title: str, xlabel: str, ylabel: str) -> None:
        finish(axes, title=f"{summary.env}: {title}", xlabel=xlabel, ylabel=ylabel,
               spread=spread, integer_x=xlabel == "epoch")  # fmt: skip
        fig.tight_layout()
        path = root / FIGURES[name]
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as temporary:
            fig.savefig(temporary, format="png", metadata={"Software": None})

    def lines(axes: Any) -> None:
        for value, label, style in (
            (summary.expert_return, "expert's demonstrations", "--"),
            (summary.random_return, "random policy", ":"),
        ):
            if math.isfinite(value):
                axes.axhline(value, color="grey", linestyle=style, linewidth=1, label=label)

    episode = "return (sum of rewards per episode)"
    fig, axes = figure()
    for algo, found in summary.algos.items():
        band(axes, found.curves.irl_epochs, found.curves.irl_return.to_json(), LABELS[algo],
             color=COLORS[algo], alpha=0.2)  # fmt: skip
    lines(axes)
    save(fig, axes, "irl_returns", "IRL-phase return of the policy", "epoch", episode)

    if summary.discrete:
        fig, axes = figure()
        for algo, found in summary.algos.items():
            alignment = found.curves.alignment
            assert alignment is not None  # a discrete task's
            band(axes, found.curves.irl_epochs, alignment.to_json(), LABELS[algo],
                 color=COLORS[algo], alpha=0.2)  # fmt: skip
        baselines = summary.algos["hairl"].baselines
        for name, style in (("bc", "-."), ("majority", ":")):
            value = baselines[name].mean
            axes.axhline(
                value, color="grey", linestyle=style, linewidth=1, label=f"{name} {value:.3f}"
            )
        save(fig, axes, "alignment", "validation alignment", "epoch",
             "share of validation states (policy = expert)")

    fig, axes = figure()
    for reward in ("env", *summary.algos):
        source = summary.env_reward if reward == "env" else summary.algos[reward]
        curve = source.curves.rl
        assert curve.timesteps is not None  # an RL curve's
        band(axes, curve.timesteps, curve.to_json(), LABELS[reward], color=COLORS[reward],
             alpha=0.2)  # fmt: skip
    lines(axes)
    save(fig, axes, "rl_returns", "RL-phase true return", "timesteps",
         f"true {episode}")
