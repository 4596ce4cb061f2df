# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The network's geometry without torch: configuration, receptive field, weight layout.

The online runtime (streaming engine, node, bag tools) builds the network from a model
file's arrays with this alone; :mod:`denoise_imu_ros.learn.model` builds the torch module for
training and batch evaluation from the same configuration.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

BN_EPS = 1e-5  # BatchNorm epsilon (torch's default), also used by the streaming engine
BLOCK = 4      # modules per hidden block in GyroNet.net: conv, BatchNorm, GELU, dropout
IMU_CHANNELS = 6  # what every tool feeds the network: gyro xyz, accelerometer xyz
# bounds of what a model file may ask the runtime to allocate (model files are user input)
MAX_WIDTH = 4096
MAX_RECEPTIVE_FIELD = 1 << 16
MAX_MEMBERS = 64
MAX_STREAM_STATE = 1 << 26  # float32 values of the streaming engine's histories (256 MB)
HISTORY_SLACK = 1024  # rows a streaming history grows by between two compactions


def _counts(values: tuple[int, ...], upper: int | None = None) -> bool:
    """Whether every value is an integer of at least 1 (and at most ``upper``)."""
    return all(isinstance(v, int) and not isinstance(v, bool) and v >= 1
               and (upper is None or v <= upper) for v in values)


@dataclass(frozen=True)
class ModelConfig:
    """Architecture; defaults are the paper's network (77,052 trainable parameters)."""

    in_channels: int = IMU_CHANNELS              # gyro xyz (rad/s) + accel xyz (m/s^2)
    channels: tuple[int, ...] = (16, 32, 64, 128)  # hidden widths, doubling per layer
    kernels: tuple[int, ...] = (7, 7, 7, 7)      # hidden kernel sizes
    dilations: tuple[int, ...] = (1, 4, 16, 64)  # cumulative products of [4, 4, 4]
    dropout: float = 0.1                         # after each hidden block
    bn_momentum: float = 0.1
    # sigma_g, rad/s: scales f(u) so that early outputs are small (EuRoC [1, 2, 5] deg/s)
    gyro_std: tuple[float, float, float] = tuple(math.radians(d) for d in (1.0, 2.0, 5.0))
    # The paper's "calibrated IMU" baseline: no network, only I + Delta and a bias (12).
    calibration_only: bool = False
    members: int = 1                             # ensemble size (networks averaged)

    def __post_init__(self) -> None:
        """Reject inconsistent layer lists early (config files are user input)."""
        if self.in_channels != IMU_CHANNELS:
            raise ValueError(f'in_channels must be {IMU_CHANNELS} (gyro and accelerometer xyz), '
                             f'not {self.in_channels!r}')
        if not len(self.channels) == len(self.kernels) == len(self.dilations):
            raise ValueError('channels, kernels and dilations must have the same length')
        if not (_counts(self.channels, MAX_WIDTH) and _counts(self.kernels)
                and _counts(self.dilations)):
            raise ValueError(f'channels (at most {MAX_WIDTH}), kernels and dilations must be '
                             'positive integers')
        if not self.calibration_only and not self.channels:
            raise ValueError('a network needs at least one hidden layer (channels)')
        if self.receptive_field > MAX_RECEPTIVE_FIELD:
            raise ValueError(f'receptive field {self.receptive_field} samples: more than '
                             f'{MAX_RECEPTIVE_FIELD}')
        if not 0.0 <= self.dropout < 1.0 or not 0.0 <= self.bn_momentum <= 1.0:
            raise ValueError('dropout must be in [0, 1) and bn_momentum in [0, 1]')
        if len(self.gyro_std) != 3 or min(self.gyro_std) <= 0:
            raise ValueError('gyro_std must be three positive values (rad/s)')
        if not _counts((self.members,), MAX_MEMBERS) or (
                self.calibration_only and self.members > 1):
            raise ValueError(f'members must be an integer from 1 to {MAX_MEMBERS} (1 for '
                             'calibration_only)')
        state = self.stream_state()
        if state > MAX_STREAM_STATE:
            raise ValueError(f'the streaming engine would hold {state:,} values of history: '
                             f'more than {MAX_STREAM_STATE:,}')

    def stream_state(self) -> int:
        """Count the float32 values of the streaming engine's input histories."""
        if self.calibration_only:
            return 0
        return sum(c_in * ((k - 1) * d + 1 + HISTORY_SLACK)
                   for c_in, _, k, d, _ in self.convolutions()[:-1])

    @property
    def receptive_field(self) -> int:
        """Count the samples one output depends on: the newest plus the left padding."""
        if self.calibration_only:
            return 1
        return 1 + sum(d * (k - 1) for k, d in zip(self.kernels, self.dilations))

    def convolutions(self) -> list[tuple[int, int, int, int, int]]:
        """(c_in, c_out, kernel, dilation, groups) of every convolution, input to output."""
        m, convs = self.members, []
        c_in, groups = self.in_channels, 1  # the first layer reads the shared input
        for c_out, k, d in zip(self.channels, self.kernels, self.dilations):
            convs.append((c_in * groups, c_out * m, k, d, groups))
            c_in, groups = c_out, m
        convs.append((c_in * m, 3 * m, 1, 1, m))
        return convs

    def state_shapes(self) -> dict[str, tuple[int, ...]]:
        """Name and shape of every array of the state dict, as GyroNet names them."""
        shapes: dict[str, tuple[int, ...]] = {
            'input_mean': (self.in_channels,), 'input_std': (self.in_channels,),
            'gyro_std': (3,), 'delta': (3, 3)}
        if self.calibration_only:
            return dict(shapes, bias=(3,))
        convs = self.convolutions()
        for i, (c_in, c_out, k, _, groups) in enumerate(convs):
            shapes[f'net.{BLOCK * i}.weight'] = (c_out, c_in // groups, k)
            shapes[f'net.{BLOCK * i}.bias'] = (c_out,)
            if i < len(convs) - 1:
                bn = f'net.{BLOCK * i + 1}.'
                shapes.update({bn + 'weight': (c_out,), bn + 'bias': (c_out,),
                               bn + 'running_mean': (c_out,), bn + 'running_var': (c_out,),
                               bn + 'num_batches_tracked': ()})
        return shapes
