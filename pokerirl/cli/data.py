"""``pokerirl data``: the named IRC data (``list``, ``fetch``), and :func:`months`, the one
place where a month argument's dataset names become files (``ingest irc-199504``)."""

from __future__ import annotations

from pathlib import Path

import typer

from pokerirl.cli.app import app
from pokerirl.cli.errors import echo, settings_from_options
from pokerirl.errors import InputError, UsageError

data_app = typer.Typer(
    help="The named IRC data: the shipped April 1995 sample and the IRC Poker Database archive.",
    no_args_is_help=True,
)
app.add_typer(data_app, name="data")

MONTHS_HELP = (
    "Month folders, folders of months, month .tgz archives or IRCdata.tgz, or a dataset name "
    "(irc-199504, shipped; a fetched one: pokerirl data list)."
)


def months(sources: list[Path]) -> list[Path]:
    """A month argument's callback: each dataset name as its file (a path that exists wins);
    a fetchable name not fetched yet is one line saying how to fetch it."""
    from pokerirl.datasets.catalog import NotFetched, resolve_sources

    try:
        return resolve_sources(sources)
    except NotFetched as error:
        raise InputError(f"{error}; fetch it: pokerirl data fetch {error.dataset.name}") from None


def _megabytes(size: int | None) -> str:
    return "?" if size is None else f"{size / 1e6:,.1f} MB"


@data_app.command("list")
def list_data() -> None:
    """The shipped sample, the downloadable archive and the fetched months: name, size, hands,
    channels, months, and where each is (the cache folder: $POKERIRL_DATA)."""
    from pokerirl.cache import TURN_TABLE_NAME, cache_folder
    from pokerirl.datasets.catalog import listing

    cache = cache_folder()
    rows = [("name", "size", "hands", "channels", "months", "where")]
    for item in listing(cache):
        dataset = item.dataset
        channels = dataset.channels
        shown = ",".join(channels) if len(channels) <= 3 else f"{len(channels)} channels"
        rows.append((
            dataset.name,
            _megabytes(item.size),
            "?" if dataset.hands is None else f"{dataset.hands:,}",
            shown,
            dataset.months,
            str(item.path) if item.path is not None else "not fetched",
        ))  # fmt: skip
    widths = [max(len(row[k]) for row in rows) for k in range(len(rows[0]) - 1)]
    for row in rows:
        echo("  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=False))
             + "  " + row[-1])  # fmt: skip
    built = (cache / TURN_TABLE_NAME).is_file()
    table = "built" if built else "not built (pokerirl data turn-table)"
    echo(f"cache: {cache} (move it with $POKERIRL_DATA); irc-<channel>-<YYYYMM> fetches one "
         f"month out of IRCdata.tgz; the turn-equity table: {table}")  # fmt: skip


@data_app.command()
def fetch(
    name: str = typer.Argument(
        ..., help="irc (IRCdata.tgz, the whole database) or irc-<channel>-<YYYYMM> (one month)."
    ),
    url: str | None = typer.Option(
        None, "--url", metavar="URL|FILE",
        help="Download from this mirror URL, or copy this local file (what you downloaded by "
        "hand), instead of the archive's own address.",
    ),
    sha256: str | None = typer.Option(
        None, "--sha256", metavar="HEX",
        help="The SHA-256 the file must have (default: the published one, else the one "
        "recorded at the first fetch).",
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """Download a dataset into the cache ($POKERIRL_DATA, default ~/.cache/pokerirl/data),
    SHA-256 checked before it is used; an interrupted download resumes when rerun. Then its
    name stands for it wherever a month is taken (pokerirl ingest NAME --out t.parquet)."""
    from tqdm import tqdm

    from pokerirl.datasets.catalog import FetchError, Kind, Verified, check_sha256, find
    from pokerirl.datasets.catalog import fetch as fetch_dataset

    sha256 = settings_from_options(check_sha256, sha256)  # a malformed sum: a usage error

    dataset = find(name)
    if dataset is None:
        raise UsageError(
            f"unknown dataset {name!r} (irc-199504, irc, or irc-<channel>-<YYYYMM>: "
            "pokerirl data list)"
        )
    if dataset.kind is Kind.SHIPPED:
        echo(f"{name}: shipped with pokerirl, nothing to fetch ({dataset.path()})")
        return
    bars: list[tqdm] = []  # made at the first byte: an offline fetch shows no empty bar

    def progress(done: int, total: int | None) -> None:
        if not bars:
            bars.append(tqdm(total=total, unit="B", unit_scale=True, unit_divisor=1024,
                             desc=name, disable=quiet))  # fmt: skip
        bar = bars[0]
        if total is not None and bar.total != total:
            bar.total = total
        bar.update(done - bar.n)

    try:
        fetched = fetch_dataset(dataset, url=url, sha256=sha256, progress=progress)
    except FetchError as error:
        if not error.offline:
            raise
        raise InputError(f"{error}, then: pokerirl data fetch {name} --url FILE") from None
    finally:
        for bar in bars:
            bar.close()
    checked = {
        Verified.PUBLISHED: "matches the published sum",
        Verified.GIVEN: "matches --sha256",
        Verified.RECORDED: "matches the sum recorded at its first fetch",
        Verified.FIRST: "not verified (no sum is published): recorded for later fetches",
    }[fetched.verified]
    echo(f"{name}: {fetched.path} ({_megabytes(fetched.path.stat().st_size)}; SHA-256 "
         f"{fetched.sha256} {checked})")  # fmt: skip


@data_app.command("turn-table")
def turn_table_command(
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """Build the exact turn-equity table into the cache ($POKERIRL_DATA): every turn board up
    to a permutation of the suits (16,432) by every hole pair, 87 MB, about two minutes of
    one core, once. The strength encoding then reads a turn state's equity from it instead
    of counting its 45,540 cases (the same values, bit for bit): DQN training, local best
    response and fold imputation on that encoding run faster. Already built: checked."""
    from tqdm import tqdm

    from pokerirl.game.equity import (
        TURN_CLASSES,
        TURN_TABLE_SHA256,
        build_turn_table,
        turn_table,
        turn_table_path,
    )

    path = turn_table_path()
    if path.is_file():
        turn_table()  # checked: InputError for a file that is not the table
        echo(f"{path}: built, SHA-256 {TURN_TABLE_SHA256} as recorded")
        return
    with tqdm(total=TURN_CLASSES, unit="board", desc="turn table", disable=quiet) as bar:
        try:
            build_turn_table(path, on_class=lambda _: bar.update())  # its bytes checked
        except OSError as error:
            where = error.filename if error.filename and Path(error.filename) != path else None
            why = "not a folder" if isinstance(error, FileExistsError) else error.strerror
            about = f" ({where}: {why})" if where else f": {why or error}"
            raise InputError(f"cannot write {path}{about}") from None
    echo(f"{path}: {path.stat().st_size / 1e6:,.1f} MB, SHA-256 {TURN_TABLE_SHA256}")
