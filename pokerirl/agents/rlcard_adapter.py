"""Play a pokerirl agent inside RLCard 1.2.0: an adapter with RLCard's agent interface.

:class:`RLCardAgent` wraps any :class:`~pokerirl.game.bots.Agent` (a built-in, an agent
folder, ``reward:RUN``: whatever :func:`~pokerirl.agents.resolve_agent` returns) so that it
sits in ``rlcard.make("limit-holdem")`` and plays RLCard's own ``rlcard.utils.tournament``:
``use_raw`` False, ``step(state)`` and ``eval_step(state)`` returning ``(action, info)``.

Each RLCard state becomes the decision state the engine would give the agent
(:func:`rlcard_states`): hole cards, the board in the order dealt and the raise counts from
``state["raw_obs"]``, the legal actions from ``state["legal_actions"]`` (RLCard's action ids
are pokerirl's: call, raise, fold, check). The agent then reads it in its own encoding, and
an agent that sees the cards gets them, exactly as in :func:`~pokerirl.game.play_match`.

RLCard 1.2.0 hands out the first state of every hand but the first with the previous
hand's raise counts (``tests/test_game_engine.py``,
``test_rlcard_first_state_has_stale_raise_counts``): the small blind's first decision has
no raise yet in any round, so there they are read as zero.

>>> import numpy as np
>>> from collections import OrderedDict
>>> state = {"raw_obs": {"hand": ["SA", "HA"], "public_cards": [], "my_chips": 1,
...                      "raise_nums": [2, 0, 0, 0]},  # stale, from the hand before
...          "legal_actions": OrderedDict({0: None, 1: None, 2: None})}
>>> rlcard_states(state).raise_nums.tolist()
[[0, 0, 0, 0]]
>>> from pokerirl.agents import resolve_agent
>>> RLCardAgent(agent=resolve_agent("raise")).eval_step(state)
(1, {'probs': {'call': 0.0, 'raise': 1.0, 'fold': 0.0}})
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pokerirl.errors import InputError, check_count
from pokerirl.game.bots import Agent, agent_action_probs, agent_actions
from pokerirl.game.encodings import RawStates
from pokerirl.game.engine import SMALL_BLIND
from pokerirl.game.match import agent_encoding
from pokerirl.holdem import ACTIONS, NUM_ACTIONS, NUM_CARDS, NUM_ROUNDS, rlcard_card_str

# RLCard's suit-then-rank card text ("SA", "CQ") -> pokerirl's card index.
RLCARD_CARD_INDEX: Mapping[str, int] = {rlcard_card_str(i): i for i in range(NUM_CARDS)}

def _card_indices(texts: Any, what: str) -> list[int]:
    try:
        return [RLCARD_CARD_INDEX[text] for text in texts]
    except (KeyError, TypeError):
        raise InputError(f"RLCard state: {what} {texts!r} are not RLCard cards") from None


def rlcard_states(state: Mapping[str, Any]) -> RawStates:
    """The one decision state (a :class:`~pokerirl.game.encodings.RawStates` of length 1) of an
    RLCard ``limit-holdem`` state of the player to act.

    Raises:
        InputError: not a limit hold'em state (one line).
    """
    raw = state.get("raw_obs")
    if not isinstance(raw, Mapping) or "legal_actions" not in state:
        raise InputError("RLCard state: no raw_obs or legal_actions (not a limit-holdem state)")
    hole = _card_indices(raw.get("hand"), "hand")
    board = _card_indices(raw.get("public_cards"), "public_cards")
    if len(hole) != 2 or len(board) not in (0, 3, 4, 5):
        raise InputError(f"RLCard state: {len(hole)} hole and {len(board)} board cards")
    cards = np.full((1, 7), -1, dtype=np.int8)
    cards[0, : 2 + len(board)] = hole + board
    raise_nums = np.zeros((1, NUM_ROUNDS), dtype=np.int8)
    # The small blind before its first action: no raise yet, whatever RLCard's stale list says.
    if board or raw.get("my_chips") != SMALL_BLIND:
        raise_nums[0] = np.asarray(raw.get("raise_nums"), dtype=np.int8)
    legal = np.zeros((1, NUM_ACTIONS), dtype=bool)
    legal[0, list(state["legal_actions"])] = True
    return RawStates(cards=cards, raise_nums=raise_nums, legal_mask=legal)


@dataclass(frozen=True, kw_only=True)
class RLCardAgent:
    """A pokerirl :class:`~pokerirl.game.bots.Agent` with RLCard 1.2.0's agent interface.

    ``env.set_agents([RLCardAgent(agent=resolve_agent("agents/dqn")), RandomAgent(4)])``,
    then ``rlcard.utils.tournament(env, hands)``. ``seed`` seeds the generator the agent
    draws its random choices from (none for a deterministic agent). ``step`` and
    ``eval_step`` choose alike: the wrapped agent decides how it plays, RLCard only whether
    it trains; ``eval_step``'s info holds ``probs`` by action name when the agent can say them.
    """

    agent: Agent
    seed: int = 0
    rng: np.random.Generator = field(init=False, repr=False)
    use_raw: bool = field(default=False, init=False)  # RLCard: step returns action ids

    def __post_init__(self) -> None:
        if not (callable(getattr(self.agent, "act", None)) and hasattr(self.agent, "name")):
            raise TypeError(
                f"agent must be a pokerirl Agent (resolve_agent gives one), got {self.agent!r:.60}"
            )
        check_count("seed", self.seed, low=0, high=2**32 - 1)
        object.__setattr__(self, "rng", np.random.default_rng(self.seed))

    @property
    def name(self) -> str:
        """The wrapped agent's name."""
        return self.agent.name

    def _decide(self, states: RawStates, obs: np.ndarray) -> int:
        action = agent_actions(self.agent, obs, states.legal_mask, self.rng, lambda: states.cards)
        return int(action[0])

    def step(self, state: Mapping[str, Any]) -> int:
        """The agent's action id for an RLCard state (RLCard calls it while training)."""
        states = rlcard_states(state)
        return self._decide(states, agent_encoding(self.agent).encode(states))

    def eval_step(self, state: Mapping[str, Any]) -> tuple[int, dict[str, Any]]:
        """The agent's action id and ``{"probs": {action name: probability}}`` over the legal
        actions (an empty info for an agent without ``action_probs``)."""
        states = rlcard_states(state)
        obs = agent_encoding(self.agent).encode(states)
        action = self._decide(states, obs)
        if getattr(self.agent, "action_probs", None) is None:
            return action, {}
        probs = agent_action_probs(self.agent, obs, states.legal_mask, states.cards)[0]
        legal = np.flatnonzero(states.legal_mask[0])
        return action, {"probs": {ACTIONS[a]: float(probs[a]) for a in legal}}
