"""R copies of one architecture called as one: the lock-step runs' nets.

:class:`StackedNets` is what the trainer calls; :func:`stack_modules` turns the default
nets' layers into the stacked layers of :mod:`pokerirl.stacking` (batched products), and any
other architecture goes through ``torch.func.vmap``.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any

import torch
from torch import Tensor, nn

from pokerirl.stacking import StackedLayerNorm, StackedLinear


class StackedNets:
    """R copies of a (reward or policy) architecture, called with a leading run dimension.

    Inputs carry the run dimension first (or none where ``shared``); a reward's state
    arguments also carry an action-row axis of size 1, so that they broadcast against the
    (M, B, k) action rows both inside one run and across runs.

    One run calls the module itself. Several runs made of the default nets' layers (Linear,
    LayerNorm, activations) become one module whose parameters have a leading run dimension
    (``stack_modules``: batched matrix products, one kernel per layer for all runs); any
    other architecture goes through ``vmap(functional_call)`` over stacked parameters.
    Either way ``params`` are the leaves the optimizer updates.
    """

    def __init__(self, modules: Sequence[nn.Module]) -> None:
        self.modules = list(modules)
        self.stacked: nn.Module | None = None
        if len(self.modules) == 1:
            self.params = list(self.modules[0].parameters())
            return
        self.stacked = stack_modules(self.modules)
        if self.stacked is not None:
            self.params = list(self.stacked.parameters())
            return
        self.base = copy.deepcopy(self.modules[0]).to("meta")
        params, self.buffers = torch.func.stack_module_state(self.modules)
        self.vmapped = params
        self.params = list(params.values())

    def __call__(self, *args: Tensor | None, shared: Sequence[bool] = ()) -> Any:
        """Call with args of (R, ...) (or without R where ``shared[i]``)."""
        shared = tuple(shared) + (False,) * (len(args) - len(shared))
        runs = len(self.modules)
        if runs == 1:
            inner = (a if s or a is None else a[0] for a, s in zip(args, shared, strict=True))
            return _unsqueeze(self.modules[0](*inner))
        if self.stacked is not None:
            return self.stacked(
                *(a.expand(runs, *a.shape) if s and a is not None else a
                  for a, s in zip(args, shared, strict=True))
            )  # fmt: skip
        dims = tuple(None if s or a is None else 0 for a, s in zip(args, shared, strict=True))

        def call(params: dict, buffers: dict, *inner: Tensor | None) -> Any:
            return torch.func.functional_call(self.base, (params, buffers), inner)

        return torch.func.vmap(call, in_dims=(0, 0, *dims))(self.vmapped, self.buffers, *args)

    @torch.no_grad()
    def write_back(self) -> None:
        """Copy the runs' parameters into the R modules (no-op for one run)."""
        if len(self.modules) == 1:
            return
        source = dict(self.stacked.named_parameters()) if self.stacked is not None else self.vmapped
        for r, module in enumerate(self.modules):
            for name, value in module.named_parameters():
                value.copy_(source[name][r])


_STACKABLE = (nn.Sequential, nn.Identity, nn.ReLU, nn.Tanh, nn.LeakyReLU)


def stack_modules(modules: Sequence[nn.Module]) -> nn.Module | None:
    """One module computing all R ``modules`` (same architecture) on inputs with a leading
    run dimension, or None when an architecture is not made of known layers.

    Known: the default nets (whose forward code broadcasts over leading dimensions),
    Sequential, Linear, LayerNorm (elementwise affine) and parameter-free activations.
    """
    from pokerirl.irl.nets import DiscretePolicy, GaussianPolicy, ShapedReward, StateActionReward

    known = (*_STACKABLE, DiscretePolicy, GaussianPolicy, ShapedReward, StateActionReward)
    for module in modules[0].modules():
        if (
            isinstance(module, nn.LayerNorm)
            and module.elementwise_affine
            and module.bias is not None
        ):
            continue
        if type(module) is not nn.Linear and type(module) not in known:
            return None
    stacked = copy.deepcopy(modules[0])

    def convert(target: nn.Module, sources: list[nn.Module]) -> None:
        for name, child in list(target.named_children()):
            originals = [getattr(source, name) for source in sources]
            if type(child) is nn.Linear:
                biases = None if child.bias is None else [m.bias for m in originals]
                setattr(target, name, StackedLinear.stack([m.weight for m in originals], biases))
            elif isinstance(child, nn.LayerNorm):
                setattr(target, name, StackedLayerNorm(originals))
            else:
                convert(child, originals)
        for name, _ in list(target.named_parameters(recurse=False)):
            value = torch.stack([getattr(source, name).detach() for source in sources])
            setattr(target, name, nn.Parameter(value))
        for name, _ in list(target.named_buffers(recurse=False)):
            target.register_buffer(name, torch.stack([getattr(s, name) for s in sources]))

    convert(stacked, list(modules))
    return stacked


def _unsqueeze(out: Any) -> Any:
    if isinstance(out, tuple):
        return tuple(o.unsqueeze(0) for o in out)
    return out.unsqueeze(0)
