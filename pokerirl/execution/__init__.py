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

**Modules**, each saying what it owns; this one re-exports their public names: ``backend``
(:class:`Backend`, :func:`choose_backend`, :class:`ExecutionError`), ``mapping``
(:func:`map_units`), ``threads`` (thread pinning), ``progress`` (a unit's progress and the
bar), ``local`` (the fork server's workers), ``ray_connect`` (the session, the probe, the
token), ``ray_private`` (the private instance's reaper, :func:`ray_head`), ``ray_tasks``
(units as Ray tasks), ``scratch`` (scratch folders), ``processes`` (``/proc``), ``files``
(inputs and outputs as bytes). They import each other, never this package.

>>> map_units(pow, [(2, 3), (3, 2)], backend=Backend())
[8, 9]
"""

from __future__ import annotations

from pokerirl.execution.backend import LOCAL_RAY, RETRIES, Backend, ExecutionError, choose_backend
from pokerirl.execution.files import folder_files, read_files, write_files
from pokerirl.execution.mapping import map_units
from pokerirl.execution.progress import REPORT_EVERY, progress_share, unit_progress, watched
from pokerirl.execution.ray_connect import PROBE_SECONDS, check_reachable
from pokerirl.execution.ray_private import ray_head
from pokerirl.execution.ray_tasks import run_unit_in_scratch
from pokerirl.execution.scratch import PRIVATE_RAY_PREFIX, SCRATCH_PREFIX, sweep_leftovers
from pokerirl.execution.threads import pin_threads, pinned_threads, run_unit

__all__ = [
    "LOCAL_RAY",
    "PRIVATE_RAY_PREFIX",
    "PROBE_SECONDS",
    "REPORT_EVERY",
    "RETRIES",
    "SCRATCH_PREFIX",
    "Backend",
    "ExecutionError",
    "check_reachable",
    "choose_backend",
    "folder_files",
    "map_units",
    "pin_threads",
    "pinned_threads",
    "progress_share",
    "ray_head",
    "read_files",
    "run_unit",
    "run_unit_in_scratch",
    "sweep_leftovers",
    "unit_progress",
    "watched",
    "write_files",
]
