"""pokerirl.execution on local processes: order, thread pinning, private working folders,
retries when a worker dies, errors, and the unit records that decide reuse, recompute or
refuse. (The real Ray cluster is in test_execution_ray.py, killed drivers in
test_execution_kill.py.)"""

from __future__ import annotations

import json
import os
import pickle
import signal
from pathlib import Path

import pytest

from pokerirl.execution import (
    RECORD_FILE,
    Backend,
    ExecutionError,
    UnitConflict,
    choose_backend,
    load_unit,
    load_unit_folder,
    make_record,
    map_units,
    save_record,
    save_unit_folder,
    tidy_folder,
)

TWO = Backend(jobs=2)


# Units must be module-level functions: spawned workers import them by name.
def describe(k: int) -> tuple[int, int, str, int]:
    import torch

    return k * k, torch.get_num_threads(), os.getcwd(), os.getpid()


def die_once(k: int, marks: str) -> int:
    """Kill its own worker the first time unit k runs (a real SIGKILL), then succeed."""
    mark = Path(marks) / f"unit-{k}"
    if k == 1 and not mark.exists():
        mark.write_text("died")
        os.kill(os.getpid(), signal.SIGKILL)
    return 10 * k


def always_die(marks: str) -> None:
    Path(marks, f"attempt-{os.getpid()}").write_text("")
    os.kill(os.getpid(), signal.SIGKILL)


def fail_on_two(k: int) -> int:
    if k == 2:
        raise ValueError(f"unit {k} has bad input")
    return k


def read_relative(name: str) -> bool:
    return Path(name).exists()


def test_results_in_unit_order_whatever_the_jobs_and_threads_pinned() -> None:
    import torch

    units = [(k,) for k in range(5)]
    before = torch.get_num_threads()
    torch.set_num_threads(2)  # the driver's own setting: units must not inherit it
    try:
        one = map_units(describe, units, backend=Backend())
        assert torch.get_num_threads() == 2  # and it is given back
    finally:
        torch.set_num_threads(before)
    two = map_units(describe, units, backend=TWO)
    assert [r[0] for r in one] == [r[0] for r in two] == [0, 1, 4, 9, 16]
    assert {r[1] for r in one} == {r[1] for r in two} == {1}  # one torch thread per unit
    assert {r[3] for r in one} == {os.getpid()}  # one job: in this process
    assert len({r[3] for r in two}) == 2 and os.getpid() not in {r[3] for r in two}
    threads = map_units(describe, units, backend=Backend(jobs=2, threads=2))
    assert {r[1] for r in threads} == {2}


def test_workers_run_in_a_private_folder_not_the_drivers(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    Path("here.txt").write_text("driver's file")
    results = map_units(describe, [(0,), (1,)], backend=TWO)
    assert {Path(r[2]).resolve() for r in results}.isdisjoint({tmp_path.resolve()})
    assert map_units(read_relative, [("here.txt",), ("here.txt",)], backend=TWO) == [False] * 2
    assert map_units(read_relative, [("here.txt",)], backend=TWO) == [True]  # in-process


def test_a_unit_whose_worker_dies_is_retried(tmp_path: Path) -> None:
    seen: list[int] = []
    results = map_units(
        die_once,
        [(k, str(tmp_path)) for k in range(4)],
        backend=TWO,
        on_result=lambda i, r: seen.append(i),
    )
    assert results == [0, 10, 20, 30] and sorted(seen) == [0, 1, 2, 3]
    assert (tmp_path / "unit-1").read_text() == "died"


def test_a_worker_that_keeps_dying_stops_the_run_after_the_retries(tmp_path: Path) -> None:
    with pytest.raises(ExecutionError, match=r"^seed-[12]: its worker died 2 times.*giving up"):
        map_units(
            always_die,
            [(str(tmp_path),)] * 2,
            backend=Backend(jobs=2, retries=1),
            labels=["seed-1", "seed-2"],
        )
    assert len(list(tmp_path.glob("attempt-*"))) >= 2


def test_a_unit_error_is_raised_as_is_and_finished_units_were_handed_over() -> None:
    seen: dict[int, int] = {}
    for backend in (Backend(), TWO):
        seen.clear()
        with pytest.raises(ValueError, match="unit 2 has bad input"):
            map_units(
                fail_on_two,
                [(k,) for k in range(3)],
                backend=backend,
                on_result=seen.__setitem__,
            )
        # Unit 2 starts only once unit 0 or 1 finished, and that one was handed over.
        assert seen and all(seen[k] == k for k in seen) and 2 not in seen


def test_choose_backend() -> None:
    assert choose_backend(jobs=3, environ={}) == Backend(jobs=3)
    assert choose_backend(ray="local", environ={"RAY_ADDRESS": "a:1"}).address == "local"
    assert choose_backend(environ={"RAY_ADDRESS": "h:6379"}) == Backend(
        kind="ray", address="h:6379"
    )
    with pytest.raises(ValueError, match="needs an address"):
        choose_backend(ray=" ", environ={})
    with pytest.raises(ValueError, match="jobs must be at least 1"):
        choose_backend(jobs=0, environ={})


CONFIG = {"seed": 1, "nested": {"width": [64, 64]}}


def test_folder_units_reuse_recompute_or_refuse(tmp_path: Path) -> None:
    unit = tmp_path / "seed-1"
    assert load_unit_folder(unit, CONFIG) is None  # missing: compute
    save_unit_folder(unit, {"model.pt": b"weights"}, CONFIG, unhashed={"timings.json": b"{}"})
    record = load_unit_folder(unit, CONFIG)
    assert record is not None and list(record["files"]) == ["model.pt"]
    assert sorted(p.name for p in unit.iterdir()) == ["model.pt", "timings.json", RECORD_FILE]
    (unit / "timings.json").write_text("other timings")  # not covered: still finished
    assert load_unit_folder(unit, CONFIG) is not None
    other = {"seed": 1, "nested": {"width": (64, 32)}}
    with pytest.raises(
        UnitConflict, match=r"seed-1 was made .*nested.width \[64, 64\] -> \[64, 32\]"
    ):
        load_unit_folder(unit, other)
    assert load_unit_folder(unit, other, overwrite=True) is None
    (unit / "model.pt").write_bytes(b"weighTs")  # corrupt: recompute, never refuse
    assert load_unit_folder(unit, other) is None
    (unit / "model.pt").unlink()  # half-written
    assert load_unit_folder(unit, CONFIG) is None
    (unit / RECORD_FILE).write_text("[]")
    assert load_unit_folder(unit, CONFIG) is None


def test_a_folder_without_a_record_is_never_replaced_silently(tmp_path: Path) -> None:
    theirs = tmp_path / "agent"
    theirs.mkdir()
    (theirs / "model.pt").write_bytes(b"an older agent")
    with pytest.raises(UnitConflict, match=r"no unit.json .*--overwrite to replace it"):
        load_unit_folder(theirs, CONFIG)
    assert load_unit_folder(theirs, CONFIG, overwrite=True) is None
    (theirs / "sub").mkdir()
    with pytest.raises(UnitConflict, match="has subfolders, so it is never replaced"):
        load_unit_folder(theirs, CONFIG, overwrite=True)


def test_a_swap_killed_half_way_is_undone_and_leftovers_go(tmp_path: Path) -> None:
    unit = tmp_path / "agent"
    save_unit_folder(unit, {"model.pt": b"old"}, CONFIG)
    old = {p.name: p.read_bytes() for p in unit.iterdir()}
    # What a kill between the two renames of a swap leaves: the old folder moved aside.
    aside = tmp_path / ".agent.old-x1"
    aside.mkdir()
    os.rename(unit, aside / "x")
    (tmp_path / ".agent.new-y2").mkdir()  # and an unfinished new one
    tidy_folder(unit)
    assert {p.name: p.read_bytes() for p in unit.iterdir()} == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["agent"]
    save_unit_folder(unit, {"model.pt": b"new"}, {**CONFIG, "seed": 2})
    assert (unit / "model.pt").read_bytes() == b"new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["agent"]


def test_file_units_keep_their_result(tmp_path: Path) -> None:
    path = tmp_path / "seeds" / "seed-0.json"
    save_record(path, make_record(CONFIG, result={"mean": 1.5}))
    assert load_unit(path, CONFIG)["result"] == {"mean": 1.5}
    assert json.loads(path.read_text())["fingerprint"].startswith("sha256:")
    with pytest.raises(UnitConflict, match="seed 1 -> 2"):
        load_unit(path, {**CONFIG, "seed": 2})
    for damage in ("", "{", '"text"', "[]", '{"format": "pokerirl-unit/1"}'):
        path.write_text(damage)
        assert load_unit(path, CONFIG) is None


def not_picklable(k: int) -> object:
    return lambda: k


def test_a_result_that_does_not_pickle_is_one_error_not_a_dying_worker() -> None:
    with pytest.raises((AttributeError, pickle.PicklingError), match="pickle"):
        map_units(not_picklable, [(1,), (2,)], backend=TWO)


def test_an_unreachable_ray_address_is_one_line() -> None:
    from typer.testing import CliRunner

    from pokerirl.cli import app

    result = CliRunner().invoke(
        app, ["tournament", "raise", "call", "--hands", "100", "--seeds", "0",
              "--ray", "127.0.0.1:1", "--out", "unused", "-q"],
    )  # fmt: skip
    assert result.exit_code == 1 and result.stdout == ""
    assert (
        result.stderr == "error: cannot reach the Ray cluster at 127.0.0.1:1: Connection refused\n"
    )
