"""Every figure is finished alike (pokerirl.figures.finish): the legend beside the axes, never
over the data; whole numbers on a counting axis; the title says what a band is; and a run
without a legal mask draws no legal_majority line."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from pokerirl.figures import finish


def _axes() -> tuple[Figure, Any]:
    figure = Figure(figsize=(6, 4))
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    axes.plot([1, 2, 3], [0.2, 0.8, 0.5], label="H-AIRL")
    axes.fill_between([1, 2, 3], [0.1, 0.7, 0.4], [0.3, 0.9, 0.6])
    return figure, axes


def test_the_legend_sits_beside_the_data_and_epochs_are_whole() -> None:
    figure, axes = _axes()
    finish(axes, title="IRL", xlabel="epoch", ylabel="share of states",
           spread="bands: ± 1 std over 3 runs", integer_x=True)  # fmt: skip
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    legend = axes.get_legend().get_window_extent(renderer)
    assert legend.x0 >= axes.get_window_extent(renderer).x1  # right of the plotting area
    ticks = [t for t in axes.get_xticks() if axes.get_xlim()[0] <= t <= axes.get_xlim()[1]]
    assert ticks and all(float(t).is_integer() for t in ticks)
    assert axes.get_title() == "IRL\nbands: ± 1 std over 3 runs"
    assert (axes.get_xlabel(), axes.get_ylabel()) == ("epoch", "share of states")


def test_no_legend_without_labels() -> None:
    figure = Figure()
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    axes.plot([0, 1], [0, 1])
    finish(axes, title="t", xlabel="x", ylabel="y")
    assert axes.get_legend() is None


@pytest.mark.parametrize("masked", [True, False])
def test_legal_majority_is_drawn_only_with_a_legal_mask(
    masked: bool, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from pokerirl.irl import Transitions, load_config
    from pokerirl.irl import run as irl_run

    drawn: list[set[str]] = []
    real = irl_run.plot_curves

    def spy(metrics: Any, folder: Path, *, baselines: dict[str, float]) -> list[Path]:
        drawn.append(set(baselines))
        return real(metrics, folder, baselines=baselines)

    monkeypatch.setattr(irl_run, "plot_curves", spy)
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(60, 4)).astype(np.float32)
    mask = np.ones((60, 3), dtype=bool) if masked else None
    data = Transitions.from_arrays(obs, rng.integers(0, 3, 60), groups=np.arange(60) // 3,
                                   legal_mask=mask)  # fmt: skip
    config = load_config("airl", overrides={"epochs": 1, "batch_size": 16})
    irl_run.train_into(data, tmp_path / "run", algo="airl", config=config)
    assert ("legal_majority" in drawn[0]) is masked and "majority" in drawn[0]
    assert (tmp_path / "run" / "alignment.png").is_file()
