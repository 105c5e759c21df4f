"""Units: independent pieces of work whose outputs are saved with a record, and resumed.

A :class:`Unit` names its place (a folder, a file, or a record that holds its result), its
configuration and the digests of its inputs, and the picklable function that computes it.
:func:`run_units` is every fan-out's loop: :func:`check` each unit (reuse a finished one of
the same fingerprint; recompute a half-written or corrupt one; refuse, in one line, one made
with another configuration unless ``overwrite``), run the rest with
:func:`pokerirl.execution.map_units` on a backend, and :func:`save` each as it finishes, so an
interrupted run resumes from what it finished. :func:`writing` is the same save for a unit
computed in this process that writes its files itself (a run streaming its metrics).

Layouts (:class:`Layout`), with the record and the files it vouches for:

* ``folder``: ``target/`` holds the files (subfolders allowed) and ``target/unit.json``;
  swapped in whole. A folder that holds files but no record was not written by a unit: it is
  refused unless ``overwrite``, and even then only when it holds no subfolder.
* ``file``: ``target`` (and any other plain files the unit writes beside it) with the record
  ``<target stem>.unit.json`` beside them; all swapped in as one. A target without its record
  is recomputed: the writers before the store wrote the file first, so that is a write a
  kill interrupted.
* ``record``: ``target`` is the record; the unit's output is its ``result``.

A unit whose own record is missing may be vouched for by a record an older pokerirl kept
elsewhere (:class:`LegacyRecord`: a poker study's ``stages/<stage>.json``, a ``gym rl`` folder's
``rl.job.json``).

>>> import tempfile
>>> root = Path(tempfile.mkdtemp())
>>> def square(n):  # units run elsewhere need a module-level function; here, in process
...     return UnitOutput(result=n * n)
>>> units = [Unit(key=f"square {n}", target=root / f"{n}.json", layout=Layout.RECORD,
...               config={"n": n}, fn=square, args=(n,)) for n in (2, 3)]
>>> [done.unit.key for done in run_units(units).run]
['square 2', 'square 3']
>>> report = run_units(units)
>>> [(done.fate.value, done.record.result) for done in report.done]
[('reused', 4), ('reused', 9)]
"""

from __future__ import annotations

import os
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from enum import StrEnum
from functools import cached_property
from pathlib import Path
from typing import Any, Generic, TypeVar

from pokerirl.errors import Remedy
from pokerirl.execution import Backend, map_units
from pokerirl.store.record import (
    Json,
    UnitConflict,
    UnitRecord,
    describe_changes,
    fingerprint,
    identity_of,
    read_record,
)
from pokerirl.store.staged import RECORD_NAME, RECORD_SUFFIX, staged_files, staged_folder, tidy

E = TypeVar("E")


class Layout(StrEnum):
    """Where a unit's files and record go (see the module's docstring)."""

    FOLDER = "folder"
    FILE = "file"
    RECORD = "record"


class Fate(StrEnum):
    """What became of a unit: ``reused`` (finished already), ``run`` (nothing was there) or
    ``recomputed`` (what was there was replaced: half-written, corrupt, or, with
    ``overwrite``, made with another configuration)."""

    REUSED = "reused"
    RUN = "run"
    RECOMPUTED = "recomputed"


@dataclass(frozen=True, kw_only=True)
class LegacyRecord:
    """A record an older pokerirl kept for this unit elsewhere, and the identity it was made
    with: a finished one of that fingerprint means the unit is finished (when its target
    exists); one of another fingerprint is refused like a conflict."""

    path: Path
    identity: Mapping[str, Any]


@dataclass(frozen=True, kw_only=True)
class UnitOutput(Generic[E]):
    """What a unit's function returns (from any process: it must pickle).

    ``files``: the outputs the record vouches for, by path relative to the unit's folder;
    ``unhashed``: files written beside them and never fingerprinted (wall-clock timings);
    ``result``: JSON kept in the record (``record`` units); ``extra``: handed back to the
    caller in :class:`UnitDone`, never saved.
    """

    files: Mapping[str, bytes] = field(default_factory=dict)
    unhashed: Mapping[str, bytes] = field(default_factory=dict)
    result: Json = None
    extra: E | None = None


@dataclass(frozen=True, kw_only=True)
class Unit(Generic[E]):
    """One unit: its name in messages (``key``), its place, what determines it, and how to
    compute it: ``fn(*args)``, a module-level function returning a :class:`UnitOutput`.

    ``config`` and ``inputs`` (content digests of what it reads, such as
    ``{"table": digest(table_bytes)}``) are JSON; together they are its identity
    (:func:`pokerirl.store.record.identity_of`), and a name may not be in both.
    ``accepts``: whether a finished record's ``result`` is one the caller can use; a record
    of the right fingerprint whose result is not (one no write of this unit leaves) is
    recomputed.
    """

    key: str
    target: Path
    config: Mapping[str, Any]
    inputs: Mapping[str, Any] = field(default_factory=dict)
    layout: Layout = Layout.FOLDER
    fn: Callable[..., UnitOutput[E]] | None = None
    args: tuple[Any, ...] = ()
    legacy: tuple[LegacyRecord, ...] = ()
    accepts: Callable[[Json], bool] | None = None

    @cached_property
    def identity(self) -> dict[str, Json]:
        return identity_of(self.config, self.inputs)

    @cached_property
    def fingerprint(self) -> str:
        return fingerprint(self.identity)

    @property
    def record_path(self) -> Path:
        if self.layout is Layout.FOLDER:
            return self.target / RECORD_NAME
        if self.layout is Layout.FILE:
            return self.target.with_name(self.target.stem + RECORD_SUFFIX)
        return self.target

    @property
    def folder(self) -> Path:
        """The folder the record's file names are relative to."""
        return self.record_path.parent


@dataclass(frozen=True, kw_only=True)
class Check:
    """What :func:`check` found: the fate the unit will have, the record to reuse (for
    ``reused``) and why it is recomputed (for ``recomputed``)."""

    fate: Fate
    record: UnitRecord | None = None
    why: str | None = None


@dataclass(frozen=True, kw_only=True)
class UnitDone(Generic[E]):
    """A unit after :func:`run_units`: its fate, its record, why it was recomputed, and the
    ``extra`` its function returned (None when reused)."""

    unit: Unit[E]
    fate: Fate
    record: UnitRecord
    why: str | None = None
    extra: E | None = None


@dataclass(frozen=True, kw_only=True)
class Group(Generic[E]):
    """How :func:`run_units` computes several units in one call: the units to run with the
    same ``key(unit)`` are one group, computed by ``fn(*args(members))``, which returns one
    output per member, in order; each member is then saved with its own record, as alone.
    ``fn`` is a module-level function (it runs on the backend); ``label`` names a group in
    messages."""

    key: Callable[[Unit[E]], Any]
    fn: Callable[..., Sequence[UnitOutput[E]]]
    args: Callable[[Sequence[Unit[E]]], tuple[Any, ...]]
    label: Callable[[Sequence[Unit[E]]], str]


@dataclass(frozen=True)
class UnitsReport(Generic[E]):
    """Every unit of a :func:`run_units` call, in the order given."""

    done: tuple[UnitDone[E], ...]

    def with_fate(self, fate: Fate) -> tuple[UnitDone[E], ...]:
        return tuple(d for d in self.done if d.fate is fate)

    @property
    def reused(self) -> tuple[UnitDone[E], ...]:
        return self.with_fate(Fate.REUSED)

    @property
    def run(self) -> tuple[UnitDone[E], ...]:
        return self.with_fate(Fate.RUN)

    @property
    def recomputed(self) -> tuple[UnitDone[E], ...]:
        return self.with_fate(Fate.RECOMPUTED)


# --------------------------------------------------------------------------- checking


def check(unit: Unit[Any], *, overwrite: bool = False) -> Check:
    """Whether ``unit`` is finished, to run, or to recompute; finishes or clears what a
    killed writer left at its place first.

    Raises:
        UnitConflict: (unless ``overwrite``) it was made with another configuration, by a
            newer pokerirl, or its folder holds files that no unit wrote; or (always) its
            place is of the wrong kind, or a folder with subfolders that no unit wrote.
    """
    target = unit.target
    tidy(target.parent, key=target.name)
    _check_kind(unit)
    try:
        record = read_record(unit.record_path)
    except UnitConflict as error:  # a newer pokerirl's
        if overwrite:
            return Check(fate=Fate.RECOMPUTED, why=str(error))
        raise
    if record is not None:
        found = _judge(unit, record, unit.fingerprint, unit.identity, str(target), overwrite)
        if found.fate is Fate.REUSED and unit.accepts and not unit.accepts(record.result):
            return Check(fate=Fate.RECOMPUTED, why="its result is not one this unit writes")
        return found
    for legacy in unit.legacy:
        old = read_record(legacy.path)
        if old is not None:
            wanted = fingerprint(identity_of(legacy.identity, {}))
            found = _judge(unit, old, wanted, legacy.identity, str(legacy.path), overwrite)
            if found.fate is not Fate.REUSED or os.path.lexists(target):
                return found
            break  # finished, but its outputs are gone: computed again
    return _without_record(unit, overwrite)


def _check_kind(unit: Unit[Any]) -> None:
    target = unit.target
    if unit.layout is Layout.FOLDER:
        if os.path.lexists(target) and not target.is_dir():
            raise UnitConflict(f"{target} exists and is not a folder", remedy=Remedy.ELSEWHERE)
    elif target.is_dir():
        raise UnitConflict(f"{target} is a folder, not a file", remedy=Remedy.ELSEWHERE)


def _judge(
    unit: Unit[Any],
    record: UnitRecord,
    wanted: str,
    identity: Mapping[str, Any],
    what: str,
    overwrite: bool,
) -> Check:
    if record.finished:
        problem = record.missing_or_changed(unit.folder)
        if problem is not None:  # whatever its configuration: nothing finished to keep
            return Check(fate=Fate.RECOMPUTED, why=f"half-written or corrupt: {problem}")
        if record.fingerprint == wanted:
            return Check(fate=Fate.REUSED, record=record)
    elif record.fingerprint == wanted:  # a stage an older study started: resumed
        return Check(fate=_replacing(unit), why="left unfinished by an earlier run")
    changes = describe_changes(record.identity, identity_of(identity, {}))
    if overwrite:
        return Check(fate=Fate.RECOMPUTED, why=f"made with another configuration ({changes})")
    raise UnitConflict(
        f"{what} was made with another configuration ({changes})", remedy=Remedy.RECOMPUTE
    )


def _replacing(unit: Unit[Any]) -> Fate:
    return Fate.RECOMPUTED if _holds_something(unit.target) else Fate.RUN


def _holds_something(target: Path) -> bool:
    if target.is_dir() and not target.is_symlink():
        return any(target.iterdir())
    return os.path.lexists(target)


def _without_record(unit: Unit[Any], overwrite: bool) -> Check:
    target = unit.target
    if not _holds_something(target):
        return Check(fate=Fate.RUN)
    if unit.layout is not Layout.FOLDER:
        # A file without its record (or an unreadable record): a write a kill interrupted.
        return Check(fate=Fate.RECOMPUTED, why=f"{unit.record_path.name} is missing or unreadable")
    if (target / RECORD_NAME).exists():  # an unreadable record: a unit wrote this folder
        return Check(fate=Fate.RECOMPUTED, why=f"{RECORD_NAME} is unreadable")
    subfolders = any(child.is_dir() for child in target.iterdir())
    if overwrite and not subfolders:
        return Check(fate=Fate.RECOMPUTED, why=f"it held files but no {RECORD_NAME}")
    never = "; it has subfolders, so it is never replaced" if overwrite else ""
    raise UnitConflict(
        f"{target} already holds files but no {RECORD_NAME} (not written by this pokerirl){never}",
        remedy=Remedy.ELSEWHERE if overwrite else Remedy.REPLACE,
    )


# --------------------------------------------------------------------------- saving


def save(unit: Unit[Any], output: UnitOutput[Any]) -> UnitRecord:
    """Write ``output`` at the unit's place with its record, staged: a kill leaves the old
    unit or the new one. Returns the record written."""
    _check_output(unit, output)
    record = UnitRecord.make(
        unit.config, inputs=unit.inputs, files=output.files, result=output.result
    )
    with _staging(unit) as new:
        if unit.layout is Layout.RECORD:
            (new / unit.target.name).write_text(record.to_text(), encoding="utf-8")
        else:
            for name, data in {**output.files, **output.unhashed}.items():
                path = new / name
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_bytes(data)
            (new / unit.record_path.name).write_text(record.to_text(), encoding="utf-8")
    return record


@contextmanager
def writing(unit: Unit[Any], *, unhashed: Collection[str] = ()) -> Iterator[Path]:
    """Yield the new folder where a unit computed in this process writes its files (the
    unit's folder, or the folder of a ``file`` unit's files); on success every file in it is
    recorded, except those whose name is in ``unhashed``, and it is swapped in.
    ``record`` units have no files: use :func:`save`."""
    if unit.layout is Layout.RECORD:
        raise ValueError("a record unit has no files to write: save its result with save()")
    with _staging(unit) as new:
        yield new
        files = {
            path.relative_to(new).as_posix(): path.read_bytes()
            for path in sorted(new.rglob("*"))
            if path.is_file() and path.name not in unhashed
        }
        _check_output(unit, UnitOutput(files=files))
        record = UnitRecord.make(unit.config, inputs=unit.inputs, files=files)
        (new / unit.record_path.name).write_text(record.to_text(), encoding="utf-8")


@contextmanager
def _staging(unit: Unit[Any]) -> Iterator[Path]:
    if unit.layout is Layout.FOLDER:
        with staged_folder(unit.target) as folder:
            yield folder
    else:
        with staged_files(unit.target.parent, key=unit.target.name) as new:
            yield new


def _check_output(unit: Unit[Any], output: UnitOutput[Any]) -> None:
    names = [*output.files, *output.unhashed]
    record = unit.record_path.name
    if unit.layout is Layout.RECORD:
        if names:
            raise ValueError(f"{unit.key}: a record unit writes no files, got {names[0]!r}")
        return
    for name in names:
        parts = Path(name).parts
        if not parts or Path(name).is_absolute() or ".." in parts or name == record:
            raise ValueError(f"{unit.key}: cannot write a file named {name!r}")
        if unit.layout is Layout.FILE and len(parts) > 1:
            raise ValueError(f"{unit.key}: a file unit writes plain files, got {name!r}")
    if unit.layout is Layout.FILE and unit.target.name not in output.files:
        raise ValueError(f"{unit.key}: the unit did not write {unit.target.name}")


# --------------------------------------------------------------------------- running


def run_units(
    units: Sequence[Unit[E]],
    backend: Backend | None = None,
    *,
    overwrite: bool = False,
    progress: bool = False,
    desc: str = "units",
    on_saved: Callable[[UnitDone[E]], None] | None = None,
    group: Group[E] | None = None,
) -> UnitsReport[E]:
    """Check every unit, run those not finished on ``backend`` (default: in this process)
    and save each as it finishes; return what became of each, in the order given.

    Every refusal comes before anything runs. A unit that raises stops the run with its
    exception (see :func:`pokerirl.execution.map_units`); the units saved before are kept,
    so a rerun resumes. ``on_saved`` is called in this process after each save. With
    ``group``, the units to run are computed in groups (:class:`Group`), one call each, and
    saved each on its own (so resuming is as without it: a group holds the unfinished only).

    Raises:
        UnitConflict: see :func:`check`.
        ValueError: two units share a place, or a unit to run has no function.
    """
    places = [unit.record_path for unit in units]
    if len(set(places)) < len(places):
        twice = next(p for p in places if places.count(p) > 1)
        raise ValueError(f"two units would write {twice}")
    checks = [check(unit, overwrite=overwrite) for unit in units]
    done: list[UnitDone[E] | None] = [
        UnitDone(unit=unit, fate=found.fate, record=found.record)
        if found.fate is Fate.REUSED and found.record is not None
        else None
        for unit, found in zip(units, checks, strict=True)
    ]
    todo = [i for i, item in enumerate(done) if item is None]

    def finished_unit(i: int, output: UnitOutput[E]) -> None:
        unit = units[i]
        record = save(unit, output)
        item = UnitDone(
            unit=unit, fate=checks[i].fate, record=record, why=checks[i].why, extra=output.extra
        )
        done[i] = item
        if on_saved is not None:
            on_saved(item)

    if group is not None:
        _run_groups(units, todo, group, finished_unit, backend=backend, progress=progress,
                    desc=desc)  # fmt: skip
        return UnitsReport(done=tuple(item for item in done if item is not None))
    functions: list[Callable[..., UnitOutput[E]]] = []
    for i in todo:
        function = units[i].fn
        if function is None:
            raise ValueError(f"{units[i].key}: not finished, and the unit has no function")
        functions.append(function)

    def finished(index: int, output: UnitOutput[E]) -> None:
        finished_unit(todo[index], output)

    fn: Callable[..., UnitOutput[E]] = call
    arguments: list[tuple[Any, ...]] = [
        (f, units[i].args) for f, i in zip(functions, todo, strict=True)
    ]
    if functions and all(f is functions[0] for f in functions):
        # One function (the usual case): the fork server preloads its module.
        fn, arguments = functions[0], [units[i].args for i in todo]
    map_units(
        fn,
        arguments,
        backend=backend or Backend(),
        progress=progress,
        desc=desc,
        reused=len(units) - len(todo),
        on_result=finished,
        labels=[units[i].key for i in todo],
    )
    return UnitsReport(done=tuple(item for item in done if item is not None))


def _run_groups(
    units: Sequence[Unit[E]],
    todo: Sequence[int],
    group: Group[E],
    finished: Callable[[int, UnitOutput[E]], None],
    *,
    backend: Backend | None,
    progress: bool,
    desc: str,
) -> None:
    """The units ``todo`` (indices) in groups, one :func:`map_units` unit per group."""
    members: dict[Any, list[int]] = {}
    for i in todo:
        members.setdefault(group.key(units[i]), []).append(i)
    groups = list(members.values())

    def saved(index: int, outputs: Sequence[UnitOutput[E]]) -> None:
        for i, output in zip(groups[index], outputs, strict=True):
            finished(i, output)

    map_units(
        group.fn,
        [group.args([units[i] for i in g]) for g in groups],
        backend=backend or Backend(),
        progress=progress,
        desc=desc,
        reused=len(units) - len(todo),
        on_result=saved,
        labels=[group.label([units[i] for i in g]) for g in groups],
    )


def call(fn: Callable[..., UnitOutput[E]], args: tuple[Any, ...]) -> UnitOutput[E]:
    """``fn(*args)``: how units of different functions share one :func:`map_units` call."""
    return fn(*args)
