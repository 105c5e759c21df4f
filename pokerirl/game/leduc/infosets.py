"""Every information set of a rule set as rows of arrays, and the map from a batch's hands to
those rows: what the demonstrations, the tabular agents and the study share.

An :class:`InfoSets` numbers the keys of :meth:`BettingTree.keys` (tree order) and gives each
its 36-d observation, its legal actions (the four columns of
:data:`~pokerirl.game.leduc.batch.ACTIONS`) and, per node of
:func:`~pokerirl.game.leduc.batch.node_arrays` and deal, the row of the actor's set.

>>> from pokerirl.game.leduc.rules import RLCARD
>>> sets = info_sets(RLCARD)
>>> len(sets.keys), sets.observations.shape, sets.legal[sets.row["K:"]].tolist()
(288, (288, 36), [True, False, True, True])
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from pokerirl.game.leduc.batch import ACTIONS
from pokerirl.game.leduc.engine import OBSERVATION_SIZE
from pokerirl.game.leduc.rules import Action, LeducRules
from pokerirl.game.leduc.strategy import Strategy, tables
from pokerirl.game.leduc.tree import Node, betting_tree


@dataclass(frozen=True, kw_only=True, eq=False)
class InfoSets:
    """The information sets of ``rules``, by row."""

    rules: LeducRules
    keys: tuple[str, ...]
    row: Mapping[str, int]
    observations: np.ndarray  # rows x 36: RLCard's observation (the same for every deal)
    legal: np.ndarray  # rows x 4 bool, ACTIONS order
    node_rows: np.ndarray  # batch nodes x deals: the actor's row, -1 at a leaf
    deal_index: np.ndarray  # cards^3: the deal's index in the tree's deals (-1: not a deal)

    def rows_of(self, node: np.ndarray, cards: np.ndarray) -> np.ndarray:
        """The actor's row in each hand (``cards``: hands x 3) at batch node ``node``."""
        n = self.rules.cards
        deals = self.deal_index[(cards[:, 0] * n + cards[:, 1]) * n + cards[:, 2]]
        return self.node_rows[node, deals]

    def probabilities(self, strategy: Strategy) -> np.ndarray:
        """rows x 4: ``strategy``'s probabilities (0 for illegal actions); an
        :class:`~pokerirl.errors.InputError` if it does not cover the rules' tree."""
        tree = betting_tree(self.rules)
        found = np.zeros((len(self.keys), len(ACTIONS)))
        by_node = tables(tree, strategy)
        for node in tree.nodes():
            columns = [ACTIONS.index(a) for a in node.actions]
            rows = [self.row[key] for key in node.keys]
            found[np.ix_(rows, columns)] = by_node[id(node)]
        return found

    def strategy(self, probabilities: np.ndarray) -> dict[str, dict[str, float]]:
        """The strategy of ``rows x 4`` probabilities (renormalized over the legal actions)."""
        found: dict[str, dict[str, float]] = {}
        for row, key in enumerate(self.keys):
            legal = np.flatnonzero(self.legal[row])
            p = np.clip(probabilities[row, legal], 0.0, None)
            p = p / p.sum() if p.sum() > 0 else np.full(len(legal), 1 / len(legal))
            found[key] = {ACTIONS[a].value: float(q) for a, q in zip(legal, p, strict=True)}
        return found

    def greedy(self, values: np.ndarray) -> dict[str, dict[str, float]]:
        """The pure strategy taking the legal argmax of ``rows x 4`` values (ties: the first
        legal action in ACTIONS order, as :func:`~pokerirl.game.leduc.exact.agreement`)."""
        return self.strategy(one_hot_argmax(values, self.legal))


def one_hot_argmax(values: np.ndarray, legal: np.ndarray) -> np.ndarray:
    """rows x 4: 1 at each row's legal argmax."""
    best = np.where(legal, values, -np.inf).argmax(axis=1)
    found = np.zeros(values.shape)
    found[np.arange(len(best)), best] = 1.0
    return found


@functools.lru_cache(maxsize=8)
def info_sets(rules: LeducRules) -> InfoSets:
    """The :class:`InfoSets` of ``rules`` (built once per rule set)."""
    tree = betting_tree(rules)
    legal_of = tree.keys()
    keys = tuple(legal_of)
    row = {key: i for i, key in enumerate(keys)}
    legal = np.array([[a in legal_of[key] for a in ACTIONS] for key in keys])
    observations = np.zeros((len(keys), OBSERVATION_SIZE))
    nodes = _batch_nodes(tree.root)  # node_arrays' order
    node_rows = np.full((len(nodes), len(tree.deals)), -1, dtype=np.int64)
    for i, node in enumerate(nodes):
        if node.actor is None:
            continue
        assert node.rows is not None
        global_rows = np.array([row[key] for key in node.keys], dtype=np.int64)
        node_rows[i] = global_rows[node.rows]
        first = np.unique(node.rows, return_index=True)[1]  # a deal of each of its sets
        for local, deal in enumerate(first.tolist()):
            own, public = tree.deals[deal, node.actor], tree.deals[deal, 2]
            obs = observations[global_rows[local]]
            obs[:] = 0
            obs[own // 2] = 1
            if node.round >= 1:
                obs[3 + public // 2] = 1
            obs[6 + node.chips[node.actor]] = 1
            obs[21 + node.chips[1 - node.actor]] = 1
    n = rules.cards
    deal_index = np.full(n**3, -1, dtype=np.int64)
    deals = tree.deals
    deal_index[(deals[:, 0] * n + deals[:, 1]) * n + deals[:, 2]] = np.arange(len(deals))
    return InfoSets(
        rules=rules, keys=keys, row=row, observations=observations, legal=legal,
        node_rows=node_rows, deal_index=deal_index,
    )  # fmt: skip


def _batch_nodes(root: Node) -> list[Node]:
    """Every node, leaves too, in :func:`~pokerirl.game.leduc.batch.node_arrays`' order."""
    nodes: list[Node] = []
    stack = [root]
    while stack:
        node = stack.pop()
        nodes.append(node)
        stack.extend(reversed(node.children))
    return nodes


def pure(rules: LeducRules, choose: Mapping[Action, int]) -> dict[str, dict[str, float]]:
    """A pure strategy choosing, at every set, the legal action of the highest priority in
    ``choose`` (e.g. always call, else check): the simple bots of the tests and demos."""
    sets = info_sets(rules)
    values = np.array([[choose.get(a, -1) for a in ACTIONS]] * len(sets.keys), dtype=float)
    return sets.greedy(values)
