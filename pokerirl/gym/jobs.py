"""The ``gym expert`` and ``gym rl`` folders: their work (:func:`expert_folder`,
:func:`rl_runs`) and their record, what their outputs were trained with (:func:`claim`).

A rerun into the same folder with the same settings resumes (finished runs are kept); with
other settings it is refused in one line before anything is touched, unless ``overwrite``,
which removes every earlier output first, so that a rerun killed midway can never leave runs
of two settings side by side.

>>> import tempfile
>>> folder = Path(tempfile.mkdtemp())
>>> claim(folder, "rl.job.json", {"reward": "env"}, outputs=["run-*"], overwrite=False)
>>> (folder / "run-0").mkdir()
>>> claim(folder, "rl.job.json", {"reward": "a.pt"}, outputs=["run-*"], overwrite=False)
... # doctest: +ELLIPSIS
Traceback (most recent call last):
...
pokerirl.store.record.UnitConflict: ...: its outputs were trained with other settings (...)...
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Mapping, Sequence
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pokerirl.atomic import write_text
from pokerirl.errors import InputError, Remedy
from pokerirl.execution import watched
from pokerirl.gym.experts import CONFIG_FILE, METRICS_FILE, MODEL_FILE, ExpertRecord, require_gym
from pokerirl.gym.tasks import task
from pokerirl.meanstd import MeanStd, mean_std
from pokerirl.store import UnitConflict, describe_changes, digest, staged_files, staged_folder, tidy

JOB_FORMAT = "pokerirl-gym-job/1"


def claim(
    folder: Path,
    name: str,
    identity: Mapping[str, Any],
    *,
    outputs: Sequence[str],
    overwrite: bool,
) -> None:
    """Make ``folder/name`` record ``identity``, refusing (``UnitConflict``) when the
    folder's outputs (glob patterns) were made with another identity, unless ``overwrite``:
    then they are removed first."""
    identity = json.loads(json.dumps(identity))  # as it reads back: tuples become lists
    path = folder / name
    found = _outputs(folder, outputs)
    old: Any = None
    if path.is_file():
        try:
            record = json.loads(path.read_text())
            old = record["identity"] if record.get("format") == JOB_FORMAT else None
        except (ValueError, KeyError, TypeError, AttributeError):
            old = None
        if old == identity:
            return
    if found and not overwrite:
        if old is None:
            raise UnitConflict(
                f"{folder} holds outputs without a readable {name} (another version's, or "
                "its record is corrupt)",
                remedy=Remedy.REPLACE,
            )
        raise UnitConflict(
            f"{folder}: its outputs were trained with other settings "
            f"({describe_changes(old, identity)})",
            remedy=Remedy.REPLACE,
        )
    for output in found:  # the record goes first: a kill from here leaves no stale record
        if output.is_dir() and not output.is_symlink():
            shutil.rmtree(output)
        else:
            output.unlink()
    folder.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps({"format": JOB_FORMAT, "identity": identity}, indent=2) + "\n")


def _outputs(folder: Path, patterns: Sequence[str]) -> list[Path]:
    if not folder.is_dir():
        return []
    return sorted({p for pattern in patterns for p in folder.glob(pattern)})


RUN_FILES = (CONFIG_FILE, METRICS_FILE, MODEL_FILE)  # an expert's, and an RL run's


@dataclass(frozen=True)
class ExpertFolder:
    """A ``gym expert`` folder: its record, and whether it was already there."""

    record: ExpertRecord
    reused: bool


def expert_folder(
    out: Path,
    env: str,
    *,
    seed: int,
    hyper: str,
    timesteps: int | None,
    eval_every: int | None,
    eval_episodes: int,
    final_episodes: int,
    overwrite: bool,
) -> ExpertFolder:
    """Train an SB3 expert into ``out``, or keep the one there if it was trained with the same
    settings (others are refused, unless ``overwrite``: ``out/expert.job.json`` records them).
    Its three files land together, or not at all."""
    from pokerirl.gym.experts import expert_settings, train_expert_record

    identity = {
        "env": env, "seed": seed, "hyper": hyper,
        "timesteps": timesteps or expert_settings(env, hyper=hyper).timesteps,
        "eval_every": eval_every, "eval_episodes": eval_episodes,
        "final_episodes": final_episodes,
    }  # fmt: skip
    claim(out, "expert.job.json", identity, outputs=list(RUN_FILES), overwrite=overwrite)
    tidy(out, key="expert")  # what a killed rerun left
    if all((out / name).is_file() for name in RUN_FILES):
        return ExpertFolder(record=_expert_record(out / CONFIG_FILE), reused=True)
    with staged_files(out, key="expert") as new:
        record = train_expert_record(
            new,
            env,
            seed=seed,
            timesteps=timesteps,
            hyper=hyper,
            eval_every=eval_every,
            eval_episodes=eval_episodes,
            final_episodes=final_episodes,
        )
    return ExpertFolder(record=record, reused=False)


@dataclass(frozen=True)
class RLRuns:
    """A ``gym rl`` folder's runs: run k's final true return at ``finals[k]``."""

    finals: tuple[float, ...]

    @property
    def final(self) -> MeanStd:
        return mean_std(self.finals)


def rl_runs(
    out: Path,
    env: str,
    *,
    reward_run: Path | None,
    runs: int,
    timesteps: int | None,
    evaluations: int,
    eval_episodes: int,
    rl_backend: str,
    overwrite: bool,
    progress: bool = False,
) -> RLRuns:
    """RL runs ``out/run-<k>`` (seed k) on the env reward or ``reward_run``'s learned reward;
    ``progress``: a bar that moves with the runs' timesteps.

    Resumable: the finished runs of a folder trained with the same settings are kept; other
    settings (the backend too) are refused, unless ``overwrite`` (``out/rl.job.json`` records
    them). Each run lands whole; on the lock-step backend the unfinished runs train as one
    group (run k is the same run either way it is grouped), and land together."""
    from pokerirl.gym.rl import train_rl

    reward = None
    reward_identity: Any = "env"
    if reward_run is not None:
        from pokerirl.irl import load_reward
        from pokerirl.irl.run import REWARD_FILE

        reward = load_reward(reward_run)
        weights = reward_run / REWARD_FILE
        reward_identity = {
            "run": str(reward_run),
            "sha256": digest(weights.read_bytes()) if weights.is_file() else None,
        }
    identity = {
        "env": env,
        "reward": reward_identity,
        "timesteps": timesteps or task(env).rl.timesteps,
        "evaluations": evaluations,
        "eval_episodes": eval_episodes,
        # Only for lockstep: folders written before the switch keep their identity.
        **({} if rl_backend == "sb3" else {"backend": rl_backend}),
    }
    if rl_backend != "sb3":
        require_gym()  # the lock-step trainers import gymnasium: say so before any change
    claim(out, "rl.job.json", identity, outputs=["run-*"], overwrite=overwrite)
    reward_name = "env" if reward is None else str(reward_run)
    found: dict[int, float] = {}
    todo = []
    for k in range(runs):
        run = out / f"run-{k}"
        tidy(out, key=run.name)  # what a killed rerun left
        if all((run / name).is_file() for name in RUN_FILES):
            found[k] = _final_return(run / CONFIG_FILE)
        else:
            todo.append(k)
    if rl_backend == "sb3":
        with watched("RL runs", total=len(todo), enabled=progress and bool(todo)) as run_done:
            for k in todo:
                with staged_folder(out / f"run-{k}") as stage:  # a run is whole, or not at all
                    result = train_rl(
                        env,
                        reward=reward,
                        reward_name=reward_name,
                        seed=k,
                        timesteps=timesteps,
                        evaluations=evaluations,
                        eval_episodes=eval_episodes,
                        out=stage,
                    )
                found[k] = result.final_return
                run_done()
    elif todo:
        from pokerirl.gym.lockstep.group import train_rl_group

        with ExitStack() as stack:  # every run of the group lands whole, or none does
            stages = [stack.enter_context(staged_folder(out / f"run-{k}")) for k in todo]
            stack.enter_context(watched(f"RL, {len(todo)} runs in lock-step", enabled=progress))
            results = train_rl_group(
                env,
                rewards=[reward] * len(todo),
                reward_names=[reward_name] * len(todo),
                seeds=todo,
                timesteps=timesteps,
                evaluations=evaluations,
                eval_episodes=eval_episodes,
                outs=stages,
            )
        found.update({k: result.final_return for k, result in zip(todo, results, strict=True)})
    return RLRuns(finals=tuple(found[k] for k in range(runs)))


def _expert_record(config: Path) -> ExpertRecord:
    """A finished expert's record, from its config file (corrupt: one line naming it)."""
    try:
        return ExpertRecord.from_json(json.loads(config.read_text()))
    except (ValueError, KeyError, TypeError) as error:  # not JSON, or not an expert's record
        raise InputError(f"{config}: corrupt: not an expert's record ({error!r})") from None


def _final_return(config: Path) -> float:
    """A finished RL run's final return, from its config file (corrupt: one line naming it)."""
    try:
        return float(json.loads(config.read_text())["final_return"])
    except (ValueError, KeyError, TypeError) as error:  # not JSON, or not a run's record
        raise InputError(f"{config}: corrupt: no final return ({error!r})") from None
