# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The fused BatchNorm, GELU and dropout equal PyTorch's layers, forward and backward."""

import copy

from denoise_imu_ros.core.architecture import ModelConfig
from denoise_imu_ros.learn import fused
from denoise_imu_ros.learn.model import Dropout, GyroNet
import pytest
import torch
from torch import nn
import torch.nn.functional as F  # noqa: N812

pytestmark = pytest.mark.skipif(not fused.available(), reason='_block.c was not built')


def _layers(channels: int, momentum: float | None = 0.1) -> nn.BatchNorm1d:
    torch.manual_seed(3)
    norm = nn.BatchNorm1d(channels, momentum=momentum)
    with torch.no_grad():
        norm.weight.uniform_(0.5, 1.5)
        norm.bias.normal_()
        norm.running_mean.normal_()  # the statistics' centre: exactness may not need 0
    return norm


def _close(a: torch.Tensor, b: torch.Tensor, tol: float = 1e-6) -> None:
    """Equal to ``tol`` of the reference's largest magnitude."""
    assert (a - b).abs().max().item() <= tol * b.abs().max().item(), (a - b).abs().max()


@pytest.mark.parametrize('momentum', [0.1, None])
def test_without_dropout_output_gradients_and_statistics_equal_pytorch(momentum):
    torch.manual_seed(0)
    x = (2.0 * torch.randn(3, 24, 3000) + 5.0).requires_grad_()  # a level well off 0
    grad = torch.randn(3, 24, 3000)
    mine, ref = _layers(24, momentum), _layers(24, momentum)
    out = fused.block(x, mine, nn.GELU(), Dropout(0.0))
    out.backward(grad)
    gx, x.grad = x.grad, None
    expected = F.gelu(ref(x))
    expected.backward(grad)
    _close(out, expected)
    _close(gx, x.grad)
    _close(mine.weight.grad, ref.weight.grad)
    _close(mine.bias.grad, ref.bias.grad)
    _close(mine.running_mean, ref.running_mean)
    _close(mine.running_var, ref.running_var)
    assert mine.num_batches_tracked == ref.num_batches_tracked == 1


def test_dropout_drops_p_of_the_elements_scales_the_rest_and_backpropagates_the_same_mask():
    torch.manual_seed(1)
    x = torch.randn(2, 16, 20000, requires_grad=True)
    norm, ref = _layers(16), _layers(16)
    out = fused.block(x, norm, nn.GELU(), Dropout(0.25))
    kept = out != 0
    n = kept.numel()
    assert abs((~kept).sum().item() / n - 0.25) < 5 * (0.25 * 0.75 / n) ** 0.5
    per_channel = (~kept).float().mean((0, 2))
    assert per_channel.min() > 0.23 and per_channel.max() < 0.27  # no channel left out
    plain = F.gelu(ref(x))
    _close(out, torch.where(kept, plain / 0.75, 0.0))
    grad = torch.randn_like(out)
    out.backward(grad)
    gx, x.grad = x.grad, None
    torch.where(kept, plain / 0.75, 0.0).backward(grad)
    _close(gx, x.grad)


def test_masks_follow_torch_seed():
    x = torch.randn(1, 8, 4000)
    norm = _layers(8)
    draws = []
    for seed in (5, 5, 6):
        torch.manual_seed(seed)
        draws.append(fused.block(x, norm, nn.GELU(), Dropout(0.1)) == 0)
    assert torch.equal(draws[0], draws[1])
    assert not torch.equal(draws[0], draws[2])


def test_outside_cpu_float32_training_with_exact_gelu_the_modules_run():
    norm = _layers(4)
    x = torch.randn(2, 4, 100, dtype=torch.float64)
    assert not fused.fusable(x, norm.double(), nn.GELU())
    assert not fused.fusable(x.float(), norm.float(), nn.GELU(approximate='tanh'))
    # another device (a GPU in training): PyTorch's layers, as with fused: false
    assert not fused.fusable(torch.empty(2, 4, 100, device='meta'), norm, nn.GELU())
    assert not fused.fusable(x.float(), norm.eval(), nn.GELU())
    before = norm.running_mean.clone()
    _close(fused.block(x.float(), norm, nn.GELU(), Dropout(0.5).eval()),
           F.gelu(norm(x.float())))
    assert torch.equal(norm.running_mean, before)  # evaluation does not move them


@pytest.mark.parametrize('members', [1, 3])
def test_the_network_trains_through_the_same_function_either_way(members):
    torch.manual_seed(2)
    model = GyroNet(ModelConfig(dropout=0.0, members=members)).train()
    u = torch.randn(2, 1500, 6)
    model.set_normalization(u.reshape(-1, 6).mean(0), u.reshape(-1, 6).std(0))
    layers = copy.deepcopy(model)
    layers.fuse_layers = False
    out, expected = model(u), layers(u)
    grad = torch.randn_like(out)
    out.backward(grad)
    expected.backward(grad)
    _close(out, expected)
    largest = max(p.grad.abs().max() for p in layers.parameters())
    for (name, mine), theirs in zip(model.named_parameters(), layers.parameters()):
        # convolution biases before BatchNorm get rounding noise (their gradient is 0)
        assert (mine.grad - theirs.grad).abs().max() <= 1e-6 * largest, name
    for (name, mine), theirs in zip(model.named_buffers(), layers.buffers()):
        _close(mine.float(), theirs.float())
