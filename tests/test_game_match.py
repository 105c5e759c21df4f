"""Whole hands and matches: termination, zero-sum payoffs, seeds, seats, duplicate, the CLI."""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pytest
from typer.testing import CliRunner

from pokerirl.cli import app
from pokerirl.game import IllegalActionError, LimitHoldemBatch, make_agent, play_match
from pokerirl.holdem import CHECK


def test_every_hand_ends_and_payoffs_sum_to_zero() -> None:
    game = LimitHoldemBatch.from_seed(seed=2, start=0, count=20_000)
    agent, rng = make_agent("random"), np.random.default_rng(0)
    for _ in range(23):  # no hand has more than 23 actions
        if not game.active().size:
            break
        game.step(agent.act(game.observe(), game.legal_mask(), rng))
    assert game.done.all() and game.active().size == 0
    np.testing.assert_array_equal(game.payoffs.sum(axis=1), 0)
    assert game.folded.any() and (~game.folded).any()
    showdown = ~game.folded
    assert (game.chips[showdown, 0] == game.chips[showdown, 1]).all()
    assert (np.abs(game.payoffs) <= 25).all()  # at most 10 + 8 + 16 + 16 chips = 25 big blinds
    assert (game.payoffs[showdown] == 0).any()  # split pots happen


def test_finished_hands_are_not_visited_again() -> None:
    game = LimitHoldemBatch.from_seed(seed=3, start=0, count=4)
    game.step(np.array([2, 0, 2, 0]))  # hands 0 and 2 fold
    assert game.active().tolist() == [1, 3]
    assert game.observe().shape == (2, 72) and game.legal_mask().shape == (2, 4)


def test_same_seed_same_result_and_deals_do_not_depend_on_batch_size() -> None:
    raise_agent, random_agent, call_agent = (
        make_agent("raise"),
        make_agent("random"),
        make_agent("call"),
    )
    first = play_match(raise_agent, random_agent, hands=3_000, seed=9, batch_size=1_000)
    second = play_match(raise_agent, random_agent, hands=3_000, seed=9, batch_size=1_000)
    np.testing.assert_array_equal(first.results_bb, second.results_bb)
    other = play_match(raise_agent, random_agent, hands=3_000, seed=10, batch_size=1_000)
    assert (first.results_bb != other.results_bb).any()
    # Deterministic agents: only the deals matter, and they ignore the batch size.
    small = play_match(raise_agent, call_agent, hands=3_000, seed=9, batch_size=64, duplicate=False)
    large = play_match(raise_agent, call_agent, hands=3_000, seed=9, duplicate=False)
    np.testing.assert_array_equal(small.results_bb, large.results_bb)


def test_duplicate_mirror_match_is_exactly_even() -> None:
    """The same deterministic agent on both sides of every deal, both ways round, nets zero."""
    result = play_match(make_agent("raise"), make_agent("raise"), hands=4_000, seed=4)
    np.testing.assert_array_equal(result.results_bb.reshape(-1, 2).sum(axis=1), 0)
    assert result.mbb_per_hand == 0 and result.std_error == 0
    alternating = play_match(
        make_agent("raise"), make_agent("raise"), hands=4_000, seed=4, duplicate=False
    )
    assert alternating.std_error > 0


def test_standard_error_unit_is_the_pair_in_duplicate_and_the_hand_otherwise() -> None:
    a, b = make_agent("raise"), make_agent("random")
    duplicate = play_match(a, b, hands=2_000, seed=5)
    pairs = duplicate.results_bb.reshape(-1, 2).mean(axis=1)
    assert duplicate.std_error == pytest.approx(1000 * pairs.std(ddof=1) / np.sqrt(1_000))
    assert duplicate.mbb_per_hand == pytest.approx(1000 * duplicate.results_bb.mean())
    alternating = play_match(a, b, hands=2_000, seed=5, duplicate=False)
    hands = alternating.results_bb
    assert alternating.std_error == pytest.approx(1000 * hands.std(ddof=1) / np.sqrt(2_000))


def test_always_raise_beats_random_by_about_2_9_big_blinds() -> None:
    # RLCard's own loop gives 2880.7 +- 7.1 mbb/h over 400,000 hands (benchmarks/engine.py).
    result = play_match(make_agent("raise"), make_agent("random"), hands=40_000, seed=1)
    assert abs(result.mbb_per_hand - 2880.7) < 4 * np.hypot(result.std_error, 7.1)


@dataclass(frozen=True, kw_only=True)
class _AlwaysCheck:
    name: str = "always-check"

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return np.full(obs.shape[0], CHECK)


def test_an_illegal_move_names_the_agent() -> None:
    with pytest.raises(IllegalActionError, match="always-check"):
        play_match(_AlwaysCheck(), make_agent("call"), hands=10, seed=0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"hands": 0}, "at least 1"), ({"hands": 11}, "even"), ({"hands": 10, "seed": -1}, "seed")],
)
def test_bad_match_arguments(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        play_match(make_agent("call"), make_agent("call"), **{"seed": 0, **kwargs})


def test_cli_match_prints_json_last() -> None:
    result = CliRunner().invoke(
        app, ["match", "raise", "random", "--hands", "2000", "--format", "json"]
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout.strip().splitlines()[-1])
    assert set(summary) == {"mbb_per_hand", "std_error", "hands", "hands_per_second",
                            "aivat_seconds"}  # fmt: skip
    assert summary["hands"] == 2000 and summary["mbb_per_hand"] > 2000


def test_cli_match_text_and_errors() -> None:
    runner = CliRunner()
    text = runner.invoke(app, ["match", "call", "random", "--hands", "100", "--no-duplicate"])
    assert text.exit_code == 0 and "mbb/h" in text.stdout
    for args in (["match", "raise", "nobody"], ["match", "raise", "call", "--hands", "0"]):
        failed = runner.invoke(app, args)
        assert failed.exit_code != 0
        assert (
            failed.stderr.strip().startswith("error:")
            and len(failed.stderr.strip().splitlines()) == 1
        )


@dataclass(frozen=True)
class _Recorder:
    """A random agent that records the observation widths it is given."""

    widths: list
    reads_obs: bool = True
    name: str = "recorder"

    def act(self, obs: np.ndarray, legal_mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        self.widths.append(obs.shape[1])
        return make_agent("random").act(obs, legal_mask, rng)


def test_agents_that_read_no_observation_get_none_and_results_do_not_change() -> None:
    """The built-ins decide from the legal mask: the engine skips their observations (half a
    match's time), which must change no result; an agent that reads them still gets 72."""
    reader, skipper = _Recorder(widths=[]), _Recorder(widths=[], reads_obs=False)
    first = play_match(reader, make_agent("raise"), hands=500, seed=3)
    second = play_match(skipper, make_agent("raise"), hands=500, seed=3)
    assert set(reader.widths) == {72} and set(skipper.widths) == {0}
    assert np.array_equal(first.results_bb, second.results_bb)
    assert not make_agent("random").reads_obs and not make_agent("fold").reads_obs  # type: ignore[attr-defined]


def test_time_in_on_batch_is_kept_apart_from_the_play() -> None:
    import time

    found = play_match(make_agent("raise"), make_agent("random"), hands=200, seed=0,
                       batch_size=100, on_batch=lambda *_: time.sleep(0.2))  # fmt: skip
    assert found.on_batch_seconds >= 0.4 and found.seconds < found.on_batch_seconds
