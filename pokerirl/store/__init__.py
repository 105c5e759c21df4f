"""The one owner of saving and resuming: staged writes, unit records, and the units loop.

* :mod:`~pokerirl.store.staged`: write beside, swap in as one, tidy what dead writers left
  (:func:`staged_folder`, :func:`staged_files`, :func:`tidy`);
* :mod:`~pokerirl.store.record`: :class:`UnitRecord` (fingerprint, configuration, inputs'
  and files' sha256), reading today's format and the two before it;
* :mod:`~pokerirl.store.units`: :class:`Unit`, :func:`check`, :func:`save`,
  :func:`writing` and :func:`run_units` (find the finished units, run the rest on an
  execution backend, save each as it finishes).

The store sits above :mod:`pokerirl.execution` (it runs units with ``map_units``) and below
everything that writes results (datasets, irl, agents, gym, tournaments, the studies).
"""

from __future__ import annotations

from pokerirl.store.record import (
    RECORD_FORMAT,
    Json,
    StoreError,
    UnitConflict,
    UnitRecord,
    describe_changes,
    digest,
    fingerprint,
    read_record,
)
from pokerirl.store.staged import RECORD_NAME, RECORD_SUFFIX, staged_files, staged_folder, tidy
from pokerirl.store.units import (
    Check,
    Fate,
    Group,
    Layout,
    LegacyRecord,
    Unit,
    UnitDone,
    UnitOutput,
    UnitsReport,
    check,
    run_units,
    save,
    writing,
)

__all__ = [
    "RECORD_FORMAT",
    "RECORD_NAME",
    "RECORD_SUFFIX",
    "Check",
    "Fate",
    "Group",
    "Json",
    "Layout",
    "LegacyRecord",
    "StoreError",
    "Unit",
    "UnitConflict",
    "UnitDone",
    "UnitOutput",
    "UnitRecord",
    "UnitsReport",
    "check",
    "describe_changes",
    "digest",
    "fingerprint",
    "read_record",
    "run_units",
    "save",
    "staged_files",
    "staged_folder",
    "tidy",
    "writing",
]
