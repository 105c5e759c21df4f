"""PNG learning curves for training runs (matplotlib's Agg canvas, no global pyplot state)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from pokerirl.atomic import atomic_path
from pokerirl.figures import finish
from pokerirl.irl.metrics import Metric

ALIGNMENT_FIGURE = "alignment.png"
# file name -> (title, y label, the metrics drawn, each with its label)
CURVES: dict[str, tuple[str, str, tuple[Metric, ...]]] = {
    ALIGNMENT_FIGURE: (
        "Validation action alignment",
        "share of validation states",
        (Metric.VAL_ALIGNMENT, Metric.VAL_REWARD_ALIGNMENT),
    ),
    "losses.png": (
        "Training losses",
        "loss",
        (Metric.DISC_LOSS, Metric.POLICY_ADV_LOSS, Metric.POLICY_SUP_LOSS),
    ),
    "disc_accuracy.png": (
        "Discriminator accuracy",
        "accuracy (share of samples)",
        (Metric.DISC_ACC_EXPERT, Metric.DISC_ACC_POLICY),
    ),
}
BANDS_FILE = "alignment_bands.png"


def new_figure() -> tuple[Figure, Any]:
    """A 6x4 inch Agg figure and its axes, as every run-folder figure is drawn."""
    figure = Figure(figsize=(6, 4), dpi=100)
    FigureCanvasAgg(figure)
    return figure, figure.add_subplot()


def save_figure(
    figure: Figure, axes: Any, path: Path, title: str, ylabel: str, *, spread: str | None = None
) -> Path:
    """Title, labels (whole epochs on x), grid and legend (:func:`pokerirl.figures.finish`);
    written atomically to ``path``."""
    finish(axes, title=title, xlabel="epoch", ylabel=ylabel, spread=spread, integer_x=True)
    figure.tight_layout()
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format="png")
    return path


def _baseline_lines(axes: Any, baselines: Mapping[str, float]) -> None:
    for i, (name, value) in enumerate(sorted(baselines.items())):
        axes.axhline(value, linestyle="--", linewidth=1, color=f"C{i + 3}", label=name)


def plot_curves(
    metrics: Sequence[Mapping[str, Any]],
    out_dir: str | os.PathLike[str],
    *,
    baselines: Mapping[str, float] | None = None,
) -> list[Path]:
    """Write the curves in :data:`CURVES` that ``metrics`` has data for; the alignment plot
    draws ``baselines`` as horizontal lines. Returns the paths written."""
    out_dir = Path(out_dir)
    epochs = [m["epoch"] for m in metrics]
    written = []
    for name, (title, ylabel, series) in CURVES.items():
        present = [metric for metric in series if metrics and metric in metrics[0]]
        if not present:
            continue
        figure, axes = new_figure()
        for metric in present:
            values = [metric.of(m) for m in metrics]
            axes.plot(epochs, values, marker=".", label=metric.label)
        if name == ALIGNMENT_FIGURE and baselines:
            _baseline_lines(axes, baselines)
        written.append(save_figure(figure, axes, out_dir / name, title, ylabel))
    return written


def plot_bands(summary: Mapping[str, Any], out_dir: str | os.PathLike[str]) -> Path | None:
    """Mean ± std over runs of the alignment metrics, with the baselines' means as lines."""
    epochs = summary["epochs"]
    series = [m for m in CURVES[ALIGNMENT_FIGURE][2] if m in summary["metrics"]]
    if not series:
        return None
    figure, axes = new_figure()
    for i, metric in enumerate(series):
        curve = metric.of(summary["metrics"])
        mean, std = curve["mean"], curve["std"]
        axes.plot(epochs, mean, color=f"C{i}", label=metric.label)
        low = [m - s for m, s in zip(mean, std, strict=True)]
        high = [m + s for m, s in zip(mean, std, strict=True)]
        axes.fill_between(epochs, low, high, color=f"C{i}", alpha=0.25)
    _baseline_lines(axes, {k: v["mean"] for k, v in summary["baselines"].items()})
    spread = f"lines: mean over {summary['runs']} runs; bands: ± 1 std (sample) over runs"
    return save_figure(figure, axes, Path(out_dir) / BANDS_FILE, "Validation alignment",
                       "share of validation states", spread=spread)  # fmt: skip
