"""The main commands with ``--game leduc`` (issue 42): match, tournament and exploit give the
exact figures of :mod:`pokerirl.game.leduc.exact`, synth writes what ``leduc synth`` writes,
agent train writes a strategy the other commands read, and the Leduc agent specs of
:mod:`pokerirl.agents.leduc_specs` (a run's reward and policy included)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pokerirl.agents.leduc_specs import (
    leduc_spec_reason,
    policy_table,
    resolve_leduc_agent,
)
from pokerirl.cli import app
from pokerirl.errors import InputError
from pokerirl.game.leduc.exact import best_response_values, expected_value, exploitability
from pokerirl.game.leduc.infosets import info_sets
from pokerirl.game.leduc.rules import OPENSPIEL, RLCARD
from pokerirl.game.leduc.strategy import read_strategy, to_json, uniform_strategy


def invoke(*words: str) -> str:
    result = CliRunner().invoke(app, [str(w) for w in words])
    assert result.exit_code == 0, result.output
    return result.stdout


def match_json(a: str, b: str, *rules: str) -> dict[str, float]:
    return json.loads(invoke("match", a, b, "--game", "leduc", "--format", "json", *rules))


@pytest.mark.parametrize(("a", "b", "rules"), [("cfr:20", "random", RLCARD),
                                               ("raise", "fold", OPENSPIEL)])  # fmt: skip
def test_match_is_the_exact_expected_value_and_antisymmetric(a: str, b: str, rules) -> None:  # type: ignore[no-untyped-def]
    flags = ("--rules", rules.name)
    forward, backward = match_json(a, b, *flags), match_json(b, a, *flags)
    direct = expected_value(rules, resolve_leduc_agent(a, rules).strategy,
                            resolve_leduc_agent(b, rules).strategy)  # fmt: skip
    assert forward["chips_per_hand"] == pytest.approx(direct.mean, abs=1e-12)
    assert (forward["position_0"], forward["position_1"]) == pytest.approx(
        (direct.first, direct.second), abs=1e-12
    )
    assert forward["chips_per_hand"] != 0  # the two differ: antisymmetry is not 0 = -0
    assert backward["chips_per_hand"] == pytest.approx(-forward["chips_per_hand"], abs=1e-12)
    assert forward["milli_chips_per_hand"] == pytest.approx(1000 * forward["chips_per_hand"])


def exploitability_of(*words: str) -> float:
    text = invoke("exploit", *words, "--game", "leduc", "--exact")
    return float(text.split("exploitability: ")[1].split()[0])


def test_exploit_is_exact_small_for_cfr_and_large_for_raise() -> None:
    cfr = exploitability_of("cfr")
    assert cfr == pytest.approx(exploitability(RLCARD, resolve_leduc_agent("cfr", RLCARD).strategy),
                                abs=1e-9)  # fmt: skip
    assert cfr < 0.01 and exploitability_of("raise") > 2
    # A pair: the best response to raise in position 1 and to cfr in position 0.
    pair = exploitability_of("cfr", "--pair", "raise")
    raise_br = best_response_values(RLCARD, resolve_leduc_agent("raise", RLCARD).strategy)[0]
    cfr_br = best_response_values(RLCARD, resolve_leduc_agent("cfr", RLCARD).strategy)[1]
    assert pair == pytest.approx((raise_br + cfr_br) / 2, abs=1e-9)


def test_tournament_is_the_round_robin_of_exact_values(tmp_path: Path) -> None:
    invoke("tournament", "cfr:20", "random", "call", "--game", "leduc", "--out", tmp_path, "-q")
    report = json.loads((tmp_path / "report.json").read_text())
    strategies = {s: resolve_leduc_agent(s, RLCARD).strategy for s in report["agents"]}
    values = report["expected_value"]
    assert values["random"]["call"] == pytest.approx(
        expected_value(RLCARD, strategies["random"], strategies["call"]).mean, abs=1e-12
    )
    assert values["call"]["cfr:20"] == -values["cfr:20"]["call"] != 0
    assert report["exploitability"]["random"] == pytest.approx(
        exploitability(RLCARD, uniform_strategy(RLCARD))
    )
    assert "| cfr:20 |" in (tmp_path / "report.md").read_text()


def test_synth_writes_what_leduc_synth_writes(tmp_path: Path) -> None:
    expert = tmp_path / "expert.json"
    expert.write_text(to_json(RLCARD, resolve_leduc_agent("cfr:20", RLCARD).strategy))
    invoke("synth", "--game", "leduc", "-n", "50", "--seed", "3", "--expert", expert,
           "--opponent", "call", "--out", tmp_path / "a.npz")  # fmt: skip
    call = tmp_path / "call.json"
    call.write_text(to_json(RLCARD, resolve_leduc_agent("call", RLCARD).strategy))
    invoke("leduc", "synth", "-n", "50", "--seed", "3", "--expert", expert, "--opponent", call,
           "--out", tmp_path / "b.npz")  # fmt: skip
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()


@pytest.mark.slow  # torch's import and a DQN: about 7 s
def test_agent_train_writes_a_strategy_that_exploit_and_match_read(tmp_path: Path) -> None:
    out = tmp_path / "agent"
    text = invoke("agent", "train", "--game", "leduc", "--out", out, "--hands", "500",
                  "--opponent", "call", "--seed", "1")  # fmt: skip
    rules, strategy = read_strategy(out / "strategy.json")
    summary = json.loads((out / "summary.json").read_text())
    assert rules == RLCARD and summary["exploitability_chips"] == pytest.approx(
        exploitability(RLCARD, strategy))
    assert exploitability_of(str(out)) == pytest.approx(summary["exploitability_chips"], abs=1e-9)
    value = match_json(str(out), "call")["chips_per_hand"]
    assert value == pytest.approx(summary["value_against_opponent_chips"], abs=1e-12)
    assert "against call" in text


def test_agent_train_tabular_is_the_study_learner_and_reads_back(tmp_path: Path) -> None:
    from pokerirl.agents.leduc_q import QConfig, train_q

    invoke("agent", "train", "--game", "leduc", "--rl", "tabular", "--out", tmp_path / "q",
           "--hands", "3000", "--opponent", "raise", "--seed", "2",
           "--rules", "openspiel")  # fmt: skip
    rules, strategy = read_strategy(tmp_path / "q" / "strategy.json")
    raised = resolve_leduc_agent("raise", OPENSPIEL).strategy
    direct = train_q(OPENSPIEL, raised, config=QConfig(hands=3000, seed=2)).strategy()
    assert rules == OPENSPIEL and strategy == read_strategy_text(OPENSPIEL, direct)
    assert exploitability_of(str(tmp_path / "q"), "--rules", "openspiel") == pytest.approx(
        exploitability(OPENSPIEL, strategy), abs=1e-9)


def read_strategy_text(rules, strategy):  # type: ignore[no-untyped-def]
    """A strategy as its file holds it (rounded)."""
    return json.loads(to_json(rules, strategy))["strategy"]


def test_the_specs_of_each_game_are_refused_by_the_other(tmp_path: Path) -> None:
    strategy = tmp_path / "s.json"
    strategy.write_text(to_json(RLCARD, uniform_strategy(RLCARD)))
    assert leduc_spec_reason(str(strategy)) and leduc_spec_reason(str(tmp_path)) is None
    assert leduc_spec_reason("cfr:5") and leduc_spec_reason("random") is None
    assert resolve_leduc_agent(str(strategy), RLCARD).strategy == read_strategy(strategy)[1]
    with pytest.raises(InputError, match="rlcard rules, not openspiel"):
        resolve_leduc_agent(str(strategy), OPENSPIEL)
    for spec in ("tightbot", "rlcard:x.pt", str(tmp_path / "missing")):
        with pytest.raises(InputError, match=r"not a Leduc agent|no such file"):
            resolve_leduc_agent(spec, RLCARD)
    fold = resolve_leduc_agent("fold", RLCARD).strategy
    assert fold["K:"] == {"fold": 1.0, "call": 0.0, "raise": 0.0}  # small blind: no check
    assert fold["K:c"]["check"] == 1.0  # checking is free: it checks


@pytest.mark.slow
def test_a_leduc_run_plays_as_reward_and_policy(tmp_path: Path) -> None:
    """A Leduc IRL run (two epochs) as reward:RUN, policy:RUN and policy-probs:RUN; the
    reward trains an agent; reward-card and hold'em refuse it."""
    demos, run = tmp_path / "d.npz", tmp_path / "run"
    invoke("synth", "--game", "leduc", "-n", "200", "--out", demos)
    invoke("train", demos, "--out", run, "--epochs", "2", "--quiet", "--game", "leduc")
    from pokerirl.irl.run import load_policy

    sets = info_sets(RLCARD)
    probs = sets.strategy(policy_table(load_policy(run), sets))
    assert resolve_leduc_agent(f"policy-probs:{run}", RLCARD).strategy == probs
    greedy = resolve_leduc_agent(f"policy:{run}", RLCARD).strategy
    assert all(max(p.values()) == 1.0 for p in greedy.values())
    assert exploitability_of(f"reward:{run}") > 0
    invoke("agent", "train", "--game", "leduc", "--out", tmp_path / "a", "--hands", "200",
           "--reward", "learned", "--reward-run", run)  # fmt: skip
    assert "learned" in json.loads((tmp_path / "a" / "summary.json").read_text())["reward"]
    for line in (["reward-card", str(run)], ["match", f"reward:{run}", "random"]):
        result = CliRunner().invoke(app, line)
        assert result.exit_code == 1 and "Leduc" in result.stderr, result.stderr
