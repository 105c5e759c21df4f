"""One way to run independent units (seeds, runs, matchups), locally or on a Ray cluster.

:func:`map_units` maps a top-level function over a list of argument tuples and returns the
results in unit order, whatever the backend:

* **local processes** (the default, ``--jobs N``): up to N workers, forked from a
  ``multiprocessing`` fork server that imported the unit's module (torch) once, so starting
  a worker costs no second import. Each worker dies with the driver (the fork server exits
  with it; ``PR_SET_PDEATHSIG`` on Linux, and a watchdog on the parent's and the driver's
  pids everywhere), ignores Ctrl-C (the driver stops them), and works in a private empty
  folder, so no unit can depend on the driver's working directory. One unit, or one job, runs in the
  driver itself, with the same thread pinning.
* **Ray** (``--ray ADDRESS``, or ``RAY_ADDRESS`` set; ``--ray local`` starts a private
  single-machine instance): one task per unit with one CPU. ``ray`` is imported only then
  (``pip install 'pokerirl[ray]'``).

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

**Unit records.** :func:`save_unit_folder` and :func:`load_unit` give the resume rules shared
by every command: a unit is finished only when its outputs and its record (``unit.json``: a
fingerprint of its configuration and inputs, and the sha256 of each output file) were written;
a rerun reuses it when the fingerprint matches, recomputes it when it is half-written or
corrupt, and refuses it, in one line, when it was made with another configuration, unless
``overwrite``. Folders are written beside their target and swapped in at the end, so a killed
run leaves the previous folder as it was.

>>> map_units(pow, [(2, 3), (3, 2)], backend=Backend())
[8, 9]
>>> fingerprint({"b": 1, "a": [2]}) == fingerprint({"a": [2], "b": 1})
True
"""

from __future__ import annotations

import contextlib
import hashlib
import json
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

R = TypeVar("R")

RETRIES = 2  # a unit whose worker dies runs at most 1 + RETRIES times
RECORD_FILE = "unit.json"
RECORD_FORMAT = "pokerirl-unit/1"
LOCAL_RAY = "local"


class ExecutionError(RuntimeError):
    """A unit could not be run (its worker kept dying, Ray is missing); one line."""


class UnitConflict(ValueError):
    """A finished unit was made with another configuration; one line."""


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
            raise ValueError(f"unknown backend {self.kind!r} (local or ray)")
        if self.jobs < 1:
            raise ValueError(f"jobs must be at least 1, got {self.jobs}")
        if self.threads < 1:
            raise ValueError(f"threads must be at least 1, got {self.threads}")
        if self.retries < 0:
            raise ValueError(f"retries must be at least 0, got {self.retries}")
        if (self.kind == "ray") != bool(self.address):
            raise ValueError("a Ray backend needs an address ('local' for a private one)")

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
            raise ValueError("--ray needs an address (HOST:PORT) or 'local'")
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


def run_unit(fn: Callable[..., R], args: tuple[Any, ...], threads: int = 1) -> R:
    """``fn(*args)`` with torch pinned to ``threads`` threads: what every backend calls."""
    with pinned_threads(threads):
        return fn(*args)


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
            bar.done()

        if ray is not None:
            _map_ray(ray, fn, units, backend, finished, bar, names)
        elif backend.jobs == 1 or len(units) == 1:
            for index, args in enumerate(units):
                finished(index, run_unit(fn, args, backend.threads))
        else:
            _map_local(fn, units, backend, finished, bar, names)
    return results


class _Bar:
    """One tqdm bar over units with reused and failed counts in its postfix."""

    def __init__(self, total: int, *, reused: int, desc: str, enabled: bool) -> None:
        self.reused, self.failed = reused, 0
        self.bar = tqdm(
            total=total + reused, initial=reused, unit="unit", desc=desc, disable=not enabled
        )
        self._postfix()

    def _postfix(self) -> None:
        self.bar.set_postfix_str(f"reused {self.reused}, failed {self.failed}", refresh=False)

    def done(self) -> None:
        self.bar.update(1)

    def fail(self) -> None:
        self.failed += 1
        self._postfix()
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


def _worker(connection: Any, parent: int, threads: int) -> None:
    """A local worker: run the units the driver sends until it sends None or goes away."""
    _die_with(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the driver's to handle
    # tqdm's default lock is a multiprocessing semaphore: a worker killed mid-unit would leak
    # it and the resource tracker would complain. Workers draw no bars; a thread lock does.
    tqdm.set_lock(threading.RLock())
    for variable in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[variable] = str(threads)
    home = tempfile.mkdtemp(prefix="pokerirl-worker-")
    os.chdir(home)  # units must not depend on the driver's working directory
    try:
        while True:
            try:
                message = connection.recv()
            except EOFError:
                return
            if message is None:
                return
            index, fn, args = message
            try:
                reply = (index, True, run_unit(fn, args, threads))
                data = pickle.dumps(reply)
            except Exception as error:  # the unit raised, or its result does not pickle
                data = pickle.dumps((index, False, _portable(error)))
            connection.send_bytes(data)
    finally:
        os.chdir(tempfile.gettempdir())
        shutil.rmtree(home, ignore_errors=True)


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
    context = multiprocessing.get_context(
        "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
    )
    if context.get_start_method() == "forkserver" and fn.__module__ not in ("__main__", None):
        context.set_forkserver_preload([__name__, fn.__module__])
    queue = deque(range(len(units)))
    deaths = [0] * len(units)
    slots: list[_Slot] = []
    remaining = len(units)

    def start() -> _Slot:
        mine, theirs = context.Pipe()
        process = context.Process(
            target=_worker, args=(theirs, os.getpid(), backend.threads), daemon=True
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
                    if reply is not None:
                        index, ok, value = reply
                        slot.unit = None
                        if not ok:
                            raise value
                        remaining -= 1
                        finished(index, value)
                    elif not slot.process.is_alive() or slot.process.sentinel in ready:
                        slot.process.join()
                        unit, slot.unit = slot.unit, None
                        deaths[unit] += 1
                        bar.fail()
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
    private = None
    if connect_here:
        if backend.address == LOCAL_RAY:  # its own short folder: never /tmp/ray, shared
            private = tempfile.mkdtemp(prefix="ray", dir="/tmp" if os.path.isdir("/tmp") else None)
        _ray_init(ray, backend.address or LOCAL_RAY, private)
    try:
        yield ray
    finally:
        if connect_here:
            ray.shutdown()
        if private is not None:
            shutil.rmtree(private, ignore_errors=True)


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

    task = ray.remote(num_cpus=1, max_retries=backend.retries)(run_unit)
    pending = {task.remote(fn, args, backend.threads): i for i, args in enumerate(units)}
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            index = pending.pop(ready[0])
            try:
                value = ray.get(ready[0])
            except RayTaskError as error:  # the unit raised: re-raise what it raised
                cause = error.cause if isinstance(error.cause, Exception) else None
                raise (cause or ExecutionError(_first_line(error))) from None
            except RayError as error:
                bar.fail()
                raise ExecutionError(
                    f"{names[index]}: failed on Ray after {backend.retries} retries "
                    f"({type(error).__name__}: {_first_line(error)})"
                ) from None
            finished(index, value)
    finally:
        for ref in pending:
            with contextlib.suppress(Exception):
                ray.cancel(ref, force=True)


def _ray_init(ray: Any, address: str, temp_dir: str | None) -> None:
    import logging

    _check_reachable(address)
    options: dict[str, Any] = {"log_to_driver": False, "logging_level": logging.WARNING}
    if address == LOCAL_RAY:
        options.update(include_dashboard=False, _temp_dir=temp_dir)
    try:
        ray.init(address=address, **options)
    except (ConnectionError, RuntimeError, ValueError) as error:
        raise ExecutionError(f"cannot connect to Ray at {address}: {_first_line(error)}") from None


def _check_reachable(address: str, timeout: float = 10.0) -> None:
    """Fail in one line when nothing listens at a ``HOST:PORT`` address: ``ray.init`` would
    otherwise retry for ever."""
    import socket

    host, _, port = address.rpartition(":")
    if "://" in address or not host or not port.isdigit():
        return  # ray://, auto, local: Ray's own checks
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise ExecutionError(f"cannot reach the Ray cluster at {address}: {reason}") from None


@contextlib.contextmanager
def ray_head(*, num_cpus: int = 2, timeout: float = 120.0) -> Iterator[str]:
    """A private single-node Ray cluster, started with Ray's own ``ray start --head``; yields
    its address (for ``--ray``).

    For tests and benchmarks. It owns everything it starts: a temporary folder of its own (a
    short path: Ray's socket paths must fit in 107 characters), free ports, workers whose
    working directory is an empty folder of their own, this ``pokerirl`` importable on them.
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
    }
    environment.pop("RAY_ADDRESS", None)
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


# --- unit records and fingerprints ---------------------------------------------------------


def fingerprint(config: Any) -> str:
    """``sha256:<hex>`` of ``config`` as canonical JSON (sorted keys, no spaces)."""
    text = json.dumps(config, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return f"sha256:{hashlib.sha256(text.encode()).hexdigest()}"


def bytes_fingerprint(data: bytes) -> str:
    return f"sha256:{hashlib.sha256(data).hexdigest()}"


def read_files(folder: str | os.PathLike[str], names: Sequence[str]) -> dict[str, bytes]:
    """The bytes of ``names`` in ``folder``: how a unit's inputs travel to its worker."""
    return {name: (Path(folder) / name).read_bytes() for name in names}


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


def make_record(
    config: Mapping[str, Any],
    *,
    files: Mapping[str, bytes] | None = None,
    result: Any = None,
) -> dict[str, Any]:
    """A unit record: its fingerprint (of ``config``), ``config`` itself, the sha256 of each
    output file and, for units that are a single file, the ``result``."""
    return {
        "format": RECORD_FORMAT,
        "fingerprint": fingerprint(config),
        "config": dict(config),
        "files": {name: bytes_fingerprint(data) for name, data in sorted((files or {}).items())},
        "result": result,
    }


def load_unit(
    record_path: str | os.PathLike[str],
    config: Mapping[str, Any],
    *,
    overwrite: bool = False,
    what: str | None = None,
) -> dict[str, Any] | None:
    """The record of a finished unit at ``record_path`` to reuse, or None to (re)compute it.

    None when the record is missing, unreadable, or a file it lists is missing or has other
    bytes (half-written or corrupt: recompute). A valid record of another configuration is
    refused with :class:`UnitConflict` naming what changed, unless ``overwrite``.
    """
    path = Path(record_path)
    try:
        record = json.loads(path.read_text())
        if not isinstance(record, dict) or record.get("format") != RECORD_FORMAT:
            return None
        saved_print, saved_config = record["fingerprint"], record["config"]
        for name, digest in record["files"].items():
            if bytes_fingerprint((path.parent / name).read_bytes()) != digest:
                return None
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None
    if saved_print == fingerprint(config):
        return record
    if overwrite:
        return None
    changed = describe_changes(saved_config, json.loads(json.dumps(config)))  # tuples: lists
    raise UnitConflict(
        f"{what or path} was made with another configuration ({changed}); "
        "use another --out, or --overwrite to recompute it"
    )


def describe_changes(old: Any, new: Any, *, limit: int = 4) -> str:
    """``key old -> new, ...`` over the leaves of two JSON-like configs.

    >>> describe_changes({"a": 1, "d": {"x": 2}}, {"a": 1, "d": {"x": 3}})
    'd.x 2 -> 3'
    """
    flat_old, flat_new = _flatten(old), _flatten(new)
    keys = sorted(
        k for k in flat_old.keys() | flat_new.keys() if flat_old.get(k) != flat_new.get(k)
    )
    parts = [f"{k} {flat_old.get(k)!r} -> {flat_new.get(k)!r}" for k in keys[:limit]]
    if len(keys) > limit:
        parts.append(f"{len(keys) - limit} more")
    return ", ".join(parts) or "fingerprint differs"


def _flatten(value: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(value, Mapping):
        out: dict[str, Any] = {}
        for key, item in value.items():
            out.update(_flatten(item, f"{prefix}{key}."))
        return out
    return {prefix.rstrip("."): value}


def save_record(path: str | os.PathLike[str], record: Mapping[str, Any]) -> None:
    """Write a single-file unit's record atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.write_text(path, json.dumps(record, indent=2, sort_keys=True) + "\n")


def save_unit_folder(
    folder: str | os.PathLike[str],
    files: Mapping[str, bytes],
    config: Mapping[str, Any],
    *,
    unhashed: Mapping[str, bytes] | None = None,
) -> None:
    """Replace ``folder`` with ``files``, ``unhashed`` files (timings) and a record last.

    Everything is written into a new folder beside ``folder``, which is then swapped in: a
    reader never sees a mix of old and new files, and a kill leaves the old folder whole
    (:func:`tidy_folder` finishes or undoes an interrupted swap).
    """
    folder = Path(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    tidy_folder(folder)
    with atomic.naming(folder):  # errors name the folder, not the staging one
        staging = Path(tempfile.mkdtemp(prefix=f".{folder.name}.new-", dir=folder.parent))
        try:
            atomic.make_shareable(staging)
            write_files(staging, {**files, **(unhashed or {})})
            record = make_record(config, files=files)
            text = json.dumps(record, indent=2, sort_keys=True) + "\n"
            (staging / RECORD_FILE).write_text(text)
            if folder.exists():
                old = Path(tempfile.mkdtemp(prefix=f".{folder.name}.old-", dir=folder.parent))
                os.rename(folder, old / "x")
                os.rename(staging, folder)
                shutil.rmtree(old, ignore_errors=True)
            else:
                os.rename(staging, folder)
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise


def tidy_folder(folder: str | os.PathLike[str]) -> None:
    """Clear what a killed :func:`save_unit_folder` left beside ``folder``: put back an old
    folder moved aside but not yet replaced, and delete unfinished new ones."""
    folder = Path(folder)
    if not folder.parent.is_dir():
        return
    for leftover in sorted(folder.parent.glob(f".{folder.name}.old-*")):
        if not folder.exists() and (leftover / "x").is_dir():
            os.rename(leftover / "x", folder)
        shutil.rmtree(leftover, ignore_errors=True)
    for leftover in folder.parent.glob(f".{folder.name}.new-*"):
        shutil.rmtree(leftover, ignore_errors=True)


def load_unit_folder(
    folder: str | os.PathLike[str],
    config: Mapping[str, Any],
    *,
    overwrite: bool = False,
) -> dict[str, Any] | None:
    """:func:`load_unit` for a unit that is a folder (its record is ``unit.json`` inside).

    A folder that holds files but no record was not written by a unit (an older pokerirl, or
    a user's folder): it is refused unless ``overwrite``, and even then only when it holds
    plain files and no subfolders, so a mistyped ``--out`` never replaces a tree.
    """
    folder = Path(folder)
    tidy_folder(folder)
    if folder.exists() and not folder.is_dir():
        raise UnitConflict(f"{folder} exists and is not a folder")
    if not folder.exists() or not any(folder.iterdir()):
        return None
    if (folder / RECORD_FILE).is_file():
        return load_unit(folder / RECORD_FILE, config, overwrite=overwrite, what=str(folder))
    if overwrite and all(child.is_file() for child in folder.iterdir()):
        return None
    raise UnitConflict(
        f"{folder} already holds files but no {RECORD_FILE} (not written by this pokerirl); "
        + (
            "it has subfolders, so it is never replaced: use another --out"
            if overwrite
            else "use another --out, or --overwrite to replace it"
        )
    )
