"""The paper's Gymnasium half: task presets, SB3 experts, expert data, the IRL phase
(:mod:`pokerirl.gym.irl`), the RL phase, and the ``gym expert`` and ``gym rl`` folders
(:mod:`pokerirl.gym.jobs`).

Gymnasium and Stable-Baselines3 (the ``pokerirl[gym]`` extra) are imported lazily, inside the
functions that need them, so importing :mod:`pokerirl.gym.presets` costs a poker-only user
nothing.
"""

from __future__ import annotations

import importlib
from typing import Any

# The public surface, each name imported from its module on first use (torch, and with the
# functions Gymnasium and SB3, load then).
_LAZY = {
    "learned_reward_env": "rewards",
    "load_expert": "expert_policies",
}

__all__ = [*_LAZY]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f"pokerirl.gym.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'pokerirl.gym' has no attribute {name!r}")
