"""run_units on real local backends: finished units are reused, a run stopped by a failing
unit (or a killed driver) resumes from the units it saved, changed settings are refused in
one line, corrupt units are recomputed, and every layout is written with its record."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pokerirl.execution import Backend
from pokerirl.store import (
    Fate,
    Group,
    Layout,
    Unit,
    UnitConflict,
    UnitOutput,
    UnitRecord,
    check,
    read_record,
    run_units,
    save,
    writing,
)

TWO_JOBS = Backend(jobs=2)


def square(n: int, seconds: float = 0.0, fail_if: str | None = None) -> UnitOutput[int]:
    """A unit: ``n * n`` in a file, after ``seconds``; raises when the file ``fail_if``
    exists (how a test stops a run midway)."""
    time.sleep(seconds)
    if fail_if is not None and Path(fail_if).exists():
        raise RuntimeError(f"unit {n} failed on purpose")
    return UnitOutput(
        files={"square.txt": f"{n * n}\n".encode()},
        unhashed={"timings.json": json.dumps({"pid": os.getpid()}).encode()},
        extra=n * n,
    )


def cube(n: int) -> UnitOutput[int]:
    return UnitOutput(files={"square.txt": f"{n**3}\n".encode()}, extra=n**3)


def squares(ns: list[int]) -> list[UnitOutput[int]]:
    """A group's function: every member's output in one call (the members in its timings)."""
    timings = json.dumps({"members": ns}).encode()
    return [UnitOutput(files=square(n).files, unhashed={"timings.json": timings}) for n in ns]


def units(root: Path, count: int = 6, *, power: int = 2, **options: object) -> list[Unit[int]]:
    def args(n: int) -> tuple[object, ...]:
        seconds = options.get("slow", {}).get(n, 0.0)  # type: ignore[attr-defined]
        return (n, seconds, options.get("fail_if") if n == options.get("failing") else None)

    return [
        Unit(
            key=f"n-{n}",
            target=root / f"n-{n}",
            config={"n": n, "power": power},
            inputs={"data": "sha256:0"},
            fn=square,
            args=args(n),
        )
        for n in range(count)
    ]


def contents(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.glob("*/square.txt"))}


def test_a_run_stopped_by_a_failing_unit_resumes_and_reuses_what_it_saved(
    tmp_path: Path,
) -> None:
    stop = tmp_path / "stop"
    stop.touch()
    root = tmp_path / "units"
    # Unit 3 fails after a while; the other worker finishes quick units meanwhile.
    first = units(root, failing=3, fail_if=str(stop), slow={3: 1.0})
    saved: list[str] = []
    with pytest.raises(RuntimeError, match="unit 3 failed on purpose"):
        run_units(first, TWO_JOBS, on_saved=lambda done: saved.append(done.unit.key))
    finished = sorted(p.parent.name for p in root.glob("*/unit.json"))
    assert finished == sorted(saved) and 1 <= len(finished) < 6 and "n-3" not in finished

    stop.unlink()
    report = run_units(units(root, failing=3, fail_if=str(stop)), TWO_JOBS)
    assert sorted(d.unit.key for d in report.reused) == finished
    assert sorted(d.unit.key for d in report.run) == sorted(
        {f"n-{n}" for n in range(6)} - set(finished)
    )
    assert [d.unit.key for d in report.done] == [f"n-{n}" for n in range(6)]  # unit order
    assert all(d.extra == int(d.unit.key[2:]) ** 2 for d in report.run)
    assert all(d.extra is None for d in report.reused)
    assert contents(root) == {f"n-{n}/square.txt": f"{n * n}\n".encode() for n in range(6)}
    again = run_units(units(root), TWO_JOBS)
    assert len(again.reused) == 6 and not again.run and not again.recomputed


def test_a_killed_driver_leaves_finished_units_that_a_rerun_reuses(tmp_path: Path) -> None:
    root = tmp_path / "units"
    script = f"""
import sys
sys.path[:0] = {[str(Path(__file__).parent), *sys.path]!r}
from pathlib import Path
from test_store_units import TWO_JOBS, units
from pokerirl.store import run_units
run_units(units(Path({str(root)!r}), slow={{n: 0.3 + n * 0.3 for n in range(6)}}), TWO_JOBS)
"""
    driver = subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while not list(root.glob("*/unit.json")):
        assert driver.poll() is None, driver.stderr.read() if driver.stderr else ""
        assert time.monotonic() < deadline
        time.sleep(0.02)
    driver.send_signal(signal.SIGKILL)
    driver.wait()
    finished = {p.parent.name: p.read_bytes() for p in root.glob("*/unit.json")}
    assert 1 <= len(finished) < 6
    report = run_units(units(root), TWO_JOBS)
    assert {d.unit.key for d in report.reused} == set(finished)
    assert {name: (root / name / "unit.json").read_bytes() for name in finished} == finished
    assert contents(root) == {f"n-{n}/square.txt": f"{n * n}\n".encode() for n in range(6)}
    assert sorted(p.name for p in root.iterdir()) == [f"n-{n}" for n in range(6)]  # tidy


def test_other_settings_are_refused_before_anything_runs_unless_overwrite(
    tmp_path: Path,
) -> None:
    root = tmp_path / "units"
    run_units(units(root, 2))
    changed = units(root, 3, power=3)
    with pytest.raises(UnitConflict) as refused:
        run_units(changed)
    line = f"{root / 'n-0'} was made with another configuration (power 2 -> 3)"
    assert str(refused.value) == line
    assert not (root / "n-2").exists()  # refused before any unit ran
    cubes = [
        Unit(key=u.key, target=u.target, config=u.config, inputs=u.inputs, fn=cube, args=(i,))
        for i, u in enumerate(changed)
    ]
    report = run_units(cubes, overwrite=True)
    assert [d.fate for d in report.done] == [Fate.RECOMPUTED, Fate.RECOMPUTED, Fate.RUN]
    assert "power 2 -> 3" in (report.done[0].why or "")
    assert (root / "n-2" / "square.txt").read_bytes() == b"8\n"


def test_a_corrupt_unit_is_recomputed_to_the_same_bytes(tmp_path: Path) -> None:
    root = tmp_path / "units"
    run_units(units(root, 3))
    record = (root / "n-1" / "unit.json").read_bytes()
    (root / "n-1" / "square.txt").write_bytes(b"garbage")
    report = run_units(units(root, 3))
    assert [d.fate for d in report.done] == [Fate.REUSED, Fate.RECOMPUTED, Fate.REUSED]
    assert report.done[1].why == "half-written or corrupt: square.txt has other bytes"
    assert (root / "n-1" / "square.txt").read_bytes() == b"1\n"
    assert (root / "n-1" / "unit.json").read_bytes() == record  # same inputs, same bytes


def test_the_record_vouches_for_the_files_but_not_the_timings(tmp_path: Path) -> None:
    root = tmp_path / "units"
    run_units(units(root, 1))
    record = read_record(root / "n-0" / "unit.json")
    assert record is not None and sorted(record.files) == ["square.txt"]
    assert record.config == {"n": 0, "power": 2} and record.inputs == {"data": "sha256:0"}
    (root / "n-0" / "timings.json").write_text("{}")  # wall-clock: never makes it corrupt
    assert check(units(root, 1)[0]).fate is Fate.REUSED


def test_units_of_different_functions_run_together(tmp_path: Path) -> None:
    root = tmp_path / "units"
    mixed = [
        Unit(key="a", target=root / "a", config={"k": "a"}, fn=square, args=(3,)),
        Unit(key="b", target=root / "b", config={"k": "b"}, fn=cube, args=(3,)),
    ]
    report = run_units(mixed, TWO_JOBS)
    assert [d.extra for d in report.done] == [9, 27]


def test_file_and_record_units_and_in_process_writers(tmp_path: Path) -> None:
    data = Unit(
        key="data", target=tmp_path / "env" / "expert.parquet", layout=Layout.FILE,
        config={"unit": "gym-data"},
    )  # fmt: skip
    save(data, UnitOutput(files={"expert.parquet": b"rows"}))
    assert sorted(p.name for p in data.target.parent.iterdir()) == [
        "expert.parquet",
        "expert.unit.json",
    ]
    assert check(data).fate is Fate.REUSED
    with pytest.raises(ValueError, match=r"did not write expert\.parquet"):
        save(data, UnitOutput(files={"other.parquet": b"rows"}))

    seed = Unit(key="seed 0", target=tmp_path / "seeds" / "seed-0.json", layout=Layout.RECORD,
                config={"seed": 0})  # fmt: skip
    record = save(seed, UnitOutput(result={"estimate": 1.5}))
    assert UnitRecord.from_json(json.loads(seed.target.read_text())) == record
    assert check(seed).record == record

    run = Unit(key="run", target=tmp_path / "run", config={"epochs": 2})
    with writing(run, unhashed={"timings.json"}) as folder:
        (folder / "metrics.jsonl").write_text('{"epoch": 1}\n')
        (folder / "timings.json").write_text("{}")
        assert not run.target.exists()  # nothing visible until it is finished
    found = check(run)
    assert found.fate is Fate.REUSED and found.record is not None
    assert sorted(found.record.files) == ["metrics.jsonl"]


def test_a_folder_that_no_unit_wrote_is_never_replaced_silently(tmp_path: Path) -> None:
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "notes.txt").write_text("mine")
    unit = Unit(key="x", target=theirs, config={"k": 1})
    with pytest.raises(UnitConflict, match=r"holds files but no unit.json \(not written by"):
        check(unit)
    assert check(unit, overwrite=True).fate is Fate.RECOMPUTED
    (theirs / "sub").mkdir()
    with pytest.raises(UnitConflict, match=r"it has subfolders, so it is never replaced$"):
        check(unit, overwrite=True)
    (tmp_path / "file").write_text("")
    with pytest.raises(UnitConflict, match="exists and is not a folder"):
        check(Unit(key="y", target=tmp_path / "file", config={}))


def test_two_units_of_one_place_are_refused(tmp_path: Path) -> None:
    same = [Unit(key=k, target=tmp_path / "a", config={}, fn=cube, args=(1,)) for k in "xy"]
    with pytest.raises(ValueError, match="two units would write"):
        run_units(same)


def test_a_group_computes_several_units_in_one_call_and_each_resumes_alone(
    tmp_path: Path,
) -> None:
    # Units grouped by parity: one call per group (its members named in each timings), each
    # member saved with its own record; a rerun reuses them, and a missing one is recomputed
    # in a group of one.
    by_parity = Group(
        key=lambda unit: unit.config["n"] % 2,
        fn=squares,
        args=lambda members: ([unit.args[0] for unit in members],),
        label=lambda members: f"{len(members)} squares",
    )
    work = units(tmp_path, 5)
    report = run_units(work, TWO_JOBS, group=by_parity)
    assert [done.fate for done in report.done] == [Fate.RUN] * 5
    assert contents(tmp_path) == {f"n-{n}/square.txt": f"{n * n}\n".encode() for n in range(5)}
    def members(n: int) -> list[int]:
        return json.loads((tmp_path / f"n-{n}" / "timings.json").read_text())["members"]

    assert [members(n) for n in range(5)] == [[0, 2, 4], [1, 3], [0, 2, 4], [1, 3], [0, 2, 4]]
    assert all(check(unit).fate is Fate.REUSED for unit in work)  # each its own record

    (tmp_path / "n-3" / "square.txt").unlink()
    again = run_units(work, TWO_JOBS, group=by_parity)
    assert [done.fate for done in again.done] == [Fate.REUSED] * 3 + [Fate.RECOMPUTED] + [
        Fate.REUSED]
    assert (tmp_path / "n-3" / "square.txt").read_bytes() == b"9\n" and members(3) == [3]
