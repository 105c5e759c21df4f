"""The local backend: workers forked from a ``multiprocessing`` fork server, each dying with
the driver (``_die_with``: ``PR_SET_PDEATHSIG`` and a watchdog), ignoring Ctrl-C and SIGTERM,
working in a scratch folder of its own (``_worker``); the driver's loop that hands them units,
runs a unit again when its worker dies, and stops them all (``_map_local``, ``_stop``)."""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import sys
import tempfile
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from tqdm import tqdm

from pokerirl.execution.backend import Backend, ExecutionError, _first_line
from pokerirl.execution.progress import _Bar, _reporting
from pokerirl.execution.scratch import _enter_scratch, _leave_scratch, sweep_leftovers
from pokerirl.execution.threads import run_unit


def _die_with(driver: int) -> None:
    """End this process when the driver dies, even while a unit is computing.

    The immediate parent is the driver (spawn) or its fork server, which exits with it.
    """
    parent = os.getppid()
    if sys.platform.startswith("linux"):
        import ctypes

        PR_SET_PDEATHSIG = 1
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)

    def driver_alive() -> bool:
        try:
            os.kill(driver, 0)
        except ProcessLookupError:
            return False
        except PermissionError:
            pass
        return True

    def watch() -> None:  # elsewhere, and for a parent that died before prctl
        while os.getppid() == parent and driver_alive():
            time.sleep(0.5)
        os._exit(1)

    if not driver_alive():
        os._exit(1)
    threading.Thread(target=watch, daemon=True).start()


def _worker(connection: Any, parent: int, threads: int, temp: str) -> None:
    """A local worker: run the units the driver sends until it sends None or goes away.

    ``temp``: the driver's temporary folder, where this worker's scratch folder goes.
    """
    _die_with(parent)
    # Ctrl-C, and SIGTERM sent to the whole group (timeout, SLURM), are the driver's to
    # handle: it stops its workers itself, after it keeps what finished.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    # tqdm's default lock is a multiprocessing semaphore: a worker killed mid-unit would leak
    # it and the resource tracker would complain. Workers draw no bars; a thread lock does.
    tqdm.set_lock(threading.RLock())
    for variable in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[variable] = str(threads)
    os.chdir(_enter_scratch(temp))  # units must not depend on the driver's working directory
    try:
        while True:
            try:
                message = connection.recv()
            except (EOFError, OSError):  # the driver is gone: leave quietly, no traceback
                return
            if message is None:
                return
            index, fn, args = message

            def send(fraction: float, index: int = index) -> None:
                with contextlib.suppress(OSError):  # the driver is gone: the unit goes on
                    connection.send_bytes(pickle.dumps((index, None, fraction)))

            try:
                with _reporting(send):
                    value = run_unit(fn, args, threads)
                data = pickle.dumps((index, True, value))
            except Exception as error:  # the unit raised, or its result does not pickle
                data = pickle.dumps((index, False, _portable(error)))
            try:
                connection.send_bytes(data)
            except OSError:  # the driver is gone (BrokenPipeError): leave quietly
                return
    finally:
        os.chdir(temp)
        _leave_scratch()


def _portable(error: Exception) -> Exception:
    """``error`` if it survives pickling, else an ExecutionError with its message."""
    try:
        pickle.loads(pickle.dumps(error))
        return error
    except Exception:
        return ExecutionError(f"{type(error).__name__}: {_first_line(error)}")


@dataclass
class _Slot:
    process: Any
    connection: Any
    unit: int | None = None


def _map_local(
    fn: Callable[..., Any],
    units: Sequence[tuple[Any, ...]],
    backend: Backend,
    finished: Callable[[int, Any], None],
    bar: _Bar,
    names: list[str],
) -> None:
    from multiprocessing.connection import wait

    context = _context(fn)
    queue = deque(range(len(units)))
    deaths = [0] * len(units)
    slots: list[_Slot] = []
    remaining = len(units)

    temp = tempfile.gettempdir()

    def start() -> _Slot:
        mine, theirs = context.Pipe()
        process = context.Process(
            target=_worker, args=(theirs, os.getpid(), backend.threads, temp), daemon=True
        )
        process.start()
        theirs.close()
        return _Slot(process=process, connection=mine)

    try:
        slots = [start() for _ in range(min(backend.jobs, len(units)))]
        while remaining:
            for slot in slots:
                if slot.unit is None and queue:
                    slot.unit = queue.popleft()
                    slot.connection.send((slot.unit, fn, units[slot.unit]))
            busy = [slot for slot in slots if slot.unit is not None]
            ready = wait([s.connection for s in busy] + [s.process.sentinel for s in busy])
            for i, slot in enumerate(slots):
                if slot.unit is None:
                    continue
                if slot.connection in ready or slot.process.sentinel in ready:
                    reply = _receive(slot)
                    if reply is not None and reply[1] is None:  # the unit's progress
                        bar.partial(reply[0], reply[2])
                    elif reply is not None:
                        index, ok, value = reply
                        slot.unit = None
                        if not ok:
                            raise value
                        remaining -= 1
                        finished(index, value)
                    elif not slot.process.is_alive() or slot.process.sentinel in ready:
                        queue.appendleft(_bury(slot, deaths, backend.retries, bar, names, temp))
                        slots[i] = start()
    finally:
        _stop(slots)
        sweep_leftovers(temp)  # workers killed by _stop


def _bury(
    slot: _Slot, deaths: list[int], retries: int, bar: _Bar, names: list[str], temp: str
) -> int:
    """A worker that died: its scratch folder removed, its unit's death counted; the unit, to
    run again on a fresh worker, unless it has died more than ``retries`` times."""
    slot.process.join()
    sweep_leftovers(temp)  # the dead worker's scratch folder
    unit, slot.unit = slot.unit, None
    assert unit is not None  # only busy slots are watched
    deaths[unit] += 1
    bar.fail(unit)
    if deaths[unit] > retries:
        raise ExecutionError(
            f"{names[unit]}: its worker died {deaths[unit]} times "
            f"(last exit code {slot.process.exitcode}); giving up"
        )
    slot.connection.close()
    return unit


def _context(fn: Callable[..., Any]) -> Any:
    """The ``multiprocessing`` context workers start from, with ``fn``'s module preloaded.

    Not a plain fork: a forked child can deadlock on the driver's torch thread pools. A fork
    server is a clean process that imports the unit's module once; workers fork from it.
    (It exits when the driver dies, and its workers with it.)
    """
    import multiprocessing

    context: Any = multiprocessing.get_context(
        "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
    )
    if context.get_start_method() == "forkserver" and fn.__module__ not in ("__main__", None):
        context.set_forkserver_preload([__name__, fn.__module__])
    return context


def _receive(slot: _Slot) -> tuple[int, bool | None, Any] | None:
    """The worker's message waiting in its pipe (a unit's result, error or progress), or None:
    nothing waits, or the worker is gone."""
    reply = None
    with contextlib.suppress(EOFError, OSError):
        if slot.connection.poll():
            reply = pickle.loads(slot.connection.recv_bytes())
    return reply


def _stop(slots: list[_Slot]) -> None:
    """Stop every worker: idle ones are asked, busy ones (an error, Ctrl-C) are killed."""
    for slot in slots:
        if slot.unit is None:
            with contextlib.suppress(OSError, ValueError):
                slot.connection.send(None)
        else:
            slot.process.kill()
    for slot in slots:
        slot.process.join(timeout=5)
        if slot.process.is_alive():
            slot.process.kill()
            slot.process.join()
        slot.connection.close()
