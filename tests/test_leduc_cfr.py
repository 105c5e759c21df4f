"""The CFR+ solver: OpenSpiel's CFRPlusSolver iteration by iteration (skipped without
open_spiel), the same bytes on a rerun, and below one milli-chip per hand on both rule sets
(the slow test; benchmarks/leduc.py times it)."""

from __future__ import annotations

import pytest

from pokerirl.game.leduc import OPENSPIEL, RLCARD, LeducRules
from pokerirl.game.leduc.cfr import CFRPlus
from pokerirl.game.leduc.exact import MILLI, exploitability
from pokerirl.game.leduc.strategy import sha256, to_json


def test_the_curve_is_openspiels_cfr_plus_iteration_by_iteration() -> None:
    pytest.importorskip("pyspiel", reason="open_spiel is not installed (pip install open_spiel)")
    import pyspiel
    from open_spiel.python.algorithms import cfr
    from open_spiel.python.algorithms import exploitability as theirs

    game = pyspiel.load_game("leduc_poker")
    solver = cfr.CFRPlusSolver(game)
    expected = []
    for _ in range(4):
        solver.evaluate_and_update_policy()
        expected.append(theirs.exploitability(game, solver.average_policy()))
    curve = CFRPlus(OPENSPIEL).run(4)
    assert [p.iteration for p in curve] == [1, 2, 3, 4]
    assert [p.exploitability for p in curve] == pytest.approx(expected, abs=1e-9)
    assert expected[-1] < 0.7 * expected[0]  # it learns: the curve is no constant


def test_a_rerun_writes_the_same_bytes() -> None:
    def solved(iterations: int) -> str:
        solver = CFRPlus(RLCARD)
        solver.run(iterations, every=iterations)
        return sha256(to_json(RLCARD, solver.average(), iterations=iterations))

    assert solved(20) == solved(20)
    assert solved(21) != solved(20)


@pytest.mark.slow
@pytest.mark.parametrize("rules", [RLCARD, OPENSPIEL], ids=["rlcard", "openspiel"])
def test_cfr_plus_gets_below_one_milli_chip_per_hand(rules: LeducRules) -> None:
    solver = CFRPlus(rules)
    curve = solver.run(500, every=100)
    assert curve[-1].exploitability * MILLI < 1.0
    assert exploitability(rules, solver.average()) == curve[-1].exploitability
    values = [p.exploitability for p in curve]
    assert values == sorted(values, reverse=True)
