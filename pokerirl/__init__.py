"""pokerirl: learn reward functions from real poker play.

IRC Poker Database ingest, AIRL / Hybrid-AIRL reward learning, DQN agents and tournaments,
all in RLCard's heads-up limit hold'em encoding.

The public API is the names in :data:`__all__` (``docs/architecture.md``, "The public
API"), each imported from its own module on first use, so ``import pokerirl`` (and
``pokerirl --help``) stays light: torch loads only with the first name that needs it.

* reward learning (:mod:`pokerirl.irl`): :class:`Transitions`, :class:`AIRLConfig`,
  :func:`train`, :func:`train_into`, :func:`load_reward`, :func:`load_policy`;
  the ``imitation`` library's arrays to and from :class:`Transitions`
  (:func:`from_imitation_transitions`, :func:`to_imitation_transitions`,
  :func:`from_imitation_trajectories`, :func:`to_imitation_trajectories`);
* poker play (:mod:`pokerirl.game`, :mod:`pokerirl.agents`): :func:`play_match`, the
  :class:`Agent` protocol, :func:`load_agent`, :func:`resolve_agent`, and
  :class:`RLCardAgent` (any agent, playing inside RLCard);
* Gymnasium (:mod:`pokerirl.gym`, the ``pokerirl[gym]`` extra): :func:`learned_reward_env`,
  :func:`load_expert`;
* encodings (:mod:`pokerirl.game.encodings`): :class:`Encoding`, :func:`get_encoding`.

>>> import pokerirl
>>> pokerirl.resolve_agent("raise").name
'raise'
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

# Each public name and the module it is read from: the subpackage's own surface where it has
# one (its __all__ lists the name), the defining module otherwise.
_PUBLIC: dict[str, str] = {
    "Transitions": "pokerirl.irl",
    "AIRLConfig": "pokerirl.irl",
    "train": "pokerirl.irl",
    "train_into": "pokerirl.irl",
    "load_reward": "pokerirl.irl",
    "load_policy": "pokerirl.irl",
    "from_imitation_transitions": "pokerirl.irl",
    "to_imitation_transitions": "pokerirl.irl",
    "from_imitation_trajectories": "pokerirl.irl",
    "to_imitation_trajectories": "pokerirl.irl",
    "play_match": "pokerirl.game",
    "Agent": "pokerirl.game",
    "load_agent": "pokerirl.agents",
    "resolve_agent": "pokerirl.agents",
    "RLCardAgent": "pokerirl.agents",
    "learned_reward_env": "pokerirl.gym",
    "load_expert": "pokerirl.gym",
    "Encoding": "pokerirl.game.encodings",
    "get_encoding": "pokerirl.game.encodings",
}

__all__ = [*_PUBLIC]  # and __version__, as every package has it


def __getattr__(name: str) -> Any:
    # PEP 562: a public name is imported when first read (torch takes seconds), then cached.
    if name in _PUBLIC:
        value = getattr(importlib.import_module(_PUBLIC[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'pokerirl' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_PUBLIC})
