"""The ``gym expert`` and ``gym rl`` folders, as units of :mod:`pokerirl.store`.

``gym expert``: the expert folder is one folder unit (``OUT/unit.json``). ``gym rl``: each
run ``OUT/run-<k>`` (seed k) is a folder unit with its own record; on the lock-step backend
the unfinished runs train as one group (``run_units(..., group=...)``: run k is the same run
either way it is grouped), each saved on its own.

A rerun with the same settings keeps what is finished; one with other settings is refused in
one line before anything is touched, unless ``overwrite``. For ``gym rl`` both hold for the
whole folder: every ``run-<k>`` of other settings (those beyond ``runs`` too) is checked, and
with ``overwrite`` removed before the first new run starts, so that a rerun killed midway
never leaves runs of two settings side by side.

Folders written before the store kept one record for the folder, ``expert.job.json`` or
``rl.job.json`` (``pokerirl-gym-job/1``): it is read as a legacy record
(:class:`~pokerirl.store.LegacyRecord`) of the outputs without their own record, so they are
reused when its settings match and refused (or replaced) when not; it goes once nothing of
its own is left.
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pokerirl.errors import InputError
from pokerirl.execution import Backend, folder_files
from pokerirl.gym.envs import require_gym
from pokerirl.gym.expert_policies import ExpertRecord
from pokerirl.gym.manifest import CONFIG_FILE, METRICS_FILE, MODEL_FILE
from pokerirl.gym.tasks import task
from pokerirl.irl.reward import RewardFn
from pokerirl.jsonio import read_json
from pokerirl.meanstd import MeanStd, mean_std
from pokerirl.store import (
    RECORD_NAME,
    Fate,
    Group,
    LegacyRecord,
    Unit,
    UnitOutput,
    check,
    digest,
    run_units,
    staged_folder,
    tidy,
)

LEGACY_EXPERT, LEGACY_RL = "expert.job.json", "rl.job.json"  # pokerirl-gym-job/1, pre-store
RUN_FILES = (CONFIG_FILE, METRICS_FILE, MODEL_FILE)  # an expert's, and an RL run's
_RUN = re.compile(r"run-(\d+)")


# --------------------------------------------------------------------------- the units


def expert_unit(
    env: str,
    seed: int,
    hyper: str,
    timesteps: int | None,
    eval_every: int | None,
    eval_episodes: int,
    final_episodes: int,
) -> UnitOutput[None]:
    """An SB3 expert's files (see :func:`pokerirl.gym.expert_policies.train_expert_record`)."""
    from pokerirl.gym.expert_policies import train_expert_record

    with tempfile.TemporaryDirectory(prefix="pokerirl-gym-expert-") as scratch:
        train_expert_record(
            scratch,
            env,
            seed=seed,
            timesteps=timesteps,
            hyper=hyper,
            eval_every=eval_every,
            eval_episodes=eval_episodes,
            final_episodes=final_episodes,
        )
        return UnitOutput(files=folder_files(Path(scratch)))


def rl_unit(
    env: str,
    reward: RewardFn | None,
    reward_name: str,
    seed: int,
    timesteps: int | None,
    evaluations: int,
    eval_episodes: int,
) -> UnitOutput[None]:
    """One RL run's files, on the env reward (``reward`` None) or a learned one. In this
    process only: a reward does not travel."""
    from pokerirl.gym.rl import train_rl

    with tempfile.TemporaryDirectory(prefix="pokerirl-gym-rl-") as scratch:
        train_rl(
            env,
            reward=reward,
            reward_name=reward_name,
            seed=seed,
            timesteps=timesteps,
            evaluations=evaluations,
            eval_episodes=eval_episodes,
            out=scratch,
        )
        return UnitOutput(files=folder_files(Path(scratch)))


def rl_group_unit(
    env: str,
    reward: RewardFn | None,
    reward_name: str,
    seeds: Sequence[int],
    timesteps: int | None,
    evaluations: int,
    eval_episodes: int,
) -> list[UnitOutput[None]]:
    """The runs of ``seeds`` in lock-step on one reward: each run's files, in order."""
    from pokerirl.gym.lockstep.group import train_rl_group

    with tempfile.TemporaryDirectory(prefix="pokerirl-gym-rl-group-") as scratch:
        outs = [Path(scratch) / f"run-{seed}" for seed in seeds]
        for out in outs:
            out.mkdir()
        train_rl_group(
            env,
            rewards=[reward] * len(seeds),
            reward_names=[reward_name] * len(seeds),
            seeds=seeds,
            timesteps=timesteps,
            evaluations=evaluations,
            eval_episodes=eval_episodes,
            outs=outs,
        )
        return [UnitOutput(files=folder_files(out)) for out in outs]


# --------------------------------------------------------------------------- gym expert


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
    threads: int = 1,
) -> ExpertFolder:
    """Train an SB3 expert into the unit folder ``out``, or keep the one there if it was
    trained with the same settings (others are refused, unless ``overwrite``). Its files
    land together, or not at all."""
    from pokerirl.gym.expert_policies import expert_settings

    settings = {
        "env": env, "seed": seed, "hyper": hyper,
        "timesteps": timesteps or expert_settings(env, hyper=hyper).timesteps,
        "eval_every": eval_every, "eval_episodes": eval_episodes,
        "final_episodes": final_episodes,
    }  # fmt: skip
    legacy = LegacyRecord(path=out / LEGACY_EXPERT, identity=settings)
    tidy(out, key="expert")  # what a killed pre-store run left: its files, swapped in or not
    _drop_unused(legacy, vouches=(out / CONFIG_FILE).is_file())
    unit: Unit[None] = Unit(
        key=f"{env} expert",
        target=out,
        config={"unit": "gym-expert", **settings},
        fn=expert_unit,
        args=(env, seed, hyper, timesteps, eval_every, eval_episodes, final_episodes),
        legacy=(legacy,),
    )
    out.mkdir(parents=True, exist_ok=True)  # an unwritable place fails here, before training
    done = run_units([unit], Backend(threads=threads), overwrite=overwrite).done[0]
    return ExpertFolder(record=_expert_record(out / CONFIG_FILE), reused=done.fate is Fate.REUSED)


# --------------------------------------------------------------------------- gym rl


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
    threads: int = 1,
) -> RLRuns:
    """RL runs ``out/run-<k>`` (seed k) on the env reward or ``reward_run``'s learned reward;
    ``progress``: a bar that moves with the runs' timesteps.

    Resumable: the finished runs of the same settings are kept; other settings (the backend
    too) are refused, unless ``overwrite`` (see the module's docstring). Each run lands
    whole; on the lock-step backend the unfinished runs train as one group."""
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
    settings = {
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
    legacy = LegacyRecord(path=out / LEGACY_RL, identity=settings)
    reward_name = "env" if reward is None else str(reward_run)

    def unit(k: int) -> Unit[None]:
        return Unit(
            key=f"run-{k}",
            target=out / f"run-{k}",
            config={"unit": "gym-rl-run", **settings, "seed": k},
            fn=rl_unit,
            args=(env, reward, reward_name, k, timesteps, evaluations, eval_episodes),
            legacy=(legacy,),
        )

    _drop_unused(legacy, vouches=bool(_legacy_runs(out)))
    units = [unit(k) for k in range(runs)]
    _clear_other_settings([*units, *(unit(k) for k in _seeds(out) if k >= runs)], overwrite)
    _drop_unused(legacy, vouches=bool(_legacy_runs(out)))
    out.mkdir(parents=True, exist_ok=True)  # an unwritable place fails here, before training
    group = None
    if rl_backend != "sb3":
        group = Group(
            key=lambda _: None,  # one group: every unfinished run
            fn=rl_group_unit,
            args=lambda members: (env, reward, reward_name, [m.config["seed"] for m in members],
                                  timesteps, evaluations, eval_episodes),
            label=lambda members: f"RL, {len(members)} runs in lock-step",
        )  # fmt: skip
    run_units(units, Backend(threads=threads), overwrite=overwrite, progress=progress,
              desc="RL runs", group=group)  # fmt: skip
    return RLRuns(finals=tuple(_final_return(u.target / CONFIG_FILE) for u in units))


def _seeds(out: Path) -> list[int]:
    """The seeds of the ``run-<k>`` folders in ``out``."""
    if not out.is_dir():
        return []
    return sorted(int(m[1]) for p in out.iterdir() if (m := _RUN.fullmatch(p.name)))


def _legacy_runs(out: Path) -> list[int]:
    """The runs only the folder's legacy record vouches for (those without a ``unit.json``)."""
    return [k for k in _seeds(out) if not (out / f"run-{k}" / RECORD_NAME).is_file()]


def _clear_other_settings(units: Sequence[Unit[None]], overwrite: bool) -> None:
    """Check every unit first (a refusal comes before any change); then, with ``overwrite``,
    empty the place of each to be recomputed, so that no run of other settings outlives
    the start of the new ones."""
    stale = [u.target for u in units if check(u, overwrite=overwrite).fate is Fate.RECOMPUTED]
    for target in filter(Path.is_dir, stale):
        with staged_folder(target):  # swapped for an empty folder: a kill leaves all or none
            pass
        target.rmdir()


def _drop_unused(legacy: LegacyRecord, *, vouches: bool) -> None:
    """Remove a legacy record that vouches for nothing (its outputs never landed, or were
    replaced): of other settings, it would refuse the new outputs."""
    if not vouches:
        legacy.path.unlink(missing_ok=True)


def _expert_record(config: Path) -> ExpertRecord:
    """A finished expert's record, from its config file (corrupt: one line naming it)."""
    try:
        return ExpertRecord.from_json(read_json(config))
    except (ValueError, KeyError, TypeError) as error:  # not JSON, or not an expert's record
        raise InputError(f"{config}: corrupt: not an expert's record ({error!r})") from None


def _final_return(config: Path) -> float:
    """A finished RL run's final return, from its config file (corrupt: one line naming it)."""
    try:
        return float(read_json(config)["final_return"])
    except (ValueError, KeyError, TypeError) as error:  # not JSON, or not a run's record
        raise InputError(f"{config}: corrupt: no final return ({error!r})") from None
