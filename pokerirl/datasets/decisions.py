"""Read a poker decision table (Parquet, one row per decision) into validated numpy arrays.

Only the columns the trainer needs are read, and each goes pyarrow -> numpy through its flat
child array, without per-row Python. Problems with the table raise ``ValueError`` with a
one-line message naming it. The arrays are what :meth:`pokerirl.irl.Transitions.from_arrays`
takes; :func:`pokerirl.poker.read_table` makes the :class:`~pokerirl.irl.Transitions` (this
layer is below ``irl/``, which knows nothing of poker).

Required columns: ``hand_id`` (string), ``obs`` (fixed_size_list<uint8>[72]), ``action_id``
(integer), ``legal_mask`` (fixed_size_list<bool>[4]). Optional: ``reward`` (float; payoff in
big blinds on the player's last decision of a hand, else 0) and ``player`` (string), which
gives next_obs (the same player's next decision in the hand) and done (their last one).

Optional columns of ``pokerirl ingest --folds impute`` (docs/folds.md): ``weight`` (float: the
row's weight in every mean), ``imputed`` (bool: its hole cards are a posterior draw) and
``imputation`` (integer: which draw, 0 for observed rows); a player's next decision is then
looked up within the same draw.

A table's ``obs`` column is RLCard's 72-d observation (read only for that encoding). Another
encoding (:mod:`pokerirl.game.encodings`) is computed on reading from the columns that hold
the state apart: ``hole_cards`` and ``board`` (texts) and ``raise_nums``; a table without them
cannot give it, and is refused in one line.

:func:`read_data` is the one reader: a :class:`Table` holds the arrays and their
:class:`~pokerirl.game.spec.TableSpec` (the game, the encoding), from a hold'em table or from
Leduc demonstrations (``pokerirl leduc synth``'s ``.npz``).

>>> from pokerirl.datasets.toy import toy_expert_table
>>> decisions = decisions_from_arrow(toy_expert_table(num_hands=20, seed=1))
>>> decisions.obs.shape[1], decisions.num_actions, decisions.dones is not None
(72, 4, True)
>>> decisions.spec.game, decisions.spec.encoding
(<GameName.HOLDEM: 'holdem'>, 'rlcard')
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from pokerirl.errors import InputError
from pokerirl.game.encodings import RLCARD, Encoding, EncodingName, RawStates
from pokerirl.game.spec import LEDUC, GameName, TableSpec, holdem_spec
from pokerirl.holdem import NUM_ACTIONS, NUM_ROUNDS, OBS_SIZE, cards_from_text
from pokerirl.parquet import fixed_width, read_parquet

if TYPE_CHECKING:
    from pokerirl.game.leduc.demos import Demonstrations

REQUIRED_COLUMNS = ("hand_id", "obs", "action_id", "legal_mask")
OPTIONAL_COLUMNS = ("reward", "player")
IMPUTATION_COLUMNS = ("weight", "imputed", "imputation")  # ingest --folds impute
STATE_COLUMNS = ("hole_cards", "board", "raise_nums")  # what other encodings are computed from
TABLE_ENCODING = RLCARD  # a hold'em table's states, unless told: its obs column as it is


@dataclass(frozen=True, kw_only=True, eq=False)
class Table:
    """A validated table of decisions as numpy arrays, one row per expert decision, and what
    it is of (``spec``: the game, the encoding of ``obs``, the actions)."""

    spec: TableSpec
    obs: np.ndarray  # (N, spec.width): (N, 72) uint8 for hold'em's rlcard
    action_ids: np.ndarray  # (N,) int64, legal under legal_mask
    groups: np.ndarray  # (N,) hand ids (strings)
    legal_mask: np.ndarray  # (N, spec.num_actions) bool
    next_obs: np.ndarray | None = None  # (N, spec.width): the same player's next decision
    dones: np.ndarray | None = None  # (N,) bool: the player's last decision of the hand
    rewards: np.ndarray | None = None  # (N,) float32
    weights: np.ndarray | None = None  # (N,) float32 > 0, from a ``weight`` column
    imputed: np.ndarray | None = None  # (N,) bool, from an ``imputed`` column

    @property
    def num_actions(self) -> int:
        return self.spec.num_actions


def table_cards(table: pa.Table, source: str) -> np.ndarray:
    """(N, 7) int8 cards of a table's ``hole_cards`` and ``board`` texts (``-1`` not shown);
    :class:`InputError` naming ``source`` for a text that is not cards."""
    hole, board = (table.column(c).to_pylist() for c in ("hole_cards", "board"))
    try:
        return cards_from_text(hole, board)
    except ValueError as error:
        raise InputError(f"{source}: {error} in hole_cards or board") from None


def check_legal_actions(actions: np.ndarray, legal_mask: np.ndarray, source: str) -> None:
    """Refuse, in one line naming ``source``, action ids outside the legal mask's columns,
    rows with no legal action, and actions their row's legal mask forbids."""
    count = legal_mask.shape[1]
    if len(actions) and (actions.min() < 0 or actions.max() >= count):
        raise InputError(f"{source}: 'action_id' must lie in 0..{count - 1}")
    empty = ~legal_mask.any(axis=1)
    if empty.any():
        bad = int(empty.sum())
        raise InputError(f"{source}: {bad} row(s) have no legal action in 'legal_mask'")
    illegal = ~legal_mask[np.arange(len(actions)), actions]
    if illegal.any():
        raise InputError(
            f"{source}: {int(illegal.sum())} row(s) take an action their 'legal_mask' forbids"
        )


def read_data(path: str | os.PathLike[str], *, encoding: Encoding | None = None) -> Table:
    """The decisions at ``path``, validated, with their game: Leduc demonstrations (the
    ``.npz`` of ``pokerirl leduc synth``, in their one encoding) or a hold'em decision table
    (:func:`read_decisions`, its states in ``encoding``). Raises ``FileNotFoundError`` for a
    missing file and ``ValueError`` for anything else wrong."""
    source = Path(path)
    if data_game(source) is GameName.LEDUC:
        if encoding is not None:
            raise InputError(
                f"{source}: Leduc demonstrations are in their one encoding "
                f"({LEDUC.encoding}), not {encoding.spec}"
            )
        return leduc_table(source)
    return read_decisions(source, encoding=encoding)


def data_game(path: str | os.PathLike[str]) -> GameName:
    """The game of the decisions at ``path``: Leduc for an ``.npz`` (a zip file: Leduc
    demonstrations), else hold'em (a Parquet table, whose reader says what else is wrong)."""
    try:
        with Path(path).open("rb") as stream:
            return GameName.LEDUC if stream.read(4) == b"PK\x03\x04" else GameName.HOLDEM
    except OSError:  # missing, a folder: the Parquet reader says so in its words
        return GameName.HOLDEM


def leduc_table(path: Path) -> Table:
    """The Leduc demonstrations file at ``path`` (:func:`pokerirl.game.leduc.demos.load`) as
    a :class:`Table`."""
    from pokerirl.game.leduc.demos import load

    demos = load(path)
    if len(demos) == 0:
        raise InputError(f"{path} is empty: no expert decisions to learn from")
    check_legal_actions(demos.action, demos.legal, str(path))
    return demos_table(demos)


def demos_table(demos: Demonstrations) -> Table:
    """Leduc demonstrations as a :class:`Table`, one group per hand (a split keeps the hands'
    order of appearance, so the ids' type changes no split)."""
    return Table(
        spec=LEDUC, obs=demos.obs, action_ids=demos.action, groups=demos.hand.astype(str),
        legal_mask=demos.legal, next_obs=demos.next_obs, dones=demos.done, rewards=demos.reward,
    )  # fmt: skip


def read_decisions(path: str | os.PathLike[str], *, encoding: Encoding | None = None) -> Table:
    """Read and validate the hold'em decision table at ``path``, its states in ``encoding``
    (default :data:`TABLE_ENCODING`: the ``obs`` column as it is).

    Raises ``FileNotFoundError`` for a missing file and ``ValueError`` for anything else wrong
    (not Parquet, missing columns, wrong types or widths, nulls, empty, illegal expert actions).
    """
    optional = (*OPTIONAL_COLUMNS, *STATE_COLUMNS, *IMPUTATION_COLUMNS)
    table = read_parquet(path, REQUIRED_COLUMNS, optional, what="table")
    return decisions_from_arrow(table, source=str(Path(path)), encoding=encoding)


def decisions_from_arrow(
    table: pa.Table, *, source: str = "table", encoding: Encoding | None = None
) -> Table:
    """Validate an Arrow table with the decision-table schema and convert it."""
    chosen = TABLE_ENCODING if encoding is None else encoding
    if table.num_rows == 0:
        raise InputError(f"{source} is empty: no expert decisions to learn from")
    for name in (*REQUIRED_COLUMNS, *OPTIONAL_COLUMNS, *IMPUTATION_COLUMNS):
        if name in table.column_names and table.column(name).null_count:
            raise InputError(f"{source}: column {name!r} has null values")
    hand = _strings(table, "hand_id", source)
    mask = fixed_width(table, "legal_mask", NUM_ACTIONS, source).astype(bool, copy=False)

    action = table.column("action_id")
    if not pa.types.is_integer(action.type):
        raise InputError(f"{source}: column 'action_id' must be integer, got {action.type}")
    action_ids = action.to_numpy().astype(np.int64)
    check_legal_actions(action_ids, mask, source)

    rewards = None
    if "reward" in table.column_names:
        reward = table.column("reward")
        if not pa.types.is_floating(reward.type) and not pa.types.is_integer(reward.type):
            raise InputError(f"{source}: column 'reward' must be numeric, got {reward.type}")
        rewards = reward.to_numpy().astype(np.float32)

    weights, imputed, draw = _imputation_columns(table, source)
    if chosen.name == EncodingName.RLCARD:  # the obs column is read only when it is the states
        obs = fixed_width(table, "obs", OBS_SIZE, source).astype(np.uint8, copy=False)
    else:
        obs = chosen.encode(table_states(table, mask, source, chosen.name))
    next_obs = dones = None
    if "player" in table.column_names:
        player = _strings(table, "player", source)
        following = next_decision(hand.indices, player.indices, draw)
        dones = following < 0
        next_obs = obs[np.where(dones, np.arange(len(obs)), following)]

    return Table(
        spec=holdem_spec(chosen),
        obs=obs,
        action_ids=action_ids,
        groups=np.asarray(hand.dictionary.to_numpy(zero_copy_only=False))[hand.indices],
        legal_mask=mask,
        next_obs=next_obs,
        dones=dones,
        rewards=rewards,
        weights=weights,
        imputed=imputed,
    )


def _imputation_columns(
    table: pa.Table, source: str
) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """(weights, imputed, draw) from the optional columns of an imputed table, or Nones."""
    names = table.column_names
    weights = imputed = draw = None
    if "weight" in names:
        column = table.column("weight")
        if not pa.types.is_floating(column.type):
            raise InputError(f"{source}: column 'weight' must be float, got {column.type}")
        weights = column.to_numpy().astype(np.float32)
        if not (np.isfinite(weights).all() and (weights > 0).all()):
            raise InputError(f"{source}: column 'weight' must hold finite positive numbers")
    if "imputed" in names:
        column = table.column("imputed")
        if not pa.types.is_boolean(column.type):
            raise InputError(f"{source}: column 'imputed' must be bool, got {column.type}")
        imputed = column.to_numpy(zero_copy_only=False).astype(bool)
    if "imputation" in names:
        column = table.column("imputation")
        if not pa.types.is_integer(column.type):
            raise InputError(f"{source}: column 'imputation' must be integer, got {column.type}")
        draw = column.to_numpy().astype(np.int64)
    return weights, imputed, draw


def table_states(table: pa.Table, legal_mask: np.ndarray, source: str, why: str) -> RawStates:
    """The decision states of a table's rows, from its ``hole_cards``, ``board`` and
    ``raise_nums`` columns; one line naming ``why`` (the encoding) when it lacks them."""
    missing = [name for name in STATE_COLUMNS if name not in table.column_names]
    if missing:
        raise InputError(
            f"{source} has no {', '.join(missing)} column(s): the {why} encoding is computed "
            "from them (a table of pokerirl ingest has them)"
        )
    for name in STATE_COLUMNS:
        if table.column(name).null_count:
            raise InputError(f"{source}: column {name!r} has null values")
    cards = table_cards(table, source)
    if (cards[:, 0] < 0).any():
        row = int(np.flatnonzero(cards[:, 0] < 0)[0])
        raise InputError(f"{source}: row {row} has no hole cards (concealed decisions are none)")
    raise_nums = fixed_width(table, "raise_nums", NUM_ROUNDS, source)
    return RawStates(cards=cards, raise_nums=raise_nums, legal_mask=legal_mask)


class _Encoded:
    def __init__(self, indices: np.ndarray, dictionary: pa.Array) -> None:
        self.indices, self.dictionary = indices, dictionary


def _strings(table: pa.Table, name: str, source: str) -> _Encoded:
    column = table.column(name)
    if not (pa.types.is_string(column.type) or pa.types.is_large_string(column.type)):
        raise InputError(f"{source}: column {name!r} must be string, got {column.type}")
    encoded = pc.dictionary_encode(column.combine_chunks())
    indices = encoded.indices.to_numpy(zero_copy_only=False).astype(np.int64)
    return _Encoded(indices, encoded.dictionary)


def next_decision(
    hand: np.ndarray, player: np.ndarray, draw: np.ndarray | None = None
) -> np.ndarray:
    """Per row, the row of the same player's next decision in the same hand (and the same
    imputation ``draw``, when given), or -1.

    Rows of a hand are in decision order, as ``pokerirl ingest`` writes them.

    >>> next_decision(np.array([0, 0, 0, 0, 1]), np.array([0, 1, 0, 1, 0])).tolist()
    [2, 3, -1, -1, -1]
    >>> next_decision(np.array([0, 0, 0, 0]), np.zeros(4, int), np.array([1, 2, 1, 2])).tolist()
    [2, 3, -1, -1]
    """
    key = hand * (int(player.max()) + 1) + player
    if draw is not None:
        key = key * (int(draw.max()) + 1) + draw
    order = np.argsort(key, kind="stable")  # rows of one (hand, player), in table order
    same = key[order[1:]] == key[order[:-1]]
    following = np.full(len(key), -1, dtype=np.int64)
    following[order[:-1][same]] = order[1:][same]
    return following
