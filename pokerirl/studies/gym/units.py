"""The units of the Gymnasium study and the sweep, as units of :mod:`pokerirl.store`.

Three kinds of unit, each a top-level function of plain arguments that returns bytes (so it
runs on any :mod:`pokerirl.execution` backend, with no shared filesystem):

- :func:`collect_unit`: the shipped expert's transitions (``gym collect``) as Parquet bytes;
- :func:`irl_unit`: one algorithm's IRL runs in lock-step (``gym irl``), or online one after
  another (``gym irl --mode online``), as a folder's files;
- :func:`rl_unit`: one RL run (``gym rl``) on the env reward or on one IRL run's reward;
- :func:`rl_group_unit`: with the lock-step RL backend, one group of RL runs (one task, one
  reward kind, one ``rl/<reward>`` folder: its unfinished runs) trained together, whose runs
  are saved each into its own run folder with its own record, as :func:`rl_unit`'s are.

:func:`pokerirl.store.run_units` writes what comes back, with a unit record (``unit.json``,
or ``expert.unit.json`` beside the data) holding a fingerprint of everything the unit's result
depends on: the task, the settings, the seeds and the sha256 of its inputs. A rerun reuses a
unit whose record matches (those of an older pokerirl, ``pokerirl-unit/1``, too), recomputes
one that is missing, half-written or corrupt, and refuses, in one line, one made with other
settings or inputs unless ``overwrite``.
"""

from __future__ import annotations

import hashlib
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pokerirl.execution import Backend, folder_files, read_files, write_files
from pokerirl.gym.presets import IRLSettings, RLSettings
from pokerirl.gym.rl import RLBackend
from pokerirl.irl.run import CONFIG_FILE, REWARD_FILE, TIMINGS_FILE
from pokerirl.store import (
    Group,
    Json,
    Layout,
    Unit,
    UnitOutput,
    digest,
    run_units,
)
from pokerirl.studies.common import StudyError

if TYPE_CHECKING:  # torch: the units import it lazily
    from pokerirl.gym.online import OnlineSettings

DATA_FILE = "expert.parquet"
DATA_RECORD = "expert.unit.json"
REWARD_INPUTS = (CONFIG_FILE, REWARD_FILE)  # what load_reward reads of a run folder


class JobError(StudyError):
    """An input a unit cannot read, or an unknown RL backend; the message is one line."""


def _output(files: dict[str, bytes]) -> UnitOutput[None]:
    # Wall-clock seconds: written, never fingerprinted.
    timed = {name: data for name, data in files.items() if Path(name).name == TIMINGS_FILE}
    kept = {name: data for name, data in files.items() if name not in timed}
    return UnitOutput(files=kept, unhashed=timed)


def expert_fingerprint(env_id: str, expert: Path | None = None) -> dict[str, Json]:
    """The shipped expert of ``env_id`` (``expert`` None): its manifest entry and the sha256 of
    its weights; or the expert folder ``expert``: the sha256 of its files."""
    from pokerirl.gym.expert_policies import resolve_expert_dir
    from pokerirl.gym.manifest import MODEL_FILE, shipped_manifest

    if expert is not None:
        return {"folder_sha256": {n: digest(b) for n, b in expert_files(expert).items()}}
    folder = resolve_expert_dir("shipped", env_id)
    entry = next((e for e in shipped_manifest() if e["env"] == env_id), None)
    sha256 = hashlib.sha256((folder / MODEL_FILE).read_bytes()).hexdigest()
    return {"manifest": None if entry is None else dict(entry), "model_sha256": sha256}


def expert_files(folder: Path) -> dict[str, bytes]:
    """What :func:`pokerirl.gym.expert_policies.load_expert` reads of an expert folder, by name: the
    bytes travel to the unit, which may run on another machine."""
    from pokerirl.gym.manifest import CONFIG_FILE as EXPERT_CONFIG
    from pokerirl.gym.manifest import MODEL_FILE

    try:
        return {name: (folder / name).read_bytes() for name in (EXPERT_CONFIG, MODEL_FILE)}
    except FileNotFoundError as error:
        missing = Path(error.filename).name
        raise JobError(f"{folder}: not an expert folder ({missing} missing)") from None


# --------------------------------------------------------------------------- the units


def collect_unit(
    env_id: str, transitions: int, seed: int, expert_folder: dict[str, bytes] | None = None
) -> UnitOutput[None]:
    """The shipped expert's (or the expert folder's files') ``transitions`` transitions
    (episode k from ``reset(seed=seed + k)``), as the bytes of the table ``gym collect``
    writes."""
    from pokerirl.gym.collect import collect
    from pokerirl.gym.expert_policies import load_expert, resolve_expert_dir

    with tempfile.TemporaryDirectory(prefix="pokerirl-collect-") as scratch:
        path = Path(scratch) / DATA_FILE
        if expert_folder is None:
            expert = load_expert(resolve_expert_dir("shipped", env_id))
        else:
            for name, data in expert_folder.items():
                (Path(scratch) / name).write_bytes(data)
            expert = load_expert(scratch)
            if expert.env_id != env_id:
                raise JobError(f"the expert is for {expert.env_id}, not {env_id}")
        # deterministic=None: the task's default (continuous: sampled), recorded in the table
        collect(expert, path, transitions=transitions, seed=seed, deterministic=None)
        return UnitOutput(files={DATA_FILE: path.read_bytes()})


def irl_unit(
    env_id: str,
    data: bytes,
    data_label: str,
    algo: str,
    runs: int,
    settings: IRLSettings,
    seed: int,
    online: OnlineSettings | None = None,
) -> UnitOutput[None]:
    """``runs`` IRL runs of ``algo`` in lock-step on the expert data (Parquet bytes): the
    files of a ``gym irl`` folder (``run-<k>/...``, ``summary.json``, figures); with
    ``online``, ``gym irl --mode online``'s runs (one after another, a PPO generator each)."""
    from pokerirl.gym.irl import train_gym_irl

    with tempfile.TemporaryDirectory(prefix="pokerirl-gym-irl-") as scratch:
        path = Path(scratch) / DATA_FILE
        path.write_bytes(data)
        out = Path(scratch) / "out"
        if online is not None:
            from pokerirl.gym.online import train_gym_online

            train_gym_online(env_id, path, algo=algo, runs=runs, settings=settings,
                             online=online, seed=seed, out=out, progress=False,
                             data_label=data_label)  # fmt: skip
            return _output(folder_files(out))
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
        return _output(folder_files(out))


def rl_unit(
    env_id: str,
    reward_files: dict[str, bytes] | None,
    reward_name: str,
    seed: int,
    settings: RLSettings,
    evaluations: int,
    eval_episodes: int,
) -> UnitOutput[None]:
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
        return _output(folder_files(out))


def rl_group_unit(
    env_id: str,
    reward_files: Sequence[dict[str, bytes] | None],
    reward_names: Sequence[str],
    seeds: Sequence[int],
    settings: RLSettings,
    evaluations: int,
    eval_episodes: int,
) -> list[UnitOutput[None]]:
    """R RL runs in lock-step (``pokerirl.gym.lockstep.group``), run r on ``reward_files[r]``
    with seed ``seeds[r]``: the files of each run folder, run r's output r-th."""
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
        return [_output(folder_files(out)) for out in outs]


# --------------------------------------------------------------------------- jobs


@dataclass(frozen=True, kw_only=True)
class DataJob:
    """The expert data of one task, written to ``path`` (its record beside it)."""

    env: str
    transitions: int
    seed: int
    path: Path
    expert: Path | None = None  # an expert folder; None: the shipped expert

    def config(self) -> dict[str, Json]:
        from pokerirl.gym.collect import default_deterministic

        return {
            "unit": "gym-data",
            "env": self.env,
            "expert": expert_fingerprint(self.env, self.expert),
            "transitions": self.transitions,
            "seed": self.seed,
            # Only where the expert's actions are sampled (continuous tasks, issue 20): the
            # discrete tasks' records, made before the choice existed, stay valid.
            **({} if default_deterministic(self.env) else {"actions": "sampled"}),
        }

    def unit(self) -> Unit[None]:
        """The store unit: the data file, its record ``expert.unit.json`` beside it."""
        return Unit(
            key=f"{self.env} data",
            target=self.path,
            layout=Layout.FILE,
            config=self.config(),
            fn=collect_unit,
            args=(self.env, self.transitions, self.seed)
            + (() if self.expert is None else (expert_files(self.expert),)),
        )


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
    online: OnlineSettings | None = None  # None: offline IRL (the paper's)

    def config(self) -> dict[str, Json]:
        """The unit's configuration; its input is the data (:meth:`unit`)."""
        return {
            "unit": "gym-irl",
            "env": self.env,
            "algo": self.algo,
            "runs": self.runs,
            "seed": self.seed,
            "settings": asdict(self.settings),
            # Only online: offline records (every study made before) keep their bytes, and
            # the two modes' runs never pass for each other.
            **({} if self.online is None else {"mode": "online", "online": asdict(self.online)}),
        }

    def unit(self, data: bytes) -> Unit[None]:
        """The store unit; ``data`` is the bytes of ``self.data``."""
        return Unit(
            key=f"{self.env} {self.algo}",
            target=self.folder,
            config=self.config(),
            inputs={"data": digest(data)},
            fn=irl_unit,
            args=(self.env, data, str(self.data.resolve()), self.algo, self.runs,
                  self.settings, self.seed, self.online),
        )  # fmt: skip

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
    backend: str = RLBackend.SB3

    def reward_files(self) -> dict[str, bytes] | None:
        if self.reward_run is None:
            return None
        try:
            return read_files(self.reward_run, REWARD_INPUTS)
        except OSError as error:
            raise JobError(f"{self.reward_run}: cannot read the IRL run ({error})") from None

    def config(self) -> dict[str, Json]:
        """The unit's configuration; its input is the reward run's files (:meth:`unit`)."""
        return {
            "unit": "gym-rl",
            "env": self.env,
            "reward": self.reward,
            "seed": self.seed,
            "settings": asdict(self.settings),
            "evaluations": self.evaluations,
            "eval_episodes": self.eval_episodes,
            # Only for lock-step runs: sb3 records (every study made before) stay valid, and
            # the two backends' runs never pass for each other.
            **({} if self.backend == RLBackend.SB3 else {"backend": self.backend}),
        }

    def unit(self, reward_files: dict[str, bytes] | None) -> Unit[None]:
        """The store unit of this run; ``reward_files`` are :meth:`reward_files`."""
        prints = None if reward_files is None else {
            name: digest(data) for name, data in sorted(reward_files.items())}  # fmt: skip
        return Unit(
            key=f"{self.env} {self.reward} seed {self.seed}",
            target=self.folder,
            config=self.config(),
            inputs={"reward_run": prints},
            fn=rl_unit,
            args=(self.env, reward_files, self.reward_name(), self.seed, self.settings,
                  self.evaluations, self.eval_episodes),
        )  # fmt: skip

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


def run_data_jobs(
    jobs: Sequence[DataJob],
    *,
    backend: Backend,
    overwrite: bool = False,
    progress: bool = False,
) -> int:
    """Collect every job's data that is not already there; returns how many were reused."""
    units = [job.unit() for job in jobs]
    done = run_units(units, backend, overwrite=overwrite, progress=progress, desc="expert data")
    return len(done.reused)


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
    units = [job.unit(data[job.data]) for job in jobs]
    return len(run_units(units, backend, overwrite=overwrite, progress=progress, desc="IRL").reused)


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
    inputs = [job.reward_files() for job in jobs]
    units = [job.unit(files) for job, files in zip(jobs, inputs, strict=True)]
    sb3 = [unit for job, unit in zip(jobs, units, strict=True) if job.backend == RLBackend.SB3]
    lockstep = [unit for job, unit in zip(jobs, units, strict=True) if job.backend != RLBackend.SB3]
    runs = {unit.target: (job, files) for job, files, unit in zip(jobs, inputs, units, strict=True)}

    def group_args(members: Sequence[Unit[None]]) -> tuple[Any, ...]:
        found = [runs[unit.target] for unit in members]
        first = found[0][0]
        return (first.env, [files for _, files in found], [job.reward_name() for job, _ in found],
                [job.seed for job, _ in found], first.settings, first.evaluations,
                first.eval_episodes)  # fmt: skip

    def group_label(members: Sequence[Unit[None]]) -> str:
        first = runs[members[0].target][0]
        return f"{first.env} {first.reward} lock-step x{len(members)}"

    groups = Group(key=lambda unit: runs[unit.target][0].group_key(), fn=rl_group_unit,
                   args=group_args, label=group_label)  # fmt: skip
    reused = 0
    for chosen, desc, grouped in ((sb3, "RL runs", None), (lockstep, "RL groups", groups)):
        if chosen:
            done = run_units(chosen, backend, overwrite=overwrite, progress=progress, desc=desc,
                             group=grouped)  # fmt: skip
            reused += len(done.reused)
    return reused
