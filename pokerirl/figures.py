"""How every figure is finished, so that all of them read alike: a title that says what a band
or error bar is, axes labelled with their units, integer ticks where the axis counts (epochs,
seeds, experiments), and the legend beside the axes, never over the data.

Works on any matplotlib ``Axes``; it imports nothing of matplotlib itself but its tick locator.
"""

from __future__ import annotations

from typing import Any


def finish(
    axes: Any,
    *,
    title: str,
    xlabel: str,
    ylabel: str,
    spread: str | None = None,
    integer_x: bool = False,
    grid: bool = True,
) -> None:
    """Title (with ``spread``, what a band or bar is, on a second line), labels, integer x
    ticks when ``integer_x``, a light grid, and the legend outside the axes on the right."""
    axes.set(title=title if spread is None else f"{title}\n{spread}", xlabel=xlabel,
             ylabel=ylabel)  # fmt: skip
    axes.title.set_fontsize(10)
    if integer_x:
        from matplotlib.ticker import MaxNLocator

        axes.xaxis.set_major_locator(MaxNLocator(integer=True))
    if grid:
        axes.grid(alpha=0.3)
    if axes.get_legend_handles_labels()[0]:
        axes.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0),
                    borderaxespad=0.0)  # fmt: skip

