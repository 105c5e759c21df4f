"""Vectorized heads-up limit hold'em with RLCard 1.2.0's rules: deals, hand strength, engine,
agents and matches; Leduc hold'em in :mod:`pokerirl.game.leduc`; the :class:`Game` protocol both
implement (:mod:`pokerirl.game.games`). See ``docs/rules.md`` for how the rules differ from
ACPC's."""

from __future__ import annotations

from pokerirl.game.bots import (
    BUILT_IN_AGENTS,
    Agent,
    CallAgent,
    RaiseAgent,
    RandomAgent,
    ScriptedAgent,
    agent_actions,
    make_agent,
    seat_cards,
)
from pokerirl.game.deals import DEAL_SIZE, deal_cards
from pokerirl.game.engine import (
    BIG_BLIND,
    SMALL_BLIND,
    IllegalActionError,
    LimitHoldemBatch,
)
from pokerirl.game.evaluator import HAND_CATEGORIES, category, hand_strength
from pokerirl.game.games import HOLDEM, Game, Hands, LeducGame, play_out
from pokerirl.game.match import (
    DecisionLog,
    MatchResult,
    check_match_size,
    play_batch,
    play_match,
    turn_cards,
)

__all__ = [
    "BIG_BLIND",
    "BUILT_IN_AGENTS",
    "DEAL_SIZE",
    "HAND_CATEGORIES",
    "HOLDEM",
    "SMALL_BLIND",
    "Agent",
    "CallAgent",
    "DecisionLog",
    "Game",
    "Hands",
    "IllegalActionError",
    "LeducGame",
    "LimitHoldemBatch",
    "MatchResult",
    "RaiseAgent",
    "RandomAgent",
    "ScriptedAgent",
    "agent_actions",
    "category",
    "check_match_size",
    "deal_cards",
    "hand_strength",
    "make_agent",
    "play_batch",
    "play_match",
    "play_out",
    "seat_cards",
    "turn_cards",
]
