"""Where a fan-out command's units run: its ``--jobs``, ``--ray`` and ``--threads`` made into an
execution backend (:func:`command_backend`), and the ``--ray`` help every such command shows
(:data:`RAY_HELP`). The units and their backends are :mod:`pokerirl.execution`'s.
"""

from __future__ import annotations

from pokerirl import execution  # light: tqdm only; ray loads when chosen
from pokerirl.errors import UsageError

RAY_HELP = (
    "Run the units on the Ray cluster at ADDRESS (default: $RAY_ADDRESS when set), or 'local' "
    "for a private single-machine Ray. Results do not change."
)


def command_backend(jobs: int, ray: str | None, threads: int = 1) -> execution.Backend:
    """The execution backend of a fan-out command from its ``--jobs``, ``--ray`` and
    ``--threads``: a Ray cluster (``--ray``, else ``$RAY_ADDRESS``), else ``jobs`` local
    processes of ``threads`` threads each (:func:`pokerirl.execution.choose_backend`).

    An empty ``--ray`` is a :class:`~pokerirl.errors.UsageError`; a cluster that cannot be
    reached fails here, before any work.
    """
    if ray is not None and not ray.strip():
        raise UsageError("--ray needs an address (HOST:PORT) or 'local'")
    backend = execution.choose_backend(jobs=jobs, ray=ray, threads=threads)
    if backend.kind == "ray" and backend.address != execution.LOCAL_RAY:
        # Before any work: a study would otherwise build its data first, then fail.
        execution.check_reachable(backend.address or "")
    return backend
