"""Exact equity (``pokerirl.game.equity``) against brute-force enumerations: the river and the
turn by eval7 (an independent evaluator), the flop table by the engine's seven-card
evaluator over all 1,070,190 cases of a state, the preflop classes from the flop table and
published figures; and the strength encoding's versions."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from equity_reference import engine_flop_count, eval7_cards, eval7_count

from pokerirl.errors import InputError
from pokerirl.game.cases import PREFLOP_DENOMINATOR
from pokerirl.game.encodings import (
    STRENGTH,
    STRENGTH_V1,
    RawStates,
    get_encoding,
    recorded_encoding,
)
from pokerirl.game.equity import (
    _PERMUTED_CARD,
    FLOP_CLASSES,
    FLOP_DENOMINATOR,
    RIVER_DENOMINATOR,
    TURN_CLASSES,
    TURN_DENOMINATOR,
    _class_counts,
    _set_code,
    all_pairs_turn_counts,
    board_classes,
    exact_equity,
    flop_counts,
    flop_table,
    hole_counts,
    preflop_counts,
    river_counts,
    table_digest,
    turn_counts,
)
from pokerirl.game.evaluator import pair_index
from pokerirl.game.preflop import PREFLOP_COUNTS, class_index, preflop_equity
from pokerirl.holdem import NUM_PAIRS, PAIRS, parse_card

eval7 = pytest.importorskip("eval7")


def _random_states(n: int, seed: int, board: int) -> tuple[np.ndarray, np.ndarray]:
    cards = np.random.default_rng(seed).random((n, 52)).argsort(axis=1)[:, : 2 + board]
    return cards[:, :2], cards[:, 2:]


def test_river_counts_equal_an_eval7_enumeration() -> None:
    holes, boards = _random_states(300, seed=1, board=5)
    deck = eval7_cards()
    expected = [eval7_count(h, b, deck) for h, b in zip(holes, boards, strict=True)]
    assert hole_counts(holes, boards).tolist() == expected
    # Every pair at once, by ranks: the same counts at each state's own pair.
    every = river_counts(boards)
    assert every[np.arange(len(holes)), pair_index(holes[:, 0], holes[:, 1])].tolist() == expected
    # A pair that meets the board counts 0; the others split 990 opponents into wins,
    # ties and losses, and over all pairs the wins and losses balance (equity 1/2 on average).
    clash = (PAIRS[None, :, :, None] == boards[:, None, None, :]).any(axis=(2, 3))
    assert (every[clash] == 0).all() and (every[~clash] <= RIVER_DENOMINATOR).all()
    assert (every.sum(axis=1) == 1_081 * RIVER_DENOMINATOR // 2).all()


def test_turn_counts_equal_an_eval7_enumeration() -> None:
    holes, boards = _random_states(12, seed=2, board=4)
    deck = eval7_cards()
    expected = [eval7_count(h, b, deck) for h, b in zip(holes, boards, strict=True)]
    assert turn_counts(holes, boards).tolist() == expected
    assert (np.array(expected) <= TURN_DENOMINATOR).all()


@pytest.mark.parametrize(("size", "classes"), [(3, FLOP_CLASSES), (4, TURN_CLASSES)])
def test_the_board_classes_cover_every_board_by_a_suit_permutation(
    size: int, classes: int
) -> None:
    found = board_classes(size)
    assert len(found.representatives) == classes and classes in (1_755, 16_432)
    assert len(found.codes) == len(found.class_of) == [22_100, 270_725][size - 3]
    boards = np.random.default_rng(3).random((500, 52)).argsort(axis=1)[:, :size]
    k, perm = found.find(boards[:, ::-1])  # any order of the board
    mapped = _PERMUTED_CARD[perm[:, None], boards]
    assert np.array_equal(_set_code(mapped), _set_code(found.representatives[k]))
    # Each representative is its class's smallest board, mapped to itself.
    own_k, own_perm = found.find(found.representatives)
    assert np.array_equal(own_k, np.arange(classes)) and not own_perm.any()


def test_the_shipped_flop_table_is_the_one_recorded_and_equals_an_enumeration() -> None:
    table = flop_table()
    assert table.shape == (FLOP_CLASSES, NUM_PAIRS) and table_digest(table) != ""
    holes, flops = _random_states(2, seed=4, board=3)
    expected = [engine_flop_count(h, f) for h, f in zip(holes, flops, strict=True)]
    assert flop_counts(holes, flops).tolist() == expected
    # And one state by eval7, every case (1,081 runouts x 990 opponents).
    assert eval7_count(holes[0], flops[0]) == expected[0]


def test_the_preflop_classes_are_exact_and_reproduce_published_figures() -> None:
    counts = preflop_counts()  # from the flop table, every flop and runout
    row, column = class_index(PAIRS)
    # Every hand of a class has its class's count, and the shipped 13 x 13 table is it.
    assert np.array_equal(counts, PREFLOP_COUNTS[row, column])
    # Equity averages exactly 1/2 over all hands: every win is someone's loss.
    assert 2 * counts.sum() == NUM_PAIRS * PREFLOP_DENOMINATOR
    aces = np.array([[parse_card("As"), parse_card("Ah")], [parse_card("7c"), parse_card("2d")]])
    assert preflop_equity(aces).round(3).tolist() == [0.852, 0.346]


def test_exact_equity_reads_each_street_and_is_bitwise_stable() -> None:
    rng = np.random.default_rng(6)
    deck = rng.random((400, 52)).argsort(axis=1)[:, :7]
    shown = np.arange(7) < (2 + np.array([0, 3, 4, 5])[rng.integers(0, 4, 400)])[:, None]
    cards = np.where(shown, deck, -1)
    found = exact_equity(cards)
    street = shown[:, 2:].sum(axis=1)
    river, turn, flop = street == 5, street == 4, street == 3
    assert np.array_equal(found[river],
                          hole_counts(cards[river, :2], cards[river, 2:]) / RIVER_DENOMINATOR)
    assert np.array_equal(found[turn],
                          turn_counts(cards[turn, :2], cards[turn, 2:6]) / TURN_DENOMINATOR)
    assert np.array_equal(found[flop],
                          flop_counts(cards[flop, :2], cards[flop, 2:5]) / FLOP_DENOMINATOR)
    # Rows are independent: a state's equity does not depend on its batch.
    assert np.array_equal(exact_equity(cards[::-1])[::-1], found)


# A digest of version 1's rows for fixed states, taken before version 2 existed.
V1_DIGEST = "206dfba6d2ae77b7c5401b5f7db0d69eff5631b5381478c2213628aac741b9a5"


def _v1_states() -> RawStates:
    from pokerirl.game.bots import seat_cards
    from pokerirl.game.deals import deal_cards

    rng = np.random.default_rng(41)
    deals = deal_cards(seed=41, start=0, count=2000)
    rounds, seats = rng.integers(0, 4, 2000), rng.integers(0, 2, 2000)
    return RawStates(cards=seat_cards(deals, rounds, seats),
                  raise_nums=rng.integers(0, 3, (2000, 4)).astype(np.int8),
                  legal_mask=np.tile([True, True, True, False], (2000, 1)))  # fmt: skip


def test_version_1_keeps_its_bytes_and_version_2_its_exact_equity() -> None:
    states = _v1_states()
    assert hashlib.sha256(STRENGTH_V1.encode(states).tobytes()).hexdigest() == V1_DIGEST
    exact = STRENGTH.features(states)["equity"][:, 0]
    assert np.array_equal(exact, exact_equity(states.cards).astype(np.float32))
    assert STRENGTH.spec == "strength-v2" and STRENGTH_V1.spec == "strength-v1"
    assert get_encoding("strength") is STRENGTH and get_encoding("strength-v1") is STRENGTH_V1
    # A record made before versions says "strength": that was version 1.
    assert recorded_encoding("strength") is STRENGTH_V1
    assert recorded_encoding("strength-v2") is STRENGTH and recorded_encoding(None).spec == "rlcard"


def test_an_agent_of_the_old_version_loads_as_version_1(tmp_path: Path) -> None:
    from pokerirl.agents.checkpoint import load_agent, save_agent
    from pokerirl.agents.dqn import QNetwork
    from pokerirl.game.match import agent_encoding

    network = QNetwork(hidden=(8,), obs_size=STRENGTH.width, input_norm=False)
    save_agent(tmp_path / "old", network, {"hidden": [8], "encoding": "strength"})
    old = load_agent(tmp_path / "old")
    assert old.encoding == "strength-v1" and agent_encoding(old) is STRENGTH_V1
    save_agent(tmp_path / "new", network, {"hidden": [8], "encoding": STRENGTH.spec})
    assert agent_encoding(load_agent(tmp_path / "new")) is STRENGTH
    assert json.loads((tmp_path / "new" / "config.json").read_text())["encoding"] == "strength-v2"


def test_rows_sharing_a_board_give_the_same_counts_at_once() -> None:
    """Local best response encodes all pairs of one state: those rows go through every
    pair's count at once, which must equal the row-by-row count."""
    from pokerirl.game.equity import all_pairs_turn_counts, river_equity, turn_equity

    _, boards = _random_states(1, seed=9, board=5)
    live = ~(PAIRS[:, :, None] == boards[0][None, None, :]).any(axis=(1, 2))
    pairs = PAIRS[live][:200]
    for board, street_equity, denominator, per_row in (
        (boards[0], river_equity, RIVER_DENOMINATOR, hole_counts),
        (boards[0, :4], turn_equity, TURN_DENOMINATOR, turn_counts),
    ):
        shared = np.broadcast_to(board, (len(pairs), len(board)))
        at_once = street_equity(pairs, shared[:, ::-1])  # any order of the board
        assert np.array_equal(at_once, per_row(pairs, shared) / denominator)
    every = all_pairs_turn_counts(boards[0, :4])
    assert every[pair_index(pairs[:5, 0], pairs[:5, 1])].tolist() == turn_counts(
        pairs[:5], np.broadcast_to(boards[0, :4], (5, 4))).tolist()


@pytest.mark.parametrize("board", ["Ah Kh 7h 2h", "Ah Kh 7h 2c", "Ah Kh 7s 2s", "Ah Kh 7d 2c",
                                   "9s 9d 5c 2h", "Ts Js Qs 9s", "8c 8d 8h 3c"])  # fmt: skip
def test_turn_counts_of_every_pair_equal_the_sorted_rivers(board: str) -> None:
    """The turn's count by rank groups and flush corrections (every river of one rank shared
    unless it makes the hand's own flush) equals every pair ranked on each river by a sort
    (an independent path): on boards of four, three and two of a suit, and paired boards,
    where the flush corrections and the grouping are all exercised (two suits of two
    cards: a river of either makes three, two groups of one rank)."""
    from pokerirl.game.equity import all_pairs_turn_counts

    cards = np.array([parse_card(c) for c in board.split()])
    live = ~(PAIRS[:, :, None] == cards[None, None, :]).any(axis=(1, 2))
    pairs = PAIRS[live]
    found = turn_counts(pairs, np.broadcast_to(cards, (len(pairs), 4)))
    every = all_pairs_turn_counts(cards)
    assert found.tolist() == every[pair_index(pairs[:, 0], pairs[:, 1])].tolist()


def _turn_states_of_classes(classes: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Turn states (holes, boards) on boards of the given classes: each representative under
    a random suit permutation, with random hole cards off it."""
    rng = np.random.default_rng(seed)
    representatives = board_classes(4).representatives[classes]
    boards = _PERMUTED_CARD[rng.integers(0, 24, len(classes))[:, None], representatives]
    holes = np.array([rng.choice(np.setdiff1d(np.arange(52), b), 2, replace=False)
                      for b in boards])  # fmt: skip
    return holes, boards


def test_the_turn_table_read_by_class_equals_the_counted_turn() -> None:
    """A table's row per turn class, read through the board's suit permutation (the pair
    mapped by the same one), gives every state's own count."""
    picked = np.random.default_rng(7).choice(TURN_CLASSES, 12, replace=False)
    table = np.zeros((TURN_CLASSES, NUM_PAIRS), dtype=np.uint32)
    for k in picked:
        table[k] = all_pairs_turn_counts(board_classes(4).representatives[k])
    holes, boards = _turn_states_of_classes(np.repeat(picked, 5), seed=8)
    assert _class_counts(table, board_classes(4), holes, boards).tolist() == turn_counts(
        holes, boards
    ).tolist()


def test_a_built_turn_table_is_read_checked_and_refused_when_not_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The build writes the file (nothing left beside it) only when its bytes are the
    recorded ones, ``turn_equity`` reads it and gives the counted values; a file that is not
    the table is one line (exit 1 from the command). Three classes stand for the 16,432 (two
    minutes)."""
    from typer.testing import CliRunner

    from pokerirl.cli import app
    from pokerirl.game import equity

    monkeypatch.setenv("POKERIRL_DATA", str(tmp_path / "cache"))
    monkeypatch.setattr(equity, "_TURN_TABLE", equity._TurnTableUse())
    assert equity.turn_table() is None  # not built: turn states are counted
    real = board_classes(4)
    few = real._replace(representatives=real.representatives[:3])
    monkeypatch.setattr(equity, "board_classes", lambda size: few if size == 4 else real)
    monkeypatch.setattr(equity, "TURN_CLASSES", 3)
    rows = np.array([all_pairs_turn_counts(b) for b in few.representatives], dtype="<u4")
    with pytest.raises(RuntimeError, match="not the recorded one"):  # the real digest
        equity.build_turn_table(equity.turn_table_path())
    assert list((tmp_path / "cache").iterdir()) == []  # a wrong build publishes nothing
    monkeypatch.setattr(equity, "TURN_TABLE_SHA256", table_digest(rows))
    table = equity.build_turn_table(equity.turn_table_path())
    assert [p.name for p in (tmp_path / "cache").iterdir()] == ["turn_equity_v1.npy"]
    counted: list[int] = []  # a place it cannot write: refused before any counting
    with pytest.raises(OSError):
        equity.build_turn_table(tmp_path / "cache" / "turn_equity_v1.npy" / "x.npy",
                                on_class=counted.append)  # fmt: skip
    assert counted == []
    assert np.array_equal(table, rows)
    wrong = rows.copy()
    wrong[0, 0] += 1  # a file there that is not the table
    np.save(equity.turn_table_path(), wrong, allow_pickle=False)
    with pytest.raises(InputError, match="is not the turn table this version builds"):
        equity.turn_table()  # another digest than the recorded one
    result = CliRunner().invoke(app, ["data", "turn-table"])
    assert result.exit_code == 1 and "not the turn table" in result.output
    np.save(equity.turn_table_path(), rows, allow_pickle=False)
    holes, boards = _turn_states_of_classes(np.array([0, 1, 2, 2]), seed=9)
    expected = turn_counts(holes, boards) / TURN_DENOMINATOR
    equity.use_turn_table(False)  # counted, then read from the table: the same values
    assert np.array_equal(equity.turn_equity(holes, boards), expected)
    assert equity.turn_table() is None
    equity.use_turn_table(True)
    monkeypatch.setattr(equity, "turn_counts", None)  # the table alone now
    monkeypatch.setattr(equity, "_TURN_ROWS", None)
    assert equity.turn_table() is not None
    assert np.array_equal(equity.turn_equity(holes, boards), expected)


def test_the_built_turn_table_where_there_is_one_equals_counting() -> None:
    """On a machine where ``pokerirl data turn-table`` ran: 400 random turn states read from
    it equal their count (its digest already pins every byte; this reads it end to end)."""
    from pokerirl.game import equity

    if equity.turn_table() is None:
        pytest.skip("the turn table is not built here (pokerirl data turn-table)")
    holes, boards = _random_states(400, seed=12, board=4)
    assert np.array_equal(equity.turn_equity(holes, boards),
                          turn_counts(holes, boards) / TURN_DENOMINATOR)  # fmt: skip
