# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
A hidden block's BatchNorm, GELU and dropout in training, fused on the CPU (``_block.c``).

PyTorch runs the three as separate layers, each a few passes over the block's activations
forward and backward, and those passes cost a third of a CPU training step: the
convolutions around them run near the machine's matrix-product speed, these at its
memory speed. The fused function computes the same thing in two passes each way:
BatchNorm with the batch's statistics (summed over data-parallel processes, as
:class:`~denoise_imu_ros.learn.parallel.SyncBatchNorm` does), exact GELU, and inverted
dropout whose mask is a hash of a seed drawn from torch's generator and of the element,
recomputed in the backward instead of stored. :func:`block` falls back to the modules
themselves where the library was not built, on other devices and in evaluation.
"""

from __future__ import annotations

import ctypes
import importlib.util
from typing import Any

import torch
from torch import nn

from .parallel import sum_over_processes, update_running_stats

_F, _D = ctypes.POINTER(ctypes.c_float), ctypes.POINTER(ctypes.c_double)
_I, _SEED = ctypes.c_int64, ctypes.c_uint64
_SIGNATURES = {
    'block_sums': [_F, _I, _I, _I, _F, _D],
    'block_forward': [_F, _F, _I, _I, _I, _F, _F, ctypes.c_float, ctypes.c_int32, _SEED],
    'block_backward_sums': [_F, _F, _F, _I, _I, _I, _F, _F, _F, ctypes.c_float,
                            ctypes.c_int32, _SEED, _D],
    'block_backward_input': [_F, _F, _I, _I, _I, _F, _F, _F],
}


def _load() -> Any:
    """Return _block.c's library, or None where the package was built without it."""
    spec = importlib.util.find_spec(f'{__package__}._block')
    if spec is None or not spec.origin:
        return None
    try:
        lib = ctypes.CDLL(spec.origin)
        for name, args in _SIGNATURES.items():
            fn = getattr(lib, name)
            fn.argtypes, fn.restype = args, None
    except (OSError, AttributeError):
        return None
    return lib


_LIB = _load()


def available() -> bool:
    """Whether the fused block was built with this package."""
    return _LIB is not None


def _ptr(t: torch.Tensor) -> Any:
    """Return a contiguous CPU tensor's data as the C pointer of its type."""
    return ctypes.cast(t.data_ptr(), _D if t.dtype == torch.float64 else _F)


def _threshold(p: float) -> int:
    """Dropout's threshold for _block.c's signed 32-bit draws: p of them fall below it."""
    return round(p * 2 ** 32) - 2 ** 31


class _BlockFn(torch.autograd.Function):
    """Training-mode BatchNorm, GELU and inverted dropout over (B, C, T) float32."""

    @staticmethod
    def forward(ctx: Any, x: torch.Tensor, weight: torch.Tensor, bias: torch.Tensor,
                center: torch.Tensor, eps: float, p: float, seed: int,
                ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Return the output, the batch mean and the unbiased batch variance."""
        x = x.contiguous()
        rows, channels, length = x.shape
        center = center.detach().float().contiguous()  # the same in every process
        local = torch.zeros(2 * channels + 1, dtype=torch.float64)
        _LIB.block_sums(_ptr(x), rows, channels, length, _ptr(center), _ptr(local))
        local[-1] = rows * length
        total = sum_over_processes(local)
        count = total[-1]
        shifted = total[:channels] / count
        var64 = (total[channels:2 * channels] / count - shifted ** 2).clamp(min=0)
        mean = (center.double() + shifted).float()
        invstd = torch.rsqrt(var64 + eps).float()
        scale = (weight.detach() * invstd).contiguous()
        shift = (bias.detach() - mean * scale).contiguous()
        keep = 1.0 / (1.0 - p)
        out = torch.empty_like(x)
        _LIB.block_forward(_ptr(x), _ptr(out), rows, channels, length, _ptr(scale),
                           _ptr(shift), keep, _threshold(p), seed)
        ctx.save_for_backward(x, mean, invstd, scale, shift)
        ctx.dropout = (keep, _threshold(p), seed)
        ctx.count = float(count)
        unbiased = (var64 * count / (count - 1)).float()  # what BatchNorm keeps running
        ctx.mark_non_differentiable(mean, unbiased)
        return out, mean, unbiased

    @staticmethod
    def backward(ctx: Any, grad: torch.Tensor, *_: Any) -> tuple[Any, ...]:
        """Gradients of x (the whole batch's), weight and bias (this process's share)."""
        x, mean, invstd, scale, shift = ctx.saved_tensors
        grad = grad.contiguous()
        rows, channels, length = x.shape
        dy = torch.empty_like(x)
        local = torch.zeros(2 * channels, dtype=torch.float64)
        _LIB.block_backward_sums(_ptr(grad), _ptr(x), _ptr(dy), rows, channels, length,
                                 _ptr(scale), _ptr(shift), _ptr(mean), *ctx.dropout,
                                 _ptr(local))
        total = sum_over_processes(local)
        # local sums: sum(dy) is the bias gradient, sum(dy * x_hat) the weight's
        grad_bias = local[:channels].float()
        grad_weight = (local[channels:] * invstd.double()).float()
        # dx = w invstd (dy - mean(dy) - x_hat mean(dy x_hat)), the means over the batch
        slope = -scale.double() * invstd.double() ** 2 * total[channels:] / ctx.count
        offset = -scale.double() * total[:channels] / ctx.count - slope * mean.double()
        slope, offset = slope.float(), offset.float()  # held while C reads them
        _LIB.block_backward_input(_ptr(dy), _ptr(x), rows, channels, length, _ptr(scale),
                                  _ptr(slope), _ptr(offset))
        return dy, grad_weight, grad_bias, None, None, None, None


def fusable(x: torch.Tensor, norm: nn.BatchNorm1d, gelu: nn.Module) -> bool:
    """Whether :func:`block` runs fused: built, CPU, float32, training, exact GELU."""
    return (_LIB is not None and norm.training and x.device.type == 'cpu'
            and x.dtype == torch.float32 and x.dim() == 3 and norm.affine
            and norm.track_running_stats and isinstance(gelu, nn.GELU)
            and gelu.approximate == 'none')


def block(x: torch.Tensor, norm: nn.BatchNorm1d, gelu: nn.Module,
          dropout: nn.Module) -> torch.Tensor:
    """
    ``dropout(gelu(norm(x)))``, fused where :func:`fusable`, else by the modules.

    ``dropout`` has a drop probability ``p``. In training ``norm``'s running statistics
    move as BatchNorm1d's do (momentum None: the cumulative average), with the statistics
    of the whole data-parallel batch.
    """
    if not fusable(x, norm, gelu):
        return dropout(gelu(norm(x)))
    seed = int(torch.randint(-2 ** 63, 2 ** 63 - 1, ()).item()) % 2 ** 64
    out, mean, var = _BlockFn.apply(x, norm.weight, norm.bias, norm.running_mean, norm.eps,
                                    dropout.p if dropout.training else 0.0, seed)
    update_running_stats(norm, mean, var)
    return out


__all__ = ['available', 'block', 'fusable']
