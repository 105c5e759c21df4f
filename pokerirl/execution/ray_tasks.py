"""Units on Ray: one task per unit with one CPU (``_map_ray``), each running in a scratch
folder (:func:`run_unit_in_scratch`) and telling its progress to a small actor the driver
asks while it waits (``_ProgressSink``)."""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from pokerirl.execution.backend import Backend, ExecutionError, _first_line
from pokerirl.execution.progress import REPORT_EVERY, _Bar, _ignore, _reporting
from pokerirl.execution.scratch import _enter_scratch
from pokerirl.execution.threads import run_unit

R = TypeVar("R")


def _map_ray(
    ray: Any,
    fn: Callable[..., Any],
    units: Sequence[tuple[Any, ...]],
    backend: Backend,
    finished: Callable[[int, Any], None],
    bar: _Bar,
    names: list[str],
) -> None:
    from ray.exceptions import RayError, RayTaskError

    task = ray.remote(num_cpus=1, max_retries=backend.retries)(run_unit_in_scratch)
    # The units' progress: a small actor they tell, which the driver asks while it waits.
    sink = ray.remote(num_cpus=0)(_ProgressSink).remote() if bar.enabled else None
    pending = {
        task.remote(fn, args, backend.threads, sink, i): i for i, args in enumerate(units)
    }
    try:
        while pending:
            wait = REPORT_EVERY if sink is not None else None
            ready, _ = ray.wait(list(pending), num_returns=1, timeout=wait)
            if sink is not None:
                sink = _show_progress(ray, sink, set(pending.values()), bar)
            if not ready:
                continue
            index = pending.pop(ready[0])
            try:
                value = ray.get(ready[0])
            except RayTaskError as error:  # the unit raised: re-raise what it raised
                cause = error.cause if isinstance(error.cause, Exception) else None
                raise (cause or ExecutionError(_first_line(error))) from None
            except RayError as error:
                bar.fail(index)
                raise ExecutionError(
                    f"{names[index]}: failed on Ray after {backend.retries} retries "
                    f"({type(error).__name__}: {_first_line(error)})"
                ) from None
            finished(index, value)
    finally:
        for ref in pending:
            with contextlib.suppress(Exception):
                ray.cancel(ref, force=True)
        if sink is not None:
            with contextlib.suppress(Exception):
                ray.kill(sink)


def _show_progress(ray: Any, sink: Any, running: set[int], bar: _Bar) -> Any:
    """Move the bar by the running units' latest fractions from ``sink``; the sink, or None
    once it failed."""
    from ray.exceptions import RayError

    try:
        latest = ray.get(sink.take.remote())
    except RayError:  # progress is never worth a run: go on without it
        return None
    for unit, fraction in latest.items():
        if unit in running:
            bar.partial(unit, fraction)
    return sink


class _ProgressSink:
    """A Ray actor holding each running unit's latest fraction done until the driver asks."""

    def __init__(self) -> None:
        self.latest: dict[int, float] = {}

    def put(self, index: int, fraction: float) -> None:
        self.latest[index] = fraction

    def take(self) -> dict[int, float]:
        latest, self.latest = self.latest, {}
        return latest


def run_unit_in_scratch(
    fn: Callable[..., R], args: tuple[Any, ...], threads: int, sink: Any = None, index: int = 0
) -> R:
    """:func:`run_unit` in a Ray worker, with its temporary files in a scratch folder and its
    progress told to ``sink`` (a :class:`_ProgressSink`), if any."""
    _enter_scratch(tempfile.gettempdir())
    send = _ignore if sink is None else (lambda fraction: sink.put.remote(index, fraction))
    with _reporting(send):
        return run_unit(fn, args, threads)
