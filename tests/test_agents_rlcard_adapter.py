"""pokerirl agents inside RLCard 1.2.0 (pokerirl/agents/rlcard_adapter.py), no mocks: each
agent plays RLCard's own ``tournament`` on ``rlcard.make("limit-holdem")`` against RLCard's
``RandomAgent``, and every decision it took there is replayed on pokerirl's engine: the
engine's view of the same state (its observation, cards and legal actions) must be what the
adapter made of RLCard's state, and a deterministic agent must decide the same there."""

from __future__ import annotations

import copy
import json
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import rlcard
import torch

from pokerirl.agents import RLCardAgent, resolve_agent, rlcard_states
from pokerirl.agents.dqn import GreedyQAgent, QNetwork
from pokerirl.errors import InputError
from pokerirl.game import ScriptedAgent, agent_actions, play_match, turn_cards
from pokerirl.game.encodings import RLCARD, get_encoding
from pokerirl.game.engine import LimitHoldemBatch
from pokerirl.game.match import agent_encoding, observe
from pokerirl.game.synth import DEFAULT_PLAYERS
from pokerirl.holdem import ACTIONS, FOLD, NUM_CARDS

HANDS = 300  # per tournament; the replays check every decision of half as many
with open(Path(rlcard.__path__[0]) / "games/limitholdem/card2index.json") as _file:
    CARD2INDEX: dict[str, int] = json.load(_file)


@dataclass
class Recorder:
    """Passes RLCard's calls to an :class:`RLCardAgent`, keeping each state as it was then
    (RLCard mutates its raise counts and action record afterwards) and the action taken."""

    inner: RLCardAgent
    player: int  # its player id in the env
    use_raw: bool = False
    seen: list[tuple[dict[str, Any], int]] = field(default_factory=list)

    def step(self, state: Mapping[str, Any]) -> int:
        raise AssertionError("tournament() plays with eval_step")

    def eval_step(self, state: Mapping[str, Any]) -> tuple[int, dict[str, Any]]:
        action, info = self.inner.eval_step(state)
        kept = {
            "raw_obs": copy.deepcopy(state["raw_obs"]),
            "legal_actions": dict(state["legal_actions"]),
            "action_record": list(state["action_record"]),
            "obs": state["obs"].copy(),
        }
        self.seen.append((kept, action))
        return action, info


def in_rlcard(
    agent: Any, *, player: int, seed: int, hands: int = HANDS
) -> tuple[Recorder, list[float]]:
    from rlcard.agents import RandomAgent  # runs `pip freeze` once: imported only here
    from rlcard.utils import set_seed, tournament

    set_seed(seed)
    env = rlcard.make("limit-holdem", config={"seed": seed})
    recorder = Recorder(inner=RLCardAgent(agent=agent, seed=seed), player=player)
    seats: list[Any] = [RandomAgent(num_actions=4)] * 2
    seats[player] = recorder
    env.set_agents(seats)
    return recorder, tournament(env, hands)


def replay(state: dict[str, Any], player: int) -> LimitHoldemBatch:
    """The engine at ``state``: the player's cards (the rest of the deal is filler nobody
    sees before the state) and the hand's actions so far."""
    # Cards read with RLCard's own card2index, not the adapter's: the engine's view is the
    # reference the adapter's is checked against.
    hole = [CARD2INDEX[c] for c in state["raw_obs"]["hand"]]
    board = [CARD2INDEX[c] for c in state["raw_obs"]["public_cards"]]
    record = state["action_record"]
    seat = 0 if not record or record[0][0] == player else 1  # the small blind acts first
    filler = [c for c in range(NUM_CARDS) if c not in hole + board]
    deal = [*hole, *filler[:2]] if seat == 0 else [*filler[:2], *hole]
    deal += board + filler[2 : 7 - len(board)]
    game = LimitHoldemBatch(deals=np.array([deal]))
    for _, action in record:
        game.step(np.array([ACTIONS.index(action)]))
    assert not game.done[0] and game.to_act[0] == seat
    return game


def strength_dqn() -> GreedyQAgent:
    torch.manual_seed(0)
    width = get_encoding("strength").width
    network = QNetwork(hidden=(8,), obs_size=width, input_norm=False)
    return GreedyQAgent(name="tiny-strength-dqn", network=network, encoding="strength")


AGENTS = {
    "call": lambda: resolve_agent("call"),
    "tightbot-noiseless": lambda: ScriptedAgent(
        name="tight", player=replace(DEFAULT_PLAYERS[0], noise=0.0)
    ),
    "tiny-dqn": lambda: (
        torch.manual_seed(1), GreedyQAgent(name="tiny-dqn", network=QNetwork(hidden=(8,)))
    )[1],
    "tiny-strength-dqn": strength_dqn,
}


@pytest.mark.parametrize("name", sorted(AGENTS))
def test_a_pokerirl_agent_decides_in_rlcard_as_on_the_engine(name: str) -> None:
    agent = AGENTS[name]()
    recorder, payoffs = in_rlcard(agent, player=1, seed=3, hands=HANDS // 2)
    assert payoffs[0] == pytest.approx(-payoffs[1])  # zero-sum, in big blinds a hand
    assert len(recorder.seen) >= HANDS // 4  # many decisions checked, whoever folds first
    stale = 0
    encoding = agent_encoding(agent)
    for state, action in recorder.seen:
        game = replay(state, recorder.player)
        states = rlcard_states(state)
        np.testing.assert_array_equal(RLCARD.encode(states), game.observe())
        np.testing.assert_array_equal(states.legal_mask, game.legal_mask())
        np.testing.assert_array_equal(states.cards, turn_cards(game, np.array([0])))
        stale += not np.array_equal(state["obs"], game.observe()[0])  # RLCard's own obs
        obs = observe(game, np.array([0]), encoding)
        cards = lambda game=game: turn_cards(game, np.array([0]))  # noqa: E731
        expected = agent_actions(agent, obs, game.legal_mask(), np.random.default_rng(), cards)
        assert action == expected[0]
    assert stale > 0  # RLCard's stale first states were met, and read right
    assert len({action for _, action in recorder.seen}) > 1 or name == "call"


def test_always_call_never_folds_in_rlcard_and_wins_there_as_on_the_engine() -> None:
    recorder, payoffs = in_rlcard(resolve_agent("call"), player=0, seed=5)
    actions = [action for _, action in recorder.seen]
    assert FOLD not in actions and set(actions) == {0, 3}  # calls and checks
    ours = play_match(resolve_agent("call"), resolve_agent("random"), hands=20_000, seed=0)
    # RLCard's 300 hands have a standard error near 0.2 big blinds; the engine's far less.
    assert abs(payoffs[0] - ours.mbb_per_hand / 1000) < 0.6
    assert payoffs[0] > 0.5


def test_eval_step_gives_rlcard_probs_and_bad_states_one_line() -> None:
    state = {"raw_obs": {"hand": ["SA", "HK"], "public_cards": ["D2", "C3", "S9"],
                         "my_chips": 4, "raise_nums": [1, 2, 0, 0]},
             "legal_actions": {0: None, 1: None, 2: None}}  # fmt: skip
    action, info = RLCardAgent(agent=resolve_agent("random"), seed=0).eval_step(state)
    assert action in (0, 1, 2) and info == {"probs": {"call": 1 / 3, "raise": 1 / 3,
                                                      "fold": 1 / 3}}  # fmt: skip
    assert rlcard_states(state).raise_nums.tolist() == [[1, 2, 0, 0]]  # not the first decision
    with pytest.raises(InputError, match=r"^RLCard state: hand \['SA', 'XX'\] are not RLCard"):
        rlcard_states({**state, "raw_obs": {**state["raw_obs"], "hand": ["SA", "XX"]}})
    with pytest.raises(InputError, match="no raw_obs"):
        rlcard_states({"obs": np.zeros(72)})
