"""The tournament report: its data, its files (``report.md``, ``report.json``,
``per_seed.csv``, ``per_seed.png``, and ``timings.json`` beside them) and its text.

Every number lives in :class:`TournamentReport`; the files are renderings of it, written
atomically (:mod:`pokerirl.atomic`), so the numbers agree across them: Markdown shows
them rounded, JSON and CSV in full (``repr``) precision. The same seeds give the same bytes
in all four: the run's wall-clock figures are in ``timings.json`` alone.

>>> render_p(0.000123456), render_p(0.5), render_p(0.0)
('0.000123', '0.5', '< 1e-300')
"""

from __future__ import annotations

import csv
import enum
import io
import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from pokerirl import atomic
from pokerirl.jsonio import read_json
from pokerirl.seeds import format_seeds
from pokerirl.serial import SerialError, Serializable, meta
from pokerirl.tournaments.lineup import Group, TournamentError
from pokerirl.tournaments.stats import Estimate, across_agents, bonferroni, holm

REPORT_FORMAT = "pokerirl-tournament/2"
# /1 had no comparisons: each matchup was its own, and they are derived when one is read
OLD_FORMATS = ("pokerirl-tournament/1",)
TIMINGS_FILE = "timings.json"
REPORT_FILE, MARKDOWN_FILE = "report.json", "report.md"
SEEDS_TABLE, SEEDS_FIGURE = "per_seed.csv", "per_seed.png"


@dataclass(frozen=True, kw_only=True)
class Line:
    """One test: estimate in mbb/h (from A's side), its p-value and the corrected ones.

    ``n`` is the number of independent units (duplicate pairs, hands, or seeds for the pooled
    line). Significance is ``p_value < alpha / m`` (Bonferroni) and ``p_value_holm < alpha``.
    """

    mbb_per_hand: float
    std_error: float
    ci95: tuple[float, float]
    p_value: float
    n: int
    p_value_bonferroni: float
    p_value_holm: float
    significant_bonferroni: bool
    significant_holm: bool


@dataclass(frozen=True, kw_only=True)
class SeedLine(Line):
    """One seed of one matchup, with the agents that played it."""

    seed: int
    hands: int
    fingerprint_a: str
    fingerprint_b: str
    aivat: Estimate | None = None  # the chance-corrected twin (None: saved before AIVAT)


@dataclass(frozen=True, kw_only=True)
class MatchupReport(Serializable):
    """A against B over every seed; ``pooled_over`` says what the pooled line's units are."""

    agent_a: str
    agent_b: str
    spec_a: str
    spec_b: str
    pooled: Line
    pooled_over: Literal["seeds", "units of the only seed"]
    seeds: tuple[SeedLine, ...]
    aivat: Estimate | None = None  # the pooled line's chance-corrected twin (AIVAT)

    @property
    def seeds_significant_bonferroni(self) -> int:
        return sum(line.significant_bonferroni for line in self.seeds)

    def to_json(self) -> dict[str, Any]:  # the count: written for the reader, never read
        return {
            **super().to_json(),
            "seeds_significant_bonferroni": self.seeds_significant_bonferroni,
        }


class Replication(enum.StrEnum):
    """What a comparison's test replicates, so what it can support a claim about."""

    TRAINING_SEEDS = "training seeds"  # several independently trained agents on a side
    DEAL_SEEDS = "deal seeds only"  # one agent per side: a claim about these two agents


class Design(enum.StrEnum):
    """How the agents of a comparison's two sides met."""

    ONE_PAIR = "one pair"  # one agent per side
    PAIRS = "independent pairs"  # each agent in one pair (seed k against seed k), or one side fixed
    CROSSED = "crossed"  # every A agent against every B agent, on the same deals


@dataclass(frozen=True, kw_only=True)
class Comparison(Serializable):
    """One side against the other, over every agent each side has: the test the verdict is.

    ``agents_a``/``agents_b``: the distinct agents (fingerprints) on each side, so the
    training seeds; ``pairs``: the distinct agent pairs that met. With one agent per side
    (``Replication.DEAL_SEEDS``) ``line`` is the matchup's pooled line: a test about these two
    agents only. With more, ``line`` is the test across training seeds
    (:func:`~pokerirl.tournaments.stats.across_agents`: its standard error never below
    ``deal_std_error``, ``df`` its degrees of freedom), Bonferroni and Holm over every
    comparison. ``deal_std_error``: the standard error the deals' noise alone gives on the same
    games; ``between_std_error``: the one from the spread between the pairs alone (None with
    one pair). ``matchups``: the indices of the matchups (agent pairs) it is made of.
    """

    agent_a: str
    agent_b: str
    replication: Replication
    design: Design
    agents_a: int
    agents_b: int
    pairs: int
    line: Line
    df: float
    deal_std_error: float
    between_std_error: float | None
    matchups: tuple[int, ...]


@dataclass(frozen=True, kw_only=True)
class TournamentSettings(Serializable):
    """What every seed of a tournament played: hands per seed, the seeds, duplicate deals or
    not, the engine's batch, and the significance level."""

    hands: int
    seeds: tuple[int, ...]
    duplicate: bool
    batch_size: int
    alpha: float


@dataclass(frozen=True, kw_only=True)
class FamilySizes(Serializable):
    """The families of tests: per seed (seeds x matchups), pooled (matchups: agent pairs) and
    the comparisons (one per side against side), each with its Bonferroni threshold."""

    per_seed_tests: int
    per_seed_threshold: float
    pooled_tests: int
    pooled_threshold: float
    comparison_tests: int = 0  # the comparisons, whose tests are the verdicts (0: a /1 file)
    comparison_threshold: float = 0.0


@dataclass(frozen=True, kw_only=True)
class TournamentReport(Serializable):
    """Everything ``pokerirl tournament`` found, ready to write or print.

    ``config``: hands per seed, seeds, duplicate, batch_size, alpha. ``family``: the size and
    Bonferroni threshold of the per-seed family (seeds x matchups), of the pooled family
    (matchups) and of the comparisons. ``comparisons``: each side against the other over all
    its agents, with what its test replicates; their lines are the verdicts. ``timing``: this
    run's wall time, hands/s, backend and the seeds it played
    and reused; not part of the results (a rerun that reuses saved seeds is faster and
    reports the same numbers), so not in :meth:`to_json`: it is written to ``timings.json``,
    which :func:`load_report` reads back when it is there.
    """

    FORMAT = REPORT_FORMAT

    config: TournamentSettings
    family: FamilySizes
    matchups: tuple[MatchupReport, ...]
    versions: Mapping[str, str | None]
    comparisons: tuple[Comparison, ...] = ()  # () only while a /1 file is read
    # timings.json, as read: never in report.json
    timing: Mapping[str, Any] = field(default_factory=dict, metadata=meta(skip=True))


def corrected_lines(estimates: list[Estimate], alpha: float) -> list[Line]:
    """Each estimate with Bonferroni and Holm over the whole list (one family)."""
    p = np.array([e.p_value for e in estimates])
    p_bonferroni, p_holm = bonferroni(p), holm(p)
    threshold = alpha / len(estimates)
    return [
        Line(
            **asdict(e),
            p_value_bonferroni=float(p_bonferroni[i]),
            p_value_holm=float(p_holm[i]),
            significant_bonferroni=bool(e.p_value < threshold),
            significant_holm=bool(p_holm[i] < alpha),
        )
        for i, e in enumerate(estimates)
    ]


def compare(
    matchups: tuple[MatchupReport, ...], groups: list[Group], alpha: float
) -> tuple[Comparison, ...]:
    """Each group's comparison, its test chosen by how many agents each side has (told apart
    by fingerprint, seed by seed), then corrected over all groups."""
    found: list[dict[str, Any]] = []  # each comparison's fields but its corrected line
    estimates: list[Estimate] = []
    for group in groups:
        lines = [line for k in group.matchups for line in matchups[k].seeds]
        # In the order the matchups list them, not by fingerprint: a fingerprint covers the
        # agent's config, which names its run's folder, and sums taken in another order differ
        # in their last bits (the same study elsewhere must give the same bytes).
        rows = list(dict.fromkeys(line.fingerprint_a for line in lines))
        cols = list(dict.fromkeys(line.fingerprint_b for line in lines))
        cells: dict[tuple[int, int], list[SeedLine]] = {}
        for line in lines:
            cell = rows.index(line.fingerprint_a), cols.index(line.fingerprint_b)
            cells.setdefault(cell, []).append(line)
        means = np.full((len(rows), len(cols)), np.nan)
        deal_variances = np.zeros_like(means)
        for (i, j), played in cells.items():
            means[i, j] = float(np.mean([line.mbb_per_hand for line in played]))
            deal_variances[i, j] = sum(line.std_error**2 for line in played) / len(played) ** 2
        fields: dict[str, Any] = dict(agent_a=group.agent_a, agent_b=group.agent_b,
                                      agents_a=len(rows), agents_b=len(cols), pairs=len(cells),
                                      matchups=group.matchups)  # fmt: skip
        if len(cells) == 1:  # these two agents only: the pooled line over the deal seeds
            only = matchups[group.matchups[0]].pooled
            estimates.append(Estimate(mbb_per_hand=only.mbb_per_hand, std_error=only.std_error,
                                      ci95=only.ci95, p_value=only.p_value, n=only.n))  # fmt: skip
            fields.update(replication=Replication.DEAL_SEEDS, design=Design.ONE_PAIR,
                          df=float(max(only.n - 1, 1)), between_std_error=None,
                          deal_std_error=float(np.sqrt(deal_variances.sum())))  # fmt: skip
        else:
            across = across_agents(means, deal_variances)
            estimates.append(across.estimate)
            fields.update(replication=Replication.TRAINING_SEEDS,
                          design=Design.CROSSED if across.crossed else Design.PAIRS,
                          df=across.df, between_std_error=across.between_std_error,
                          deal_std_error=across.deal_std_error)  # fmt: skip
        found.append(fields)
    tested = corrected_lines(estimates, alpha)
    return tuple(
        Comparison(**fields, line=line) for fields, line in zip(found, tested, strict=True)
    )


def with_comparisons(report: TournamentReport) -> TournamentReport:
    """A report of the /1 format, which had none, with its comparisons: one per matchup."""
    if report.comparisons:
        return report
    groups = [Group(agent_a=m.agent_a, agent_b=m.agent_b, matchups=(k,))
              for k, m in enumerate(report.matchups)]  # fmt: skip
    comparisons = compare(report.matchups, groups, report.config.alpha)
    family = replace(report.family, comparison_tests=len(comparisons),
                     comparison_threshold=report.config.alpha / len(comparisons))  # fmt: skip
    return replace(report, comparisons=comparisons, family=family)


# --- writing and reading -------------------------------------------------------------------


def write_report(report: TournamentReport, out: Path) -> None:
    """Write the four report files and ``timings.json`` (when the report has timings) into
    ``out``; report.json last, so it marks a whole run."""
    out.mkdir(parents=True, exist_ok=True)
    if report.timing:
        atomic.write_text(out / TIMINGS_FILE, json.dumps(report.timing, indent=2) + "\n")
    atomic.write_text(out / MARKDOWN_FILE, render_markdown(report))
    atomic.write_text(out / SEEDS_TABLE, render_csv(report))
    atomic.write_bytes(out / SEEDS_FIGURE, render_png(report))
    atomic.write_text(out / REPORT_FILE, render_json(report))


def load_report(out: Path | str) -> TournamentReport:
    """The report saved in ``out`` by ``pokerirl tournament``.

    Raises:
        TournamentError: one line naming ``report.json`` if it is missing, not JSON, or not a
            whole report.
    """
    path = Path(out) / REPORT_FILE
    try:
        data = read_json(path)
    except FileNotFoundError:
        raise TournamentError(f"{out}: no {REPORT_FILE} (run pokerirl tournament first)") from None
    except (OSError, json.JSONDecodeError) as error:
        raise TournamentError(f"{path}: cannot read the report ({error})") from None
    if not isinstance(data, dict):
        raise TournamentError(f"{path}: not a tournament report (a JSON object), got {_kind(data)}")
    try:
        if data.get("format") in OLD_FORMATS:  # the same fields, less the comparisons
            data = {**data, "format": REPORT_FORMAT}
        report = with_comparisons(TournamentReport.from_json(data))
        render_markdown(report)  # a report that loads can be printed: check every field once
    except (TournamentError, SerialError) as error:
        raise TournamentError(f"{path}: {error}") from None
    except (KeyError, IndexError, TypeError, ValueError, AttributeError, ArithmeticError) as error:
        raise TournamentError(f"{path}: malformed report ({error!r})") from None
    try:  # wall-clock figures, not results: a missing or damaged file is no timings
        timing = read_json(Path(out) / TIMINGS_FILE)
    except (OSError, ValueError):
        timing = {}
    return replace(report, timing=timing if isinstance(timing, dict) else {})


def _kind(data: object) -> str:
    """A JSON value's kind for messages: ``list``, ``str``, ``null``..."""
    return "null" if data is None else type(data).__name__


# --- renderings ----------------------------------------------------------------------------


def render_report(report: TournamentReport, output_format: str = "markdown") -> str:
    """The report as ``"markdown"`` (what ``report.md`` holds) or ``"json"``."""
    if output_format == "json":
        return render_json(report)
    if output_format in ("markdown", "text"):
        return render_markdown(report)
    raise TournamentError(f"unknown format {output_format!r} (markdown or json)")


def render_json(report: TournamentReport) -> str:
    return json.dumps(report.to_json(), indent=2) + "\n"


def render_p(p: float) -> str:
    """A p-value with three significant digits."""
    return "< 1e-300" if p == 0.0 else f"{p:.3g}"


def _mbb(value: float) -> str:
    return f"{value:+.2f}"


def _ci(ci: tuple[float, float]) -> str:
    return f"[{ci[0]:+.2f}, {ci[1]:+.2f}]"


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def _threshold(alpha: float, tests: int) -> str:
    return f"p < {alpha:g}/{tests} = {alpha / tests:.4g}"


def _agents(count: int) -> str:
    return "1 agent" if count == 1 else f"{count} agents"


def replication_lines(report: TournamentReport) -> list[str]:
    """What each comparison's test replicates, so which claim it supports: the report's
    first lines."""
    seeds = len(report.config.seeds)
    out = ["Unit of replication (what the p-values and verdicts below generalize over):", ""]
    for c in report.comparisons:
        sides = f"{c.agent_a} {_agents(c.agents_a)}, {c.agent_b} {_agents(c.agents_b)}"
        if c.replication is Replication.DEAL_SEEDS:
            out.append(
                f"- {c.agent_a} vs {c.agent_b}: **deal seeds only** ({sides}). The p-value "
                f"and the verdict are about these two agents only: the {seeds} seed(s) "
                "re-deal the cards for the same two agents and never sample the variance "
                "of training; a claim about the method that trained them needs at "
                "least 2 agents per side, trained with different seeds."
            )
            continue
        how = (
            "every pair on the same deals, two-way random-effects test"
            if c.design is Design.CROSSED
            else "each agent in one pair, t-test over the pairs' means"
        )
        fixed = [name for name, n in ((c.agent_a, c.agents_a), (c.agent_b, c.agents_b)) if n == 1]
        scope = (
            f"a claim about the training that made them, against this one {fixed[0]} agent"
            if fixed
            else "a claim about the training that made them, not about one pair of agents"
        )
        out.append(
            f"- {c.agent_a} vs {c.agent_b}: **training seeds** ({sides}; {c.pairs} pairs, "
            f"{how}, df {c.df:.3g}): {scope}."
        )
    return out


def render_markdown(report: TournamentReport) -> str:
    config, family = report.config, report.family
    alpha, seeds = config.alpha, config.seeds
    per_seed_rule = _threshold(alpha, family.per_seed_tests)
    pooled_rule = _threshold(alpha, family.pooled_tests)
    verdict_rule = _threshold(alpha, family.comparison_tests)
    names = ", ".join(f"{c.agent_a} vs {c.agent_b}" for c in report.comparisons)
    unit = "duplicate pair (a deal played from both seats)" if config.duplicate else "hand"
    seating = "duplicate deals" if config.duplicate else "seats alternating, no duplicate"
    pooled_how = (
        f"the mean of the {len(seeds)} per-seed means, with its standard error and a t-test "
        f"over those {len(seeds)} values (df {len(seeds) - 1})"
        if len(seeds) > 1
        else "with a single seed, that seed's own test over its units"
    )
    out = [
        f"# Tournament: {names}",
        "",
        *replication_lines(report),
        "",
        f"{config.hands:,} hands per seed, seeds {format_seeds(seeds)} ({len(seeds)}), "
        f"{seating}. Payoffs are the first agent's, in milli-big-blinds per hand (mbb/h).",
        "",
        "## Results",
        "",
        f"| Model | Opponent | Agents (A, B) | Replicated over | Payoff (mbb/h) ± SE | 95% CI "
        f"| df | p-value | Significant after Bonferroni ({verdict_rule}) | Holm p | Deal-only SE "
        f"| Seeds significant ({per_seed_rule}) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in report.comparisons:
        p = c.line
        seed_lines = [s for k in c.matchups for s in report.matchups[k].seeds]
        significant = sum(s.significant_bonferroni for s in seed_lines)
        out.append(
            f"| {c.agent_a} | {c.agent_b} | {c.agents_a}, {c.agents_b} | {c.replication} | "
            f"{_mbb(p.mbb_per_hand)} ± {p.std_error:.2f} | {_ci(p.ci95)} | {c.df:.3g} | "
            f"{render_p(p.p_value)} | {_yes(p.significant_bonferroni)} | "
            f"{render_p(p.p_value_holm)} | {c.deal_std_error:.2f} | "
            f"{significant}/{len(seed_lines)} |"
        )
    kinds = {c.replication for c in report.comparisons}
    out += [
        "",
        *([f"One agent per side: the pooled line over the deal seeds, {pooled_how}."]
          if Replication.DEAL_SEEDS in kinds else []),
        *(["Several agents per side (training seeds): the test across them (a t-test over "
           "independent pairs' means, or the two-way random-effects model when every agent "
           "met every agent: docs/cli.md), its standard error never below the deal-only one."]
          if Replication.TRAINING_SEEDS in kinds else []),
        "Deal-only SE: what the deals' noise alone gives on the same games, as if the agents "
        f"were fixed. Bonferroni and Holm over the {family.comparison_tests} comparison(s).",
    ]  # fmt: skip
    if any(len(c.matchups) > 1 for c in report.comparisons):
        out += _pairs_section(report, pooled_rule)
    out += _aivat_section(report)
    out += [
        "",
        "## Per seed",
        "",
        f"Unit: one {unit}; standard errors, CIs and two-sided t-tests are over the units of "
        f"each seed. Bonferroni and Holm over all {family.per_seed_tests} per-seed tests "
        f"({len(seeds)} seeds x {len(report.matchups)} matchup(s)): significant if "
        f"{per_seed_rule} (the paper's 0.05/20 is this threshold for one matchup and 20 "
        "seeds).",
        "",
        "| Model | Opponent | Seed | Payoff (mbb/h) ± SE | 95% CI | p-value | Bonferroni p "
        "| Holm p | Significant after Bonferroni |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for m in report.matchups:
        for s in m.seeds:
            out.append(
                f"| {m.agent_a} | {m.agent_b} | {s.seed} | {_mbb(s.mbb_per_hand)} ± "
                f"{s.std_error:.2f} | {_ci(s.ci95)} | {render_p(s.p_value)} | "
                f"{render_p(s.p_value_bonferroni)} | {render_p(s.p_value_holm)} | "
                f"{_yes(s.significant_bonferroni)} |"
            )
    out += ["", "## Run", ""]
    for m in report.matchups:
        for side, spec, key in (("A", m.spec_a, "fingerprint_a"), ("B", m.spec_b, "fingerprint_b")):
            prints = {getattr(s, key) for s in m.seeds}
            shown = (
                prints.pop()
                if len(prints) == 1
                else f"{len(prints)} agents, one per seed (fingerprints in per_seed.csv)"
            )
            out.append(f"- {m.agent_a} vs {m.agent_b}, {side} = `{spec}`: {shown}")
    versions = ", ".join(f"{name} {version}" for name, version in report.versions.items())
    out += [
        f"- batch size {config.batch_size}; versions: {versions}",
        f"- wall-clock figures of the last run (and the seeds it reused): {TIMINGS_FILE}",
        "",
    ]
    return "\n".join(out)


def _pairs_section(report: TournamentReport, pooled_rule: str) -> list[str]:
    """Each agent pair's own result over the deal seeds (about that pair only)."""
    out = [
        "",
        "## Per agent pair (deal seeds only)",
        "",
        "Each pair of agents over the deal seeds: about that pair only. Bonferroni and Holm over "
        f"the {report.family.pooled_tests} pairs.",
        "",
        f"| Model | Opponent | Payoff (mbb/h) ± SE | 95% CI | p-value | Significant after "
        f"Bonferroni ({pooled_rule}) | Holm p |",
        "|---|---|---|---|---|---|---|",
    ]
    for m in report.matchups:
        p = m.pooled
        out.append(
            f"| {m.agent_a} | {m.agent_b} | {_mbb(p.mbb_per_hand)} ± {p.std_error:.2f} | "
            f"{_ci(p.ci95)} | {render_p(p.p_value)} | {_yes(p.significant_bonferroni)} | "
            f"{render_p(p.p_value_holm)} |"
        )
    return out


def _aivat_section(report: TournamentReport) -> list[str]:
    """The raw and the chance-corrected (AIVAT) pooled results side by side, when known."""
    rows = [m for m in report.matchups if m.aivat is not None]
    if not rows:
        return []
    out = [
        "",
        "## Variance-reduced (AIVAT chance corrections)",
        "",
        "The same hands, each corrected at the flop, turn and river by v(after the card) - "
        "E[v] with v = chips committed x (2 equity - 1), fixed in code "
        "(`pokerirl.tournaments.aivat`): an unbiased estimate of the same payoff, usually "
        "with a smaller standard error.",
        "",
        "| Model | Opponent | Raw (mbb/h) ± SE | Corrected (mbb/h) ± SE | SE corrected / raw |",
        "|---|---|---|---|---|",
    ]
    for m in rows:
        raw, fixed = m.pooled, m.aivat
        assert fixed is not None
        ratio = f"{fixed.std_error / raw.std_error:.2f}" if raw.std_error > 0 else "n/a"
        out.append(
            f"| {m.agent_a} | {m.agent_b} | {_mbb(raw.mbb_per_hand)} ± {raw.std_error:.2f} | "
            f"{_mbb(fixed.mbb_per_hand)} ± {fixed.std_error:.2f} | {ratio} |"
        )
    return out


CSV_COLUMNS = (
    "agent_a",
    "agent_b",
    "seed",
    "hands",
    "n",
    "mbb_per_hand",
    "std_error",
    "ci95_low",
    "ci95_high",
    "p_value",
    "p_value_bonferroni",
    "p_value_holm",
    "significant_bonferroni",
    "significant_holm",
    "fingerprint_a",
    "fingerprint_b",
    "aivat_mbb_per_hand",
    "aivat_std_error",
)


def render_csv(report: TournamentReport) -> str:
    """One row per (matchup, seed); floats in full precision."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=CSV_COLUMNS, lineterminator="\n")
    writer.writeheader()
    for m in report.matchups:
        for s in m.seeds:
            row = {k: v for k, v in asdict(s).items() if k in CSV_COLUMNS}
            row.update(
                agent_a=m.agent_a, agent_b=m.agent_b, ci95_low=s.ci95[0], ci95_high=s.ci95[1],
                aivat_mbb_per_hand=None if s.aivat is None else s.aivat.mbb_per_hand,
                aivat_std_error=None if s.aivat is None else s.aivat.std_error,
            )  # fmt: skip
            writer.writerow({k: repr(v) if isinstance(v, float) else v for k, v in row.items()})
    return buffer.getvalue()


def render_png(report: TournamentReport) -> bytes:
    """Per-seed mbb/h with 95% CIs, one colour per matchup, pooled means dashed.

    Drawn on a bare ``Figure`` (Agg canvas, no pyplot): no display, no global state.
    """
    from matplotlib.figure import Figure

    from pokerirl.figures import finish

    figure = Figure(figsize=(max(6.0, 0.35 * len(report.config.seeds) + 3), 4.0))
    axes = figure.subplots()
    width = 0.6 / max(1, len(report.matchups))
    for i, m in enumerate(report.matchups):
        x = [s.seed + (i - (len(report.matchups) - 1) / 2) * width for s in m.seeds]
        y = [s.mbb_per_hand for s in m.seeds]
        # Clipped at 0: rounding can put a zero-width CI a hair off its mean.
        errors = [
            [max(0.0, s.mbb_per_hand - s.ci95[0]) for s in m.seeds],
            [max(0.0, s.ci95[1] - s.mbb_per_hand) for s in m.seeds],
        ]
        bars = axes.errorbar(
            x, y, yerr=errors, fmt="o", capsize=3, markersize=4, label=f"{m.agent_a} vs {m.agent_b}"
        )
        axes.axhline(m.pooled.mbb_per_hand, linestyle="--", linewidth=1, color=bars[0].get_color())
    axes.axhline(0.0, color="black", linewidth=0.8)
    finish(axes, title=f"Per seed: {report.config.hands:,} hands each",
           xlabel="seed", ylabel="mbb/hand of the first agent",
           spread="bars: 95% CI of each seed; dashed: the pooled mean", integer_x=True)  # fmt: skip
    figure.tight_layout()
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=120)
    return buffer.getvalue()
