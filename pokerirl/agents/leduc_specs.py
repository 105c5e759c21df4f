"""Leduc agents by name: what ``match``, ``tournament``, ``exploit``, ``synth`` and ``agent
train`` resolve with ``--game leduc``, each as a strategy over every information set (the
exact evaluations of :mod:`pokerirl.game.leduc.exact` read nothing else); and the tables of a
Leduc IRL run (its reward g(s, a) and its policy at every information set), which the Leduc
study computes with the same functions.

A spec is one of:

* a strategy file (``pokerirl leduc solve``, ``agent train --game leduc``) or a folder that
  holds one (``strategy.json``);
* a built-in: ``random`` (uniform over the legal actions), ``call`` (call, else check),
  ``raise`` (raise, else call), ``fold`` (check when free, else fold), ``cfr`` or
  ``cfr:ITERS`` (CFR+ solved here, :data:`CFR_ITERATIONS` iterations by default: about a
  second, 3.6 milli-chips from equilibrium under RLCard's rules);
* ``reward:RUN``: the legal argmax of a Leduc run's learned reward at every information set;
* ``policy:RUN``: its policy, greedy; ``policy-probs:RUN``: its policy's probabilities.

Hold'em's agents (``tightbot``, ``loosebot``, ``rlcard:CKPT``, a DQN agent folder, a hold'em
run) are refused in one line, and :func:`leduc_spec_reason` says when a spec given to hold'em
is a Leduc one. torch is imported only for a run.

>>> from pokerirl.game.leduc.rules import RLCARD
>>> resolve_leduc_agent("call", RLCARD).strategy["K:"]
{'fold': 0.0, 'call': 1.0, 'raise': 0.0}
"""

from __future__ import annotations

import functools
import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pokerirl.agents.names import CONFIG_FILE, RLCARD_PREFIX
from pokerirl.errors import InputError
from pokerirl.game.bots import BUILT_IN_AGENTS
from pokerirl.game.leduc.batch import ACTIONS
from pokerirl.game.leduc.infosets import InfoSets, info_sets, pure
from pokerirl.game.leduc.rules import Action, LeducRules
from pokerirl.game.leduc.strategy import FORMAT, Strategy, read_strategy, uniform_strategy
from pokerirl.game.spec import GameName, recorded_game
from pokerirl.poker.agent_specs import POLICY_PREFIX, REWARD_PREFIX

STRATEGY_FILE = "strategy.json"  # in a solve folder and in an agent folder of agent train
CFR_PREFIX = "cfr"
CFR_ITERATIONS = 200
MAX_CFR_ITERATIONS = 100_000  # minutes: a solve folder is the way to keep more
PROBS_PREFIX = "policy-probs:"
# The pure built-ins: the legal action of the highest priority.
PURE = {
    "call": {Action.CALL: 2, Action.CHECK: 1},
    "raise": {Action.RAISE: 3, Action.CALL: 2, Action.CHECK: 1},
    "fold": {Action.CHECK: 2, Action.FOLD: 1},
}
BUILT_INS = ("random", *PURE, CFR_PREFIX)
KINDS = (
    "a strategy file, a folder holding strategy.json, random, call, raise, fold, cfr[:ITERS], "
    "reward:RUN, policy:RUN or policy-probs:RUN"
)


@dataclass(frozen=True, kw_only=True, eq=False)
class LeducAgent:
    """A resolved spec: its name (the spec) and its strategy under ``rules``."""

    name: str
    rules: LeducRules
    strategy: Strategy = field(repr=False)


def resolve_leduc_agent(spec: str, rules: LeducRules) -> LeducAgent:
    """The agent ``spec`` names, under ``rules`` (an :class:`InputError` of one line for an
    unknown spec, a hold'em agent, a missing file or a strategy of other rules)."""
    return LeducAgent(name=spec, rules=rules, strategy=_strategy(spec, rules))


def _strategy(spec: str, rules: LeducRules) -> Strategy:
    if spec == "random":
        return uniform_strategy(rules)
    if spec in PURE:
        return pure(rules, PURE[spec])
    if spec == CFR_PREFIX or spec.startswith(CFR_PREFIX + ":"):
        return cfr_strategy(rules, _iterations(spec))
    for prefix in (REWARD_PREFIX, POLICY_PREFIX, PROBS_PREFIX):
        if spec.startswith(prefix):
            return run_strategy(Path(spec.removeprefix(prefix)), rules, prefix=prefix)
    reason = holdem_spec_reason(spec)
    if reason is not None:
        raise InputError(f"{spec}: {reason}, not a Leduc agent ({KINDS})")
    path = Path(spec)
    if path.is_dir() and (path / STRATEGY_FILE).is_file():
        path = path / STRATEGY_FILE
    if not path.exists():
        raise InputError(f"unknown Leduc agent {spec!r}: no such file ({KINDS})")
    if path.is_dir():
        raise InputError(f"{spec}: a folder without {STRATEGY_FILE}, not a Leduc agent ({KINDS})")
    found, strategy = read_strategy(path)
    if found.name != rules.name:
        raise InputError(f"{spec}: a strategy for the {found.name} rules, not {rules.name}")
    return strategy


def _iterations(spec: str) -> int:
    text = spec.removeprefix(CFR_PREFIX).removeprefix(":") or str(CFR_ITERATIONS)
    if not text.isdigit() or not 1 <= int(text) <= MAX_CFR_ITERATIONS:
        raise InputError(f"{spec}: cfr:ITERS needs 1 <= ITERS <= {MAX_CFR_ITERATIONS:,}")
    return int(text)


@functools.lru_cache(maxsize=4)
def cfr_strategy(rules: LeducRules, iterations: int) -> Strategy:
    """CFR+'s average strategy after ``iterations`` (deterministic; cached: a tournament
    names it more than once)."""
    from pokerirl.game.leduc.cfr import CFRPlus

    solver = CFRPlus(rules)
    solver.run(iterations, every=iterations)
    return solver.average()


def holdem_spec_reason(spec: str) -> str | None:
    """What makes ``spec`` a hold'em agent (a hold'em bot, an RLCard checkpoint, a DQN agent
    folder), or None."""
    if spec in BUILT_IN_AGENTS and spec not in BUILT_INS:
        return "a hold'em bot"
    if spec.startswith(RLCARD_PREFIX):
        return "an RLCard hold'em checkpoint"
    if (Path(spec) / CONFIG_FILE).is_file() and not (Path(spec) / STRATEGY_FILE).is_file():
        return "a hold'em agent folder"
    return None


def leduc_spec_reason(spec: str) -> str | None:
    """What makes ``spec`` a Leduc agent, for hold'em's commands to refuse it in one line: a
    strategy file or a folder holding one, ``cfr``, ``policy-probs:RUN``, or a run learned on
    Leduc demonstrations; None for anything else (hold'em's resolver judges it)."""
    if spec == CFR_PREFIX or spec.startswith((CFR_PREFIX + ":", PROBS_PREFIX)):
        return "a Leduc built-in"
    for prefix in (REWARD_PREFIX, POLICY_PREFIX):
        if spec.startswith(prefix) and _run_game(Path(spec.removeprefix(prefix))) is GameName.LEDUC:
            return "a run learned on Leduc demonstrations"
    path = Path(spec)
    if path.is_dir():
        path = path / STRATEGY_FILE
    if path.is_file() and path.suffix == ".json" and _strategy_format(path):
        return "a Leduc strategy"
    return None


def _strategy_format(path: Path) -> bool:
    try:
        with path.open("rb") as stream:
            head = stream.read(200).decode("utf-8", "replace")
    except OSError:
        return False
    return f'"format": "{FORMAT}"' in head


def _run_game(run: Path) -> GameName | None:
    try:
        document = json.loads((run / "config.json").read_text())
    except (OSError, ValueError):
        return None
    return recorded_game(document.get("data")) if isinstance(document, dict) else None


def run_strategy(run: Path, rules: LeducRules, *, prefix: str) -> Strategy:
    """The strategy of a Leduc IRL run: its reward's legal argmax (``reward:``), its policy
    greedy (``policy:``) or its policy's probabilities (``policy-probs:``)."""
    from pokerirl.irl.run import load_policy, load_reward

    game = _run_game(run)
    if game is not GameName.LEDUC:
        what = "no run folder" if game is None else f"a run on {game} decisions"
        raise InputError(f"{prefix}{run}: {what}, not a run learned on Leduc demonstrations")
    _check_run_rules(run, rules)
    sets = info_sets(rules)
    try:
        if prefix == REWARD_PREFIX:
            return sets.greedy(reward_table(load_reward(run).net, sets))
        probabilities = policy_table(load_policy(run), sets)
    except ValueError as error:  # the run's files: one line naming the file
        raise InputError(f"{prefix}{run}: {error}") from None
    return sets.greedy(probabilities) if prefix == POLICY_PREFIX else sets.strategy(probabilities)


def _check_run_rules(run: Path, rules: LeducRules) -> None:
    """Refuse a run whose demonstrations (still there) were dealt under other rules."""
    data = json.loads((run / "config.json").read_text()).get("data") or {}
    path = data.get("path") if isinstance(data, dict) else None
    if not isinstance(path, str) or not Path(path).is_file():
        return  # the demonstrations are gone: the rules given are the run's
    try:
        with np.load(path, allow_pickle=False) as archive:
            found = json.loads(str(archive["header"].item())).get("rules")
    except (OSError, ValueError, KeyError, zipfile.BadZipFile):
        return
    if found != rules.name:
        raise InputError(f"{run}: learned on demonstrations of the {found} rules, not {rules.name}")


def reward_table(reward: Any, sets: InfoSets) -> np.ndarray:
    """g(s, a) of a reward net (its ``transferable`` part) at every information set and action
    (rows x 4; -inf where illegal)."""
    import torch

    obs = torch.as_tensor(sets.observations, dtype=torch.float32)
    actions = torch.eye(len(ACTIONS))[:, None, :].expand(len(ACTIONS), len(obs), len(ACTIONS))
    with torch.inference_mode():  # tables, not training
        values = reward.transferable(obs, actions).T.double().numpy()
    return np.where(sets.legal, values, -np.inf)


def policy_table(policy: Any, sets: InfoSets) -> np.ndarray:
    """π(a | s) of a policy net at every information set (rows x 4, 0 where illegal)."""
    import torch

    obs = torch.as_tensor(sets.observations, dtype=torch.float32)
    with torch.inference_mode():
        log_p = policy(obs, torch.as_tensor(sets.legal))
    return np.where(sets.legal, log_p.exp().double().numpy(), 0.0)
