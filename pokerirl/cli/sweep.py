"""``pokerirl sweep``: which settings, if any, make a learned reward help on real hands."""

from __future__ import annotations

from pathlib import Path

import typer

from pokerirl.cli.app import app
from pokerirl.cli.data import MONTHS_HELP, months
from pokerirl.cli.errors import INTERRUPTED, echo, on_error, settings_from_options
from pokerirl.cli.fanout import RAY_HELP, command_backend
from pokerirl.cli.seeds import seed_list
from pokerirl.errors import UsageError

GYM_SWEEP_MOVED = (
    "'pokerirl sweep' is the poker sweep now; the Gymnasium one is 'pokerirl gym sweep {env}'"
)


@app.command()
@on_error(interrupted=INTERRUPTED)
def sweep(
    sources: list[Path] = typer.Argument(..., callback=months, help=MONTHS_HELP),
    out: Path = typer.Option(..., "--out", "-o", help="The sweep folder."),
    preset_name: str = typer.Option(
        "sample", "--preset", metavar="sample|smoke",
        help="sample (one axis at a time around the base cell; the April 1995 sample in a "
        "session on 2 cores) or smoke (seconds; its numbers mean nothing).",
    ),
    test: bool = typer.Option(
        False, "--test",
        help="Run the cell the choose split chose on the test split (the later hands), which "
        "nothing in the choice read.",
    ),
    runs: int | None = typer.Option(None, "--runs", min=1, max=100, help="IRL runs per reward."),
    seeds: str | None = typer.Option(
        None, "--seeds", callback=seed_list, metavar="SEEDS", help="DQN seeds, e.g. 0-3."
    ),
    jobs: int = typer.Option(2, "--jobs", min=1, help="Processes for training and play."),
    ray: str | None = typer.Option(None, "--ray", metavar="ADDRESS", help=RAY_HELP),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Recompute changed units, and the units that read them."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars."),
) -> None:
    """Sweep the settings of the poker pipeline on the earlier part of a month (the choose
    split), one axis at a time: encoding, folds, which players are the expert, algorithm and
    reward decay, the reward's transform and payoff weight, the DQN's opponent and budget.
    Chooses a cell by a rule fixed in advance; --test shows it on the later part. Writes
    OUT/<split>/sweep.md, sweep.json, sweep.csv, sweep.png. Resumable."""
    from pokerirl.seeds import seeds_as_written
    from pokerirl.studies.poker.sweep import Split, run_sweep, sweep_preset

    if sources and "-v" in sources[0].name and not sources[0].exists():
        raise UsageError(GYM_SWEEP_MOVED.format(env=sources[0].name))
    config = settings_from_options(
        sweep_preset, preset_name, runs=runs, jobs=jobs,
        seeds=None if seeds is None else tuple(seeds_as_written(seeds)),
    )  # fmt: skip
    result = run_sweep(
        sources, out, config, split=Split.TEST if test else Split.CHOOSE,
        backend=command_backend(jobs, ray), overwrite=overwrite, progress=not quiet, say=echo,
    )  # fmt: skip
    folder = out / result.split
    echo("")
    echo(f"{folder / 'sweep.md'}: {len(result.cells)} cells"
         + (f"; chosen: {result.chosen}" if result.chosen else ""))  # fmt: skip
