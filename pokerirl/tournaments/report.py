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
import io
import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

from pokerirl import atomic
from pokerirl.jsonio import read_json
from pokerirl.seeds import format_seeds
from pokerirl.serial import SerialError, Serializable, meta
from pokerirl.tournaments.lineup import TournamentError
from pokerirl.tournaments.stats import Estimate

REPORT_FORMAT = "pokerirl-tournament/1"
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
    """The two families of tests: per seed (seeds x matchups) and pooled (matchups), each
    with its Bonferroni threshold."""

    per_seed_tests: int
    per_seed_threshold: float
    pooled_tests: int
    pooled_threshold: float


@dataclass(frozen=True, kw_only=True)
class TournamentReport(Serializable):
    """Everything ``pokerirl tournament`` found, ready to write or print.

    ``config``: hands per seed, seeds, duplicate, batch_size, alpha. ``family``: the size and
    Bonferroni threshold of the per-seed family (seeds x matchups) and of the pooled family
    (matchups). ``timing``: this run's wall time, hands/s, backend and the seeds it played
    and reused; not part of the results (a rerun that reuses saved seeds is faster and
    reports the same numbers), so not in :meth:`to_json`: it is written to ``timings.json``,
    which :func:`load_report` reads back when it is there.
    """

    FORMAT = REPORT_FORMAT

    config: TournamentSettings
    family: FamilySizes
    matchups: tuple[MatchupReport, ...]
    versions: Mapping[str, str | None]
    # timings.json, as read: never in report.json
    timing: Mapping[str, Any] = field(default_factory=dict, metadata=meta(skip=True))


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
        report = TournamentReport.from_json(data)
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


def render_markdown(report: TournamentReport) -> str:
    config, family = report.config, report.family
    alpha, seeds = config.alpha, config.seeds
    per_seed_rule = _threshold(alpha, family.per_seed_tests)
    pooled_rule = _threshold(alpha, family.pooled_tests)
    names = ", ".join(f"{m.agent_a} vs {m.agent_b}" for m in report.matchups)
    unit = "duplicate pair (a deal played from both seats)" if config.duplicate else "hand"
    seating = "duplicate deals" if config.duplicate else "seats alternating, no duplicate"
    pooled_how = (
        f"the mean of the {len(seeds)} per-seed means, with its standard error and a t-test "
        f"over those {len(seeds)} values (df {len(seeds) - 1}): seeds are the replicates"
        if len(seeds) > 1
        else "with a single seed, the pooled line is that seed's own test"
    )
    out = [
        f"# Tournament: {names}",
        "",
        f"{config.hands:,} hands per seed, seeds {format_seeds(seeds)} ({len(seeds)}), "
        f"{seating}. Payoffs are the first agent's, in milli-big-blinds per hand (mbb/h).",
        "",
        "## Results",
        "",
        f"| Model | Opponent | Payoff (mbb/h) ± SE | 95% CI | p-value | Significant after "
        f"Bonferroni ({pooled_rule}) | Holm p | Seeds significant ({per_seed_rule}) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for m in report.matchups:
        p = m.pooled
        out.append(
            f"| {m.agent_a} | {m.agent_b} | {_mbb(p.mbb_per_hand)} ± {p.std_error:.2f} | "
            f"{_ci(p.ci95)} | {render_p(p.p_value)} | {_yes(p.significant_bonferroni)} | "
            f"{render_p(p.p_value_holm)} | {m.seeds_significant_bonferroni}/{len(m.seeds)} |"
        )
    out += [
        "",
        f"Pooled: {pooled_how}. Bonferroni and Holm over the {family.pooled_tests} pooled "
        f"test(s), one per matchup.",
        *_aivat_section(report),
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
