"""Feature encodings (``pokerirl.game.encodings``): what they compute, checked against the
engine, the evaluator, an independent equity estimate and published preflop figures; and
that every place that loads a run, an agent or a table refuses an encoding that does not fit.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.errors import ConfigError, InputError
from pokerirl.game import DecisionLog, LimitHoldemBatch, make_agent, play_match
from pokerirl.game.encodings import (
    RLCARD,
    STRENGTH,
    STRENGTH_FEATURES,
    STRENGTH_V1,
    RawStates,
    get_encoding,
    pot_and_call,
    sampled_equity,
    visible_category,
)
from pokerirl.game.equity import RANGE_ROWS, use_turn_table
from pokerirl.game.evaluator import category, hand_strength, pair_index
from pokerirl.game.match import observe, turn_cards
from pokerirl.game.preflop import PREFLOP_EQUITY, class_index, compute_preflop_table
from pokerirl.holdem import CALL, cards_from_text, parse_card
from pokerirl.poker.rewards import ObservedDecisions


def _random_play(hands: int, seed: int) -> Iterator[tuple[LimitHoldemBatch, np.ndarray]]:
    """(game, the hands to act) at every decision step of random play, before the step."""
    game = LimitHoldemBatch.from_seed(seed=seed, start=0, count=hands)
    rng = np.random.default_rng(seed)
    random = make_agent("random")
    while game.active().size:
        active = game.active().copy()
        yield game, active
        game.step(random.act(game.observe(active), game.legal_mask(active), rng), active)


def _states(game: LimitHoldemBatch, hands: np.ndarray) -> RawStates:
    return RawStates(cards=turn_cards(game, hands), raise_nums=game.raises[hands],
                  legal_mask=game.legal_mask(hands))  # fmt: skip


def test_rlcard_encoding_is_the_engines_observation_bit_for_bit() -> None:
    steps = 0
    for game, hands in _random_play(300, seed=1):
        assert np.array_equal(RLCARD.encode(_states(game, hands)), game.observe(hands))
        steps += 1
    assert steps > 5


def test_pot_and_call_match_the_engines_chips_at_every_decision() -> None:
    for game, hands in _random_play(500, seed=2):
        states = _states(game, hands)
        pot, to_call = pot_and_call(states.street, states.raise_nums, states.legal_mask[:, CALL])
        seat = game.to_act[hands]
        assert np.array_equal(pot, game.chips[hands].sum(axis=1))
        mine, theirs = game.round_chips[hands, seat], game.round_chips[hands, 1 - seat]
        assert np.array_equal(to_call, np.maximum(theirs - mine, 0))


def test_visible_category_is_the_evaluators_on_seven_cards_and_sane_on_fewer() -> None:
    rng = np.random.default_rng(0)
    cards = rng.random((20_000, 52)).argsort(axis=1)[:, :7]
    assert np.array_equal(visible_category(cards), category(hand_strength(cards)))
    # Fewer cards: a pair on the flop, quads of five, a flush of five, a wheel straight.
    texts = ["As Ah Kc 7d 2s", "9s 9h 9d 9c 2h", "2h 7h 9h Jh Kh", "As 2c 3d 4h 5s"]
    found = [np.array([[parse_card(c) for c in t.split()] + [-1, -1]]) for t in texts]
    assert [int(visible_category(c)[0]) for c in found] == [2, 8, 6, 5]


def test_sampled_equity_agrees_with_an_independent_estimate() -> None:
    from pokerirl.poker.reward_card import equity  # its own draws, its own code

    rng = np.random.default_rng(5)
    deck = rng.random((60, 52)).argsort(axis=1)[:, :7]
    street = rng.integers(1, 4, size=60)
    shown = np.arange(7) < (2 + np.array([0, 3, 4, 5])[street])[:, None]
    cards = np.where(shown, deck, -1)
    ours, theirs = sampled_equity(cards, samples=2_000), equity(cards, samples=2_000)
    difference = ours - theirs
    assert abs(difference.mean()) < 0.01  # both unbiased
    assert difference.std() < 0.03  # two estimates' noise at 2,000 samples each (about 0.016)
    # The shipped sample count: each state within 4 standard errors of the fine estimate.
    coarse = sampled_equity(cards, samples=64)
    assert np.all(np.abs(coarse - theirs) < 4 * 0.5 / 8 + 0.05)


def test_the_shipped_preflop_table_matches_a_recomputation_and_published_figures() -> None:
    fresh = compute_preflop_table(samples=1_500, seed=11)
    assert np.abs(fresh - PREFLOP_EQUITY).max() < 0.06  # 4.6 SE at 1,500 runouts
    aces, seven_deuce = [[parse_card("As"), parse_card("Ah")], [parse_card("7c"), parse_card("2d")]]
    row, column = class_index(np.array([aces, seven_deuce]))
    assert PREFLOP_EQUITY[row[0], column[0]] == pytest.approx(0.852, abs=0.004)
    assert PREFLOP_EQUITY[row[1], column[1]] == pytest.approx(0.346, abs=0.004)


def test_strength_features_of_a_known_hand() -> None:
    cards = np.array([[parse_card(c) for c in "Ah Kh Qh 7h 2c".split()] + [-1, -1]], np.int8)
    states = RawStates(cards=cards, raise_nums=np.array([[1, 1, 0, 0]]),
                    legal_mask=np.array([[True, True, True, False]]))  # fmt: skip
    found = STRENGTH.features(states)
    assert set(found) == set(STRENGTH_FEATURES)
    assert found["hole"].sum() == 2 and found["board"].sum() == 3
    assert found["street"].argmax() == 1 and found["category"].argmax() == 0  # flop, high card
    assert found["flush_draw"][0, 0] == 1 and found["straight_draw"][0, 0] == 0
    assert found["top_pair"][0, 0] == 0 and found["hole_pairs_board"][0, 0] == 0
    # Preflop 1 raise (4 chips each), flop: the opponent bet 2: pot 10, 2 to call.
    assert found["pot"][0, 0] == pytest.approx(10 / 100)
    assert found["pot_odds"][0, 0] == pytest.approx(2 / 12)
    assert STRENGTH.encode(states).shape == (1, STRENGTH.width)
    again = STRENGTH.encode(states)
    assert np.array_equal(again, STRENGTH.encode(states))  # a function of the state alone


def _reference_card_features(cards: list[int]) -> dict[str, float]:
    """The strength encoding's card features of one state, card by card from their
    definitions (docs/encodings.md), independent of the encoding's rank and suit masks."""
    shown = [c for c in cards if c >= 0]
    rank = [(c % 13 + 12) % 13 for c in shown]  # 2 .. A as 0 .. 12
    suit = [c // 13 for c in shown]
    hole_rank, board_rank = rank[:2], rank[2:]
    street = {0: 0, 3: 1, 4: 2, 5: 3}[len(shown) - 2]
    counts = {r: rank.count(r) for r in set(rank)}

    def straight(ranks: set[int]) -> bool:
        return any({(low + k) % 13 for k in range(5)} <= ranks for low in range(-1, 9))

    by_suit = [{r for r, s in zip(rank, suit, strict=True) if s == t} for t in range(4)]
    flush = any(len(ranks) >= 5 for ranks in by_suit)
    trips = any(n >= 3 for n in counts.values())
    held_twice = sum(n >= 2 for n in counts.values())
    category = 1 + max([0, (held_twice >= 1), 2 * (held_twice >= 2), 3 * trips,
                        4 * straight(set(rank)), 5 * flush, 6 * (trips and held_twice >= 2),
                        7 * any(n == 4 for n in counts.values()),
                        8 * any(len(r) >= 5 and straight(r) for r in by_suit)])  # fmt: skip
    to_come = street in (1, 2)
    windows = [{12, 0, 1, 2, 3}] + [set(range(low, low + 5)) for low in range(9)]
    pocket = hole_rank[0] == hole_rank[1]
    top = max(board_rank, default=-1)
    four_suited = any(len(by_suit[s]) == 4 for s in suit[:2])
    four_in_row = any(len(w & set(rank)) == 4 and w & set(hole_rank) for w in windows)
    return {
        "category": category,
        "hole_pairs_board": sum(r in board_rank for r in hole_rank) / 2,
        "top_pair": float(top in hole_rank),
        "overpair": float(pocket and bool(board_rank) and hole_rank[0] > top),
        "flush_draw": float(to_come and not flush and four_suited),
        "straight_draw": float(to_come and not straight(set(rank)) and four_in_row),
        "high_rank": max(hole_rank),
        "low_rank": min(hole_rank),
        "pocket_pair": float(hole_rank[0] == hole_rank[1]),
        "suited": float(suit[0] == suit[1]),
        "street": street,
    }


def _random_cards(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 7) states' cards on every street, a third from two suits (flushes and flush
    draws) and a third from six ranks (straights, pairs, trips, quads)."""
    found = np.empty((n, 7), dtype=np.int8)
    narrow_suits = np.arange(26)
    narrow_ranks = np.array([r + 13 * s for r in (0, 1, 2, 3, 4, 12) for s in range(4)])
    for i in range(n):
        deck = (np.arange(52), narrow_suits, narrow_ranks)[i % 3]
        found[i] = rng.choice(deck, size=7, replace=False)
        found[i, 2 + (0, 3, 4, 5)[rng.integers(4)] :] = -1
    return found


def test_strength_card_features_equal_a_card_by_card_reference() -> None:
    rng = np.random.default_rng(3)
    cards = _random_cards(rng, 3_000)
    states = RawStates(cards=cards, raise_nums=rng.integers(0, 5, (len(cards), 4)),
                       legal_mask=rng.random((len(cards), 4)) < 0.5)  # fmt: skip
    found = STRENGTH.features(states)
    one_hots = ("category", "street", "high_rank", "low_rank")
    seen = {name: set() for name in ("category", "flush_draw", "straight_draw", "overpair")}
    for i, row in enumerate(cards.tolist()):
        for name, value in _reference_card_features(row).items():
            got = found[name][i].argmax() + (name == "category") if name in one_hots else (
                found[name][i, 0])  # fmt: skip
            assert got == value, (name, row, got, value)
            if name in seen:
                seen[name].add(value)
    assert seen["category"] == set(range(1, 10))  # every category, and both values of each flag
    assert all(len(values) == 2 for name, values in seen.items() if name != "category")
    # The betting columns (read from a table of the betting states) against their definitions.
    raises = found["raises"].reshape(-1, 4, 5)
    assert np.array_equal(raises.argmax(axis=2), states.raise_nums) and raises.sum() == 4 * 3_000
    facing = states.legal_mask[:, CALL]
    pot, to_call = pot_and_call(states.street, states.raise_nums, facing)
    assert np.array_equal(found["facing_bet"][:, 0], facing)
    assert np.array_equal(found["pot"][:, 0], (pot / 100).astype(np.float32))
    odds = np.where(facing, to_call / np.maximum(pot + to_call, 1), 0.0).astype(np.float32)
    assert np.array_equal(found["pot_odds"][:, 0], odds) and found["pot_odds"].max() > 0


@pytest.mark.parametrize("rows", [5_000, 300, 9])
def test_a_range_encodes_as_the_states_it_stands_for(rows: int) -> None:
    """``encode_pairs`` (a state's board and betting with many pairs, as local best response
    asks) gives the rows of the states it stands for, in every encoding: ~80 rows a state
    (each board's work done once), at most ~12 (row by row), fewer than 16 rows in all."""
    rng = np.random.default_rng(4)
    boards = _random_cards(rng, 60)
    states = RawStates(cards=boards, raise_nums=rng.integers(0, 5, (60, 4)),
                       legal_mask=rng.random((60, 4)) < 0.5)  # fmt: skip
    of = rng.integers(0, 60, rows)
    assert (np.bincount(of).max() >= RANGE_ROWS) == (rows == 5_000)  # the paths meant
    taken = np.asarray(boards, dtype=np.int64)[of]
    pairs = np.array([rng.choice(np.setdiff1d(np.arange(52), row), 2, replace=False)
                      for row in taken])  # fmt: skip
    whole = RawStates(cards=np.concatenate([pairs, taken[:, 2:]], axis=1).astype(np.int8),
                      raise_nums=states.raise_nums[of], legal_mask=states.legal_mask[of])
    for encoding, table in ((RLCARD, True), (STRENGTH, True), (STRENGTH, False),
                            (STRENGTH_V1, True)):  # fmt: skip
        use_turn_table(table)  # where it is built: turn equity read, or counted
        try:
            expected = encoding.encode(whole)
            found = encoding.encode_pairs(pair_index(pairs[:, 0], pairs[:, 1]), states, of)
        finally:
            use_turn_table(True)
        assert found.dtype == expected.dtype and np.array_equal(found, expected), encoding


def test_the_engine_builds_each_agents_own_encoding_as_a_log_would() -> None:
    """A match's logged states (RLCard obs, cards, legal actions) give the same strength rows
    as the engine builds for an agent reading that encoding."""
    for game, hands in _random_play(200, seed=4):
        direct = observe(game, hands, STRENGTH)
        log = DecisionLog(obs=game.observe(hands), legal_mask=game.legal_mask(hands),
                          cards=turn_cards(game, hands),
                          actions=np.zeros(len(hands), int))  # fmt: skip
        decisions = ObservedDecisions(obs=log.obs, legal_mask=log.legal_mask, cards=log.cards)
        assert np.array_equal(decisions.encode(STRENGTH), direct)


def test_cards_from_text_reads_tables_and_refuses_what_is_not_cards() -> None:
    assert cards_from_text(["Th 2c", "As Kd"], ["", "Qc Jc Tc 9c 8c"]).tolist() == [
        [22, 40, -1, -1, -1, -1, -1],
        [0, 38, 50, 49, 48, 47, 46],
    ]
    for hole, board in ((["As"], [""]), (["As Kx"], [""]), (["As Kd"], ["Qc Th"])):
        with pytest.raises(ValueError, match="bad cards"):
            cards_from_text(hole, board)


def test_unknown_encodings_are_one_line() -> None:
    with pytest.raises(ConfigError, match="unknown encoding 'onehot'"):
        get_encoding("onehot")
    output = CliRunner().invoke(app, ["train", "x.parquet", "--out", "r", "--encoding", "bad"])
    assert output.exit_code == 2 and "unknown --encoding 'bad'" in output.output


# --------------------------------------------------------------------------- mismatches


@pytest.fixture(scope="module")
def strength_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from pokerirl.datasets.toy import toy_expert_table
    from pokerirl.irl import load_config
    from pokerirl.poker import train_table

    root = tmp_path_factory.mktemp("strength")
    pq.write_table(toy_expert_table(num_hands=150, seed=2), root / "table.parquet")
    config = load_config("hairl", overrides={"epochs": 1, "batch_size": 64})
    train_table(root / "table.parquet", root / "run", config=config, progress=False,
                encoding=STRENGTH)  # fmt: skip
    return root / "run"


@pytest.mark.slow
def test_a_strength_run_records_its_encoding_and_its_reward_reads_it(strength_run: Path) -> None:
    from pokerirl.poker.reward_sources import RewardSource

    record = json.loads((strength_run / "config.json").read_text())
    assert record["data"]["encoding"] == "strength-v2"  # the spec: name and version
    assert record["architecture"]["obs_dim"] == STRENGTH.width
    source = RewardSource.resolve(strength_run)
    assert source.encoding == "strength-v2" and source.load().needs_cards


@pytest.mark.slow
def test_a_run_and_a_table_or_flag_of_another_encoding_are_refused(
    strength_run: Path, tmp_path: Path
) -> None:
    runner = CliRunner()
    # The run reads strength; asking for rlcard is refused in one line naming the run.
    result = runner.invoke(app, ["reward-card", str(strength_run), "--encoding", "rlcard",
                                 "--out", str(tmp_path / "card")])  # fmt: skip
    assert result.exit_code == 1 and result.output.count("\n") == 1
    assert "a reward on the strength-v2 encoding, not rlcard" in result.output
    assert not (tmp_path / "card").exists()
    # A table without the columns the strength encoding is computed from.
    table = pq.read_table(strength_run.parent / "table.parquet").drop(["hole_cards", "board"])
    pq.write_table(table, tmp_path / "bare.parquet")
    for args, message in (
        (["train", str(tmp_path / "bare.parquet"), "--out", str(tmp_path / "r"),
          "--encoding", "strength", "--epochs", "1", "--quiet"],
         "no hole_cards, board column(s): the strength encoding is computed from them"),
        (["reward-card", str(strength_run), "--table", str(tmp_path / "bare.parquet"),
          "--out", str(tmp_path / "card")], "lacks required column(s): hole_cards, board"),
    ):  # fmt: skip
        result = runner.invoke(app, args)
        assert result.exit_code == 1 and result.output.count("\n") == 1, result.output
        assert message in result.output
    # A run whose record names one encoding and whose reward reads another width.
    forged = tmp_path / "forged"
    forged.mkdir()
    (forged / "reward.pt").write_bytes((strength_run / "reward.pt").read_bytes())
    record = json.loads((strength_run / "config.json").read_text())
    record["data"]["encoding"] = "rlcard"
    (forged / "config.json").write_text(json.dumps(record))
    from pokerirl.poker.reward_sources import RewardSource

    with pytest.raises(InputError, match="not the rlcard encoding's 72-d states"):
        RewardSource.resolve(forged)


def test_an_agent_folder_of_an_unknown_encoding_is_refused(tmp_path: Path) -> None:
    from pokerirl.agents.checkpoint import load_agent, save_agent
    from pokerirl.agents.dqn import QNetwork

    save_agent(tmp_path / "a", QNetwork(hidden=(8,), obs_size=STRENGTH.width, input_norm=False),
               {"hidden": [8], "encoding": "strength"})  # fmt: skip
    assert load_agent(tmp_path / "a").encoding == "strength-v1"  # before versions: v1
    save_agent(tmp_path / "b", QNetwork(hidden=(8,)), {"hidden": [8], "encoding": "colour"})
    with pytest.raises(InputError, match="unknown encoding 'colour'"):
        load_agent(tmp_path / "b")
    # A strength network saved as rlcard: its weights do not fit, named in one line.
    save_agent(tmp_path / "c", QNetwork(hidden=(8,), obs_size=STRENGTH.width), {"hidden": [8]})
    with pytest.raises(InputError, match="on the rlcard encoding"):
        load_agent(tmp_path / "c")


@pytest.mark.slow
def test_agents_of_different_encodings_meet_in_one_match(strength_run: Path) -> None:
    """A policy reading strength plays a bot and an RLCard-encoded DQN on the engine."""
    from pokerirl.agents import land_agent, resolve_agent, ship_agent
    from pokerirl.agents.dqn import DQNConfig, train_dqn

    policy = resolve_agent(f"policy:{strength_run}")
    assert policy.encoding == "strength-v2"  # type: ignore[attr-defined]
    dqn = train_dqn(DQNConfig(concurrent_hands=64, replay_init=32), hands=128, seed=0,
                    opponent=policy).greedy_agent()  # fmt: skip
    for rival in (make_agent("tightbot"), dqn):
        result = play_match(policy, rival, hands=400, seed=0)
        assert np.isfinite(result.mbb_per_hand)
    argmax = resolve_agent(f"reward:{strength_run}")
    assert play_match(argmax, policy, hands=200, seed=1).hands == 200
    # Shipped to a worker as bytes and landed: the same agent.
    import tempfile

    landed = land_agent(ship_agent(f"policy:{strength_run}"), tempfile.mkdtemp())
    assert landed.fingerprint == policy.fingerprint  # type: ignore[attr-defined]


@pytest.mark.slow
def test_match_and_tournament_check_the_agents_encoding(strength_run: Path, tmp_path: Path) -> None:
    runner = CliRunner()
    policy = f"policy:{strength_run}"
    ok = runner.invoke(app, ["match", policy, "tightbot", "--hands", "20", "--encoding",
                             "strength", "--format", "json"])  # fmt: skip
    assert ok.exit_code == 0, ok.output
    for args in (
        ["match", policy, "tightbot", "--hands", "20", "--encoding", "rlcard"],
        ["tournament", policy, "call", "--hands", "20", "--seeds", "0",
         "--out", str(tmp_path / "t"), "--encoding", "rlcard"],
    ):  # fmt: skip
        result = runner.invoke(app, args)
        assert result.exit_code == 1 and result.output.count("\n") == 1, result.output
        assert f"{policy}: an agent on the strength encoding, not rlcard" in result.output
    assert not (tmp_path / "t").exists()
