"""OpenSpiel's ``leduc_poker`` and our OpenSpiel rules, side by side: its information-state
strings as our keys, its tabular policies as our strategies and back (tests and
``benchmarks/leduc.py`` compare the two; ``pip install open_spiel``).

OpenSpiel's actions are 0 fold, 1 call (a check when no bet is faced), 2 raise.
"""

from __future__ import annotations

import functools
import itertools
from typing import Any

from pokerirl.errors import MissingExtra
from pokerirl.game.leduc.engine import LeducState, deal
from pokerirl.game.leduc.rules import OPENSPIEL, Action
from pokerirl.game.leduc.strategy import Strategy
from pokerirl.game.leduc.tree import betting_tree

GAME = "leduc_poker"


def _pyspiel() -> Any:
    try:
        import pyspiel
    except ImportError as error:
        raise MissingExtra("OpenSpiel is not installed: pip install open_spiel") from error
    return pyspiel


ACTION_IDS = {Action.FOLD: 0, Action.CHECK: 1, Action.CALL: 1, Action.RAISE: 2}


def ours(state: LeducState, action_id: int) -> Action:
    """Our action for OpenSpiel's ``action_id`` at ``state``."""
    return next(a for a in state.legal_actions() if ACTION_IDS[a] == action_id)


@functools.lru_cache(maxsize=1)
def key_map() -> dict[str, str]:
    """OpenSpiel's information-state string -> our key, for every decision of every deal."""
    game = _pyspiel().load_game(GAME)
    found: dict[str, str] = {}

    def walk(theirs: Any, mine: LeducState) -> None:
        if theirs.is_terminal():
            return
        if theirs.is_chance_node():  # the public card: the one ours was dealt
            walk(theirs.child(mine.cards[2]), mine)
            return
        player = theirs.current_player()
        assert player == mine.to_act
        found[theirs.information_state_string(player)] = mine.info_key(player)
        for action_id in theirs.legal_actions():
            walk(theirs.child(action_id), mine.step(ours(mine, action_id)))

    for first, second, public in itertools.permutations(range(OPENSPIEL.cards), 3):
        state = game.new_initial_state()
        state.apply_action(first)
        state.apply_action(second)
        walk(state, deal(OPENSPIEL, cards=(first, second, public)))
    return found


def from_openspiel(policy: Any) -> dict[str, dict[str, float]]:
    """Our strategy of OpenSpiel's ``TabularPolicy`` over ``leduc_poker``."""
    keys, legal_of = key_map(), betting_tree(OPENSPIEL).keys()
    strategy: dict[str, dict[str, float]] = {}
    for theirs, row in policy.state_lookup.items():
        key = keys[theirs]
        probabilities = policy.action_probability_array[row]
        strategy[key] = {
            a.value: float(probabilities[ACTION_IDS[a]]) for a in legal_of[key]
        }
    return strategy


def to_openspiel(strategy: Strategy) -> Any:
    """OpenSpiel's ``TabularPolicy`` of our strategy over ``leduc_poker``."""
    from open_spiel.python import policy as policies

    tabular = policies.TabularPolicy(_pyspiel().load_game(GAME))
    keys = key_map()
    tabular.action_probability_array[:] = 0.0
    for theirs, row in tabular.state_lookup.items():
        for name, p in strategy[keys[theirs]].items():
            tabular.action_probability_array[row, ACTION_IDS[Action(name)]] = p
    return tabular
