"""Where a poker reward comes from: :class:`RewardSource` resolves what a user typed (a run
folder of ``pokerirl train``, or ``authors:FILE``) once, in the driver: its bytes, checked,
and their fingerprint; a worker builds the reward from those bytes (:meth:`RewardSource.load`).

Apart from :mod:`pokerirl.poker.rewards` (what a reward is), which the authors' reward
(:mod:`pokerirl.poker.authors_reward`) builds on: this module imports both, neither imports it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from pokerirl.errors import InputError
from pokerirl.poker.rewards import (
    AUTHORS_PREFIX,
    ObsReward,
    PokerReward,
    is_authors_spec,
    read_capped,
    run_encoding,
)
from pokerirl.store import digest

AUTHORS_FILE = "authors.model"  # a shipped authors: file's name in a worker's folder
# An authors' reward is about 20 KB; a run's reward.pt and config.json are small nets' and a
# record's. Far larger files are not rewards: refused before they are read (issue 36).
MAX_AUTHORS_BYTES = 1024 * 1024
MAX_RUN_FILE_BYTES = 64 * 1024 * 1024


@dataclass(frozen=True, kw_only=True)
class RewardSource:
    """A reward a user named (a run folder of ``pokerirl train``, or ``authors:FILE``),
    resolved once: its files read, checked and hashed here, in the driver. It travels to
    workers as it is (plain bytes), and :meth:`load` builds the reward from those bytes, so
    no worker reads the user's files again.

    ``fingerprint`` is ``sha256:<hex>`` over the files' bytes in order (a run's ``reward.pt``
    then ``config.json``; an authors' file), as agent and study records have named rewards.
    """

    spec: str
    files: tuple[tuple[str, bytes], ...] = field(repr=False)
    fingerprint: str

    @property
    def is_authors(self) -> bool:
        return is_authors_spec(self.spec)

    @classmethod
    def resolve(cls, spec: str | os.PathLike[str]) -> RewardSource:
        """Read and check ``spec``; :class:`~pokerirl.errors.InputError` (one line) when it
        is neither a poker reward run nor an ``authors:`` file."""
        source = cls.read(spec)
        source.load()  # every problem now, in one line naming the user's files
        return source

    @classmethod
    def read(cls, spec: str | os.PathLike[str]) -> RewardSource:
        """Read and hash ``spec``'s files without checking what they hold (:meth:`resolve`
        checks); a missing file is one line."""
        from pokerirl.irl.run import REWARD_RUN_FILES

        text = str(spec)
        if is_authors_spec(text):
            path = Path(text.removeprefix(AUTHORS_PREFIX))
            if not os.path.lexists(path):
                raise InputError(f"{text}: no such file (authors:FILE names an authors' reward)")
            data = read_capped(path, MAX_AUTHORS_BYTES, where=text)
            files: tuple[tuple[str, bytes], ...] = ((AUTHORS_FILE, data),)
        else:
            for name in REWARD_RUN_FILES:
                if not os.path.lexists(Path(text) / name):
                    raise InputError(f"{text}: not a reward run (no {name}) nor authors:FILE")
            files = tuple(
                (name, read_capped(Path(text) / name, MAX_RUN_FILE_BYTES, where=f"{text}/{name}"))
                for name in REWARD_RUN_FILES
            )
        return cls(spec=text, files=files, fingerprint=digest(b"".join(d for _, d in files)))

    def load(self) -> PokerReward:
        """The reward, built from the bytes (never from the user's files)."""
        from pokerirl.irl.run import CONFIG_FILE, REWARD_FILE, parse_run_config, reward_from_bytes

        files = dict(self.files)
        if self.is_authors:
            from pokerirl.poker.authors_reward import AuthorsReward, read_authors_bytes

            weights = read_authors_bytes(files[AUTHORS_FILE], where=self.spec)
            return AuthorsReward(weights, name=self.spec)
        run = Path(self.spec)
        record = parse_run_config(files[CONFIG_FILE], where=run / CONFIG_FILE)
        encoding = run_encoding(run, record)
        fn = reward_from_bytes(record, files[REWARD_FILE], where=run / REWARD_FILE)
        return ObsReward(fn, name=self.spec, fingerprint=self.fingerprint, encoding=encoding)

    @property
    def encoding(self) -> str | None:
        """The encoding the reward reads (its run's), or None for an authors' reward (which
        reads its own 61-d state of the cards)."""
        if self.is_authors:
            return None
        from pokerirl.irl.run import CONFIG_FILE, parse_run_config

        record = parse_run_config(dict(self.files)[CONFIG_FILE], where=self.spec)
        return run_encoding(Path(self.spec), record).spec


def load_reward_source(spec: str | os.PathLike[str]) -> PokerReward:
    """The reward of a run folder or of ``authors:FILE`` (:meth:`RewardSource.resolve`)."""
    return RewardSource.resolve(spec).load()
