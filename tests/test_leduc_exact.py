"""The exact Leduc tools against two independent references: OpenSpiel's own exploitability,
expected values and CFR+ on its ``leduc_poker`` (skipped without open_spiel), and, on RLCard's
rules, a naive recursion over the hand engine's states that draws the cards one by one with
their probabilities and chooses the best response information set by information set.

The naive best response can be told to cheat (see the other's card) or to draw the cards
with wrong probabilities: ours must equal the honest one and differ from both."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator
from dataclasses import replace

import numpy as np
import pytest

from pokerirl.errors import InputError
from pokerirl.game.leduc import OPENSPIEL, RLCARD, LeducRules, LeducState, deal
from pokerirl.game.leduc.cfr import CFRPlus
from pokerirl.game.leduc.exact import best_response, expected_value, exploitability
from pokerirl.game.leduc.rules import Action
from pokerirl.game.leduc.strategy import (
    Strategy,
    profile,
    read_strategy,
    strategy_from_callable,
    to_json,
    uniform_strategy,
)

SMALL = replace(RLCARD, name="rlcard", ranks=2)  # RLCard's rules with four cards (J, Q)


def random_strategy(rules: LeducRules, seed: int) -> dict[str, dict[str, float]]:
    rng = np.random.default_rng(seed)

    def policy(key: str, legal: tuple[Action, ...]) -> dict[str, float]:
        return dict(zip(legal, rng.dirichlet(np.ones(len(legal))).tolist(), strict=True))

    return strategy_from_callable(rules, policy)


# --- the naive reference: engine states, cards drawn one by one ---------------------------

Chance = Callable[[LeducRules], Iterator[tuple[tuple[int, int, int], float]]]


def drawn(rules: LeducRules) -> Iterator[tuple[tuple[int, int, int], float]]:
    """Each deal and its probability: three cards drawn without replacement."""
    n = rules.cards
    for cards in itertools.permutations(range(n), 3):
        yield cards, (1 / n) * (1 / (n - 1)) * (1 / (n - 2))


def by_rank(rules: LeducRules) -> Iterator[tuple[tuple[int, int, int], float]]:
    """Wrong on purpose: the public card's rank drawn uniformly, whatever is left of it."""
    n = rules.cards
    for a, b, c in itertools.permutations(range(n), 3):
        left = sum(1 for card in range(n) if card // 2 == c // 2 and card not in (a, b))
        yield (a, b, c), (1 / n) * (1 / (n - 1)) * (1 / rules.ranks) / left


def naive_best_response(
    rules: LeducRules, strategy: Strategy, position: int, *, chance: Chance = drawn,
    cheat: bool = False,
) -> float:  # fmt: skip
    """Backward induction over ``position``'s information sets, deepest first."""
    def key(state: LeducState) -> str:
        mine = state.info_key(position)
        return f"{mine}|{state.cards[1 - position]}" if cheat else mine

    # Every decision of `position`, with the other's reach times chance.
    sets: dict[str, list[tuple[LeducState, float]]] = {}

    def collect(state: LeducState, weight: float) -> None:
        if state.is_over or weight == 0:
            return
        if state.to_act == position:
            sets.setdefault(key(state), []).append((state, weight))
            for action in state.legal_actions():
                collect(state.step(action), weight)
        else:
            probabilities = strategy[state.info_key(state.to_act)]
            for action in state.legal_actions():
                collect(state.step(action), weight * probabilities.get(action.value, 0.0))

    for cards, p in chance(rules):
        collect(deal(rules, cards=cards), p)
    chosen: dict[str, Action] = {}

    def value(state: LeducState) -> float:
        if state.is_over:
            return state.payoffs()[position]
        if state.to_act == position:
            return value(state.step(chosen[key(state)]))
        probabilities = strategy[state.info_key(state.to_act)]
        return sum(p * value(state.step(Action(a))) for a, p in probabilities.items() if p)

    for name in sorted(sets, key=lambda k: -len(k)):  # longer betting: deeper
        states = sets[name]
        legal = states[0][0].legal_actions()
        worth = [sum(w * value(s.step(a)) for s, w in states) for a in legal]
        chosen[name] = legal[int(np.argmax(worth))]
    return sum(p * value(deal(rules, cards=cards)) for cards, p in chance(rules))


@pytest.mark.parametrize("position", [0, 1])
def test_the_best_response_is_the_naive_one_and_neither_cheats_nor_misweighs(
    position: int,
) -> None:
    strategy = random_strategy(SMALL, seed=position)
    ours = best_response(SMALL, strategy, position).value
    honest = naive_best_response(SMALL, strategy, position)
    cheating = naive_best_response(SMALL, strategy, position, cheat=True)
    misweighed = naive_best_response(SMALL, strategy, position, chance=by_rank)
    assert ours == pytest.approx(honest, abs=1e-12)
    assert cheating > honest + 0.05  # seeing the other's card is worth much
    assert abs(misweighed - honest) > 0.01


def test_the_best_response_is_the_naive_one_on_rlcards_full_deck() -> None:
    strategy = random_strategy(RLCARD, seed=7)
    for position in (0, 1):
        assert best_response(RLCARD, strategy, position).value == pytest.approx(
            naive_best_response(RLCARD, strategy, position), abs=1e-12
        )


def test_the_expected_value_is_what_sampled_hands_win() -> None:
    a, b = random_strategy(SMALL, seed=3), random_strategy(SMALL, seed=4)
    exact = expected_value(SMALL, a, b)
    # A best response to a strategy that plays like B in both positions wins at least as
    # much as A does, from each position.
    assert best_response(SMALL, b, 0).value >= exact.first - 1e-12
    assert best_response(SMALL, a, 1).value >= -exact.first - 1e-12
    # The same figure, sampled: hands dealt from a shuffled deck, actions drawn.
    rng = np.random.default_rng(0)
    won = []
    for _ in range(4_000):
        cards = tuple(int(c) for c in rng.choice(SMALL.cards, size=3, replace=False))
        state = deal(SMALL, cards=(cards[0], cards[1], cards[2]))
        while not state.is_over:
            probabilities = (a if state.to_act == 0 else b)[state.info_key(state.to_act)]
            names = list(probabilities)
            pick = rng.choice(len(names), p=list(probabilities.values()))
            state = state.step(Action(names[pick]))
        won.append(state.payoffs()[0])
    error = np.std(won) / np.sqrt(len(won))
    assert abs(np.mean(won) - exact.first) < 4 * error
    assert exact.mean == pytest.approx((exact.first + exact.second) / 2)


def test_a_pairs_exploitability_is_each_best_response_to_the_other() -> None:
    a, b = random_strategy(RLCARD, seed=8), random_strategy(RLCARD, seed=9)
    pair = profile(RLCARD, a, b)
    expected = (best_response(RLCARD, b, 0).value + best_response(RLCARD, a, 1).value) / 2
    assert exploitability(RLCARD, pair) == pytest.approx(expected, abs=1e-12)
    assert exploitability(RLCARD, pair) != pytest.approx(exploitability(RLCARD, a), abs=1e-3)


def test_a_strategy_must_cover_the_tree_with_distributions() -> None:
    strategy = uniform_strategy(RLCARD)
    with pytest.raises(InputError, match="no information set 'K:'"):
        exploitability(RLCARD, {k: v for k, v in strategy.items() if k != "K:"})
    with pytest.raises(InputError, match="sum to"):
        exploitability(RLCARD, {**strategy, "K:": {"fold": 0.5, "call": 0.6}})
    with pytest.raises(InputError, match="illegal actions"):
        exploitability(RLCARD, {**strategy, "K:": {"check": 1.0}})


def test_a_strategy_file_is_the_same_bytes_and_reads_back(tmp_path) -> None:  # type: ignore[no-untyped-def]
    strategy = random_strategy(RLCARD, seed=1)
    text = to_json(RLCARD, strategy)
    assert text == to_json(RLCARD, dict(reversed(strategy.items())))
    (tmp_path / "s.json").write_text(text)
    rules, back = read_strategy(tmp_path / "s.json")
    assert rules is RLCARD
    assert exploitability(RLCARD, back) == pytest.approx(exploitability(RLCARD, strategy), abs=1e-9)
    (tmp_path / "bad.json").write_text(text.replace('"K:"', '"X:"'))
    with pytest.raises(InputError, match=r"bad\.json: the strategy has no information set"):
        read_strategy(tmp_path / "bad.json")


# --- OpenSpiel's leduc_poker ---------------------------------------------------------------


@pytest.fixture(scope="module")
def openspiel():  # type: ignore[no-untyped-def]
    pytest.importorskip("pyspiel", reason="open_spiel is not installed (pip install open_spiel)")
    import pyspiel
    from open_spiel.python.algorithms import exploitability as os_exploitability

    return pyspiel.load_game("leduc_poker"), os_exploitability.exploitability


def test_exploitability_is_openspiels_for_uniform_random_and_cfr_plus(openspiel) -> None:  # type: ignore[no-untyped-def]
    from open_spiel.python import policy as policies

    from pokerirl.game.leduc.interop import to_openspiel

    game, theirs = openspiel
    uniform = uniform_strategy(OPENSPIEL)
    assert exploitability(OPENSPIEL, uniform) == pytest.approx(
        theirs(game, policies.UniformRandomPolicy(game)), abs=1e-9
    )
    mixed = random_strategy(OPENSPIEL, seed=5)
    assert exploitability(OPENSPIEL, mixed) == pytest.approx(
        theirs(game, to_openspiel(mixed)), abs=1e-9
    )
    solver = CFRPlus(OPENSPIEL)
    solver.run(10, every=10)
    assert exploitability(OPENSPIEL, solver.average()) == pytest.approx(
        theirs(game, to_openspiel(solver.average())), abs=1e-9
    )


@pytest.mark.slow
def test_exploitability_is_openspiels_after_10_iterations_of_its_own_cfr(openspiel) -> None:  # type: ignore[no-untyped-def]
    from open_spiel.python.algorithms import cfr

    from pokerirl.game.leduc.interop import from_openspiel

    game, theirs = openspiel
    solver = cfr.CFRSolver(game)  # vanilla CFR: a strategy ours never makes
    for _ in range(10):
        solver.evaluate_and_update_policy()
    average = solver.average_policy()
    assert exploitability(OPENSPIEL, from_openspiel(average)) == pytest.approx(
        theirs(game, average), abs=1e-9
    )


@pytest.mark.slow
def test_exploitability_is_openspiels_after_100_and_1000_cfr_plus_iterations(openspiel) -> None:  # type: ignore[no-untyped-def]
    from pokerirl.game.leduc.interop import to_openspiel

    game, theirs = openspiel
    ours = CFRPlus(OPENSPIEL)
    for iterations in (100, 900):
        ours.run(iterations, every=iterations)
        assert exploitability(OPENSPIEL, ours.average()) == pytest.approx(
            theirs(game, to_openspiel(ours.average())), abs=1e-9
        )


def test_expected_value_is_openspiels(openspiel) -> None:  # type: ignore[no-untyped-def]
    from open_spiel.python.algorithms import expected_game_score

    from pokerirl.game.leduc.interop import to_openspiel

    game, _ = openspiel
    a, b = random_strategy(OPENSPIEL, seed=1), random_strategy(OPENSPIEL, seed=2)
    values = expected_game_score.policy_value(
        game.new_initial_state(), [to_openspiel(a), to_openspiel(b)]
    )
    assert expected_value(OPENSPIEL, a, b).first == pytest.approx(values[0], abs=1e-9)
