"""The betting tree of a rule set, with every deal at once: what the exact tools and the
CFR+ solver walk.

The betting does not depend on the cards, so one tree of public histories serves every deal
(the two private cards and the public card, in order: ``n (n-1) (n-2)`` equally likely
deals of ``n`` cards). Each decision node maps every deal to the row of the actor's
information set at that node (its card, the public card in the second round), so a strategy
at a node is a ``rows x actions`` table and the walks are numpy operations over the deals.

>>> from pokerirl.game.leduc.rules import RLCARD, OPENSPIEL
>>> tree = betting_tree(RLCARD)
>>> len(tree.deals), tree.decisions, len(tree.keys())
(120, 36, 288)
>>> betting_tree(OPENSPIEL).decisions, len(betting_tree(OPENSPIEL).keys())
(36, 936)
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

from pokerirl.game.leduc.engine import LeducState, deal, info_key, showdowns
from pokerirl.game.leduc.rules import Action, LeducRules


@dataclass(frozen=True, kw_only=True, eq=False)
class Node:
    """A public history. A decision node has an actor, its actions and one child per action;
    a leaf has the payoffs of position 0 for every deal."""

    histories: tuple[str, ...]
    chips: tuple[int, int]  # each position's chips in the pot
    round: int  # 2 after the second round
    folded: int | None
    actor: int | None  # None at a leaf
    actions: tuple[Action, ...] = ()
    children: tuple[Node, ...] = ()
    rows: np.ndarray | None = None  # deal -> row of the actor's information set
    keys: tuple[str, ...] = ()  # row -> information-set key
    payoff: np.ndarray | None = None  # at a leaf: position 0's chips, by deal

    def bincount(self, weights: np.ndarray) -> np.ndarray:
        """Per-row sums of ``deals x actions`` ``weights``: ``rows x actions``."""
        assert self.rows is not None
        return np.stack(
            [np.bincount(self.rows, w, minlength=len(self.keys)) for w in weights.T], axis=1
        )


@dataclass(frozen=True, kw_only=True, eq=False)
class BettingTree:
    """The tree of ``rules`` and its deals (``deals x 3`` card ids)."""

    rules: LeducRules
    deals: np.ndarray
    root: Node

    @property
    def chance(self) -> float:
        """The probability of each deal."""
        return 1.0 / len(self.deals)

    def nodes(self) -> list[Node]:
        """The decision nodes, parents before children."""
        found: list[Node] = []
        stack = [self.root]
        while stack:
            node = stack.pop()
            if node.actor is not None:
                found.append(node)
                stack.extend(reversed(node.children))
        return found

    @property
    def decisions(self) -> int:
        return len(self.nodes())

    def keys(self) -> dict[str, tuple[Action, ...]]:
        """Every information set's key and its legal actions, in tree order."""
        return {key: node.actions for node in self.nodes() for key in node.keys}


@functools.lru_cache(maxsize=8)
def betting_tree(rules: LeducRules) -> BettingTree:
    """The tree of ``rules`` (built once per rule set)."""
    deals = np.array(list(itertools.permutations(range(rules.cards), 3)), dtype=np.int64)
    signs = showdowns(deals).astype(np.float64)
    start = deal(rules, cards=(0, 1, 2))  # the betting is the same for every deal
    return BettingTree(rules=rules, deals=deals, root=_node(start, deals, signs))


def _node(state: LeducState, deals: np.ndarray, signs: np.ndarray) -> Node:
    if state.is_over:
        if state.folded is not None:
            loss = state.chips[state.folded]
            payoff = np.full(len(deals), -loss if state.folded == 0 else loss, dtype=np.float64)
        else:
            payoff = signs * state.chips[0]  # equal chips at a showdown
        return Node(**_public(state), actor=None, payoff=payoff)
    actor = state.to_act
    seen = [
        info_key(state.rules, own, public if state.round else None, state.histories)
        for own, public in zip(deals[:, actor].tolist(), deals[:, 2].tolist(), strict=True)
    ]
    keys = tuple(dict.fromkeys(seen))
    row_of = {key: row for row, key in enumerate(keys)}
    actions = state.legal_actions()
    return Node(
        **_public(state),
        actor=actor,
        actions=actions,
        children=tuple(_node(state.step(a), deals, signs) for a in actions),
        rows=np.array([row_of[key] for key in seen], dtype=np.int64),
        keys=keys,
    )


def _public(state: LeducState) -> dict[str, Any]:
    return {
        "histories": state.histories, "chips": state.chips, "round": state.round,
        "folded": state.folded,
    }  # fmt: skip
