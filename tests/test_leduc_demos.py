"""Leduc demonstrations (pokerirl/game/leduc/demos.py) and the information-set rows they use
(infosets.py): seeded bytes, the expert's probabilities recovered from the data at the right
keys, and the file's refusals."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

from pokerirl.errors import InputError
from pokerirl.game.leduc import (
    OPENSPIEL,
    RLCARD,
    LeducRules,
    random_deal,
    strategy_from_callable,
    uniform_strategy,
)
from pokerirl.game.leduc.demos import load, save, synthesize
from pokerirl.game.leduc.infosets import info_sets, pure
from pokerirl.game.leduc.rules import Action
from pokerirl.game.leduc.strategy import Strategy


def random_strategy(rules: LeducRules, seed: int) -> Strategy:
    """Probabilities drawn per information set: every key its own distribution, so a
    decision recorded under another key (the other seat's, another round's) shows."""
    rng = np.random.default_rng(seed)
    return strategy_from_callable(
        rules, lambda key, actions: dict(zip(actions, rng.dirichlet(np.ones(len(actions))),
                                             strict=True)))  # fmt: skip


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_the_same_seed_writes_the_same_bytes_and_loads_back(tmp_path: Path) -> None:
    expert = random_strategy(RLCARD, 0)
    paths = [tmp_path / f"{name}.npz" for name in ("a", "b", "c")]
    for path, seed in zip(paths, (1, 1, 2), strict=True):
        save(synthesize(RLCARD, expert, hands=500, seed=seed), path)
    assert digest(paths[0]) == digest(paths[1]) != digest(paths[2])
    demos = load(paths[0])
    again = synthesize(RLCARD, expert, hands=500, seed=1)
    assert demos.rules == RLCARD and demos.hands == 500 and demos.seed == 1
    for name in ("obs", "legal", "action", "next_obs", "done", "reward", "hand", "row"):
        assert np.array_equal(getattr(demos, name), getattr(again, name)), name


@pytest.mark.parametrize("rules", [RLCARD, OPENSPIEL], ids=lambda r: r.name)
def test_the_actions_follow_the_expert_at_each_key(rules: LeducRules) -> None:
    # Frequencies at the 12 most visited sets within 5 standard errors of the expert's
    # probabilities: a row recorded under the other seat's key (or the wrong card) fails.
    expert = random_strategy(rules, 3)
    demos = synthesize(rules, expert, hands=20_000, seed=0)
    sets = info_sets(rules)
    truth = sets.probabilities(expert)
    counts = np.zeros(truth.shape)
    np.add.at(counts, (demos.row, demos.action), 1)
    for row in np.argsort(-counts.sum(axis=1))[:12]:
        n = counts[row].sum()
        p = truth[row]
        error = np.abs(counts[row] / n - p) / np.sqrt(np.maximum(p * (1 - p), 1e-4) / n)
        assert error.max() < 5, (sets.keys[row], counts[row] / n, p)
    # every decision's observation and legal actions are its set's
    assert np.array_equal(sets.observations[demos.row], demos.obs)
    assert np.array_equal(sets.legal[demos.row], demos.legal)
    assert demos.legal[np.arange(len(demos)), demos.action].all()


def test_hands_end_once_per_seat_and_are_zero_sum() -> None:
    demos = synthesize(RLCARD, random_strategy(RLCARD, 1), hands=2_000, seed=4)
    seats = demos.hand * 2 + demos.position
    assert np.bincount(seats[demos.done]).max() == 1  # one last decision per seat
    assert set(seats[demos.done]) == set(seats)
    per_hand = np.bincount(demos.hand, demos.reward)
    both = np.bincount(demos.hand, demos.done) == 2  # both seats decided in the hand
    assert np.allclose(per_hand[both], 0) and np.abs(demos.reward).max() > 0
    # a decision that is not the seat's last sees its next one: more chips in the pot or
    # the public card
    assert (demos.next_obs[~demos.done] != demos.obs[~demos.done]).any(axis=1).all()


def test_against_an_opponent_only_the_experts_seat_is_recorded() -> None:
    caller = pure(RLCARD, {Action.CALL: 2, Action.CHECK: 1})
    demos = synthesize(RLCARD, random_strategy(RLCARD, 2), hands=1_000, seed=0, opponent=caller)
    assert np.array_equal(demos.position, demos.hand % 2)  # the expert sits in hand % 2
    assert demos.opponent_sha256 != demos.expert_sha256


def test_a_file_that_is_not_demonstrations_is_refused(tmp_path: Path) -> None:
    garbage = tmp_path / "x.npz"
    garbage.write_text("no zip")
    with pytest.raises(InputError, match="not a Leduc demonstrations file"):
        load(garbage)
    np.savez(tmp_path / "other.npz", header=np.array('{"format": "other"}'),
             **{name: np.zeros(1) for name in ("obs", "legal", "action", "next_obs", "done",
                                               "reward", "hand", "position", "row")})  # fmt: skip
    with pytest.raises(InputError, match="not a Leduc demonstrations file"):
        load(tmp_path / "other.npz")
    with pytest.raises(InputError, match="hands"):
        synthesize(RLCARD, random_strategy(RLCARD, 0), hands=0, seed=0)


def test_info_set_rows_cover_the_tree() -> None:
    for rules in (RLCARD, OPENSPIEL):
        sets = info_sets(rules)
        assert len(sets.keys) == len(set(sets.keys)) == (288 if rules is RLCARD else 936)
        decided = (sets.node_rows >= 0).all(axis=1)  # a decision node: a row for every deal
        assert ((sets.node_rows == -1).all(axis=1) | decided).all() and decided.sum() == 36
        assert sets.strategy(sets.legal.astype(float)) == uniform_strategy(rules)


@pytest.mark.parametrize("rules", [RLCARD, OPENSPIEL], ids=lambda r: r.name)
def test_each_sets_observation_is_the_engines(rules: LeducRules) -> None:
    # The study reads every learned reward and policy at these rows: they must be what the
    # one-hand engine shows the player at that key, whatever the deal.
    sets = info_sets(rules)
    rng = np.random.default_rng(0)
    seen = set()
    for _ in range(300):
        state = random_deal(rules, rng)
        while not state.is_over:
            key = state.info_key(state.to_act)
            row = sets.row[key]
            seen.add(row)
            assert np.array_equal(sets.observations[row], state.observation(state.to_act)), key
            legal = state.legal_actions()
            assert [a in legal for a in Action] == sets.legal[row].tolist()
            state = state.step(legal[rng.integers(len(legal))])
    assert len(seen) > 100
