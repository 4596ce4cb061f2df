# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
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

import numpy as np
import torch
from torch import nn
import torch.nn.functional as F  # noqa: N812

from . import fused
from ..core.architecture import BLOCK, BN_EPS, ModelConfig

CHUNK = 65536  # samples per network call in correct_gyro; long recordings go in pieces


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
        self.fuse_layers = True  # see _layers; False: PyTorch's layers one by one
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
        *hidden, (c_in, c_out, _, _, groups) = config.convolutions()
        for c_in_h, c_out_h, k, d, g in hidden:  # conv, BatchNorm, GELU, dropout
            layers += [nn.Conv1d(c_in_h, c_out_h, k, dilation=d, groups=g),
                       nn.BatchNorm1d(c_out_h, eps=BN_EPS, momentum=config.bn_momentum),
                       nn.GELU(),
                       Dropout(config.dropout)]
        layers.append(nn.Conv1d(c_in, c_out, 1, groups=groups))
        self.net = nn.Sequential(*layers)

    @property
    def receptive_field(self) -> int:
        """Count the samples one output depends on: the newest plus the left padding."""
        return self.config.receptive_field

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
        out = self._layers(x)                                           # (B, 3 K, T)
        if self.config.members > 1:
            out = out.unflatten(1, (self.config.members, 3)).mean(1)
        return out.transpose(1, 2)  # (B, T, 3)

    def _layers(self, x: torch.Tensor) -> torch.Tensor:
        """Run the convolutions, each hidden one's BatchNorm, GELU and dropout in one call."""
        if not self.fuse_layers:
            return self.net(x)
        for i in range(0, len(self.net) - 1, BLOCK):
            conv, norm, gelu, dropout = self.net[i:i + BLOCK]
            x = fused.block(conv(x), norm, gelu, dropout)
        return self.net[-1](x)

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

    The members must share the architecture (trainings of one recipe, e.g. differing in
    their seed). Their input normalisations and gyro_std may differ (the statistics of
    two runs on the same data differ in the last float32 digits): the first member's are
    kept and each member's own are folded into its first and last convolutions, which is
    exact since both are affine (the first layer's replication padding commutes with it).
    """
    first = members[0]
    base = dataclasses.replace(first.config, members=1)
    for k, other in enumerate(members):
        if other.config.calibration_only:
            raise ValueError(f'member {k + 1} is a calibration: an ensemble averages networks')
        if other.config.members != 1:
            raise ValueError(f'member {k + 1} is an ensemble of {other.config.members} already: '
                             'give its trainings instead')
        if dataclasses.replace(other.config, gyro_std=base.gyro_std) != base:
            raise ValueError(f'member {k + 1} differs in architecture from member 1')
    merged = GyroNet(dataclasses.replace(base, members=len(members)))
    last = f'net.{len(base.channels) * BLOCK}.'
    states = []
    with torch.no_grad():
        for m in members:
            st = {k: v.detach().clone() for k, v in m.state_dict().items()}
            # (u - mu_k) / s_k = (s / s_k) (u - mu) / s + (mu - mu_k) / s_k
            scale = first.input_std / m.input_std
            shift = (first.input_mean - m.input_mean) / m.input_std
            w = st['net.0.weight'].double()                         # (c_out, 6, k)
            st['net.0.bias'] = (st['net.0.bias'].double()
                                + (w * shift.double()[None, :, None]).sum((1, 2))).float()
            st['net.0.weight'] = (w * scale.double()[None, :, None]).float()
            # gyro_std_k f_k = gyro_std (gyro_std_k / gyro_std) f_k
            ratio = (m.gyro_std / first.gyro_std)
            st[last + 'weight'] = st[last + 'weight'] * ratio[:, None, None]
            st[last + 'bias'] = st[last + 'bias'] * ratio
            states.append(st)
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


@torch.no_grad()
def correct_gyro(model: GyroNet, imu: np.ndarray) -> np.ndarray:
    """
    Corrected gyro (N, 3) rad/s for raw samples (N, 6), exactly as one batch call.

    Chunks after the first get receptive_field - 1 samples of real context, so their
    outputs equal those of a single call over the whole recording.
    """
    ctx = model.receptive_field - 1
    u = torch.as_tensor(imu, dtype=torch.float32)
    out = []
    for start in range(0, len(u), CHUNK):
        first = max(0, start - ctx)
        out.append(model(u[None, first:start + CHUNK])[0, start - first:])
    return torch.cat(out).double().numpy()
