"""Exact evaluation of Leduc strategies: the best response's value and strategy, the
exploitability and the expected value of one strategy against another, by walking every deal
(each of probability 1/120) and every betting history. No sampling: the figures are exact up
to float rounding.

Units: chips per hand (RLCard's environment reports big blinds, half as many: see
:attr:`~pokerirl.game.leduc.rules.LeducRules.env_chips_per_unit`); :data:`MILLI` chips are
what docs/leduc.md and the command line print.

The exploitability of a strategy (it covers both positions) is OpenSpiel's: the mean, over
the two positions, of what a best response wins there against it,
``(BR_0(sigma_1) + BR_1(sigma_0)) / 2``: half the NashConv of the profile. Zero at an
equilibrium.

>>> from pokerirl.game.leduc.rules import OPENSPIEL
>>> from pokerirl.game.leduc.strategy import uniform_strategy
>>> round(exploitability(OPENSPIEL, uniform_strategy(OPENSPIEL)), 6)
2.373611
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pokerirl.game.leduc.rules import Action, LeducRules
from pokerirl.game.leduc.strategy import Strategy, tables
from pokerirl.game.leduc.tree import Node, betting_tree

MILLI = 1000.0  # milli-chips per chip


@dataclass(frozen=True, kw_only=True)
class BestResponse:
    """A best response in one position: its value (chips per hand, in that position) and its
    action at each of its information sets."""

    position: int
    value: float
    actions: dict[str, Action]


@dataclass(frozen=True, kw_only=True)
class Matchup:
    """The exact expected value of A against B, chips per hand for A, by A's position."""

    first: float  # A in position 0
    second: float  # A in position 1

    @property
    def mean(self) -> float:
        """Over both positions, as the seats alternate (RLCard seats them at random)."""
        return (self.first + self.second) / 2


def best_response(rules: LeducRules, strategy: Strategy, position: int) -> BestResponse:
    """The best response in ``position`` to ``strategy``'s play in the other position."""
    tree = betting_tree(rules)
    table = tables(tree, strategy, positions=(1 - position,))
    actions: dict[str, Action] = {}
    reach = np.full(len(tree.deals), tree.chance)  # the other's reach times chance, by deal

    def walk(node: Node, reach: np.ndarray) -> np.ndarray:
        # Counterfactual values: reach times position's winnings from here, by deal.
        if node.actor is None:
            assert node.payoff is not None
            return reach * (node.payoff if position == 0 else -node.payoff)
        assert node.rows is not None
        if node.actor != position:
            sigma = table[id(node)][node.rows]
            return sum(
                (walk(child, reach * sigma[:, a]) for a, child in enumerate(node.children)),
                start=np.zeros_like(reach),
            )
        values = np.stack([walk(child, reach) for child in node.children], axis=1)
        # The information set (not the deal) chooses: the sum over its deals is its value.
        best = node.bincount(values).argmax(axis=1)
        actions.update(
            {key: node.actions[a] for key, a in zip(node.keys, best.tolist(), strict=True)}
        )
        return values[np.arange(len(reach)), best[node.rows]]

    value = float(walk(tree.root, reach).sum())
    return BestResponse(position=position, value=value, actions=actions)


def best_response_values(rules: LeducRules, strategy: Strategy) -> tuple[float, float]:
    """What a best response wins against ``strategy`` in position 0 and in position 1."""
    return (
        best_response(rules, strategy, 0).value,
        best_response(rules, strategy, 1).value,
    )


def exploitability(rules: LeducRules, strategy: Strategy) -> float:
    """Chips per hand: the mean of :func:`best_response_values` (OpenSpiel's exploitability)."""
    first, second = best_response_values(rules, strategy)
    return (first + second) / 2


def expected_value(rules: LeducRules, a: Strategy, b: Strategy) -> Matchup:
    """A's exact winnings against B, chips per hand, from each position."""
    tree = betting_tree(rules)
    plays = (tables(tree, a), tables(tree, b))

    def walk(node: Node, reach: np.ndarray, a_position: int) -> float:
        if node.actor is None:
            assert node.payoff is not None
            sign = 1.0 if a_position == 0 else -1.0
            return float(sign * (reach * node.payoff).sum())
        assert node.rows is not None
        player = plays[0] if node.actor == a_position else plays[1]
        sigma = player[id(node)][node.rows]
        return sum(
            walk(child, reach * sigma[:, i], a_position) for i, child in enumerate(node.children)
        )

    start = np.full(len(tree.deals), tree.chance)
    return Matchup(first=walk(tree.root, start, 0), second=walk(tree.root, start, 1))


@dataclass(frozen=True, kw_only=True)
class Agreement:
    """How often two strategies' most likely actions agree over the information sets:
    ``uniform`` counts each set once, ``reached`` weighs each by how often the reference
    (B) reaches it playing itself, chance included. Ties go to the first legal action in
    the order fold, check, call, raise."""

    uniform: float
    reached: float
    information_sets: int


def reach_probabilities(rules: LeducRules, strategy: Strategy) -> dict[str, float]:
    """Each information set's probability of occurring in a hand ``strategy`` plays against
    itself (chance and both players' actions)."""
    tree = betting_tree(rules)
    table = tables(tree, strategy)
    found: dict[str, float] = {}

    def walk(node: Node, reach: np.ndarray) -> None:
        if node.actor is None:
            return
        assert node.rows is not None
        totals = np.bincount(node.rows, reach, minlength=len(node.keys))
        found.update(zip(node.keys, totals.tolist(), strict=True))
        sigma = table[id(node)][node.rows]
        for a, child in enumerate(node.children):
            walk(child, reach * sigma[:, a])

    walk(tree.root, np.full(len(tree.deals), tree.chance))
    return found


def agreement(rules: LeducRules, a: Strategy, b: Strategy) -> Agreement:
    """The share of information sets where A's and B's argmax actions agree."""
    tree = betting_tree(rules)
    first, second = tables(tree, a), tables(tree, b)
    weight = reach_probabilities(rules, b)
    agree: list[bool] = []
    weights: list[float] = []
    for node in tree.nodes():
        same = first[id(node)].argmax(axis=1) == second[id(node)].argmax(axis=1)
        agree.extend(same.tolist())
        weights.extend(weight[key] for key in node.keys)
    shares = np.asarray(agree, dtype=np.float64)
    return Agreement(
        uniform=float(shares.mean()),
        reached=float(np.dot(shares, weights) / np.sum(weights)),
        information_sets=len(agree),
    )
