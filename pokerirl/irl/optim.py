"""Adam over one flat parameter buffer: a handful of kernels per step for a whole net.

``torch.optim.Adam`` on CPU loops over parameters in Python and keeps its step count in
tensors; for our tiny nets that bookkeeping costs more than the math. ``FlatAdam`` moves a
module's parameters into views of one contiguous buffer, so one update touches one tensor.
It follows ``torch.optim.Adam`` exactly (weight decay added to the gradient, as there).

>>> import torch
>>> net = torch.nn.Linear(3, 1)
>>> opt = FlatAdam(net.parameters(), lr=0.1)
>>> loss = net(torch.ones(2, 3)).sum()
>>> opt.step(torch.autograd.grad(loss, opt.params))
>>> net.weight.data_ptr() == opt.flat.data_ptr()  # parameters now live in the flat buffer
True
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import torch
from torch import Tensor, nn


class FlatAdam:
    """Adam (Kingma & Ba) with L2 weight decay, like ``torch.optim.Adam``."""

    def __init__(
        self,
        params: Iterable[nn.Parameter],
        *,
        lr: float,
        betas: tuple[float, float] = (0.9, 0.999),
        eps: float = 1e-8,
        weight_decay: float = 0.0,
    ) -> None:
        self.params = list(params)
        self.lr, self.betas, self.eps, self.weight_decay = lr, betas, eps, weight_decay
        with torch.no_grad():
            self.flat = torch.cat([p.detach().reshape(-1) for p in self.params])
            offset = 0
            for p in self.params:
                p.data = self.flat[offset : offset + p.numel()].view_as(p)
                offset += p.numel()
        self.exp_avg = torch.zeros_like(self.flat)
        self.exp_avg_sq = torch.zeros_like(self.flat)
        self.steps = 0  # a Python int: bias corrections never sync with the device

    @torch.no_grad()
    def step(self, grads: Sequence[Tensor]) -> None:
        """One update from gradients given in the order of ``self.params``."""
        if self.steps == 0:  # a gradient list in the wrong order would cat to the right size
            shapes = [tuple(g.shape) for g in grads]
            if shapes != [tuple(p.shape) for p in self.params]:
                raise ValueError(f"gradient shapes {shapes} do not match the parameters")
        grad = torch.cat([g.reshape(-1) for g in grads])
        if self.weight_decay:
            grad.add_(self.flat, alpha=self.weight_decay)
        beta1, beta2 = self.betas
        self.steps += 1
        self.exp_avg.lerp_(grad, 1 - beta1)
        self.exp_avg_sq.mul_(beta2).addcmul_(grad, grad, value=1 - beta2)
        bias1 = 1 - beta1**self.steps
        bias2_sqrt = math.sqrt(1 - beta2**self.steps)
        # m / (sqrt(v) / b2 + eps) = b2 · m / (sqrt(v) + eps · b2): one kernel fewer.
        denom = self.exp_avg_sq.sqrt().add_(self.eps * bias2_sqrt)
        self.flat.addcdiv_(self.exp_avg, denom, value=-self.lr * bias2_sqrt / bias1)
