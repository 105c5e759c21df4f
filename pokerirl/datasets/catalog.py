"""Named IRC data: the April 1995 sample shipped with pokerirl, the full IRC Poker Database
archive (``IRCdata.tgz``) and single months out of it, fetched into a cache.

A name stands wherever a month folder or archive does: :func:`resolve_sources` turns
``irc-199504`` into the shipped archive and a fetched name into its cached file, and leaves
any path that exists alone (a folder called ``irc-199504`` wins over the name).

``fetch`` downloads into ``$POKERIRL_DATA`` (default ``~/.cache/pokerirl/data``): the bytes go
to a ``.part`` file first, an interrupted download resumes with an HTTP ``Range`` request, and
the SHA-256 is checked before the file takes its name and before anything is read out of it.
A wrong sum deletes the download, so the cache holds nothing it did not hold before. The
University of Alberta publishes no sum for ``IRCdata.tgz``: the first fetch records what it got
(``sha256.json`` in the cache) and later fetches are held to it, unless a sum is given.

>>> find("irc-199504").hands
13426
>>> find("irc-holdem-199601").file
'holdem.199601.tgz'
>>> find("nope") is None
True
"""

from __future__ import annotations

import contextlib
import fcntl
import gzip
import hashlib
import http.client
import io
import json
import os
import re
import shutil
import tarfile
import tempfile
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import IO

from pokerirl.cache import cache_folder
from pokerirl.errors import ConfigError, InputError

SAMPLE_NAME = "irc-199504"
ARCHIVE_NAME = "irc"
SHIPPED_FOLDER = Path(__file__).resolve().parent / "data"
RECORDED_SUMS = "sha256.json"  # in the cache: the sums recorded at the first fetch
CHUNK = 1 << 16
# The shipped archive's members: every mtime is this one (1995-04-19 00:00 UTC, where the
# sample ends), so the same month folder packs to the same bytes on every machine.
PACKED_MTIME = 798249600

Progress = Callable[[int, int | None], None]  # (bytes so far, total bytes or None)


class Kind(StrEnum):
    """Where a dataset comes from."""

    SHIPPED = "shipped"  # package data: nothing to fetch
    ARCHIVE = "archive"  # the whole IRC Poker Database, downloaded
    MONTH = "month"  # one month archive, out of the whole one (or from a mirror's URL)


class Verified(StrEnum):
    """What a fetched file's SHA-256 was held to."""

    PUBLISHED = "published"  # the catalog's sum
    GIVEN = "given"  # the caller's sum
    RECORDED = "recorded"  # the sum recorded at an earlier fetch
    FIRST = "first fetch"  # nothing to hold it to: its sum is recorded now


@dataclass(frozen=True, kw_only=True)
class Dataset:
    """One named dataset: what it holds and where its bytes live."""

    name: str
    kind: Kind
    file: str  # its file name, in the package's data folder or in the cache
    description: str
    channels: tuple[str, ...]
    months: str
    hands: int | None  # None: not known before it is fetched
    size: int | None  # bytes of the file; None: not known before it is fetched
    sha256: str | None  # the published sum; None where nobody publishes one
    url: str | None  # where fetch downloads it from; None: shipped, or out of the archive

    def path(self, cache: Path | None = None) -> Path:
        """Where its file is (shipped) or will be (fetched)."""
        if self.kind is Kind.SHIPPED:
            return SHIPPED_FOLDER / self.file
        return (cache or cache_folder()) / self.file


SAMPLE = Dataset(
    name=SAMPLE_NAME,
    kind=Kind.SHIPPED,
    file="irc-199504.tar.gz",
    description="#holdem 10-20, the hands before 1995-04-19 of April 1995 (shipped)",
    channels=("holdem",),
    months="1995-04",
    hands=13_426,
    size=1_103_041,
    sha256="879442acd9969bf0403e10806342764eee8c588ee6bf9d59b9c2f56be14e34ce",
    url=None,
)
ARCHIVE = Dataset(
    name=ARCHIVE_NAME,
    kind=Kind.ARCHIVE,
    file="IRCdata.tgz",
    description="the IRC Poker Database, every channel (over 10 million hands; no published "
    "SHA-256)",
    # The archive's README.TXT: the 10-20 limit hold'em channels first, then the others.
    channels=("holdem", "holdem1", "holdemii", "botsonly", "h1-nobots", "holdem2", "holdem3",
              "holdempot", "nolimit", "tourney", "7stud", "7studhi", "omaha", "omahahi", "ohlpot",
              "omahapot", "ptourney"),
    months="1995-2001",
    hands=None,
    size=None,
    sha256=None,
    url="http://poker.cs.ualberta.ca/IRC/IRCdata.tgz",
)
_MONTH = re.compile(
    r"irc-(?P<channel>[a-z0-9][a-z0-9-]*)-(?P<month>(?:19|20)\d\d(?:0[1-9]|1[0-2]))"
)


def month_dataset(channel: str, month: str) -> Dataset:
    """``irc-<channel>-<YYYYMM>``: one month archive of ``IRCdata.tgz``."""
    return Dataset(
        name=f"irc-{channel}-{month}",
        kind=Kind.MONTH,
        file=f"{channel}.{month}.tgz",
        description=f"#{channel}, {month[:4]}-{month[4:]}, out of {ARCHIVE.file}",
        channels=(channel,),
        months=f"{month[:4]}-{month[4:]}",
        hands=None,
        size=None,
        sha256=None,
        url=None,
    )


CATALOG: tuple[Dataset, ...] = (SAMPLE, ARCHIVE)


def find(name: str) -> Dataset | None:
    """The dataset called ``name``, or None."""
    for dataset in CATALOG:
        if dataset.name == name:
            return dataset
    match = _MONTH.fullmatch(name)
    return month_dataset(match["channel"], match["month"]) if match else None


class NotFetched(InputError):
    """A fetchable dataset's name, before it was fetched."""

    def __init__(self, dataset: Dataset, cache: Path) -> None:
        super().__init__(f"{dataset.name}: not fetched yet (nothing at {cache / dataset.file})")
        self.dataset = dataset


class FetchError(InputError):
    """A download that did not complete: unreachable host, HTTP error, connection cut."""

    def __init__(self, message: str, *, url: str, offline: bool = False) -> None:
        super().__init__(message)
        self.url, self.offline = url, offline

    def __reduce__(self) -> tuple[object, ...]:  # pickles whole, as PokerIRLError does
        return (_fetch_error, (str(self), self.url, self.offline))


def _fetch_error(message: str, url: str, offline: bool) -> FetchError:
    return FetchError(message, url=url, offline=offline)


class ChecksumError(InputError):
    """A download whose SHA-256 is not the expected one (it was deleted)."""


def resolve_source(text: str | os.PathLike[str]) -> Path:
    """A month source as given: a path that exists, else a dataset name's file, else the path
    unchanged (the reader then says it is missing). :class:`NotFetched` for a fetchable name
    that is not in the cache."""
    path = Path(text)
    if os.path.lexists(path):
        return path
    dataset = find(os.fspath(text))
    if dataset is None:
        return path
    found = dataset.path()
    if dataset.kind is not Kind.SHIPPED and not found.is_file():
        raise NotFetched(dataset, found.parent)
    return found


def resolve_sources(sources: Sequence[str | os.PathLike[str]]) -> list[Path]:
    """:func:`resolve_source` of each source: what every month-taking command calls."""
    return [resolve_source(source) for source in sources]


# --------------------------------------------------------------------------- listing


@dataclass(frozen=True, kw_only=True)
class Listed:
    """A dataset in ``pokerirl data list``: its file where it is there, its size and sum."""

    dataset: Dataset
    path: Path | None  # None: not fetched
    size: int | None
    sha256: str | None  # the shipped or recorded sum


def listing(cache: Path | None = None) -> list[Listed]:
    """The shipped sample, the archive and every month in the cache, with where they are."""
    cache = cache or cache_folder()
    months = sorted(p.name for p in cache.glob("*.*.tgz")) if cache.is_dir() else []
    datasets = [*CATALOG]
    for name in months:
        channel, _, month = name.removesuffix(".tgz").rpartition(".")
        found = find(f"irc-{channel}-{month}")
        if found is not None:
            datasets.append(found)
    rows = []
    for dataset in datasets:
        path = dataset.path(cache)
        there = path.is_file()
        rows.append(
            Listed(
                dataset=dataset,
                path=path if there else None,
                size=path.stat().st_size if there else dataset.size,
                sha256=dataset.sha256 or _recorded_sum(cache, dataset.file),
            )
        )
    return rows


# --------------------------------------------------------------------------- fetching


@dataclass(frozen=True, kw_only=True)
class Fetched:
    """What :func:`fetch` left in the cache."""

    dataset: Dataset
    path: Path
    sha256: str
    verified: Verified
    downloaded: int  # bytes downloaded by this call (0: it was there already)


def fetch(
    dataset: Dataset,
    *,
    url: str | None = None,
    sha256: str | None = None,
    cache: Path | None = None,
    progress: Progress | None = None,
    timeout: float = 60.0,
) -> Fetched:
    """Put ``dataset`` in the cache (from ``url``: a mirror, a local file or ``file://``),
    its SHA-256 checked before it takes its name; return where it is.

    A month without a ``url`` is read out of the cached ``IRCdata.tgz``, which is fetched
    first when it is missing."""
    if dataset.kind is Kind.SHIPPED:
        path = dataset.path()
        return Fetched(dataset=dataset, path=path, sha256=_sha256_of(path),
                       verified=Verified.PUBLISHED, downloaded=0)  # fmt: skip
    cache = cache or cache_folder()
    sha256 = check_sha256(sha256)
    local = _local_path(url)
    if local is not None and not local.is_file():  # before the cache is touched
        raise InputError(f"{local}: {'not a file' if local.exists() else 'no such file'}")
    expected, verified = _expected(dataset, cache, sha256)
    target = dataset.path(cache)
    if target.is_file():
        digest = _sha256_of(target)
        if expected is not None and digest != expected:
            raise ChecksumError(
                f"{target}: SHA-256 {digest}, not the {verified} {expected}; delete it to fetch "
                "it again"
            )
        return _keep(dataset, cache, target, digest, verified, downloaded=0)
    made = not cache.exists()  # a cache this fetch makes goes again if it keeps nothing
    cache.mkdir(parents=True, exist_ok=True)
    part = cache / f".{dataset.file}.part"
    with _locked(part, cache if made else None):
        if dataset.kind is Kind.MONTH and url is None:
            archive = fetch(ARCHIVE, cache=cache, progress=progress, timeout=timeout)
            downloaded = archive.downloaded
            _month_out_of(archive.path, dataset.file, part)
        else:
            source = url or dataset.url
            assert source is not None  # the archive has one; a month without url is above
            downloaded = _download(source, part, progress=progress, timeout=timeout)
        digest = _sha256_of(part)
        if expected is not None and digest != expected:
            part.unlink()  # nothing of it is kept: the next fetch starts from zero
            raise ChecksumError(
                f"{dataset.name}: the download's SHA-256 is {digest}, not the {verified} "
                f"{expected}; nothing was kept"
            )
        os.replace(part, target)
    return _keep(dataset, cache, target, digest, verified, downloaded=downloaded)


def check_sha256(text: str | None) -> str | None:
    """A SHA-256 as given (any case), in lower case; :class:`ConfigError` if it is not one.

    >>> check_sha256("AB" * 32) == "ab" * 32
    True
    """
    if text is None:
        return None
    if not re.fullmatch(r"[0-9a-fA-F]{64}", text):
        raise ConfigError(f"{text!r} is not a SHA-256 (64 hexadecimal digits)")
    return text.lower()


def _local_path(url: str | None) -> Path | None:
    """The file a ``--url`` names, when it is a path or a ``file://`` URL."""
    if url is None:
        return None
    parsed = urllib.parse.urlparse(url)
    if parsed.scheme == "file":
        return Path(urllib.request.url2pathname(parsed.path))
    return Path(url) if parsed.scheme == "" or len(parsed.scheme) == 1 else None


def _expected(dataset: Dataset, cache: Path, given: str | None) -> tuple[str | None, Verified]:
    if given is not None:
        return given, Verified.GIVEN
    if dataset.sha256 is not None:
        return dataset.sha256, Verified.PUBLISHED
    recorded = _recorded_sum(cache, dataset.file)
    if recorded is not None:
        return recorded, Verified.RECORDED
    return None, Verified.FIRST


def _keep(
    dataset: Dataset, cache: Path, path: Path, digest: str, verified: Verified, *, downloaded: int
) -> Fetched:
    """Record the sum of a file the cache keeps (where none is published) and say so."""
    if dataset.sha256 is None and _recorded_sum(cache, dataset.file) != digest:
        recorded = _recorded(cache)
        recorded[dataset.file] = {"sha256": digest, "size": path.stat().st_size}
        _write_atomic(cache / RECORDED_SUMS, json.dumps(recorded, indent=2, sort_keys=True) + "\n")
    return Fetched(dataset=dataset, path=path, sha256=digest, verified=verified,
                   downloaded=downloaded)  # fmt: skip


def _recorded(cache: Path) -> dict[str, dict[str, object]]:
    path = cache / RECORDED_SUMS
    if not path.is_file():
        return {}
    try:
        found = json.loads(path.read_text())
    except (OSError, ValueError) as error:
        raise InputError(f"{path}: not a readable record of sums ({error})") from error
    if not isinstance(found, dict):
        raise InputError(f"{path}: not a record of sums (expected a JSON object)")
    return found


def _recorded_sum(cache: Path, file: str) -> str | None:
    """The SHA-256 recorded at ``file``'s first fetch, or None."""
    entry = _recorded(cache).get(file)
    found = entry.get("sha256") if isinstance(entry, dict) else None
    return found if isinstance(found, str) else None


def _write_atomic(path: Path, text: str) -> None:
    with tempfile.NamedTemporaryFile("w", dir=path.parent, prefix=f".{path.name}.",
                                     delete=False) as handle:  # fmt: skip
        handle.write(text)
    os.replace(handle.name, path)


def _remove_if_empty(folder: Path) -> None:
    with contextlib.suppress(OSError):
        folder.rmdir()


@contextlib.contextmanager
def _locked(part: Path, made: Path | None) -> Iterator[None]:
    """Hold ``part`` for this fetch: a second fetch of the same name is refused, not mixed.
    A part left empty (the host unreachable) is removed, and the cache too if it is empty."""
    with open(part, "ab") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise InputError(f"{part}: another fetch is writing it; wait for it") from None
        try:
            yield
        finally:
            if part.is_file() and part.stat().st_size == 0:
                part.unlink()
            if made is not None:
                _remove_if_empty(made)


def _sha256_of(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        while chunk := handle.read(CHUNK * 16):
            digest.update(chunk)
    return digest.hexdigest()


def _download(url: str, part: Path, *, progress: Progress | None, timeout: float) -> int:
    """Bytes of ``url`` into ``part``, resuming after what ``part`` holds (HTTP ``Range``);
    returns the bytes this call transferred."""
    local = _local_path(url)
    if local is not None:
        return _copy_local(local, part, progress)
    parsed = urllib.parse.urlparse(url)
    have = part.stat().st_size
    headers = {"User-Agent": "pokerirl"}
    if have:
        headers["Range"] = f"bytes={have}-"
    request = urllib.request.Request(url, headers=headers)
    try:
        response = urllib.request.urlopen(request, timeout=timeout)
    except urllib.error.HTTPError as error:
        if error.code == 416 and have:  # asked past the end: the part is whole
            return 0
        raise FetchError(f"{url}: HTTP {error.code} {error.reason}", url=url) from None
    except (urllib.error.URLError, OSError) as error:
        reason = getattr(error, "reason", error)
        raise FetchError(
            f"cannot reach {parsed.hostname} ({reason}); download {url} by hand", url=url,
            offline=True,
        ) from None  # fmt: skip
    with response:
        resumed = have and response.status == 206 and _range_start(response) == have
        if not resumed:
            have = 0  # the server sent the whole file: start again
        length = response.headers.get("Content-Length")
        total = have + int(length) if length and length.isdecimal() else None
        start = have
        with open(part, "ab" if resumed else "wb") as out:
            try:
                while chunk := response.read(CHUNK):
                    out.write(chunk)
                    have += len(chunk)
                    if progress is not None:
                        progress(have, total)
            except (http.client.HTTPException, OSError) as error:
                _cut(url, have, total, error)
        if total is not None and have < total:
            _cut(url, have, total, "closed early")
    return have - start


def _cut(url: str, have: int, total: int | None, why: object) -> None:
    of = f" of {total:,}" if total is not None else ""
    raise FetchError(
        f"{url}: the connection was cut after {have:,}{of} bytes ({why}); the part is kept, "
        "fetch again to resume",
        url=url,
    )


def _range_start(response: http.client.HTTPResponse) -> int | None:
    found = re.match(r"bytes (\d+)-", response.headers.get("Content-Range", ""))
    return int(found[1]) if found else None


def _copy_local(source: Path, part: Path, progress: Progress | None) -> int:
    total = source.stat().st_size
    done = 0
    with open(source, "rb") as handle, open(part, "wb") as out:
        while chunk := handle.read(CHUNK * 16):
            out.write(chunk)
            done += len(chunk)
            if progress is not None:
                progress(done, total)
    return done


def _month_out_of(archive: Path, member_name: str, part: Path) -> None:
    """Copy the month archive ``member_name`` out of ``archive`` (streamed) into ``part``."""
    try:
        with tarfile.open(archive, mode="r|*") as tar:
            for member in tar:
                if member.isfile() and Path(member.name).name == member_name:
                    inner = tar.extractfile(member)
                    assert inner is not None  # a regular file
                    with open(part, "wb") as out:
                        shutil.copyfileobj(inner, out, CHUNK * 16)
                    return
    except (tarfile.TarError, EOFError) as error:
        raise InputError(f"{archive}: not a readable tar archive ({error})") from error
    part.unlink()
    raise InputError(f"{archive}: holds no {member_name}")


# --------------------------------------------------------------------------- packing


def pack_month(month: Path, out: IO[bytes], *, readme: bytes) -> None:
    """A month folder as a .tar.gz of ``<channel>/<YYYYMM>/...`` with ``README.md`` first:
    members sorted, mtimes :data:`PACKED_MTIME`, no owners, a gzip header without a time or
    a name, so the same folder gives the same bytes (how the shipped sample was made)."""
    channel, name = month.parent.name, month.name
    files = sorted(p for p in month.rglob("*") if p.is_file())

    def add(tar: tarfile.TarFile, arcname: str, data: bytes) -> None:
        info = tarfile.TarInfo(arcname)
        info.size, info.mtime, info.mode = len(data), PACKED_MTIME, 0o644
        tar.addfile(info, io.BytesIO(data))

    with gzip.GzipFile(fileobj=out, mode="wb", compresslevel=9, mtime=0, filename="") as zipped:
        with tarfile.open(fileobj=zipped, mode="w", format=tarfile.USTAR_FORMAT) as tar:
            add(tar, "README.md", readme)
            for path in files:
                relative = path.relative_to(month).as_posix()
                add(tar, f"{channel}/{name}/{relative}", path.read_bytes())


def unpack_sample(into: Path) -> Path:
    """The shipped sample unpacked into ``into`` (its ``holdem/199504`` folder returned), for
    readers that need a folder; checked against its sum first."""
    path = SAMPLE.path()
    if _sha256_of(path) != SAMPLE.sha256:
        raise InputError(f"{path}: not the shipped sample (its SHA-256 differs)")
    with tarfile.open(path, mode="r:gz") as tar:
        tar.extractall(into, filter="data")
    return into / "holdem" / "199504"
