"""Thread pinning: torch's intra-op thread count, part of a unit's result, is set here and
nowhere else (:func:`pinned_threads` around a unit, :func:`pin_threads` for a command's own
work), and :func:`run_unit`, the call every backend makes."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

R = TypeVar("R")


@contextlib.contextmanager
def pinned_threads(threads: int) -> Iterator[None]:
    """torch on ``threads`` intra-op threads inside the block, if torch is loaded.

    Sums split over another number of threads round differently, which changes weights and
    near-tie argmaxes: the thread count is part of a unit's result.
    """
    torch = sys.modules.get("torch")
    if torch is None:
        yield
        return
    before = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        yield
    finally:
        torch.set_num_threads(before)


def pin_threads(threads: int) -> None:
    """torch on ``threads`` intra-op threads in this process from now on, loading torch: a
    command's own work (small nets train fastest on one; the count is part of the result,
    see :func:`pinned_threads`)."""
    import torch

    torch.set_num_threads(threads)


def run_unit(fn: Callable[..., R], args: tuple[Any, ...], threads: int = 1) -> R:
    """``fn(*args)`` with torch pinned to ``threads`` threads: what every backend calls."""
    with pinned_threads(threads):
        return fn(*args)
