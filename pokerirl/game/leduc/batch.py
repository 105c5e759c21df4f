"""Many Leduc hands at once: each hand is its deal and a node of the betting tree, so a step
of every hand is a lookup in arrays built once from :mod:`pokerirl.game.leduc.tree` (which
the one-hand engine built). What ``benchmarks/leduc.py`` times against RLCard's env.

>>> import numpy as np
>>> from pokerirl.game.leduc.rules import RLCARD
>>> batch = LeducBatch(RLCARD, cards=np.array([[4, 0, 2], [0, 4, 1]]))
>>> batch.legal()  # fold, check, call, raise: the small blind faces the big blind
array([[ True, False,  True,  True],
       [ True, False,  True,  True]])
>>> batch.step(np.array([ACTIONS.index(Action.FOLD), ACTIONS.index(Action.CALL)]))
>>> batch.over.tolist(), batch.payoffs()[0].tolist()
([True, False], [-1.0, 1.0])
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from pokerirl.errors import ConfigError
from pokerirl.game.engine import IllegalActionError
from pokerirl.game.leduc.engine import OBSERVATION_SIZE, showdowns
from pokerirl.game.leduc.rules import Action, LeducRules
from pokerirl.game.leduc.tree import Node, betting_tree

ACTIONS = tuple(Action)  # the columns of legal(): fold, check, call, raise


@dataclass(frozen=True, kw_only=True, eq=False)
class NodeArrays:
    """The betting tree as arrays, by node id (the root is 0)."""

    actor: np.ndarray  # -1 at a leaf
    child: np.ndarray  # nodes x 4 (ACTIONS): the next node, -1 where illegal
    chips: np.ndarray  # nodes x 2: each position's chips in the pot
    round: np.ndarray  # 0 or 1 (2 at a showdown)
    folded: np.ndarray  # the position that folded, -1 if none
    showdown: np.ndarray  # a leaf reached by calling the last round


@functools.lru_cache(maxsize=8)
def node_arrays(rules: LeducRules) -> NodeArrays:
    """The arrays of ``rules``'s tree."""
    nodes: list[Node] = []
    stack = [betting_tree(rules).root]
    while stack:
        node = stack.pop()
        nodes.append(node)
        stack.extend(reversed(node.children))
    index = {id(node): i for i, node in enumerate(nodes)}
    child = np.full((len(nodes), len(ACTIONS)), -1, dtype=np.int64)
    for i, node in enumerate(nodes):
        for action, kid in zip(node.actions, node.children, strict=True):
            child[i, ACTIONS.index(action)] = index[id(kid)]
    return NodeArrays(
        actor=np.array([-1 if n.actor is None else n.actor for n in nodes], dtype=np.int64),
        child=child,
        chips=np.array([n.chips for n in nodes], dtype=np.int64),
        round=np.array([n.round for n in nodes], dtype=np.int64),
        folded=np.array([-1 if n.folded is None else n.folded for n in nodes], dtype=np.int64),
        showdown=np.array([n.actor is None and n.folded is None for n in nodes]),
    )


class LeducBatch:
    """Hands of ``cards`` (``hands x 3``: position 0's, position 1's, the public card)."""

    def __init__(self, rules: LeducRules, *, cards: np.ndarray) -> None:
        cards = np.asarray(cards, dtype=np.int64)
        if cards.ndim != 2 or cards.shape[1] != 3 or cards.min(initial=0) < 0 \
                or cards.max(initial=0) >= rules.cards \
                or np.any((cards[:, 0] == cards[:, 1]) | (cards[:, 0] == cards[:, 2])
                          | (cards[:, 1] == cards[:, 2])):  # fmt: skip
            raise ConfigError(f"cards must be hands x 3 different cards in 0..{rules.cards - 1}")
        self.rules, self.cards = rules, cards
        self.arrays = node_arrays(rules)
        self.node = np.zeros(len(cards), dtype=np.int64)

    @classmethod
    def dealt(cls, rules: LeducRules, hands: int, rng: np.random.Generator) -> LeducBatch:
        """``hands`` hands dealt from shuffled decks."""
        keys = rng.random((hands, rules.cards))
        return cls(rules, cards=np.argsort(keys, axis=1)[:, :3])

    @property
    def over(self) -> np.ndarray:
        return self.arrays.actor[self.node] < 0

    @property
    def to_act(self) -> np.ndarray:
        """Each hand's position to act (-1 once over)."""
        return self.arrays.actor[self.node]

    def legal(self) -> np.ndarray:
        """``hands x 4`` legal actions (:data:`ACTIONS` order); none once over."""
        return self.arrays.child[self.node] >= 0

    def step(self, actions: np.ndarray) -> None:
        """Play ``actions`` (indices into :data:`ACTIONS`) in the hands not over."""
        live = ~self.over
        nxt = self.arrays.child[self.node[live], np.asarray(actions)[live]]
        if np.any(nxt < 0):
            raise IllegalActionError("an illegal action in a hand of the batch")
        self.node[live] = nxt

    def payoffs(self) -> np.ndarray:
        """``hands x 2`` chips won by each position (zero until a hand is over)."""
        arrays, node = self.arrays, self.node
        chips = arrays.chips[node]
        folded = arrays.folded[node]
        first = np.where(arrays.showdown[node], showdowns(self.cards) * chips[:, 1], 0)
        first = np.where(folded == 0, -chips[:, 0], np.where(folded == 1, chips[:, 1], first))
        return np.stack([first, -first], axis=1).astype(np.float64)

    def observations(self, position: np.ndarray) -> np.ndarray:
        """RLCard's 36-d observation of ``position`` (one per hand)."""
        rows = np.arange(len(self.node))
        position = np.asarray(position, dtype=np.int64)
        chips = self.arrays.chips[self.node]
        obs = np.zeros((len(rows), OBSERVATION_SIZE))
        obs[rows, self.cards[rows, position] // 2] = 1
        shown = self.arrays.round[self.node] >= 1
        obs[rows[shown], 3 + self.cards[shown, 2] // 2] = 1
        obs[rows, 6 + chips[rows, position]] = 1
        obs[rows, 21 + chips[rows, 1 - position]] = 1
        return obs

    def play_random(self, rng: np.random.Generator) -> None:
        """Play every hand to its end, each action uniform among the legal ones."""
        while not self.over.all():
            draws = rng.random((len(self.node), len(ACTIONS))) * self.legal()
            self.step(draws.argmax(axis=1))
