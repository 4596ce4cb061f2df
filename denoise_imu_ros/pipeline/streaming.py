# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Exact per-sample evaluation of the network, in numpy, for online use.

Each convolution keeps a buffer of its last (k - 1) * d + 1 inputs, so a new IMU sample
costs one column of every layer (~76 k multiply-adds) instead of recomputing the
511-sample window. BatchNorm (eval mode), the input normalisation and the output scale
sigma_g (with an ensemble's averaging) are folded into the convolutions, and each bias
into its matrix (an input that is always 1), so a hidden layer is four numpy calls on
preallocated buffers: gather the taps, one matrix-vector product, GELU (two calls). The
same step over the same buffers is compiled in ``_step.c`` when the package is built; it
does the arithmetic without a Python call per layer, and is used wherever it was built.
Before the first sample every buffer is filled with the activations a constant input
equal to that sample produces, which reproduces the batch model's left replication
padding: the output equals :class:`~denoise_imu_ros.learn.model.GyroNet` in eval mode
from the very first sample.
"""

from __future__ import annotations

import ctypes
import importlib.util
import math
from typing import Any, NamedTuple

import numpy as np

from ..core.architecture import BLOCK, BN_EPS, HISTORY_SLACK, ModelConfig


TINY_WEIGHT = 1e-15  # folded weights below this are 0 (see _layers)


class _CLayer(ctypes.Structure):
    """_step.c's layer_t: one hidden layer's sizes and buffers."""

    _fields_ = [(name, ctypes.c_int64) for name in
                ('groups', 'c_in', 'c_out', 'kernel', 'dilation', 'span', 'rows')] + [
                (name, ctypes.c_void_p) for name in ('pos', 'hist', 'col', 'weight', 'out')]


class _CNet(ctypes.Structure):
    """_step.c's net_t: the hidden layers, the output layer and the calibration."""

    _fields_ = [('n_layers', ctypes.c_int64), ('layers', ctypes.c_void_p),
                ('imu', ctypes.c_void_p), ('x0', ctypes.c_void_p), ('calib', ctypes.c_void_p),
                ('out_weight', ctypes.c_void_p), ('out_cols', ctypes.c_int64),
                ('out_in', ctypes.c_void_p), ('gyro', ctypes.c_void_p)]


def _load_compiled() -> Any:
    """Return _step.c's net_step, or None where the package was built without it."""
    spec = importlib.util.find_spec(f'{__package__}._step')
    if spec is None or not spec.origin:
        return None
    try:
        fn = ctypes.CDLL(spec.origin).net_step
    except (OSError, AttributeError):
        return None
    fn.argtypes, fn.restype = [ctypes.c_void_p], None
    return fn


_NET_STEP = _load_compiled()


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

    @property
    def bias_total(self) -> np.ndarray:
        """Return the groups' biases summed (the output layer's: the members' mean)."""
        return self.bias.reshape(self.groups, -1).sum(0)


# Phi, the standard normal CDF, tabulated once from math.erf: linear interpolation on this
# grid is within 3e-8 of it, below float32 precision, in one compiled call (np.interp);
# scipy.special's ndtr would cost the node 0.4 s of import. Phi(-10) is set to 0: the
# exact tail underflows to denormal floats, which this CPU multiplies ~10x slower.
_PHI_X = np.linspace(-10.0, 10.0, 20001)
_PHI = np.array([0.5 * math.erfc(-v / math.sqrt(2.0)) for v in _PHI_X])
_PHI[0] = 0.0


def _gelu(x: np.ndarray) -> np.ndarray:
    """
    GELU, x * Phi(x) as torch's (erf-based), in place; exactly 0 below x = -10.

    With the tail at 0 and no weight below TINY_WEIGHT, no product in the engine is
    denormal, so the engine needs no flush-to-zero mode (and no torch to set it).
    """
    return np.multiply(x, np.interp(x, _PHI_X, _PHI), out=x)


def _layers(cfg: ModelConfig, state: dict[str, np.ndarray]) -> list[_Layer]:
    """
    Convolutions of the network with its (eval-mode) BatchNorm folded in.

    The first also takes the input normalisation, (u - mean) / std; the last the output
    scale sigma_g and the 1 / K of an ensemble's mean. Folding is done in float64, the
    result kept in float32: a float32 matrix-vector product costs about half as much,
    and the output still matches the (float32) batch network to ~1e-7 rad/s. Weights
    that weight decay drove below TINY_WEIGHT are set to 0: as float32 they are (or
    their products are) denormal numbers, which x86 CPUs multiply about ten times more
    slowly, and they change no output by more than ~1e-13 rad/s.
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
        if i == 0:  # W (u - mean) / std = (W / std) u - W mean / std
            mean, std = state['input_mean'], state['input_std']
            b = b - (w * (mean / std)[None, :, None]).sum(axis=(1, 2))
            w = w / std[None, :, None]
        if not hidden:  # member m's three outputs are rows 3m..3m+2
            scale = np.tile(state['gyro_std'], groups) / groups
            w, b = w * scale[:, None, None], b * scale
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

    def __init__(self, config: ModelConfig, arrays: dict[str, np.ndarray],
                 compiled: bool | None = None) -> None:
        if compiled and _NET_STEP is None:
            raise RuntimeError('the compiled step (_step.c) was not built with this package')
        state = {k: np.asarray(v, dtype=np.float64) for k, v in arrays.items()}
        self.receptive_field = config.receptive_field
        self._calib = np.eye(3) + state['delta']
        self.samples = 0
        self._const = np.zeros(3)
        self._hidden: list[_Buffers] = []
        self._net: _CNet | None = None
        if config.calibration_only:
            self._const = state['gyro_std'] * state['bias']
            return
        *hidden, last = _layers(config, state)
        self._hidden = [_Buffers(ly) for ly in hidden]
        # the last hidden layer writes into a vector whose final entry stays 1: the input
        # of the output layer, whose bias is its last column
        self._out_in = np.ones(last.in_channels + 1, np.float32)
        self._hidden[-1].out = self._out_in[:-1]
        self._out = np.hstack([_dense(last), last.bias_total[:, None]]).astype(np.float32)
        if compiled is not False and _NET_STEP is not None:
            self._bind()

    @property
    def compiled(self) -> bool:
        """Whether :meth:`step` runs _step.c (else numpy)."""
        return self._net is not None

    def _bind(self) -> None:
        """Point _step.c's structures at this engine's buffers (kept alive by self)."""
        def addr(a: np.ndarray) -> int:
            assert a.flags.c_contiguous
            return a.ctypes.data
        self._imu = np.zeros(6)
        self._x0 = np.zeros(6, np.float32)
        self._gyro = np.zeros(3)
        self._c_layers = (_CLayer * len(self._hidden))(*(_CLayer(
            b.layer.groups, b.hist.shape[2], b.weight.shape[1], b.layer.kernel,
            b.layer.dilation, b.span, b.hist.shape[1], addr(b.state), addr(b.hist),
            addr(b.col), addr(b.weight), addr(b.out)) for b in self._hidden))
        self._net = _CNet(len(self._hidden), ctypes.addressof(self._c_layers), addr(self._imu),
                          addr(self._x0), addr(self._calib), addr(self._out),
                          self._out.shape[1], addr(self._out_in), addr(self._gyro))
        self._net_addr = ctypes.addressof(self._net)

    @classmethod
    def from_module(cls, model: Any, compiled: bool | None = None) -> StreamingCorrector:
        """Build the engine of an eval-mode :class:`~denoise_imu_ros.learn.model.GyroNet`."""
        if model.training:
            raise ValueError('StreamingCorrector needs a model in eval mode')
        return cls(model.config, {k: v.detach().cpu().double().numpy()
                                  for k, v in model.state_dict().items()}, compiled)

    def reset(self) -> None:
        """Forget the past: the next sample is treated as the first of a recording."""
        self.samples = 0

    def step(self, imu: np.ndarray) -> np.ndarray:
        """Corrected gyro (3,) rad/s for one raw sample (6,): gyro rad/s, accel m/s^2."""
        if not self._hidden:
            self.samples += 1
            return self._calib @ imu[:3] + self._const
        if self.samples == 0:
            x = imu.astype(np.float32)
            for buf in self._hidden:
                x = buf.prime(x)
        self.samples += 1
        if self._net is not None:
            self._imu[:] = imu
            _NET_STEP(self._net_addr)
            return self._gyro.copy()
        x = imu
        for buf in self._hidden:
            x = buf.step(x)
        return self._calib @ imu[:3] + self._out @ self._out_in

    def process(self, imu: np.ndarray) -> np.ndarray:
        """Run :meth:`step` over (N, 6) samples; returns (N, 3)."""
        return np.array([self.step(row) for row in imu]).reshape(-1, 3)


class _Buffers:
    """One hidden layer's input history, gathered taps and output, all preallocated."""

    def __init__(self, ly: _Layer) -> None:
        self.layer = ly
        self.span = (ly.kernel - 1) * ly.dilation + 1
        g, c = ly.groups, ly.in_channels // ly.groups
        # the history is written once per sample and compacted every HISTORY_SLACK
        # samples, so that the last `span` rows are always one strided slice
        self.hist = np.zeros((g, self.span + HISTORY_SLACK, c), np.float32)
        self.state = np.array([self.span - 2], np.int64)  # newest row; _step.c's too
        self.col = np.ones((g, ly.kernel * c + 1, 1), np.float32)  # taps, then a 1
        self.taps = self.col[:, :-1, 0].reshape(g, ly.kernel, c)
        self.weight = np.concatenate([ly.weight, ly.bias.reshape(g, -1, 1)], axis=2)
        self.out = np.empty(ly.bias.shape[0], np.float32)

    def prime(self, x: np.ndarray) -> np.ndarray:
        """Fill the history as if ``x`` had been the input forever; return the output."""
        g = self.layer.groups
        self.hist[:, :self.span - 1] = x.reshape(g, 1, -1)
        self.state[0] = self.span - 2
        self.out[:] = self.layer.summed @ x + self.layer.bias
        return _gelu(self.out)

    def step(self, x: np.ndarray) -> np.ndarray:
        """Take the newest input; return this layer's output (a view of its buffer)."""
        pos = int(self.state[0])
        if pos + 1 == self.hist.shape[1]:  # full: keep the last span - 1 rows
            self.hist[:, :self.span - 1] = self.hist[:, pos - self.span + 2:]
            pos = self.span - 2
        pos += 1
        self.state[0] = pos
        g, d = self.layer.groups, self.layer.dilation
        self.hist[:, pos] = x.reshape(g, -1)
        np.copyto(self.taps, self.hist[:, pos - self.span + 1:pos + 1:d])
        if g == 1:  # np.dot: a third of matmul's call overhead on small matrices
            np.dot(self.weight[0], self.col[0, :, 0], out=self.out)
        else:
            np.matmul(self.weight, self.col, out=self.out.reshape(g, -1, 1))
        return _gelu(self.out)


def _dense(last: _Layer) -> np.ndarray:
    """Return the output layer as one (3, C) matrix over every member's hidden channels."""
    return np.hstack(list(last.weight))
