"""Leduc hold'em: two rule sets (RLCard's ``leduc-holdem``, OpenSpiel's ``leduc_poker``), a
hand engine, exact best response, exploitability and expected values, and a CFR+ solver.
docs/leduc.md describes the rules and the tools."""

from __future__ import annotations

from pokerirl.game.leduc.batch import LeducBatch
from pokerirl.game.leduc.cfr import CFRPlus
from pokerirl.game.leduc.engine import OBSERVATION_SIZE, LeducState, deal, random_deal
from pokerirl.game.leduc.exact import (
    MILLI,
    agreement,
    best_response,
    expected_value,
    exploitability,
)
from pokerirl.game.leduc.rules import (
    OPENSPIEL,
    RLCARD,
    Action,
    LeducRules,
    RuleSet,
    get_rules,
)
from pokerirl.game.leduc.strategy import (
    read_strategy,
    strategy_from_callable,
    uniform_strategy,
)

__all__ = [
    "MILLI",
    "OBSERVATION_SIZE",
    "OPENSPIEL",
    "RLCARD",
    "Action",
    "CFRPlus",
    "LeducBatch",
    "LeducRules",
    "LeducState",
    "RuleSet",
    "agreement",
    "best_response",
    "deal",
    "expected_value",
    "exploitability",
    "get_rules",
    "random_deal",
    "read_strategy",
    "strategy_from_callable",
    "uniform_strategy",
]
