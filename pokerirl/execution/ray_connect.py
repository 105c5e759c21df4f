"""Connecting to a Ray cluster: the session ``map_units`` runs in (``_ray_session``), the
probe that fails in one line where no Ray head answers (:func:`check_reachable`), the private
instance's own token (``_private_token``), and loopback addresses used as given."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from typing import Any

from pokerirl.execution.backend import LOCAL_RAY, Backend, ExecutionError, _first_line
from pokerirl.execution.ray_private import _private_ray_folder
from pokerirl.execution.scratch import sweep_leftovers

LOCAL_ATTEMPTS = 3  # starts of a private instance (--ray local) before giving up


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
            if connect_here and backend.address == LOCAL_RAY:
                stack.enter_context(_private_ray(ray))
            elif connect_here:
                _ray_init(ray, backend.address or LOCAL_RAY, None)
                stack.callback(ray.shutdown)
            yield ray
    finally:
        sweep_leftovers()  # the scratch folders of Ray workers killed on this machine


@contextlib.contextmanager
def _private_ray(ray: Any, attempts: int = LOCAL_ATTEMPTS) -> Iterator[None]:
    """``ray`` connected to a private instance of its own (``--ray local``). One that fails to
    start (Ray gives its raylet a fixed 30 s to register, which a loaded machine can exceed)
    is shut down and started afresh in a new folder, up to ``attempts`` times in all, as
    :func:`~pokerirl.execution.ray_private.ray_head` does.

    Raises:
        ExecutionError: no attempt started (each one's reason in the line).
    """
    reasons: list[str] = []
    for _ in range(attempts):
        with contextlib.ExitStack() as stack:
            private = stack.enter_context(_private_ray_folder())
            stack.enter_context(_private_token(ray))
            try:
                _ray_init(ray, LOCAL_RAY, private)
            except ExecutionError as error:
                ray.shutdown()  # what a failed start left, before its folder goes
                reasons.append(str(error).removeprefix(f"cannot connect to Ray at {LOCAL_RAY}: "))
                continue
            stack.callback(ray.shutdown)
            yield
            return
    raise ExecutionError(
        f"cannot start a private Ray ({LOCAL_RAY}) in {attempts} attempts: "
        + "; ".join(f"{n}: {reason}" for n, reason in enumerate(reasons, 1))
    )


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
    except Exception as error:  # Ray's own startup timeout is a bare Exception
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
