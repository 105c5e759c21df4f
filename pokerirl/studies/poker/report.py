"""The study report: ``report.json`` (every number, with the names scripts read) and
``report.md`` (the paper's Table 1 beside ours, then IRL, RL and the panel, with figures)."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pokerirl import atomic
from pokerirl.holdem import ACTIONS
from pokerirl.irl.metrics import Metric
from pokerirl.jsonio import read_json
from pokerirl.meanstd import MeanStd, mean_and_std
from pokerirl.studies.common import REPORT_JSON, REPORT_MD, markdown_table
from pokerirl.studies.poker import paper
from pokerirl.studies.poker.config import (
    ALGO_LABELS,
    KIND_LABELS,
    LBR_CHECK_UNTIL,
    TABLE1_ORDER,
    StudyConfig,
    StudyError,
    matchup_label,
)
from pokerirl.studies.poker.report_types import (
    AuthorsRow,
    BCPart,
    CardSummary,
    DataPart,
    HandsResult,
    IRLAlgoPart,
    IRLPaper,
    IRLPart,
    PanelPart,
    RLKindPart,
    RLPart,
    StudyReport,
    Table1Row,
    TrainingLengthPart,
)
from pokerirl.studies.poker.results import (
    AgentsResult,
    Ingested,
    IRLResult,
    IRLRuns,
    Panel,
    Reference,
    Replaced,
    Table1Line,
)

if TYPE_CHECKING:  # ``pokerirl report`` loads no tournament code
    from pokerirl.tournaments import AuthorsMatchup

REPORT_FORMAT = "pokerirl-study-report/1"
FIGURES = {
    "irl_alignment": "figures/irl_alignment.png",
    "irl_discriminator": "figures/irl_discriminator.png",
    "irl_actions": "figures/irl_actions.png",
    "rl_vs_random": "figures/rl_vs_random.png",
    "panel_heatmap": "figures/panel_heatmap.png",
}
PANEL_CSV = "panel.csv"
def _paper_line(name: str) -> Reference | None:
    """The paper's Table 1 line of matchup ``name`` (None: the paper has no such row)."""
    published = paper.TABLE1.get(name)
    return None if published is None else Reference(**published)


AUTHORS_FIGURE = "figures/authors_tournament.png"


def build_report(
    config: StudyConfig,
    *,
    ingested: Ingested,
    irl: IRLResult,
    agents: AgentsResult,
    tournament: Mapping[str, Table1Line],
    panel: Panel,
    authors: Mapping[str, AuthorsMatchup] | None = None,
    cards: Mapping[str, CardSummary | None] | None = None,
) -> StudyReport:
    """The whole report, typed (its JSON: :meth:`StudyReport.to_json`).

    ``authors``: the authors' tournament stage's result (``table1_authors``); ``cards``: the
    reward cards' summaries per algorithm (``reward_cards``).
    """
    table1 = {
        name: Table1Row(line=line, paper=_paper_line(name)) for name, line in tournament.items()
    }
    algos: dict[str, IRLAlgoPart | Replaced] = {}
    runs = {algo: found for algo, found in irl.items() if isinstance(found, IRLRuns)}
    # BC is trained inside every run on that run's split; H-AIRL's runs' BC is the one reported.
    reported = next((algo for algo in TABLE1_ORDER if algo in runs), None)
    for algo in config.algos:
        found = irl[algo]
        if isinstance(found, Replaced):
            algos[algo] = found
            continue
        final = found.final
        published = paper.IRL_ALIGNMENT.get(algo)  # GAIL is not in the paper
        algos[algo] = IRLAlgoPart(
            final_val_alignment=Metric.VAL_ALIGNMENT.of(final).stats,
            final_disc_acc_expert=Metric.DISC_ACC_EXPERT.of(final).stats,
            final_disc_acc_policy=Metric.DISC_ACC_POLICY.of(final).stats,
            per_run_val_alignment=Metric.VAL_ALIGNMENT.of(final).values,
            final_val_reward_alignment=(
                Metric.VAL_REWARD_ALIGNMENT.of(final).stats
                if Metric.VAL_REWARD_ALIGNMENT in final
                else None
            ),
            paper=IRLPaper(
                final_val_alignment=None if published is None else MeanStd(**published),
                final_disc_acc=paper.DISC_ACC_FINAL.get(algo),
            ),
        )
    irl_part = IRLPart(algos=algos, runs=config.runs)
    if reported is not None:
        baselines = runs[reported].baselines
        irl_part = IRLPart(
            algos=algos,
            runs=config.runs,
            bc=BCPart(final_val_alignment=baselines["bc"].stats,
                      per_run_val_alignment=baselines["bc"].values),
            baselines={
                name: baselines[name].stats for name in ("majority", "legal_majority")
            },
            epochs=runs[reported].epochs,
        )  # fmt: skip
    # The authors' preset plays its kept checkpoint: that one is measured against random.
    vs_random = agents.vs_random
    rl = RLPart(
        kinds={kind: _rl_kind(vs_random[kind], paper.RL_VS_RANDOM.get(kind))
               for kind in config.kinds},
        references=dict(agents.references),
        per_seed={kind: vs_random[kind] for kind in config.kinds},
        measured=(
            f"the playing checkpoint, {agents.playing_hands:,} duplicate hands"
            if agents.playing_vs_random is not None
            else "the last evaluation of training"
        ),
        follows_reward=agents.follows_reward,
    )
    length = agents.training_length
    summary = ingested.summary
    figures = dict(FIGURES)
    table1_authors = None
    if authors is not None:
        table1_authors = {
            name: AuthorsRow(**vars(authors[name].summary()), paper=_paper_line(name))
            for name in table1
        }
        figures["authors_tournament"] = AUTHORS_FIGURE
    return StudyReport(
        format=REPORT_FORMAT,
        preset=config.preset,
        runs=config.runs,
        seeds=list(config.seeds),
        hands=config.hands,
        settings=config.settings(),
        data=DataPart(
            kept_hands=summary.get("kept_hands"),
            rows=summary.get("rows"),
            hands_read_total=summary.get("hands_read_total"),
        ),
        table1=table1,
        irl=irl_part,
        rl_vs_random=rl,
        training_length=TrainingLengthPart(
            short=_hands_result(length.short_agent_hands, length.short),
            long=_hands_result(length.agent_hands, length.long),
            paper=paper.DQN_TRAINING,
        ),
        panel=PanelPart(
            panel=panel,
            hands=config.panel_hands,
            lbr_hands=config.lbr_hands,
            lbr_check_until=LBR_CHECK_UNTIL,
        ),
        figures=figures,
        paper=paper.paper_values(),
        reward_cards=cards,
        table1_authors=table1_authors,
    )


def _rl_kind(values: Sequence[float], published: float | None) -> RLKindPart:
    mean, std = mean_and_std(values)
    return RLKindPart(mean=mean, std=std, paper=published)


def _hands_result(hands: int, values: Sequence[float]) -> HandsResult:
    mean, std = mean_and_std(values)
    return HandsResult(hands=hands, mean=mean, std=std)


def panel_csv(panel: Panel) -> str:
    """The cross-table: one row per agent, ``mbb ± se`` against each column agent."""
    names = panel.agents
    lines = [",".join(["agent", *names])]
    for name, row, errors in zip(names, panel.mbb_per_hand, panel.std_error, strict=True):
        cells = [
            "" if v is None else f"{v:.1f} ± {e:.1f}" for v, e in zip(row, errors, strict=True)
        ]
        lines.append(",".join([name, *cells]))
    return "\n".join(lines) + "\n"


def _pm(value: MeanStd, scale: float = 1.0, digits: int = 0) -> str:
    mean, std = value.measured
    return f"{mean * scale:,.{digits}f} ± {std * scale:,.{digits}f}"


def _p(p: float) -> str:
    return f"{p:.2e}" if p < 1e-3 else f"{p:.3f}"


def plain_verdict(report: StudyReport) -> str | None:
    """The report's first paragraph, in plain words: does the learned reward help the first
    learned-reward DQN of Table 1 here, by how much, and against what (None: no Table 1)."""
    if not report.table1:
        return None
    name, row = next(iter(report.table1.items()))
    kind = name.split("_vs_")[0]
    algo = kind.removesuffix("_dqn")
    line = row.line
    helps = line.mbb_per_hand > 0 and line.p_bonferroni < 0.05
    words = [
        f"**Does the learned reward help here?** {'Yes' if helps else 'No'}: "
        f"{matchup_label(name)} is {line.mbb_per_hand:+,.0f} ± {line.std_error:,.0f} mbb/hand "
        f"(SE over {line.n:,} independent units, {len(report.seeds)} seeds; Bonferroni p "
        f"{_p(line.p_bonferroni)})."
    ]
    panel = report.panel.panel
    lbr = dict(zip(panel.agents, panel.lbr_mbb_per_hand, strict=False))
    if lbr.get(kind) is not None and lbr.get("dqn") is not None and lbr.get("call") is not None:
        words.append(
            f"A local best response wins {lbr[kind]:+,.0f} mbb/hand from it, "
            f"{lbr['dqn']:+,.0f} from the sparse DQN and {lbr['call']:+,.0f} from always-call "
            "(lower is less exploitable)."
        )
    follows = (report.rl_vs_random.follows_reward or {}).get(kind)
    if follows:
        words.append(f"It takes its reward's best action on {sum(follows) / len(follows):.0%} "
                     "of its decisions against random.")  # fmt: skip
    part = report.irl.algos.get(algo)
    reward = getattr(part, "final_val_reward_alignment", None)
    if reward is not None and report.irl.bc is not None:
        bc = report.irl.bc.final_val_alignment.mean
        words.append(
            f"Its reward's argmax agrees with the expert on {reward.mean:.1%} of validation "
            f"states, behaviour cloning on {bc:.1%}."
        )
    return " ".join(words)


def irl_phase(settings: Mapping[str, Any], epochs: int | None) -> str:
    """How the IRL runs trained: offline epochs, or (issue 43) online rounds on the engine."""
    if settings.get("irl_mode") != "online":
        return f"{epochs} epochs"
    return (f"online: {settings['online_rounds']} rounds of "
            f"{settings['online_generator_steps']:,} decisions on the engine against "
            f"{settings['online_opponent']}")  # fmt: skip


def render_markdown(report: StudyReport) -> str:
    """``report.md``: the paper's numbers beside ours, and what the paper leaves open."""
    return "\n".join([
        *_header_markdown(report),
        *_table1_markdown(report),
        *_irl_markdown(report),
        *_rl_markdown(report),
        *authors_markdown(report),
        *cards_markdown(report),
        *_panel_markdown(report),
        *lbr_markdown(report.panel, len(report.seeds)),
    ])  # fmt: skip


def _header_markdown(report: StudyReport) -> list[str]:
    """The title, the plain verdict, the data and the sizes against the paper's."""
    settings = report.settings
    seeds = report.seeds
    n_seeds = len(seeds)
    verdict = plain_verdict(report)
    lines = [
        f"# pokerirl study ({report.preset} preset)",
        "",
        *([verdict, ""] if verdict else []),
        f"Data: {report.data.kept_hands:,} kept heads-up hands, {report.data.rows:,} decisions.",
        f"Sizes: {report.runs} IRL runs per algorithm ({irl_phase(settings, report.irl.epochs)}), "
        f"{n_seeds} agent seeds ({seeds[0]}-{seeds[-1]}) of "
        f"{settings['agent_hands']:,} training hands, {report.hands:,} tournament hands per "
        f"seed ({'duplicate deals' if settings['duplicate'] else 'no duplicate deals'}), "
        f"{settings['panel_hands']:,} per seed for each panel pair.",
        replication_line(report),
    ]
    if report.preset == "authors":
        if report.runs < 20:
            lines.append(
                f"**Fewer experiments**: the authors ran 20 experiments; this study ran "
                f"{report.runs} (`--runs`); these numbers are noisier."
            )
    elif report.preset != "paper":
        lines.append(
            "**Reduced sizes**: the paper's protocol is 10 IRL runs, 20 seeds of 50,000 hands and "
            "20 x 1,000,000 tournament hands (`--preset paper`); these numbers are noisier."
        )
    return lines


def _table1_markdown(report: StudyReport) -> list[str]:
    """Table 1: each learned-reward DQN against the sparse one, beside the paper's."""
    n_seeds = len(report.seeds)
    lines = [
        "",
        "## Table 1: against the sparse-reward DQN (mbb/hand, "
        f"{'across training seeds' if n_seeds > 1 else 'one agent per side'})",
        "",
        "| matchup | ours | SE | p | p (Bonferroni) | seeds with p < 0.05/m | the paper |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, entry in report.table1.items():
        row, theirs = entry.line, entry.paper
        lines.append(
            f"| {matchup_label(name)} | {row.mbb_per_hand:+,.0f} | {row.std_error:,.0f} | "
            f"{_p(row.p_value)} | {_p(row.p_bonferroni)} | "
            f"{row.seeds_significant_bonferroni}/{n_seeds} | "
            + ("not in the paper |" if theirs is None
               else f"{theirs.mbb_per_hand:+,} ± {theirs.std_error} (p < 1e-10) |")
        )  # fmt: skip
    spread = {
        name: (min(row.line.per_seed), max(row.line.per_seed))
        for name, row in report.table1.items()
    }
    lines += [
        "",
        "Per-seed range: "
        + "; ".join(f"{name} {low:+,.0f} to {high:+,.0f}" for name, (low, high) in spread.items())
        + f". {_table1_test(report)}",
        "",
        "**Where the paper is silent.** The paper does not say whether its tournament used "
        "duplicate deals. We do (each deal from both seats), which removes the luck of the cards "
        "but also makes two deterministic agents of opposite styles (an aggressive one and a "
        "calling station) nearly cancel out, so a DQN-vs-DQN number near 0 can hide very "
        "different play. The panel below answers that: every agent against every other and "
        "against fixed strategies.",
        "",
    ]
    return lines


def _irl_markdown(report: StudyReport) -> list[str]:
    """The IRL stage: validation alignment and discriminator accuracy, with the figures."""
    lines = [
        "## IRL (validation alignment: share of held-out expert actions the policy picks)",
        "",
        "| | ours (mean ± std over runs) | the paper |",
        "|---|---|---|",
    ]
    irl = report.irl
    trained: list[tuple[IRLAlgoPart, str]] = []
    for algo, part in irl.algos.items():
        label = ALGO_LABELS[algo]
        if isinstance(part, Replaced):
            lines.append(f"| {label} | replaced by `{part.source}` | |")
            continue
        trained.append((part, label))
        ours, published = part.final_val_alignment, part.paper.final_val_alignment
        lines.append(
            f"| {label} | {_pm(ours, 100, 1)}% | "
            + ("not in the paper |" if published is None
               else f"{published.measured[0] * 100:.1f} ± {published.measured[1] * 100:.1f}% |")
        )  # fmt: skip
    if irl.bc is not None:
        lines.append(f"| BC (supervised only) | {_pm(irl.bc.final_val_alignment, 100, 1)}%"
                     " | not reported |")  # fmt: skip
        for name in ("majority", "legal_majority"):
            baseline = (irl.baselines or {})[name]
            lines.append(f"| {name} | {_pm(baseline, 100, 1)}% | not reported |")
    lines += [
        "",
        "Discriminator accuracy at the end of IRL (expert / policy actions):",
        "",
        "| | ours, expert | ours, policy | the paper (about) |",
        "|---|---|---|---|",
    ]
    for part, label in trained:
        lines.append(
            f"| {label} | {_pm(part.final_disc_acc_expert, 100, 1)}% | "
            f"{_pm(part.final_disc_acc_policy, 100, 1)}% | "
            + ("not in the paper |" if part.paper.final_disc_acc is None
               else f"{part.paper.final_disc_acc * 100:.0f}% |")
        )  # fmt: skip
    figures = report.figures
    lines += [
        "",
        f"![validation alignment]({figures['irl_alignment']})",
        f"![discriminator accuracy]({figures['irl_discriminator']})",
        f"![action distributions]({figures['irl_actions']})",
        "",
        "The BC action distribution is not drawn: the IRL core records only BC's alignment.",
        "",
    ]
    return lines


def _rl_markdown(report: StudyReport) -> list[str]:
    """The DQNs against random, how closely they follow their rewards, training length."""
    n_seeds = len(report.seeds)
    figures = report.figures
    lines = [
        f"## RL against random (mbb/hand of {rl_measured(report)}, mean ± std over seeds)",
        "",
        "| agent | ours | per-seed range | the paper (about) |",
        "|---|---|---|---|",
    ]
    rl = report.rl_vs_random
    for kind, found in rl.kinds.items():
        values = rl.per_seed[kind]
        lines.append(
            f"| {KIND_LABELS[kind]} | {_pm(MeanStd(mean=found.mean, std=found.std))} | "
            f"{min(values):+,.0f} to {max(values):+,.0f} | "
            + ("not in the paper |" if found.paper is None else f"{found.paper:+,} |")
        )  # fmt: skip
    for name in ("call", "raise"):
        ref = rl.references[name]
        lines.append(f"| always-{name} | {ref.mbb_per_hand:+,.0f} (SE {ref.std_error:,.0f})"
                     " | one fixed strategy | not reported |")  # fmt: skip
    length = report.training_length
    if rl.follows_reward:
        follows = ", ".join(
            f"{KIND_LABELS[kind]} {sum(values) / len(values):.0%} "
            f"({min(values):.0%} to {max(values):.0%})"
            for kind, values in rl.follows_reward.items()
        )
        lines += [
            "",
            "How closely each learned-reward DQN follows its reward (the share of its decisions "
            "against random that take the reward's best legal action; mean, seed range): "
            f"{follows}.",
        ]
    lines += [
        "",
        f"![RL against random]({figures['rl_vs_random']})",
        "",
    ]
    short, long = length.short, length.long
    if short.hands != long.hands:
        lines += [
            f"**Training length.** The paper's DQN trains {length.paper}; ours trains "
            f"{long.hands:,} hands. On the same {n_seeds} seeds, the sparse DQN ends "
            f"at {_pm(MeanStd(mean=short.mean, std=short.std))} mbb/hand against random after "
            f"{short.hands:,} hands and {_pm(MeanStd(mean=long.mean, std=long.std))} after "
            f"{long.hands:,}.",
            "",
        ]
    return lines


def _panel_markdown(report: StudyReport) -> list[str]:
    """Every agent against every other, with its replication."""
    n_seeds = len(report.seeds)
    figures = report.figures
    lines = [
        "## Panel: row agent against column agent (mbb/hand ± SE over seeds)",
        "",
    ]
    panel = report.panel.panel
    names = panel.agents
    lines += markdown_table(
        ["", *names],
        (
            [name, *("-" if v is None else f"{v:+,.0f} ± {e:,.0f}"
                     for v, e in zip(row, errors, strict=True))]
            for name, row, errors in zip(names, panel.mbb_per_hand, panel.std_error,
                                         strict=True)
        ),
    )  # fmt: skip
    lines += [
        "",
        f"{report.panel.hands:,} hands per seed per pair, {n_seeds} seeds; cross-table in "
        f"`{PANEL_CSV}`. {_panel_replication(panel)}",
        "",
        f"![panel]({figures['panel_heatmap']})",
        "",
    ]
    return lines


TRAINING_SEEDS = "training seeds"  # the tournament's Replication values, as written
DEAL_SEEDS = "deal seeds only"


def replication_line(report: StudyReport) -> str:
    """The report's first word on what its tests replicate (the study trains one agent per
    seed and kind, and plays seed k against seed k on the deals of seed k)."""
    n = len(report.seeds)
    if n < 2:
        return (
            "**Unit of replication: deal seeds only** (1 agent per kind): Table 1's and the "
            "panel's p-values are about these agents only, not about the methods that "
            "trained them."
        )
    return (
        f"**Unit of replication: training seeds** ({n} agents per DQN kind, one per seed; "
        "seed k plays seed k on the deals of seed k): Table 1 and the panel's DQN cells test "
        f"across the {n} independent pairs of agents (df {n - 1}), a claim about the training "
        "methods; cells between two fixed strategies (random, raise, call) replicate deal "
        "seeds only."
    )


def _table1_test(report: StudyReport) -> str:
    """How Table 1's SE and p were computed, from its lines (reports before it said: the
    seeds were the replicates, as now)."""
    lines = [row.line for row in report.table1.values()]
    said = [line for line in lines if line.replicated_over is not None]
    if not said:
        return "Seeds are the replicates (SE over per-seed means, df = seeds - 1)."
    if all(line.replicated_over == DEAL_SEEDS for line in said):
        return ("One agent per side: SE over the deal seeds, about these agents only, not "
                "about their training.")  # fmt: skip
    floors = ", ".join(f"{line.deal_std_error:,.0f}" for line in said
                       if line.deal_std_error is not None)  # fmt: skip
    return (
        "Training seeds are the replicates: SE over the per-pair means (seed k against seed "
        f"k; df = seeds - 1), never below the deals' own noise on the same games (deal-only "
        f"SE: {floors})."
    )


def _panel_replication(panel: Panel) -> str:
    """Which panel cells are tested across training seeds and which over deal seeds only."""
    units = panel.replicated_over
    if units is None:
        return "SE over per-seed means."
    cells = [unit for row in units for unit in row if unit is not None]
    trained = sum(unit == TRAINING_SEEDS for unit in cells) // 2
    dealt = sum(unit == DEAL_SEEDS for unit in cells) // 2
    return (
        f"SE across training seeds for the {trained} pairs with a DQN kind (one agent per "
        f"seed); over deal seeds only for the {dealt} between fixed strategies."
    )


def lbr_markdown(part: PanelPart, n_seeds: int) -> list[str]:
    """Each panel member's exploitability by LBR, beside its result against random."""
    panel = part.panel
    if not part.lbr_hands or not panel.lbr_mbb_per_hand:
        return []
    versus_random = panel.agents.index("random") if "random" in panel.agents else None
    rows = []
    for k, name in enumerate(panel.agents):
        lbr, error = panel.lbr_mbb_per_hand[k], panel.lbr_std_error[k]
        vs = None if versus_random is None else panel.mbb_per_hand[k][versus_random]
        vs_error = None if versus_random is None else panel.std_error[k][versus_random]
        rows.append([
            name,
            "-" if lbr is None else f"{lbr:+,.0f} ± {error:,.0f}",
            "-" if vs is None else f"{vs:+,.0f} ± {vs_error:,.0f}",
        ])  # fmt: skip
    return [
        "## How exploitable each agent is: local best response (mbb/hand ± SE)",
        "",
        *markdown_table(["agent", "LBR wins against it", "it wins against random"], rows),
        "",
        f"LBR (docs/exploit.md) plays {part.lbr_hands:,} duplicate hands per seed against each "
        f"agent, {n_seeds} seeds pooled; it only checks or calls before the "
        f"{part.lbr_check_until}. Its win rate is a lower bound on the agent's exploitability: "
        "higher is weaker. Always-fold gives exactly +750; a result against random says little "
        "(always-call beats random by about +1,190 and LBR from the turn beats it by about "
        "900).",
        "",
    ]


def rl_measured(report: StudyReport) -> str:
    measured = report.rl_vs_random.measured
    return "the last evaluation of training" if measured is None else measured


def _f(value: MeanStd | None) -> str:
    if value is not None:
        mean, std = value.measured
        return f"{mean:+.2f} ± {std:.2f}"
    return "n/a" if value is None else str(value)


def cards_markdown(report: StudyReport) -> list[str]:
    """The reward cards section: what each learned reward prefers (mean ± std over runs)."""
    cards = report.reward_cards or {}
    if not any(cards.values()):
        return []
    lines = [
        "## Reward cards (what each learned reward prefers, on the validation hands)",
        "",
        "f per action over the states where it is legal; the per-decision bonus is the mean of f "
        "over the legal actions other than fold; shares are of f's argmax over the legal "
        "actions. Mean ± std over runs.",
        "",
        "| | f call | f raise | f fold | f check | bonus | argmax raise | argmax = expert | "
        "argmax = legal majority |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    theirs = report.paper.get("authors_rewards", {})
    for algo, card in cards.items():
        if not card:
            continue
        label = ALGO_LABELS[algo]
        f = card.mean_f
        lines.append(
            f"| {label} ({card.runs} runs) | {_f(f['call'])} | {_f(f['raise'])} | "
            f"{_f(f['fold'])} | {_f(f['check'])} | {_f(card.decision_bonus)} | "
            f"{_pm(card.argmax_share['raise'], 100, 1)}% | "
            f"{_pm(card.agree_expert, 100, 1)}% | "
            f"{_pm(card.agree_legal_majority, 100, 1)}% |"
        )
        if algo in theirs:
            mine = theirs[algo]
            f_theirs = " | ".join(f"{mine['mean_f'][a]:+.2f}" for a in ACTIONS)
            lines.append(
                f"| the authors' published {label} reward (the review; not in the paper) | "
                f"{f_theirs} | | {mine['argmax_share']['raise'] * 100:.0f}% | "
                f"{mine['agree_expert']} | |"
            )
    any_card = next(c for c in cards.values() if c)
    expert = any_card.expert_share
    raises = "" if not expert else (
        f" The expert raises in {_pm(expert['raise'], 100, 1)}% of them."
    )  # fmt: skip
    lines += [
        "",
        f"The legal-majority rule itself agrees with the expert on "
        f"{_pm(any_card.legal_majority_agree_expert, 100, 1)}% of these states.{raises}",
        "",
    ]
    for algo, card in cards.items():
        if card:
            lines.append(f"- {algo}: {card.predictions[0]}")
            if card.figure:
                lines.append(f"  ![{algo} reward card]({card.figure})")
    for algo, card in cards.items():
        if card and card.below_bc:
            lines += [
                "",
                f"**Warning: {card.below_bc} of {card.runs} {algo} rewards agree with the expert "
                "less than behaviour cloning on the same validation hands** (f's argmax below "
                "BC's alignment): such a reward has learned less of the expert than a plain "
                "classifier.",
            ]
            if report.preset == "demo":
                lines += ["", DEMO_BELOW_BC]
    return [*lines, ""]


# Why the demo's run is expected to raise that warning (pokerirl demo says it in its last lines).
DEMO_BELOW_BC = (
    "*In the demo this is expected, not a broken install:* BC is trained to predict the "
    "expert's action and the reward is not (its argmax is a by-product of telling the expert's "
    "actions from the policy's), and the demo's month is synthetic: two scripted threshold "
    "players whose actions a classifier fits closely, learned from in a few short runs, where "
    "the reward's argmax lands a little below BC. The study on real hands "
    "(`pokerirl study irc-199504`) makes the same comparison on the paper's kind of data."
)


def authors_markdown(report: StudyReport) -> list[str]:
    """The authors' protocol section, when the study ran it."""
    table = report.table1_authors
    if not table:
        return []
    first = next(iter(table.values()))
    n = len(first.per_experiment)
    lines = [
        "## The authors' protocol (their train_rl.py and main.py, on our engine)",
        "",
        f"{n} experiments: IRL run k, then a sparse DQN, an AIRL-DQN and an H-AIRL-DQN with "
        "their DQN settings (5,000 hands against random; the > 0.8 x best checkpoint plays), "
        f"then {first.repeats} x {first.games:,} non-duplicate games per pair, the small "
        "blind drawn per game. Their ± is std(repeats)/√1000 over all repeats: deal seeds "
        "only, whose replicates re-deal the cards for the same agents; the SE over "
        "experiments replicates training seeds (each experiment its own IRL run and DQNs), "
        "the one a claim about the methods needs.",
        "",
        "| matchup | mean | their ± | SE over experiments | ours: duplicate deals | the paper |",
        "|---|---|---|---|---|---|",
    ]
    for name, row in table.items():
        se = row.se_over_experiments
        duplicate = row.duplicate_mbb_per_hand
        theirs = row.paper
        lines.append(
            f"| {matchup_label(name)} | {row.mean:+,.0f} | {row.paper_style_se:,.0f} | "
            f"{'n/a' if se is None else f'{se:,.0f}'} | "
            f"{'n/a' if duplicate is None else f'{duplicate:+,.0f}'} | "
            + ("not in the paper |" if theirs is None
               else f"{theirs.mbb_per_hand:+,} ± {theirs.std_error} |")
        )  # fmt: skip
        per = ", ".join(f"{v:+,.0f}" for v in row.per_experiment)
        lines.append(f"| (per experiment) | {per} | | | | |")
    return [*lines, "", f"![the authors' tournament]({report.figures['authors_tournament']})",
            ""]  # fmt: skip


def write_study_report(root: Path, report: StudyReport, panel: Panel) -> None:
    """``panel.csv``, ``report.md``, then ``report.json`` last: it marks a finished study."""
    atomic.write_text(root / PANEL_CSV, panel_csv(panel))
    atomic.write_text(root / REPORT_MD, render_markdown(report))
    atomic.write_text(root / REPORT_JSON, json.dumps(report.to_json(), indent=2) + "\n")


def is_study_report(folder: Path | str) -> bool:
    """Whether ``folder/report.json`` is a study report (not a tournament's)."""
    try:
        data = read_json(Path(folder) / REPORT_JSON)
    except (OSError, json.JSONDecodeError):
        return False
    return isinstance(data, dict) and data.get("format") == REPORT_FORMAT


def load_study_report(folder: Path | str) -> StudyReport:
    """The study report in ``folder``; one-line :class:`StudyError` when it is not one."""
    path = Path(folder) / REPORT_JSON
    try:
        data = read_json(path)
    except FileNotFoundError:
        raise StudyError(f"{folder}: no report.json (run pokerirl study first)") from None
    except (OSError, json.JSONDecodeError) as error:
        raise StudyError(f"{path}: cannot read the report ({error})") from None
    if not isinstance(data, dict) or data.get("format") != REPORT_FORMAT:
        raise StudyError(f"{path}: not a study report")
    try:
        report = StudyReport.from_json(data)
        render_markdown(report)
    except (KeyError, IndexError, TypeError, ValueError, AttributeError) as error:
        raise StudyError(f"{path}: malformed study report ({error!r})") from None
    return report
