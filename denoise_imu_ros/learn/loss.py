# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Training loss: Huber on SO(3) increments over 16 and 32 samples (Brossard et al.).

With R_k the ground-truth attitude at sample k and gyro sample k driving k -> k + 1,
the increment over block m of j samples is R_{jm}^T R_{j(m+1)}; the prediction is the
ordered product of exp(omega_hat_k dt_k) over the block, formed by a log2(j)-deep tree
of batched products in float64. Blocks do not overlap. A block counts only if the
ground truth is valid at every sample it spans. The increment lengths are powers of two
(16 and 32 in the paper); longer ones suit ground truth with more jitter per sample.
With ``heading_weight`` below 1 each error is turned into the poses' world frame, where
its component about the vertical is scaled down.
"""

from __future__ import annotations

from collections.abc import Callable
import math

import torch
import torch.nn.functional as F  # noqa: N812

from .config import LossConfig
from .so3 import quat_conj, quat_exp, quat_log, quat_mul, quat_rotate, tree_product


Count = Callable[[torch.Tensor], torch.Tensor]


def _huber(residual: torch.Tensor, valid: torch.Tensor, cfg: LossConfig,
           reduce_count: Count) -> torch.Tensor:
    """Masked mean of the component-wise Huber loss of (B, M, 3) residuals."""
    residual, valid = residual[:, cfg.skip_blocks:], valid[:, cfg.skip_blocks:]
    per = F.huber_loss(residual, torch.zeros_like(residual), reduction='none',
                       delta=cfg.huber_delta).sum(-1)
    count = reduce_count(3 * valid.sum())
    return cfg.scale * (per * valid).sum() / count.clamp(min=1)


def increment_loss(omega_hat: torch.Tensor, dt: torch.Tensor, gt_quat: torch.Tensor,
                   gt_valid: torch.Tensor, cfg: LossConfig = LossConfig(),
                   reduce_count: Count = lambda count: count) -> torch.Tensor:
    """
    Return the scalar (float64) loss of corrected gyro against ground-truth attitude.

    omega_hat (B, T, 3) is the corrected angular velocity in rad/s, T a multiple of
    cfg.span; dt (B, T) the time from each sample to the next in s; gt_quat
    (B, T + 1, 4) the xyzw ground-truth attitude at the T + 1 stamps; gt_valid
    (B, T + 1) whether ground truth is trusted at that stamp. reduce_count maps this
    batch's count of valid terms to the count the means divide by: in data-parallel
    training, the sum over processes, so that the losses of all processes add up to the
    loss of the whole batch.
    """
    b, t, _ = omega_hat.shape
    j = cfg.increments[0]
    q = quat_exp(omega_hat.double() * dt.double().unsqueeze(-1))     # (B, T, 4)
    pred = tree_product(q, int(math.log2(j)))                        # (B, T / j, 4)
    gt = gt_quat.double()
    truth = quat_mul(quat_conj(gt[:, :-1:j]), gt[:, j::j])           # (B, T / j, 4)
    ok = gt_valid[:, :t].reshape(b, t // j, j).all(-1) & gt_valid[:, j::j]
    total = torch.zeros((), dtype=torch.float64)
    for length, weight in zip(cfg.increments, cfg.weights):
        while j < length:  # one tree level up: blocks twice as long
            pred, truth = tree_product(pred, 1), tree_product(truth, 1)
            ok = ok[:, 0::2] & ok[:, 1::2]
            j *= 2
        residual = quat_log(quat_mul(quat_conj(pred), truth))  # in the body frame at its end
        if cfg.heading_weight != 1.0:
            residual = quat_rotate(gt[:, j::j], residual) * residual.new_tensor(
                [1.0, 1.0, cfg.heading_weight])
        total = total + weight * _huber(residual, ok, cfg, reduce_count)
    return total
