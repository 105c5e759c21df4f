"""The units of the Gymnasium study and the sweep, and the rules that make them resumable.

Three kinds of unit, each a top-level function of plain arguments that returns bytes (so it
runs on any :mod:`pokerirl.execution` backend, with no shared filesystem):

- :func:`collect_unit`: the shipped expert's transitions (``gym collect``) as Parquet bytes;
- :func:`irl_unit`: one algorithm's IRL runs in lock-step (``gym irl``), as a folder's files;
- :func:`rl_unit`: one RL run (``gym rl``) on the env reward or on one IRL run's reward;
- :func:`rl_group_unit`: with the lock-step RL backend, one group of RL runs (one task, one
  reward kind, one ``rl/<reward>`` folder: its unfinished runs) trained together, whose runs
  are saved each into its own run folder with its own record, as :func:`rl_unit`'s are.

The driver writes what comes back, with a unit record (``unit.json``, or ``expert.unit.json``
beside the data) holding a fingerprint of everything the unit's result depends on: the task,
the settings, the seeds and the sha256 of its inputs. A rerun reuses a unit whose record
matches, recomputes one that is missing, half-written or corrupt, and refuses, in one line,
one made with other settings or inputs unless ``overwrite``.
"""

from __future__ import annotations

import hashlib
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from pokerirl.atomic import write_bytes
from pokerirl.execution import (
    Backend,
    UnitConflict,
    bytes_fingerprint,
    load_unit,
    load_unit_folder,
    make_record,
    map_units,
    read_files,
    save_record,
    save_unit_folder,
    write_files,
)
from pokerirl.gym.presets import IRLSettings, RLSettings
from pokerirl.irl.run import CONFIG_FILE, REWARD_FILE, TIMINGS_FILE

DATA_FILE = "expert.parquet"
DATA_RECORD = "expert.unit.json"
REWARD_INPUTS = (CONFIG_FILE, REWARD_FILE)  # what load_reward reads of a run folder


class JobError(ValueError):
    """A unit made with other settings, or a folder that does not fit; the message is one line."""


def _folder_files(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` by its relative path (``run-0/reward.pt``)."""
    return {
        str(path.relative_to(root)): path.read_bytes()
        for path in sorted(root.rglob("*"))
        if path.is_file()
    }


def _split_timings(files: dict[str, bytes]) -> tuple[dict[str, bytes], dict[str, bytes]]:
    # Wall-clock seconds: written, never fingerprinted.
    timed = {name: data for name, data in files.items() if Path(name).name == TIMINGS_FILE}
    return {name: data for name, data in files.items() if name not in timed}, timed


def expert_fingerprint(env_id: str) -> dict[str, Any]:
    """The shipped expert of ``env_id``: its manifest entry and the sha256 of its weights."""
    from pokerirl.gym.experts import MODEL_FILE, resolve_expert_dir, shipped_manifest

    folder = resolve_expert_dir("shipped", env_id)
    entry = next((e for e in shipped_manifest() if e["env"] == env_id), None)
    digest = hashlib.sha256((folder / MODEL_FILE).read_bytes()).hexdigest()
    return {"manifest": entry, "model_sha256": digest}


# --------------------------------------------------------------------------- the units


def collect_unit(env_id: str, transitions: int, seed: int) -> bytes:
    """The shipped expert's ``transitions`` transitions (episode k from
    ``reset(seed=seed + k)``), as the bytes of the Parquet table ``gym collect`` writes."""
    from pokerirl.gym.collect import collect
    from pokerirl.gym.experts import load_expert, resolve_expert_dir

    with tempfile.TemporaryDirectory(prefix="pokerirl-collect-") as scratch:
        path = Path(scratch) / DATA_FILE
        expert = load_expert(resolve_expert_dir("shipped", env_id))
        # deterministic=None: the task's default (continuous: sampled), recorded in the table
        collect(expert, path, transitions=transitions, seed=seed, deterministic=None)
        return path.read_bytes()


def irl_unit(
    env_id: str,
    data: bytes,
    data_label: str,
    algo: str,
    runs: int,
    settings: IRLSettings,
    seed: int,
) -> dict[str, bytes]:
    """``runs`` IRL runs of ``algo`` in lock-step on the expert data (Parquet bytes): the
    files of a ``gym irl`` folder (``run-<k>/...``, ``summary.json``, figures)."""
    from pokerirl.gym.irl import train_gym_irl

    with tempfile.TemporaryDirectory(prefix="pokerirl-gym-irl-") as scratch:
        path = Path(scratch) / DATA_FILE
        path.write_bytes(data)
        out = Path(scratch) / "out"
        train_gym_irl(
            env_id,
            path,
            algo=algo,
            runs=runs,
            settings=settings,
            seed=seed,
            out=out,
            progress=False,
            data_label=data_label,
        )
        return _folder_files(out)


def rl_unit(
    env_id: str,
    reward_files: dict[str, bytes] | None,
    reward_name: str,
    seed: int,
    settings: RLSettings,
    evaluations: int,
    eval_episodes: int,
) -> dict[str, bytes]:
    """One RL run on the env reward (``reward_files`` None) or on the learned reward of the IRL
    run whose ``config.json`` and ``reward.pt`` are given: the files ``gym rl`` writes."""
    from pokerirl.gym.rl import train_rl
    from pokerirl.irl import load_reward

    with tempfile.TemporaryDirectory(prefix="pokerirl-gym-rl-") as scratch:
        reward = None
        if reward_files is not None:
            reward = load_reward(write_files(Path(scratch) / "reward-run", reward_files))
        out = Path(scratch) / "run"
        train_rl(
            env_id,
            reward=reward,
            reward_name=reward_name,
            seed=seed,
            settings=settings,
            evaluations=evaluations,
            eval_episodes=eval_episodes,
            out=out,
        )
        return _folder_files(out)


def rl_group_unit(
    env_id: str,
    reward_files: Sequence[dict[str, bytes] | None],
    reward_names: Sequence[str],
    seeds: Sequence[int],
    settings: RLSettings,
    evaluations: int,
    eval_episodes: int,
) -> dict[str, bytes]:
    """R RL runs in lock-step (``pokerirl.gym.lockstep.group``), run r on ``reward_files[r]``
    with seed ``seeds[r]``: the files of each run folder, as ``<r>/<name>``."""
    from pokerirl.gym.lockstep.group import train_rl_group
    from pokerirl.irl import load_reward

    with tempfile.TemporaryDirectory(prefix="pokerirl-gym-rl-group-") as scratch:
        rewards = [
            None if files is None
            else load_reward(write_files(Path(scratch) / f"reward-run-{r}", files))
            for r, files in enumerate(reward_files)
        ]  # fmt: skip
        outs = [Path(scratch) / "runs" / str(r) for r in range(len(seeds))]
        train_rl_group(
            env_id,
            rewards=rewards,
            reward_names=reward_names,
            seeds=seeds,
            settings=settings,
            evaluations=evaluations,
            eval_episodes=eval_episodes,
            outs=outs,
        )
        return _folder_files(Path(scratch) / "runs")


# --------------------------------------------------------------------------- jobs


@dataclass(frozen=True, kw_only=True)
class DataJob:
    """The expert data of one task, written to ``path`` (its record beside it)."""

    env: str
    transitions: int
    seed: int
    path: Path

    def config(self) -> dict[str, Any]:
        from pokerirl.gym.collect import default_deterministic

        return {
            "unit": "gym-data",
            "env": self.env,
            "expert": expert_fingerprint(self.env),
            "transitions": self.transitions,
            "seed": self.seed,
            # Only where the expert's actions are sampled (continuous tasks, issue 20): the
            # discrete tasks' records, made before the choice existed, stay valid.
            **({} if default_deterministic(self.env) else {"actions": "sampled"}),
        }


@dataclass(frozen=True, kw_only=True)
class IRLJob:
    """``runs`` IRL runs of ``algo`` (seeds ``seed + k``) into the unit folder ``folder``."""

    env: str
    algo: str
    runs: int
    settings: IRLSettings
    seed: int
    data: Path
    folder: Path

    def config(self, data: bytes) -> dict[str, Any]:
        """The unit's fingerprinted configuration; ``data`` is the bytes of ``self.data``."""
        return {
            "unit": "gym-irl",
            "env": self.env,
            "algo": self.algo,
            "runs": self.runs,
            "seed": self.seed,
            "settings": asdict(self.settings),
            "data": bytes_fingerprint(data),
        }

    def run(self, k: int) -> Path:
        return self.folder / f"run-{k}"


@dataclass(frozen=True, kw_only=True)
class RLJob:
    """One RL run (seed ``seed``) on the env reward (``reward_run`` None) or on the reward of
    the IRL run folder ``reward_run``, into the unit folder ``folder``."""

    env: str
    reward: str  # "env", or the IRL algorithm whose reward it learns from
    reward_run: Path | None
    seed: int
    settings: RLSettings
    evaluations: int
    eval_episodes: int
    folder: Path
    backend: str = "sb3"  # or "lockstep": see pokerirl.gym.rl.RL_BACKENDS

    def reward_files(self) -> dict[str, bytes] | None:
        if self.reward_run is None:
            return None
        try:
            return read_files(self.reward_run, REWARD_INPUTS)
        except OSError as error:
            raise JobError(f"{self.reward_run}: cannot read the IRL run ({error})") from None

    def config(self, reward_files: dict[str, bytes] | None) -> dict[str, Any]:
        return {
            "unit": "gym-rl",
            "env": self.env,
            "reward": self.reward,
            "reward_run": None
            if reward_files is None
            else {name: bytes_fingerprint(data) for name, data in sorted(reward_files.items())},
            "seed": self.seed,
            "settings": asdict(self.settings),
            "evaluations": self.evaluations,
            "eval_episodes": self.eval_episodes,
            # Only for lock-step runs: sb3 records (every study made before) stay valid, and
            # the two backends' runs never pass for each other.
            **({} if self.backend == "sb3" else {"backend": self.backend}),
        }

    def group_key(self) -> tuple[Any, ...]:
        """Runs that train as one lock-step group: one task, reward kind, folder of runs and
        settings."""
        return (self.env, self.reward, str(self.folder.parent), repr(self.settings),
                self.evaluations, self.eval_episodes)  # fmt: skip

    def reward_name(self) -> str:
        if self.reward_run is None:
            return "env"
        return f"{self.reward}:{self.reward_run.name}"


Say = Callable[[str], None]


def _run_folder_units(
    fn: Callable[..., dict[str, bytes]],
    *,
    folders: Sequence[Path],
    configs: Sequence[dict[str, Any]],
    unit_args: Callable[[int], tuple[Any, ...]],
    labels: Sequence[str],
    desc: str,
    backend: Backend,
    overwrite: bool,
    progress: bool,
) -> int:
    """Run ``fn(*unit_args(i))`` for each unit folder not finished with ``configs[i]`` and save
    the files it returns there (timings unhashed); returns how many units were reused."""
    todo = []
    for i, (folder, config) in enumerate(zip(folders, configs, strict=True)):
        try:
            if load_unit_folder(folder, config, overwrite=overwrite) is None:
                todo.append(i)
        except UnitConflict as error:
            raise JobError(str(error)) from None

    def save(index: int, files: dict[str, bytes]) -> None:
        i = todo[index]
        hashed, timed = _split_timings(files)
        save_unit_folder(folders[i], hashed, configs[i], unhashed=timed)

    map_units(
        fn,
        [unit_args(i) for i in todo],
        backend=backend,
        progress=progress,
        desc=desc,
        reused=len(folders) - len(todo),
        on_result=save,
        labels=[labels[i] for i in todo],
    )
    return len(folders) - len(todo)


def run_data_jobs(
    jobs: Sequence[DataJob],
    *,
    backend: Backend,
    overwrite: bool = False,
    progress: bool = False,
) -> int:
    """Collect every job's data that is not already there; returns how many were reused."""
    configs = [job.config() for job in jobs]
    todo = []
    for job, config in zip(jobs, configs, strict=True):
        record = job.path.parent / DATA_RECORD
        try:
            if load_unit(record, config, overwrite=overwrite, what=str(job.path)) is None:
                todo.append((job, config))
        except UnitConflict as error:
            raise JobError(str(error)) from None

    def save(index: int, data: bytes) -> None:
        job, config = todo[index]
        job.path.parent.mkdir(parents=True, exist_ok=True)
        write_bytes(job.path, data)
        save_record(job.path.parent / DATA_RECORD, make_record(config, files={DATA_FILE: data}))

    map_units(
        collect_unit,
        [(job.env, job.transitions, job.seed) for job, _ in todo],
        backend=backend,
        progress=progress,
        desc="expert data",
        reused=len(jobs) - len(todo),
        on_result=save,
        labels=[f"{job.env} data" for job, _ in todo],
    )
    return len(jobs) - len(todo)


def run_irl_jobs(
    jobs: Sequence[IRLJob],
    *,
    backend: Backend,
    overwrite: bool = False,
    progress: bool = False,
) -> int:
    """Train every IRL job that is not finished with its settings; returns how many were reused."""
    # Each data file is read once, whether one job or many (both algorithms, all sweep points)
    # train on it: for its fingerprint and for the units that need it.
    data = {path: path.read_bytes() for path in {job.data for job in jobs}}

    def unit_args(i: int) -> tuple[Any, ...]:
        job = jobs[i]
        label = str(job.data.resolve())
        return job.env, data[job.data], label, job.algo, job.runs, job.settings, job.seed

    return _run_folder_units(
        irl_unit,
        folders=[job.folder for job in jobs],
        configs=[job.config(data[job.data]) for job in jobs],
        unit_args=unit_args,
        labels=[f"{job.env} {job.algo}" for job in jobs],
        desc="IRL",
        backend=backend,
        overwrite=overwrite,
        progress=progress,
    )


def run_rl_jobs(
    jobs: Sequence[RLJob],
    *,
    backend: Backend,
    overwrite: bool = False,
    progress: bool = False,
) -> int:
    """Train every RL job that is not finished with its settings and reward; returns how many
    were reused. Lock-step jobs (``job.backend``) train in groups (:meth:`RLJob.group_key`)
    of their unfinished runs, one unit per group."""
    from pokerirl.gym.rl import RL_BACKENDS

    for job in jobs:
        if job.backend not in RL_BACKENDS:
            raise JobError(f"unknown RL backend {job.backend!r}; choose one of "
                           f"{', '.join(RL_BACKENDS)}")  # fmt: skip
    sb3 = [job for job in jobs if job.backend == "sb3"]
    lockstep = [job for job in jobs if job.backend != "sb3"]
    reused = 0
    if sb3:
        reused += _run_sb3_jobs(sb3, backend=backend, overwrite=overwrite, progress=progress)
    if lockstep:
        reused += _run_group_jobs(lockstep, backend=backend, overwrite=overwrite,
                                  progress=progress)  # fmt: skip
    return reused


def _run_sb3_jobs(
    jobs: Sequence[RLJob], *, backend: Backend, overwrite: bool, progress: bool
) -> int:
    inputs = [job.reward_files() for job in jobs]

    def unit_args(i: int) -> tuple[Any, ...]:
        job = jobs[i]
        return (job.env, inputs[i], job.reward_name(), job.seed, job.settings, job.evaluations,
                job.eval_episodes)  # fmt: skip

    return _run_folder_units(
        rl_unit,
        folders=[job.folder for job in jobs],
        configs=[job.config(files) for job, files in zip(jobs, inputs, strict=True)],
        unit_args=unit_args,
        labels=[f"{job.env} {job.reward} seed {job.seed}" for job in jobs],
        desc="RL runs",
        backend=backend,
        overwrite=overwrite,
        progress=progress,
    )


def _run_group_jobs(
    jobs: Sequence[RLJob], *, backend: Backend, overwrite: bool, progress: bool
) -> int:
    """The unfinished runs of each group as one unit; each run saved to its own folder with
    its own record (so resuming, and the folders, are as with sb3)."""
    inputs = [job.reward_files() for job in jobs]
    configs = [job.config(files) for job, files in zip(jobs, inputs, strict=True)]
    groups: dict[tuple[Any, ...], list[int]] = {}
    for i, (job, config) in enumerate(zip(jobs, configs, strict=True)):
        try:
            if load_unit_folder(job.folder, config, overwrite=overwrite) is None:
                groups.setdefault(job.group_key(), []).append(i)
        except UnitConflict as error:
            raise JobError(str(error)) from None
    members = list(groups.values())
    todo = sum(len(m) for m in members)

    def unit_args(group: list[int]) -> tuple[Any, ...]:
        first = jobs[group[0]]
        return (first.env, [inputs[i] for i in group], [jobs[i].reward_name() for i in group],
                [jobs[i].seed for i in group], first.settings, first.evaluations,
                first.eval_episodes)  # fmt: skip

    def save(index: int, files: dict[str, bytes]) -> None:
        for r, i in enumerate(members[index]):
            prefix = f"{r}/"
            run = {name[len(prefix):]: data for name, data in files.items()
                   if name.startswith(prefix)}  # fmt: skip
            hashed, timed = _split_timings(run)
            save_unit_folder(jobs[i].folder, hashed, configs[i], unhashed=timed)

    map_units(
        rl_group_unit,
        [unit_args(group) for group in members],
        backend=backend,
        progress=progress,
        desc="RL groups",
        reused=len(jobs) - todo,
        on_result=save,
        labels=[f"{jobs[g[0]].env} {jobs[g[0]].reward} lock-step x{len(g)}" for g in members],
    )
    return len(jobs) - todo
