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

ALIGNMENT_FIGURE = "alignment.png"
# file name -> (title, y label, [(metric key, legend label)])
CURVES: dict[str, tuple[str, str, list[tuple[str, str]]]] = {
    ALIGNMENT_FIGURE: (
        "Validation action alignment",
        "share of validation states",
        [
            ("val_alignment", "policy argmax = expert"),
            ("val_reward_alignment", "reward argmax = expert"),
        ],
    ),
    "losses.png": (
        "Training losses",
        "loss",
        [
            ("disc_loss", "discriminator"),
            ("policy_adv_loss", "policy, adversarial"),
            ("policy_sup_loss", "policy, supervised"),
        ],
    ),
    "disc_accuracy.png": (
        "Discriminator accuracy",
        "accuracy (share of samples)",
        [("disc_acc_expert", "on expert samples"), ("disc_acc_policy", "on policy samples")],
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
        present = [(key, label) for key, label in series if metrics and key in metrics[0]]
        if not present:
            continue
        figure, axes = new_figure()
        for key, label in present:
            axes.plot(epochs, [m[key] for m in metrics], marker=".", label=label)
        if name == ALIGNMENT_FIGURE and baselines:
            _baseline_lines(axes, baselines)
        written.append(save_figure(figure, axes, out_dir / name, title, ylabel))
    return written


def plot_bands(summary: Mapping[str, Any], out_dir: str | os.PathLike[str]) -> Path | None:
    """Mean ± std over runs of the alignment metrics, with the baselines' means as lines."""
    epochs = summary["epochs"]
    series = [
        (key, label) for key, label in CURVES[ALIGNMENT_FIGURE][2] if key in summary["metrics"]
    ]
    if not series:
        return None
    figure, axes = new_figure()
    for i, (key, label) in enumerate(series):
        mean, std = summary["metrics"][key]["mean"], summary["metrics"][key]["std"]
        axes.plot(epochs, mean, color=f"C{i}", label=label)
        low = [m - s for m, s in zip(mean, std, strict=True)]
        high = [m + s for m, s in zip(mean, std, strict=True)]
        axes.fill_between(epochs, low, high, color=f"C{i}", alpha=0.25)
    _baseline_lines(axes, {k: v["mean"] for k, v in summary["baselines"].items()})
    spread = f"lines: mean over {summary['runs']} runs; bands: ± 1 std (sample) over runs"
    return save_figure(figure, axes, Path(out_dir) / BANDS_FILE, "Validation alignment",
                       "share of validation states", spread=spread)  # fmt: skip
