"""The study's figures, drawn with matplotlib's Agg backend and written atomically as PNG."""

from __future__ import annotations

import io
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pokerirl.atomic import write_bytes
from pokerirl.figures import finish
from pokerirl.holdem import ACTIONS
from pokerirl.irl.metrics import Metric
from pokerirl.meanstd import Curve
from pokerirl.studies.common import band
from pokerirl.studies.poker.config import ALGO_LABELS, KIND_LABELS, TABLE1_ORDER, matchup_label
from pokerirl.studies.poker.report_types import StudyReport
from pokerirl.studies.poker.results import (
    AgentsResult,
    IRLResult,
    IRLRuns,
    Panel,
)

if TYPE_CHECKING:
    from pokerirl.tournaments import AuthorsMatchup



def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(figure: Any, path: Path) -> None:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110, bbox_inches="tight", metadata={"Software": None})
    _pyplot().close(figure)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bytes(path, buffer.getvalue())


def _trained(irl: IRLResult) -> dict[str, tuple[str, IRLRuns]]:
    """The algorithms whose IRL runs the study trained (not replaced by a given reward)."""
    return {
        algo: (label, found)
        for algo, label in ALGO_LABELS.items()
        if isinstance(found := irl.get(algo), IRLRuns)
    }


def _band_figure(
    path: Path,
    bands: Iterable[tuple[Any, Curve, str]],
    lines: Iterable[tuple[float, str, str]] = (),
    *,
    title: str,
    xlabel: str,
    ylabel: str,
    spread: str,
    integer_x: bool = False,
    ylim: tuple[float, float] | None = None,
) -> None:
    """Mean ± std bands (x, curve, label) and grey reference lines (value, style, label),
    finished by :func:`pokerirl.figures.finish`."""
    plt = _pyplot()
    figure, axis = plt.subplots(figsize=(6.4, 4))
    for x, curve, label in bands:
        band(axis, x, curve.to_json(), label)
    for value, style, label in lines:
        axis.axhline(value, color="grey", linestyle=style, label=label)
    if ylim is not None:
        axis.set_ylim(*ylim)
    finish(axis, title=title, xlabel=xlabel, ylabel=ylabel, spread=spread, integer_x=integer_x)
    _save(figure, path)


def _over_runs(irl: IRLResult) -> str:
    runs = sorted({found.runs for _, found in _trained(irl).values()})
    return f"lines: mean over {'/'.join(map(str, runs))} runs; bands: ± 1 std (sample) over runs"


def _epochs(curve: Curve) -> np.ndarray:
    return np.arange(1, len(curve.mean) + 1)


def irl_alignment(irl: IRLResult, path: Path) -> None:
    """Validation alignment over epochs, mean ± std over runs, with the baselines as lines."""
    trained = _trained(irl)
    curves = {label: Metric.VAL_ALIGNMENT.of(runs.curves) for label, runs in trained.values()}
    bands = [(_epochs(curve), curve, label) for label, curve in curves.items()]
    lines = []
    styles = {"majority": ":", "legal_majority": "--", "bc": "-."}
    reported = next((trained[algo][1] for algo in TABLE1_ORDER if algo in trained), None)
    if reported is not None:
        for name, style in styles.items():
            value = reported.baselines[name].mean
            lines.append((value, style, f"{name} {value:.3f}"))
    _band_figure(path, bands, lines, xlabel="epoch",
                 ylabel="validation alignment (share of decisions)",
                 title="IRL: the policy's argmax against the expert's action",
                 spread=_over_runs(irl), integer_x=True)  # fmt: skip


def irl_discriminator(irl: IRLResult, path: Path) -> None:
    """Discriminator accuracy on expert and on policy actions over epochs, mean ± std."""
    bands = [
        (_epochs(metric.of(runs.curves)), metric.of(runs.curves), f"{label}, {side}")
        for label, runs in _trained(irl).values()
        for metric, side in ((Metric.DISC_ACC_EXPERT, "expert"), (Metric.DISC_ACC_POLICY, "policy"))
    ]
    _band_figure(path, bands, xlabel="epoch", ylabel="accuracy (share of samples)",
                 title="IRL: discriminator accuracy", spread=_over_runs(irl), integer_x=True,
                 ylim=(0, 1))  # fmt: skip


def irl_actions(irl: IRLResult, path: Path) -> None:
    """Validation action distributions (expert, AIRL, H-AIRL mean π) as grouped bars."""
    plt = _pyplot()
    trained = _trained(irl)
    groups: dict[str, Curve] = {}
    for label, runs in trained.values():
        groups["expert"] = Metric.VAL_EXPERT_DIST.of(runs.action_dist)
        groups[label] = Metric.VAL_POLICY_DIST.of(runs.action_dist)
    if not groups:
        figure, axis = plt.subplots(figsize=(6.4, 4))
        axis.set_title("no IRL runs: both rewards were given")
        _save(figure, path)
        return
    groups = {"expert": groups.pop("expert"), **groups}
    count = len(groups["expert"].mean)
    x = np.arange(count)
    width = 0.8 / len(groups)
    figure, axis = plt.subplots(figsize=(6.4, 4))
    for index, (label, dist) in enumerate(groups.items()):
        axis.bar(x + index * width, dist.mean, width, yerr=dist.std, label=label)
    names = ACTIONS if count == len(ACTIONS) else tuple(str(a) for a in range(count))
    axis.set_xticks(x + width * (len(groups) - 1) / 2, names)
    finish(axis, title="Action shares on the validation decisions", xlabel="action",
           ylabel="share of validation decisions", spread="bars: mean over runs; "
           "error bars: ± 1 std (sample) over runs", grid=False)  # fmt: skip
    _save(figure, path)


def rl_curves(agents: AgentsResult, path: Path) -> None:
    """Learning curves against random, mean ± std over seeds, with always-call and
    always-raise as reference lines (the paper's RL figure)."""
    bands = [(agents.curves[kind].timesteps, agents.curves[kind], label)
             for kind, label in KIND_LABELS.items() if kind in agents.curves]  # fmt: skip
    lines = []
    for name, style in (("call", ":"), ("raise", "--")):
        value = agents.references[name].mbb_per_hand
        lines.append((value, style, f"always-{name} {value:,.0f}"))
    over = f" over {len(agents.final_vs_random['dqn'])} seeds"
    _band_figure(path, bands, lines, xlabel="training hands",
                 ylabel="mbb/hand against random (duplicate deals)", title="RL against random",
                 spread=f"lines: mean{over}; bands: ± 1 std (sample){over}")  # fmt: skip


def panel_heatmap(panel: Panel, path: Path) -> None:
    """The panel's cross-table (row agent's mbb/h against the column agent) as a heat map."""
    plt = _pyplot()
    names = panel.agents
    matrix = np.array(
        [[np.nan if v is None else v for v in row] for row in panel.mbb_per_hand], dtype=float
    )
    limit = float(np.nanmax(np.abs(matrix))) if np.isfinite(matrix).any() else 1.0
    figure, axis = plt.subplots(figsize=(6.4, 5.4))
    image = axis.imshow(matrix, cmap="RdBu", vmin=-limit, vmax=limit or 1.0)
    axis.set_xticks(range(len(names)), names, rotation=45, ha="right")
    axis.set_yticks(range(len(names)), names)
    for i, row in enumerate(panel.mbb_per_hand):
        for j, value in enumerate(row):
            if value is not None:
                error = panel.std_error[i][j]
                axis.text(
                    j, i, f"{value:,.0f}\n±{error:,.0f}", ha="center", va="center", fontsize=7
                )
    figure.colorbar(image, label="mbb/hand (row vs column)")
    axis.set_title("Panel: row agent against column agent")
    _save(figure, path)


def authors_tournament(
    authors: Mapping[str, AuthorsMatchup], report: StudyReport, path: Path
) -> None:
    """Every pair's result under the authors' protocol: each repeat (dots), each experiment's
    mean, the overall mean with their ± and with the SE over experiments, our duplicate-deal
    figure on the same agents and the paper's."""
    plt = _pyplot()
    labels = {name: matchup_label(name) for name in report.table1_authors or {}}
    figure, axes = plt.subplots(1, len(labels), figsize=(5.5 * len(labels), 4.2), sharey=True,
                                squeeze=False)  # fmt: skip
    axes = axes[0]
    rng = np.random.default_rng(0)  # jitter only
    for axis, (name, label) in zip(axes, labels.items(), strict=True):
        row = (report.table1_authors or {})[name]
        repeats = [list(e.repeats_mbb) for e in authors[name].experiments]
        for k, values in enumerate(repeats):
            x = k + rng.uniform(-0.2, 0.2, len(values))
            axis.scatter(x, values, s=6, alpha=0.35, color="C0")
            axis.scatter([k], [np.mean(values)], marker="D", color="black", zorder=3)
        right = len(repeats) - 0.5
        mean = row.mean
        axis.axhline(mean, color="C1", label=f"mean {mean:+,.0f}")
        axis.axhspan(mean - row.paper_style_se, mean + row.paper_style_se, color="C1",
                     alpha=0.5, label=f"their ± {row.paper_style_se:,.0f}")  # fmt: skip
        se = row.se_over_experiments
        if se is not None:
            axis.axhspan(mean - se, mean + se, color="C1", alpha=0.15,
                         label=f"SE over experiments {se:,.0f}")  # fmt: skip
        duplicate = row.duplicate_mbb_per_hand
        if duplicate is not None:
            axis.axhline(duplicate, color="C2", linestyle="--",
                         label=f"ours, duplicate {duplicate:+,.0f}")  # fmt: skip
        theirs = row.paper
        if theirs is not None:
            paper_label = f"the paper {theirs.mbb_per_hand:+,} ± {theirs.std_error}"
            axis.axhline(theirs.mbb_per_hand, color="C3", linestyle=":", label=paper_label)
        axis.set_xlim(-0.5, right)
        axis.set_xticks(range(len(repeats)))
        finish(axis, title=label, xlabel="experiment (diamond: its mean)",
               ylabel=f"mbb/hand of one repeat ({row.games:,} games)" if axis is axes[0] else "",
               spread="dots: repeats; shaded: mean ± their SE, ± SE over experiments")  # fmt: skip
    figure.suptitle("The authors' tournament protocol: every repeat of every pair", fontsize=10)
    _save(figure, path)
