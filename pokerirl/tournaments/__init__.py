"""Multi-seed head-to-head tournaments: mbb/h per seed and pooled, t-tests, Bonferroni and
Holm corrections, and the report files (``pokerirl tournament``, ``pokerirl report``);
AIVAT-corrected matches (:mod:`~pokerirl.tournaments.aivat`) and local best response
(:mod:`~pokerirl.tournaments.lbr`, ``pokerirl exploit``: :mod:`~pokerirl.tournaments.exploit`).

>>> import tempfile
>>> with tempfile.TemporaryDirectory() as out:
...     report = run_tournament([("raise", "random")], hands=2_000, seeds=parse_seeds("0-2"),
...                             out=out)
>>> m = report.matchups[0]
>>> (m.agent_a, m.agent_b, len(m.seeds), m.pooled.n, report.family.per_seed_tests)
('raise', 'random', 3, 3, 3)
"""

from __future__ import annotations

from pokerirl.seeds import format_seeds, parse_seeds
from pokerirl.tournaments.aivat import CorrectedMatch, play_corrected_match
from pokerirl.tournaments.authors import (
    AuthorsMatchup,
    load_authors_tournament,
    run_authors_tournament,
)
from pokerirl.tournaments.exploit import (
    ExploitConfig,
    LBRReport,
    LBRRun,
    lbr_of,
    run_lbr,
    run_lbr_many,
)
from pokerirl.tournaments.lbr import LBRSettings, Street
from pokerirl.tournaments.lineup import Side, TournamentError
from pokerirl.tournaments.report import (
    Comparison,
    Design,
    Line,
    MatchupReport,
    Replication,
    SeedLine,
    TournamentReport,
    load_report,
    render_report,
    write_report,
)
from pokerirl.tournaments.runner import run_tournament
from pokerirl.tournaments.stats import (
    AcrossAgents,
    Estimate,
    across_agents,
    bonferroni,
    estimate,
    holm,
)

__all__ = [
    "AcrossAgents",
    "AuthorsMatchup",
    "Comparison",
    "CorrectedMatch",
    "Design",
    "Estimate",
    "ExploitConfig",
    "LBRReport",
    "LBRRun",
    "LBRSettings",
    "Line",
    "MatchupReport",
    "Replication",
    "SeedLine",
    "Side",
    "Street",
    "TournamentError",
    "TournamentReport",
    "across_agents",
    "bonferroni",
    "estimate",
    "format_seeds",
    "holm",
    "lbr_of",
    "load_authors_tournament",
    "load_report",
    "parse_seeds",
    "play_corrected_match",
    "render_report",
    "run_authors_tournament",
    "run_lbr",
    "run_lbr_many",
    "run_tournament",
    "write_report",
]
