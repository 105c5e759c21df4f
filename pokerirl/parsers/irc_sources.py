"""Reading the IRC Poker Database's files: month folders, folders of them, month archives
and the whole ``IRCdata.tgz`` (archives inside an archive), into the raw bytes of each month
(:class:`MonthFiles`). Archives are streamed member by member and never extracted; only regular
files are read, and every size is checked against :data:`MAX_FILE_BYTES` and
:data:`MAX_MONTH_BYTES` before anything is allocated. :mod:`pokerirl.parsers.irc` parses what
this yields.
"""

from __future__ import annotations

import gzip
import os
import stat
import tarfile
import zlib
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import IO

from pokerirl.errors import PokerIRLError

# Big blind in chips per limit hold'em channel; bets are one big blind, doubled on turn and river.
BIG_BLIND_BY_CHANNEL: dict[str, int] = {
    "holdem": 10,
    "holdem1": 10,
    "holdemii": 10,
    "botsonly": 10,
    "h1-nobots": 10,
    "holdem2": 20,
    "holdem3": 50,
}

# Real months are a few MB (holdem/199504: 0.9 MB of hdb, 6.9 MB in all) and the largest
# synthetic one (1M hands) 242 MB; a file or month beyond these caps is not IRC data, and
# reading it whole would take several times its size in memory.
MAX_FILE_BYTES = 128 * 1024 * 1024
MAX_MONTH_BYTES = 512 * 1024 * 1024
# tarfile reads a long name or a pax header whole into memory; IRC names are short.
MAX_TAR_HEADER_BYTES = 1024 * 1024
_ARCHIVE_SUFFIXES = (".tgz", ".tar.gz", ".tar")


class IngestError(PokerIRLError):
    """A source cannot be read as IRC data, or ``strict`` met a malformed line."""


@dataclass(frozen=True)
class MonthFiles:
    """The raw bytes of one month of one channel."""

    channel: str
    month: str
    origin: str  # where it came from, for messages
    hdb: bytes
    hroster: bytes
    pdb: dict[str, bytes]  # file name -> contents

    @property
    def key(self) -> str:
        return f"{self.channel}/{self.month}"


# ---------------------------------------------------------------------------------------------
# Sources


def check_sources(sources: Sequence[str | os.PathLike[str]]) -> None:
    """Fail early, with :class:`IngestError`, on a source that cannot be IRC data."""
    if not sources:
        raise IngestError("no source given")
    for source in sources:
        path = Path(source)
        if not path.exists():
            raise IngestError(f"{path}: no such file or folder")
        if not path.is_dir() and not path.name.endswith(_ARCHIVE_SUFFIXES):
            raise IngestError(
                f"{path}: not IRC data (expected a month folder, a folder of months, "
                "or a .tgz archive)"
            )
        if path.is_dir():
            _folder_items(path)  # a folder without IRC data fails here, before any progress


def iter_months(sources: Sequence[str | os.PathLike[str]]) -> Iterator[MonthFiles]:
    """Yield every month found in ``sources``, in a deterministic order.

    Raises :class:`IngestError` for a source that is missing, unreadable or holds no IRC data.
    """
    check_sources(sources)
    for source in sources:
        path = Path(source)
        found = False
        for month in _iter_folder(path) if path.is_dir() else _iter_archive_file(path):
            found = True
            yield month
        if not found:
            raise IngestError(f"{path}: no IRC data here (no <channel>/<month>/hdb inside)")


def _present(path: Path) -> bool:
    """Whether ``path`` names anything but a folder (a file, a FIFO, a link, even a dangling
    one): what a month's files are looked up by, so a FIFO is refused, not passed over."""
    return os.path.lexists(path) and not path.is_dir()


def _iter_folder(path: Path) -> Iterator[MonthFiles]:
    for item in _folder_items(path):
        if item.is_dir():
            yield _read_month_folder(item)
        else:
            yield from _iter_archive_file(item)


def _folder_items(path: Path) -> list[Path]:
    """The month folders and archives under ``path``, sorted; IngestError when there are none."""
    if _present(path / "hdb"):
        return [path]
    found: list[Path] = []
    try:
        for root, dirs, files in os.walk(path):
            dirs.sort()
            if "hdb" in files:
                found.append(Path(root))
                dirs.clear()
                continue
            found.extend(Path(root) / f for f in sorted(files) if f.endswith(_ARCHIVE_SUFFIXES))
    except OSError as error:
        raise IngestError(f"{path}: cannot read ({error.strerror})") from error
    if not found:
        raise IngestError(f"{path}: no IRC data here (no hdb file and no .tgz archive)")
    return sorted(found)


def _check_size(where: str, size: int, month_total: int) -> None:
    """Raise :class:`IngestError` for a file or month larger than IRC data ever is."""
    if size > MAX_FILE_BYTES:
        raise IngestError(
            f"{where}: {size:,} bytes, more than the {MAX_FILE_BYTES:,} an IRC file may hold "
            "(not IRC data?)"
        )
    if month_total > MAX_MONTH_BYTES:
        raise IngestError(
            f"{where}: its month holds {month_total:,} bytes, more than the "
            f"{MAX_MONTH_BYTES:,} an IRC month may hold (not IRC data?)"
        )


_FILE_KINDS = {
    stat.S_IFDIR: "a folder",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFIFO: "a FIFO",
    stat.S_IFSOCK: "a socket",
}


@contextmanager
def _open_regular(path: Path) -> Iterator[tuple[IO[bytes], int]]:
    """``path`` open for reading, and its size; :class:`IngestError` unless it is a regular
    file (after links). Opening does not block: a FIFO without a writer is refused at once."""
    try:
        descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as error:
        raise IngestError(f"{path}: cannot read ({error.strerror or error})") from None
    with os.fdopen(descriptor, "rb") as handle:
        info = os.fstat(descriptor)
        if not stat.S_ISREG(info.st_mode):
            kind = _FILE_KINDS.get(stat.S_IFMT(info.st_mode), "not a plain file")
            raise IngestError(f"{path}: not a regular file ({kind}); IRC data is plain files")
        try:
            yield handle, info.st_size
        except OSError as error:
            raise IngestError(f"{path}: cannot read ({error.strerror or error})") from None


def _read_bytes(path: Path, month_total: int = 0) -> bytes:
    """The bytes of ``path``, checked against the caps given the month's bytes read so far:
    its size before reading, and what was read (at most one byte past the caps), in case the
    file grew in between."""
    with _open_regular(path) as (handle, size):
        _check_size(str(path), size, month_total + size)
        data = handle.read(min(MAX_FILE_BYTES, MAX_MONTH_BYTES - month_total) + 1)
        _check_size(str(path), len(data), month_total + len(data))
        return data


def _read_month_folder(path: Path) -> MonthFiles:
    resolved = path.resolve()
    channel, month = _text(resolved.parent.name), _text(resolved.name)
    pdb_dir = path / "pdb"
    hdb = _read_bytes(path / "hdb")
    roster_path = path / "hroster"
    roster = _read_bytes(roster_path, len(hdb)) if _present(roster_path) else b""
    total = len(hdb) + len(roster)
    pdb: dict[str, bytes] = {}
    if channel in BIG_BLIND_BY_CHANNEL and pdb_dir.is_dir():
        for pdb_file in sorted(pdb_dir.iterdir()):
            if pdb_file.name.startswith("pdb.") and _present(pdb_file):
                pdb[pdb_file.name] = data = _read_bytes(pdb_file, total)
                total += len(data)
    return MonthFiles(channel, month, str(path), hdb, roster, pdb)


def _text(name: str) -> str:
    """A file name as valid text for the table: bytes that are not UTF-8 (which ``os.fsdecode``
    and tarfile keep as surrogates) shown as ``\\xNN``, as ``ls -b`` does.

    >>> _text("1995" + os.fsdecode(b"\\xff") + "04")
    '1995\\\\xff04'
    """
    try:
        return name.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a surrogate no file name decodes to
        return name.encode("utf-8", "backslashreplace").decode("utf-8")


def _iter_archive_file(path: Path) -> Iterator[MonthFiles]:
    with _open_regular(path) as (handle, _):
        yield from _iter_tar_stream(handle, str(path), path.name)


def _hint_from_archive_name(name: str) -> tuple[str | None, str | None]:
    """``holdem.199504.tgz`` -> ("holdem", "199504")."""
    stem = name
    for suffix in _ARCHIVE_SUFFIXES:
        if stem.endswith(suffix):
            stem = stem[: -len(suffix)]
            break
    channel, _, month = stem.rpartition(".")
    if channel and month.isdecimal():
        return channel, month
    return None, None


def _member_key(name: str, hint: tuple[str | None, str | None]) -> tuple[str, str, str] | None:
    """Map an archive member to (channel, month, file name), or None if it is not IRC data."""
    parts = [p for p in PurePosixPath(name).parts if p not in (".", "/")]
    if not parts:
        return None
    leaf = parts[-1]
    if leaf in ("hdb", "hroster"):
        folder = parts[:-1]
    elif leaf.startswith("pdb.") and len(parts) >= 2 and parts[-2] == "pdb":
        folder = parts[:-2]
    else:
        return None
    month = folder[-1] if folder else hint[1]
    channel = folder[-2] if len(folder) >= 2 else hint[0]
    if month is None or channel is None:
        return None
    return _text(channel), _text(month), leaf


class _HeaderTooLarge(IngestError):
    """A tar header of more than :data:`MAX_TAR_HEADER_BYTES`; the archive's reader names the
    archive (internal: never reaches a user as it is)."""

    def __init__(self, size: int) -> None:
        super().__init__(f"a tar header of {size:,} bytes")
        self.size = size


class _BoundedTarInfo(tarfile.TarInfo):
    """A tar header that refuses a long-name or pax header beyond
    :data:`MAX_TAR_HEADER_BYTES`, which tarfile would otherwise read whole into memory."""

    _EXTENDED = (
        tarfile.GNUTYPE_LONGNAME,
        tarfile.GNUTYPE_LONGLINK,
        tarfile.XHDTYPE,
        tarfile.XGLTYPE,
        tarfile.SOLARIS_XHDTYPE,
    )

    def _proc_member(self, tar: tarfile.TarFile) -> tarfile.TarInfo:
        if self.type in self._EXTENDED and self.size > MAX_TAR_HEADER_BYTES:
            raise _HeaderTooLarge(self.size)
        return super()._proc_member(tar)  # type: ignore[misc]


def _iter_tar_stream(fileobj: IO[bytes], origin: str, archive_name: str) -> Iterator[MonthFiles]:
    hint = _hint_from_archive_name(archive_name)
    current: tuple[str, str] | None = None
    files: dict[str, bytes] = {}
    month_total = 0  # bytes of the current month's files

    def flush() -> Iterator[MonthFiles]:
        if current is not None and "hdb" in files:
            channel, month = current
            pdb = {k: v for k, v in files.items() if k.startswith("pdb.")}
            yield MonthFiles(
                channel,
                month,
                f"{origin}:{channel}/{month}",
                files["hdb"],
                files.get("hroster", b""),
                dict(sorted(pdb.items())),
            )

    # gzip is opened here, not by tarfile: tarfile stops at the tar end block and never reads
    # the gzip trailer, so a flipped byte was ingested as fewer hands with exit 0. GzipFile
    # checks the CRC and the length when the stream is drained to its end (_drain).
    unzipped = gzip.GzipFile(fileobj=fileobj, mode="rb") if _is_gzip(fileobj) else None
    try:
        # "r|" / "r|*" stream: each member is read once, in order, with no seeking back.
        with tarfile.open(fileobj=unzipped or fileobj, mode="r|" if unzipped else "r|*",
                          tarinfo=_BoundedTarInfo) as tar:  # fmt: skip
            for member in tar:
                if not member.isfile():
                    if not member.isdir() and _member_key(member.name, hint) is not None:
                        raise IngestError(
                            f"{origin}:{member.name}: not a regular file in the archive "
                            f"({_MEMBER_KINDS.get(member.type, 'a special member')}); "
                            "IRC data is plain files"
                        )
                    continue
                if member.name.endswith(_ARCHIVE_SUFFIXES):
                    yield from flush()
                    current, files, month_total = None, {}, 0
                    inner = tar.extractfile(member)
                    if inner is not None:
                        inner_name = PurePosixPath(member.name).name
                        yield from _iter_tar_stream(inner, f"{origin}:{member.name}", inner_name)
                    continue
                key = _member_key(member.name, hint)
                if key is None:
                    continue
                channel, month, leaf = key
                if (channel, month) != current:
                    yield from flush()
                    current, files, month_total = (channel, month), {}, 0
                if leaf.startswith("pdb.") and channel not in BIG_BLIND_BY_CHANNEL:
                    continue  # skipped channels only need their hdb, to count the hands
                # The header gives the size: check it before reading a byte of the member.
                month_total += member.size
                _check_size(f"{origin}:{member.name}", member.size, month_total)
                extracted = tar.extractfile(member)
                if extracted is not None:
                    files[leaf] = extracted.read()
            _drain(unzipped, origin)  # before the last month: a damaged archive gives none
            yield from flush()
    except _HeaderTooLarge as error:
        raise IngestError(
            f"{origin}: a tar header of {error.size:,} bytes, more than the "
            f"{MAX_TAR_HEADER_BYTES:,} an IRC archive's names need (not IRC data?)"
        ) from None
    except (tarfile.TarError, EOFError, OSError, zlib.error) as error:
        damaged = unzipped is not None and not isinstance(error, tarfile.TarError)
        reason = f"damaged gzip: {error}" if damaged else str(error)
        raise IngestError(f"{origin}: not a readable tar archive ({reason})") from None


def _is_gzip(fileobj: IO[bytes]) -> bool:
    peek = getattr(fileobj, "peek", None)
    return peek is not None and bytes(peek(2)[:2]) == b"\x1f\x8b"


def _drain(unzipped: gzip.GzipFile | None, origin: str) -> None:
    """Read what follows the tar end block (zero padding) to the end of the gzip stream, where
    GzipFile checks each member's CRC and length; IngestError naming ``origin`` otherwise."""
    if unzipped is None:
        return
    left = MAX_FILE_BYTES  # padding is at most a record; a stream that goes on is not IRC's
    while chunk := unzipped.read(min(left, 1 << 20) + 1):
        left -= len(chunk)
        if left < 0:
            raise IngestError(f"{origin}: more than {MAX_FILE_BYTES:,} bytes after the tar's end")


_MEMBER_KINDS = {
    tarfile.SYMTYPE: "a symbolic link",
    tarfile.LNKTYPE: "a hard link",
    tarfile.CHRTYPE: "a character device",
    tarfile.BLKTYPE: "a block device",
    tarfile.FIFOTYPE: "a FIFO",
}
