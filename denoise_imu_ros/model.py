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
The gyro-correcting network of Brossard et al. (RA-L 2020), shared by every path.

    omega_hat = (I + Delta) @ omega_imu + gyro_std * f(u)

f is a causal dilated 1-D CNN over the normalised IMU signal u = [gyro, accel]; the
output at sample n depends on samples n - 510 ... n only (receptive field 511).

An ensemble of K such networks trained alike (same data, so the same input
normalisation) is one network of K groups (grouped convolutions, K times wider), whose
f is the mean of the members' and whose Delta is the mean of theirs: exactly the mean
of the members' outputs, in one pass (:func:`merge`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
import math

import torch
from torch import nn
import torch.nn.functional as F  # noqa: N812


BN_EPS = 1e-5  # BatchNorm epsilon (torch's default), also used by the streaming engine


@dataclass(frozen=True)
class ModelConfig:
    """Architecture; defaults are the paper's network (77,052 trainable parameters)."""

    in_channels: int = 6                         # gyro xyz (rad/s) + accel xyz (m/s^2)
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
        if not len(self.channels) == len(self.kernels) == len(self.dilations):
            raise ValueError('channels, kernels and dilations must have the same length')
        if not isinstance(self.members, int) or self.members < 1 or (
                self.calibration_only and self.members > 1):
            raise ValueError('members must be a positive integer (1 for calibration_only)')
        if len(self.gyro_std) != 3 or min(self.gyro_std) <= 0:
            raise ValueError('gyro_std must be three positive values (rad/s)')


class Dropout(nn.Module):
    """
    Inverted dropout, like ``nn.Dropout``, with a cheaper random mask.

    ``nn.Dropout`` draws one Bernoulli variable per element, which was the largest
    single cost of a CPU training step (~40 %). Here each 64-bit random word yields
    four 16-bit uniform draws, so the drop probability is p rounded to 1/65536.
    """

    def __init__(self, p: float) -> None:
        super().__init__()
        self.p = p
        self.threshold = -32768 + round(p * 65536)  # int16 draws below it are dropped

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Drop and rescale in training mode; identity in eval mode."""
        if not self.training or self.p == 0:
            return x
        n = x.numel()
        words = torch.randint(-2**63, 2**63 - 1, ((n + 3) // 4,), dtype=torch.int64,
                              device=x.device)
        keep = (words.view(torch.int16)[:n] >= self.threshold).view(x.shape)
        # one float mask, 0 or 1 / (1 - p): a single multiply forward and backward
        return x * torch.where(keep, 1.0 / (1.0 - self.p), 0.0).to(x.dtype)


class GyroNet(nn.Module):
    """Corrected gyro from raw IMU samples; see the module docstring."""

    def __init__(self, config: ModelConfig) -> None:
        super().__init__()
        self.config = config
        # Input normalisation, set from the training data before training starts.
        self.register_buffer('input_mean', torch.zeros(config.in_channels))
        self.register_buffer('input_std', torch.ones(config.in_channels))
        self.register_buffer('gyro_std', torch.tensor(config.gyro_std, dtype=torch.float32))
        # C_omega = I + Delta starts exactly at the identity (the reference drew it at random).
        self.delta = nn.Parameter(torch.zeros(3, 3))
        if config.calibration_only:
            self.bias = nn.Parameter(torch.zeros(3))  # in units of gyro_std
            return
        layers: list[nn.Module] = []
        m = config.members  # the first layer reads the shared input; later ones per member
        c_in, groups = config.in_channels, 1
        for c_out, k, d in zip(config.channels, config.kernels, config.dilations):
            layers += [nn.Conv1d(c_in * groups, c_out * m, k, dilation=d, groups=groups),
                       nn.BatchNorm1d(c_out * m, eps=BN_EPS, momentum=config.bn_momentum),
                       nn.GELU(),
                       Dropout(config.dropout)]
            c_in, groups = c_out, m
        layers.append(nn.Conv1d(c_in * m, 3 * m, 1, groups=m))
        self.net = nn.Sequential(*layers)

    @property
    def receptive_field(self) -> int:
        """Count the samples one output depends on: the newest plus the left padding."""
        if self.config.calibration_only:
            return 1
        return 1 + sum(d * (k - 1) for k, d in zip(self.config.kernels, self.config.dilations))

    def set_normalization(self, mean: torch.Tensor, std: torch.Tensor) -> None:
        """Store per-channel input statistics (std floored to avoid division by ~0)."""
        self.input_mean.copy_(mean)
        self.input_std.copy_(torch.clamp(std, min=1e-6))

    def correction(self, u: torch.Tensor) -> torch.Tensor:
        """
        Network term f(u), before scaling by gyro_std: (B, T, 6) -> (B, T, 3).

        The first receptive_field - 1 inputs are replicated on the left, so a sequence's
        first outputs see copies of its first sample (as the reference code does).
        """
        if self.config.calibration_only:
            return self.bias.expand(u.shape[0], u.shape[1], 3)
        x = ((u - self.input_mean) / self.input_std).transpose(1, 2)  # (B, 6, T)
        x = F.pad(x, (self.receptive_field - 1, 0), mode='replicate')  # (B, 6, T + 510)
        out = self.net(x)                                               # (B, 3 K, T)
        if self.config.members > 1:
            out = out.unflatten(1, (self.config.members, 3)).mean(1)
        return out.transpose(1, 2)  # (B, T, 3)

    def forward(self, u: torch.Tensor) -> torch.Tensor:
        """Corrected angular velocity (B, T, 3) in rad/s from raw IMU samples (B, T, 6)."""
        calib = torch.eye(3, dtype=u.dtype, device=u.device) + self.delta
        return u[..., :3] @ calib.T + self.gyro_std * self.correction(u)

    def num_trainable(self) -> int:
        """Trainable parameters (the paper's count: 77,052)."""
        return sum(p.numel() for p in self.parameters() if p.requires_grad)


def merge(members: list[GyroNet]) -> GyroNet:
    """
    One eval-mode network whose output is the mean of ``members``' outputs, exactly.

    The members must share architecture, input normalisation and gyro_std (trainings of
    one recipe differing only in their seed).
    """
    first = members[0]
    base = dataclasses.replace(first.config, members=1)
    for other in members[1:]:
        if dataclasses.replace(other.config, members=1) != base:
            raise ValueError('ensemble members differ in architecture')
        for name in ('input_mean', 'input_std', 'gyro_std'):
            if not torch.equal(getattr(other, name), getattr(first, name)):
                raise ValueError(f'ensemble members differ in {name} (trained on other data?)')
    if any(m.config.members != 1 or m.config.calibration_only for m in members):
        raise ValueError('ensemble members must be single trained networks')
    merged = GyroNet(dataclasses.replace(base, members=len(members)))
    states = [m.state_dict() for m in members]
    state = {}
    for key, value in states[0].items():
        if key.startswith('net.') and not key.endswith('num_batches_tracked'):
            state[key] = torch.cat([s[key] for s in states])
        elif key == 'delta':
            state[key] = torch.stack([s[key] for s in states]).mean(0)
        else:
            state[key] = value
    merged.load_state_dict(state)
    return merged.eval()
