"""Reader for the University of Alberta IRC Poker Database.

A month of a channel is three things: ``hdb`` (one line per hand), ``hroster`` (the players of
each hand, in name order) and ``pdb/pdb.<nick>`` (one line per player and hand). Sources may be
month folders, folders of month folders, month archives (``holdem.199504.tgz``) or the whole
``IRCdata.tgz`` (archives inside an archive). Archives are streamed member by member and never
extracted; only one month is held in memory at a time.

:func:`iter_months` yields the raw files of each month; :func:`parse_month` turns one month into
the heads-up hands that can be learned from, and puts every hand of ``hdb`` into exactly one
bucket of :class:`IngestStats`.
"""

from __future__ import annotations

import os
import tarfile
from collections import Counter, defaultdict
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import IO

import numpy as np

from pokerirl.encoding import parse_card
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
_PROGRESS_EVERY = 8192
_ARCHIVE_SUFFIXES = (".tgz", ".tar.gz", ".tar")


class IngestError(Exception):
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

    def inconsistent(self, reason: str) -> None:
        self.buckets["inconsistent_hand"] += 1
        self.inconsistent_reasons[reason] += 1


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
    """The kept heads-up hands of one month, as parallel lists (one entry per hand)."""

    channel: str
    month: str
    big_blind: int
    timestamps: list[int] = field(default_factory=list)
    replays: list[Replay] = field(default_factory=list)
    players: list[tuple[str, str]] = field(default_factory=list)  # by position
    hole_cards: list[tuple[int, int, int, int]] = field(default_factory=list)  # -1: concealed
    boards: list[tuple[int, int, int, int, int]] = field(default_factory=list)
    chips_in: list[tuple[int, int]] = field(default_factory=list)
    chips_won: list[tuple[int, int]] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.timestamps)


# ---------------------------------------------------------------------------------------------
# Sources


def iter_months(sources: Sequence[str | os.PathLike[str]]) -> Iterator[MonthFiles]:
    """Yield every month found in ``sources``, in a deterministic order.

    Raises :class:`IngestError` for a source that is missing, unreadable or holds no IRC data.
    """
    for source in sources:
        path = Path(source)
        if not path.exists():
            raise IngestError(f"{path}: no such file or folder")
        if path.is_dir():
            yield from _iter_folder(path)
        elif path.name.endswith(_ARCHIVE_SUFFIXES):
            yield from _iter_archive_file(path)
        else:
            raise IngestError(
                f"{path}: not IRC data (expected a month folder, a folder of months, "
                "or a .tgz archive)"
            )


def _iter_folder(path: Path) -> Iterator[MonthFiles]:
    if (path / "hdb").is_file():
        yield _read_month_folder(path)
        return
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
    for item in sorted(found):
        if item.is_dir():
            yield _read_month_folder(item)
        else:
            yield from _iter_archive_file(item)


def _read_bytes(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError as error:
        raise IngestError(f"{path}: cannot read ({error.strerror})") from error


def _read_month_folder(path: Path) -> MonthFiles:
    resolved = path.resolve()
    channel, month = resolved.parent.name, resolved.name
    pdb_dir = path / "pdb"
    pdb: dict[str, bytes] = {}
    if channel in BIG_BLIND_BY_CHANNEL and pdb_dir.is_dir():
        for pdb_file in sorted(pdb_dir.iterdir()):
            if pdb_file.name.startswith("pdb.") and pdb_file.is_file():
                pdb[pdb_file.name] = _read_bytes(pdb_file)
    roster_path = path / "hroster"
    roster = _read_bytes(roster_path) if roster_path.is_file() else b""
    return MonthFiles(channel, month, str(path), _read_bytes(path / "hdb"), roster, pdb)


def _iter_archive_file(path: Path) -> Iterator[MonthFiles]:
    try:
        with open(path, "rb") as handle:
            yield from _iter_tar_stream(handle, str(path), path.name)
    except OSError as error:
        raise IngestError(f"{path}: cannot read ({error.strerror or error})") from error


def _hint_from_archive_name(name: str) -> tuple[str | None, str | None]:
    """``holdem.199504.tgz`` -> ("holdem", "199504")."""
    stem = name
    for suffix in _ARCHIVE_SUFFIXES:
        if stem.endswith(suffix):
            stem = stem[: -len(suffix)]
            break
    channel, _, month = stem.rpartition(".")
    if channel and month.isdigit():
        return channel, month
    return None, None


def _member_key(
    name: str, hint: tuple[str | None, str | None]
) -> tuple[str, str, str] | None:
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
    return channel, month, leaf


def _iter_tar_stream(fileobj: IO[bytes], origin: str, archive_name: str) -> Iterator[MonthFiles]:
    hint = _hint_from_archive_name(archive_name)
    current: tuple[str, str] | None = None
    files: dict[str, bytes] = {}

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

    try:
        # "r|*" streams: each member is read once, in order, with no seeking back.
        with tarfile.open(fileobj=fileobj, mode="r|*") as tar:
            for member in tar:
                if not member.isfile():
                    continue
                if member.name.endswith(_ARCHIVE_SUFFIXES):
                    yield from flush()
                    current, files = None, {}
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
                    current, files = (channel, month), {}
                if leaf.startswith("pdb.") and channel not in BIG_BLIND_BY_CHANNEL:
                    continue  # skipped channels only need their hdb, to count the hands
                extracted = tar.extractfile(member)
                if extracted is not None:
                    files[leaf] = extracted.read()
            yield from flush()
    except (tarfile.TarError, EOFError, OSError) as error:
        raise IngestError(f"{origin}: not a readable tar archive ({error})") from error


# ---------------------------------------------------------------------------------------------
# Parsing one month


def _lines(data: bytes) -> list[str]:
    # latin-1 never fails, and nicks may hold any byte; CRLF and LF both end lines.
    text = data.decode("latin-1")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return [line[:-1] if line.endswith("\r") else line for line in lines]


@dataclass(frozen=True, slots=True)
class _PdbLine:
    nick: str
    position: int
    actions: tuple[str, str, str, str]
    chips_in: int
    chips_won: int
    cards: tuple[int, int] | None


def _parse_pdb_line(fields: list[str]) -> _PdbLine:
    """Parse a heads-up pdb line; raise ValueError if it is malformed."""
    if len(fields) not in (11, 13):
        raise ValueError(f"expected 11 or 13 fields, got {len(fields)}")
    cards = None
    if len(fields) == 13:
        first, second = parse_card(fields[11]), parse_card(fields[12])
        if first == second:
            raise ValueError("the same hole card twice")
        cards = (first, second)
    chips_in, chips_won = int(fields[9]), int(fields[10])
    int(fields[8])  # bankroll: must be a number
    if chips_in < 0 or chips_won < 0:
        raise ValueError("negative chips")
    return _PdbLine(
        nick=fields[0],
        position=int(fields[3]),
        actions=(fields[4], fields[5], fields[6], fields[7]),
        chips_in=chips_in,
        chips_won=chips_won,
        cards=cards,
    )


def _read_pdb(
    month: MonthFiles, stats: IngestStats
) -> tuple[dict[int, list[_PdbLine]], set[int]]:
    """Heads-up pdb lines by timestamp, and the timestamps that had a malformed heads-up line."""
    by_hand: dict[int, list[_PdbLine]] = defaultdict(list)
    malformed_hands: set[int] = set()
    for file_name, data in month.pdb.items():
        where = f"{month.origin}/pdb/{file_name}"
        for number, line in enumerate(_lines(data), start=1):
            fields = line.split()
            if len(fields) < 11 or not fields[1].isdigit() or not fields[2].isdigit():
                stats.malformed(f"{where}:{number}", "not a pdb line")
                continue
            if fields[2] != "2":
                continue
            timestamp = int(fields[1])
            try:
                by_hand[timestamp].append(_parse_pdb_line(fields))
            except ValueError as error:
                stats.malformed(f"{where}:{number}", str(error))
                malformed_hands.add(timestamp)
    return by_hand, malformed_hands


def _read_roster(month: MonthFiles, stats: IngestStats) -> dict[int, tuple[str, ...]]:
    roster: dict[int, tuple[str, ...]] = {}
    for number, line in enumerate(_lines(month.hroster), start=1):
        fields = line.split()
        if len(fields) < 2 or not fields[0].isdigit() or not fields[1].isdigit():
            stats.malformed(f"{month.origin}/hroster:{number}", "not an hroster line")
            continue
        roster[int(fields[0])] = tuple(fields[2:])
    return roster


def parse_month(
    month: MonthFiles,
    stats: IngestStats,
    seen: dict[str, np.ndarray],
    on_hands: Callable[[int], None] | None = None,
) -> MonthHands:
    """Parse one month: count every hdb line into a bucket and return the kept hands.

    ``seen`` maps each month key (``channel/month``) to the timestamps already read and is
    updated, so a hand given twice, in one hdb or in two sources, is a ``duplicate_hand``.
    ``on_hands(n)`` is called as hdb lines are read, for progress bars.
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

    pdb, malformed_pdb = _read_pdb(month, stats)
    roster = _read_roster(month, stats)
    used_pdb: set[int] = set()
    hdb_where = f"{month.origin}/hdb"
    timestamps: set[int] = set(seen[month.key].tolist()) if month.key in seen else set()

    parsed: list[tuple[int, list[str]]] = []
    for number, line in enumerate(hdb_lines, start=1):
        if on_hands is not None and number % _PROGRESS_EVERY == 0:
            on_hands(_PROGRESS_EVERY)
        fields = line.split()
        board_size = len(fields) - 8
        if (
            board_size not in (0, 3, 4, 5)
            or not fields[0].isdigit()
            or not fields[3].isdigit()
            or not all("/" in pot for pot in fields[4:8])
        ):
            stats.malformed(f"{hdb_where}:{number}", "not an hdb line")
            stats.drop("malformed_line")
            continue
        timestamp = int(fields[0])
        if timestamp in timestamps:
            stats.drop("duplicate_hand")
            continue
        timestamps.add(timestamp)
        if fields[3] != "2":
            stats.drop("not_heads_up")
            continue
        stats.heads_up_hands += 1
        parsed.append((number, fields))

    # Sorting by timestamp makes the table's order independent of the hdb's line order.
    parsed.sort(key=lambda item: int(item[1][0]))
    for number, fields in parsed:
        timestamp = int(fields[0])
        used_pdb.add(timestamp)
        try:
            board = tuple(parse_card(card) for card in fields[8:])
        except ValueError as error:
            stats.malformed(f"{hdb_where}:{number}", str(error))
            stats.drop("malformed_line")
            continue
        _classify_hand(
            timestamp, board, pdb.get(timestamp, []), timestamp in malformed_pdb,
            roster.get(timestamp), hands, stats,
        )
    stats.orphan_pdb_lines += sum(len(v) for k, v in pdb.items() if k not in used_pdb)
    seen[month.key] = np.fromiter(timestamps, dtype=np.int64, count=len(timestamps))
    if on_hands is not None:
        on_hands(len(hdb_lines) % _PROGRESS_EVERY)
    return hands


def _classify_hand(
    timestamp: int,
    board: tuple[int, ...],
    lines: list[_PdbLine],
    has_malformed_line: bool,
    roster_names: tuple[str, ...] | None,
    hands: MonthHands,
    stats: IngestStats,
) -> None:
    """Put one heads-up hand into its bucket, appending it to ``hands`` if it is kept."""
    if has_malformed_line:
        stats.drop("malformed_line")
        return
    if len(lines) < 2:
        stats.drop("missing_pdb_line")
        return
    nicks = {line.nick for line in lines}
    if len(lines) > 2 or roster_names is None or len(nicks) != 2 or set(roster_names) != nicks:
        stats.drop("roster_mismatch")
        return
    by_position = sorted(lines, key=lambda line: line.position)
    first, second = by_position
    if (first.position, second.position) != (1, 2):
        stats.inconsistent("positions are not 1 and 2")
        return
    try:
        interleaved = tuple(a for pair in zip(first.actions, second.actions) for a in pair)
        replay = replay_actions(interleaved)  # type: ignore[arg-type]
    except ReplayError as error:
        stats.inconsistent(f"actions: {error}")
        return
    if not replay.showdown or (first.cards is None and second.cards is None):
        stats.drop("cards_concealed")
        return
    if len(board) != 5:
        stats.inconsistent("showdown without five board cards")
        return
    chips_in = (first.chips_in, second.chips_in)
    chips_won = (first.chips_won, second.chips_won)
    if sum(chips_in) != sum(chips_won):
        stats.inconsistent("chips won differ from chips put in")
        return
    hole = (first.cards or (-1, -1)) + (second.cards or (-1, -1))
    known = [card for card in hole + board if card >= 0]
    if len(set(known)) != len(known):
        stats.inconsistent("a card dealt twice")
        return
    if replay.blinds_posted != (True, True):
        stats.single_blind_hands += 1
    scale = hands.big_blind // 2  # replay chips are in small blinds
    if tuple(c * scale for c in replay.chips_in) != chips_in:
        stats.chips_mismatch_hands += 1
    stats.drop(KEPT)
    hands.timestamps.append(timestamp)
    hands.replays.append(replay)
    hands.players.append((first.nick, second.nick))
    hands.hole_cards.append(hole)  # type: ignore[arg-type]
    hands.boards.append(board)  # type: ignore[arg-type]
    hands.chips_in.append(chips_in)
    hands.chips_won.append(chips_won)
