"""``pokerirl train``: AIRL / H-AIRL / GAIL on a poker decision table, one run or several.

The run folder's format and the trainer are poker-free (:mod:`pokerirl.irl.run`,
:mod:`pokerirl.irl.adversarial`); this module adds what is poker's: reading the decision table
(:func:`pokerirl.poker.read_table`), the reward card of a table with cards
(``reward_card.json`` and ``reward_card.png``, :mod:`pokerirl.poker.reward_card`), and the
fan-out of several runs on an execution backend. A folder of several runs holds ``run-<k>``
folders, each with seed ``seed + k``, and ``summary.json`` (mean and std over runs) with a
banded plot.

A finished folder is never modified in place: a run is written into a hidden temporary folder
beside it and renamed into place at the end (replacing an old run only with ``overwrite``).
Errors are :class:`~pokerirl.irl.RunError` s naming the folder, never a command-line flag; the
ones a command could get past carry a :class:`~pokerirl.errors.Remedy`.

>>> import tempfile, numpy as np, pyarrow.parquet as pq
>>> from pokerirl.datasets.toy import toy_expert_table
>>> from pokerirl.irl import load_config, load_reward
>>> tmp = Path(tempfile.mkdtemp())
>>> pq.write_table(toy_expert_table(num_hands=200), tmp / "table.parquet")
>>> config = load_config("hairl", overrides={"epochs": 2, "batch_size": 64})
>>> summary = train_table(tmp / "table.parquet", tmp / "run", config=config, progress=False)
>>> sorted(summary.baselines)
['bc', 'legal_majority', 'majority']
>>> reward = load_reward(tmp / "run")
>>> reward(np.zeros((3, 72), np.uint8), np.array([0, 1, 3])).dtype
dtype('float32')
"""

from __future__ import annotations

import functools
import json
import os
import tempfile
import warnings
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import torch

from pokerirl.atomic import write_text
from pokerirl.datasets.decisions import Table, data_game, read_data
from pokerirl.errors import ConfigError, Remedy
from pokerirl.execution import Backend, pinned_threads
from pokerirl.game.encodings import RLCARD, Encoding
from pokerirl.game.spec import GameName
from pokerirl.irl.adversarial import resolve_device
from pokerirl.irl.config import AIRLConfig, Algo
from pokerirl.irl.metrics import Metric
from pokerirl.irl.plots import plot_bands
from pokerirl.irl.run import (
    CONFIG_FILE,
    SUMMARY_FILE,
    TIMINGS_FILE,
    RunError,
    RunHooks,
    RunSummary,
    read_run_result,
    summarize,
    train_runs_into,
)
from pokerirl.irl.run import TRAINED_SHARE as TRAINED_SHARE  # importable here as before
from pokerirl.jsonio import read_json
from pokerirl.poker.data import as_transitions, read_table
from pokerirl.poker.reward_card import CARD_FILE
from pokerirl.store import Unit, UnitConflict, UnitOutput, digest, run_units, staged_folder

CARD_COLUMNS = ("hole_cards", "board")  # what the card reads beyond the trainer's columns


# --------------------------------------------------------------------------- one run


def train_table(
    table: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    algo: str = Algo.HAIRL,
    config: AIRLConfig | None = None,
    device: str = "cpu",
    progress: bool = True,
    overwrite: bool = False,
    encoding: Encoding | None = None,
) -> RunSummary:
    """Train on the decisions at ``table`` (:func:`~pokerirl.datasets.decisions.read_data`:
    a hold'em table, its states in ``encoding``, or Leduc demonstrations) and write the run
    folder ``out_dir``.

    Validation is a seeded share of the *hands* (``config.val_fraction``), never of rows. A
    reward whose argmax agrees with the expert less than the run's own behaviour-cloning
    baseline is flagged (:class:`RewardBelowBC`, a warning).
    """
    config = config or AIRLConfig.for_algo(algo)
    resolve_device(device)  # fail before reading a large table
    out = Path(out_dir)
    check_destination(out, overwrite=overwrite)
    data = read_data(table, encoding=encoding)
    with staged_folder(out) as folder:  # the store's: a kill leaves out as it was
        summary = train_table_into(
            data, folder, algo=algo, config=config, device=device, progress=progress, table=table
        )
    warn_below_bc(out, summary.metrics[-1], summary.baselines)
    return replace(summary, out_dir=out)


class RewardBelowBC(UserWarning):
    """A reward whose argmax agrees with the expert less than behaviour cloning does on the
    same split: it has learned less of the expert than a plain classifier."""


def below_bc(metrics: Mapping[str, Any], baselines: Mapping[str, float]) -> float | None:
    """How far the reward's argmax alignment (``val_reward_alignment``) falls below the
    run's BC baseline, or None when it does not (or either is missing)."""
    reward, bc = Metric.VAL_REWARD_ALIGNMENT.of(metrics, None), baselines.get("bc")
    if reward is None or bc is None or reward >= bc:
        return None
    return float(bc - reward)


def warn_below_bc(run: Path, metrics: Mapping[str, Any], baselines: Mapping[str, float]) -> None:
    """Warn, in one line naming the run, when its reward falls below its BC baseline."""
    gap = below_bc(metrics, baselines)
    if gap is not None:
        warnings.warn(
            RewardBelowBC(
                f"{run}: the reward's argmax agrees with the expert on "
                f"{Metric.VAL_REWARD_ALIGNMENT.of(metrics):.1%} of validation states, below its "
                f"own behaviour cloning's {baselines['bc']:.1%}"
            ),
            stacklevel=2,
        )


def train_table_into(
    data: Table,
    folder: Path,
    *,
    algo: str,
    config: AIRLConfig,
    device: str = "cpu",
    progress: bool = False,
    table: str | os.PathLike[str] | None = None,
    table_file: str | os.PathLike[str] | None = None,
) -> RunSummary:
    """One run of :func:`pokerirl.irl.run.train_runs_into`, its reward card (hold'em) as the
    finish.

    ``data`` is the table, its spec recorded in ``config.json``'s ``data`` (the encoding,
    and the game when not hold'em); ``table`` is the table's path for the record;
    ``table_file`` the file to read the reward card's states from (default ``table``)."""
    card = None
    if data.spec.game is GameName.HOLDEM:
        card = functools.partial(write_reward_card, table=table_file or table,
                                 label=None if table is None else str(table))  # fmt: skip
    trained = train_runs_into(
        as_transitions(data), [folder], algo=algo, config=config, hooks=RunHooks(finish=card),
        device=device, progress=progress, data_path=table, data_notes=data.spec.record(),
    )  # fmt: skip
    return RunSummary.of(trained.results, out_dir=folder, several=False)


def write_reward_card(
    folder: Path, table: str | os.PathLike[str] | None, *, label: str | None = None
) -> None:
    """The run's reward card over its validation hands, when ``table`` has the cards
    (``label``: the table's name in the card, when ``table`` is a scratch copy)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    if table is None:
        return
    try:
        names = pq.read_schema(table).names
    except (OSError, pa.ArrowException):
        return
    if all(name in names for name in CARD_COLUMNS):
        from pokerirl.poker.reward_card import run_card, write_card

        write_card(run_card(folder, table, label=label), folder)


# --------------------------------------------------------------------------- several runs


def train_unit(
    data: Table,
    table: bytes,
    table_path: str,
    algo: str,
    settings: Mapping[str, Any],
    device: str,
) -> UnitOutput[None]:
    """One run of a fan-out: a top-level, picklable function of plain arguments.

    ``data`` arrives read and encoded once by the driver; the table's bytes come along for
    the reward card, and the run folder leaves as bytes (the driver writes them;
    ``timings.json`` unfingerprinted), so a worker needs no shared filesystem. Pins torch to
    one thread (restored after) and seeds from ``settings["seed"]``.
    """
    with pinned_threads(1), tempfile.TemporaryDirectory(prefix="pokerirl-run-") as scratch:
        path = Path(scratch) / "table.parquet"
        path.write_bytes(table)
        torch.manual_seed(settings["seed"])
        run = Path(scratch) / "run"
        train_table_into(
            data,
            run,
            algo=algo,
            config=AIRLConfig(**settings),
            device=device,
            table=table_path,
            table_file=path,
        )
        files = {f.name: f.read_bytes() for f in sorted(run.iterdir()) if f.is_file()}
    timings = {TIMINGS_FILE: files.pop(TIMINGS_FILE)}
    return UnitOutput(files=files, unhashed=timings)


def train_runs(
    table: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    runs: int,
    algo: str = Algo.HAIRL,
    config: AIRLConfig | None = None,
    device: str = "cpu",
    progress: bool = True,
    overwrite: bool = False,
    backend: Backend | None = None,
    encoding: Encoding | None = None,
    single_folder: bool = True,
) -> RunSummary:
    """``runs`` runs of ``config`` with seeds ``seed + k`` into ``out_dir/run-<k>``, then
    ``summary.json`` and ``alignment_bands.png``. One run keeps the single-folder layout
    unless ``single_folder`` is False (then it is ``run-0``, a resumable unit like the others).
    The table is read once (:func:`~pokerirl.datasets.decisions.read_data`: a hold'em
    table's states in ``encoding``, :mod:`pokerirl.game.encodings`, or Leduc demonstrations)
    and its arrays go to every run.

    Each run is a unit of :func:`pokerirl.store.run_units` on ``backend`` (default: in this
    process): written atomically with a record of its settings and table, reused by a
    rerun with the same ones, recomputed when corrupt, refused when made with other
    settings unless ``overwrite``. Results do not depend on the backend.
    """
    if runs < 1:
        raise ConfigError(f"runs must be at least 1, got {runs}")
    config = config or AIRLConfig.for_algo(algo)
    if runs == 1 and single_folder:
        return train_table(
            table,
            out_dir,
            algo=algo,
            config=config,
            device=device,
            progress=progress,
            overwrite=overwrite,
            encoding=encoding,
        )
    resolve_device(device)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise RunError(f"{out} exists and is not a folder", remedy=Remedy.ELSEWHERE)
    if (out / CONFIG_FILE).is_file():
        raise RunError(
            f"{out} holds a single run, not a folder of {runs} runs", remedy=Remedy.ELSEWHERE
        )
    data = read_data(table, encoding=encoding)  # a bad table fails once, before any unit starts
    table_bytes = Path(table).read_bytes()
    folders = [out / f"run-{k}" for k in range(runs)]
    units = []
    for k, folder in enumerate(folders):
        settings = {**config.to_dict(), "seed": config.seed + k}
        unit_config: dict[str, object] = {"algo": algo, "device": device, "settings": settings}
        if data.spec.encoding != RLCARD.spec:  # runs of the 72-d encoding keep their prints
            unit_config.update(data.spec.record())
        units.append(
            Unit(
                key=folder.name,
                target=folder,
                config=unit_config,
                inputs={"table": digest(table_bytes)},
                fn=train_unit,
                args=(data, table_bytes, str(Path(table).resolve()), algo, settings, device),
            )
        )
    try:
        run_units(units, backend, overwrite=overwrite, progress=progress, desc=f"{algo} runs")
    except UnitConflict as error:
        raise RunError(str(error), remedy=error.remedy) from None
    for folder in folders:  # runs of an older pokerirl, reused: add their card
        if data.spec.game is GameName.HOLDEM and not (folder / CARD_FILE).is_file():
            write_reward_card(folder, table)
    results = [read_run_result(folder) for folder in folders]
    for folder, result in zip(folders, results, strict=True):
        warn_below_bc(folder, result.metrics[-1], result.baselines)
    summary = summarize(results).to_json()
    write_text(out / SUMMARY_FILE, json.dumps(summary, indent=2) + "\n")
    plot_bands(summary, out)
    return RunSummary.of(results, out_dir=out)


# --------------------------------------------------------------------------- EM


EM_FILE = "em.json"


def train_em(
    table: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    rounds: int,
    algo: str = Algo.HAIRL,
    config: AIRLConfig | None = None,
    device: str = "cpu",
    progress: bool = True,
    overwrite: bool = False,
    encoding: Encoding | None = None,
) -> dict[str, Any]:
    """EM over the hidden cards of an imputed table (``ingest --folds impute``): train on it
    (``OUT/round-0``), then ``rounds`` times re-impute its hidden players with the last run's
    IRL policy as π_B (``OUT/table-<r>.parquet``, K and the draws' seed as the table's
    summary says, else the defaults) and train again (``OUT/round-<r>``).

    ``OUT/em.json`` reports per round the agreement of the run's policy argmax (and of its
    reward's) with the actions of the imputed rows and of the observed rows of the table it
    was trained on (weighted), its change from the round before, and the posterior's mean
    entropy; returned too.
    """
    import pyarrow.parquet as pq

    from pokerirl.datasets.ingest import IngestSummary, summary_path
    from pokerirl.poker.folds import ImputeConfig
    from pokerirl.poker.impute import Behaviour, impute

    if rounds < 0:
        raise ConfigError(f"EM rounds must be >= 0, got {rounds}")
    config = config or AIRLConfig.for_algo(algo)
    out = Path(out_dir)
    check_destination(out, overwrite=overwrite)
    if data_game(table) is not GameName.HOLDEM:
        raise ConfigError(f"{table}: EM re-imputes the hidden cards of a hold'em table, not "
                          "Leduc demonstrations")  # fmt: skip
    names = pq.read_schema(table).names
    if "imputed" not in names or "imputation" not in names:
        raise ConfigError(
            f"{table}: EM re-imputes hidden cards: it needs a table of ingest's fold imputation "
            "(with the imputed and imputation columns)"
        )
    impute_config = ImputeConfig(seed=config.seed)
    summary_file = summary_path(table)
    if summary_file.is_file():
        folds = IngestSummary.from_json(read_json(summary_file)).folds
        if folds is not None:
            impute_config = ImputeConfig(imputations=folds.imputations, seed=folds.seed)
    out.mkdir(parents=True, exist_ok=True)
    current = Path(table)
    history: list[dict[str, Any]] = []
    for r in range(rounds + 1):
        run = out / f"round-{r}"
        if r > 0:
            behaviour = Behaviour.from_run(out / f"round-{r - 1}")
            config_r = replace(impute_config, seed=impute_config.seed + r)
            imputation = impute(pq.read_table(current), config_r, behaviour=behaviour,
                                progress=progress, source=str(current))  # fmt: skip
            current = out / f"table-{r}.parquet"
            pq.write_table(imputation.table, current, compression="zstd")
        train_table(current, run, algo=algo, config=config, device=device, progress=progress,
                    overwrite=overwrite, encoding=encoding)  # fmt: skip
        found = {"round": r, "table": str(current), **_agreement(run, current, encoding)}
        if r > 0:
            found["mean_entropy_bits"] = imputation.summary.entropy_bits["mean"]
            for key in ("policy_agree_imputed", "reward_agree_imputed"):
                found[f"{key}_change"] = found[key] - history[-1][key]
        history.append(found)
    report = {"rounds": history}
    write_text(out / EM_FILE, json.dumps(report, indent=2) + "\n")
    return report


def _agreement(run: Path, table: Path, encoding: Encoding | None) -> dict[str, float]:
    """How often the run's policy argmax and reward argmax (legal actions) take the action of
    the table's rows, weighted, over its imputed rows and its observed rows apart."""
    from pokerirl.irl.run import load_policy, load_reward

    data = read_table(table, encoding=encoding)
    assert data.weights is not None and data.imputed is not None and data.legal_mask is not None
    policy, reward = load_policy(run), load_reward(run)
    with torch.no_grad():
        by_policy = policy(data.obs, data.legal_mask).argmax(-1)
    with torch.no_grad():
        values = torch.stack([reward(data.obs, torch.full((len(data),), a))
                              for a in range(data.action_dim)], dim=1)  # fmt: skip
    by_reward = values.masked_fill(~data.legal_mask, -torch.inf).argmax(-1)
    found = {}
    for part, rows in (("imputed", data.imputed), ("observed", ~data.imputed)):
        w = data.weights[rows].double()
        for name, best in (("policy", by_policy), ("reward", by_reward)):
            hit = (best[rows] == data.actions[rows]).double()
            found[f"{name}_agree_{part}"] = float((hit * w).sum() / w.sum()) if len(w) else 0.0
    return found


# --------------------------------------------------------------------------- folders


def check_destination(out: Path, *, overwrite: bool) -> None:
    """Refuse an ``out`` that is a file, or a non-empty folder unless ``overwrite``."""
    if out.exists() and not out.is_dir():
        raise RunError(f"{out} exists and is not a folder", remedy=Remedy.ELSEWHERE)
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise RunError(f"{out} already holds files (a finished run?)", remedy=Remedy.REPLACE)
