"""Synthetic IRC Poker Database months: heads-up 10-20 limit hold'em between two scripted players.

The hands follow the IRC logs' conventions, not RLCard's: position 1 posts the small blind and
acts first on every street, there is no raise cap, and hole cards appear only for players who
reach showdown. The players' rule is known, which makes the output a test bed for reward learning:

- a visible-strength score ``s`` in [0, 1] is computed from the hole cards and the board shown
  so far (pairs with the board, pocket pairs, high cards);
- with probability ``1 - noise`` a player raises when ``s > raise_above`` (at most
  ``max_raises`` raises per street), otherwise calls a bet when ``s > call_above``, otherwise
  checks or folds; with probability ``noise`` it picks uniformly among those options.

>>> import tempfile
>>> month = write_synthetic_month(tempfile.mkdtemp(), hands=20, seed=1)
>>> sorted(p.name for p in month.iterdir())
['hdb', 'hroster', 'pdb']
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from pokerirl.errors import ConfigError
from pokerirl.game.evaluator import hand_strength
from pokerirl.holdem import card_str

SMALL_BLIND, BIG_BLIND = 5, 10
BET_BY_STREET = (10, 10, 20, 20)
FIRST_TIMESTAMP = 978_307_200  # 2001-01-01 00:00 UTC
SECONDS_PER_HAND = 60
STARTING_BANKROLL = 1000
# One month is built in memory (about 1.7 GB at this size) and must stay within ingest's caps
# (pokerirl.parsers.irc_sources.MAX_FILE_BYTES: 1M hands make a 68 MB hdb).
MAX_HANDS = 1_000_000


@dataclass(frozen=True)
class ScriptedPlayer:
    """A threshold player; see the module docstring."""

    nick: str
    raise_above: float
    call_above: float
    noise: float = 0.05
    max_raises: int = 3


DEFAULT_PLAYERS = (
    ScriptedPlayer(nick="TightBot", raise_above=0.62, call_above=0.30),
    ScriptedPlayer(nick="LooseBot", raise_above=0.50, call_above=0.18),
)


def visible_strength(hole: np.ndarray, board: np.ndarray) -> np.ndarray:
    """Strength score in [0, 1] on every street, from the cards a player can see.

    Args:
        hole: (N, 2) card indices.
        board: (N, 5) card indices.

    Returns:
        (N, 4) float, one score per street (preflop, flop, turn, river).
    """
    # Ace high: 0 for a deuce .. 12 for an ace.
    hole_ranks = (hole % 13 - 1) % 13
    board_ranks = (board % 13 - 1) % 13
    high, low = hole_ranks.max(axis=1) / 12, hole_ranks.min(axis=1) / 12
    pocket = hole_ranks[:, 0] == hole_ranks[:, 1]
    suited = hole[:, 0] // 13 == hole[:, 1] // 13
    strength = np.empty((hole.shape[0], 4))
    strength[:, 0] = np.where(pocket, 0.55 + 0.45 * high, 0.35 * high + 0.2 * low + 0.08 * suited)
    for street, shown in ((1, 3), (2, 4), (3, 5)):
        visible = board_ranks[:, :shown]
        hits = (visible[:, None, :] == hole_ranks[:, :, None]).sum(axis=2)  # (N, 2)
        paired = (hits > 0).sum(axis=1)
        trips = (hits >= 2).any(axis=1) | (pocket & (hits[:, 0] > 0))
        top_pair = (hits > 0).any(axis=1) & (hole_ranks.max(axis=1) >= visible.max(axis=1))
        strength[:, street] = np.clip(
            0.1
            + 0.3 * (paired >= 1)
            + 0.2 * (paired == 2)
            + 0.3 * trips
            + 0.15 * top_pair
            + 0.3 * pocket
            + 0.1 * high,
            0.0,
            1.0,
        )
    return strength


def write_synthetic_month(
    out_dir: str | os.PathLike[str],
    *,
    hands: int,
    seed: int,
    players: tuple[ScriptedPlayer, ScriptedPlayer] = DEFAULT_PLAYERS,
    reveal_all: bool = False,
) -> Path:
    """Write ``hands`` heads-up hands as ``out_dir/holdem/<YYYYMM>/``; return that folder.

    ``reveal_all`` writes every player's hole cards in ``pdb``, in hands that end in a fold
    too (real logs show them only at showdown), so that ingest keeps every hand: the truth
    against which a reward learned from showdowns alone is scored. The deals and the bots'
    actions are the same as without it, for the same seed.

    Raises:
        ValueError: one line, for ``hands`` outside [1, :data:`MAX_HANDS`] or a negative seed.
    """
    if not 1 <= hands <= MAX_HANDS:
        raise ConfigError(f"hands must be between 1 and {MAX_HANDS:,} (one month), got {hands}")
    if seed < 0:
        raise ConfigError(f"seed must be non-negative, got {seed}")
    rng = np.random.default_rng(seed)
    deals = rng.random((hands, 52)).argsort(axis=1)[:, :9].astype(np.int64)
    # Player 0 of the pair sits in position 1 on even hands; the button alternates.
    seat_of_player0 = np.arange(hands) % 2
    holes = np.stack([deals[:, 0:2], deals[:, 2:4]], axis=1)  # (N, position, 2)
    boards = deals[:, 4:9]
    strength = np.stack([visible_strength(holes[:, p], boards) for p in (0, 1)], axis=1)
    final = np.stack(
        [hand_strength(np.concatenate([holes[:, p], boards], axis=1)) for p in (0, 1)], axis=1
    )
    uniforms = rng.random((hands, 64))

    month = datetime.fromtimestamp(FIRST_TIMESTAMP, UTC).strftime("%Y%m")
    folder = Path(out_dir) / "holdem" / month
    (folder / "pdb").mkdir(parents=True, exist_ok=True)
    hdb_lines: list[str] = []
    roster_lines: list[str] = []
    pdb_lines: dict[str, list[str]] = {p.nick: [] for p in players}
    bankroll = {p.nick: STARTING_BANKROLL for p in players}

    for hand in range(hands):
        timestamp = FIRST_TIMESTAMP + SECONDS_PER_HAND * hand
        by_position = (
            (players[0], players[1]) if seat_of_player0[hand] == 0 else (players[1], players[0])
        )
        outcome = _play_hand(by_position, strength[hand], uniforms[hand])
        streets_seen = outcome.streets_seen
        pot_at = [0, 0, 0, 0]
        for street in range(1, streets_seen):
            pot_at[street] = outcome.pot_before_street[street]
        board_shown = (0, 3, 4, 5)[streets_seen - 1]
        if outcome.folder is None:
            order = np.sign(final[hand, 0] - final[hand, 1])
            winners = [0] if order > 0 else [1] if order < 0 else [0, 1]
        else:
            winners = [1 - outcome.folder]
        pot = sum(outcome.chips_in)
        won = [0, 0]
        for w in winners:
            won[w] = pot // len(winners)
        street_fields = [f"2/{pot_at[s]}" if s < streets_seen else "0/0" for s in (1, 2, 3)]
        showdown_field = f"2/{pot}" if outcome.folder is None else f"1/{pot}"
        board_text = " ".join(card_str(c) for c in boards[hand, :board_shown])
        hdb_lines.append(
            f"{timestamp}   1 {hand + 1:5d}  2  {street_fields[0]:<7} {street_fields[1]:<7} "
            f"{street_fields[2]:<8} {showdown_field:<8} {board_text}".rstrip()
        )
        roster_lines.append(f"{timestamp}  2 " + " ".join(sorted(p.nick for p in players)))
        for position, player in enumerate(by_position):
            cards = ""
            if outcome.folder is None or reveal_all:
                cards = " " + " ".join(card_str(c) for c in holes[hand, position])
            actions = [a if a else "-" for a in outcome.actions[position]]
            pdb_lines[player.nick].append(
                f"{player.nick:<9} {timestamp}  2 {position + 1:2d} {actions[0]:<3} "
                f"{actions[1]:<5} {actions[2]:<5} {actions[3]:<5} {bankroll[player.nick]:6d} "
                f"{outcome.chips_in[position]:5d} {won[position]:5d}{cards}"
            )
            bankroll[player.nick] += won[position] - outcome.chips_in[position]

    # The real logs end lines with CRLF; so do we.
    (folder / "hdb").write_text("\r\n".join(hdb_lines) + "\r\n", encoding="latin-1")
    (folder / "hroster").write_text("\r\n".join(roster_lines) + "\r\n", encoding="latin-1")
    for nick, lines in pdb_lines.items():
        (folder / "pdb" / f"pdb.{nick}").write_text("\r\n".join(lines) + "\r\n", encoding="latin-1")
    return folder


@dataclass
class _Outcome:
    actions: list[list[str]]  # [position][street] action string
    chips_in: list[int]
    folder: int | None
    streets_seen: int
    pot_before_street: list[int]


def _play_hand(
    by_position: tuple[ScriptedPlayer, ScriptedPlayer],
    strength: np.ndarray,
    uniforms: np.ndarray,
) -> _Outcome:
    """Play one hand with IRC conventions: position 1 first on every street, no raise cap."""
    actions = [["B", "", "", ""], ["B", "", "", ""]]
    chips_in = [SMALL_BLIND, BIG_BLIND]
    pot_before = [0, 0, 0, 0]
    draw = iter(uniforms)
    for street in range(4):
        pot_before[street] = sum(chips_in)
        street_in = [SMALL_BLIND, BIG_BLIND] if street == 0 else [0, 0]
        to_act = [True, True]
        raises = 0
        seat = 0
        while to_act[0] or to_act[1]:
            if not to_act[seat]:
                seat = 1 - seat
                continue
            player = by_position[seat]
            facing = street_in[1 - seat] > street_in[seat]
            score = strength[seat, street]
            options: list[str | None] = ["c" if facing else "k", "f" if facing else None]
            can_raise = raises < player.max_raises
            if can_raise:
                options.append("b" if raises == 0 and street > 0 else "r")
            if next(draw) < player.noise:
                choices = [o for o in options if o is not None]
                code = choices[int(next(draw) * len(choices))]
            elif can_raise and score > player.raise_above:
                code = str(options[2])
            elif not facing or score > player.call_above:
                code = str(options[0])
            else:
                code = "f"
            actions[seat][street] += code
            to_act[seat] = False
            if code == "f":
                return _Outcome(actions, chips_in, seat, street + 1, pot_before)
            if code == "c":
                chips_in[seat] += street_in[1 - seat] - street_in[seat]
                street_in[seat] = street_in[1 - seat]
            elif code in "br":
                level = max(street_in) + BET_BY_STREET[street]
                chips_in[seat] += level - street_in[seat]
                street_in[seat] = level
                raises += 1
                to_act[1 - seat] = True
            seat = 1 - seat
    return _Outcome(actions, chips_in, None, 4, pot_before)
