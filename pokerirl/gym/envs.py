"""Gymnasium environments, made lazily: :func:`make_env` (``gymnasium.make`` with one clear
line for an unknown id) and :func:`require_gym` (one clear line when the ``pokerirl[gym]``
extra is missing).

Apart and light (Gymnasium is imported inside the functions): every part of the Gymnasium half
makes environments, :mod:`pokerirl.gym.episodes` below the experts
(:mod:`pokerirl.gym.expert_policies`) included, which evaluate with it.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

from pokerirl.errors import ConfigError, MissingExtra

if TYPE_CHECKING:
    import gymnasium


def require_gym() -> None:
    """Raise one clear line when the ``pokerirl[gym]`` extra is missing."""
    try:
        import gymnasium  # noqa: F401
        import stable_baselines3  # noqa: F401
    except ImportError as error:
        raise MissingExtra(
            f"pokerirl.gym needs the gym extra (pip install 'pokerirl[gym]'): {error}"
        ) from None


def make_env(env_id: str) -> gymnasium.Env:
    """``gymnasium.make(env_id)``, with a clear error for an unknown id."""
    require_gym()
    import gymnasium

    try:
        with warnings.catch_warnings():
            # Ant-v4 and HalfCheetah-v4 are kept on purpose (the paper's versions).
            warnings.filterwarnings(
                "ignore", message=".*is out of date", category=DeprecationWarning
            )
            return gymnasium.make(env_id)
    except gymnasium.error.Error as error:
        raise ConfigError(f"unknown environment {env_id!r}: {error}") from None
