"""The IRL trainer's Adam: :class:`pokerirl.stacking.StackedAdam` over one flat buffer.

``torch.optim.Adam`` spends most of a step, for nets this small, in Python bookkeeping and in
its tensor step counters (measured: about 190 µs a step, of which the fused kernel is 14).
``FlatAdam`` moves a module's parameters into views of one contiguous buffer and presets
their ``.grad`` to views of another, which autograd then accumulates into in place; an update
is six kernels on two tensors (``AdamKernel.FOLDED``), with the step count a Python int. It
follows ``torch.optim.Adam`` (L2 weight decay added to the gradient, as there) up to
rounding; a test compares them.

>>> import torch
>>> net = torch.nn.Linear(3, 1)
>>> opt = FlatAdam(net.parameters(), lr=0.1)
>>> opt.zero_grad()
>>> net(torch.ones(2, 3)).sum().backward()
>>> opt.step()
>>> net.weight.data_ptr() == opt.flat.data_ptr()  # parameters now live in the flat buffer
True
"""

from __future__ import annotations

from collections.abc import Iterable

from torch import nn

from pokerirl.stacking import AdamKernel, Flat, StackedAdam


class FlatAdam(StackedAdam):
    """Adam (Kingma & Ba) with L2 weight decay over one ``Flat.PARAMETERS`` buffer, the
    folded kernel: the arithmetic every IRL run's bytes were made with."""

    def __init__(self, params: Iterable[nn.Parameter], *, lr: float,
                 betas: tuple[float, float] = (0.9, 0.999), eps: float = 1e-8,
                 weight_decay: float = 0.0) -> None:  # fmt: skip
        super().__init__(params, lr=lr, betas=betas, eps=eps, weight_decay=weight_decay,
                         kernel=AdamKernel.FOLDED, flat=Flat.PARAMETERS)  # fmt: skip
