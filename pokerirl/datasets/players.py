"""Which decisions an ingest keeps: a period of each month, cut by time, and the players
taken as the expert (by name, by hands played, by winnings), with what each filter kept.

A :class:`Selection` is what ``ingest_table(selection=...)`` and ``pokerirl ingest
--period/--player/--min-hands/--min-bb-per-100`` take. The period is a pair of fractions of
each month's hands in time order (every distinct hand of ``hdb``, at any table size), so
``Period(end=0.6)`` and ``Period(start=0.6)`` are the earlier and the later part of the same
months, disjoint and covering them. The players' statistics (hands played, big blinds won
per 100 hands) come from the heads-up pdb lines of the period alone: a later part is never
read when the expert is chosen on an earlier one.

>>> Period.parse("0:0.6")
Period(start=0.0, end=0.6)
>>> Period.parse("0:0.6").cut(np.arange(10, 20))
(None, 16)
>>> Period.parse("0.6:1").cut(np.arange(10, 20))
(16, None)
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
import pyarrow as pa

from pokerirl.errors import ConfigError
from pokerirl.parsers.irc import HeadsUpResults
from pokerirl.serial import Omit, Serializable, meta

# The drop reasons a selection adds to the summary's buckets.
OUTSIDE_PERIOD = "outside_period"
NOT_THE_EXPERT = "not_the_expert"


class Filter(enum.StrEnum):
    """The steps of a selection, in the order they apply."""

    ALL = "all"  # what the ingest keeps before any selection
    PERIOD = "period"
    PLAYERS = "players"  # by name
    MIN_HANDS = "min_hands"
    MIN_BB_PER_100 = "min_bb_per_100"


def _exact(value: float) -> Fraction:
    """``value`` as the decimal it was written as: 0.6 is 3/5, not the float below it, so
    ``0.6 * 10`` hands is 6."""
    return Fraction(repr(float(value)))


@dataclass(frozen=True, kw_only=True)
class Period(Serializable):
    """The hands of each month from fraction ``start`` (included) to ``end`` (excluded, the
    month's last hand included at 1) of its hands in time order."""

    start: float = 0.0
    end: float = 1.0

    def __post_init__(self) -> None:
        bounds = (self.start, self.end)
        finite = all(isinstance(v, int | float) and math.isfinite(v) for v in bounds)
        if not (finite and 0 <= self.start < self.end <= 1):
            raise ConfigError(
                f"period must be START:END with 0 <= START < END <= 1, got {self.start}:{self.end}"
            )
        object.__setattr__(self, "start", float(self.start))
        object.__setattr__(self, "end", float(self.end))

    @classmethod
    def parse(cls, text: str) -> Period:
        """``"0:0.6"`` -> ``Period(start=0.0, end=0.6)``; a one-line :class:`ConfigError`
        otherwise."""
        start, colon, end = text.partition(":")
        try:
            if not colon:
                raise ValueError
            bounds = float(start), float(end)
        except ValueError:
            raise ConfigError(
                f"period must be START:END, fractions of each month's hands by time "
                f"(0:0.6, 0.6:1), got {text!r}"
            ) from None
        return cls(start=bounds[0], end=bounds[1])

    @property
    def whole(self) -> bool:
        return self.start == 0 and self.end == 1

    def __str__(self) -> str:
        return f"{self.start:g}:{self.end:g}"

    def cut(self, timestamps: np.ndarray) -> tuple[int | None, int | None]:
        """The period of a month whose hands have ``timestamps``, as timestamps: the first
        one in it (None: from the start) and the first one after it (None: to the end).
        Hand ``i`` of ``n`` in time order is in it when ``floor(start n) <= i < floor(end
        n)``, so periods that meet at a fraction share no hand and miss none."""
        ordered = np.unique(timestamps)
        n = len(ordered)
        first = math.floor(_exact(self.start) * n)
        after = math.floor(_exact(self.end) * n)
        # start < 1, so first < n whenever there is a hand.
        return (
            None if first == 0 else int(ordered[first]),
            None if after >= n else int(ordered[after]),
        )


def in_period(timestamps: np.ndarray, cut: tuple[int | None, int | None]) -> np.ndarray:
    """Which of ``timestamps`` lie in a month's period, given as :meth:`Period.cut`."""
    first, after = cut
    inside = np.ones(len(timestamps), dtype=bool)
    if first is not None:
        inside &= timestamps >= first
    if after is not None:
        inside &= timestamps < after
    return inside


@dataclass(frozen=True, kw_only=True)
class Selection(Serializable):
    """What an ingest keeps: the ``period`` of each month, then, if any is given, the
    players named in ``players``, those who played at least ``min_hands`` heads-up hands in
    the period, and those who won at least ``min_bb_per_100`` big blinds per 100 of them
    (which needs ``min_hands``: over a few hands winnings are luck). The decisions kept are
    the selected players'. Names are kept sorted and once each, so the same players in
    another order are the same selection (and the same bytes)."""

    period: Period = field(default_factory=Period)
    players: tuple[str, ...] = ()
    min_hands: int | None = field(default=None, metadata=meta(omit=Omit.NONE))
    min_bb_per_100: float | None = field(default=None, metadata=meta(omit=Omit.NONE))

    def __post_init__(self) -> None:
        if isinstance(self.players, str):  # one name, not its letters
            raise ConfigError(f"players must be a list of names, got {self.players!r}")
        object.__setattr__(self, "players", tuple(sorted(set(self.players))))
        if self.min_hands is not None and (
            isinstance(self.min_hands, bool) or not isinstance(self.min_hands, int)
            or self.min_hands < 1
        ):  # fmt: skip
            raise ConfigError(f"min_hands must be a whole number >= 1, got {self.min_hands!r}")
        if self.min_bb_per_100 is not None:
            if not (
                isinstance(self.min_bb_per_100, int | float) and math.isfinite(self.min_bb_per_100)
            ):
                raise ConfigError(
                    f"min_bb_per_100 must be a finite number, got {self.min_bb_per_100!r}"
                )
            if self.min_hands is None:
                raise ConfigError(
                    "min_bb_per_100 needs min_hands (the hands the winnings are measured over)"
                )
            object.__setattr__(self, "min_bb_per_100", float(self.min_bb_per_100))

    @property
    def filters(self) -> tuple[Filter, ...]:
        """The steps this selection takes, in order (``all`` first)."""
        wanted = {
            Filter.PERIOD: not self.period.whole,
            Filter.PLAYERS: bool(self.players),
            Filter.MIN_HANDS: self.min_hands is not None,
            Filter.MIN_BB_PER_100: self.min_bb_per_100 is not None,
        }
        return (Filter.ALL, *(step for step, on in wanted.items() if on))

    @property
    def chooses_players(self) -> bool:
        return bool(self.players) or self.min_hands is not None


@dataclass(frozen=True, kw_only=True)
class FilterStep(Serializable):
    """What the table holds after one filter (and those before it)."""

    filter: Filter
    players: int  # players with at least one decision left
    hands: int  # hands with at least one decision left
    decisions: int


@dataclass(frozen=True, kw_only=True)
class MonthPeriod(Serializable):
    """The period of one month, as the hands it holds."""

    month: str
    hands: int  # distinct hands of the month's hdb
    period_hands: int  # those in the period
    first_timestamp: int | None  # the first hand in it; None: from the month's start
    after_timestamp: int | None  # the first hand after it; None: to the month's end


@dataclass(frozen=True, kw_only=True)
class SelectionSummary(Serializable):
    """The ``selection`` key of an ingest summary: the settings, each month's period, what
    each filter kept, in order, and the expert's names when players were chosen."""

    settings: Selection
    months: tuple[MonthPeriod, ...]
    steps: tuple[FilterStep, ...]
    expert: tuple[str, ...] = ()  # sorted; empty when no player filter was given


@dataclass(frozen=True, kw_only=True, eq=False)
class PlayerStats:
    """Heads-up hands played and big blinds won per player, in a period."""

    players: tuple[str, ...]  # sorted
    hands: np.ndarray  # int64
    net_bb: np.ndarray  # float64

    @property
    def bb_per_100(self) -> np.ndarray:
        return 100 * self.net_bb / np.maximum(self.hands, 1)

    @classmethod
    def of(cls, results: Sequence[HeadsUpResults]) -> PlayerStats:
        names = [name for part in results for name in part.players]
        players, ids = np.unique(np.array(names, dtype=object), return_inverse=True)
        net = np.concatenate([part.net_bb for part in results]) if results else np.zeros(0)
        return cls(
            players=tuple(players),
            hands=np.bincount(ids, minlength=len(players)).astype(np.int64),
            net_bb=np.bincount(ids, weights=net, minlength=len(players)),
        )

    def chosen(self, selection: Selection) -> dict[Filter, frozenset[str]]:
        """The players each player filter of ``selection`` keeps, with those before it."""
        keep = np.ones(len(self.players), dtype=bool)
        names = np.array(self.players, dtype=object)
        chosen: dict[Filter, frozenset[str]] = {}
        if selection.players:
            keep &= np.isin(names, np.array(selection.players, dtype=object))
            chosen[Filter.PLAYERS] = frozenset(names[keep])
        if selection.min_hands is not None:
            keep &= self.hands >= selection.min_hands
            chosen[Filter.MIN_HANDS] = frozenset(names[keep])
        if selection.min_bb_per_100 is not None:
            keep &= self.bb_per_100 >= selection.min_bb_per_100
            chosen[Filter.MIN_BB_PER_100] = frozenset(names[keep])
        return chosen


class Selector:
    """A :class:`Selection` applied month by month during an ingest: each month's table is
    cut to its period at once (:meth:`month`); the players are chosen when every month's
    statistics are in (:meth:`finish`), and the caller keeps their rows."""

    def __init__(self, selection: Selection) -> None:
        self.selection = selection
        self._months: list[MonthPeriod] = []
        self._results: list[HeadsUpResults] = []
        # Every kept row before the cut, for the steps' counts: (month, timestamp), player.
        self._hand_month: list[np.ndarray] = []
        self._hand_time: list[np.ndarray] = []
        self._player_ids: list[np.ndarray] = []
        self._inside: list[np.ndarray] = []
        self._ids: dict[str, int] = {}

    def month(
        self, key: str, hand_timestamps: np.ndarray, results: HeadsUpResults, table: pa.Table
    ) -> pa.Table:
        """``table``, one month's rows, cut to the period of the month whose distinct hands
        have ``hand_timestamps``; ``results`` are its heads-up pdb lines."""
        hands = np.unique(hand_timestamps)
        cut = self.selection.period.cut(hands)
        self._months.append(
            MonthPeriod(
                month=key,
                hands=len(hands),
                period_hands=int(in_period(hands, cut).sum()),
                first_timestamp=cut[0],
                after_timestamp=cut[1],
            )
        )
        inside_results = in_period(results.timestamps, cut)
        self._results.append(
            HeadsUpResults(
                timestamps=results.timestamps[inside_results],
                players=tuple(np.array(results.players, dtype=object)[inside_results]),
                net_bb=results.net_bb[inside_results],
            )
        )
        stamps = table.column("timestamp").to_numpy()
        inside = in_period(stamps, cut)
        self._hand_month.append(np.full(len(stamps), len(self._months), dtype=np.int64))
        self._hand_time.append(stamps)
        self._player_ids.append(self._player_codes(table.column("player")))
        self._inside.append(inside)
        return table if inside.all() else table.filter(pa.array(inside))

    def _player_codes(self, column: pa.ChunkedArray) -> np.ndarray:
        encoded = column.combine_chunks().dictionary_encode()
        lookup = np.array(
            [self._ids.setdefault(name, len(self._ids)) for name in encoded.dictionary.to_pylist()],
            dtype=np.int64,
        )
        indices = encoded.indices.to_numpy(zero_copy_only=False)
        return lookup[indices] if len(lookup) else np.zeros(0, dtype=np.int64)

    def finish(self) -> tuple[frozenset[str] | None, SelectionSummary]:
        """The expert's names (None: every player's rows are kept) and the summary."""
        chosen = PlayerStats.of(self._results).chosen(self.selection)
        hand_month = np.concatenate([np.zeros(0, np.int64), *self._hand_month])
        hand_time = np.concatenate([np.zeros(0, np.int64), *self._hand_time])
        player = np.concatenate([np.zeros(0, np.int64), *self._player_ids])
        keep = np.ones(len(player), dtype=bool)
        names = np.array(sorted(self._ids, key=self._ids.__getitem__), dtype=object)
        steps = []
        for step in self.selection.filters:
            if step is Filter.PERIOD:
                keep &= np.concatenate([np.zeros(0, bool), *self._inside])
            elif step is not Filter.ALL:
                wanted = np.array(sorted(chosen[step]), dtype=object)
                keep &= np.isin(names, wanted)[player] if len(names) else keep
            hands = np.unique(np.stack([hand_month[keep], hand_time[keep]]), axis=1)
            steps.append(
                FilterStep(
                    filter=step,
                    players=len(np.unique(player[keep])),
                    hands=hands.shape[1],
                    decisions=int(keep.sum()),
                )
            )
        expert = chosen[self.selection.filters[-1]] if self.selection.chooses_players else None
        kept_names = frozenset(names[np.unique(player[keep])]) if expert is not None else None
        summary = SelectionSummary(
            settings=self.selection,
            months=tuple(self._months),
            steps=tuple(steps),
            expert=tuple(sorted(kept_names or ())),
        )
        return expert, summary
