"""The Leduc study (``pokerirl leduc study``): CFR+ expert -> demonstrations -> AIRL, H-AIRL,
GAIL and BC runs -> RL (DQN seeds, or the tabular learner) on each learned reward and on the
sparse reward, against the expert -> exact
agreement, exploitability and expected values -> ``report.md``, ``report.json``, a figure.

Stages write files under the study folder and a rerun skips those present (``study.json``
refuses a folder made with other settings): ``solve/``, ``demos.npz``, ``irl/LEARNER.json``,
``rl/SOURCE-SEED.json``. The store's units are not used: every stage here is seconds to
minutes and runs in this process.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from pokerirl.atomic import write_text
from pokerirl.errors import ConfigError, InputError
from pokerirl.game.leduc.demos import Demonstrations, load, save, synthesize
from pokerirl.game.leduc.exact import MILLI, agreement, expected_value, exploitability
from pokerirl.game.leduc.infosets import InfoSets, info_sets, one_hot_argmax
from pokerirl.game.leduc.rules import LeducRules, RuleSet, get_rules
from pokerirl.game.leduc.strategy import Strategy, read_strategy
from pokerirl.meanstd import mean_and_std
from pokerirl.studies.common import claim_folder, markdown_table
from pokerirl.studies.leduc.learn import Learned, Learner, counted_policy, learn

REWARDS = (Learner.AIRL, Learner.HAIRL, Learner.GAIL)  # the learners with a reward
SPARSE = "sparse"
LABELS = {Learner.AIRL: "AIRL", Learner.HAIRL: "H-AIRL", Learner.GAIL: "GAIL", Learner.BC: "BC"}
FILES = ("report.md", "report.json", "agreement.png")


class RLKind(StrEnum):
    """The RL stage's agents: :mod:`pokerirl.agents.leduc_dqn` or :mod:`pokerirl.agents.leduc_q`."""

    DQN = "dqn"
    TABULAR = "tabular"


RL_NAMES = {RLKind.DQN: "DQN", RLKind.TABULAR: "tabular Monte-Carlo"}


@dataclass(frozen=True, kw_only=True)
class LeducStudyConfig:
    """A preset: CFR+ iterations, demonstration hands, IRL runs per learner and epochs, the RL
    agents (``rl``), their seeds (seed s trains on IRL run ``s % runs``) and hands per agent."""

    preset: str
    rules: RuleSet = RuleSet.RLCARD
    cfr_iterations: int
    hands: int
    runs: int
    epochs: int
    rl_seeds: tuple[int, ...]
    rl_hands: int
    rl: RLKind = RLKind.DQN
    seed: int = 0  # of the demonstrations

    def __post_init__(self) -> None:
        if self.rl not in tuple(RLKind):
            raise ConfigError(f"unknown RL agent {self.rl!r}: choose {', '.join(RLKind)}")
        if min(self.cfr_iterations, self.hands, self.runs, self.epochs, self.rl_hands) < 1 \
                or not self.rl_seeds or len(set(self.rl_seeds)) != len(self.rl_seeds) \
                or min(self.rl_seeds) < 0:  # fmt: skip
            raise ConfigError("a Leduc study needs counts >= 1 and distinct RL seeds >= 0")

    def settings(self) -> dict[str, Any]:
        return {**asdict(self), "rl_seeds": list(self.rl_seeds)}


# quick: the poker study's quick IRL (2 runs per algorithm, 20 epochs, 4 agent seeds: two
# per IRL run) on 10,000 expert hands (~35,000 decisions); wide: quick's sizes with 5 IRL runs
# and 10 agent seeds, for the spreads; smoke: seconds, numbers meaningless.
PRESETS = {
    "quick": LeducStudyConfig(preset="quick", cfr_iterations=1000, hands=10_000, runs=2,
                              epochs=20, rl_seeds=(0, 1, 2, 3), rl_hands=100_000),
    "wide": LeducStudyConfig(preset="wide", cfr_iterations=1000, hands=10_000, runs=5,
                             epochs=20, rl_seeds=tuple(range(10)), rl_hands=100_000),
    "smoke": LeducStudyConfig(preset="smoke", cfr_iterations=20, hands=200, runs=2, epochs=1,
                              rl_seeds=(0, 1), rl_hands=2_000),
}  # fmt: skip
# The tabular learner's hands per agent (samples are cheap, and it needs many: one cell each).
TABULAR_HANDS = {"quick": 500_000, "wide": 500_000, "smoke": 2_000}


def preset(name: str, *, rules: str = RuleSet.RLCARD, rl: str = RLKind.DQN) -> LeducStudyConfig:
    if name not in PRESETS:
        raise ConfigError(f"unknown Leduc study preset {name!r}: choose {', '.join(PRESETS)}")
    if rl not in tuple(RLKind):
        raise ConfigError(f"unknown RL agent {rl!r}: choose {', '.join(RLKind)}")
    found = replace(PRESETS[name], rules=RuleSet(get_rules(rules).name), rl=RLKind(rl))
    return replace(found, rl_hands=TABULAR_HANDS[name]) if rl == RLKind.TABULAR else found


def run_leduc_study(
    config: LeducStudyConfig,
    out: Path,
    *,
    expert: Path | None = None,
    overwrite: bool = False,
    echo: Callable[[str], None] = lambda line: None,
) -> dict[str, Any]:
    """Run (or finish) the study in ``out``; ``expert``: a strategy file or solve folder to
    use in place of solving. Returns report.json's content."""
    from pokerirl.game.leduc.solve import solve

    rules = get_rules(config.rules)
    strategy_file = _expert_file(expert) if expert is not None else out / "solve" / "strategy.json"
    if expert is not None:  # a bad file is refused before the folder is claimed
        _check_rules(strategy_file, read_strategy(strategy_file)[0], rules)
    settings = {**config.settings(), "expert": None if expert is None else str(strategy_file)}
    out.mkdir(parents=True, exist_ok=True)
    claim_folder(out, settings, overwrite=overwrite)
    clock = time.perf_counter()

    def stage(line: str) -> None:
        echo(f"[{time.perf_counter() - clock:6.1f} s] {line}")

    if not strategy_file.is_file():
        stage(f"solve: CFR+ {config.cfr_iterations:,} iterations ({rules.name} rules)")
        solve(rules, iterations=config.cfr_iterations, out=out / "solve", overwrite=True)
    found_rules, cfr = read_strategy(strategy_file)
    _check_rules(strategy_file, found_rules, rules)
    demos_file = out / "demos.npz"
    if not demos_file.is_file() or overwrite:
        stage(f"synth: {config.hands:,} hands of the expert against itself (seed {config.seed})")
        save(synthesize(rules, cfr, hands=config.hands, seed=config.seed), demos_file)
    demos = load(demos_file)
    stage(f"demonstrations: {len(demos):,} decisions")
    sets = info_sets(rules)
    runs = tuple(range(config.runs))
    learned: dict[Learner, list[Learned]] = {}
    for learner in Learner:
        path = out / "irl" / f"{learner}.json"
        if not path.is_file() or overwrite:
            stage(f"irl: {learner}, {config.runs} run(s) of {config.epochs} epochs")
            _write_learned(path, learn(demos, learner, seeds=runs, epochs=config.epochs))
        learned[learner] = _read_learned(path, learner, sets)
    agents: dict[str, dict[int, dict[str, Any]]] = {}
    for source in (SPARSE, *REWARDS):
        agents[source] = {}
        for seed in config.rl_seeds:
            path = out / "rl" / f"{source}-{seed}.json"
            if not path.is_file() or overwrite:
                stage(f"rl: {config.rl} on the {source} reward, seed {seed}, "
                      f"{config.rl_hands:,} hands")
                _write_agent(path, config, rules, cfr, sets, source, seed, learned)
            agents[source][seed] = json.loads(path.read_text())
    stage("evaluate: exact agreement, exploitability and expected values")
    report = _report(config, rules, cfr, demos, sets, learned, agents)
    write_text(out / "report.json", json.dumps(report, indent=1) + "\n")
    write_text(out / "report.md", render(report))
    _figure(report, out / "agreement.png")
    stage(f"wrote {out}/report.md, report.json, agreement.png")
    return report


def _check_rules(path: Path, found: LeducRules, rules: LeducRules) -> None:
    if found != rules:
        raise InputError(f"{path}: a strategy for the {found.name} rules, not {rules.name}")


def _expert_file(expert: Path) -> Path:
    return expert / "strategy.json" if expert.is_dir() else expert


# ----------------------------------------------------------------------------- stage files


def _write_learned(path: Path, runs: list[Learned]) -> None:
    def table(values: np.ndarray | None) -> list[list[float]] | None:
        return None if values is None else np.where(np.isfinite(values), values, 0.0).tolist()

    rows = [{"seed": r.seed, "val_alignment": r.val_alignment, "reward": table(r.reward),
             "policy": table(r.policy)} for r in runs]  # fmt: skip
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps(rows) + "\n")


def _read_learned(path: Path, learner: Learner, sets: InfoSets) -> list[Learned]:
    rows = json.loads(path.read_text())

    def table(values: list[list[float]], fill: float) -> np.ndarray:
        return np.where(sets.legal, np.asarray(values), fill)

    return [
        Learned(
            learner=learner, seed=row["seed"], val_alignment=row["val_alignment"],
            reward=None if row["reward"] is None else table(row["reward"], -np.inf),
            policy=table(row["policy"], 0.0),
        )
        for row in rows
    ]


def _write_agent(path: Path, config: LeducStudyConfig, rules: LeducRules, cfr: Strategy,
                 sets: InfoSets, source: str, seed: int,
                 learned: dict[Learner, list[Learned]]) -> None:  # fmt: skip
    run = None if source == SPARSE else learned[Learner(source)][seed % config.runs]
    reward = None if run is None or run.reward is None else np.where(sets.legal, run.reward, 0)
    if config.rl == RLKind.DQN:
        from pokerirl.agents.leduc_dqn import LeducDQNConfig, train_leduc_dqn

        dqn = LeducDQNConfig(hands=config.rl_hands, seed=seed)
        values = train_leduc_dqn(rules, cfr, config=dqn, reward=reward).q
    else:
        from pokerirl.agents.leduc_q import QConfig, train_q

        agent = train_q(rules, cfr, config=QConfig(hands=config.rl_hands, seed=seed),
                        reward=reward)  # fmt: skip
        values = np.where(agent.visits > 0, agent.q, 0.0)  # unvisited actions count 0
    greedy = one_hot_argmax(values, sets.legal)
    follows = None
    if reward is not None:  # the share of information sets where it takes its reward's argmax
        follows = float((greedy.argmax(1) == one_hot_argmax(reward, sets.legal).argmax(1)).mean())
    document = {"source": source, "agent": config.rl, "seed": seed,
                "irl_run": None if run is None else run.seed,
                "follows_reward": follows, "greedy": greedy.argmax(1).tolist()}  # fmt: skip
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps(document) + "\n")


# ----------------------------------------------------------------------------- the report


def _stats(values: list[float]) -> dict[str, float]:
    mean, std = mean_and_std(values)
    return {"mean": mean, "std": std, "n": len(values)}


def _report(config: LeducStudyConfig, rules: LeducRules, cfr: Strategy, demos: Demonstrations,
            sets: InfoSets, learned: dict[Learner, list[Learned]],
            agents: dict[str, dict[int, dict[str, Any]]]) -> dict[str, Any]:  # fmt: skip
    def agree(strategy: Strategy) -> dict[str, float]:
        found = agreement(rules, strategy, cfr)
        return {"uniform": found.uniform, "reached": found.reached}

    learners: dict[str, Any] = {}
    for learner, runs in learned.items():
        rows = []
        for run in runs:
            policy = sets.strategy(run.policy)
            row: dict[str, Any] = {"seed": run.seed, "val_alignment": run.val_alignment,
                                   "policy_agreement": agree(policy),
                                   "policy_exploitability": exploitability(rules, policy)}
            if run.reward is not None:
                row["reward_agreement"] = agree(sets.greedy(run.reward))
            rows.append(row)
        learners[learner] = {"runs": rows, "summary": _summary(rows)}
    counted = sets.strategy(counted_policy(demos))
    bc_counts = {"policy_agreement": agree(counted),
                 "policy_exploitability": exploitability(rules, counted)}  # fmt: skip
    strategies = {source: {seed: sets.strategy(np.eye(4)[a["greedy"]]) for seed, a in by.items()}
                  for source, by in agents.items()}  # fmt: skip
    rl: dict[str, Any] = {}
    for source, by in agents.items():
        rows = []
        for seed, agent in by.items():
            mine = strategies[source][seed]
            row = {"seed": seed, "irl_run": agent["irl_run"],
                   "exploitability": exploitability(rules, mine),
                   "ev_vs_expert": expected_value(rules, mine, cfr).mean,
                   "ev_vs_sparse": expected_value(rules, mine, strategies[SPARSE][seed]).mean,
                   "follows_reward": agent["follows_reward"]}  # fmt: skip
            rows.append(row)
        rl[source] = {"agents": rows, "summary": _summary(rows)}
    return {
        "format": "leduc-study", "version": 1, "settings": config.settings(),
        "rules": rules.name, "decisions": len(demos), "information_sets": len(sets.keys),
        "expert": {"sha256": demos.expert_sha256, "exploitability": exploitability(rules, cfr)},
        "learners": learners, "bc_counts": bc_counts, "rl_agent": _rl_agent(config), "rl": rl,
    }  # fmt: skip


def _rl_agent(config: LeducStudyConfig) -> dict[str, Any]:
    """The RL agents' settings, as trained (seed: the agent's)."""
    if config.rl == RLKind.DQN:
        from pokerirl.agents.leduc_dqn import LeducDQNConfig

        found = asdict(LeducDQNConfig(hands=config.rl_hands))
        found["hidden"] = list(found["hidden"])
    else:
        from pokerirl.agents.leduc_q import QConfig

        found = asdict(QConfig(hands=config.rl_hands))
    del found["seed"]
    return {"kind": str(config.rl), **found}


def _summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Mean and std (over runs or seeds) of every number, nested names joined by dots."""
    flat: dict[str, list[float]] = {}
    for row in rows:
        for name, value in _flatten(row):
            if name not in ("seed", "irl_run") and value is not None:
                flat.setdefault(name, []).append(float(value))
    return {name: _stats(values) for name, values in flat.items()}


def _flatten(row: dict[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    found: list[tuple[str, Any]] = []
    for name, value in row.items():
        if isinstance(value, dict):
            found += _flatten(value, f"{prefix}{name}.")
        else:
            found.append((prefix + name, value))
    return found


def _pm(summary: dict[str, Any], name: str, scale: float = 1.0, digits: int = 3) -> str:
    if name not in summary:
        return "–"
    s = summary[name]
    return f"{s['mean'] * scale:.{digits}f} ± {s['std'] * scale:.{digits}f}"


def render(report: dict[str, Any]) -> str:
    """report.md: a verdict paragraph, then the tables (mean ± std over runs or seeds)."""
    settings, learners, rl = report["settings"], report["learners"], report["rl"]
    expert_mc = report["expert"]["exploitability"] * MILLI
    lines = [f"# Leduc study ({report['rules']} rules, preset {settings['preset']})", "",
             verdict(report), "",
             f"Expert: CFR+ after {settings['cfr_iterations']:,} iterations, exploitability "
             f"{expert_mc:.3f} milli-chips per hand. Demonstrations: {settings['hands']:,} "
             f"hands of the expert against itself (seed {settings['seed']}), "
             f"{report['decisions']:,} decisions; {report['information_sets']} information "
             f"sets. IRL: {settings['runs']} runs per learner, {settings['epochs']} epochs. "
             f"RL: {_rl_name(report)} agents against the expert, {settings['rl_hands']:,} "
             f"hands per agent, seeds {settings['rl_seeds']} (seed s on IRL run s mod "
             f"{settings['runs']}). Every figure is exact (no sampling) except the training "
             "itself; ± is the standard deviation over IRL runs or RL seeds.", "",
             "## What was learned, against the CFR expert", "",
             "Agreement: the share of information sets where the argmax matches the expert's "
             "(uniform: each set once; reached: weighted by how often the expert reaches "
             "it). Exploitability in milli-chips per hand.", ""]  # fmt: skip
    head = ["learner", "policy agreement (uniform)", "policy agreement (reached)",
            "policy exploitability (mchips)", "reward argmax agreement (uniform)",
            "reward argmax agreement (reached)", "validation alignment"]  # fmt: skip
    rows = []
    for name, part in learners.items():
        s = part["summary"]
        rows.append([LABELS[Learner(name)],
                     _pm(s, "policy_agreement.uniform"), _pm(s, "policy_agreement.reached"),
                     _pm(s, "policy_exploitability", MILLI, 0),
                     _pm(s, "reward_agreement.uniform"), _pm(s, "reward_agreement.reached"),
                     _pm(s, "val_alignment")])  # fmt: skip
    counts = report["bc_counts"]
    rows.append(["BC (counts: the data's frequencies)",
                 f"{counts['policy_agreement']['uniform']:.3f}",
                 f"{counts['policy_agreement']['reached']:.3f}",
                 f"{counts['policy_exploitability'] * MILLI:.0f}", "–", "–", "–"])  # fmt: skip
    rows.append(["CFR expert", "1", "1", f"{expert_mc:.3f}", "–", "–", "–"])
    lines += markdown_table(head, rows)
    lines += ["", "## RL on each reward, against the CFR expert", "",
              f"Greedy strategies of {_rl_name(report)} agents; expected values in milli-chips "
              "per hand for the agent, the mean over both seats (exact). 'follows reward': the "
              "share of information sets where the agent's action is its reward's argmax. No "
              "strategy scores more against the expert than its exploitability "
              f"({expert_mc:.3f}: a best response's value, over the seats); a pure strategy "
              "inside the expert's support scores the game value in each seat, 0 on average "
              "over the seats.", ""]  # fmt: skip
    head = ["reward", "exploitability (mchips)", "EV vs CFR expert (mchips)",
            "EV vs sparse agent (mchips)", "follows reward"]  # fmt: skip
    rows = []
    for name, part in rl.items():
        s = part["summary"]
        rows.append([name if name == SPARSE else f"learned ({LABELS[Learner(name)]})",
                     _pm(s, "exploitability", MILLI, 0), _pm(s, "ev_vs_expert", MILLI, 1),
                     _pm(s, "ev_vs_sparse", MILLI, 1), _pm(s, "follows_reward")])  # fmt: skip
    lines += markdown_table(head, rows)
    return "\n".join(lines) + "\n"


def verdict(report: dict[str, Any]) -> str:
    """The opening paragraph, from the numbers (what was found, not what was hoped)."""
    learners, rl = report["learners"], report["rl"]

    def mean(part: dict[str, Any], name: str, scale: float = 1.0) -> float:
        return float(part["summary"][name]["mean"]) * scale

    def span(values: dict[str, float], fmt: str) -> str:
        low, high = min(values.values()), max(values.values())
        return format(low, fmt) if low == high else f"{low:{fmt}} to {high:{fmt}}"

    irl = {n: p for n, p in learners.items() if n != Learner.BC}
    reached = {n: mean(p, "policy_agreement.reached") for n, p in irl.items()}
    uniform = {n: mean(p, "policy_agreement.uniform") for n, p in irl.items()}
    rewards = {n: mean(p, "reward_agreement.reached") for n, p in irl.items()}
    exploit = {n: mean(p, "policy_exploitability", MILLI) for n, p in learners.items()}
    bc = learners[Learner.BC]
    beat = [LABELS[Learner(n)] for n in irl if reached[n] > mean(bc, "policy_agreement.reached")]
    learned = {n: p for n, p in rl.items() if n != SPARSE}
    vs_expert = {n: mean(p, "ev_vs_expert", MILLI) for n, p in learned.items()}
    vs_sparse = {n: mean(p, "ev_vs_sparse", MILLI) for n, p in learned.items()}
    sparse = mean(rl[SPARSE], "ev_vs_expert", MILLI)
    better = [LABELS[Learner(n)] for n, v in vs_expert.items() if v > sparse]
    expert = report["expert"]["exploitability"] * MILLI
    return (
        f"Under {report['rules']}'s rules, the policies of AIRL, H-AIRL and GAIL take the CFR "
        f"expert's most likely action at {span(reached, '.1%')} of the information sets, "
        f"weighted by how often the expert reaches them; BC, the same policy net trained "
        f"without an adversary, at {mean(bc, 'policy_agreement.reached'):.1%}, so "
        + ("no IRL policy beats BC here" if not beat else f"{', '.join(beat)} beat BC")
        + f". Counting each of the {report['information_sets']} sets once, agreement falls to "
        f"{span(uniform, '.1%')} (BC {mean(bc, 'policy_agreement.uniform'):.1%}): the sets "
        f"the expert rarely reaches have little or no data. The rewards' own argmax agrees "
        f"with the expert at {span(rewards, '.1%')} of the reached sets. Every learned policy "
        f"is far from an equilibrium: exploitability {span(exploit, ',.0f')} milli-chips per "
        f"hand, against the expert's {expert:.3f}. {_capital(_rl_name(report))} agents "
        "trained against the expert "
        f"on a learned reward score {span(vs_expert, '+.0f')} milli-chips per hand against it, "
        f"agents trained on the chips themselves {sparse:+.0f} (a best response to the expert: "
        f"{expert:+.1f}); "
        + (f"the {', '.join(better)} reward(s) did better in the mean than the sparse one "
           "against the expert (the tables give the spreads)" if better
           else "no learned reward did better in the mean than the sparse one")
        + f", and head to head the learned-reward agents win {span(vs_sparse, '+.0f')} "
        "milli-chips per hand against the sparse agents of the same seed."
    )


def _rl_name(report: dict[str, Any]) -> str:
    """The RL agents' name (reports written before the DQN had tabular agents)."""
    return RL_NAMES[RLKind(report["settings"].get("rl", RLKind.TABULAR))]


def _capital(text: str) -> str:
    return text[:1].upper() + text[1:]


def _figure(report: dict[str, Any], path: Path) -> None:
    from matplotlib.figure import Figure

    from pokerirl.figures import finish

    figure = Figure(figsize=(11, 4))
    names = list(report["learners"])
    bc = report["learners"][Learner.BC]["summary"]
    for panel, weighting in enumerate(("reached", "uniform")):
        axes = figure.add_subplot(1, 2, panel + 1)
        for i, kind in enumerate(("policy", "reward")):
            metric = f"{kind}_agreement.{weighting}"
            xs, means, stds = [], [], []
            for j, name in enumerate(names):
                summary = report["learners"][name]["summary"]
                if metric in summary:
                    xs.append(j + (i - 0.5) * 0.35)
                    means.append(summary[metric]["mean"])
                    stds.append(summary[metric]["std"])
            label = "policy" if kind == "policy" else "reward argmax"
            axes.bar(xs, means, width=0.35, yerr=stds, capsize=3, label=label)
        axes.axhline(bc[f"policy_agreement.{weighting}"]["mean"], linestyle="-.", color="k",
                     label="BC policy")  # fmt: skip
        axes.set_xticks(range(len(names)), [LABELS[Learner(n)] for n in names])
        axes.set_ylim(0, 1.05)
        what = "weighted by the expert's reach" if weighting == "reached" else "each set once"
        finish(axes, title=f"Leduc ({report['rules']}): argmax = CFR expert's",
               xlabel="learner", ylabel=f"share of information sets ({what})",
               spread="bars: mean ± std over IRL runs")  # fmt: skip
        legend = axes.get_legend()
        if panel == 0 and legend is not None:
            legend.remove()  # one legend, beside the right panel
    figure.savefig(path, format="png", dpi=100, bbox_inches="tight", metadata={"Software": None})

