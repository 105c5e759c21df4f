"""CFR+ for Leduc hold'em: regret matching+, alternating updates (position 0's pass, then
position 1's, each against the other's current strategy) and linear averaging (iteration
``t`` weighs ``t``): OpenSpiel's ``CFRPlusSolver``, vectorized over the deals of
:mod:`~pokerirl.game.leduc.tree`.

Deterministic: no sampling, no seed; the same rules and iterations give the same strategy
and, written by :func:`~pokerirl.game.leduc.strategy.to_json`, the same bytes.

>>> from pokerirl.game.leduc.rules import OPENSPIEL
>>> solver = CFRPlus(OPENSPIEL)
>>> curve = solver.run(10, every=5)
>>> [(point.iteration, round(point.exploitability, 6)) for point in curve]
[(5, 1.371232), (10, 0.610439)]
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pokerirl.errors import check_count
from pokerirl.game.leduc.exact import exploitability
from pokerirl.game.leduc.rules import LeducRules
from pokerirl.game.leduc.tree import Node, betting_tree

MAX_ITERATIONS = 10_000_000


@dataclass(frozen=True, kw_only=True)
class CurvePoint:
    """The average strategy's exploitability (chips per hand) after ``iteration``."""

    iteration: int
    exploitability: float


class CFRPlus:
    """The solver's state: cumulative regrets and the weighted sum of strategies, one
    ``rows x actions`` table per decision node."""

    def __init__(self, rules: LeducRules) -> None:
        self.rules = rules
        self.tree = betting_tree(rules)
        self.nodes = self.tree.nodes()
        shapes = {id(n): (len(n.keys), len(n.actions)) for n in self.nodes}
        self.regrets = {i: np.zeros(shape) for i, shape in shapes.items()}
        self.totals = {i: np.zeros(shape) for i, shape in shapes.items()}
        self.current = {i: np.full(shape, 1.0 / shape[1]) for i, shape in shapes.items()}
        self.iteration = 0

    def step(self) -> None:
        """One iteration: position 0 updates, then position 1."""
        self.iteration += 1
        for position in (0, 1):
            ones = np.ones(len(self.tree.deals))
            self._walk(self.tree.root, position, ones, ones * self.tree.chance)
            for node in self.nodes:
                if node.actor == position:
                    regrets = np.maximum(self.regrets[id(node)], 0.0)  # regret matching+
                    self.regrets[id(node)] = regrets
                    self.current[id(node)] = _matched(regrets)

    def _walk(self, node: Node, position: int, mine: np.ndarray, others: np.ndarray
              ) -> np.ndarray:  # fmt: skip
        # mine: position's reach by deal; others: the other's reach times chance. Returns
        # position's counterfactual values by deal.
        if node.actor is None:
            assert node.payoff is not None
            return others * (node.payoff if position == 0 else -node.payoff)
        assert node.rows is not None
        sigma = self.current[id(node)][node.rows]
        if node.actor != position:
            return sum(
                (self._walk(c, position, mine, others * sigma[:, a])
                 for a, c in enumerate(node.children)),
                start=np.zeros_like(mine),
            )  # fmt: skip
        values = np.stack(
            [self._walk(c, position, mine * sigma[:, a], others)
             for a, c in enumerate(node.children)], axis=1,
        )  # fmt: skip
        value = (values * sigma).sum(axis=1)
        self.regrets[id(node)] += node.bincount(values - value[:, None])
        self.totals[id(node)] += self.iteration * node.bincount(mine[:, None] * sigma)
        return value

    def average(self) -> dict[str, dict[str, float]]:
        """The average strategy (uniform where it was never reached)."""
        strategy: dict[str, dict[str, float]] = {}
        for node in self.nodes:
            for key, row in zip(node.keys, _matched(self.totals[id(node)]), strict=True):
                strategy[key] = {a.value: float(p) for a, p in zip(node.actions, row, strict=True)}
        return strategy

    def run(
        self,
        iterations: int,
        *,
        every: int = 1,
        progress: Callable[[CurvePoint], None] | None = None,
    ) -> list[CurvePoint]:
        """``iterations`` more iterations; the average strategy's exploitability after every
        ``every``-th and after the last."""
        check_count("iterations", iterations, low=1, high=MAX_ITERATIONS)
        check_count("every", every, low=1, high=MAX_ITERATIONS)
        curve = []
        end = self.iteration + iterations
        while self.iteration < end:
            self.step()
            if self.iteration % every == 0 or self.iteration == end:
                point = CurvePoint(
                    iteration=self.iteration,
                    exploitability=exploitability(self.rules, self.average()),
                )
                curve.append(point)
                if progress is not None:
                    progress(point)
        return curve


def _matched(values: np.ndarray) -> np.ndarray:
    """Rows of non-negative ``values`` normalized; uniform where a row sums to zero."""
    total = values.sum(axis=1, keepdims=True)
    uniform = np.full_like(values, 1.0 / values.shape[1])
    return np.where(total > 0, values / np.where(total > 0, total, 1.0), uniform)
