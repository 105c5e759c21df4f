"""PNG learning curves for a training run (matplotlib's Agg canvas, no global pyplot state)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from pokerirl.atomic import atomic_path

# file name -> (title, y label, [(metric key, legend label)])
CURVES: dict[str, tuple[str, str, list[tuple[str, str]]]] = {
    "alignment.png": (
        "Validation action alignment",
        "share of states",
        [("val_alignment", "policy argmax = expert"), ("majority_alignment", "majority action")],
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
        "accuracy",
        [("disc_acc_expert", "on expert samples"), ("disc_acc_policy", "on policy samples")],
    ),
}


def plot_curves(metrics: Sequence[dict[str, Any]], out_dir: str | os.PathLike[str]) -> list[Path]:
    """Write the curves in :data:`CURVES` that ``metrics`` has data for; return their paths."""
    out_dir = Path(out_dir)
    epochs = [m["epoch"] for m in metrics]
    written = []
    for name, (title, ylabel, series) in CURVES.items():
        present = [(key, label) for key, label in series if metrics and key in metrics[0]]
        if not present:
            continue
        figure = Figure(figsize=(6, 4), dpi=100)
        FigureCanvasAgg(figure)
        axes = figure.add_subplot()
        for key, label in present:
            axes.plot(epochs, [m[key] for m in metrics], marker=".", label=label)
        axes.set(title=title, xlabel="epoch", ylabel=ylabel)
        axes.grid(alpha=0.3)
        axes.legend()
        figure.tight_layout()
        path = out_dir / name
        with atomic_path(path) as temporary:
            figure.savefig(temporary, format="png")
        written.append(path)
    return written
