"""The ``pokerirl`` command line: thin typer commands over the library."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="pokerirl",
    help="Learn reward functions from real poker play (AIRL / Hybrid-AIRL on IRC hand histories).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def fail(message: str, code: int = 1) -> None:
    """Print a one-line error to stderr and exit non-zero, without a traceback."""
    typer.secho(f"error: {message}", err=True, fg=typer.colors.RED)
    raise typer.Exit(code)


@app.command()
def version() -> None:
    """Print the package version."""
    from pokerirl import __version__

    typer.echo(__version__)


@app.command()
def train(
    table: str = typer.Argument(..., help="Parquet decision table written by `pokerirl ingest`."),
    out: str = typer.Option(..., "--out", help="Run directory for checkpoints, metrics and plots."),
    algo: str = typer.Option("hairl", "--algo", help="hairl or airl (picks the defaults)."),
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
    """Learn a reward function with AIRL or Hybrid-AIRL from an expert decision table."""
    import torch

    from pokerirl.irl import load_config, train_table

    if threads < 1:
        fail("--threads must be at least 1")
    torch.set_num_threads(threads)

    widths = None
    if hidden is not None:
        try:
            widths = tuple(int(w) for w in hidden.split(",") if w.strip())
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
        summary = train_table(
            table, out, algo=algo, config=settings, device=device, progress=not quiet
        )
    except (ValueError, OSError) as error:
        fail(str(error))
    last = summary.metrics[-1]
    typer.echo(
        f"{algo}: {len(summary.metrics)} epochs on {summary.train_rows} rows "
        f"({summary.samples_per_second:,.0f} samples/s); validation alignment "
        f"{last['val_alignment']:.3f} vs majority {last['majority_alignment']:.3f} "
        f"on {summary.val_rows} rows"
    )
    typer.echo(f"wrote {summary.out_dir}: reward.pt, policy.pt, config.json, metrics, plots")
