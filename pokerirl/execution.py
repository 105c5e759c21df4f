"""One way to run independent units (seeds, runs, matchups), locally or on a Ray cluster.

:func:`map_units` maps a top-level function over a list of argument tuples and returns the
results in unit order, whatever the backend:

* **local processes** (the default, ``--jobs N``): up to N workers, forked from a
  ``multiprocessing`` fork server that imported the unit's module (torch) once, so starting
  a worker costs no second import. Each worker dies with the driver (the fork server exits
  with it; ``PR_SET_PDEATHSIG`` on Linux, and a watchdog on the parent's and the driver's
  pids everywhere), ignores Ctrl-C and SIGTERM (the driver stops them), leaves quietly when
  the driver is gone, and works in a private empty folder, so no unit can depend on the
  driver's working directory. One unit, or one job, runs in the driver itself, with the same
  thread pinning.
* **Ray** (``--ray ADDRESS``, or ``RAY_ADDRESS`` set; ``--ray local`` starts a private
  single-machine instance): one task per unit with one CPU. ``ray`` is imported only then
  (``pip install 'pokerirl[ray]'``). An address is used as given, loopback included, and one
  where no Ray head answers fails in one line within seconds. A private instance dies with
  its driver, even a killed one: a small reaper process kills every process the instance
  started and removes its folder (``pokerirl-ray-<pid>-*`` in the temp folder).

**Scratch.** Every worker (local or Ray) keeps its temporary files in a folder of its own,
``pokerirl-scratch-<pid>-*`` in the temp folder, locked while it lives. A worker that is
killed leaves it behind: the driver removes it when it sees the worker die, and any later
run removes those of processes that are gone.

Results do not depend on the backend or on the number of jobs: every unit runs with torch
pinned to ``threads`` threads (one by default) and seeds everything from its own arguments.

**Data.** Units get their inputs as arguments (the bytes of agents and reward runs, read by
the driver) and return their outputs as values; the driver writes them. Workers need no
shared filesystem and their working directory does not matter. On Ray the arguments travel
through the object store. Only ``pokerirl`` itself must be installed on every node.

**Failures.** A unit whose worker dies (killed, out of memory, a lost node) is run again, up
to :data:`RETRIES` more times, on a fresh worker; then the run stops with one line. A unit that
raises stops the run with its own exception. Units finished before a stop are kept: callers
save each result as it arrives (``on_result``), so a rerun resumes from them.

**Unit records** are the store's (:mod:`pokerirl.store`: ``Unit``, ``run_units``), which runs
its units with :func:`map_units`.

>>> map_units(pow, [(2, 3), (3, 2)], backend=Backend())
[8, 9]
"""

from __future__ import annotations

import atexit
import contextlib
import functools
import os
import pickle
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from tqdm import tqdm

from pokerirl import atomic
from pokerirl.errors import ConfigError, PokerIRLError

R = TypeVar("R")

RETRIES = 2  # a unit whose worker dies runs at most 1 + RETRIES times
LOCAL_RAY = "local"
SCRATCH_PREFIX = "pokerirl-scratch-"  # + the owner's pid: a worker's temporary files
PRIVATE_RAY_PREFIX = "pokerirl-ray-"  # + the driver's pid: a private Ray instance's folder


class ExecutionError(PokerIRLError, RuntimeError):
    """A unit could not be run (its worker kept dying, Ray is missing); one line."""


# --- backends ------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Backend:
    """Where units run: ``local`` processes (``jobs`` of them) or a Ray cluster at ``address``
    (``"local"``: a private single-machine instance). ``threads``: torch threads per unit.
    """

    kind: str = "local"
    jobs: int = 1
    address: str | None = None
    threads: int = 1
    retries: int = RETRIES

    def __post_init__(self) -> None:
        if self.kind not in ("local", "ray"):
            raise ConfigError(f"unknown backend {self.kind!r} (local or ray)")
        if self.jobs < 1:
            raise ConfigError(f"jobs must be at least 1, got {self.jobs}")
        if self.threads < 1:
            raise ConfigError(f"threads must be at least 1, got {self.threads}")
        if self.retries < 0:
            raise ConfigError(f"retries must be at least 0, got {self.retries}")
        if (self.kind == "ray") != bool(self.address):
            raise ConfigError("a Ray backend needs an address ('local' for a private one)")

    def describe(self) -> str:
        """``local, 2 jobs`` or ``ray at ADDRESS``."""
        if self.kind == "ray":
            return f"ray at {self.address}"
        return f"local, {self.jobs} job{'s' * (self.jobs > 1)}"


def choose_backend(
    *,
    jobs: int = 1,
    ray: str | None = None,
    threads: int = 1,
    environ: Mapping[str, str] | None = None,
) -> Backend:
    """The backend a command asked for: ``ray`` (an address or ``local``), else the
    ``RAY_ADDRESS`` environment variable, else ``jobs`` local processes.

    >>> choose_backend(jobs=2, environ={}).describe()
    'local, 2 jobs'
    >>> choose_backend(environ={"RAY_ADDRESS": "10.0.0.1:6379"}).describe()
    'ray at 10.0.0.1:6379'
    """
    environ = os.environ if environ is None else environ
    address = ray if ray is not None else environ.get("RAY_ADDRESS") or None
    if address is not None:
        if not address.strip():
            raise ConfigError("Ray needs an address (HOST:PORT) or 'local', got a blank one")
        return Backend(kind="ray", address=address.strip(), jobs=jobs, threads=threads)
    return Backend(jobs=jobs, threads=threads)


# --- running units -------------------------------------------------------------------------


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


# --- progress from inside a unit ------------------------------------------------------------

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


# --- local processes -----------------------------------------------------------------------


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


# --- scratch folders -------------------------------------------------------------------------

_scratch: tuple[Path, int | None] | None = None  # this process's scratch folder and its lock


def _owned_folder(prefix: str, parent: str | None) -> tuple[Path, int | None]:
    """A new folder ``<prefix><pid>-*`` in ``parent``, locked by this process (the lock's
    descriptor, to close when the folder goes)."""
    folder = Path(tempfile.mkdtemp(prefix=f"{prefix}{os.getpid()}-", dir=parent))
    return folder, atomic.lock_folder(folder)


def _enter_scratch(temp: str) -> Path:
    """This process's scratch folder in ``temp`` (made on the first call, after removing the
    leftovers of processes that are gone), and tempfile's folder from now on: whatever units
    leave there goes with it."""
    global _scratch
    if _scratch is None:
        sweep_leftovers(temp)
        _scratch = _owned_folder(SCRATCH_PREFIX, temp)
        tempfile.tempdir = str(_scratch[0])
        atexit.register(_leave_scratch)
    return _scratch[0]


def _leave_scratch() -> None:
    global _scratch
    if _scratch is not None:
        (folder, lock), _scratch = _scratch, None
        tempfile.tempdir = None
        shutil.rmtree(folder, ignore_errors=True)
        if lock is not None:
            os.close(lock)


def sweep_leftovers(temp: str | os.PathLike[str] | None = None) -> list[Path]:
    """Remove the scratch and private-Ray folders in ``temp`` (default: the temporary folder)
    left by processes that are gone: the pid in the name is not running, and nobody holds the
    folder's lock. Returns the folders removed."""
    removed: list[Path] = []
    try:
        entries = list(Path(temp or tempfile.gettempdir()).iterdir())
    except OSError:
        return removed
    for folder in entries:
        prefix = next(
            (p for p in (SCRATCH_PREFIX, PRIVATE_RAY_PREFIX) if folder.name.startswith(p)), None
        )
        owner = folder.name[len(prefix) :].partition("-")[0] if prefix else ""
        if not owner.isdecimal() or _running(int(owner)) or not folder.is_dir():
            continue
        lock = atomic.lock_folder(folder)
        if lock is None:  # a process it was handed to still holds it
            continue
        try:
            shutil.rmtree(folder, ignore_errors=True)
        finally:
            os.close(lock)
        removed.append(folder)
    return removed


def _running(pid: int) -> bool:
    """Whether ``pid`` is a process that has not ended (a zombie has ended)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return _start_mark(pid) != "Z"


def _start_mark(pid: int) -> str | None:
    """``pid``'s start time (Linux ``/proc``), to tell it from a later process given the same
    pid; ``"Z"`` for a zombie, None when it is gone or unknown."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return "Z" if fields[0] in ("Z", "X") else fields[19]


def _portable(error: Exception) -> Exception:
    """``error`` if it survives pickling, else an ExecutionError with its message."""
    try:
        pickle.loads(pickle.dumps(error))
        return error
    except Exception:
        return ExecutionError(f"{type(error).__name__}: {_first_line(error)}")


def _first_line(error: BaseException) -> str:
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__


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
    import multiprocessing
    from multiprocessing.connection import wait

    # Not a plain fork: a forked child can deadlock on the driver's torch thread pools. A fork
    # server is a clean process that imports the unit's module once; workers fork from it.
    # (It exits when the driver dies, and its workers with it.)
    context: Any = multiprocessing.get_context(
        "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
    )
    if context.get_start_method() == "forkserver" and fn.__module__ not in ("__main__", None):
        context.set_forkserver_preload([__name__, fn.__module__])
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
                    reply = None
                    with contextlib.suppress(EOFError, OSError):
                        if slot.connection.poll():
                            reply = pickle.loads(slot.connection.recv_bytes())
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
                        slot.process.join()
                        sweep_leftovers(temp)  # the dead worker's scratch folder
                        unit, slot.unit = slot.unit, None
                        deaths[unit] += 1
                        bar.fail(unit)
                        if deaths[unit] > backend.retries:
                            raise ExecutionError(
                                f"{names[unit]}: its worker died {deaths[unit]} times "
                                f"(last exit code {slot.process.exitcode}); giving up"
                            )
                        queue.appendleft(unit)
                        slot.connection.close()
                        slots[i] = start()
    finally:
        _stop(slots)
        sweep_leftovers(temp)  # workers killed by _stop


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


# --- Ray -----------------------------------------------------------------------------------


@contextlib.contextmanager
def _ray_session(backend: Backend) -> Iterator[Any]:
    """``ray``, connected to the backend's cluster (unless this process already is)."""
    try:
        import ray
    except ImportError:
        raise ExecutionError("the Ray backend needs ray: pip install 'pokerirl[ray]'") from None
    connect_here = not ray.is_initialized()
    try:
        with contextlib.ExitStack() as stack:
            private = None
            if connect_here and backend.address == LOCAL_RAY:
                private = stack.enter_context(_private_ray_folder())
                stack.enter_context(_private_token(ray))
            if connect_here:
                _ray_init(ray, backend.address or LOCAL_RAY, private)
                stack.callback(ray.shutdown)
            yield ray
    finally:
        sweep_leftovers()  # the scratch folders of Ray workers killed on this machine


@contextlib.contextmanager
def _private_ray_folder() -> Iterator[str]:
    """The folder of a private Ray instance (short: Ray's socket paths must fit in 107
    characters; never /tmp/ray, which is shared), and a reaper that, whenever this process
    ends (a kill included), kills the processes the instance started and removes the folder."""
    import subprocess

    folder, lock = _owned_folder(PRIVATE_RAY_PREFIX, "/tmp" if os.path.isdir("/tmp") else None)
    package_root = str(Path(__file__).resolve().parents[1])
    path = os.environ.get("PYTHONPATH")
    code = "from pokerirl.execution import _reap; _reap()"
    reaper = subprocess.Popen(
        [sys.executable, "-c", code, str(os.getpid()), str(folder)],
        stdin=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env={**os.environ, "PYTHONPATH": package_root + (os.pathsep + path if path else "")},
        start_new_session=True,  # a Ctrl-C or a kill of the driver's group spares it
    )
    try:
        yield str(folder)
    finally:
        reaper.stdin.close()  # type: ignore[union-attr]  # the end of this process does the same
        with contextlib.suppress(subprocess.TimeoutExpired):
            reaper.wait(timeout=30)
        shutil.rmtree(folder, ignore_errors=True)
        if lock is not None:
            os.close(lock)


def _reap() -> None:
    """The reaper of a private Ray instance (``python -c``; arguments: the driver's pid and
    the instance's folder).

    Until its standard input closes (the driver is done, or gone) or its parent changes, it
    notes, four times a second, every process below the driver that was not there when it
    started (the instance's: Ray's own agents outlive a killed driver by a minute or more);
    then it kills those still running, by pid and start time, and removes the folder.
    """
    import select

    driver, folder = int(sys.argv[1]), sys.argv[2]
    for name in ("SIGINT", "SIGHUP"):
        signal.signal(getattr(signal, name), signal.SIG_IGN)
    before = _descendants(driver) | {os.getpid()}
    seen: dict[int, str] = {}
    while os.getppid() == driver:
        for pid in _descendants(driver) - before - seen.keys():
            if (mark := _start_mark(pid)) not in (None, "Z"):
                seen[pid] = mark  # type: ignore[assignment]
        if select.select([sys.stdin], [], [], 0.25)[0] and not os.read(sys.stdin.fileno(), 64):
            break
    doomed = {pid for pid, mark in seen.items() if _start_mark(pid) == mark}
    for pid in list(doomed):  # and what they started since the last look
        doomed |= {child for child in _descendants(pid) if _start_mark(child) not in (None, "Z")}
    for pid in doomed:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    deadline = time.monotonic() + 10
    while any(_running(pid) for pid in doomed) and time.monotonic() < deadline:
        time.sleep(0.05)
    shutil.rmtree(folder, ignore_errors=True)


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
                running = set(pending.values())
                try:
                    latest = ray.get(sink.take.remote())
                except RayError:  # progress is never worth a run: go on without it
                    sink, latest = None, {}
                for unit, fraction in latest.items():
                    if unit in running:
                        bar.partial(unit, fraction)
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


def _ray_init(ray: Any, address: str, temp_dir: str | None) -> None:
    import logging

    check_reachable(address)
    options: dict[str, Any] = {"log_to_driver": False, "logging_level": logging.WARNING}
    if address == LOCAL_RAY:
        options.update(include_dashboard=False, _temp_dir=temp_dir)
    # ray.init sets a SIGTERM handler that exits with code 15 and no line; a handler the
    # program set (the command line's: SIGTERM is Ctrl-C) is put back.
    main = threading.current_thread() is threading.main_thread()
    handler = signal.getsignal(signal.SIGTERM) if main else None
    try:
        with _address_as_given():
            ray.init(address=address, **options)
    except (ConnectionError, RuntimeError, ValueError) as error:
        raise ExecutionError(f"cannot connect to Ray at {address}: {_why(error)}") from None
    finally:
        if callable(handler):
            signal.signal(signal.SIGTERM, handler)


def _why(error: BaseException) -> str:
    """The first line of a failed ``ray.init``, or what its causes say about a token."""
    cause: BaseException | None = error
    while cause is not None:
        if "InvalidAuthToken" in str(cause):
            return (
                "the cluster wants its authentication token (set RAY_AUTH_MODE=token, with "
                "the token in RAY_AUTH_TOKEN or ~/.ray/auth_token)"
            )
        cause = cause.__cause__ or cause.__context__
    return _first_line(error)


@contextlib.contextmanager
def _private_token(ray: Any) -> Iterator[None]:
    """For a private instance, from before it starts to after it stops: a token of its own,
    in its processes' environment only.

    Ray otherwise saves a new local instance's token to ``~/.ray/auth_token``, and every
    ``ray start --head`` on the machine then wants it, which drivers given an explicit
    address never send: one ``--ray local`` would break every later ``--ray HOST:PORT``.
    Ray's processes inherit the token as they start; this process's environment is put back.
    """
    names = ("RAY_AUTH_TOKEN", "RAY_AUTH_MODE")
    if any(os.environ.get(n) for n in ("RAY_AUTH_TOKEN", "RAY_AUTH_TOKEN_PATH")):
        yield  # the user's own
        return
    import secrets

    before = {name: os.environ.get(name) for name in names}
    os.environ["RAY_AUTH_TOKEN"] = secrets.token_hex(32)
    try:
        yield
    finally:
        for name, value in before.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
        with contextlib.suppress(AttributeError, RuntimeError):
            ray._raylet.Config.initialize("")  # Ray reads RAY_AUTH_MODE again


@contextlib.contextmanager
def _address_as_given() -> Iterator[None]:
    """Inside the block, Ray connects to a loopback address as given.

    Ray replaces ``127.0.0.1``, ``localhost`` and ``::1`` with this machine's network address
    before it connects (for multi-node clusters), and a head started with
    ``--node-ip-address 127.0.0.1`` may not answer there. Without that helper (another Ray),
    Ray's own behaviour stays.
    """
    services = sys.modules.get("ray._private.services")
    original = getattr(services, "resolve_ip_for_localhost", None)
    if original is None:
        yield
        return
    services.resolve_ip_for_localhost = lambda host: host  # type: ignore[union-attr]
    try:
        yield
    finally:
        services.resolve_ip_for_localhost = original  # type: ignore[union-attr]


PROBE_SECONDS = 5.0  # how long a Ray head has to answer the first bytes of gRPC
# HTTP/2's client preface and an empty SETTINGS frame: a gRPC server (Ray's GCS) answers with
# a SETTINGS frame of its own; an HTTP/1 server (Ray's dashboard) with "HTTP/" or a page.
_HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])


def check_reachable(address: str, timeout: float = 10.0) -> None:
    """Fail in one line, within seconds, when nothing listens at a ``HOST:PORT`` address, or
    something that is not a Ray head (an HTTP server, a silent port): ``ray.init`` would
    otherwise retry for ever."""
    import socket

    host, _, port = address.rpartition(":")
    if "://" in address or not host or not port.isdigit():
        return  # ray://, auto, local: Ray's own checks
    try:
        connection = socket.create_connection((host.strip("[]"), int(port)), timeout=timeout)
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise ExecutionError(f"cannot reach the Ray cluster at {address}: {reason}") from None
    if os.environ.get("RAY_USE_TLS", "0").lower() in ("1", "true"):
        connection.close()  # a TLS head answers a handshake first: Ray's own checks
        return
    answer = b""
    with connection, contextlib.suppress(OSError):
        connection.settimeout(PROBE_SECONDS)
        connection.sendall(_HTTP2_PREFACE)
        while len(answer) < 9 and (data := connection.recv(9 - len(answer))):
            answer += data
    if len(answer) == 9 and answer[3] == 4 and answer[5:9] == bytes(4):
        return  # a SETTINGS frame on stream 0: gRPC
    if answer.startswith((b"HTTP/", b"<")):  # a status line, or an HTTP/0.9 page
        why = "an HTTP server answers there, not a Ray head (the head's --port, not its dashboard)"
    elif answer:
        why = "what answers there is not a Ray head (no gRPC)"
    else:
        why = f"it accepts connections but gave no Ray answer within {PROBE_SECONDS:g} s"
    raise ExecutionError(f"cannot connect to Ray at {address}: {why}")


@contextlib.contextmanager
def ray_head(*, num_cpus: int = 2, timeout: float = 120.0) -> Iterator[str]:
    """A private single-node Ray cluster, started with Ray's own ``ray start --head``; yields
    its address (for ``--ray``).

    For tests and benchmarks. It owns everything it starts: a temporary folder of its own (a
    short path: Ray's socket paths must fit in 107 characters), free ports, workers whose
    working directory is an empty folder of their own, this ``pokerirl`` importable on them,
    no token authentication (whatever ``~/.ray`` holds: drivers given an address send none).
    It stops only its own processes, by the process ids it recorded: never Ray's
    stop-everything command, which ends every Ray process on the machine.

    Raises:
        ExecutionError: Ray did not start (with the reason from its log).
    """
    import socket
    import subprocess

    executable = Path(sys.executable).with_name("ray")
    if not executable.exists():
        executable = Path(shutil.which("ray") or "ray")
    home = Path(tempfile.mkdtemp(prefix="ray", dir="/tmp" if os.path.isdir("/tmp") else None))
    sockets = [socket.socket() for _ in range(9)]
    for sock in sockets:
        sock.bind(("127.0.0.1", 0))
    port, *others = [sock.getsockname()[1] for sock in sockets]
    for sock in sockets:
        sock.close()
    options = (
        "ray-client-server-port", "dashboard-port", "dashboard-agent-listen-port",
        "dashboard-agent-grpc-port", "metrics-export-port", "runtime-env-agent-port",
        "node-manager-port", "object-manager-port",
    )  # fmt: skip
    command = [
        str(executable), "start", "--head", "--block", f"--port={port}",
        "--node-ip-address=127.0.0.1", f"--num-cpus={num_cpus}", f"--temp-dir={home / 't'}",
        "--include-dashboard=false", "--disable-usage-stats",
        *(f"--{option}={value}" for option, value in zip(options, others, strict=True)),
    ]  # fmt: skip
    package_root = str(Path(__file__).resolve().parents[1])
    path = os.environ.get("PYTHONPATH")
    environment = {
        **os.environ,
        "PYTHONPATH": package_root + (os.pathsep + path if path else ""),
        "RAY_DISABLE_USAGE_STATS": "1",
        # Ray would want a token whenever ~/.ray/auth_token exists (any local ray.init leaves
        # one); drivers given an explicit address never send it.
        "RAY_AUTH_MODE": "disabled",
    }
    for name in ("RAY_ADDRESS", "RAY_AUTH_TOKEN", "RAY_AUTH_TOKEN_PATH"):
        environment.pop(name, None)
    (home / "cwd").mkdir()
    log = home / "head.log"
    with log.open("wb") as stream:
        head = subprocess.Popen(
            command, cwd=home / "cwd", env=environment, stdout=stream, stderr=subprocess.STDOUT
        )
    owned: set[int] = set()
    try:
        deadline = time.monotonic() + timeout
        while b"Ray runtime started" not in log.read_bytes():
            if head.poll() is not None or time.monotonic() > deadline:
                tail = log.read_text(errors="replace").strip().splitlines()[-3:]
                raise ExecutionError(f"ray start --head failed: {' | '.join(tail)}")
            time.sleep(0.2)
        yield f"127.0.0.1:{port}"
    finally:
        owned = _descendants(head.pid)
        head.terminate()  # ray start --block stops what it started on SIGTERM
        try:
            head.wait(timeout=20)
        except subprocess.TimeoutExpired:
            head.kill()
            head.wait()
        for pid in owned | _descendants(head.pid):
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(home, ignore_errors=True)


def _descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (Linux ``/proc``; empty elsewhere)."""
    found: set[int] = set()
    todo = [pid]
    while todo:
        for task in Path(f"/proc/{todo.pop()}/task").glob("*"):
            with contextlib.suppress(OSError, ValueError):
                for child in map(int, (task / "children").read_text().split()):
                    if child not in found:
                        found.add(child)
                        todo.append(child)
    return found


# --- how a unit's inputs and outputs travel ------------------------------------------------


def read_files(folder: str | os.PathLike[str], names: Sequence[str]) -> dict[str, bytes]:
    """The bytes of ``names`` in ``folder``: how a unit's inputs travel to its worker."""
    return {name: (Path(folder) / name).read_bytes() for name in names}


def folder_files(folder: str | os.PathLike[str]) -> dict[str, bytes]:
    """Every file under ``folder`` by its relative path (``run-0/reward.pt``), sorted: how a
    unit computed in a scratch folder returns its outputs."""
    root = Path(folder)
    return {
        path.relative_to(root).as_posix(): path.read_bytes()
        for path in sorted(root.rglob("*"))
        if path.is_file()
    }


def write_files(folder: str | os.PathLike[str], files: Mapping[str, bytes]) -> Path:
    """Write ``files`` into ``folder`` (created, as are subfolders named in ``files``): how a
    worker lands its inputs."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in files.items():
        path = folder / name  # names may hold subfolders: "run-0/reward.pt"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    return folder
