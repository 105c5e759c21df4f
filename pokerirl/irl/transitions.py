"""``Transitions``: the one type of expert data the trainer reads, for poker and environments.

Rows are expert decisions (s, a) with, optionally, the next state s', whether the episode
ended there, the environment's reward and the legal actions. Every row has a group id (a
poker hand, an environment episode): the train/validation split never cuts a group.

Rows may carry a **weight** (``weights``: every loss, baseline and alignment metric is then a
weighted mean) and an **imputed** flag (``imputed``: rows whose inputs were imputed rather
than observed, e.g. several weighted guesses of a hidden state; the validation metrics are
then also reported for the observed and the imputed rows apart). Without them every row
counts once, exactly as before.

Poker tables come in through :func:`pokerirl.poker.read_table` (which builds them with
:meth:`Transitions.from_arrays`: this module knows nothing of poker); environment rollouts
through :meth:`Transitions.from_parquet` (the schema ``pokerirl gym collect`` writes) or
:meth:`Transitions.from_arrays`.

>>> t = Transitions.from_arrays(np.eye(4, 3), np.array([0, 1, 2, 0]), groups=np.array([0, 0, 1, 1]))
>>> t.discrete, t.action_dim, len(t)
(True, 3, 4)
>>> train, val, val_groups = t.split(val_fraction=0.5, seed=0)
>>> len(train), len(val), len(val_groups)
(2, 2, 1)
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import numbers
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor

from pokerirl.errors import InputError
from pokerirl.settings import MAX_ACTIONS

ENV_COLUMNS = ("obs", "action", "reward", "next_obs", "done", "episode")


def _described(value: object) -> str:
    shape = getattr(value, "shape", None)
    return type(value).__name__ + ("" if shape is None else f" of shape {tuple(shape)}")


def _check_tensor(
    name: str, value: object, *, ndim: int, floating: bool = False, boolean: bool = False
) -> None:
    """``value`` is a tensor of ``ndim`` dimensions (floating and finite, or bool, or an
    integer or float tensor for actions); TypeError or InputError naming ``name``."""
    if not isinstance(value, Tensor):
        hint = " (Transitions.from_arrays takes numpy)" if isinstance(value, np.ndarray) else ""
        raise TypeError(f"Transitions.{name} must be a torch.Tensor{hint}, got {_described(value)}")
    if value.ndim != ndim:
        raise InputError(
            f"Transitions.{name} must have {ndim} dimension(s), got shape {tuple(value.shape)}"
        )
    if boolean and value.dtype != torch.bool:
        raise TypeError(f"Transitions.{name} must be a bool tensor, got {value.dtype}")
    if floating and not value.is_floating_point():
        raise TypeError(f"Transitions.{name} must be a float tensor, got {value.dtype}")
    if value.dtype == torch.bool and not boolean:
        raise TypeError(f"Transitions.{name} must be numbers, got a bool tensor")
    if value.is_floating_point() and not bool(torch.isfinite(value).all()):
        rows = (~torch.isfinite(value.reshape(len(value), -1))).any(dim=1)
        raise InputError(
            f"Transitions.{name} holds NaN or infinity ({int(rows.sum())} row(s), the first "
            f"row {int(rows.nonzero()[0])})"
        )


@dataclass(frozen=True, kw_only=True, eq=False)
class Transitions:
    """Expert transitions as tensors (``groups`` is numpy: strings or integers)."""

    obs: Tensor  # (N, d) float32
    actions: Tensor  # (N,) int64 for discrete actions, (N, k) float32 for continuous ones
    groups: np.ndarray  # (N,) group id per row: hand_id strings, episode numbers
    next_obs: Tensor | None = None  # (N, d) float32
    dones: Tensor | None = None  # (N,) bool: the group's (player's) last decision
    rewards: Tensor | None = None  # (N,) float32 environment reward
    legal_mask: Tensor | None = None  # (N, K) bool, discrete only
    num_actions: int | None = None  # K, discrete only
    action_low: tuple[float, ...] | None = None  # box bounds, continuous only
    action_high: tuple[float, ...] | None = None
    weights: Tensor | None = None  # (N,) float32 > 0: each row's weight in every mean
    imputed: Tensor | None = None  # (N,) bool: the row's inputs are imputed, not observed

    def __post_init__(self) -> None:
        # Checked whole here, so that every later step (split, the trainer, the metrics) can
        # trust it: a NaN observation trained to a NaN reward without a word.
        _check_tensor("obs", self.obs, ndim=2, floating=True)
        n, width = self.obs.shape
        _check_tensor("actions", self.actions, ndim=1 if self.discrete else 2)
        if not isinstance(self.groups, np.ndarray) or self.groups.ndim != 1:
            raise TypeError(
                f"Transitions.groups must be a 1-d numpy array, got {_described(self.groups)}"
            )
        if self.discrete:
            self._check_discrete()
        else:
            self._check_continuous()
        for name in ("actions", "groups", "next_obs", "dones", "rewards", "legal_mask",
                     "weights", "imputed"):  # fmt: skip
            value = getattr(self, name)
            if value is not None and len(value) != n:
                raise InputError(f"Transitions.{name} has {len(value)} rows, obs has {n}")
        if (self.next_obs is None) != (self.dones is None):
            raise InputError("Transitions need next_obs and dones together")
        if self.next_obs is not None:
            _check_tensor("next_obs", self.next_obs, ndim=2, floating=True)
            if self.next_obs.shape[1] != width:
                raise InputError(
                    f"Transitions.next_obs is {self.next_obs.shape[1]} wide, obs {width}"
                )
        for name in ("dones", "imputed"):
            if getattr(self, name) is not None:
                _check_tensor(name, getattr(self, name), ndim=1, boolean=True)
        if self.rewards is not None:
            _check_tensor("rewards", self.rewards, ndim=1, floating=True)
        if self.weights is not None:
            _check_tensor("weights", self.weights, ndim=1, floating=True)
            if bool((self.weights <= 0).any()):
                raise InputError("row weights must be finite and positive")

    def _check_discrete(self) -> None:
        k = self.num_actions
        if isinstance(k, numbers.Integral) and not isinstance(k, bool):
            k = int(k)  # numpy's integers too
            object.__setattr__(self, "num_actions", k)
        if isinstance(k, bool) or not isinstance(k, int) or not 1 <= k <= MAX_ACTIONS:
            raise InputError(
                f"discrete Transitions need num_actions, an integer in 1..{MAX_ACTIONS}, got {k!r}"
            )
        if len(self.actions) and not (0 <= int(self.actions.min()) <= int(self.actions.max()) < k):
            raise InputError(
                f"Transitions.actions must lie in 0..{k - 1} (num_actions {k}), got "
                f"{int(self.actions.min())}..{int(self.actions.max())}"
            )
        if self.legal_mask is not None:
            _check_tensor("legal_mask", self.legal_mask, ndim=2, boolean=True)
            if self.legal_mask.shape[1] != k:
                raise InputError(
                    f"Transitions.legal_mask is {self.legal_mask.shape[1]} wide, num_actions {k}"
                )

    def _check_continuous(self) -> None:
        if self.legal_mask is not None or self.num_actions is not None:
            raise InputError("continuous Transitions take no legal_mask or num_actions")
        k = self.actions.shape[1]
        for name in ("action_low", "action_high"):
            bound = getattr(self, name)
            if not isinstance(bound, tuple) or len(bound) != k or not all(
                isinstance(b, int | float) and not isinstance(b, bool) and math.isfinite(b)
                for b in bound
            ):  # fmt: skip
                raise InputError(
                    f"continuous Transitions need {name}, {k} finite numbers, got {bound!r}"
                )
        if not all(lo <= hi for lo, hi in zip(self.action_low, self.action_high, strict=True)):  # type: ignore[arg-type]
            raise InputError("Transitions.action_low must not lie above action_high")

    @classmethod
    def from_arrays(
        cls,
        obs: Any,
        actions: Any,
        *,
        groups: Any,
        next_obs: Any = None,
        dones: Any = None,
        rewards: Any = None,
        legal_mask: Any = None,
        num_actions: int | None = None,
        low: Sequence[float] | None = None,
        high: Sequence[float] | None = None,
        weights: Any = None,
        imputed: Any = None,
    ) -> Transitions:
        """From numpy arrays (or tensors). Integer ``actions`` (N,) are discrete (``num_actions``
        defaults to the legal mask's width, else max + 1); float ones (N, k) are continuous
        (bounds default to the actions' range). ``weights`` and ``imputed``: see the module
        docstring (None: every row observed, weight 1)."""
        actions_t = torch.tensor(np.asarray(actions))
        discrete = not actions_t.is_floating_point()
        opt = lambda x, dtype: None if x is None else torch.tensor(np.asarray(x), dtype=dtype)  # noqa: E731
        mask = opt(legal_mask, torch.bool)
        if discrete:
            actions_t = actions_t.long().reshape(-1)
            if num_actions is None:
                num_actions = mask.shape[1] if mask is not None else int(actions_t.max()) + 1
            bounds: dict[str, Any] = {"num_actions": num_actions}
        else:
            actions_t = actions_t.float().reshape(len(actions_t), -1)
            lo = actions_t.min(dim=0).values if low is None else torch.as_tensor(low)
            hi = actions_t.max(dim=0).values if high is None else torch.as_tensor(high)
            hi = torch.where(hi > lo, hi, lo + 1)  # a constant dimension still needs a box
            bounds = {"action_low": tuple(lo.tolist()), "action_high": tuple(hi.tolist())}
        return cls(
            obs=torch.tensor(np.asarray(obs), dtype=torch.float32),
            actions=actions_t,
            groups=np.asarray(groups),
            next_obs=opt(next_obs, torch.float32),
            dones=opt(dones, torch.bool),
            rewards=opt(rewards, torch.float32),
            legal_mask=mask,
            weights=opt(weights, torch.float32),
            imputed=opt(imputed, torch.bool),
            **bounds,
        )

    @classmethod
    def from_parquet(
        cls,
        path: str | os.PathLike[str],
        *,
        low: Sequence[float] | None = None,
        high: Sequence[float] | None = None,
    ) -> Transitions:
        """Environment rollouts: columns ``obs`` and ``next_obs`` (fixed_size_list<float>[d]),
        ``action`` (int64, or fixed_size_list<float>[k]), ``reward`` (float), ``done`` (bool),
        ``episode`` (int). Bad files raise ``ValueError`` naming the file."""
        import pyarrow as pa

        from pokerirl.parquet import fixed_width, read_parquet

        path = Path(path)
        table = read_parquet(path, ENV_COLUMNS, what="rollouts")
        if table.num_rows == 0:
            raise InputError(f"{path} is empty: no transitions")
        for name in ENV_COLUMNS:
            if table.column(name).null_count:
                raise InputError(f"{path}: column {name!r} has null values")
        obs = fixed_width(table, "obs", None, str(path), floating=True)
        next_obs = fixed_width(table, "next_obs", obs.shape[1], str(path), floating=True)
        action_type = table.column("action").type
        if pa.types.is_integer(action_type):
            actions: np.ndarray = table.column("action").to_numpy().astype(np.int64)
        elif pa.types.is_fixed_size_list(action_type):
            actions = fixed_width(table, "action", None, str(path), floating=True)
            actions = actions.astype(np.float32)
        else:
            raise InputError(f"{path}: column 'action' must be int64 or fixed_size_list<float>")
        if not pa.types.is_boolean(table.column("done").type):
            raise InputError(f"{path}: column 'done' must be bool")
        for name in ("reward", "episode"):
            kind = table.column(name).type
            if not (pa.types.is_floating(kind) or pa.types.is_integer(kind)):
                raise InputError(f"{path}: column {name!r} must be numeric, got {kind}")
        rewards = table.column("reward").to_numpy().astype(np.float32)
        # NaN or infinity trains to a NaN reward without a word, and its metrics are not JSON.
        for name, values in (("obs", obs), ("next_obs", next_obs), ("action", actions),
                             ("reward", rewards)):  # fmt: skip
            finite = np.isfinite(values).reshape(len(values), -1).all(axis=1)
            if not finite.all():
                row = int(np.flatnonzero(~finite)[0])
                raise InputError(
                    f"{path}: column {name!r} holds NaN or infinity ({int((~finite).sum())} "
                    f"row(s), the first row {row})"
                )
        return cls.from_arrays(
            obs,
            actions,
            groups=table.column("episode").to_numpy().astype(np.int64),
            next_obs=next_obs,
            dones=table.column("done").to_numpy(zero_copy_only=False),
            rewards=rewards,
            low=low,
            high=high,
        )

    # ------------------------------------------------------------------ properties

    @property
    def discrete(self) -> bool:
        return not self.actions.is_floating_point()

    @property
    def obs_dim(self) -> int:
        return self.obs.shape[1]

    @property
    def action_dim(self) -> int:
        """K for discrete actions, k for continuous ones."""
        return int(self.num_actions) if self.discrete else self.actions.shape[1]  # type: ignore[arg-type]

    def __len__(self) -> int:
        return len(self.obs)

    def action_vectors(self) -> Tensor:
        """What the reward net reads: one-hots (N, K), or the continuous actions."""
        if self.discrete:
            return torch.nn.functional.one_hot(self.actions, self.action_dim).float()
        return self.actions

    def subset(self, index: np.ndarray | Tensor) -> Transitions:
        """Rows ``index`` (integer indices or a bool mask)."""
        index_t = torch.as_tensor(np.asarray(index)) if isinstance(index, np.ndarray) else index
        index_np = index_t.cpu().numpy()
        pick = lambda t: None if t is None else t[index_t]  # noqa: E731
        return dataclasses.replace(
            self,
            obs=self.obs[index_t],
            actions=self.actions[index_t],
            groups=self.groups[index_np],
            next_obs=pick(self.next_obs),
            dones=pick(self.dones),
            rewards=pick(self.rewards),
            legal_mask=pick(self.legal_mask),
            weights=pick(self.weights),
            imputed=pick(self.imputed),
        )

    def split(self, *, val_fraction: float, seed: int) -> tuple[Transitions, Transitions, list]:
        """(train, validation, validation group ids), never cutting a group.

        A seeded permutation of the groups (in order of first appearance) picks
        ``round(val_fraction · groups)`` of them, at least one, leaving at least one.
        """
        _, first, inverse = np.unique(self.groups, return_index=True, return_inverse=True)
        order = np.argsort(first, kind="stable")  # unique's sorted ids -> appearance order
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        group_index = rank[inverse.reshape(-1)]
        num_groups = len(first)
        if num_groups < 2:
            raise InputError("need at least two groups (hands, episodes) to split")
        num_val = min(max(round(val_fraction * num_groups), 1), num_groups - 1)
        is_val_group = np.zeros(num_groups, dtype=bool)
        is_val_group[np.random.default_rng(seed).permutation(num_groups)[:num_val]] = True
        is_val = is_val_group[group_index]
        val_groups = self.groups[np.sort(first[order][is_val_group])].tolist()
        return (
            self.subset(np.flatnonzero(~is_val)),
            self.subset(np.flatnonzero(is_val)),
            val_groups,
        )

    def fingerprint(self) -> str:
        """SHA-256 over every array the trainer sees."""
        digest = hashlib.sha256()
        for value in (self.obs, self.actions, self.next_obs, self.dones, self.rewards):
            if value is not None:
                digest.update(value.cpu().contiguous().numpy().tobytes())
        if self.legal_mask is not None:
            digest.update(self.legal_mask.cpu().contiguous().numpy().tobytes())
        for extra in (self.weights, self.imputed):  # absent: the digest of data before them
            if extra is not None:
                digest.update(extra.cpu().contiguous().numpy().tobytes())
        digest.update("\0".join(map(str, self.groups.tolist())).encode())
        return digest.hexdigest()
