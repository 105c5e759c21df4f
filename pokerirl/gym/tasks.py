"""Which task an env id is: one of the paper's six (:data:`~pokerirl.gym.presets.TASKS`) or
any other registered Gymnasium environment, with the generic settings of
:func:`~pokerirl.gym.presets.generic_task` chosen by its action space (issue 34).

A paper task resolves without Gymnasium; another id is made once (``gymnasium.make``) to read
its spaces. Torch is never imported here.

>>> task("MountainCar-v0").generic
False
>>> task("CartPole-v1").discrete, task("CartPole-v1").generic
(True, True)
"""

from __future__ import annotations

import functools
import warnings

from pokerirl.errors import ConfigError, MissingExtra
from pokerirl.gym.presets import TASKS, Task, generic_task


def accepted() -> str:
    """What an env id may be, for the one line that refuses another."""
    return (
        f"choose one of {', '.join(TASKS)}, or another registered Gymnasium environment with "
        "a flat Box observation and a Discrete or flat Box action space, e.g. CartPole-v1 "
        "(gymnasium.pprint_registry() lists the registered ids)"
    )


def task(env_id: str) -> Task:
    """The paper's task ``env_id``, or a generic one for another registered environment.

    Raises:
        ConfigError: one line, if ``env_id`` is not registered, cannot be made, or has spaces
            the toolkit cannot learn from (images, dictionaries, multi-discrete actions).
    """
    if env_id in TASKS:
        return TASKS[env_id]
    return _generic(env_id)


@functools.cache  # made once per process: a generic task's spaces do not change
def _generic(env_id: str) -> Task:
    try:
        import gymnasium
    except ImportError as error:
        raise MissingExtra(
            f"task {env_id!r} needs the gym extra (pip install 'pokerirl[gym]'): {error}"
        ) from None
    from gymnasium import spaces

    if env_id not in gymnasium.registry:
        raise ConfigError(f"unknown task {env_id!r}; {accepted()}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # an old version's deprecation: refused below
            env = gymnasium.make(env_id)
    except gymnasium.error.Error as error:  # deprecated versions, missing optional packages
        raise ConfigError(f"task {env_id!r} cannot be made: {str(error).splitlines()[0]}") from None
    try:
        obs, action = env.observation_space, env.action_space
    finally:
        env.close()
    flat = isinstance(obs, spaces.Box) and len(obs.shape) == 1
    discrete = isinstance(action, spaces.Discrete)
    if not flat or not (discrete or (isinstance(action, spaces.Box) and len(action.shape) == 1)):
        raise ConfigError(
            f"task {env_id!r} has observation space {obs} and action space {action}; {accepted()}"
        )
    return generic_task(env_id, discrete=discrete)
