# Copyright 2026 denoise_imu_ros authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Exact per-sample evaluation of the network, in numpy, for online use.

Each convolution keeps a buffer of its last (k - 1) * d + 1 inputs, so a new IMU sample
costs one column of every layer (~76 k multiply-adds) instead of recomputing the
511-sample window. BatchNorm (eval mode) is folded into the convolutions. Before the
first sample every buffer is filled with the activations a constant input equal to that
sample produces, which reproduces the batch model's left replication padding: the output
equals :class:`~denoise_imu_ros.learn.model.GyroNet` in eval mode from the very first sample.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from scipy.special import ndtr

from ..core.architecture import BLOCK, BN_EPS, ModelConfig


TINY_WEIGHT = 1e-15  # folded weights below this are 0 (see _layers)


class _Layer(NamedTuple):
    weight: np.ndarray   # (groups, c_out / groups, k * c_in / groups), taps oldest first
    summed: np.ndarray   # (c_out, c_in): sum over taps, the response to a constant input
    bias: np.ndarray     # (c_out,)
    kernel: int
    dilation: int
    gelu: bool

    @property
    def groups(self) -> int:
        """Ensemble members this layer computes side by side (1: one shared matrix)."""
        return self.weight.shape[0]

    @property
    def in_channels(self) -> int:
        """Width of the layer's input (all groups)."""
        return self.summed.shape[1]


def _gelu(x: np.ndarray) -> np.ndarray:
    """
    GELU, x * Phi(x), taken as exactly 0 below x = -10 (where it is above -8e-23).

    The exact tail underflows to denormal floats, which this CPU multiplies ~10x slower;
    with the tail at 0 and no weight below TINY_WEIGHT, no product in the engine is
    denormal, so the engine needs no flush-to-zero mode (and no torch to set it).
    """
    return np.where(x > -10.0, x * ndtr(x), x.dtype.type(0))


def _layers(cfg: ModelConfig, state: dict[str, np.ndarray]) -> list[_Layer]:
    """
    Convolutions of the network with its (eval-mode) BatchNorm folded in.

    Folding is done in float64, the result kept in float32: a float32 matrix-vector
    product costs about half as much, and the output still matches the (float32) batch
    network to ~1e-8 rad/s. Weights that weight decay drove below TINY_WEIGHT are set to
    0: as float32 they are (or their products are) denormal numbers, which this CPU
    multiplies ~10x slower (the shipped EuRoC model: 278 against 27 us per sample), and
    they change no output by more than ~1e-13 rad/s.
    """
    layers = []
    convs = cfg.convolutions()
    for i, (_, _, _, d, groups) in enumerate(convs):
        w, b = state[f'net.{BLOCK * i}.weight'], state[f'net.{BLOCK * i}.bias']
        hidden = i < len(convs) - 1
        if hidden:  # conv, BatchNorm, GELU, Dropout: four modules per hidden block
            bn = f'net.{BLOCK * i + 1}.'
            scale = state[bn + 'weight'] / np.sqrt(state[bn + 'running_var'] + BN_EPS)
            w = w * scale[:, None, None]
            b = (b - state[bn + 'running_mean']) * scale + state[bn + 'bias']
        c_out, c_group, k = w.shape
        flat = np.ascontiguousarray(w.transpose(0, 2, 1)).reshape(groups, c_out // groups, -1)
        summed = np.zeros((c_out, c_group * groups))  # block-diagonal over the groups
        for g in range(groups):
            rows = slice(g * c_out // groups, (g + 1) * c_out // groups)
            summed[rows, g * c_group:(g + 1) * c_group] = w[rows].sum(axis=2)
        flat[np.abs(flat) < TINY_WEIGHT] = 0.0
        summed[np.abs(summed) < TINY_WEIGHT] = 0.0
        layers.append(_Layer(weight=flat.astype(np.float32), summed=summed.astype(np.float32),
                             bias=b.astype(np.float32), kernel=w.shape[2], dilation=d,
                             gelu=hidden))
    return layers


class StreamingCorrector:
    """
    Corrects one IMU sample at a time; state is the layers' input history.

    Built from the architecture and the state-dict arrays (a model file's, read without
    torch), or from an eval-mode GyroNet with :meth:`from_module`.
    """

    def __init__(self, config: ModelConfig, arrays: dict[str, np.ndarray]) -> None:
        state = {k: np.asarray(v, dtype=np.float64) for k, v in arrays.items()}
        self.receptive_field = config.receptive_field
        self._mean = state['input_mean'].astype(np.float32)
        self._std = state['input_std'].astype(np.float32)
        self._gyro_std = state['gyro_std']
        self._calib = np.eye(3) + state['delta']
        if config.calibration_only:
            self._layers: list[_Layer] = []
            self._const = self._gyro_std * state['bias']
        else:
            self._layers = _layers(config, state)
            self._const = np.zeros(3)
        # History of each layer's input, stored twice over (at i and i + span) so the
        # last `span` entries are always one contiguous slice: no modulo per tap.
        self._span = [(ly.kernel - 1) * ly.dilation + 1 for ly in self._layers]
        self._hist = [np.zeros((2 * s, ly.in_channels), np.float32)
                      for s, ly in zip(self._span, self._layers)]
        self._members = config.members
        self._pos = 0
        self.samples = 0

    @classmethod
    def from_module(cls, model: Any) -> StreamingCorrector:
        """Build the engine of an eval-mode :class:`~denoise_imu_ros.learn.model.GyroNet`."""
        if model.training:
            raise ValueError('StreamingCorrector needs a model in eval mode')
        return cls(model.config, {k: v.detach().cpu().double().numpy()
                                  for k, v in model.state_dict().items()})

    def reset(self) -> None:
        """Forget the past: the next sample is treated as the first of a recording."""
        self.samples = 0

    def _prime(self, x: np.ndarray) -> None:
        """Fill every history as if ``x`` (normalised) had been the input forever."""
        for ly, hist in zip(self._layers, self._hist):
            hist[:] = x
            x = ly.summed @ x + ly.bias
            if ly.gelu:
                x = _gelu(x)
        self._pos = 0

    def step(self, imu: np.ndarray) -> np.ndarray:
        """Corrected gyro (3,) rad/s for one raw sample (6,): gyro rad/s, accel m/s^2."""
        x = (imu.astype(np.float32) - self._mean) / self._std
        if self.samples == 0:
            self._prime(x)
        self.samples += 1
        for ly, hist, span in zip(self._layers, self._hist, self._span):
            i = self._pos % span
            hist[i] = x
            hist[i + span] = x
            taps = hist[i + 1:i + span + 1:ly.dilation]     # (k, c_in), oldest first
            if ly.groups == 1:
                x = ly.weight[0] @ taps.reshape(-1) + ly.bias
            else:  # one matrix-vector product per ensemble member, batched
                per = taps.reshape(ly.kernel, ly.groups, -1).transpose(1, 0, 2)
                x = (ly.weight @ per.reshape(ly.groups, -1, 1)).reshape(-1) + ly.bias
            if ly.gelu:
                x = _gelu(x)
        self._pos += 1
        if self._layers:
            correction = self._gyro_std * x.reshape(self._members, 3).astype(np.float64).mean(0)
        else:
            correction = self._const
        return self._calib @ imu[:3] + correction

    def process(self, imu: np.ndarray) -> np.ndarray:
        """Run :meth:`step` over (N, 6) samples; returns (N, 3)."""
        return np.array([self.step(row) for row in imu]).reshape(-1, 3)
