"""What ``--folds`` may say, and the settings of an imputation (torch-free: read by the
command line's defaults; the work is :mod:`pokerirl.poker.impute`).

>>> ImputeConfig().imputations, FoldsMode("impute")
(4, <FoldsMode.IMPUTE: 'impute'>)
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from pokerirl.errors import ConfigError
from pokerirl.game.encodings import ENCODING_SPECS, ENCODINGS, EncodingName


class FoldsMode(StrEnum):
    """What ingest does with the hands that end in a fold with nobody's cards shown."""

    DROP = "drop"  # leave them out (the table of before, byte for byte)
    IMPUTE = "impute"  # keep them, the hidden cards drawn from a posterior (docs/folds.md)


@dataclass(frozen=True, kw_only=True)
class ImputeConfig:
    """The settings of ``ingest --folds impute`` (and of EM's re-imputations).

    ``imputations``: K posterior draws per hidden player. ``behaviour``: a run folder whose
    policy is π_B; None fits π_B on the table itself, in ``behaviour_encoding``, by behaviour
    cloning (``behaviour_epochs``, the IRL policy net's defaults) on the observed rows and
    ``behaviour_rounds`` EM rounds. ``seed`` seeds the fitting and the draws.
    """

    imputations: int = 4
    behaviour: str | None = None
    behaviour_encoding: str = EncodingName.RLCARD
    behaviour_rounds: int = 5
    behaviour_epochs: int = 20
    seed: int = 0

    def __post_init__(self) -> None:
        if not 1 <= self.imputations <= 1000:
            raise ConfigError(f"imputations must be between 1 and 1000, got {self.imputations}")
        if self.behaviour_rounds < 0:
            raise ConfigError(f"behaviour rounds must be >= 0, got {self.behaviour_rounds}")
        if self.behaviour_epochs < 1:
            raise ConfigError(f"behaviour epochs must be >= 1, got {self.behaviour_epochs}")
        if self.seed < 0:
            raise ConfigError(f"seed must be non-negative, got {self.seed}")
        if self.behaviour_encoding not in {**ENCODINGS, **ENCODING_SPECS}:
            raise ConfigError(
                f"unknown behaviour encoding {self.behaviour_encoding!r} "
                f"(known: {', '.join(ENCODINGS)})"
            )
