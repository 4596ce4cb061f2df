# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The network's dilated convolutions, forward and backward, three ways, one thread.

One worker's share of an EuRoC training step (three 16,000-sample windows) through each
hidden layer: oneDNN's convolution (what training uses), the same as gathered taps and
one matrix product, and oneDNN's in bfloat16; with the float32 GEMM speed of one core,
the best case for any of them. Prints ms and GMAC/s per layer.
Run: .venv/bin/python bench/conv_layers.py
"""

import time
from typing import Callable

from denoise_imu_ros.core.architecture import ModelConfig
import torch
import torch.nn.functional as F  # noqa: N812

WINDOWS, WINDOW = 3, 16000


def best_of(fn: Callable[[], None], repeats: int = 3) -> float:
    """Fastest of ``repeats`` timed calls after a warm-up (s)."""
    fn()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def layer(c_in: int, c_out: int, k: int, d: int, length: int, dtype: torch.dtype,
          taps: bool, windows: int = WINDOWS, input_grad: bool = True) -> float:
    """Time one dilated convolution layer forward and backward (a first: no input gradient)."""
    x = torch.randn(windows, c_in, length, dtype=dtype, requires_grad=input_grad)
    w = torch.randn(c_out, c_in, k, dtype=dtype, requires_grad=True)
    b = torch.randn(c_out, dtype=dtype, requires_grad=True)
    out = length - d * (k - 1)
    grad = torch.randn(windows, c_out, out, dtype=dtype)

    def onednn() -> None:
        F.conv1d(x, w, b, dilation=d).backward(grad)

    def gathered() -> None:
        cols = torch.stack([x[:, :, j * d:j * d + out] for j in range(k)], 2)
        y = torch.matmul(w.reshape(c_out, c_in * k), cols.reshape(windows, c_in * k, out))
        (y + b[:, None]).backward(grad)
    return best_of(gathered if taps else onednn)


def main() -> None:
    torch.set_num_threads(1)
    torch.set_flush_denormal(True)
    a, b = torch.randn(2048, 2048), torch.randn(2048, 2048)
    gemm = 2048 ** 3 / best_of(lambda: torch.mm(a, b))
    print(f'float32 GEMM, one core: {gemm / 1e9:.1f} GMAC/s')
    print(f'{"layer":>16s} {"oneDNN f32":>16s} {"taps+GEMM f32":>16s} {"oneDNN bf16":>16s}')
    length = WINDOW + ModelConfig().receptive_field - 1
    for c_in, c_out, k, d, _ in ModelConfig().convolutions()[:-1]:
        out = length - d * (k - 1)
        macs = 3 * WINDOWS * out * c_in * c_out * k  # forward, input and weight gradients
        cells = []
        for dtype, taps in ((torch.float32, False), (torch.float32, True),
                            (torch.bfloat16, False)):
            t = layer(c_in, c_out, k, d, length, dtype, taps)
            cells.append(f'{1e3 * t:7.1f} ms {macs / t / 1e9:5.1f}')
        print(f'{c_in:>4d}->{c_out:<4d} d={d:<3d} ' + ' '.join(f'{c:>16s}' for c in cells))
        length = out


if __name__ == '__main__':
    main()
