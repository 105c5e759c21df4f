"""The ``pokerirl`` command line: thin typer commands over the library."""

from __future__ import annotations

import json
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

import typer
from typer.core import TyperGroup

from pokerirl import execution  # light: tqdm only; ray loads when chosen


def _command_line_errors() -> tuple[type[Exception], ...]:
    """Usage-error base classes: typer's own (recent typer vendors click, and its errors derive
    from TyperException) and click's (older typer runs on click)."""
    bases: list[type[Exception]] = []
    if hasattr(typer, "TyperException"):
        bases.append(typer.TyperException)
    try:
        import click
    except ImportError:
        pass
    else:
        bases.append(click.ClickException)
    return tuple(bases)


_COMMAND_LINE_ERRORS = _command_line_errors()


class OneLineErrors(TyperGroup):
    """The command group, with usage errors as one ``error: ...`` line (exit code 2) instead of
    click's usage text or typer's boxed panel, and warnings (such as the library's warning
    before it unpickles an ``rlcard:`` checkpoint) as one ``warning: ...`` line on stderr.
    Help (``--help``, or no arguments) is unchanged.

    Works wherever the group's ``main`` runs: the ``pokerirl`` script (``pokerirl.cli:app``),
    ``python -m pokerirl`` and typer's ``CliRunner``.
    """

    def main(
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        windows_expand_args: bool = True,
        **extra: Any,
    ) -> Any:
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, False, windows_expand_args, **extra)
        try:
            # Not standalone: click errors come here instead of being printed; typer.Exit(code)
            # and --help come back as the exit code, a command's normal end as its result.
            with warnings.catch_warnings():
                warnings.showwarning = _one_line_warning
                result = super().main(
                    args, prog_name, complete_var, False, windows_expand_args, **extra
                )
        except _COMMAND_LINE_ERRORS as error:
            if type(error).__name__ == "NoArgsIsHelpError":
                # No arguments: show the help, as typer does (rerun standalone).
                return super().main(
                    args, prog_name, complete_var, True, windows_expand_args, **extra
                )
            typer.secho(f"error: {_one_line(error)}", err=True, fg=typer.colors.RED)
            sys.exit(getattr(error, "exit_code", 2))
        except typer.Abort:
            typer.secho("error: aborted", err=True, fg=typer.colors.RED)
            sys.exit(1)
        sys.exit(result if isinstance(result, int) else 0)


def _one_line_warning(message: Warning | str, *_: Any, **__: Any) -> None:
    typer.secho(f"warning: {message}", err=True, fg=typer.colors.YELLOW)


def _one_line(error: Exception) -> str:
    """``pokerirl ingest: Missing option '--out' / '-o' (see pokerirl ingest --help)``"""
    message = " ".join(getattr(error, "format_message", error.__str__)().split())
    ctx = getattr(error, "ctx", None)
    if ctx is None:
        return message
    return f"{ctx.command_path}: {message.rstrip('.')} (see {ctx.command_path} --help)"


app = typer.Typer(
    name="pokerirl",
    help="Learn reward functions from real poker play (AIRL / Hybrid-AIRL on IRC hand histories).",
    cls=OneLineErrors,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def fail(message: str, code: int = 1) -> NoReturn:
    """Print a one-line error to stderr and exit non-zero, without a traceback."""
    typer.secho(f"error: {message}", err=True, fg=typer.colors.RED)
    raise typer.Exit(code)


def _backend(jobs: int, ray: str | None, threads: int = 1) -> execution.Backend:
    """The execution backend of a fan-out command: --ray, else $RAY_ADDRESS, else --jobs."""
    try:
        return execution.choose_backend(jobs=jobs, ray=ray, threads=threads)
    except ValueError as error:
        fail(str(error))


RAY_HELP = (
    "Run the units on the Ray cluster at ADDRESS (default: $RAY_ADDRESS when set), or 'local' "
    "for a private single-machine Ray. Results do not change."
)
INTERRUPTED = "interrupted: finished units are kept; rerun the same command to resume"


@app.command()
def version() -> None:
    """Print the package version."""
    from pokerirl import __version__

    typer.echo(__version__)


@app.command()
def ingest(
    sources: list[Path] = typer.Argument(
        ..., help="Month folders, folders of months, month .tgz archives or IRCdata.tgz."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="The Parquet table to write."),
    strict: bool = typer.Option(False, "--strict", help="Stop at the first malformed line."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar, no summary."),
) -> None:
    """Turn IRC Poker Database hand histories into a Parquet state-action table.

    Writes TABLE and TABLE.summary.json (where every hand went) and prints the summary.
    """
    from pokerirl.datasets.ingest import ingest as run_ingest
    from pokerirl.parsers.irc import IngestError

    try:
        summary = run_ingest(sources, out, strict=strict, progress=not quiet)
    except IngestError as error:
        fail(str(error))
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    if not quiet:
        typer.echo(json.dumps(summary, indent=2))


@app.command()
def synth(
    out: Path = typer.Option(..., "--out", "-o", help="Folder to write <out>/holdem/<YYYYMM>/ in."),
    hands: int = typer.Option(10_000, "--hands", "-n", min=1, help="Number of hands."),
    seed: int = typer.Option(0, "--seed", help="Random seed: the same seed, the same files."),
) -> None:
    """Write a synthetic IRC-format month of heads-up 10-20 limit hold'em between two bots."""
    from pokerirl.game.synth import write_synthetic_month

    try:
        folder = write_synthetic_month(out, hands=hands, seed=seed)
    except ValueError as error:
        fail(str(error))
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    typer.echo(f"wrote {hands} hands to {folder}")


@app.command()
def demo(
    out: Path = typer.Option(Path("demo-output"), "--out", "-o", help="Where the demo writes."),
    seed: int = typer.Option(0, "--seed", help="Seed of the synthetic data."),
    jobs: int = typer.Option(2, "--jobs", min=1, help="Processes for agent training and play."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Recompute changed stages."),
    gym: bool = typer.Option(
        True, "--gym/--no-gym", help="Also run the Gymnasium study's quick preset (~8 min)."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars."),
) -> None:
    """Run the study (pokerirl study, quick preset) on built-in synthetic data, then the
    Gymnasium study's quick preset (pokerirl gym study MountainCar-v0) on the shipped expert.

    synth -> ingest -> IRL (airl, hairl) -> agents (dqn, airl_dqn, hairl_dqn) -> Table 1
    tournament -> panel -> report.md, report.json and figures; then OUT/gym: expert data ->
    AIRL and H-AIRL -> DQN on each reward -> OUT/gym/report.md. A rerun skips finished work.
    """
    from pokerirl.demo import DemoConfig, run_demo, run_gym_demo

    try:
        result = run_demo(
            out,
            DemoConfig(seed=seed, jobs=jobs),
            say=typer.echo,
            progress=not quiet,
            overwrite=overwrite,
        )
    except (ValueError, OSError) as error:
        fail(str(error))
    typer.echo("")
    typer.echo(result.markdown)
    typer.echo(f"report: {out / 'report.md'} (pokerirl report {out})")
    if not gym:
        return
    try:
        from pokerirl.gym.experts import require_gym

        require_gym()
    except ImportError as error:
        warnings.warn(f"the Gymnasium demo is skipped: {error}", stacklevel=1)
        return
    typer.echo("")
    typer.echo(f"gym: the quick study on MountainCar-v0 -> {out / 'gym'}")
    try:
        gym_result = run_gym_demo(
            out, jobs=jobs, say=typer.echo, progress=not quiet, overwrite=overwrite
        )
    except (ValueError, OSError, execution.ExecutionError) as error:
        fail(str(error))
    except KeyboardInterrupt:
        fail(INTERRUPTED, 130)
    typer.echo("")
    typer.echo(gym_result.markdown)
    typer.echo(f"report: {out / 'gym' / 'report.md'}")


@app.command()
def study(
    sources: list[Path] = typer.Argument(..., help="IRC month folders or archives."),
    out: Path = typer.Option(..., "--out", "-o", help="The study folder."),
    preset_name: str = typer.Option("quick", "--preset", help="quick or paper."),
    runs: int | None = typer.Option(None, "--runs", min=1, help="IRL runs per algorithm."),
    seeds: str | None = typer.Option(None, "--seeds", help="Agent seeds, e.g. 0-19."),
    hands: int | None = typer.Option(None, "--hands", min=2, help="Tournament hands per seed."),
    jobs: int = typer.Option(2, "--jobs", min=1, help="Processes for training and play."),
    ray: str | None = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Recompute a stage whose settings changed, and those after it."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars."),
) -> None:
    """The paper's poker study in one command: ingest, IRL (AIRL and H-AIRL, several runs),
    DQN agents (sparse, AIRL and H-AIRL rewards), Table 1, the panel, and a report beside the
    paper's numbers (report.md, report.json, panel.csv, figures/). Resumable by stage."""
    from pokerirl.study import parse_seeds, preset, run_study

    try:
        config = preset(
            preset_name,
            runs=runs,
            seeds=None if seeds is None else parse_seeds(seeds),
            hands=hands,
            jobs=jobs,
        )
        result = run_study(
            sources,
            out,
            config,
            overwrite=overwrite,
            progress=not quiet,
            say=typer.echo,
            backend=_backend(jobs, ray),
        )
    except (ValueError, OSError, execution.ExecutionError) as error:
        fail(str(error))
    except KeyboardInterrupt:
        fail(INTERRUPTED, 130)
    typer.echo("")
    typer.echo(result.markdown)
    typer.echo(f"report: {out / 'report.md'} (pokerirl report {out})")


@app.command()
def match(
    agent_a: str = typer.Argument(
        ...,
        help="Agent A (reported): random, raise, call, an agent folder or rlcard:CKPT "
        "(an RLCard checkpoint: it is unpickled, which runs any code it holds; trusted "
        "files only).",
    ),
    agent_b: str = typer.Argument(..., help="Agent B: as agent A."),
    hands: int = typer.Option(100_000, help="Hands to play (even with --duplicate)."),
    seed: int = typer.Option(0, help="Seed of the deals and of the agents' random draws."),
    duplicate: bool = typer.Option(
        True, "--duplicate/--no-duplicate", help="Play every deal from both seats."
    ),
    output_format: str = typer.Option("text", "--format", help="text or json."),
) -> None:
    """Play A against B and print A's result in milli-big-blinds per hand."""
    from pokerirl.agents import resolve_agent
    from pokerirl.game import play_match

    if output_format not in ("text", "json"):
        fail(f"unknown format {output_format!r} (text or json)")
    try:
        result = play_match(
            resolve_agent(agent_a),
            resolve_agent(agent_b),
            hands=hands,
            seed=seed,
            duplicate=duplicate,
            progress=True,
        )
    except ValueError as error:
        fail(str(error))
    if output_format == "json":
        summary = {
            "mbb_per_hand": result.mbb_per_hand,
            "std_error": result.std_error,
            "hands": result.hands,
            "hands_per_second": result.hands_per_second,
        }
        typer.echo(json.dumps(summary))
    else:
        typer.echo(
            f"{result.agent_a} vs {result.agent_b}: {result.mbb_per_hand:+.1f} "
            f"+- {result.std_error:.1f} mbb/h over {result.hands:,} hands "
            f"({result.hands_per_second:,.0f} hands/s)"
        )


@app.command()
def tournament(
    agents: list[str] = typer.Argument(
        None,
        help="A B (one matchup, A's payoff), or with --vs the agents to play against BASE. "
        "Each: a built-in (random, raise, call), an agent folder, or an agent set (a folder "
        "of seed-<k> agent folders: seed k plays seed-k). An rlcard:CKPT agent is unpickled, "
        "which runs any code it holds (trusted files only).",
        show_default=False,
    ),
    vs: str | None = typer.Option(
        None, "--vs", metavar="BASE", help="Play every AGENT against BASE (several matchups)."
    ),
    hands: int = typer.Option(1_000_000, "--hands", "-n", help="Hands per seed."),
    seeds: str = typer.Option("0-19", "--seeds", help="Seeds, e.g. 0-19 or 0-4,10."),
    out: Path = typer.Option(..., "--out", "-o", help="Report folder (resumes what it holds)."),
    duplicate: bool = typer.Option(
        True, "--duplicate/--no-duplicate", help="Play every deal from both seats, paired."
    ),
    jobs: int = typer.Option(
        2, "--jobs", "-j", help="Local worker processes (results do not change)."
    ),
    ray: str | None = typer.Option(
        None,
        "--ray",
        metavar="ADDRESS",
        help="Play the seeds on the Ray cluster at ADDRESS (default: $RAY_ADDRESS when set), "
        "or 'local' for a private single-machine Ray. Results do not change.",
    ),
    alpha: float = typer.Option(0.05, help="Family-wise error rate (Bonferroni, Holm)."),
    batch_size: int = typer.Option(65_536, help="Hands in lock-step (part of the config)."),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Recompute saved seeds from another configuration."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar, no report."),
) -> None:
    """Multi-seed head-to-head evaluation: mbb/h, duplicate deals, Bonferroni and Holm.

    \b
    One matchup:      pokerirl tournament A B --hands N --seeds 0-19 --out DIR
    Several matchups: pokerirl tournament --vs dqn hairl-dqn airl-dqn --out DIR
                      (hairl-dqn vs dqn and airl-dqn vs dqn, corrected together)

    Writes DIR/report.md, report.json, per_seed.csv, per_seed.png; prints the report.

    \b
    Resumable: each seed is saved when it finishes. A rerun reuses saved seeds
    whose agents, hands, duplicate mode and batch size match, and refuses the
    others (--overwrite recomputes them); a corrupt saved seed is recomputed.
    pokerirl report DIR prints it again.
    """
    from pokerirl.execution import ExecutionError
    from pokerirl.seeds import parse_seeds
    from pokerirl.tournaments import render_report, run_tournament

    agents = agents or []
    if vs is not None:
        if not agents:
            fail("--vs BASE needs at least one agent to play against it")
        matchups = [(agent, vs) for agent in agents]
    elif len(agents) == 2:
        matchups = [(agents[0], agents[1])]
    else:
        fail(f"give two agents (A B) or --vs BASE and agents; got {len(agents)} agent(s)")
    backend = _backend(jobs, ray)
    try:
        report = run_tournament(
            matchups,
            hands=hands,
            seeds=parse_seeds(seeds),
            out=out,
            duplicate=duplicate,
            alpha=alpha,
            jobs=jobs,
            batch_size=batch_size,
            overwrite=overwrite,
            progress=not quiet,
            backend=backend,
        )
    except (ValueError, ExecutionError) as error:  # TournamentError, an agent's illegal move
        fail(str(error))
    except KeyboardInterrupt:
        fail(INTERRUPTED, code=130)
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    if not quiet:
        typer.echo(render_report(report))
        typer.echo(f"wrote {out}/report.md, report.json, per_seed.csv, per_seed.png")


@app.command()
def report(
    folder: Path = typer.Argument(
        ..., help="A folder written by pokerirl study, gym study or tournament."
    ),
    output_format: str = typer.Option("markdown", "--format", help="markdown or json."),
) -> None:
    """Print a study or tournament report (Markdown, or JSON for scripts)."""
    from pokerirl.gym.study import is_gym_study, load_gym_study
    from pokerirl.study import is_study_report, load_study_report, render_markdown
    from pokerirl.tournaments import load_report, render_report

    try:
        if is_gym_study(folder):
            found, markdown = load_gym_study(folder)
        elif is_study_report(folder):
            found = load_study_report(folder)
            markdown = render_markdown(found)
        else:
            typer.echo(render_report(load_report(folder), output_format), nl=False)
            return
    except ValueError as error:
        fail(str(error))
    if output_format == "json":
        typer.echo(json.dumps(found, indent=2))
    elif output_format in ("markdown", "text"):
        typer.echo(markdown, nl=False)
    else:
        fail(f"unknown --format {output_format!r}; choose markdown or json")


@app.command()
def train(
    table: str = typer.Argument(..., help="Parquet decision table written by `pokerirl ingest`."),
    out: str = typer.Option(..., "--out", help="Run folder (with --runs > 1: a folder of runs)."),
    algo: str = typer.Option("hairl", "--algo", help="hairl or airl (picks the defaults)."),
    runs: int = typer.Option(
        1, "--runs", help="Runs with seeds seed..seed+runs-1, in OUT/run-<k>."
    ),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Replace a finished run (with --runs: runs of other settings)."
    ),
    jobs: int = typer.Option(1, "--jobs", "-j", help="Processes running --runs at once."),
    ray: str | None = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP),
    epochs: int | None = typer.Option(None, "--epochs", help="Training epochs [default: 50]."),
    seed: int | None = typer.Option(None, "--seed", help="Seed for init, split, shuffle, noise."),
    device: str = typer.Option("cpu", "--device", help="cpu or cuda."),
    config: str | None = typer.Option(None, "--config", help="TOML file of hyperparameters."),
    batch_size: int | None = typer.Option(None, "--batch-size"),
    hidden: str | None = typer.Option(None, "--hidden", help="Widths for both nets, e.g. 64,64."),
    reward_lr: float | None = typer.Option(None, "--reward-lr"),
    policy_lr: float | None = typer.Option(None, "--policy-lr"),
    reward_weight_decay: float | None = typer.Option(None, "--reward-weight-decay"),
    alpha: float | None = typer.Option(None, "--alpha", help="Supervised weight in policy loss."),
    beta: float | None = typer.Option(None, "--beta", help="Env-reward weight in disc. loss."),
    sigma_start: float | None = typer.Option(None, "--sigma-start"),
    sigma_end: float | None = typer.Option(None, "--sigma-end"),
    val_fraction: float | None = typer.Option(None, "--val-fraction", help="Share of hands."),
    threads: int = typer.Option(1, "--threads", help="CPU threads; small nets train best on 1."),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bar."),
) -> None:
    """Learn a reward function with AIRL or Hybrid-AIRL from an expert decision table.

    Writes OUT/reward.pt, policy.pt, config.json, timings.json, metrics.jsonl,
    baselines.json, split.json and plots; with --runs N, OUT/run-<k> and OUT/summary.json.
    A finished OUT is replaced only with --overwrite, and only once the new run is complete.
    """
    import torch

    from pokerirl.irl import load_config, train_runs

    if threads < 1:
        fail("--threads must be at least 1")
    torch.set_num_threads(threads)

    widths = None
    if hidden is not None:
        try:
            widths = [int(w) for w in hidden.split(",") if w.strip()]
        except ValueError:
            fail(f"--hidden must be comma-separated integers, got {hidden!r}")
    overrides = {
        "epochs": epochs,
        "seed": seed,
        "batch_size": batch_size,
        "reward_hidden": widths,
        "policy_hidden": widths,
        "reward_lr": reward_lr,
        "policy_lr": policy_lr,
        "reward_weight_decay": reward_weight_decay,
        "alpha": alpha,
        "beta": beta,
        "sigma_start": sigma_start,
        "sigma_end": sigma_end,
        "val_fraction": val_fraction,
    }
    try:
        settings = load_config(algo, config_file=config, overrides=overrides)
        summary = train_runs(
            table,
            out,
            runs=runs,
            algo=algo,
            config=settings,
            device=device,
            progress=not quiet,
            overwrite=overwrite,
            backend=_backend(jobs, ray),
        )
    except (ValueError, execution.ExecutionError) as error:
        fail(str(error))
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    except KeyboardInterrupt:
        fail(INTERRUPTED, 130)
    single = {"metrics": summary.metrics, "baselines": summary.baselines}
    for run in summary.runs or (single,):
        last, base = run["metrics"][-1], run["baselines"]
        name = f"{algo} {Path(run['out']).name}" if "out" in run else algo
        rows = run.get("train_rows", summary.train_rows), run.get("val_rows", summary.val_rows)
        typer.echo(
            f"{name}: {len(run['metrics'])} epochs on {rows[0]} rows; validation "
            f"alignment {last['val_alignment']:.3f}, reward alignment "
            f"{last['val_reward_alignment']:.3f}; baselines "
            + ", ".join(f"{k} {v:.3f}" for k, v in base.items())
            + f" on {rows[1]} rows"
        )
    typer.echo(f"{summary.samples_per_second:,.0f} samples/s; wrote {summary.out_dir}")


agent_app = typer.Typer(help="Train DQN agents.", no_args_is_help=True)
app.add_typer(agent_app, name="agent")


@agent_app.command("train")
def agent_train(
    out: Path = typer.Option(..., "--out", "-o", help="Agent folder (with --seeds: its parent)."),
    reward: str = typer.Option("sparse", help="sparse (the payoff) or learned (--reward-run's f)."),
    reward_run: Path | None = typer.Option(None, help="AIRL / H-AIRL run folder (learned reward)."),
    payoff_weight: float = typer.Option(
        0.0, help="w in r = w * payoff + (1 - w) * f(s, a); 0: the learned reward alone."
    ),
    hands: int = typer.Option(50_000, "--hands", "-n", help="Training hands."),
    seed: int = typer.Option(0, help="Seed of one agent."),
    seeds: str | None = typer.Option(None, help="e.g. 0-19: one agent per seed, in OUT/seed-<k>."),
    jobs: int = typer.Option(1, "--jobs", "-j", help="Local processes training seeds at once."),
    ray: str | None = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP),
    threads: int = typer.Option(
        1, "--threads", help="torch threads per agent (part of the result: the weights change)."
    ),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Retrain finished agents of other settings (else refused)."
    ),
    opponent: str = typer.Option(
        "random",
        help="random, raise, call, an agent folder, rlcard:CKPT (unpickled: runs any code it "
        "holds; trusted files only), or self.",
    ),
    eval_every: int = typer.Option(10_000, help="Evaluate every N training hands."),
    eval_hands: int = typer.Option(20_000, help="Duplicate hands per evaluation (even)."),
    eval_seed: int = typer.Option(1_000_003, help="Deal seed of every evaluation."),
    train_every: int = typer.Option(16, help="Stored transitions per gradient update."),
    concurrent_hands: int = typer.Option(1024, help="Hands played in lock-step."),
    learning_rate: float = typer.Option(5e-5, help="Adam learning rate."),
    self_play_every: int = typer.Option(1_000, help="Updates between refreshes of 'self'."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """Train a DQN agent (or one per seed) on the sparse payoff or a learned reward.

    \b
    A finished agent folder is never changed: a rerun with the same settings reuses it,
    one with other settings is refused (--overwrite retrains it). New folders are
    written beside the old and swapped in at the end, so a killed run loses nothing.
    With --seeds, seeds run as units (--jobs or --ray); a rerun resumes the set.
    """
    from pokerirl.agents.dqn import DQNConfig
    from pokerirl.agents.train import TrainConfig, train_agent, train_seeds
    from pokerirl.execution import ExecutionError
    from pokerirl.seeds import parse_seeds

    backend = _backend(jobs, ray, threads)
    try:
        config = TrainConfig(
            hands=hands,
            seed=seed,
            reward=reward,
            reward_run=None if reward_run is None else str(reward_run),
            payoff_weight=payoff_weight,
            opponent=opponent,
            eval_every=eval_every,
            eval_hands=eval_hands,
            eval_seed=eval_seed,
            dqn=DQNConfig(
                train_every=train_every,
                concurrent_hands=concurrent_hands,
                learning_rate=learning_rate,
                self_play_every=self_play_every,
            ),
        )
        if seeds is None:
            summary = train_agent(
                out, config, progress=not quiet, overwrite=overwrite, backend=backend
            )
            lines = {seed: summary}
        else:
            lines = train_seeds(
                out,
                config,
                list(parse_seeds(seeds)),
                jobs=jobs,
                progress=not quiet,
                overwrite=overwrite,
                backend=backend,
            )
    except (ValueError, ExecutionError) as error:
        fail(str(error))
    except KeyboardInterrupt:
        fail(INTERRUPTED, code=130)
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    for agent_seed, line in lines.items():
        folder = out if seeds is None else out / f"seed-{agent_seed}"
        if line is None:
            typer.echo(f"{folder}: already finished with these settings, reused")
            continue
        scores = ", ".join(
            f"vs {name} {e['mbb_per_hand']:+.0f} +- {e['std_error']:.0f} mbb/h"
            for name, e in line["eval"].items()
        )
        typer.echo(f"{folder}: {line['hands']:,} hands, {scores}")


gym_app = typer.Typer(
    help="The paper's Gymnasium tasks: SB3 experts, expert data, RL on a learned reward.",
    no_args_is_help=True,
)
app.add_typer(gym_app, name="gym")


def _gym_threads(threads: int) -> None:
    # SB3's small MLPs run fastest on one thread; more only contend with other work.
    import torch

    torch.set_num_threads(threads)


@gym_app.command("expert")
def gym_expert(
    env: str = typer.Argument(..., help="Acrobot-v1, MountainCar-v0, LunarLander-v3, ..."),
    out: Path = typer.Option(..., "--out", "-o", help="Expert folder to write."),
    seed: int = typer.Option(0, help="Training seed."),
    timesteps: int | None = typer.Option(None, help="Budget (default: the authors')."),
    hyper: str = typer.Option("paper", help="paper (the authors' settings) or zoo (rl-zoo's)."),
    eval_every: int | None = typer.Option(None, help="Steps between evaluations (budget/20)."),
    eval_episodes: int = typer.Option(5, help="Episodes per periodic evaluation."),
    final_episodes: int = typer.Option(20, help="Episodes of the best policy's final evaluation."),
    threads: int = typer.Option(1, help="torch threads."),
) -> None:
    """Train an SB3 expert (PPO; DQN for MountainCar), keeping the best evaluated checkpoint."""
    from pokerirl.gym.experts import train_expert

    _gym_threads(threads)
    try:
        record = train_expert(
            out,
            env,
            seed=seed,
            timesteps=timesteps,
            hyper=hyper,
            eval_every=eval_every,
            eval_episodes=eval_episodes,
            final_episodes=final_episodes,
        )
    except (ValueError, ImportError) as error:
        fail(str(error))
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    typer.echo(
        f"{env}: {record['algo']} expert, return {record['return_mean']:.1f} "
        f"+- {record['return_std']:.1f} over {record['episodes']} episodes "
        f"(target {record['target']:g}); wrote {out}"
    )


@gym_app.command("experts")
def gym_experts(
    format: str = typer.Option("text", "--format", help="json or text."),
) -> None:
    """Print the manifest of the experts shipped with pokerirl."""
    from pokerirl.gym.experts import MANIFEST_KEYS, shipped_manifest

    if format not in ("json", "text"):
        fail(f"--format must be json or text, got {format!r}")
    try:
        manifest = [{key: entry[key] for key in MANIFEST_KEYS} for entry in shipped_manifest()]
    except ValueError as error:
        fail(str(error))
    if format == "json":
        typer.echo(json.dumps(manifest, indent=2))
        return
    for e in manifest:
        typer.echo(
            f"{e['env']:<16} {e['algo']:<4} {e['return_mean']:>9.1f} +- {e['return_std']:<7.1f}"
            f" ({e['episodes']} episodes; seed {e['seed']}, {e['timesteps']:,} steps)"
        )


@gym_app.command("collect")
def gym_collect(
    env: str = typer.Argument(..., help="The expert's environment."),
    expert: str = typer.Option("shipped", help="An expert folder, or 'shipped'."),
    transitions: int = typer.Option(..., "--transitions", "-n", min=1, help="Rows to write."),
    seed: int = typer.Option(0, help="Episode k starts from reset(seed=seed + k)."),
    out: Path = typer.Option(..., "--out", "-o", help="The Parquet table to write."),
    stochastic: bool = typer.Option(False, help="Sample the expert's actions (else its mode)."),
) -> None:
    """Write the expert's play as a Parquet transition table (same seed, same bytes)."""
    from pokerirl.gym.collect import collect
    from pokerirl.gym.experts import load_expert, resolve_expert_dir

    try:
        loaded = load_expert(resolve_expert_dir(expert, env))
        if loaded.env_id != env:
            fail(f"{expert}: an expert for {loaded.env_id}, not {env}")
        summary = collect(
            loaded, out, transitions=transitions, seed=seed, deterministic=not stochastic
        )
    except (ValueError, ImportError) as error:
        fail(str(error))
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    typer.echo(
        f"wrote {summary.transitions:,} transitions ({summary.episodes} episodes) to {out}; "
        f"expert return {summary.return_mean:.1f} +- {summary.return_std:.1f} "
        f"over {summary.complete_episodes} complete episodes"
    )


@gym_app.command("rl")
def gym_rl(
    env: str = typer.Argument(..., help="The environment."),
    reward_run: Path | None = typer.Option(
        None, help="IRL run folder whose learned reward replaces the env reward."
    ),
    env_reward: bool = typer.Option(False, help="Train on the env reward (the baseline)."),
    runs: int = typer.Option(10, min=1, help="Runs (seeds 0..runs-1), in OUT/run-<k>."),
    out: Path = typer.Option(..., "--out", "-o", help="Folder of the runs."),
    timesteps: int | None = typer.Option(None, help="Budget (default: the authors')."),
    evaluations: int = typer.Option(10, help="Points on the true-return curve."),
    eval_episodes: int = typer.Option(5, help="Episodes per point."),
    threads: int = typer.Option(1, help="torch threads."),
) -> None:
    """Train SB3 PPO (DQN for MountainCar) on a learned reward; the curve is the true return."""
    from pokerirl.gym.rl import summarize, train_rl

    if (reward_run is None) == (not env_reward):
        fail("give exactly one of --reward-run DIR and --env-reward")
    _gym_threads(threads)
    try:
        reward = None
        if reward_run is not None:
            from pokerirl.irl import load_reward

            reward = load_reward(reward_run)
        results = [
            train_rl(
                env,
                reward=reward,
                reward_name="env" if reward is None else str(reward_run),
                seed=k,
                timesteps=timesteps,
                evaluations=evaluations,
                eval_episodes=eval_episodes,
                out=out / f"run-{k}",
            )
            for k in range(runs)
        ]
    except (ValueError, ImportError, KeyError) as error:
        fail(str(error))
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    final = summarize(results)
    typer.echo(
        f"{env}: final true return {final['mean']:.1f} +- {final['std']:.1f} over {runs} runs; "
        f"wrote {out}"
    )


@gym_app.command("irl")
def gym_irl(
    env: str = typer.Argument(..., help="The task, e.g. MountainCar-v0."),
    data: Path | None = typer.Option(
        None,
        help="Expert Parquet (gym collect); default: collect the preset's from the "
        "shipped expert into OUT/expert.parquet.",
    ),
    algo: str = typer.Option("hairl", help="airl or hairl."),
    runs: int | None = typer.Option(None, min=1, help="Runs in lock-step (default: preset's)."),
    preset: str = typer.Option("paper", help="quick or paper: the budgets."),
    seed: int = typer.Option(0, help="Run k uses seed + k; the data split uses seed."),
    epochs: int | None = typer.Option(None, min=1, help="Override the preset's epochs."),
    raw_obs: bool = typer.Option(
        False, "--raw-obs", help="Train on raw observations (default: standardized)."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Folder of run-<k> and summary.json."),
    overwrite: bool = typer.Option(False, help="Replace earlier runs in OUT."),
    threads: int = typer.Option(1, help="torch threads."),
) -> None:
    """AIRL or H-AIRL on a task's expert data; each epoch's policy is evaluated in the env."""
    from dataclasses import replace

    from pokerirl.gym.presets import PRESETS, TASKS

    if preset not in PRESETS:
        fail(f"--preset must be one of {', '.join(PRESETS)}, got {preset!r}")
    if algo not in ("airl", "hairl"):
        fail(f"--algo must be airl or hairl, got {algo!r}")
    if env not in TASKS:
        fail(f"unknown task {env!r}; choose one of {', '.join(TASKS)}")
    if data is not None and not data.is_file():
        fail(f"--data {data}: no such file")
    settings = PRESETS[preset].irl(env)
    if epochs is not None:
        settings = replace(settings, epochs=epochs)
    settings = replace(settings, standardize_obs=not raw_obs)
    _gym_threads(threads)
    try:
        from pokerirl.gym.irl import train_gym_irl

        if data is None:
            from pokerirl.gym.collect import collect
            from pokerirl.gym.experts import load_expert, resolve_expert_dir

            data = out / "expert.parquet"
            if not data.is_file():
                out.mkdir(parents=True, exist_ok=True)
                collect(
                    load_expert(resolve_expert_dir("shipped", env)),
                    data,
                    transitions=settings.transitions,
                    seed=seed,
                )
                typer.echo(f"collected {settings.transitions:,} expert transitions into {data}")
            else:
                typer.echo(f"reusing the expert data in {data}")
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
    except (ValueError, ImportError) as error:
        fail(str(error))
    except KeyboardInterrupt:
        fail(INTERRUPTED, code=130)
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    final = result.final_return
    line = (
        f"{env} {algo}: final return {final['mean']:.1f} +- {final['std']:.1f} over "
        f"{result.runs} runs (expert {result.expert_return:.1f}, "
        f"random {result.baselines['random']:.1f})"
    )
    if result.final_alignment is not None:
        line += f", alignment {100 * result.final_alignment['mean']:.1f}%"
    typer.echo(f"{line}; wrote {out}")


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
        "shipped", "--expert", help="Reference panel: shipped, an expert folder, or none."
    ),
) -> None:
    """Draw the action each folder's learned reward f(s, a) prefers over the state space."""
    from pokerirl.gym.reward_map import plot_reward_map, reward_map

    env, *extra = env_and_folders
    # click gives an option one value: `--runs A B` leaves B among the positionals.
    folders = [*runs, *map(Path, extra)]
    if not folders:
        fail("give the IRL folders to draw: --runs AIRL_DIR HAIRL_DIR")
    try:
        result = reward_map(env, folders, grid=grid, expert=None if expert == "none" else expert)
        out.parent.mkdir(parents=True, exist_ok=True)
        plot_reward_map(result, out)
    except (ValueError, ImportError) as error:
        fail(str(error))
    except OSError as error:
        fail(f"{error.filename or out}: {error.strerror or error}")
    for panel in result.panels:
        line = panel.label
        if panel.agreement is not None:
            low, high = min(panel.run_agreements), max(panel.run_agreements)
            line += (
                f": agrees with the expert on {100 * panel.agreement:.1f}% of "
                f"{grid}x{grid} cells (single runs {100 * low:.1f}-{100 * high:.1f}%)"
            )
        typer.echo(line)
    if result.constant_agreement is not None:
        action, share = result.constant_agreement
        typer.echo(f"baseline: a constant {action!r} agrees on {100 * share:.1f}% of cells")
    typer.echo(f"wrote {out}")


# The budget and execution options that gym study and sweep share.
GYM_SEED = typer.Option(None, "--seed", min=0, help="Data seed; run k uses seed + k.")
GYM_TRANSITIONS = typer.Option(None, min=2, help="Override the expert transitions.")
GYM_EPOCHS = typer.Option(None, min=1, help="Override the IRL epochs.")
GYM_EVAL_EPISODES = typer.Option(None, min=1, help="Override episodes per evaluation.")
GYM_TIMESTEPS = typer.Option(None, min=1, help="Override the RL steps per run.")
GYM_JOBS = typer.Option(2, "--jobs", min=1, help="Processes for the units.")
GYM_RAY = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP)
GYM_OVERWRITE = typer.Option(False, "--overwrite", help="Recompute units whose settings changed.")
GYM_QUIET = typer.Option(False, "--quiet", "-q", help="No progress bars.")


def _gym_preset(name: str, task: str, **overrides: int | None) -> Any:
    """The study preset ``name`` for ``task`` (or all) with the command line's overrides."""
    from pokerirl.gym.study import parse_tasks, study_preset

    return study_preset(name, tasks=parse_tasks(task), **overrides)


@gym_app.command("study")
def gym_study(
    task: str = typer.Argument(..., metavar="ENV|all", help="A task, e.g. MountainCar-v0, or all."),
    out: Path = typer.Option(..., "--out", "-o", help="The study folder."),
    preset_name: str = typer.Option("quick", "--preset", help="quick or paper: the budgets."),
    runs: int | None = typer.Option(None, "--runs", min=1, help="Runs per algorithm and reward."),
    seed: int | None = GYM_SEED,
    transitions: int | None = GYM_TRANSITIONS,
    epochs: int | None = GYM_EPOCHS,
    eval_episodes: int | None = GYM_EVAL_EPISODES,
    timesteps: int | None = GYM_TIMESTEPS,
    jobs: int = GYM_JOBS,
    ray: str | None = GYM_RAY,
    overwrite: bool = GYM_OVERWRITE,
    quiet: bool = GYM_QUIET,
) -> None:
    """The paper's Gymnasium study: shipped expert -> data -> IRL (AIRL and H-AIRL) -> RL (env
    reward, AIRL and H-AIRL rewards) -> summary.json, figures/ and report.md beside the
    authors' finals. Resumable: finished units are kept."""
    from pokerirl.gym.study import run_gym_study

    try:
        preset = _gym_preset(
            preset_name, task, runs=runs, seed=seed, transitions=transitions, epochs=epochs,
            eval_episodes=eval_episodes, rl_timesteps=timesteps,
        )  # fmt: skip
        result = run_gym_study(
            out,
            preset,
            backend=_backend(jobs, ray),
            overwrite=overwrite,
            progress=not quiet,
            say=typer.echo,
        )
    except (ValueError, ImportError, OSError, execution.ExecutionError) as error:
        fail(str(error))
    except KeyboardInterrupt:
        fail(INTERRUPTED, 130)
    typer.echo("")
    typer.echo(result.markdown)
    typer.echo(f"report: {out / 'report.md'}")


@app.command()
def sweep(
    env: str = typer.Argument(..., help="The task, e.g. MountainCar-v0."),
    param: list[str] = typer.Option(
        ..., "--param", help="NAME=V1,V2,...: alpha, beta, sigma_start or sigma_end; repeatable."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="The sweep folder."),
    preset_name: str = typer.Option("quick", "--preset", help="quick or paper: the budgets."),
    runs: int | None = typer.Option(None, "--runs", min=1, help="Runs per point."),
    seed: int | None = GYM_SEED,
    transitions: int | None = GYM_TRANSITIONS,
    epochs: int | None = GYM_EPOCHS,
    eval_episodes: int | None = GYM_EVAL_EPISODES,
    timesteps: int | None = GYM_TIMESTEPS,
    jobs: int = GYM_JOBS,
    ray: str | None = GYM_RAY,
    overwrite: bool = GYM_OVERWRITE,
    quiet: bool = GYM_QUIET,
) -> None:
    """One-factor-at-a-time ablation of H-AIRL (the paper's Figure 5): each point runs the IRL
    phase, then RL on its learned rewards; writes sweep.csv, sweep.json and PARAM.png."""
    from pokerirl.gym.study import GymStudyError
    from pokerirl.gym.sweep import parse_param, run_sweep

    try:
        params: dict[str, tuple[float, ...]] = {}
        for text in param:
            name, values = parse_param(text)
            if name in params:
                raise GymStudyError(f"--param {name} is given twice; list its values once")
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
            backend=_backend(jobs, ray),
            overwrite=overwrite,
            progress=not quiet,
            say=typer.echo,
        )
    except (ValueError, ImportError, OSError, execution.ExecutionError) as error:
        fail(str(error))
    except KeyboardInterrupt:
        fail(INTERRUPTED, 130)
    for row in result.rows:
        line = (
            f"{row['param']}={row['value']:g}: IRL return {row['irl_final_return_mean']:.1f} "
            f"+- {row['irl_final_return_std']:.1f}, RL return {row['rl_final_return_mean']:.1f} "
            f"+- {row['rl_final_return_std']:.1f}"
        )
        if row["final_alignment_mean"] is not None:
            line += f", alignment {100 * row['final_alignment_mean']:.1f}%"
        typer.echo(line)
    typer.echo(f"wrote {out / 'sweep.csv'} and {', '.join(str(p) for p in result.figures)}")
