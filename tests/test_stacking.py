"""pokerirl.stacking: R runs stacked are R runs alone (the Adam bit for bit with torch's)."""

from __future__ import annotations

import pytest
import torch

from pokerirl.stacking import (
    AdamKernel,
    Flat,
    Product,
    StackedAdam,
    StackedLinear,
    clip_grad_norm_per_run,
    init_linears,
)

R = 3
# Per run: 32 floats (whole SIMD vectors: torch's fused kernel) and 3 (its foreach formula).
SHAPES = [(4, 8), (3,)]


def _grads(step: int) -> list[torch.Tensor]:
    gen = torch.Generator().manual_seed(step)
    return [torch.randn(R, *shape, generator=gen) * 10.0**-step for shape in SHAPES]


def test_torch_kernel_is_r_torch_adams_bit_for_bit() -> None:
    start = [torch.randn(R, *shape, generator=torch.Generator().manual_seed(9)) for shape in SHAPES]
    stacked = [torch.nn.Parameter(t.clone()) for t in start]
    ours = StackedAdam(stacked, lr=0.01, weight_decay=1e-2, runs=R)
    alone = [[torch.nn.Parameter(t[r].clone()) for t in start] for r in range(R)]
    theirs = [
        [torch.optim.Adam([p], lr=0.01, weight_decay=1e-2, fused=p.numel() % 16 == 0) for p in run]
        for run in alone
    ]
    for step in range(6):
        ours.zero_grad()
        for p, g in zip(stacked, _grads(step), strict=True):
            p.grad = g.clone()
        ours.step()
        for r, (run, optimizers) in enumerate(zip(alone, theirs, strict=True)):
            for p, optimizer, g in zip(run, optimizers, _grads(step), strict=True):
                p.grad = g[r].clone()
                optimizer.step()
    for r, run in enumerate(alone):
        for p, q in zip(run, stacked, strict=True):
            assert torch.equal(p, q[r]), (r, p.shape)
    assert not torch.equal(stacked[0], start[0])


@pytest.mark.filterwarnings("ignore:grad and param do not obey the gradient layout")
@pytest.mark.parametrize("flat", [Flat.RUNS, Flat.PARAMETERS])
@pytest.mark.parametrize("kernel", list(AdamKernel))
def test_a_flat_buffer_holds_the_parameters_and_runs_step_as_alone(
    flat: Flat, kernel: AdamKernel
) -> None:
    """Parameters become views of one buffer that backward accumulates into; run r of a
    group steps bit for bit as a group of one (Flat.RUNS: as lock-step PPO relies on)."""
    start = [torch.randn(R, *shape, generator=torch.Generator().manual_seed(3)) for shape in SHAPES]

    def trained(runs: list[int]) -> list[torch.Tensor]:
        params = [torch.nn.Parameter(t[runs].clone()) for t in start]
        opt = StackedAdam(params, lr=0.05, runs=len(runs), kernel=kernel, flat=flat)
        assert params[1].data_ptr() > params[0].data_ptr() >= opt.flat.data_ptr()
        for step in range(4):
            opt.zero_grad()
            pairs = zip(params, _grads(step), strict=True)
            losses = [((p - g[runs]) ** 2 * (1 + g[runs])).sum() for p, g in pairs]
            torch.stack(losses).sum().backward()
            opt.step()
        return [p.detach() for p in params]

    group = trained(list(range(R)))
    for r in range(R):
        for p, q in zip(trained([r]), group, strict=True):
            if flat is Flat.RUNS:
                assert torch.equal(p[0], q[r])
            else:  # parameter-major: not promised, a run's elements sit in other SIMD lanes
                torch.testing.assert_close(p[0], q[r], rtol=1e-6, atol=1e-7)
    assert not torch.equal(group[0], start[0])


@pytest.mark.parametrize("product", list(Product))
def test_stacked_linear_is_r_linears(product: Product) -> None:
    torch.manual_seed(0)
    for n_in, n_out in ((6, 1), (3, 5)):
        linears = [torch.nn.Linear(n_in, n_out) for _ in range(R)]
        layer = StackedLinear.stack([m.weight for m in linears], [m.bias for m in linears],
                                    product=product)  # fmt: skip
        assert layer.out_in == (product is not Product.WRITTEN_BACKWARD or n_out < n_in)
        x = torch.randn(R, 7, n_in, requires_grad=True)
        y = layer(x)
        y.square().sum().backward()
        for r, m in enumerate(linears):
            torch.testing.assert_close(layer.run_weight(r), m.weight.detach())
            xr = x.detach()[r].requires_grad_()
            yr = m(xr)
            yr.square().sum().backward()
            torch.testing.assert_close(y[r], yr)
            torch.testing.assert_close(x.grad[r], xr.grad)  # type: ignore[index]
            grad_w = layer.weight.grad[r]  # type: ignore[index]
            torch.testing.assert_close(grad_w if layer.out_in else grad_w.T, m.weight.grad)
            torch.testing.assert_close(layer.bias.grad[r], m.bias.grad)  # type: ignore[index,union-attr]
        # other leading shapes: (R, M, B, in), as the IRL nets call it
        x4 = torch.randn(R, 2, 7, n_in)
        torch.testing.assert_close(layer(x4)[:, 1], layer(x4[:, 1]))


def test_init_linears_is_torch_after_manual_seed_and_leaves_the_global_generator() -> None:
    before = torch.random.get_rng_state()
    (w0, b0), (w1, b1) = init_linears(5, [(4, 3), (3, 2)], [None, 0.5])
    assert torch.equal(torch.random.get_rng_state(), before)
    torch.manual_seed(5)
    first = torch.nn.Linear(4, 3)
    assert torch.equal(w0, first.weight) and torch.equal(b0, first.bias)
    assert torch.equal(b1, torch.zeros(2))
    torch.testing.assert_close(w1 @ w1.T, 0.25 * torch.eye(2))  # orthogonal rows, gain 0.5


def test_clip_grad_norm_per_run_matches_torch() -> None:
    """Each run's slices clipped as torch's clip_grad_norm_ clips that run's own parameters."""
    gen = torch.Generator().manual_seed(0)
    shapes, scales = [(3, 2, 8), (3, 1, 8), (3, 8, 3)], torch.tensor([0.1, 10.0, 100.0])
    grads = [torch.randn(shape, generator=gen) * scales.view(3, 1, 1) for shape in shapes]
    for tensors in (grads, [torch.cat([g.reshape(3, -1) for g in grads], 1)]):  # several; one
        ours = [g.clone() for g in tensors]
        clip_grad_norm_per_run([*ours, None], 10.0, 3)
        for r in range(3):
            run = [torch.nn.Parameter(torch.zeros_like(g[r])) for g in tensors]
            for p, g in zip(run, tensors, strict=True):
                p.grad = g[r].clone()
            norm = torch.nn.utils.clip_grad_norm_(run, 10.0)
            assert (norm > 10) == (r > 0)  # run 0 below the bound, runs 1 and 2 above it
            for p, q in zip(run, ours, strict=True):
                torch.testing.assert_close(q[r], p.grad, atol=1e-6, rtol=1e-6)
