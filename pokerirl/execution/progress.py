"""Progress: a running unit's reports (:func:`unit_progress`, :func:`progress_share`), how
they reach whoever shows them (``_reporting``, at most every :data:`REPORT_EVERY` seconds),
and the driver's bar over units (``_Bar``; :func:`watched` for work done in this process)."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator

from tqdm import tqdm

_report: Callable[[float], None] | None = None  # where the running unit's progress goes
REPORT_EVERY = 0.5  # seconds: a unit's progress reaches the driver at most this often


def unit_progress(done: float, total: float) -> None:
    """Say how far the running unit is: ``done`` of ``total`` (steps, epochs, hands). The
    driver's bar moves by the fraction, whether the unit runs in this process, in a local
    worker or on Ray; a no-op outside a unit (a library call, progress off)."""
    if _report is not None and total > 0:
        _report(min(max(done / total, 0.0), 1.0))


@contextlib.contextmanager
def progress_share(start: float, stop: float) -> Iterator[None]:
    """Inside the block, the running unit's reports cover ``start`` to ``stop`` of it: for a
    unit of phases (a baseline, then the training), so its bar never moves back."""
    global _report
    outer = _report
    if outer is None:
        yield
        return
    _report = lambda fraction: outer(start + (stop - start) * fraction)  # noqa: E731
    try:
        yield
    finally:
        _report = outer


@contextlib.contextmanager
def _reporting(send: Callable[[float], None]) -> Iterator[None]:
    """Inside the block, :func:`unit_progress` calls ``send`` with the unit's fraction done,
    at most every :data:`REPORT_EVERY` seconds (the last fraction is sent at the end)."""
    global _report
    last, pending = [0.0], [None]  # when we last sent; a fraction not sent yet

    def report(fraction: float) -> None:
        now = time.monotonic()
        if now - last[0] >= REPORT_EVERY:
            last[0], pending[0] = now, None
            send(fraction)
        else:
            pending[0] = fraction  # type: ignore[call-overload]

    previous, _report = _report, report
    try:
        yield
    finally:
        _report = previous
        if pending[0] is not None:
            send(pending[0])


@contextlib.contextmanager
def watched(desc: str, *, total: int = 1, enabled: bool = True) -> Iterator[Callable[[], None]]:
    """A bar over ``total`` pieces of work done in this process, not as units (a command's
    runs trained in turn, or together): :func:`unit_progress` inside moves it by the running
    piece's fraction; call the function it yields when a piece is done."""
    with _Bar(total, reused=0, desc=desc, enabled=enabled) as bar:
        running = [0]

        def piece_done() -> None:
            bar.done(running[0])
            running[0] += 1

        with _reporting(lambda fraction: bar.partial(running[0], fraction)):
            yield piece_done


def _ignore(fraction: float) -> None:
    """Progress nobody shows."""


class _Bar:
    """One tqdm bar over units with reused and failed counts in its postfix; a running unit
    counts by the fraction it reported (:func:`unit_progress`), so the bar and its ETA move
    inside long units."""

    def __init__(self, total: int, *, reused: int, desc: str, enabled: bool) -> None:
        self.enabled = enabled
        self.reused, self.failed, self.finished = reused, 0, reused
        self.running: dict[int, float] = {}  # unit index -> fraction done
        self.bar = tqdm(
            total=total + reused, initial=reused, unit="unit", desc=desc, disable=not enabled,
            bar_format="{l_bar}{bar}| {n:.2f}/{total} [{elapsed}<{remaining}{postfix}]",
        )  # fmt: skip
        self._postfix()

    def _postfix(self) -> None:
        self.bar.set_postfix_str(f"reused {self.reused}, failed {self.failed}", refresh=False)

    def _show(self) -> None:
        self.bar.update(self.finished + sum(self.running.values()) - self.bar.n)

    def partial(self, index: int, fraction: float) -> None:
        self.running[index] = fraction
        self._show()

    def done(self, index: int | None = None) -> None:
        self.running.pop(index, None)  # type: ignore[arg-type]
        self.finished += 1
        self._show()

    def fail(self, index: int | None = None) -> None:
        self.running.pop(index, None)  # type: ignore[arg-type]
        self.failed += 1
        self._postfix()
        self._show()
        self.bar.refresh()

    def __enter__(self) -> _Bar:
        return self

    def __exit__(self, *exc: object) -> None:
        self.bar.close()
