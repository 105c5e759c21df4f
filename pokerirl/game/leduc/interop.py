"""The reference implementations beside ours: OpenSpiel's ``leduc_poker`` (its
information-state strings as our keys, its tabular policies as our strategies and back;
``pip install open_spiel``) and RLCard's ``leduc-holdem`` (:func:`replay_rlcard` plays random
hands through it and through our engine, decision by decision). Tests and
``benchmarks/leduc.py`` use them.

OpenSpiel's actions are 0 fold, 1 call (a check when no bet is faced), 2 raise; RLCard's
0 call, 1 raise, 2 fold, 3 check.
"""

from __future__ import annotations

import functools
import itertools
from typing import Any

from pokerirl.errors import MissingExtra
from pokerirl.game.leduc.engine import LeducState, deal
from pokerirl.game.leduc.rules import OPENSPIEL, RLCARD, Action
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


RLCARD_ACTIONS = (Action.CALL, Action.RAISE, Action.FOLD, Action.CHECK)  # by RLCard's id
RLCARD_CARDS = {"SJ": 0, "HJ": 1, "SQ": 2, "HQ": 3, "SK": 4, "HK": 5}  # its deck's order


class Mismatch(AssertionError):
    """Our engine and the reference disagree."""


def replay_rlcard(hands: int, *, seed: int) -> int:
    """Play ``hands`` random hands through RLCard's ``leduc-holdem`` and our RLCard rules
    side by side; raise :class:`Mismatch` at the first observation, legal action set or
    payoff that differs. Returns the decisions compared.

    RLCard deals and seats the small blind at random; we read its deal (the two hands, the
    card its dealer pops next for the board, the small blind's seat) and replay its actions.
    """
    import numpy as np
    import rlcard  # the environments only (rlcard.agents would run pip freeze)

    env = rlcard.make("leduc-holdem", config={"seed": seed})
    rng = np.random.default_rng(seed)
    decisions = 0
    for hand in range(hands):
        state, player = env.reset()
        game = env.game
        seats = (player, 1 - player)  # position -> RLCard's player id: the small blind first
        held = (game.players[seats[0]].hand, game.players[seats[1]].hand, game.dealer.deck[-1])
        a, b, c = (RLCARD_CARDS[card.get_index()] for card in held)
        ours = deal(RLCARD, cards=(a, b, c))
        while not env.is_over():
            position = seats.index(player)
            legal = [RLCARD_ACTIONS.index(x) for x in ours.legal_actions()]
            if ours.to_act != position or sorted(legal) != sorted(state["legal_actions"]) \
                    or not np.array_equal(ours.observation(position), state["obs"]):  # fmt: skip
                raise Mismatch(f"hand {hand}: {ours.info_key(position)} differs from RLCard's")
            move = int(rng.choice(legal))
            state, player = env.step(move)
            ours = ours.step(RLCARD_ACTIONS[move])
            decisions += 1
        payoffs = env.get_payoffs()
        won = [payoffs[seat] * RLCARD.env_chips_per_unit for seat in seats]
        if not ours.is_over or won != list(ours.payoffs()):
            raise Mismatch(f"hand {hand}: payoffs {ours.payoffs()} against RLCard's {won}")
    return decisions
