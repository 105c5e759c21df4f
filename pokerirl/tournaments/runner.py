"""Multi-seed tournaments: every matchup on every seed, saved seed by seed, then tested.

Seed ``k`` of matchup (A, B) is ``play_match(A_k, B_k, hands=N, seed=k)``: the deals and both
agents' random draws depend only on ``k`` (and the batch size), so a seed's result is the same
whichever process plays it and in whatever order; every matchup plays the same deals on seed k.

Statistics (see :mod:`pokerirl.tournaments.stats`):

* per seed: mean mbb/h from A's side over the seed's independent units (duplicate pairs, or
  hands without duplicate), standard error, 95% t CI, two-sided one-sample t-test;
* pooled, per matchup: the same over the per-seed means (n = seeds, df = seeds - 1), so seeds
  are the replicates, which with agent sets includes the spread between training runs. With one
  seed the pooled line is that seed's own test;
* per comparison (one per pair of sides, the verdict): with one agent per side, the pooled
  line, a claim about these two agents only (deal seeds only); with several agents on a side
  (an agent set's seeds, or a list of agents: every pair on the same deals), the test across
  training seeds (:func:`~pokerirl.tournaments.stats.across_agents`), agents told apart by
  fingerprint;
* Bonferroni and Holm over the family of all per-seed tests (seeds x matchups), separately
  over the pooled tests (one per matchup), and over the comparisons. The paper's threshold
  p < 0.05/20 (one matchup, 20 seeds) is the per-seed family's; its payoff ± SE is the pooled
  line.

Execution: each (matchup, seed) is a unit of :func:`pokerirl.store.run_units`, on local
processes or Ray; the units get the agents' bytes (read here once), so workers need no shared
filesystem, and play on one torch thread, so results do not depend on the backend.

Resuming: each seed's result is saved to ``<out>/seeds/<A>-vs-<B>/seed-<k>.json`` as soon as
it finishes: a unit record (:mod:`pokerirl.store`) whose fingerprint covers the agents'
fingerprints, hands, duplicate mode and batch size (seed files of the writers before the
store keep theirs). A rerun reuses a saved seed when those
match; when they do not it refuses (:class:`TournamentError`), unless ``overwrite=True``,
which recomputes that seed. A saved seed that is not a valid record (corrupt, truncated,
``[]``, a string, an older format) cannot have come from a finished write, which is atomic:
it is recomputed, which gives the same numbers.

Same seeds, same bytes: wall-clock figures (the run's and each seed's seconds and hands/s,
the backend, the seeds reused) go to ``<out>/timings.json`` only, never into the seed files
or the report. Seed files written before that (with ``seconds`` in their result) are reused
as they are.
"""

from __future__ import annotations

import contextlib
import functools
import re
import sys
import tempfile
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pokerirl.agents import ShippedAgent, agent_fingerprint, land_agent, resolve_agent, ship_agent
from pokerirl.errors import Remedy
from pokerirl.execution import Backend, pinned_threads
from pokerirl.game.match import DEFAULT_BATCH_SIZE, check_match_size, play_match
from pokerirl.jsonio import read_json
from pokerirl.store import Json, Layout, Unit, UnitConflict, UnitOutput, run_units
from pokerirl.tournaments.aivat import CorrectedMatch, play_corrected_match
from pokerirl.tournaments.lineup import (
    Group,
    Side,
    TournamentError,
    agent_spec_for_seed,
    check_specs,
    expand_sides,
)
from pokerirl.tournaments.report import (
    REPORT_FILE,
    FamilySizes,
    MatchupReport,
    SeedLine,
    TournamentReport,
    TournamentSettings,
    compare,
    corrected_lines,
    write_report,
)
from pokerirl.tournaments.stats import Estimate, estimate
from pokerirl.versions import package_versions

SEED_KIND = "pokerirl-tournament-seed"


@dataclass(frozen=True, kw_only=True)
class SeedKey:
    """What a saved seed result must match to be reused."""

    seed: int
    fingerprint_a: str
    fingerprint_b: str
    hands: int
    duplicate: bool
    batch_size: int


@dataclass(frozen=True, kw_only=True)
class SeedResult:
    """One seed of one matchup before corrections: ``key``, ``estimate`` and its AIVAT twin
    are saved and reused; the timings (None for a reused seed) only go to ``timings.json``."""

    key: SeedKey
    estimate: Estimate
    aivat: Estimate | None = None  # None for a seed saved before the corrections
    seconds: float | None = None
    hands_per_second: float | None = None


@contextlib.contextmanager
def _torch_for_play() -> Iterator[None]:
    """Inference mode on one torch thread, restored afterwards.

    One thread whatever ``jobs`` is: the parallelism is the processes, and a network's sums
    could otherwise be split differently with another thread count, changing a near-tie
    argmax and so the result. Only agents that loaded torch need any of it; importing torch
    for built-ins would cost seconds.
    """
    torch = sys.modules.get("torch")
    if torch is None:
        yield
        return
    with pinned_threads(1), torch.inference_mode():
        yield


def _play_seed(
    key: SeedKey, shipped_a: ShippedAgent, shipped_b: ShippedAgent, aivat: bool = True
) -> UnitOutput[tuple[float, float]]:
    """Play one seed (a unit: in this process or a worker) from the agents' bytes; its
    estimate (and with ``aivat`` its chance-corrected twin) is saved, its seconds and
    hands/s go to ``timings.json`` only."""
    with tempfile.TemporaryDirectory(prefix="pokerirl-seed-") as private:
        agent_a = land_agent(shipped_a, Path(private, "a"))
        agent_b = land_agent(shipped_b, Path(private, "b"))
    found = (agent_fingerprint(agent_a), agent_fingerprint(agent_b))
    if found != (key.fingerprint_a, key.fingerprint_b):
        raise TournamentError(f"seed {key.seed}: an agent changed on disk during the run")
    play = functools.partial(play_corrected_match if aivat else play_match, agent_a, agent_b,
                             hands=key.hands, seed=key.seed, duplicate=key.duplicate,
                             batch_size=key.batch_size, report_progress=True)  # fmt: skip
    with _torch_for_play():
        played = play()
    if isinstance(played, CorrectedMatch):  # play_match's numbers, byte for byte, and AIVAT's
        result = played.match
        outcome = {"estimate": asdict(played.raw), "aivat": asdict(played.corrected)}
    else:
        result = played
        outcome = {"estimate": asdict(estimate(1000.0 * result.units_bb))}
    return UnitOutput(result=outcome, extra=(result.seconds, result.hands_per_second))


# --- saved seeds ---------------------------------------------------------------------------


def _seed_path(out: Path, folder: str, seed: int) -> Path:
    return out / "seeds" / folder / f"seed-{seed}.json"


def _seed_unit(
    out: Path,
    folder: str,
    key: SeedKey,
    shipped_a: ShippedAgent,
    shipped_b: ShippedAgent,
    aivat: bool,
) -> Unit[tuple[float, float]]:
    """Seed ``key.seed`` of a matchup: a record unit whose result is its estimate. Its
    identity is what the record of the writers before the store held (``kind`` and the key's
    fields), so their seed files are reused."""
    settings = asdict(key)
    agents = {name: settings.pop(name) for name in ("fingerprint_a", "fingerprint_b")}
    return Unit(
        key=f"{folder} seed {key.seed}",
        target=_seed_path(out, folder, key.seed),
        layout=Layout.RECORD,
        config={"kind": SEED_KIND, **settings},
        inputs=agents,
        fn=_play_seed,
        args=(key, shipped_a, shipped_b, aivat),
        accepts=_has_estimate,
    )


def _estimate(result: Json, name: str = "estimate") -> Estimate | None:
    """The estimate of a saved seed's result (older files also hold timings: ignored), or
    None when it has none; ``name="aivat"``: its chance-corrected twin (absent in seeds saved
    before the corrections)."""
    saved: Any = result.get(name) if isinstance(result, dict) else None
    try:
        return Estimate(**{**saved, "ci95": tuple(saved["ci95"])})
    except (KeyError, TypeError, ValueError):
        return None


def _has_estimate(result: Json) -> bool:
    """Whether a saved seed can be reused: one without an estimate (a record no finished
    write leaves) is recomputed."""
    return _estimate(result) is not None


def _folder_names(labels: Sequence[tuple[str, str]]) -> list[str]:
    """``<A>-vs-<B>`` per matchup, by its agents' labels, file-safe, numbered when two
    labels collide."""
    names: list[str] = []
    for a, b in labels:
        base = re.sub(r"[^A-Za-z0-9._-]+", "_", f"{a}-vs-{b}")
        name, k = base, 2
        while name in names:
            name, k = f"{base}-{k}", k + 1
        names.append(name)
    return names


def _held_matchups(out: Path) -> tuple[str, list[str]]:
    """What ``out`` holds already: ``("report", names)`` from its report.json, else
    ``("saved seeds", names)`` from its seed folders (a run stopped before its report);
    names as :func:`_folder_names` gives them. Nothing readable: ``("", [])``."""
    try:
        data = read_json(out / REPORT_FILE)
        labels = [(str(m["agent_a"]), str(m["agent_b"])) for m in data["matchups"]]
    except (OSError, ValueError, KeyError, TypeError):  # none, or damaged: the run rewrites it
        labels = []
    if labels:
        return "report", _folder_names(labels)
    with contextlib.suppress(OSError):
        return "saved seeds", sorted(p.name for p in (out / "seeds").iterdir() if p.is_dir())
    return "", []


def _check_same_matchups(out: Path, names: Sequence[str]) -> None:
    """Refuse matchups other than those of the tournament in ``out``: its report files would
    be replaced by this run's (matchups compare by label, as the seed folders do, so a moved
    agent folder is the same matchup)."""
    what, held = _held_matchups(out)
    if held and set(held) != set(names):
        raise TournamentError(
            f"{out}: holds the {what} of {', '.join(held)}, not {', '.join(names)}",
            remedy=Remedy.REPLACE,
        )


# --- the run -------------------------------------------------------------------------------


def _fingerprints(spec: str, seeds: Sequence[int]) -> dict[int, tuple[str, ShippedAgent]]:
    """Each seed's agent fingerprint and bytes; one load for agents that are the same on
    every seed. Loading here checks every agent before any unit starts."""
    cache: dict[str, tuple[str, ShippedAgent]] = {}
    prints = {}
    for seed in seeds:
        resolved = agent_spec_for_seed(spec, seed)
        if resolved not in cache:
            try:
                found = agent_fingerprint(resolve_agent(resolved))
                cache[resolved] = (found, ship_agent(resolved))  # a change after: caught
            except (ValueError, OSError) as error:  # resolve_agent's messages name the spec
                raise TournamentError(str(error)) from None
            except Exception as error:  # e.g. a corrupt checkpoint: still one line, no traceback
                first = (str(error).strip().splitlines() or [""])[0]
                raise TournamentError(
                    f"{resolved}: cannot load the agent ({type(error).__name__}: {first})"
                ) from None
        prints[seed] = cache[resolved]
    return prints


def _validate(
    matchups: Sequence[tuple[str, str]],
    hands: int,
    seeds: Sequence[int],
    duplicate: bool,
    alpha: float,
    jobs: int,
    batch_size: int,
) -> None:
    if not matchups:
        raise TournamentError("no matchups: give at least one (agent, base) pair")
    if len(set(matchups)) < len(matchups):
        raise TournamentError("the same matchup is listed twice")
    if not seeds:
        raise TournamentError("no seeds: the seed range is empty")
    if min(seeds) < 0:
        raise TournamentError(f"seeds must be non-negative, got {min(seeds)}")
    least = 4 if duplicate else 2  # two units for a standard error
    if hands < least:
        mode = "with duplicate deals (two pairs)" if duplicate else "(two hands)"
        raise TournamentError(f"hands must be at least {least} {mode}, got {hands}")
    try:
        check_match_size(hands, duplicate=duplicate, batch_size=batch_size)
    except ValueError as error:
        raise TournamentError(str(error)) from None
    if not 0 < alpha < 1:
        raise TournamentError(f"alpha must be between 0 and 1, got {alpha}")
    if jobs < 1:
        raise TournamentError(f"jobs must be at least 1, got {jobs}")


Cell = tuple[int, int]  # (matchup index, seed)


def run_tournament(
    matchups: Sequence[tuple[Side, Side]],
    *,
    hands: int,
    seeds: Sequence[int],
    out: Path | str,
    duplicate: bool = True,
    alpha: float = 0.05,
    jobs: int = 1,
    batch_size: int = DEFAULT_BATCH_SIZE,
    overwrite: bool = False,
    progress: bool = False,
    backend: Backend | None = None,
    aivat: bool = True,
) -> TournamentReport:
    """Play every (A, B) matchup on every seed, write the report files to ``out``, return it.

    Args:
        matchups: (A, B) sides; results are A's; one comparison each. A side is an agent spec
            (a built-in name, an agent folder, or an agent set: a folder of ``seed-<k>``
            agent folders, whose seed-k agent plays seed k) or a list of agent specs, several
            agents trained with different seeds: every agent of one side then plays every
            agent of the other (one matchup per pair) on the same deals, and the comparison
            is tested across them (:func:`~pokerirl.tournaments.report.compare`).
        hands: hands per seed (even with duplicate deals).
        seeds: the seeds; seed k plays deals of seed k between each set's seed-k agents.
        out: the report folder; saved seeds found there are reused when they match.
        duplicate: play each deal from both seats and pair the two results.
        alpha: family-wise error rate for Bonferroni and Holm.
        jobs: local worker processes (results do not depend on it).
        batch_size: hands in lock-step; part of the result (agents' random draws depend on it).
        overwrite: recompute saved seeds that do not match instead of refusing, and replace
            the report of other matchups in ``out`` (else refused before anything is written).
        progress: a tqdm bar over seeds on stderr (done, reused, failed, ETA).
        backend: where the seeds run (:mod:`pokerirl.execution`); default ``jobs`` local
            processes. Results do not depend on it.
        aivat: also the chance-corrected estimate of each seed
            (:mod:`pokerirl.tournaments.aivat`); it costs a few microseconds a hand. Not part
            of a seed's identity: a seed saved without it is reused as it is.

    Raises:
        TournamentError: bad input, a missing ``seed-<k>`` folder, an agent that does not load,
            a saved seed from another configuration, or ``out`` holding other matchups.

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as out:
    ...     report = run_tournament([("raise", "call")], hands=1000, seeds=[0, 1], out=out)
    >>> [s.mbb_per_hand for s in report.matchups[0].seeds]  # duplicate: exactly even here
    [0.0, 0.0]
    """
    seeds = sorted(set(seeds))
    if not matchups:
        raise TournamentError("no matchups: give at least one (agent, base) pair")
    expanded = expand_sides(matchups)
    contests, matchups = expanded.groups, expanded.pairs
    _validate(matchups, hands, seeds, duplicate, alpha, jobs, batch_size)
    check_specs(sorted({spec for pair in matchups for spec in pair}), seeds)
    out = Path(out)
    folders = _folder_names(expanded.labels)
    if not overwrite:
        _check_same_matchups(out, folders)
    prints = {spec: _fingerprints(spec, seeds) for spec in {s for pair in matchups for s in pair}}

    backend = backend or Backend(jobs=jobs)
    cells = [(m, seed) for m in range(len(matchups)) for seed in seeds]
    keys = [SeedKey(seed=seed, fingerprint_a=prints[matchups[m][0]][seed][0],
                    fingerprint_b=prints[matchups[m][1]][seed][0], hands=hands,
                    duplicate=duplicate, batch_size=batch_size)
            for m, seed in cells]  # fmt: skip
    units = [_seed_unit(out, folders[m], key, prints[matchups[m][0]][seed][1],
                        prints[matchups[m][1]][seed][1], aivat)
             for (m, seed), key in zip(cells, keys, strict=True)]  # fmt: skip

    started = time.perf_counter()
    try:  # each seed is saved as it finishes: resumable from there
        found = run_units(
            units, backend, overwrite=overwrite, progress=progress, desc="tournament seeds"
        )
    except UnitConflict as error:
        raise TournamentError(str(error), remedy=error.remedy) from None
    wall = time.perf_counter() - started
    done, played = _seed_results(cells, keys, found.done)
    report = _build_report(
        matchups,
        expanded.labels,
        contests,
        seeds,
        done,
        hands=hands,
        duplicate=duplicate,
        alpha=alpha,
        batch_size=batch_size,
        timing=_timing(
            wall, done, played, folders, hands=hands, cells=len(cells), jobs=jobs, backend=backend
        ),
    )
    write_report(report, out)
    return report


def _seed_results(
    cells: Sequence[Cell], keys: Sequence[SeedKey], found: Sequence[Any]
) -> tuple[dict[Cell, SeedResult], list[Cell]]:
    """Each cell's result from its unit (played now or reused), and the cells played now."""
    done: dict[Cell, SeedResult] = {}
    played: list[Cell] = []
    for cell, key, item in zip(cells, keys, found, strict=True):
        saved = _estimate(item.record.result)
        if saved is None:  # reused only with one (accepts=), and _play_seed writes one
            raise TournamentError(f"{item.unit.target}: a saved seed without an estimate")
        seconds, hands_per_second = item.extra or (None, None)
        done[cell] = SeedResult(
            key=key,
            estimate=saved,
            aivat=_estimate(item.record.result, "aivat"),
            seconds=seconds,
            hands_per_second=hands_per_second,
        )
        if item.extra is not None:
            played.append(cell)
    return done, played


def _timing(
    wall: float, done: Mapping[Cell, SeedResult], played: Sequence[Cell],
    folders: Sequence[str], *, hands: int, cells: int, jobs: int, backend: Backend,
) -> dict[str, Any]:  # fmt: skip
    """The report's ``timing``: this call's wall time and the seeds it played."""
    return {
        "wall_seconds": wall,
        "hands_played": len(played) * hands,
        "hands_per_second": len(played) * hands / wall if wall > 0 else 0.0,
        "seeds_reused": cells - len(played),
        "jobs": jobs,
        "backend": backend.describe(),
        "seeds_played": [
            {
                "matchup": folders[m],
                "seed": seed,
                "seconds": done[m, seed].seconds,
                "hands_per_second": done[m, seed].hands_per_second,
            }
            for m, seed in played
        ],
    }


def _pooled_aivat(per_seed: list[Estimate | None]) -> Estimate | None:
    """The corrected twin of the pooled line: over the seeds' corrected means as the raw one
    is over theirs (one seed: that seed's); None unless every seed has one."""
    found = [e for e in per_seed if e is not None]
    if len(found) < len(per_seed):
        return None
    if len(found) == 1:
        return found[0]
    return estimate(np.array([e.mbb_per_hand for e in found]))


def _build_report(
    matchups: Sequence[tuple[str, str]],
    labels: Sequence[tuple[str, str]],
    contests: list[Group],
    seeds: Sequence[int],
    done: dict[Cell, SeedResult],
    *,
    hands: int,
    duplicate: bool,
    alpha: float,
    batch_size: int,
    timing: Mapping[str, Any],
) -> TournamentReport:
    cells = [(m, seed) for m in range(len(matchups)) for seed in seeds]
    tested = corrected_lines([done[c].estimate for c in cells], alpha)
    per_seed = dict(zip(cells, tested, strict=True))
    if len(seeds) > 1:
        pooled_estimates = [
            estimate(np.array([done[m, seed].estimate.mbb_per_hand for seed in seeds]))
            for m in range(len(matchups))
        ]
    else:
        pooled_estimates = [done[m, seeds[0]].estimate for m in range(len(matchups))]
    pooled = corrected_lines(pooled_estimates, alpha)

    reports = []
    for m, (a, b) in enumerate(matchups):
        lines = tuple(
            SeedLine(
                **asdict(per_seed[m, seed]),
                seed=seed,
                hands=hands,
                fingerprint_a=done[m, seed].key.fingerprint_a,
                fingerprint_b=done[m, seed].key.fingerprint_b,
                aivat=done[m, seed].aivat,
            )
            for seed in seeds
        )
        reports.append(
            MatchupReport(
                agent_a=labels[m][0],
                agent_b=labels[m][1],
                spec_a=a,
                spec_b=b,
                pooled=pooled[m],
                pooled_over="seeds" if len(seeds) > 1 else "units of the only seed",
                seeds=lines,
                aivat=_pooled_aivat([done[m, seed].aivat for seed in seeds]),
            )
        )
    comparisons = compare(tuple(reports), contests, alpha)
    return TournamentReport(
        config=TournamentSettings(
            hands=hands, seeds=tuple(seeds), duplicate=duplicate, batch_size=batch_size,
            alpha=alpha,
        ),
        family=FamilySizes(
            per_seed_tests=len(cells),
            per_seed_threshold=alpha / len(cells),
            pooled_tests=len(matchups),
            pooled_threshold=alpha / len(matchups),
            comparison_tests=len(comparisons),
            comparison_threshold=alpha / len(comparisons),
        ),
        matchups=tuple(reports),
        comparisons=comparisons,
        versions=package_versions(),
        timing=timing,
    )
