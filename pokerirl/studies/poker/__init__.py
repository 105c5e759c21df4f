"""The paper's whole poker study in one call: :func:`run_study` (``pokerirl study``).

Stages (see :mod:`pokerirl.studies.poker.pipeline`): ingest -> IRL (AIRL, H-AIRL; several runs) ->
agents (sparse DQN, AIRL-DQN, H-AIRL-DQN; seed k on IRL run k mod runs) -> tournament
(Table 1) -> [authors: their tournament protocol, with the ``authors`` preset] -> panel
(every agent kind and built-in against every other) -> report (``report.md``,
``report.json``, ``panel.csv``, ``figures/``), with the reward cards of the IRL runs.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from pokerirl.execution import Backend
from pokerirl.studies.common import claim_folder, study_folder
from pokerirl.studies.poker import figures
from pokerirl.studies.poker.config import (
    PRESETS,
    UNRECORDED_DEFAULTS,
    StudyConfig,
    StudyError,
    preset,
)
from pokerirl.studies.poker.pipeline import (
    STAGES,
    Execution,
    Say,
    Study,
    agents_stage,
    authors_stage,
    ingest_stage,
    irl_stage,
    panel_stage,
    reward_cards,
    reward_source_prints,
    stage_names,
    tournament_stage,
)
from pokerirl.studies.poker.report import (
    AUTHORS_FIGURE,
    FIGURES,
    build_report,
    is_study_report,
    load_study_report,
    render_markdown,
    write_study_report,
)
from pokerirl.studies.poker.report_types import StudyReport

__all__ = [
    "PRESETS",
    "STAGES",
    "StudyConfig",
    "StudyError",
    "StudyReport",
    "StudyResult",
    "is_study_report",
    "load_study_report",
    "preset",
    "render_markdown",
    "run_study",
]


@dataclass(frozen=True)
class StudyResult:
    root: Path
    report: StudyReport
    markdown: str


def run_study(
    sources: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    config: StudyConfig,
    *,
    overwrite: bool = False,
    progress: bool = False,
    say: Say = lambda message: None,
    backend: Backend | None = None,
) -> StudyResult:
    """Run (or resume) the study of ``sources`` into ``out``; ``say`` hears one line per stage.

    Its units run on ``backend`` (default: ``config.jobs`` local processes); results do not
    depend on it.

    Raises:
        StudyError: bad settings.
        UnitConflict: a unit made with other settings or inputs (without ``overwrite``), or a
            stage record of an older pokerirl made with other settings. Lower layers' errors
            (IngestError, TournamentError, RunError...) pass through.
    """
    from pokerirl.parsers.irc_sources import check_sources

    if not sources:
        raise StudyError("give at least one SOURCE (an IRC month folder or archive)")
    check_sources(sources)  # before anything is written: a missing path, a plain file
    reward_source_prints(config)  # a reward that replaces IRL runs, checked as early
    root = study_folder(out)
    # Every setting checked against the folder's before anything is written; more seeds only
    # add units beside the finished ones.
    claim_folder(root, config.settings(), overwrite=overwrite, grows=("seeds",),
                 before=lambda: _report_settings(root),
                 implied=UNRECORDED_DEFAULTS)  # fmt: skip
    study = Study(
        root,
        config,
        Execution(backend or Backend(jobs=config.jobs), progress=progress, overwrite=overwrite),
        overwrite,
        say,
    )
    ingested = ingest_stage(study, sources)
    irl = irl_stage(study, ingested)
    agents = agents_stage(study, irl)
    tournament = tournament_stage(study, agents)
    authors = authors_stage(study, agents, tournament) if config.authors_repeats else None
    panel = panel_stage(study, agents)
    stages = len(stage_names(config))
    say(f"[{stages}/{stages}] report -> {root / 'report.md'}")
    report = build_report(
        config, ingested=ingested, irl=irl, agents=agents, tournament=tournament, panel=panel,
        authors=authors, cards=reward_cards(root, config),
    )  # fmt: skip
    figures.irl_alignment(irl, root / FIGURES["irl_alignment"])
    figures.irl_discriminator(irl, root / FIGURES["irl_discriminator"])
    figures.irl_actions(irl, root / FIGURES["irl_actions"])
    figures.rl_curves(agents, root / FIGURES["rl_vs_random"])
    figures.panel_heatmap(panel, root / FIGURES["panel_heatmap"])
    if authors is not None:
        figures.authors_tournament(authors, report, root / AUTHORS_FIGURE)
    write_study_report(root, report, panel)
    return StudyResult(root=root, report=report, markdown=render_markdown(report))


def _report_settings(root: Path) -> dict[str, object] | None:
    """The settings of a study an older pokerirl finished in ``root`` (its report's)."""
    try:
        return dict(load_study_report(root).settings)
    except StudyError:  # none, not a study's, or damaged: the units' records guard the rest
        return None
