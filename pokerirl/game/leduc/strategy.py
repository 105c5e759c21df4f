"""Strategies of Leduc hold'em: action probabilities per information set, checked against a
rule set's tree, built from a callable, written as JSON with fixed formatting (same strategy,
same bytes) and read back.

A strategy is a mapping ``key -> {action: probability}`` over the keys of
:meth:`~pokerirl.game.leduc.engine.LeducState.info_key`; it covers both positions (the
betting in a key says whose turn it is). The file is
``{"format": "leduc-strategy", "version": 1, "rules": ..., "strategy": {...}}``.

>>> from pokerirl.game.leduc.rules import RLCARD
>>> uniform = uniform_strategy(RLCARD)
>>> uniform["K:"]
{'fold': 0.3333333333333333, 'call': 0.3333333333333333, 'raise': 0.3333333333333333}
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from pokerirl.errors import InputError
from pokerirl.game.leduc.rules import Action, LeducRules, get_rules
from pokerirl.game.leduc.tree import BettingTree, Node, betting_tree

Strategy = Mapping[str, Mapping[str, float]]
FORMAT = "leduc-strategy"
DIGITS = 12  # decimals written: fixed, so the same strategy is the same bytes
TOLERANCE = 1e-6  # how far from 1 a row may sum (files hold DIGITS decimals)


def uniform_strategy(rules: LeducRules) -> dict[str, dict[str, float]]:
    """Every legal action equally likely."""
    return {
        key: {a.value: 1.0 / len(actions) for a in actions}
        for key, actions in betting_tree(rules).keys().items()
    }


def strategy_from_callable(
    rules: LeducRules, policy: Callable[[str, tuple[Action, ...]], Mapping[str, float]]
) -> dict[str, dict[str, float]]:
    """The strategy that ``policy(key, legal_actions)`` gives at every information set (an
    agent's action probabilities, by action name)."""
    return {
        key: {str(a): float(p) for a, p in policy(key, actions).items()}
        for key, actions in betting_tree(rules).keys().items()
    }


def profile(rules: LeducRules, first: Strategy, second: Strategy) -> dict[str, dict[str, float]]:
    """The strategy that plays ``first`` in position 0 and ``second`` in position 1 (the keys
    of the two positions never meet: the betting says whose turn it is), for the
    exploitability of a strategy pair."""
    found: dict[str, dict[str, float]] = {}
    for node in betting_tree(rules).nodes():
        source = first if node.actor == 0 else second
        found.update({key: dict(source[key]) for key in node.keys if key in source})
    return found


def tables(tree: BettingTree, strategy: Strategy, *, positions: tuple[int, ...] = (0, 1)
           ) -> dict[int, np.ndarray]:  # fmt: skip
    """``id(node) -> rows x actions`` probabilities at each decision node of ``positions``
    (an :class:`InputError` naming the first key missing or not a distribution)."""
    found: dict[int, np.ndarray] = {}
    for node in tree.nodes():
        if node.actor in positions:
            found[id(node)] = _table(node, strategy)
    return found


def _table(node: Node, strategy: Strategy) -> np.ndarray:
    table = np.zeros((len(node.keys), len(node.actions)))
    names = [a.value for a in node.actions]
    for row, key in enumerate(node.keys):
        probabilities = strategy.get(key)
        if probabilities is None:
            raise InputError(f"the strategy has no information set {key!r}")
        extra = set(probabilities) - set(names)
        if any(probabilities[name] != 0 for name in extra):
            raise InputError(f"information set {key!r}: illegal actions {sorted(extra)}")
        values = [probabilities.get(name, 0.0) for name in names]
        if not all(isinstance(v, int | float) and math.isfinite(v) and v >= 0 for v in values):
            raise InputError(f"information set {key!r}: probabilities must be >= 0, got {values}")
        total = math.fsum(values)
        if abs(total - 1) > TOLERANCE:
            raise InputError(f"information set {key!r}: probabilities sum to {total}, not 1")
        table[row] = np.asarray(values) / total
    return table


def to_json(rules: LeducRules, strategy: Strategy, **extra: object) -> str:
    """The strategy file's text: keys in tree order, probabilities with :data:`DIGITS`
    decimals."""
    keys = betting_tree(rules).keys()
    body = {
        key: {name: round(float(p), DIGITS) for name, p in strategy[key].items()}
        for key in keys
        if key in strategy
    }
    document = {"format": FORMAT, "version": 1, "rules": rules.name, **extra, "strategy": body}
    return json.dumps(document, indent=1) + "\n"


def sha256(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def read_strategy(path: str | Path) -> tuple[LeducRules, dict[str, dict[str, float]]]:
    """The rules and the strategy of a strategy file (an :class:`InputError` naming the file
    for anything else, a strategy that does not cover its rules' tree included)."""
    from pokerirl.errors import ConfigError
    from pokerirl.jsonio import read_json_object

    document = read_json_object(path)
    if document.get("format") != FORMAT or not isinstance(document.get("strategy"), dict):
        raise InputError(f"{path}: not a Leduc strategy file (format {FORMAT!r})")
    try:
        rules = get_rules(str(document.get("rules")))
    except ConfigError as error:
        raise InputError(f"{path}: {error}") from None
    strategy = document["strategy"]
    if not all(isinstance(v, dict) for v in strategy.values()):
        raise InputError(f"{path}: each information set needs {{action: probability}}")
    try:
        tables(betting_tree(rules), strategy)
    except InputError as error:
        raise InputError(f"{path}: {error}") from None
    return rules, strategy
