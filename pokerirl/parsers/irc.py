"""Parser of the University of Alberta IRC Poker Database.

A month of a channel is three things: ``hdb`` (one line per hand), ``hroster`` (the players of
each hand, in name order) and ``pdb/pdb.<nick>`` (one line per player and hand);
:mod:`pokerirl.parsers.irc_sources` reads them from folders and archives, bounded in size.
:func:`parse_month` turns one month into the heads-up hands that can be learned from, and puts
every hand of ``hdb`` into exactly one bucket of :class:`IngestStats`;
:func:`heads_up_results` reads every heads-up pdb line's result.
"""

from __future__ import annotations

import bisect
import gc
from collections import Counter, defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from pokerirl.holdem import BOARD_SIZE_BY_ROUND, CARD_INDEX
from pokerirl.parsers.irc_sources import BIG_BLIND_BY_CHANNEL, IngestError, MonthFiles
from pokerirl.parsers.replay import Replay, ReplayError, replay_actions

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
