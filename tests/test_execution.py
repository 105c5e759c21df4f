"""pokerirl.execution on local processes: order, thread pinning, private working folders,
retries when a worker dies, and errors. (The unit records that decide reuse, recompute or
refuse are the store's, in test_store_*.py; the real Ray cluster is in test_execution_ray.py,
killed drivers in test_execution_kill.py.)"""

from __future__ import annotations

import os
import pickle
import re
import signal
import sys
from pathlib import Path

import pytest

from pokerirl.execution import Backend, ExecutionError, choose_backend, map_units

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


@pytest.mark.slow
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


@pytest.mark.slow
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


def slow_steps(k: int, steps: int) -> int:
    """A unit that tells its progress: ``steps`` steps of 0.2 s."""
    import time

    from pokerirl.execution import unit_progress

    for step in range(1, steps + 1):
        time.sleep(0.2)
        unit_progress(step, steps)
    return k


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_units_own_progress_moves_the_bar_before_it_finishes(
    jobs: int, capsys: pytest.CaptureFixture[str]
) -> None:
    """In this process and in local workers alike, the bar counts a running unit by the
    fraction it reported: fractions of a unit appear before the first unit is done."""
    found = map_units(slow_steps, [(0, 10), (1, 10)], backend=Backend(jobs=jobs), progress=True,
                      desc="steps")  # fmt: skip
    assert found == [0, 1]
    shown = [float(n) for n in re.findall(r"steps: .*?\| (\d+\.\d\d)/2 ", capsys.readouterr().err)]
    assert shown[-1] == 2.0
    assert [n for n in shown if 0 < n < 1], shown  # inside the first units: not only 0, 1, 2


def two_phases(k: int) -> int:
    """A unit of two phases, each reporting 0 to 1 of itself (a baseline, then training)."""
    import time

    from pokerirl.execution import progress_share, unit_progress

    for start, stop in ((0.0, 0.3), (0.3, 1.0)):
        with progress_share(start, stop):
            for step in range(1, 5):
                time.sleep(0.15)
                unit_progress(step, 4)
    return k


def test_a_unit_of_phases_never_moves_the_bar_back(capsys: pytest.CaptureFixture[str]) -> None:
    map_units(two_phases, [(0,)], backend=Backend(), progress=True, desc="phases")
    shown = [float(n) for n in re.findall(r"phases: .*?\| (\d+\.\d\d)/1 ", capsys.readouterr().err)]
    assert shown == sorted(shown) and shown[-1] == 1.0 and any(0.3 < n < 1 for n in shown)


def test_the_processes_started_for_ray_import_this_pokerirl(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The private instance's reaper and ray_head's processes get the folder above this
    ``pokerirl`` first on PYTHONPATH, wherever the module that starts them sits in it."""
    import pokerirl
    from pokerirl.execution.ray_private import _pythonpath

    monkeypatch.delenv("PYTHONPATH", raising=False)
    here = Path(pokerirl.__file__).resolve()
    assert Path(_pythonpath()) / "pokerirl" / "__init__.py" == here
    monkeypatch.setenv("PYTHONPATH", "/elsewhere")
    assert _pythonpath().split(os.pathsep) == [str(here.parents[1]), "/elsewhere"]


def test_a_head_that_never_starts_is_one_error_with_each_attempts_reason(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from pokerirl.execution import ray_head, ray_private

    folders: list[Path] = []

    def failing(home: Path, num_cpus: int) -> tuple[list[str], int]:
        folders.append(home)
        return [sys.executable, "-c", f"print('head {len(folders)} did not register')"], 1

    monkeypatch.setattr(ray_private, "_head_command", failing)
    said: list[str] = []
    with pytest.raises(ExecutionError) as error, ray_head(num_cpus=1, attempts=3, say=said.append):
        pytest.fail("a head that never started was yielded")
    assert str(error.value) == (
        "ray start --head failed 3 times: 1: head 1 did not register; "
        "2: head 2 did not register; 3: head 3 did not register"
    )
    assert len(set(folders)) == 3 and not any(folder.exists() for folder in folders)
    assert said == [
        f"ray start --head: attempt {n} of 3 failed (head {n} did not register); starting a "
        "fresh head" for n in (1, 2)
    ]


def test_a_ray_that_fails_to_start_is_one_line() -> None:
    # Ray raises a bare Exception when its raylet does not register within its fixed 30 s
    # (a loaded machine): one line, not a traceback. A stand-in for `ray`, since no machine
    # times Ray out on demand.
    from types import SimpleNamespace

    from pokerirl.execution import LOCAL_RAY
    from pokerirl.execution.ray_connect import _ray_init

    def init(**_: object) -> None:
        raise Exception(
            "The current node timed out during startup. This could happen because some of "
            "the raylet failed to startup or the GCS has become overloaded.\nmore"
        )

    with pytest.raises(ExecutionError) as error:
        _ray_init(SimpleNamespace(init=init), LOCAL_RAY, None)
    assert str(error.value) == (
        "cannot connect to Ray at local: The current node timed out during startup. This could "
        "happen because some of the raylet failed to startup or the GCS has become overloaded."
    )


def test_a_private_ray_that_fails_to_start_is_started_afresh() -> None:
    # `--ray local`: Ray's startup timeout (a bare Exception after 30 s on a loaded machine)
    # shuts the failed start down and tries again in a new folder; three failures are one
    # line with each reason. A stand-in for `ray`, since no machine times Ray out on demand.
    from types import SimpleNamespace

    from pokerirl.execution.ray_connect import _private_ray

    folders: list[Path] = []
    calls: list[str] = []  # init and shutdown, in order

    def failing(times: int) -> SimpleNamespace:
        def init(**options: object) -> None:
            folders.append(Path(str(options["_temp_dir"])))
            assert folders[-1].is_dir()
            calls.append("init")
            if len(folders) <= times:
                raise Exception(f"The current node timed out during startup ({len(folders)}).")

        return SimpleNamespace(init=init, shutdown=lambda: calls.append("shutdown"))

    with _private_ray(failing(2)):
        assert calls == ["init", "shutdown", "init", "shutdown", "init"]
        assert len(set(folders)) == 3 and [f.exists() for f in folders] == [False, False, True]
    assert calls[-1] == "shutdown" and not folders[-1].exists()
    folders.clear()
    with pytest.raises(ExecutionError) as error, _private_ray(failing(3)):
        pass
    assert str(error.value) == (
        "cannot start a private Ray (local) in 3 attempts: 1: The current node timed out during "
        "startup (1).; 2: The current node timed out during startup (2).; 3: The current node "
        "timed out during startup (3)."
    )
    assert not any(f.exists() for f in folders)


def test_a_head_interrupted_while_starting_is_stopped(monkeypatch: pytest.MonkeyPatch) -> None:
    # A Ctrl-C (here another exception) while waiting for Ray stops the head, not only its folder.
    import time
    from types import SimpleNamespace

    from pokerirl.execution import ray_head, ray_private
    from pokerirl.execution.processes import _descendants, _running

    before, started = _descendants(os.getpid()), set()

    class Interrupted(BaseException):
        pass

    def still_starting(home: Path, num_cpus: int) -> tuple[list[str], int]:
        return [sys.executable, "-c", "import time; time.sleep(120)"], 1

    def interrupt(_: float) -> None:
        started.update(p for p in _descendants(os.getpid()) - before if _running(p))
        raise Interrupted

    monkeypatch.setattr(ray_private, "_head_command", still_starting)
    clock = SimpleNamespace(monotonic=time.monotonic, sleep=interrupt)
    monkeypatch.setattr(ray_private, "time", clock)
    with pytest.raises(Interrupted), ray_head(num_cpus=1):
        pytest.fail("a head that never started was yielded")
    assert started and not [pid for pid in started if _running(pid)]
