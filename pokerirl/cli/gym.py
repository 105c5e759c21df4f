"""The Gymnasium commands: pokerirl gym ... (the study and the sweep among them)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import typer

from pokerirl.cli.app import app
from pokerirl.cli.errors import (
    INTERRUPTED,
    RUN_ADVICE,
    display,
    echo,
    on_error,
    settings_from_options,
)
from pokerirl.cli.fanout import RAY_HELP, command_backend
from pokerirl.cli.options import LOG_DIR, choices, online_mode, write_logs
from pokerirl.cli.seeds import MAX_SEED, MAX_SEEDS, SEED_OPTION
from pokerirl.errors import InputError, UsageError
from pokerirl.gym.presets import MAX_TRANSITIONS
from pokerirl.irl.config import (  # torch-free: `gym irl`, `train` offer each
    MAX_EPOCHS,
    Algo,
    IRLMode,
)
from pokerirl.settings import MAX_STEPS
from pokerirl.studies.gym.config import MAX_EPISODES, PRESETS

gym_app = typer.Typer(
    help="The paper's Gymnasium tasks: SB3 experts, expert data, RL on a learned reward.",
    no_args_is_help=True,
)
app.add_typer(gym_app, name="gym")


# Spelled out rather than imported: pokerirl.gym.rl pulls in SB3, and the CLI imports lazily
# (tests/test_gym_lockstep_group.py checks it equals DEFAULT_RL_BACKEND).
RL_BACKEND = typer.Option(
    "lockstep", "--rl-backend", metavar="sb3|lockstep",
    help="How RL runs train: lockstep, a task's runs together in one process (PPO and DQN, "
    "SB3's semantics), or sb3, one run at a time (the reference).",
)  # fmt: skip


def _rl_backend(name: str) -> str:
    """Refuse an unknown --rl-backend in one line (exit 2)."""
    from pokerirl.gym.rl import RL_BACKENDS

    if name not in RL_BACKENDS:
        raise UsageError(f"--rl-backend must be one of {', '.join(RL_BACKENDS)}, got {name!r}")
    return name


def _known_task(env: str) -> None:
    """Refuse an env id that is neither a paper task nor a registered Gymnasium environment
    the toolkit can learn from, saying what is accepted (exit 2)."""
    from pokerirl.errors import ConfigError
    from pokerirl.gym.tasks import task

    try:
        task(env)  # a paper task costs nothing; another id imports Gymnasium to read its spaces
    except ConfigError as error:
        raise UsageError(str(error)) from None


def _no_shipped_expert(env: str, then: str) -> None:
    """Refuse a task without a shipped expert (any but the paper's) where the command would
    use one, saying how to get one (exit 2)."""
    from pokerirl.gym.tasks import task

    if task(env).generic:
        raise UsageError(
            f"no shipped expert for {env!r} (only the paper's tasks ship one): train one with "
            f"`pokerirl gym expert {env} --out DIR`, then {then}"
        )


def _folder_out(out: Path) -> None:
    """Refuse an --out that exists and is not a folder, before any work (exit 2)."""
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {display(str(out))}: exists and is not a folder")


# `gym irl`'s and `gym study`'s IRL mode and its online options.
GYM_MODE = typer.Option(
    "offline", "--mode", metavar=choices(IRLMode),
    help="offline: the policy acts at the expert's states (the paper's); online: a PPO "
    "generator acts in the env on the current learned reward (imitation's AIRL/GAIL).",
)  # fmt: skip
GYM_ROUNDS = typer.Option(
    None, "--rounds", min=1, max=MAX_EPOCHS,
    help="Online: rounds of generator steps, discriminator pass, PPO update (default 20).",
)  # fmt: skip
GYM_GENERATOR_STEPS = typer.Option(
    None, "--generator-steps", min=1, max=MAX_STEPS,
    help="Online: env steps the generator collects per round (default 2048).",
)  # fmt: skip
GYM_GENERATOR_ENVS = typer.Option(
    None, "--generator-envs", min=1, max=64,
    help="Online: the generator's vectorized envs (default 4).",
)  # fmt: skip


@gym_app.command("expert")
@on_error(interrupted=INTERRUPTED, advice=RUN_ADVICE)
def gym_expert(
    env: str = typer.Argument(
        ..., help="A paper task (Acrobot-v1, MountainCar-v0, ...) or any Gymnasium id."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Expert folder to write."),
    seed: int = typer.Option(0, **SEED_OPTION, help="Training seed."),
    timesteps: int | None = typer.Option(None, min=1, help="Budget (default: the authors')."),
    hyper: str = typer.Option(
        "paper", metavar=choices(("paper", "zoo")),
        help="paper (the authors' settings) or zoo (rl-zoo's).",
    ),
    eval_every: int | None = typer.Option(None, help="Steps between evaluations (budget/20)."),
    eval_episodes: int = typer.Option(5, help="Episodes per periodic evaluation."),
    final_episodes: int = typer.Option(20, help="Episodes of the best policy's final evaluation."),
    overwrite: bool = typer.Option(False, help="Replace an expert trained with other settings."),
    threads: int = typer.Option(1, min=1, help="torch threads."),
) -> None:
    """Train an SB3 expert (PPO; DQN for MountainCar), keeping the best evaluated checkpoint.

    A rerun with the same settings keeps the expert; other settings are refused unless
    --overwrite (OUT/unit.json records them)."""
    from pokerirl.execution import pin_threads
    from pokerirl.gym.jobs import expert_folder

    _known_task(env)
    _folder_out(out)
    pin_threads(threads)  # SB3's small MLPs train fastest on one thread
    done = expert_folder(
        out,
        env,
        seed=seed,
        hyper=hyper,
        timesteps=timesteps,
        eval_every=eval_every,
        eval_episodes=eval_episodes,
        final_episodes=final_episodes,
        overwrite=overwrite,
        threads=threads,
    )
    record = done.record
    if done.reused:
        echo(f"reusing the expert in {out} (same settings)")
    target = "" if record.target is None else f" (target {record.target:g})"  # paper tasks
    echo(
        f"{env}: {record.algo} expert, return {record.return_mean:.1f} "
        f"+- {record.return_std:.1f} over {record.episodes} episodes{target}; wrote {out}"
    )


@gym_app.command("experts")
def gym_experts(
    format: str = typer.Option(
        "text", "--format", metavar=choices(("text", "json")), help="json or text."
    ),
) -> None:
    """Print the manifest of the experts shipped with pokerirl."""
    from pokerirl.gym.manifest import MANIFEST_KEYS, shipped_manifest  # no torch: issue 34

    if format not in ("json", "text"):
        raise UsageError(f"--format must be json or text, got {format!r}")
    manifest = [{key: entry[key] for key in MANIFEST_KEYS} for entry in shipped_manifest()]
    if format == "json":
        echo(json.dumps(manifest, indent=2))
        return
    # The expert's evaluation, not the return of the demonstrations it gives (docs/gym.md).
    echo("task             algo  the expert's evaluation: return over deterministic episodes")
    for e in manifest:
        echo(
            f"{e['env']:<16} {e['algo']:<4} {e['return_mean']:>9.1f} +- {e['return_std']:<7.1f}"
            f" ({e['episodes']} episodes; seed {e['seed']}, {e['timesteps']:,} steps)"
        )


@gym_app.command("collect")
def gym_collect(
    env: str = typer.Argument(..., help="The expert's environment."),
    expert: str = typer.Option(
        "shipped", metavar="DIR|shipped", help="An expert folder, or 'shipped'."
    ),
    transitions: int = typer.Option(
        ..., "--transitions", "-n", min=1, max=MAX_TRANSITIONS, help="Rows to write."
    ),
    seed: int = typer.Option(0, **SEED_OPTION, help="Episode k starts from reset(seed=seed + k)."),
    out: Path = typer.Option(..., "--out", "-o", help="The Parquet table to write."),
    stochastic: bool | None = typer.Option(
        None,
        "--stochastic/--deterministic",
        help="Sample the expert's actions or take its mode (default: sampled for continuous "
        "tasks, the mode for discrete ones).",
    ),
) -> None:
    """Write the expert's play as a Parquet transition table (same seed, same bytes)."""
    from pokerirl.gym.collect import collect
    from pokerirl.gym.expert_policies import load_expert, resolve_expert_dir

    _known_task(env)
    if expert == "shipped":
        _no_shipped_expert(env, "pass --expert DIR")
    loaded = load_expert(resolve_expert_dir(expert, env))
    if loaded.env_id != env:
        raise InputError(f"{expert}: an expert for {loaded.env_id}, not {env}")
    from pokerirl.execution import watched

    with watched(f"expert data, {transitions:,} transitions"):  # the episodes report to it
        summary = collect(
            loaded,
            out,
            transitions=transitions,
            seed=seed,
            deterministic=None if stochastic is None else not stochastic,
        )
    echo(
        f"wrote {summary.transitions:,} transitions ({summary.episodes} episodes) to {out}; "
        f"expert return {summary.return_mean:.1f} +- {summary.return_std:.1f} "
        f"over {summary.complete_episodes} complete episodes"
    )


@gym_app.command("rl")
@on_error(interrupted=INTERRUPTED, advice=RUN_ADVICE)
def gym_rl(
    env: str = typer.Argument(..., help="The environment."),
    reward_run: Path | None = typer.Option(
        None, help="IRL run folder whose learned reward replaces the env reward."
    ),
    env_reward: bool = typer.Option(False, help="Train on the env reward (the baseline)."),
    runs: int = typer.Option(
        10, min=1, max=MAX_SEEDS, help="Runs (seeds 0..runs-1), in OUT/run-<k>."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Folder of the runs."),
    timesteps: int | None = typer.Option(None, min=1, help="Budget (default: the authors')."),
    evaluations: int = typer.Option(10, min=1, help="Points on the true-return curve."),
    eval_episodes: int = typer.Option(5, min=1, help="Episodes per point."),
    overwrite: bool = typer.Option(False, help="Replace runs trained with other settings."),
    threads: int = typer.Option(1, min=1, help="torch threads."),
    rl_backend: str = RL_BACKEND,
    log_dir: Path | None = LOG_DIR,
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """Train SB3 PPO (DQN for MountainCar) on a learned reward; the curve is the true return.

    With --rl-backend lockstep the unfinished runs train together in one process (run k is
    the same run either way it is grouped). Resumable: a rerun with the same settings keeps
    the finished runs; other settings (the backend too) are refused unless --overwrite, which
    removes every run of other settings before the first new one starts (OUT/run-<k>/unit.json
    records a run's)."""
    from pokerirl.execution import pin_threads
    from pokerirl.gym.jobs import rl_runs

    if (reward_run is None) == (not env_reward):
        raise UsageError("give exactly one of --reward-run DIR and --env-reward")
    _rl_backend(rl_backend)
    _known_task(env)
    _folder_out(out)
    pin_threads(threads)  # SB3's small MLPs train fastest on one thread
    done = rl_runs(
        out,
        env,
        reward_run=reward_run,
        runs=runs,
        timesteps=timesteps,
        evaluations=evaluations,
        eval_episodes=eval_episodes,
        rl_backend=rl_backend,
        overwrite=overwrite,
        progress=not quiet,
        threads=threads,
    )
    echo(
        f"{env}: final true return {done.final.mean:.1f} +- {done.final.std:.1f} over {runs} "
        f"runs; wrote {out}"
    )
    write_logs(out, log_dir)


@gym_app.command("irl")
@on_error(interrupted=INTERRUPTED, advice=RUN_ADVICE)
def gym_irl(
    env: str = typer.Argument(..., help="The task, e.g. MountainCar-v0."),
    data: Path | None = typer.Option(
        None,
        help="Expert Parquet (gym collect); default: collect the preset's from the "
        "shipped expert into OUT/expert.parquet.",
    ),
    algo: str = typer.Option("hairl", metavar=choices(Algo), help="airl, hairl or gail."),
    runs: int | None = typer.Option(
        None, min=1, max=MAX_SEEDS, help="Runs in lock-step (default: preset's)."
    ),
    preset: str = typer.Option(
        "paper", metavar=choices(PRESETS), help="quick, demo or paper (budgets)."
    ),
    seed: int = typer.Option(
        0, **SEED_OPTION, help="Run k uses seed + k; the data split uses seed."
    ),
    epochs: int | None = typer.Option(None, min=1, help="Override the preset's epochs."),
    raw_obs: bool = typer.Option(
        False, "--raw-obs", help="Train on raw observations (default: standardized)."
    ),
    mode: str = GYM_MODE,
    rounds: int | None = GYM_ROUNDS,
    generator_steps: int | None = GYM_GENERATOR_STEPS,
    generator_envs: int | None = GYM_GENERATOR_ENVS,
    out: Path = typer.Option(..., "--out", "-o", help="Folder of run-<k> and summary.json."),
    overwrite: bool = typer.Option(False, help="Replace earlier runs in OUT."),
    threads: int = typer.Option(1, min=1, help="torch threads."),
    log_dir: Path | None = LOG_DIR,
) -> None:
    """AIRL, H-AIRL or GAIL on a task's expert data; each epoch's (online: each round's)
    policy is evaluated in the env."""
    from dataclasses import replace

    from pokerirl.execution import pin_threads
    from pokerirl.gym.irl import train_gym_irl

    if preset not in PRESETS:
        raise UsageError(f"--preset must be one of {', '.join(PRESETS)}, got {preset!r}")
    if algo not in tuple(Algo):
        raise UsageError(f"--algo must be one of {', '.join(Algo)}, got {algo!r}")
    online = _online_settings(mode, rounds, generator_steps, generator_envs)
    _known_task(env)
    if data is not None and not data.is_file():
        raise InputError(f"--data {display(str(data))}: no such file")
    if data is None:
        _no_shipped_expert(env, f"`pokerirl gym collect {env} --expert DIR` and pass --data")
    settings = PRESETS[preset].irl(env)
    if epochs is not None:
        settings = replace(settings, epochs=epochs)
    settings = replace(settings, standardize_obs=not raw_obs)
    pin_threads(threads)  # SB3's small MLPs train fastest on one thread
    if data is None:
        from pokerirl.gym.collect import collect
        from pokerirl.gym.expert_policies import load_expert, resolve_expert_dir

        data = out / "expert.parquet"
        if not data.is_file():
            out.mkdir(parents=True, exist_ok=True)
            collect(
                load_expert(resolve_expert_dir("shipped", env)),
                data,
                transitions=settings.transitions,
                seed=seed,
            )
            echo(f"collected {settings.transitions:,} expert transitions into {data}")
        else:
            echo(f"reusing the expert data in {data}")
    if online is not None:
        result = _online_irl(env, data, algo=algo, runs=runs or PRESETS[preset].runs,
                             settings=settings, seed=seed, out=out, overwrite=overwrite,
                             online=online)  # fmt: skip
    else:
        result = train_gym_irl(
            env,
            data,
            algo=algo,
            runs=runs or PRESETS[preset].runs,
            settings=settings,
            seed=seed,
            out=out,
            overwrite=overwrite,
        )
    final = result.final_return
    line = (
        f"{env} {algo}: final return {final.mean:.1f} +- {final.std:.1f} over "
        f"{result.runs} runs (expert {result.summary.expert_return:.1f}, "
        f"random {result.baselines['random']:.1f})"
    )
    if result.final_alignment is not None:
        line += f", alignment {100 * result.final_alignment.measured[0]:.1f}%"
    echo(f"{line}; wrote {out}")
    write_logs(out, log_dir)


def _online_settings(
    mode: str, rounds: int | None, generator_steps: int | None, generator_envs: int | None
) -> Any:
    """``--mode`` and the online options (``gym irl``, ``gym study``): None offline, else the
    generator's settings, the defaults replaced by each option given; an online option
    offline is a usage error (exit 2), checked before any work."""
    from dataclasses import replace

    if not online_mode(mode, {"--rounds": rounds, "--generator-steps": generator_steps,
                              "--generator-envs": generator_envs}):  # fmt: skip
        return None
    from pokerirl.gym.online import OnlineSettings

    online = OnlineSettings()
    return replace(
        online,
        rounds=rounds or online.rounds,
        generator_steps=generator_steps or online.generator_steps,
        envs=generator_envs or online.envs,
    )


def _online_irl(env: str, data: Path, *, online: Any, **kwargs: Any) -> Any:
    """``gym irl --mode online``: :func:`pokerirl.gym.online.train_gym_online`, a line a round."""
    from pokerirl.gym.online import train_gym_online
    from pokerirl.irl.metrics import Metric

    def line(run: int, metrics: Any) -> None:
        echo(
            f"run {run} round {metrics.epoch}/{online.rounds}: return "
            f"{Metric.EVAL_RETURN.of(metrics):.1f}, disc loss {Metric.DISC_LOSS.of(metrics):.3f}, "
            f"D right on expert {Metric.DISC_ACC_EXPERT.of(metrics):.2f} / generator "
            f"{Metric.DISC_ACC_POLICY.of(metrics):.2f}"
        )

    return train_gym_online(env, data, online=online, on_round=line, progress=False, **kwargs)


@gym_app.command("reward-map")
def gym_reward_map(
    env_and_folders: list[str] = typer.Argument(
        ...,
        metavar="ENV [RUN_DIR]...",
        help="The task (a 2-d observation, discrete actions: MountainCar-v0); folders given "
        "after --runs land here too (`--runs A B`).",
    ),
    runs: list[Path] = typer.Option(
        [], "--runs", help="IRL folders (run-<k> inside, or one run), one panel each, in order."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="The PNG to write."),
    grid: int = typer.Option(101, "--grid", min=2, max=501, help="Cells per axis."),
    expert: str = typer.Option(
        "shipped", "--expert", metavar="DIR|shipped|none",
        help="Reference panel: shipped, an expert folder, or none.",
    ),
) -> None:
    """Draw the action each folder's learned reward f(s, a) prefers over the state space."""
    from pokerirl.gym.reward_map import plot_reward_map, reward_map

    env, *extra = env_and_folders
    # click gives an option one value: `--runs A B` leaves B among the positionals.
    folders = [*runs, *map(Path, extra)]
    if not folders:
        raise UsageError("give the IRL folders to draw: --runs AIRL_DIR HAIRL_DIR")
    result = reward_map(env, folders, grid=grid, expert=None if expert == "none" else expert)
    out.parent.mkdir(parents=True, exist_ok=True)
    plot_reward_map(result, out)
    for panel in result.panels:
        line = panel.label
        if panel.agreement is not None:
            low, high = min(panel.run_agreements), max(panel.run_agreements)
            line += (
                f": agrees with the expert on {100 * panel.agreement:.1f}% of "
                f"{grid}x{grid} cells (single runs {100 * low:.1f}-{100 * high:.1f}%)"
            )
        echo(line)
    if result.constant_agreement is not None:
        action, share = result.constant_agreement
        echo(f"baseline: a constant {action!r} agrees on {100 * share:.1f}% of cells")
    echo(f"wrote {out}")


# The budget and execution options that gym study and sweep share.
GYM_SEED = typer.Option(None, "--seed", **SEED_OPTION, help="Data seed; run k uses seed + k.")
GYM_TRANSITIONS = typer.Option(
    None, min=2, max=MAX_TRANSITIONS, help="Override the expert transitions."
)
GYM_EPOCHS = typer.Option(None, min=1, max=MAX_EPOCHS, help="Override the IRL epochs.")
GYM_EVAL_EPISODES = typer.Option(
    None, min=1, max=MAX_EPISODES, help="Override episodes per evaluation."
)
GYM_TIMESTEPS = typer.Option(None, min=1, max=MAX_STEPS, help="Override the RL steps per run.")
GYM_JOBS = typer.Option(2, "--jobs", min=1, help="Processes for the units.")
GYM_RAY = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP)
GYM_OVERWRITE = typer.Option(False, "--overwrite", help="Recompute units whose settings changed.")
GYM_QUIET = typer.Option(False, "--quiet", "-q", help="No progress bars.")


def _gym_preset(name: str, task: str, **overrides: Any) -> Any:
    """The study preset ``name`` for ``task`` (or all) with the command line's overrides."""
    from pokerirl.studies.gym.config import parse_tasks, study_preset

    preset = settings_from_options(study_preset, name, tasks=parse_tasks(task), **overrides)
    if preset.seed + preset.runs - 1 > MAX_SEED:  # run k uses seed + k
        raise UsageError(
            f"--seed {preset.seed:,} with {preset.runs} runs: run seeds must be at most "
            f"{MAX_SEED:,}"
        )
    return preset


@gym_app.command("study")
@on_error(interrupted=INTERRUPTED)
def gym_study(
    task: str = typer.Argument(..., metavar="ENV|all", help="A task, e.g. MountainCar-v0, or all."),
    out: Path = typer.Option(..., "--out", "-o", help="The study folder."),
    preset_name: str = typer.Option(
        "quick", "--preset", metavar=choices(PRESETS), help="quick, demo or paper (budgets)."
    ),
    runs: int | None = typer.Option(
        None, "--runs", min=1, max=MAX_SEEDS, help="Runs per algorithm and reward."
    ),
    algos: str | None = typer.Option(
        None,
        "--algos",
        metavar="ALGO,...",
        help="IRL algorithms: airl,hairl (the paper's; default), or airl,hairl,gail.",
    ),
    seed: int | None = GYM_SEED,
    transitions: int | None = GYM_TRANSITIONS,
    epochs: int | None = GYM_EPOCHS,
    eval_episodes: int | None = GYM_EVAL_EPISODES,
    timesteps: int | None = GYM_TIMESTEPS,
    jobs: int = GYM_JOBS,
    ray: str | None = GYM_RAY,
    overwrite: bool = GYM_OVERWRITE,
    quiet: bool = GYM_QUIET,
    rl_backend: str = RL_BACKEND,
    expert: Path | None = typer.Option(
        None,
        "--expert",
        help="An expert folder (gym expert) for the data; default: the shipped one. Needed "
        "for a task the paper does not have.",
    ),
    mode: str = GYM_MODE,
    rounds: int | None = GYM_ROUNDS,
    generator_steps: int | None = GYM_GENERATOR_STEPS,
    generator_envs: int | None = GYM_GENERATOR_ENVS,
    log_dir: Path | None = LOG_DIR,
) -> None:
    """The paper's Gymnasium study: shipped expert -> data -> IRL (AIRL and H-AIRL, and GAIL
    with --algos) -> RL (env reward and each algorithm's rewards) -> summary.json, figures/
    and report.md beside the authors' finals. Resumable: finished units are kept.

    With --mode online the IRL runs train online (as gym irl --mode online: a PPO generator
    in the env), everything after them as offline; the report says so, and a folder made in
    the other mode is refused unless --overwrite."""
    from pokerirl.studies.gym.config import parse_algos
    from pokerirl.studies.gym.pipeline import run_gym_study

    _rl_backend(rl_backend)
    online = _online_settings(mode, rounds, generator_steps, generator_envs)
    if expert is not None and task == "all":
        raise UsageError("--expert is for one task, not all")
    preset = _gym_preset(
        preset_name, task, runs=runs, seed=seed, transitions=transitions, epochs=epochs,
        eval_episodes=eval_episodes, rl_timesteps=timesteps,
        algos=None if algos is None else settings_from_options(parse_algos, algos),
    )  # fmt: skip
    if expert is None and task != "all":
        _no_shipped_expert(task, "pass --expert DIR")
    result = run_gym_study(
        out,
        preset,
        backend=command_backend(jobs, ray),
        overwrite=overwrite,
        progress=not quiet,
        say=echo,
        rl_backend=rl_backend,
        expert=expert,
        online=online,
    )
    echo("")
    echo(result.markdown)
    echo(f"report: {out / 'report.md'}")
    write_logs(out, log_dir)


@gym_app.command("sweep")
@on_error(interrupted=INTERRUPTED)
def gym_sweep(
    env: str = typer.Argument(..., help="The task, e.g. MountainCar-v0."),
    param: list[str] = typer.Option(
        ..., "--param", help="NAME=V1,V2,...: alpha, beta, sigma_start or sigma_end; repeatable."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="The sweep folder."),
    preset_name: str = typer.Option(
        "quick", "--preset", metavar=choices(PRESETS), help="quick, demo or paper (budgets)."
    ),
    runs: int | None = typer.Option(
        None, "--runs", min=1, max=MAX_SEEDS, help="Runs per point."
    ),
    seed: int | None = GYM_SEED,
    transitions: int | None = GYM_TRANSITIONS,
    epochs: int | None = GYM_EPOCHS,
    eval_episodes: int | None = GYM_EVAL_EPISODES,
    timesteps: int | None = GYM_TIMESTEPS,
    jobs: int = GYM_JOBS,
    ray: str | None = GYM_RAY,
    overwrite: bool = GYM_OVERWRITE,
    quiet: bool = GYM_QUIET,
    rl_backend: str = RL_BACKEND,
) -> None:
    """One-factor-at-a-time ablation of H-AIRL (the paper's Figure 5): each point runs the IRL
    phase, then RL on its learned rewards; writes sweep.csv, sweep.json and PARAM.png."""
    from pokerirl.studies.gym.sweep import parse_param, run_sweep

    _rl_backend(rl_backend)
    params: dict[str, tuple[float, ...]] = {}
    for text in param:
        name, values = parse_param(text)
        if name in params:
            raise InputError(f"--param {name} is given twice; list its values once")
        params[name] = values
    preset = _gym_preset(
        preset_name, env, runs=runs, seed=seed, transitions=transitions, epochs=epochs,
        eval_episodes=eval_episodes, rl_timesteps=timesteps,
    )  # fmt: skip
    result = run_sweep(
        env,
        params,
        preset,
        out,
        backend=command_backend(jobs, ray),
        overwrite=overwrite,
        progress=not quiet,
        say=echo,
        rl_backend=rl_backend,
    )
    for row in result.rows:
        line = (
            f"{row.param}={row.value:g}: IRL return {row.irl_final_return_mean:.1f} "
            f"+- {row.irl_final_return_std:.1f}, RL return {row.rl_final_return_mean:.1f} "
            f"+- {row.rl_final_return_std:.1f}"
        )
        if row.final_alignment_mean is not None:
            line += f", alignment {100 * row.final_alignment_mean:.1f}%"
        echo(line)
    echo(f"wrote {out / 'sweep.csv'} and {', '.join(str(p) for p in result.figures)}")
