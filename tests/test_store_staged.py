"""Staged writes: a writer SIGKILLed before any step of the swap leaves the old entries or
the new ones, whole, once the next writer (or reader) has tidied; live writers are never
disturbed; errors name the user's path.

The kill is real: a forked child runs the write and sends itself SIGKILL just before its
n-th change to the filesystem (every mkdir, rename, replace, unlink and rmdir, the deletes
inside ``rmtree`` included), for every n, so no ``finally`` block runs and its lock dies with
it, as with ``kill -9``.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from pokerirl.store import staged_files, staged_folder, tidy

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")

MUTATIONS = ("mkdir", "rename", "replace", "unlink", "rmdir")


def _count_mutations(limit: int | None) -> list[int]:
    """Wrap this process's filesystem changes: counted, and SIGKILL before number ``limit``."""
    count = [0]
    for name in MUTATIONS:
        original = getattr(os, name)

        def wrapped(
            *args: object, _original: Callable[..., object] = original, **kw: object
        ) -> object:
            count[0] += 1
            if limit is not None and count[0] == limit:
                os.kill(os.getpid(), signal.SIGKILL)
            return _original(*args, **kw)

        setattr(os, name, wrapped)
    return count


def _in_child(write: Callable[[], None], limit: int | None) -> int | None:
    """Run ``write`` in a forked child killed before mutation ``limit``; the number of
    mutations it made when it was not killed, None when it was."""
    reader, writer = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: no pytest teardown, no atexit
        os.close(reader)
        try:
            count = _count_mutations(limit)
            write()
            os.write(writer, str(count[0]).encode())
            os._exit(0)
        except BaseException:  # any failure is the child's exit code
            os._exit(3)
    os.close(writer)
    with os.fdopen(reader) as stream:
        made = stream.read()
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        assert os.WTERMSIG(status) == signal.SIGKILL
        return None
    assert os.WEXITSTATUS(status) == 0, "the write failed in the child"
    return int(made)


def _snapshot(parent: Path) -> dict[str, bytes | None]:
    """Every entry under ``parent``: files by content, folders as None."""
    return {
        str(path.relative_to(parent)): None if path.is_dir() else path.read_bytes()
        for path in sorted(parent.rglob("*"))
    }


def _kill_at_every_step(
    parent: Path, before: Callable[[], None], write: Callable[[], None]
) -> list[str]:
    """For every step n of ``write``: fresh ``before`` state, kill at n, tidy, and check that
    what is there is the old state or the new one. Returns which, per step."""

    def reset() -> None:
        shutil.rmtree(parent, ignore_errors=True)
        parent.mkdir(parents=True)
        before()

    reset()
    old = _snapshot(parent)
    steps = _in_child(write, None)
    assert steps is not None and steps > 3
    new = _snapshot(parent)
    assert new != old
    seen = []
    for limit in range(1, steps + 1):
        reset()
        assert _in_child(write, limit) is None, f"not killed at step {limit}"
        tidy(parent, key=KEY)
        state = _snapshot(parent)
        assert state in (old, new), f"killed before step {limit} of {steps}: {sorted(state)}"
        seen.append("old" if state == old else "new")
        write()  # and the next writer finishes
        assert _snapshot(parent) == new
    return seen


KEY = "run-1"


def test_a_folder_swap_killed_at_any_step_leaves_the_old_or_the_new_folder(
    tmp_path: Path,
) -> None:
    parent = tmp_path / "runs"

    def before() -> None:
        folder = parent / KEY
        (folder / "sub").mkdir(parents=True)
        (folder / "model.pt").write_bytes(b"old weights")
        (folder / "sub" / "a.json").write_bytes(b"old")
        (parent / "run-10").mkdir()  # a sibling unit whose name starts the same
        (parent / "run-10" / "model.pt").write_bytes(b"sibling")

    def write() -> None:
        with staged_folder(parent / KEY) as folder:
            (folder / "model.pt").write_bytes(b"new weights")
            (folder / "unit.json").write_bytes(b"{}")

    seen = _kill_at_every_step(parent, before, write)
    assert seen[0] == "old" and seen[-1] == "new"  # both ends of the swap were reached
    assert seen == sorted(seen, key=["old", "new"].index)  # once new, always new


def test_a_first_write_killed_at_any_step_leaves_nothing_or_the_folder(tmp_path: Path) -> None:
    parent = tmp_path / "runs"

    def write() -> None:
        with staged_folder(parent / KEY) as folder:
            (folder / "model.pt").write_bytes(b"weights")

    seen = _kill_at_every_step(parent, lambda: None, write)
    assert set(seen) == {"old", "new"}


def test_files_beside_siblings_swap_as_one(tmp_path: Path) -> None:
    """A file and its record (or a table and its summary) among other files: both old or both
    new, whatever the step, and the other entries untouched."""
    parent = tmp_path / "study"

    def before() -> None:
        (parent / "run-1.parquet").write_bytes(b"old table")
        (parent / "run-1.unit.json").write_bytes(b"old record")
        (parent / "notes.txt").write_bytes(b"the user's")

    def write() -> None:
        with staged_files(parent, key=KEY) as new:
            (new / "run-1.parquet").write_bytes(b"new table")
            (new / "run-1.unit.json").write_bytes(b"new record")

    seen = _kill_at_every_step(parent, before, write)
    assert set(seen) == {"old", "new"}


def test_the_leftovers_of_the_writers_before_the_store_are_cleared(tmp_path: Path) -> None:
    parent = tmp_path / "runs"
    parent.mkdir()
    # execution.save_unit_folder killed between its renames: the old folder moved aside.
    (parent / ".run-1.old-abcd1234" / "x").mkdir(parents=True)
    (parent / ".run-1.old-abcd1234" / "x" / "model.pt").write_bytes(b"old")
    (parent / ".run-1.new-efgh5678").mkdir()  # its half-written new folder
    (parent / ".run-1.abcdefgh.tmp").mkdir()  # pokerirl train's staged_folder
    (parent / ".run-1.ingest-abcdefgh").mkdir()  # an ingest's work folder
    (parent / ".run-2.new-abcd1234").mkdir()  # another unit's
    (parent / ".run-1.notes").mkdir()  # not a name any writer makes
    tidy(parent, key=KEY)
    assert sorted(p.name for p in parent.iterdir()) == [".run-1.notes", ".run-2.new-abcd1234", KEY]
    assert (parent / KEY / "model.pt").read_bytes() == b"old"
    # pokerirl train's old folder, moved aside before a kill
    shutil.rmtree(parent / KEY)
    (parent / f".run-1.{'0' * 32}.old").mkdir()
    (parent / f".run-1.{'0' * 32}.old" / "config.json").write_bytes(b"{}")
    tidy(parent, key=KEY)
    assert (parent / KEY / "config.json").exists()
    assert not (parent / f".run-1.{'0' * 32}.old").exists()


def test_a_live_writer_is_never_disturbed_and_the_later_one_wins(tmp_path: Path) -> None:
    parent = tmp_path / "runs"
    with staged_folder(parent / KEY) as first:
        (first / "model.pt").write_bytes(b"first")

        # Another process tidies, and writes the same unit and a sibling meanwhile.
        def other() -> None:
            tidy(parent, key=KEY)
            with staged_folder(parent / KEY) as second:
                (second / "model.pt").write_bytes(b"second")
            with staged_folder(parent / "run-2") as sibling:
                (sibling / "model.pt").write_bytes(b"sibling")

        assert _in_child(other, None) is not None
        assert first.is_dir() and (first / "model.pt").read_bytes() == b"first"
        assert (parent / KEY / "model.pt").read_bytes() == b"second"
    assert (parent / KEY / "model.pt").read_bytes() == b"first"  # the later swap
    assert (parent / "run-2" / "model.pt").read_bytes() == b"sibling"
    assert sorted(p.name for p in parent.iterdir()) == [KEY, "run-2"]


def test_a_failed_block_changes_nothing(tmp_path: Path) -> None:
    parent = tmp_path / "runs"
    with staged_folder(parent / KEY) as folder:
        (folder / "model.pt").write_bytes(b"old")
    with pytest.raises(KeyboardInterrupt), staged_folder(parent / KEY) as folder:
        (folder / "model.pt").write_bytes(b"new")
        raise KeyboardInterrupt
    assert sorted(p.name for p in parent.iterdir()) == [KEY]
    assert (parent / KEY / "model.pt").read_bytes() == b"old"


def test_a_file_replaces_a_folder_and_a_folder_a_file(tmp_path: Path) -> None:
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "x").write_bytes(b"folder")
    (tmp_path / "b").write_bytes(b"file")
    with staged_files(tmp_path, key="a") as new:
        (new / "a").write_bytes(b"now a file")
        (new / "b").mkdir()
    assert (tmp_path / "a").read_bytes() == b"now a file" and (tmp_path / "b").is_dir()


@contextmanager
def read_only(folder: Path) -> Iterator[None]:
    """``folder`` made unwritable: by its mode, or for root (whom modes do not stop) by the
    immutable attribute where ``chattr`` works; else the test is skipped."""
    if os.geteuid() != 0:
        folder.chmod(0o555)
        try:
            yield
        finally:
            folder.chmod(0o755)
        return
    if shutil.which("chattr") is None:
        pytest.skip("root, and no chattr")
    if subprocess.run(["chattr", "+i", str(folder)], capture_output=True).returncode != 0:
        pytest.skip("root, and chattr +i does not work here")
    try:
        yield
    finally:
        subprocess.run(["chattr", "-i", str(folder)], check=True)


def test_a_parent_that_cannot_be_written_is_one_error_naming_the_target(tmp_path: Path) -> None:
    parent = tmp_path / "read-only"
    parent.mkdir()
    with read_only(parent):
        with pytest.raises(PermissionError) as refused, staged_folder(parent / KEY):
            pass
        assert refused.value.filename == str(parent / KEY)
        assert ".run-1" not in str(refused.value)
        with pytest.raises(PermissionError) as refused:
            with staged_folder(parent / "deeper" / KEY):
                pass
        assert refused.value.filename == str(parent / "deeper")
    assert list(parent.iterdir()) == []


def test_a_missing_parent_is_made_or_refused_naming_the_target(tmp_path: Path) -> None:
    with staged_folder(tmp_path / "a" / "b" / KEY) as folder:
        (folder / "x").write_bytes(b"x")
    assert (tmp_path / "a" / "b" / KEY / "x").exists()
    with pytest.raises(FileNotFoundError) as refused:
        with staged_files(tmp_path / "missing", key="table.parquet", make_parent=False):
            pass
    assert str(refused.value) == (
        f"[Errno 2] its folder does not exist: '{tmp_path / 'missing' / 'table.parquet'}'"
    )
    (tmp_path / "file").write_bytes(b"")
    with pytest.raises(NotADirectoryError) as refused, staged_folder(tmp_path / "file" / KEY):
        pass
    assert refused.value.filename == str(tmp_path / "file")
