"""One name per reward concept in the IRL core.

* :class:`RewardNet`: a learned reward *module* (imitation's idea). ``forward(obs, action,
  next_obs, done)`` is f, the discriminator's reward; :meth:`~RewardNet.transferable` is g,
  the part that depends on (s, a) only (all of f for ``state_action``; for ``shaped`` f
  adds γh(s') − h(s)); :meth:`~RewardNet.predict` is the same on numpy arrays.
  The default nets (:class:`~pokerirl.irl.nets.StateActionReward`,
  :class:`~pokerirl.irl.nets.ShapedReward`) satisfy it.
* :class:`PolicyNet`: a policy *module*, ``policy(obs, legal_mask)``: log π (B, K) for
  discrete actions (:class:`~pokerirl.irl.nets.DiscretePolicy`), (mean, log σ) for a
  Gaussian (:class:`~pokerirl.irl.nets.GaussianPolicy`); a
  :class:`~pokerirl.irl.heads.PolicyHead` reads its output.
* :data:`RewardFn`: a batched reward *callable* on numpy, ``(obs, actions) -> rewards``, what
  RL consumers take (:class:`pokerirl.irl.run.RewardFunction` is one, made by
  :func:`~pokerirl.irl.load_reward`). gym's ``RewardCallable`` is this type; agents'
  ``RewardFn`` widens it with the poker reward objects.

>>> from pokerirl.irl.nets import StateActionReward
>>> net = StateActionReward(obs_dim=3, action_dim=2, hidden=(4,))
>>> isinstance(net, RewardNet)
True
>>> net.predict(np.zeros((5, 3)), np.ones((5, 2))).dtype
dtype('float32')
>>> from pokerirl.irl.nets import DiscretePolicy
>>> isinstance(DiscretePolicy(obs_dim=3, num_actions=2, hidden=(4,)), PolicyNet)
True
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, runtime_checkable

import numpy as np
from torch import Tensor

RewardFn = Callable[[np.ndarray, np.ndarray], np.ndarray]


@runtime_checkable
class RewardNet(Protocol):
    """A learned reward module: f by ``forward``/``__call__`` with s' and done, g without.

    ``obs`` is (..., B, obs_dim), ``action`` (..., M, B, action_dim) (one-hots or simplex
    points for discrete actions), the result (..., M, B)."""

    obs_dim: int
    action_dim: int

    def forward(
        self,
        obs: Tensor,
        action: Tensor,
        next_obs: Tensor | None = None,
        done: Tensor | None = None,
    ) -> Tensor: ...

    def transferable(self, obs: Tensor, action: Tensor) -> Tensor:
        """g(s, a): the reward without the shaping terms."""
        ...

    def predict(
        self,
        obs: np.ndarray,
        action: np.ndarray,
        next_obs: np.ndarray | None = None,
        done: np.ndarray | None = None,
    ) -> np.ndarray:
        """float32 numpy rewards of numpy inputs (action vectors), f with s' and done, else g."""
        ...


@runtime_checkable
class PolicyNet(Protocol):
    """A policy module: ``forward(obs, legal_mask)`` with ``obs`` (..., B, obs_dim) gives
    log π (..., B, K) for discrete actions (illegal ones masked), (mean, log σ), each
    (..., B, k), for continuous ones (``legal_mask`` None)."""

    obs_dim: int
    action_dim: int

    def forward(
        self, obs: Tensor, legal_mask: Tensor | None = None
    ) -> Tensor | tuple[Tensor, Tensor]: ...
