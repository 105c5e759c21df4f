"""map_units: the one way to run units, in unit order, on any backend (in this process for
one unit or one job, else ``local`` or ``ray``), with one progress bar over them."""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from pokerirl.execution.backend import Backend
from pokerirl.execution.local import _map_local
from pokerirl.execution.progress import _Bar, _ignore, _reporting
from pokerirl.execution.ray_connect import _ray_session
from pokerirl.execution.ray_tasks import _map_ray
from pokerirl.execution.threads import run_unit

R = TypeVar("R")


def map_units(
    fn: Callable[..., R],
    units: Sequence[tuple[Any, ...]],
    *,
    backend: Backend,
    progress: bool = False,
    desc: str = "units",
    reused: int = 0,
    on_result: Callable[[int, R], None] | None = None,
    labels: Sequence[str] | None = None,
) -> list[R]:
    """``[fn(*args) for args in units]``, run on ``backend``, in unit order.

    ``fn`` must be a module-level function and ``units`` picklable (except when everything
    runs in this process: one unit, or one local job). ``on_result(i, result)`` is called in
    this process as each unit finishes, in completion order: save results there to make the
    run resumable. ``reused``: units the caller already had, shown on the progress bar (one
    bar over units: done, reused, failed, ETA). ``labels`` name the units in messages.

    Raises:
        ExecutionError: a unit's worker died more than ``backend.retries`` times, or Ray
            cannot be used.
        Exception: the first exception a unit raised, as it was raised.
    """
    results: list[Any] = [None] * len(units)
    if not units:
        return results
    names = list(labels) if labels is not None else [f"unit {i}" for i in range(len(units))]
    with contextlib.ExitStack() as stack:
        ray = stack.enter_context(_ray_session(backend)) if backend.kind == "ray" else None
        bar = stack.enter_context(_Bar(len(units), reused=reused, desc=desc, enabled=progress))

        def finished(index: int, result: Any) -> None:
            results[index] = result
            if on_result is not None:
                on_result(index, result)
            bar.done(index)

        if ray is not None:
            _map_ray(ray, fn, units, backend, finished, bar, names)
        elif backend.jobs == 1 or len(units) == 1:
            for index, args in enumerate(units):
                with _reporting(functools.partial(bar.partial, index) if progress else _ignore):
                    result = run_unit(fn, args, backend.threads)
                finished(index, result)
        else:
            _map_local(fn, units, backend, finished, bar, names)
    return results
