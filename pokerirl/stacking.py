"""R runs of one net trained as one: the stacked linear layer, layer norm and Adam (torch only).

Every tensor here carries the run first, (R, ...); run r's slice is run r's net. The IRL
trainer (``irl/stacked.py``) and the lock-step PPO and DQN (``gym/lockstep/``) build on it.
Runs share no parameters and Adam is element-wise, so one optimizer over stacked tensors is R
per-run optimizers that step together.

The choices below that only change rounding (:class:`Product`, :class:`AdamKernel`, the flat
buffers' layouts) are options, not defaults to switch: each caller's runs keep their bytes.

>>> layer = StackedLinear.stack([torch.ones(2, 3), torch.zeros(2, 3)], [torch.ones(2)] * 2)
>>> layer(torch.ones(2, 5, 3)).shape, layer(torch.ones(2, 1, 3))[:, 0].tolist()
(torch.Size([2, 5, 2]), [[4.0, 4.0], [1.0, 1.0]])
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from enum import StrEnum
from typing import Any

import torch
import torch.nn.functional as F
from torch import Tensor, nn

# Floats per SIMD vector (AVX-512; a multiple of AVX2's and NEON's). torch's fused Adam rounds
# its vector lanes and its scalar tail differently: only a tensor whose every run's part is a
# whole number of vectors rounds alike for run r in a group of R and in a group of one.
FUSED_ALIGN = 16
# A Flat.RUNS buffer's rows are padded to this many floats (the padding's grads stay zero).
ROW_ALIGN = 64


class Product(StrEnum):
    """How :class:`StackedLinear` computes x W + b. Equal up to rounding; a run's bytes depend
    on which, so each caller keeps its own."""

    BATCHED = "batched"  # one baddbmm, autograd's backward (the IRL nets)
    # As BATCHED, but a single output as a row-wise dot product: baddbmm's kernel for a
    # (B, in) x (in, 1) product differs between R = 1 and R > 1, and with it the rounding
    # (lock-step PPO's value head, so that run r of a group equals a group of one).
    ONE_OUTPUT_DOT = "one-output-dot"
    # A written-out backward whose products keep the fast operand layouts, the weight stored
    # (R, out, in) where there are fewer outputs than inputs, else (R, in, out): MKL's batched
    # matmul is several times slower for some layouts at small shapes (256 -> 3: 0.27 ms
    # against 0.07 for the forward at R=9, 0.29 against 0.05 for the weight gradient). No
    # autograd Function without a graph (acting, targets). Lock-step DQN's Q-networks.
    WRITTEN_BACKWARD = "written-backward"


class _WrittenBackward(torch.autograd.Function):
    """x (R, B, in) -> x W + b, W stored (R, out, in) if ``out_in`` else (R, in, out)."""

    @staticmethod
    def forward(ctx: Any, x: Tensor, weight: Tensor, bias: Tensor, out_in: bool) -> Tensor:
        ctx.save_for_backward(x, weight)
        ctx.out_in = out_in
        return torch.baddbmm(bias[:, None, :], x, weight.transpose(1, 2) if out_in else weight)

    @staticmethod
    def backward(ctx: Any, grad: Tensor) -> tuple[Tensor | None, ...]:
        x, weight = ctx.saved_tensors
        gx = gw = gb = None
        if ctx.needs_input_grad[0]:
            gx = torch.bmm(grad, weight if ctx.out_in else weight.transpose(1, 2))
        if ctx.needs_input_grad[1]:
            gw = (torch.bmm(grad.transpose(1, 2), x) if ctx.out_in
                  else torch.bmm(x.transpose(1, 2), grad))  # fmt: skip
        if ctx.needs_input_grad[2]:
            gb = grad.sum(1)
        return gx, gw, gb, None


class StackedLinear(nn.Module):
    """R linear maps, run r's applied to x[r]: x (R, ..., in) -> (R, ..., out).

    ``weight`` is (R, out, in), torch's ``Linear`` layout, or (R, in, out) where ``out_in`` is
    False; ``bias`` (R, out) or None. Parameters given are kept as they are (views into a
    buffer included); plain tensors become Parameters.
    """

    def __init__(self, weight: Tensor, bias: Tensor | None, *, out_in: bool = True,
                 product: Product = Product.BATCHED) -> None:  # fmt: skip
        super().__init__()
        if product is Product.WRITTEN_BACKWARD and bias is None:
            raise ValueError("StackedLinear: the written backward needs a bias")
        self.out_in, self.product = out_in, product
        self.weight = weight if isinstance(weight, nn.Parameter) else nn.Parameter(weight)
        self.bias = bias if bias is None or isinstance(bias, nn.Parameter) else nn.Parameter(bias)

    @classmethod
    def stack(cls, weights: Sequence[Tensor], biases: Sequence[Tensor] | None, *,
              product: Product = Product.BATCHED) -> StackedLinear:  # fmt: skip
        """From the runs' (out, in) weights and (out,) biases (copied); the written backward
        picks its weight layout (see :class:`Product`)."""
        weight = torch.stack([w.detach() for w in weights])
        bias = None if biases is None else torch.stack([b.detach() for b in biases])
        out_in = product is not Product.WRITTEN_BACKWARD or weight.shape[1] < weight.shape[2]
        return cls(weight if out_in else weight.transpose(1, 2).contiguous(), bias,
                   out_in=out_in, product=product)  # fmt: skip

    def forward(self, x: Tensor) -> Tensor:
        if x.dim() == 3:
            return self._product(x)
        y = self._product(x.reshape(self.weight.shape[0], -1, x.shape[-1]))
        return y.view(*x.shape[:-1], y.shape[-1])

    def _product(self, x: Tensor) -> Tensor:
        """x (R, B, in) -> (R, B, out)."""
        weight = self.weight.transpose(1, 2) if self.out_in else self.weight  # (R, in, out)
        if self.bias is None:
            return torch.bmm(x, weight)
        if self.product is Product.WRITTEN_BACKWARD and torch.is_grad_enabled():
            return _WrittenBackward.apply(x, self.weight, self.bias, self.out_in)
        if self.product is Product.ONE_OUTPUT_DOT and weight.shape[-1] == 1:
            return (x * weight.transpose(1, 2)).sum(-1, keepdim=True) + self.bias[:, None, :]
        return torch.baddbmm(self.bias[:, None, :], x, weight)

    def run_weight(self, r: int) -> Tensor:
        """Run r's weight as torch's ``Linear`` stores it, (out, in): a copy."""
        w = self.weight.detach()[r]
        return (w if self.out_in else w.T).contiguous().clone()


class StackedLayerNorm(nn.Module):
    """R layer norms (with their own affine parameters) over x of (R, ..., H)."""

    def __init__(self, layers: Sequence[nn.LayerNorm]) -> None:
        super().__init__()
        self.shape, self.eps = layers[0].normalized_shape, layers[0].eps
        self.weight = nn.Parameter(torch.stack([m.weight.detach() for m in layers]))
        self.bias = nn.Parameter(torch.stack([m.bias.detach() for m in layers]))

    def forward(self, x: Tensor) -> Tensor:
        view = (x.shape[0],) + (1,) * (x.ndim - 2) + (x.shape[-1],)
        normed = F.layer_norm(x, self.shape, eps=self.eps)
        return torch.addcmul(self.bias.view(view), normed, self.weight.view(view))


def init_linears(seed: int, sizes: Sequence[tuple[int, int]],
                 gains: Sequence[float | None] | None = None) -> list[tuple[Tensor, Tensor]]:
    """One run's linears, (weight (out, in), bias (out,)) per (in, out) in ``sizes``, as torch
    builds them one after the other after ``torch.manual_seed(seed)`` (so as SB3 does for that
    seed): torch's default init, or where ``gains[i]`` is a number SB3's orthogonal init with
    that gain and a zero bias. torch's global generator is left as it was."""
    out = []
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        for (n_in, n_out), gain in zip(sizes, gains or [None] * len(sizes), strict=True):
            layer = nn.Linear(n_in, n_out)
            if gain is not None:
                nn.init.orthogonal_(layer.weight, gain=gain)
                layer.bias.data.fill_(0.0)
            out.append((layer.weight.data.clone(), layer.bias.data.clone()))
    return out


class AdamKernel(StrEnum):
    """The arithmetic of a :class:`StackedAdam` step: the same update up to rounding."""

    # torch.optim.Adam's numbers bit for bit: its fused kernel on the tensors whose every
    # run's part is a whole number of SIMD vectors (FUSED_ALIGN), its foreach formula on the
    # rest (exact per element).
    TORCH = "torch"
    # m / (sqrt(v) / c2 + eps) computed as c2 · m / (sqrt(v) + eps · c2): six kernels, the
    # step count a Python int (the IRL trainer's, for nets where the step's overhead counts).
    FOLDED = "folded"


class Flat(StrEnum):
    """Where :class:`StackedAdam` moves the parameters: one buffer, the parameters views of
    it and their ``.grad`` views of a second one, which autograd accumulates into in place
    (zero it, never set it to None)."""

    PARAMETERS = "parameters"  # 1-D, parameter after parameter
    # (R, P): row r holds run r's part of every parameter (leading run dimension), padded to
    # ROW_ALIGN floats, so a per-run norm is one reduction and every run's row meets the
    # fused kernel's vector lanes alike.
    RUNS = "runs"


class StackedAdam:
    """Adam (Kingma & Ba, L2 weight decay added to the gradient as ``torch.optim.Adam``) over
    parameters with a leading run dimension (or none: ``runs`` 1): R independent Adams.

    With ``flat`` the parameters move into one buffer (:class:`Flat`; ``flat``, ``grad``)
    and a step is a few kernels however many layers; without, a step reads each ``p.grad``.
    Called directly, not through ``torch.optim.Optimizer``, whose Python wrapping costs more
    than the step itself for nets this small.

    >>> net = torch.nn.Linear(3, 1)
    >>> opt = StackedAdam(net.parameters(), lr=0.1, flat=Flat.PARAMETERS)
    >>> net(torch.ones(2, 3)).sum().backward()
    >>> opt.step()
    >>> net.weight.data_ptr() == opt.flat.data_ptr()  # the parameters live in the buffer
    True
    """

    def __init__(
        self,
        params: Iterable[Tensor],
        *,
        lr: float,
        betas: tuple[float, float] = (0.9, 0.999),
        eps: float = 1e-8,
        weight_decay: float = 0.0,
        runs: int = 1,
        kernel: AdamKernel = AdamKernel.TORCH,
        flat: Flat | None = None,
    ) -> None:
        self.params = list(params)
        self.lr, self.betas, self.eps, self.weight_decay = lr, betas, eps, weight_decay
        self.kernel, self.layout = kernel, flat
        self.tensors = self.params if flat is None else [self._flatten(flat, runs)]
        self.exp_avg = [torch.zeros_like(t) for t in self.tensors]
        self.exp_avg_sq = [torch.zeros_like(t) for t in self.tensors]
        self.steps = 0  # a Python int: bias corrections never sync with the device
        fused = [kernel is AdamKernel.TORCH and t.numel() // runs % FUSED_ALIGN == 0
                 for t in self.tensors]  # fmt: skip
        self.fused = [i for i, f in enumerate(fused) if f]
        self.rest = [i for i, f in enumerate(fused) if not f]
        self.step_tensor = torch.zeros((), dtype=torch.float32)  # the fused kernel's

    @torch.no_grad()
    def _flatten(self, layout: Flat, runs: int) -> Tensor:
        rows = () if layout is Flat.PARAMETERS else (runs,)
        flat = torch.cat([p.detach().reshape(*rows, -1) for p in self.params], -1)
        if rows:
            flat = F.pad(flat, (0, -flat.shape[-1] % ROW_ALIGN))
        self.flat, self.grad = flat, torch.zeros_like(flat)
        offset = 0
        for p in self.params:
            size = p.numel() // (runs if rows else 1)
            p.data = flat[..., offset : offset + size].view_as(p)
            p.grad = self.grad[..., offset : offset + size].view_as(p)
            offset += size
        return flat

    def zero_grad(self) -> None:
        """Zero the flat gradient, or drop each parameter's."""
        if self.layout is None:
            for p in self.params:
                p.grad = None
        else:
            self.grad.zero_()

    @torch.no_grad()
    def set_grad(self, grads: list[Tensor]) -> None:
        """Write gradients given in parameter order (a hand-derived path's) into the
        ``Flat.PARAMETERS`` buffer."""
        if self.layout is not Flat.PARAMETERS:
            raise ValueError(f"StackedAdam.set_grad: a Flat.PARAMETERS buffer, not {self.layout}")
        torch.cat([g.reshape(-1) for g in grads], out=self.grad)

    @torch.no_grad()
    def step(self) -> None:
        """One update from the gradients since :meth:`zero_grad`."""
        grads = [self.grad] if self.layout is not None else [_grad(p) for p in self.params]
        self.steps += 1
        if self.kernel is AdamKernel.FOLDED:
            self._folded(grads)
            return
        if self.fused:
            self.step_tensor += 1
            torch._fused_adam_(
                [self.tensors[i] for i in self.fused], [grads[i] for i in self.fused],
                [self.exp_avg[i] for i in self.fused], [self.exp_avg_sq[i] for i in self.fused],
                [], [self.step_tensor] * len(self.fused), lr=self.lr, beta1=self.betas[0],
                beta2=self.betas[1], weight_decay=self.weight_decay, eps=self.eps,
                amsgrad=False, maximize=False,
            )  # fmt: skip
        if self.rest:
            self._foreach([self.tensors[i] for i in self.rest], [grads[i] for i in self.rest],
                          [self.exp_avg[i] for i in self.rest],
                          [self.exp_avg_sq[i] for i in self.rest])  # fmt: skip

    def _foreach(self, params: list[Tensor], grads: list[Tensor], exp_avg: list[Tensor],
                 exp_avg_sq: list[Tensor]) -> None:  # fmt: skip
        """torch.optim.Adam(foreach=True)'s step, op for op (``_multi_tensor_adam``)."""
        beta1, beta2 = self.betas
        if self.weight_decay:
            grads = list(torch._foreach_add(grads, params, alpha=self.weight_decay))
        torch._foreach_lerp_(exp_avg, grads, 1 - beta1)
        torch._foreach_mul_(exp_avg_sq, beta2)
        torch._foreach_addcmul_(exp_avg_sq, grads, grads, 1 - beta2)
        step_size = (self.lr / (1 - beta1 ** float(self.steps))) * -1
        bias2_sqrt = (1 - beta2 ** float(self.steps)) ** 0.5
        denom = torch._foreach_sqrt(exp_avg_sq)
        torch._foreach_div_(denom, bias2_sqrt)
        torch._foreach_add_(denom, self.eps)
        torch._foreach_addcdiv_(params, exp_avg, denom, step_size)

    def _folded(self, grads: list[Tensor]) -> None:
        beta1, beta2 = self.betas
        bias1 = 1 - beta1**self.steps
        bias2_sqrt = math.sqrt(1 - beta2**self.steps)
        for param, grad, exp_avg, exp_avg_sq in zip(self.tensors, grads, self.exp_avg,
                                                     self.exp_avg_sq, strict=True):  # fmt: skip
            if self.weight_decay:
                grad = grad.add(param, alpha=self.weight_decay)
            exp_avg.lerp_(grad, 1 - beta1)
            exp_avg_sq.mul_(beta2).addcmul_(grad, grad, value=1 - beta2)
            denom = exp_avg_sq.sqrt().add_(self.eps * bias2_sqrt)
            param.addcdiv_(exp_avg, denom, value=-self.lr * bias2_sqrt / bias1)


def _grad(param: Tensor) -> Tensor:
    if param.grad is None:
        raise ValueError("StackedAdam.step: a parameter without a gradient")
    return param.grad


def clip_grad_norm_per_run(grads: Sequence[Tensor | None], max_norm: float, runs: int) -> None:
    """``torch.nn.utils.clip_grad_norm_`` on each run's slices of stacked (R, ...) gradients
    (None ones skipped, as there), in place: each run's norm over its slices of all of them
    (of one, a single reduction)."""
    present = [g for g in grads if g is not None]
    with torch.no_grad():
        norms = [torch.linalg.vector_norm(g.reshape(runs, -1), 2, dim=1) for g in present]
        total = norms[0] if len(norms) == 1 else torch.linalg.vector_norm(
            torch.stack(norms), 2, dim=0)  # fmt: skip
        coef = torch.clamp(max_norm / (total + 1e-6), max=1.0)
        for g in present:
            g.mul_(coef.view(runs, *([1] * (g.dim() - 1))))
