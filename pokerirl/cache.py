"""The data cache folder: fetched datasets (:mod:`pokerirl.datasets.catalog`) and the tables
built once on a machine (the turn-equity table, :mod:`pokerirl.game.equity`)."""

from __future__ import annotations

import os
from pathlib import Path

DATA_VARIABLE = "POKERIRL_DATA"  # moves the cache folder
TURN_TABLE_NAME = "turn_equity_v1.npy"  # pokerirl data turn-table writes it there


def cache_folder() -> Path:
    """``$POKERIRL_DATA``, else ``$XDG_CACHE_HOME/pokerirl/data``, else ``~/.cache/...``."""
    given = os.environ.get(DATA_VARIABLE)
    if given:
        return Path(given).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "pokerirl" / "data"
