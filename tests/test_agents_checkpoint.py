"""Agent folders (save, load, fingerprints, errors) and the RLCard DQN checkpoint import."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from pokerirl.agents import agent_fingerprint, load_agent, resolve_agent
from pokerirl.agents.dqn import DQNConfig
from pokerirl.agents.rlcard_import import import_rlcard_dqn, load_rlcard_dqn
from pokerirl.agents.train import TrainConfig, train_agent
from pokerirl.game import LimitHoldemBatch, make_agent, play_match
from pokerirl.holdem import OBS_SIZE

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("agents") / "dqn"
    config = TrainConfig(
        hands=1_024,
        seed=7,
        opponent="call",
        eval_every=512,
        eval_hands=400,
        dqn=DQNConfig(concurrent_hands=128, hidden=(32, 16)),
    )
    train_agent(folder, config)
    return folder


def engine_states(count: int) -> tuple[np.ndarray, np.ndarray]:
    """Observations and legal masks of real decisions: a few steps of random play."""
    game = LimitHoldemBatch.from_seed(seed=11, start=0, count=count)
    rng, agent = np.random.default_rng(0), make_agent("random")
    obs, legal = [], []
    for _ in range(3):
        obs.append(game.observe())
        legal.append(game.legal_mask())
        game.step(agent.act(obs[-1], legal[-1], rng))
    return np.concatenate(obs), np.concatenate(legal)


def test_round_trip_keeps_the_network_and_the_training_record(trained: Path) -> None:
    config = json.loads((trained / "config.json").read_text())
    assert config["reward"] == {
        "mode": "sparse",
        "run": None,
        "fingerprint": None,
        "payoff_weight": 0.0,
        "transform": "raw",
        "raise_counts": "decision",
    }
    assert config["seed"] == 7 and config["hands"] == 1_024 and config["hidden"] == [32, 16]
    assert config["dqn"]["learning_rate"] == 5e-5 and config["dqn"]["gamma"] == 0.99
    assert config["opponent"] == {"spec": "call", "fingerprint": "builtin:call"}
    metrics = [json.loads(line) for line in (trained / "metrics.jsonl").read_text().splitlines()]
    assert [m["hands"] for m in metrics] == [512, 1_024]
    assert set(metrics[-1]["eval"]) == {"random", "call"} and config["final"] == metrics[-1]
    assert (trained / "learning_curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    agent = load_agent(trained)
    weights = torch.load(trained / "model.pt", weights_only=True)
    assert all(torch.equal(weights[k], v) for k, v in agent.network.state_dict().items())
    obs, legal = engine_states(500)
    actions = agent.act(obs, legal, np.random.default_rng(0))
    assert actions.dtype == np.int64 and legal[np.arange(len(obs)), actions].all()
    q = np.where(legal, agent.q_values(obs), -np.inf)
    np.testing.assert_array_equal(actions, q.argmax(axis=1))
    # The saved greedy policy is what training evaluated last (same match, same numbers).
    final = play_match(agent, make_agent("random"), hands=400, seed=1_000_003)
    assert final.mbb_per_hand == pytest.approx(metrics[-1]["eval"]["random"]["mbb_per_hand"])


def test_folders_resolve_like_agent_names_with_a_file_fingerprint(
    trained: Path, tmp_path: Path
) -> None:
    agent = resolve_agent(str(trained))
    assert agent.name == str(trained) and agent_fingerprint(agent) == agent.fingerprint
    copy = tmp_path / "copy"
    copy.mkdir()
    for name in ("model.pt", "config.json"):
        (copy / name).write_bytes((trained / name).read_bytes())
    assert load_agent(copy).fingerprint == agent.fingerprint
    record = json.loads((copy / "config.json").read_text())
    record["note"] = "changed"
    (copy / "config.json").write_text(json.dumps(record))
    assert load_agent(copy).fingerprint != agent.fingerprint


def test_bad_agent_folders_give_one_line_errors(trained: Path, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="not an agent folder"):
        load_agent(tmp_path)
    (tmp_path / "model.pt").write_bytes((trained / "model.pt").read_bytes())
    record = json.loads((trained / "config.json").read_text())
    (tmp_path / "config.json").write_text(json.dumps({**record, "hidden": [64, 64]}))
    with pytest.raises(ValueError, match="cannot load agent") as error:
        load_agent(tmp_path)
    assert "\n" not in str(error.value)
    (tmp_path / "config.json").write_text(json.dumps(record))
    (tmp_path / "model.pt").write_bytes(b"not a torch file")
    with pytest.raises(ValueError, match="cannot load agent") as error:
        load_agent(tmp_path)
    assert "\n" not in str(error.value)


def rlcard_states(env: Any, hands: int) -> list[dict[str, Any]]:
    """Decision states of both players from RLCard's own games."""
    states = []
    for _ in range(hands):
        trajectories, _ = env.run(is_training=False)
        # RLCard's obs arrays are built when the state is made, so they stay correct even
        # though raw_obs['raise_nums'] is one list that the game mutates afterwards.
        states += [s for player in trajectories for s in player[0:-1:2]]
    return states


@pytest.mark.filterwarnings("ignore::pokerirl.agents.rlcard_import.UntrustedCheckpointWarning")
def test_rlcard_checkpoint_plays_here_as_it_does_in_rlcard(tmp_path: Path) -> None:
    import rlcard
    from rlcard.agents import DQNAgent, RandomAgent
    from rlcard.utils import reorganize, set_seed

    set_seed(0)
    env = rlcard.make("limit-holdem", config={"seed": 0})
    dqn = DQNAgent(
        num_actions=4, state_shape=[OBS_SIZE], mlp_layers=[32, 32], device=torch.device("cpu")
    )
    env.set_agents([dqn, RandomAgent(num_actions=4)])
    with contextlib.redirect_stdout(io.StringIO()):  # DQNAgent prints every update
        while dqn.total_t < 400:
            trajectories, payoffs = env.run(is_training=True)
            for transition in reorganize(trajectories, payoffs)[0]:
                dqn.feed(transition)
        dqn.save_checkpoint(str(tmp_path))
    checkpoint_path = tmp_path / "checkpoint_dqn.pt"
    assert dqn.train_t > 250

    agent = load_rlcard_dqn(checkpoint_path)
    states = rlcard_states(env, 60)
    obs = np.stack([s["obs"] for s in states]).astype(np.uint8)
    legal = np.zeros((len(states), 4), bool)
    for row, state in enumerate(states):
        legal[row, list(state["legal_actions"])] = True
    expected_q = np.stack([dqn.predict(s) for s in states])  # masked with -inf by RLCard
    ours = np.where(legal, agent.q_values(obs), -np.inf)
    np.testing.assert_allclose(ours, expected_q, rtol=1e-5, atol=1e-6)
    expected_actions = [dqn.eval_step(s)[0] for s in states]
    assert agent.act(obs, legal, np.random.default_rng(0)).tolist() == expected_actions
    assert len(set(expected_actions)) > 1  # the comparison covers more than one action

    # As an agent folder: no pickle any more, same policy, epsilon fields put right.
    folder = import_rlcard_dqn(checkpoint_path, tmp_path / "imported")
    np.testing.assert_allclose(load_agent(folder).q_values(obs), agent.q_values(obs), rtol=1e-6)
    raw = torch.load(checkpoint_path, weights_only=False)
    assert (raw["epsilon_start"], raw["epsilon_end"]) == (0.1, 1.0)  # RLCard's swap
    record = json.loads((folder / "config.json").read_text())
    assert (record["dqn"]["epsilon_start"], record["dqn"]["epsilon_end"]) == (1.0, 0.1)
    assert resolve_agent(f"rlcard:{checkpoint_path}").fingerprint == agent.fingerprint

    with pytest.raises(ValueError, match="not an RLCard DQNAgent checkpoint"):
        load_rlcard_dqn(folder / "model.pt")
