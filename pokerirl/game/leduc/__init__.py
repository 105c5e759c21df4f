"""Leduc hold'em: two rule sets (RLCard's ``leduc-holdem``, OpenSpiel's ``leduc_poker``), a
hand engine, exact best response, exploitability and expected values, and a CFR+ solver.
docs/leduc.md describes the rules and the tools."""

from __future__ import annotations

from pokerirl.game.leduc.engine import OBSERVATION_SIZE, LeducState, deal, random_deal
from pokerirl.game.leduc.rules import (
    OPENSPIEL,
    RLCARD,
    Action,
    LeducRules,
    RuleSet,
    get_rules,
)

__all__ = [
    "OBSERVATION_SIZE",
    "OPENSPIEL",
    "RLCARD",
    "Action",
    "LeducRules",
    "LeducState",
    "RuleSet",
    "deal",
    "get_rules",
    "random_deal",
]
