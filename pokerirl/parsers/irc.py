"""Reader for the University of Alberta IRC Poker Database.

A month of a channel is three things: ``hdb`` (one line per hand), ``hroster`` (the players of
each hand, in name order) and ``pdb/pdb.<nick>`` (one line per player and hand). Sources may be
month folders, folders of month folders, month archives (``holdem.199504.tgz``) or the whole
``IRCdata.tgz`` (archives inside an archive). Archives are streamed member by member and never
extracted; only one month is held in memory at a time, and a month's files are capped
(:data:`MAX_FILE_BYTES` each, :data:`MAX_MONTH_BYTES` together), so memory stays bounded even
for a small archive that inflates to a huge member. Only regular files are read (a FIFO, a
device or a link to one is refused before a byte is read), and sizes are checked before
anything is allocated, in folders and in archives alike.

:func:`iter_months` yields the raw files of each month; :func:`parse_month` turns one month into
the heads-up hands that can be learned from, and puts every hand of ``hdb`` into exactly one
bucket of :class:`IngestStats`.
"""

from __future__ import annotations

import bisect
import gc
import gzip
import os
import stat
import tarfile
import zlib
from collections import Counter, defaultdict
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import IO

import numpy as np

from pokerirl.errors import PokerIRLError
from pokerirl.holdem import BOARD_SIZE_BY_ROUND, CARD_INDEX
from pokerirl.parsers.replay import Replay, ReplayError, replay_actions

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

# Every hand of hdb ends in exactly one of these.
KEPT = "kept"
DROP_REASONS: tuple[str, ...] = (
    "not_heads_up",
    "missing_pdb_line",
    "roster_mismatch",
    "cards_concealed",
    "malformed_line",
    "skipped_channel",
    "duplicate_hand",
    "inconsistent_hand",
)
MAX_MALFORMED_EXAMPLES = 10
# Real months are a few MB (holdem/199504: 0.9 MB of hdb, 6.9 MB in all) and the largest
# synthetic one (1M hands) 242 MB; a file or month beyond these caps is not IRC data, and
# reading it whole would take several times its size in memory.
MAX_FILE_BYTES = 128 * 1024 * 1024
MAX_MONTH_BYTES = 512 * 1024 * 1024
# tarfile reads a long name or a pax header whole into memory; IRC names are short.
MAX_TAR_HEADER_BYTES = 1024 * 1024
# Largest values the table's columns hold (timestamp int64, chips int32, raises int16): a line
# beyond them is malformed, not silently wrapped.
_MAX_TIMESTAMP = 2**63 - 1
_MAX_CHIPS = 2**31 - 1
_MAX_RAISES = 2**15 - 1
# Numbers are checked with str.isdecimal(), never str.isdigit(): isdigit() is true for the
# Latin-1 "²", "³" and "¹" (which byte flips of the logs produce), and int() then fails. On
# Latin-1 text isdecimal() is exactly an ASCII-digit check. Timestamps are at most 19 digits,
# which also keeps int() within its 4,300-digit limit.
_MAX_DIGITS = 19
_PROGRESS_EVERY = 8192
_ARCHIVE_SUFFIXES = (".tgz", ".tar.gz", ".tar")


class IngestError(PokerIRLError):
    """A source cannot be read as IRC data, or ``strict`` met a malformed line."""


@dataclass
class IngestStats:
    """Running accounting of an ingest: where every hand went, and why."""

    strict: bool = False
    hands_read: Counter[str] = field(default_factory=Counter)  # per channel
    buckets: Counter[str] = field(default_factory=Counter)
    inconsistent_reasons: Counter[str] = field(default_factory=Counter)
    skipped_channels: Counter[str] = field(default_factory=Counter)
    malformed_lines: int = 0
    malformed_examples: list[str] = field(default_factory=list)
    heads_up_hands: int = 0
    single_blind_hands: int = 0
    chips_mismatch_hands: int = 0
    decisions_concealed: int = 0
    orphan_pdb_lines: int = 0
    kept_fold_hands: int = 0  # kept hands that ended in a fold, their cards shown
    # Kept with ``keep_concealed`` (``ingest --folds impute``): fold hands nobody showed.
    concealed_fold_hands: int = 0
    months: list[str] = field(default_factory=list)

    def malformed(self, where: str, why: str) -> None:
        """Count a malformed line; raise instead when strict."""
        message = f"{where}: {why}"
        if self.strict:
            raise IngestError(f"malformed line at {message}")
        self.malformed_lines += 1
        if len(self.malformed_examples) < MAX_MALFORMED_EXAMPLES:
            self.malformed_examples.append(message)

    def drop(self, bucket: str, count: int = 1) -> None:
        self.buckets[bucket] += count


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


@dataclass
class MonthHands:
    """The kept heads-up hands of one month, in flat lists for fast conversion to arrays.

    Per hand: one timestamp and one replay. Per hand and position (1 then 2): the nick, two hole
    cards (``-1`` when concealed), chips put in and chips won. Per hand: five board cards.
    """

    channel: str
    month: str
    big_blind: int
    timestamps: list[int] = field(default_factory=list)
    replays: list[Replay] = field(default_factory=list)
    players: list[str] = field(default_factory=list)
    hole_cards: list[int] = field(default_factory=list)
    boards: list[int] = field(default_factory=list)
    chips_in: list[int] = field(default_factory=list)
    chips_won: list[int] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.timestamps)


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


# ---------------------------------------------------------------------------------------------
# Parsing one month


def _lines(data: bytes) -> list[str]:
    # latin-1 never fails, and nicks may hold any byte. A CR left by CRLF endings is whitespace,
    # which ``str.split()`` drops with the rest.
    lines = data.decode("latin-1").split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return lines


# A heads-up pdb line, split on whitespace, with where it came from: (fields, file, line number).
_PdbFields = tuple[list[str], str, int]


class _LostLines:
    """Where a file's unreadable lines were, as timestamps: the hand that lost its hroster or
    pdb line to one of them is a ``malformed_line``, as it would be for a corrupt hdb line,
    not a ``missing_pdb_line`` or a ``roster_mismatch``.

    The files are in time order, so a line whose timestamp is itself corrupt lies between the
    readable timestamps before and after it; a line with a readable timestamp lost only its
    own hand. Built line by line (:meth:`readable`, :meth:`unreadable`), then :meth:`close`.

    >>> lost = _LostLines()
    >>> for stamp in (10, None, 30, 40):
    ...     lost.readable(stamp) if stamp is not None else lost.unreadable(None)
    >>> lost.close()
    >>> [t for t in (10, 20, 29, 30, 40) if lost.covers(t)]
    [20, 29]
    """

    def __init__(self) -> None:
        self._after, self._open = -1, False
        self._spans: list[tuple[int, int]] = []  # exclusive bounds
        self._lows: list[int] = []
        self._highs: list[int] = []

    def readable(self, stamp: int) -> None:
        if self._open:
            self._spans.append((min(self._after, stamp), max(self._after, stamp)))
            self._open = False
        self._after = stamp

    def unreadable(self, stamp: int | None) -> None:
        """An unreadable line, with its timestamp if that part is readable."""
        if stamp is None:
            self._open = True
        else:
            self._spans.append((stamp - 1, stamp + 1))
            self.readable(stamp)

    def close(self) -> None:
        if self._open:
            self._spans.append((self._after, _MAX_TIMESTAMP + 1))
        for low, high in sorted(self._spans):  # merged, for bisect
            if self._highs and low < self._highs[-1]:
                self._highs[-1] = max(self._highs[-1], high)
            else:
                self._lows.append(low)
                self._highs.append(high)

    def covers(self, stamp: int) -> bool:
        i = bisect.bisect_left(self._lows, stamp) - 1
        return i >= 0 and stamp < self._highs[i]


_NOTHING_LOST = _LostLines()
_NOTHING_LOST.close()


def _stamp(text: str) -> int | None:
    """A timestamp field's value, or None if it is not one (not decimal, beyond int64)."""
    if len(text) > _MAX_DIGITS or not text.isdecimal():
        return None
    value = int(text)
    return value if value <= _MAX_TIMESTAMP else None


def _read_pdb(
    month: MonthFiles, stats: IngestStats
) -> tuple[dict[int, list[_PdbFields]], dict[str, _LostLines]]:
    """Heads-up pdb lines by timestamp, split but not yet validated, and each nick's
    unreadable lines."""
    by_hand: dict[int, list[_PdbFields]] = defaultdict(list)
    lost: dict[str, _LostLines] = {}
    for file_name, data in month.pdb.items():
        where = f"{month.origin}/pdb/{file_name}"
        lost[file_name.removeprefix("pdb.")] = lines_lost = _LostLines()
        for number, line in enumerate(_lines(data), start=1):
            fields = line.split()
            stamp = _stamp(fields[1]) if len(fields) >= 2 else None
            if len(fields) < 11 or stamp is None or not fields[2].isdecimal():
                stats.malformed(f"{where}:{number}", "not a pdb line")
                lines_lost.unreadable(stamp)
                continue
            lines_lost.readable(stamp)
            if fields[2] == "2":
                by_hand[stamp].append((fields, where, number))
        lines_lost.close()
    return by_hand, lost


def _read_roster(month: MonthFiles, stats: IngestStats) -> tuple[dict[int, list[str]], _LostLines]:
    roster: dict[int, list[str]] = {}
    lost = _LostLines()
    for number, line in enumerate(_lines(month.hroster), start=1):
        fields = line.split()
        stamp = _stamp(fields[0]) if fields else None
        if len(fields) < 2 or stamp is None or not fields[1].isdecimal():
            stats.malformed(f"{month.origin}/hroster:{number}", "not an hroster line")
            lost.unreadable(stamp)
            continue
        lost.readable(stamp)
        roster[stamp] = fields[2:]
    lost.close()
    return roster, lost


def parse_month(
    month: MonthFiles,
    stats: IngestStats,
    seen: dict[str, np.ndarray],
    on_hands: Callable[[int], None] | None = None,
    *,
    keep_concealed: bool = False,
) -> MonthHands:
    """Parse one month: count every hdb line into a bucket and return the kept hands.

    ``seen`` maps each month key (``channel/month``) to the timestamps already read and is
    updated, so a hand given twice, in one hdb or in two sources, is a ``duplicate_hand``.
    ``on_hands(n)`` is called as hdb lines are read, for progress bars.

    ``keep_concealed`` also keeps the hands that ended in a fold with nobody's cards shown
    (their hole cards ``-1``, counted in ``concealed_fold_hands`` and in ``kept``), for an
    imputation of the hidden cards to place (:mod:`pokerirl.poker.impute`). A showdown with
    both pairs concealed stays ``cards_concealed``: nothing but the betting tells its cards.
    """
    hdb_lines = _lines(month.hdb)
    stats.hands_read[month.channel] += len(hdb_lines)
    stats.months.append(month.key)
    big_blind = BIG_BLIND_BY_CHANNEL.get(month.channel)
    hands = MonthHands(month.channel, month.month, big_blind or 0)
    if big_blind is None:
        stats.drop("skipped_channel", len(hdb_lines))
        stats.skipped_channels[month.channel] += len(hdb_lines)
        if on_hands is not None:
            on_hands(len(hdb_lines))
        return hands

    with _gc_paused():
        return _parse_limit_holdem_month(
            month, hdb_lines, stats, seen, on_hands, hands, keep_concealed
        )


@contextmanager
def _gc_paused() -> Iterator[None]:
    """Pause the cyclic garbage collector: parsing allocates millions of small lists and no
    cycles, and the collector's repeated scans of them would double the parsing time."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def _parse_limit_holdem_month(
    month: MonthFiles,
    hdb_lines: list[str],
    stats: IngestStats,
    seen: dict[str, np.ndarray],
    on_hands: Callable[[int], None] | None,
    hands: MonthHands,
    keep_concealed: bool = False,
) -> MonthHands:
    pdb, pdb_lost = _read_pdb(month, stats)
    roster, roster_lost = _read_roster(month, stats)
    hdb_where = f"{month.origin}/hdb"
    timestamps: set[int] = set(seen[month.key].tolist()) if month.key in seen else set()

    heads_up: list[tuple[int, int, list[str]]] = []  # (timestamp, line number, fields)
    for number, line in enumerate(hdb_lines, start=1):
        if on_hands is not None and number % _PROGRESS_EVERY == 0:
            on_hands(_PROGRESS_EVERY)
        fields = line.split()
        if (
            len(fields) - 8 not in (0, 3, 4, 5)
            or len(fields[0]) > _MAX_DIGITS
            or not fields[0].isdecimal()
            or not fields[3].isdecimal()
            or "/" not in fields[4]
            or "/" not in fields[7]
        ):
            stats.malformed(f"{hdb_where}:{number}", "not an hdb line")
            stats.drop("malformed_line")
            continue
        timestamp = int(fields[0])
        if timestamp > _MAX_TIMESTAMP:
            stats.malformed(f"{hdb_where}:{number}", f"timestamp {timestamp} beyond int64")
            stats.drop("malformed_line")
            continue
        if timestamp in timestamps:
            stats.drop("duplicate_hand")
            continue
        timestamps.add(timestamp)
        if fields[3] != "2":
            stats.drop("not_heads_up")
            continue
        heads_up.append((timestamp, number, fields))

    stats.heads_up_hands += len(heads_up)
    # Sorting by timestamp makes the table's order independent of the hdb's line order.
    heads_up.sort(key=lambda item: item[0])
    for timestamp, number, fields in heads_up:
        bucket = _classify_hand(
            timestamp,
            fields,
            f"{hdb_where}:{number}",
            pdb.pop(timestamp, None),
            roster.get(timestamp),
            hands,
            stats,
            keep_concealed,
        )
        if bucket in ("missing_pdb_line", "roster_mismatch"):
            bucket = _lost_or(bucket, timestamp, pdb_lost, roster_lost, roster.get(timestamp))
        stats.buckets[bucket] += 1
    stats.orphan_pdb_lines += sum(len(lines) for lines in pdb.values())
    seen[month.key] = np.fromiter(timestamps, dtype=np.int64, count=len(timestamps))
    if on_hands is not None:
        on_hands(len(hdb_lines) % _PROGRESS_EVERY)
    return hands


def _lost_or(
    bucket: str,
    timestamp: int,
    pdb_lost: dict[str, _LostLines],
    roster_lost: _LostLines,
    roster_names: list[str] | None,
) -> str:
    """``malformed_line`` for a hand whose missing roster, or a missing pdb line of a player
    in its roster, may be an unreadable line; else ``bucket``."""
    if roster_names is None:
        return "malformed_line" if roster_lost.covers(timestamp) else bucket
    if bucket == "missing_pdb_line" and any(
        pdb_lost.get(nick, _NOTHING_LOST).covers(timestamp) for nick in roster_names
    ):
        return "malformed_line"
    return bucket


def _parse_cards(texts: list[str]) -> tuple[int, ...]:
    try:
        return tuple(map(CARD_INDEX.__getitem__, texts))
    except KeyError as error:
        raise ValueError(f"bad card {error.args[0]!r}") from None


def _parse_pdb_numbers(fields: list[str]) -> tuple[int, int, int, tuple[int, ...] | None]:
    """(position, chips in, chips won, hole cards or None); ValueError if malformed."""
    if len(fields) == 13:
        cards: tuple[int, ...] | None = _parse_cards(fields[11:13])
        if cards[0] == cards[1]:  # type: ignore[index]
            raise ValueError("the same hole card twice")
    elif len(fields) == 11:
        cards = None
    else:
        raise ValueError(f"expected 11 or 13 fields, got {len(fields)}")
    # int() raises ValueError, which the caller counts as malformed, on "²" and the like.
    int(fields[8])  # bankroll: must be a number
    chips_in, chips_won = int(fields[9]), int(fields[10])
    if not (0 <= chips_in <= _MAX_CHIPS and 0 <= chips_won <= _MAX_CHIPS):
        raise ValueError(f"chips {chips_in} and {chips_won} not within 0 and {_MAX_CHIPS}")
    return int(fields[3]), chips_in, chips_won, cards


def _two_roster_players(lines: list[_PdbFields], roster_names: list[str] | None) -> bool:
    """Whether the hand's pdb lines are two different players, both on a two-name roster."""
    nick_a, nick_b = lines[0][0][0], lines[-1][0][0]
    return (
        len(lines) == 2
        and roster_names is not None
        and len(roster_names) == 2
        and nick_a != nick_b
        and nick_a in roster_names
        and nick_b in roster_names
    )


def _showdown_inconsistency(
    board: tuple[int, ...],
    hole: tuple[int, ...],
    *,
    both_shown: bool,
    chips: tuple[int, int, int, int],
) -> str | None:
    """Why a showdown cannot have happened as logged, or None. ``chips``: in and won, a and b."""
    in_a, in_b, won_a, won_b = chips
    if len(board) != 5:
        return "showdown without five board cards"
    if in_a + in_b != won_a + won_b:
        return "chips won differ from chips put in"
    if len({*hole, *board}) != (9 if both_shown else 8):  # a concealed pair is -1, -1
        return "a card dealt twice"
    return None


def _fold_inconsistency(
    board: tuple[int, ...], hole: tuple[int, ...], last_street: int, *, chips: tuple[int, ...]
) -> str | None:
    """Why a hand that ended in a fold, cards shown, cannot have happened as logged, or None."""
    in_a, in_b, won_a, won_b = chips
    if len(board) != BOARD_SIZE_BY_ROUND[last_street]:
        return "board does not match the street the hand ended on"
    if in_a + in_b != won_a + won_b:
        return "chips won differ from chips put in"
    shown = [card for card in (*hole, *board) if card >= 0]
    if len(set(shown)) != len(shown):
        return "a card dealt twice"
    return None


def _hand_inconsistency(
    replay: Replay,
    board: tuple[int, ...],
    hole: tuple[int, ...],
    chips: tuple[int, int, int, int],
    stats: IngestStats,
) -> str | None:
    """Why a hand cannot be kept as logged, or None (a kept fold is counted: with cards shown,
    or with none, which only ``keep_concealed`` lets through)."""
    if replay.showdown:
        both_shown = min(hole) >= 0
        return _showdown_inconsistency(board, hole, both_shown=both_shown, chips=chips)
    # A fold with cards shown: never in the real logs; `pokerirl synth --reveal-all` writes it.
    reason = _fold_inconsistency(board, hole, replay.last_street, chips=chips)
    if max(hole) >= 0:
        stats.kept_fold_hands += reason is None
    else:
        stats.concealed_fold_hands += reason is None
    return reason


def _classify_hand(
    timestamp: int,
    hdb_fields: list[str],
    hdb_where: str,
    lines: list[_PdbFields] | None,
    roster_names: list[str] | None,
    hands: MonthHands,
    stats: IngestStats,
    keep_concealed: bool = False,
) -> str:
    """Return the bucket of one heads-up hand, appending the hand to ``hands`` if kept."""
    try:
        board = _parse_cards(hdb_fields[8:])
    except ValueError as error:
        stats.malformed(hdb_where, str(error))
        return "malformed_line"
    if lines is None:
        return "missing_pdb_line"
    parsed = []
    for fields, where, number in lines:
        try:
            parsed.append(_parse_pdb_numbers(fields))
        except ValueError as error:
            stats.malformed(f"{where}:{number}", str(error))
            return "malformed_line"
    if len(lines) < 2:
        return "missing_pdb_line"
    if not _two_roster_players(lines, roster_names):
        return "roster_mismatch"
    if parsed[0][0] > parsed[1][0]:
        lines, parsed = lines[::-1], parsed[::-1]
    (pos_a, in_a, won_a, cards_a), (pos_b, in_b, won_b, cards_b) = parsed
    if (pos_a, pos_b) != (1, 2):
        stats.inconsistent_reasons["positions are not 1 and 2"] += 1
        return "inconsistent_hand"
    first, second = lines[0][0], lines[1][0]
    try:
        replay = replay_actions(
            (first[4], second[4], first[5], second[5], first[6], second[6], first[7], second[7])
        )
    except ReplayError as error:
        stats.inconsistent_reasons[f"actions: {error}"] += 1
        return "inconsistent_hand"
    if replay.max_raises > _MAX_RAISES:
        stats.malformed(hdb_where, f"{replay.max_raises} raises in a round, beyond int16")
        return "malformed_line"
    hole = (cards_a or (-1, -1)) + (cards_b or (-1, -1))
    chips = (in_a, in_b, won_a, won_b)
    if cards_a is None and cards_b is None and (not keep_concealed or replay.showdown):
        return "cards_concealed"
    reason = _hand_inconsistency(replay, board, hole, chips, stats)
    if reason is not None:
        stats.inconsistent_reasons[reason] += 1
        return "inconsistent_hand"
    if replay.blinds_posted != (True, True):
        stats.single_blind_hands += 1
    scale = hands.big_blind // 2  # replay chips are in small blinds
    if (replay.chips_in[0] * scale, replay.chips_in[1] * scale) != (in_a, in_b):
        stats.chips_mismatch_hands += 1
    hands.timestamps.append(timestamp)
    hands.replays.append(replay)
    hands.players += (first[0], second[0])
    hands.hole_cards += hole
    hands.boards += board + (-1,) * (5 - len(board))  # a fold's board stops where it ended
    hands.chips_in += (in_a, in_b)
    hands.chips_won += (won_a, won_b)
    return KEPT


# ---------------------------------------------------------------------------------------------
# Players' results


@dataclass(frozen=True, kw_only=True, eq=False)
class HeadsUpResults:
    """Every heads-up pdb line of one month, one entry per (player, hand): what the player
    put in and won, in big blinds. Every hand the player was dealt into counts, folds and
    unusable hands included: the table keeps only shown cards, and a player's winnings over
    showdowns alone would leave out every blind folded away."""

    timestamps: np.ndarray  # int64
    players: tuple[str, ...]
    net_bb: np.ndarray  # float64: (chips won - chips put in) / big blind

    def __len__(self) -> int:
        return len(self.players)


def heads_up_results(month: MonthFiles) -> HeadsUpResults:
    """The heads-up results the pdb files of ``month`` record (none for a channel that is
    not limit hold'em). A line that is not a readable pdb line is left out (``parse_month``
    counts it as malformed); a (player, hand) logged twice counts once."""
    big_blind = BIG_BLIND_BY_CHANNEL.get(month.channel)
    seen: set[tuple[str, int]] = set()
    stamps: list[int] = []
    players: list[str] = []
    net: list[int] = []
    for data in month.pdb.values() if big_blind is not None else ():
        for line in _lines(data):
            fields = line.split()
            if len(fields) not in (11, 13) or fields[2] != "2":
                continue
            stamp = _stamp(fields[1])
            chips_in, chips_won = fields[9], fields[10]
            if (
                stamp is None
                or len(chips_in) > _MAX_DIGITS
                or len(chips_won) > _MAX_DIGITS
                or not (chips_in.isdecimal() and chips_won.isdecimal())
                or (fields[0], stamp) in seen
            ):
                continue
            seen.add((fields[0], stamp))
            stamps.append(stamp)
            players.append(fields[0])
            net.append(int(chips_won) - int(chips_in))
    return HeadsUpResults(
        timestamps=np.array(stamps, dtype=np.int64),
        players=tuple(players),
        net_bb=np.array(net, dtype=np.float64) / (big_blind or 1),
    )
