"""The authors' tournament protocol (silue-dev/hairl ``src/main.py``), on our engine.

For every experiment k (an IRL run and the DQNs trained on it), the authors play
``run_tournament`` 50 times: each is RLCard's ``tournament(env, 1000)``, 1,000 fresh games
without duplicate deals, in which RLCard draws the small blind for every game. Their table
reports, over all 50 x N repeats, the mean and ``np.std(repeats) / sqrt(1000)``: the spread of
one repeat's mean divided again by the square root of its games, which leaves out the
variance between experiments (training runs). Beside it we give the standard error over the
experiments' means (n = N, the replicates that carry the training variance).

Repeat r of experiment k plays deals of seed ``AUTHORS_SEED + 1000 k + r`` with seats drawn
per game (:func:`pokerirl.game.play_match` with ``seating="random"``); agent sets (folders of
``seed-<k>`` agents) give experiment k their ``seed-k`` agent. Each (matchup, experiment) is a
unit of :func:`pokerirl.store.run_units`, saved to
``<out>/experiments/<A>-vs-<B>/experiment-<k>.json`` when it finishes and reused by a rerun
whose agents (by fingerprint), games and repeats match.

>>> import tempfile
>>> with tempfile.TemporaryDirectory() as out:
...     found = run_authors_tournament([("raise", "call")], experiments=[0, 1], out=out,
...                                    repeats=3, games=200)
>>> m = found["raise-vs-call"]
>>> len(m.per_experiment), len(m.experiments[0].repeats_mbb), m.games
(2, 3, 200)
"""

from __future__ import annotations

import json
import math
import re
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np

from pokerirl.agents import ShippedAgent, agent_fingerprint, land_agent, resolve_agent, ship_agent
from pokerirl.atomic import write_text
from pokerirl.execution import Backend, unit_progress
from pokerirl.game.match import play_match
from pokerirl.jsonio import read_json
from pokerirl.serial import Serializable
from pokerirl.store import Json, Layout, Unit, UnitConflict, UnitOutput, run_units
from pokerirl.tournaments.lineup import (
    TournamentError,
    agent_label,
    agent_spec_for_seed,
    check_specs,
)

REPEATS, GAMES = 50, 1_000  # the authors' 50 x run_tournament(num_games=1000)
AUTHORS_SEED = 7_000_000  # deal seeds of the repeats: AUTHORS_SEED + 1000 k + r
REPEAT_STRIDE = 1_000
UNIT_KIND = "pokerirl-authors-tournament"
RESULT_FILE = "authors.json"
RESULT_FORMAT = "pokerirl-authors-tournament/1"


@dataclass(frozen=True, kw_only=True)
class AuthorsExperiment(Serializable):
    """One experiment's repeats: each repeat's mean mbb/h over its games."""

    experiment: int
    repeats_mbb: tuple[float, ...]
    fingerprint_a: str
    fingerprint_b: str

    @property
    def mean(self) -> float:
        return float(np.mean(self.repeats_mbb))


@dataclass(frozen=True, kw_only=True)
class AuthorsSummary(Serializable):
    """A matchup's numbers under the authors' protocol (:meth:`AuthorsMatchup.summary`): what
    ``authors.json`` and the study's ``report.json`` (``table1_authors``) keep of it."""

    mean: float
    paper_style_se: float
    se_over_experiments: float | None  # None for one experiment (JSON has no NaN)
    duplicate_mbb_per_hand: float | None
    per_experiment: list[float]
    repeats: int
    games: int
    agent_a: str
    agent_b: str


@dataclass(frozen=True, kw_only=True)
class AuthorsMatchup(Serializable):
    """A matchup under the authors' protocol: A's result in mbb/h, both statistics.

    ``mean`` is over all repeats; ``paper_style_se`` is the authors' ``std / sqrt(games)``
    over all repeats (numpy's std, ddof 0); ``se_over_experiments`` the standard error of the
    experiments' means (ddof 1; NaN for one experiment); ``per_experiment`` those means.
    ``duplicate_mbb_per_hand`` is our duplicate-deal figure on the same agents, when the
    caller measured it.
    """

    agent_a: str
    agent_b: str
    games: int
    repeats: int
    experiments: tuple[AuthorsExperiment, ...]
    duplicate_mbb_per_hand: float | None = None

    @property
    def all_repeats(self) -> np.ndarray:
        return np.concatenate([np.asarray(e.repeats_mbb) for e in self.experiments])

    @property
    def mean(self) -> float:
        return float(self.all_repeats.mean())

    @property
    def paper_style_se(self) -> float:
        return float(self.all_repeats.std() / math.sqrt(self.games))

    @property
    def per_experiment(self) -> list[float]:
        return [e.mean for e in self.experiments]

    @property
    def se_over_experiments(self) -> float:
        means = np.asarray(self.per_experiment)
        if means.size < 2:
            return float("nan")
        return float(means.std(ddof=1) / math.sqrt(means.size))

    def summary(self) -> AuthorsSummary:
        se = self.se_over_experiments
        return AuthorsSummary(
            mean=self.mean,
            paper_style_se=self.paper_style_se,
            se_over_experiments=None if math.isnan(se) else se,
            duplicate_mbb_per_hand=self.duplicate_mbb_per_hand,
            per_experiment=self.per_experiment,
            repeats=self.repeats,
            games=self.games,
            agent_a=self.agent_a,
            agent_b=self.agent_b,
        )

    def to_json(self) -> dict[str, Any]:  # the summary: written for the reader, never read
        return {**super().to_json(), "summary": self.summary().to_json()}


def repeat_seed(experiment: int, repeat: int) -> int:
    return AUTHORS_SEED + REPEAT_STRIDE * experiment + repeat


def _play_experiment(
    config: Mapping[str, Any], shipped_a: ShippedAgent, shipped_b: ShippedAgent
) -> UnitOutput[None]:
    """One experiment's repeats (a unit: in this process or a worker); the record keeps
    each repeat's mean mbb/h as its result."""
    with tempfile.TemporaryDirectory(prefix="pokerirl-authors-") as private:
        agent_a = land_agent(shipped_a, Path(private, "a"))
        agent_b = land_agent(shipped_b, Path(private, "b"))
    results = []
    for repeat in range(config["repeats"]):
        match = play_match(
            agent_a,
            agent_b,
            hands=config["games"],
            seed=repeat_seed(config["experiment"], repeat),
            duplicate=False,
            seating="random",
        )
        results.append(match.mbb_per_hand)
        unit_progress(repeat + 1, config["repeats"])
    return UnitOutput(result=results)


def _is_repeats(result: Json) -> bool:
    """Whether a saved experiment can be reused: a list of repeats (a record of the right
    settings that holds something else, which no write leaves, is replayed)."""
    return isinstance(result, list)


def _experiment(config: Mapping[str, Any], repeats_mbb: list[float]) -> AuthorsExperiment:
    return AuthorsExperiment(
        experiment=config["experiment"],
        repeats_mbb=tuple(float(x) for x in repeats_mbb),
        fingerprint_a=config["fingerprint_a"],
        fingerprint_b=config["fingerprint_b"],
    )


def _name(a: str, b: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", f"{agent_label(a)}-vs-{agent_label(b)}")


def run_authors_tournament(
    matchups: Sequence[tuple[str, str]],
    *,
    experiments: Sequence[int],
    out: str | Path,
    repeats: int = REPEATS,
    games: int = GAMES,
    names: Sequence[str] | None = None,
    duplicate: dict[str, float] | None = None,
    overwrite: bool = False,
    progress: bool = False,
    backend: Backend | None = None,
) -> dict[str, AuthorsMatchup]:
    """Play every (A, B) under the authors' protocol for every experiment; write
    ``<out>/authors.json`` and return the matchups by name (``names``, default ``A-vs-B``).

    ``duplicate`` maps a name to our duplicate-deal figure for the same agents, recorded
    beside the authors' statistics.

    Raises:
        TournamentError: bad input, a missing ``seed-<k>`` agent, or a saved experiment of
            other settings (without ``overwrite``).
    """
    if not matchups or not experiments:
        raise TournamentError("the authors' tournament needs matchups and experiments")
    if repeats < 1 or games < 2:
        raise TournamentError(f"need repeats >= 1 and games >= 2, got {repeats} and {games}")
    experiments = sorted(set(experiments))
    check_specs(sorted({spec for pair in matchups for spec in pair}), experiments)
    names = list(names) if names is not None else [_name(a, b) for a, b in matchups]
    if len(set(names)) != len(names):
        raise TournamentError("two matchups have the same name")
    out = Path(out)
    shipped: dict[str, tuple[str, ShippedAgent]] = {}

    def agent(spec: str, experiment: int) -> tuple[str, ShippedAgent]:
        resolved = agent_spec_for_seed(spec, experiment)
        if resolved not in shipped:
            try:
                shipped[resolved] = (
                    agent_fingerprint(resolve_agent(resolved)),
                    ship_agent(resolved),
                )
            except (ValueError, OSError) as error:
                raise TournamentError(str(error)) from None
        return shipped[resolved]

    cells = [(m, k) for m in range(len(matchups)) for k in experiments]
    configs, units = [], []
    for m, k in cells:
        (print_a, ship_a), (print_b, ship_b) = agent(matchups[m][0], k), agent(matchups[m][1], k)
        settings = {"kind": UNIT_KIND, "experiment": k, "repeats": repeats, "games": games}
        agents = {"fingerprint_a": print_a, "fingerprint_b": print_b}
        configs.append({**settings, **agents})
        units.append(
            Unit(
                key=f"{names[m]} experiment {k}",
                target=out / "experiments" / names[m] / f"experiment-{k}.json",
                layout=Layout.RECORD,
                config=settings,
                inputs=agents,
                fn=_play_experiment,
                args=(configs[-1], ship_a, ship_b),
                accepts=_is_repeats,
            )
        )
    try:  # each experiment is saved as it finishes: resumable from there
        report = run_units(
            units, backend or Backend(), overwrite=overwrite, progress=progress,
            desc="authors' tournament",
        )  # fmt: skip
    except UnitConflict as error:
        raise TournamentError(str(error), remedy=error.remedy) from None
    done = {  # every result is a list: reused only then (_is_repeats), written as one
        cell: _experiment(config, cast("list[float]", item.record.result))
        for cell, config, item in zip(cells, configs, report.done, strict=True)
    }
    found = {
        names[m]: AuthorsMatchup(
            agent_a=agent_label(a),
            agent_b=agent_label(b),
            games=games,
            repeats=repeats,
            experiments=tuple(done[m, k] for k in experiments),
            duplicate_mbb_per_hand=(duplicate or {}).get(names[m]),
        )
        for m, (a, b) in enumerate(matchups)
    }
    body = {"format": RESULT_FORMAT, "matchups": {n: v.to_json() for n, v in found.items()}}
    write_text(out / RESULT_FILE, json.dumps(body, indent=2) + "\n")
    return found


def load_authors_tournament(folder: str | Path) -> dict[str, AuthorsMatchup]:
    """The matchups of ``<folder>/authors.json``; :class:`TournamentError` if it is not one."""
    path = Path(folder) / RESULT_FILE
    try:
        data = read_json(path)
        if data.get("format") != RESULT_FORMAT:
            raise ValueError("format")
        return {n: AuthorsMatchup.from_json(v) for n, v in data["matchups"].items()}
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as error:
        raise TournamentError(f"{path}: not an authors' tournament ({error})") from None
