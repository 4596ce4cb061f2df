# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What would bfloat16 in the backward convolutions alone buy? An experiment.

bfloat16 through the hidden layers diverged in float32 evaluation (docs/experiments.md):
its forward differs from the float32 one the model file is evaluated with. Here the
forward stays float32 (training and evaluation compute the same function) and only the
convolutions' input and weight gradients are computed in bfloat16 (oneDNN, accumulated
in float32). Prints, for one worker's share of an EuRoC step (three 16,000-sample
windows, one thread, the real network and loss on random IMU-like data): the step time
in float32 and with the bfloat16 backward, and how far the gradients move.
Usage: .venv/bin/python scripts/experiments/bf16_backward.py
"""

import time
from typing import Any

from denoise_imu_ros.core.architecture import ModelConfig
from denoise_imu_ros.learn.config import LossConfig
from denoise_imu_ros.learn.loss import increment_loss
from denoise_imu_ros.learn.model import GyroNet
import torch
from torch import nn
import torch.nn.functional as F  # noqa: N812


class _Bf16BackwardConv(torch.autograd.Function):
    """A dilated convolution: float32 forward, bfloat16 input and weight gradients."""

    @staticmethod
    def forward(ctx: Any, x: torch.Tensor, weight: torch.Tensor, bias: torch.Tensor,
                dilation: int) -> torch.Tensor:
        """Convolve in float32, as evaluation does."""
        ctx.save_for_backward(x, weight)
        ctx.dilation = dilation
        return F.conv1d(x, weight, bias, dilation=dilation)

    @staticmethod
    def backward(ctx: Any, grad: torch.Tensor) -> tuple[Any, ...]:
        """Return the input, weight and bias gradients, the first two from bfloat16."""
        x, weight = ctx.saved_tensors
        gx, gw, _ = torch.ops.aten.convolution_backward(
            grad.bfloat16(), x.bfloat16(), weight.bfloat16(), None, [1], [0],
            [ctx.dilation], False, [0], 1, [ctx.needs_input_grad[0], True, False])
        return (None if gx is None else gx.float()), gw.float(), grad.sum((0, 2)), None


class Bf16BackwardConv1d(nn.Conv1d):
    """``nn.Conv1d`` whose backward runs in bfloat16."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Convolve; see :class:`_Bf16BackwardConv`."""
        return _Bf16BackwardConv.apply(x, self.weight, self.bias, self.dilation[0])


def step_time(model: GyroNet, batch: tuple[torch.Tensor, ...], repeats: int = 5) -> float:
    """Fastest forward, loss and backward of one worker's share (s)."""
    times = []
    for _ in range(repeats + 1):
        model.zero_grad()
        t = time.perf_counter()
        increment_loss(model(batch[0]), *batch[1:], LossConfig()).backward()
        times.append(time.perf_counter() - t)
    return min(times[1:])


def main() -> None:
    torch.set_num_threads(1)
    torch.set_flush_denormal(True)
    torch.manual_seed(0)
    windows, length = 3, 16000
    u = torch.cat([0.3 * torch.randn(windows, length, 3),
                   torch.tensor([9.2, 0.0, -3.3]) + 0.5 * torch.randn(windows, length, 3)], -1)
    dt = torch.full((windows, length), 0.005, dtype=torch.float64)
    quat = F.normalize(torch.randn(windows, length + 1, 4, dtype=torch.float64), dim=-1)
    valid = torch.ones(windows, length + 1, dtype=torch.bool)
    batch = (u, dt, quat, valid)
    model = GyroNet(ModelConfig(dropout=0.0)).train()
    model.set_normalization(u.reshape(-1, 6).mean(0), u.reshape(-1, 6).std(0))
    plain = step_time(model, batch)
    reference = {k: p.grad.clone() for k, p in model.named_parameters()}
    for i, module in enumerate(model.net):
        if isinstance(module, nn.Conv1d) and module.kernel_size[0] > 1:
            swapped = Bf16BackwardConv1d(module.in_channels, module.out_channels,
                                         module.kernel_size[0], dilation=module.dilation[0])
            swapped.load_state_dict(module.state_dict())
            model.net[i] = swapped
    mixed = step_time(model, batch)
    print(f'one worker step: float32 {plain:.3f} s, bfloat16 backward {mixed:.3f} s '
          f'({plain / mixed:.2f}x)')
    for key, g in reference.items():
        if key.endswith('.weight') and g.norm() > 0:
            moved = float((model.get_parameter(key).grad - g).norm() / g.norm())
            print(f'  {key}: gradient moved by {100 * moved:.2f} % of its norm')


if __name__ == '__main__':
    main()
