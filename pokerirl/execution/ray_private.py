"""Ray instances this process starts and owns: a private instance's folder and the reaper
that kills what the instance started when the driver ends, a kill included
(``_private_ray_folder``, ``_reap``), and :func:`ray_head`, a private single-node cluster
for tests and benchmarks. Both stop only their own processes, by pid."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from pokerirl.execution.backend import ExecutionError
from pokerirl.execution.processes import _descendants, _running, _start_mark
from pokerirl.execution.scratch import PRIVATE_RAY_PREFIX, _owned_folder

if TYPE_CHECKING:
    import subprocess


def _pythonpath() -> str:
    """``PYTHONPATH`` with this ``pokerirl`` first: the processes started here import it."""
    package_root = str(Path(__file__).resolve().parents[2])  # above pokerirl/execution/
    path = os.environ.get("PYTHONPATH")
    return package_root + (os.pathsep + path if path else "")


@contextlib.contextmanager
def _private_ray_folder() -> Iterator[str]:
    """The folder of a private Ray instance (short: Ray's socket paths must fit in 107
    characters; never /tmp/ray, which is shared), and a reaper that, whenever this process
    ends (a kill included), kills the processes the instance started and removes the folder."""
    import subprocess

    folder, lock = _owned_folder(PRIVATE_RAY_PREFIX, "/tmp" if os.path.isdir("/tmp") else None)
    code = "from pokerirl.execution.ray_private import _reap; _reap()"
    reaper = subprocess.Popen(
        [sys.executable, "-c", code, str(os.getpid()), str(folder)],
        stdin=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env={**os.environ, "PYTHONPATH": _pythonpath()},
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


@contextlib.contextmanager
def ray_head(
    *,
    num_cpus: int = 2,
    timeout: float = 120.0,
    attempts: int = 3,
    say: Callable[[str], None] = lambda message: None,
) -> Iterator[str]:
    """A private single-node Ray cluster, started with Ray's own ``ray start --head``; yields
    its address (for ``--ray``).

    For tests and benchmarks. It owns everything it starts: a temporary folder of its own (a
    short path: Ray's socket paths must fit in 107 characters), free ports, workers whose
    working directory is an empty folder of their own, this ``pokerirl`` importable on them,
    no token authentication (whatever ``~/.ray`` holds: drivers given an address send none).
    It stops only its own processes, by the process ids it recorded: never Ray's
    stop-everything command, which ends every Ray process on the machine.

    A head that fails to start is stopped and started afresh (new folder, new ports), up to
    ``attempts`` times in all, each given ``timeout`` seconds, with a line to ``say`` for each
    failure (silent by default): Ray gives its raylet a fixed 30 seconds to register, which a loaded
    machine can exceed, and a free port can be taken between its choice and its use.

    Raises:
        ExecutionError: Ray did not start (with each attempt's reason, from its log).
    """
    reasons: list[str] = []
    for attempt in range(1, attempts + 1):
        home = Path(tempfile.mkdtemp(prefix="ray", dir="/tmp" if os.path.isdir("/tmp") else None))
        try:
            head, port, reason = _start_head(home, num_cpus, timeout)
            if reason is None:
                try:
                    yield f"127.0.0.1:{port}"
                finally:
                    _stop_head(head)
                return
            _stop_head(head)
        finally:
            shutil.rmtree(home, ignore_errors=True)
        reasons.append(reason)
        if attempt < attempts:
            say(
                f"ray start --head: attempt {attempt} of {attempts} failed ({reason}); "
                "starting a fresh head"
            )
    raise ExecutionError(
        f"ray start --head failed {attempts} times: "
        + "; ".join(f"{n}: {reason}" for n, reason in enumerate(reasons, 1))
    )


def _start_head(
    home: Path, num_cpus: int, timeout: float
) -> tuple[subprocess.Popen[bytes], int, str | None]:
    """``ray start --head --block`` in ``home``; the process, the head's port, and why it did
    not start (the last lines of its log) or ``None`` once Ray says it has."""
    import subprocess

    command, port = _head_command(home, num_cpus)
    (home / "cwd").mkdir()
    log = home / "head.log"
    with log.open("wb") as stream:
        head = subprocess.Popen(
            command, cwd=home / "cwd", env=_head_environment(), stdout=stream,
            stderr=subprocess.STDOUT,
        )  # fmt: skip
    try:
        deadline = time.monotonic() + timeout
        while b"Ray runtime started" not in log.read_bytes():
            if head.poll() is not None or time.monotonic() > deadline:
                tail = log.read_text(errors="replace").strip().splitlines()[-3:]
                return head, port, " | ".join(line.strip() for line in tail) or "no output"
            time.sleep(0.2)
    except BaseException:  # a Ctrl-C while waiting: the head is stopped, not left running
        _stop_head(head)
        raise
    return head, port, None


def _head_command(home: Path, num_cpus: int) -> tuple[list[str], int]:
    """``ray start --head`` on free ports of its own, with its temporary folder in ``home``;
    and the head's port."""
    import socket

    executable = Path(sys.executable).with_name("ray")
    if not executable.exists():
        executable = Path(shutil.which("ray") or "ray")
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
    return command, port


def _head_environment() -> dict[str, str]:
    """The head's environment: this ``pokerirl`` importable, no usage stats, no token."""
    environment = {
        **os.environ,
        "PYTHONPATH": _pythonpath(),
        "RAY_DISABLE_USAGE_STATS": "1",
        # Ray would want a token whenever ~/.ray/auth_token exists (any local ray.init leaves
        # one); drivers given an explicit address never send it.
        "RAY_AUTH_MODE": "disabled",
    }
    for name in ("RAY_ADDRESS", "RAY_AUTH_TOKEN", "RAY_AUTH_TOKEN_PATH"):
        environment.pop(name, None)
    return environment


def _stop_head(head: subprocess.Popen[bytes]) -> None:
    """Stop ``ray start --block`` and, by pid, every process it started."""
    import subprocess

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
