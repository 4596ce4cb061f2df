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

With ``between_poses`` the increments run between the IMU samples nearest two pose
stamps instead, from each pose to the first at least the increment's length later (at
most twice it): poses too sparse for their motion (a SLAM's keyframes) are wrong between
their stamps, however interpolated, and right at them. The prediction is then the
prefix product of the whole window (a log2(T)-deep scan).
"""

from __future__ import annotations

from collections.abc import Callable
import math

import torch
import torch.nn.functional as F  # noqa: N812

from .config import LossConfig
from .so3 import (prefix_product, quat_conj, quat_exp, quat_log, quat_mul, quat_rotate,
                  tree_product)
from ..core.metrics import MAX_STRETCH


Count = Callable[[torch.Tensor], torch.Tensor]


def _huber(residual: torch.Tensor, valid: torch.Tensor, cfg: LossConfig,
           reduce_count: Count) -> torch.Tensor:
    """Masked mean of the component-wise Huber loss of (B, M, 3) residuals."""
    per = F.huber_loss(residual, torch.zeros_like(residual), reduction='none',
                       delta=cfg.huber_delta).sum(-1)
    count = reduce_count(3 * valid.sum())
    return cfg.scale * (per * valid).sum() / count.clamp(min=1)


def _in_world(residual: torch.Tensor, gt_end: torch.Tensor, cfg: LossConfig) -> torch.Tensor:
    """Return body-frame errors, turned into the world and weighed about the vertical."""
    if cfg.heading_weight == 1.0:
        return residual
    return quat_rotate(gt_end, residual) * residual.new_tensor([1.0, 1.0, cfg.heading_weight])


def increment_loss(omega_hat: torch.Tensor, dt: torch.Tensor, gt_quat: torch.Tensor,
                   gt_valid: torch.Tensor, cfg: LossConfig = LossConfig(),
                   reduce_count: Count = lambda count: count,
                   pose_at: torch.Tensor | None = None) -> torch.Tensor:
    """
    Return the scalar (float64) loss of corrected gyro against ground-truth attitude.

    omega_hat (B, T, 3) is the corrected angular velocity in rad/s, T a multiple of
    cfg.span; dt (B, T) the time from each sample to the next in s; gt_quat
    (B, T + 1, 4) the xyzw ground-truth attitude at the T + 1 stamps; gt_valid
    (B, T + 1) whether ground truth is trusted at that stamp. reduce_count maps this
    batch's count of valid terms to the count the means divide by: in data-parallel
    training, the sum over processes, so that the losses of all processes add up to the
    loss of the whole batch. pose_at (B, T + 1), with ``cfg.between_poses`` only: whether
    a pose stamp is nearest that stamp.
    """
    if cfg.between_poses:
        if pose_at is None:
            raise ValueError('increments between poses need the pose stamps (pose_at)')
        return _between_poses(omega_hat, dt, gt_quat, gt_valid, pose_at, cfg, reduce_count)
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
        residual = _in_world(residual, gt[:, j::j], cfg)
        skip = cfg.skip_blocks
        total = total + weight * _huber(residual[:, skip:], ok[:, skip:], cfg, reduce_count)
    return total


def _between_poses(omega_hat: torch.Tensor, dt: torch.Tensor, gt_quat: torch.Tensor,
                   gt_valid: torch.Tensor, pose_at: torch.Tensor, cfg: LossConfig,
                   reduce_count: Count) -> torch.Tensor:
    """Return the loss over increments from each pose to the first one a length later."""
    att = prefix_product(quat_exp(omega_hat.double() * dt.double().unsqueeze(-1)))
    gt = gt_quat.double()
    total = torch.zeros((), dtype=torch.float64)
    for length, weight in zip(cfg.increments, cfg.weights):
        end, ok = pose_increments(pose_at, gt_valid, length, cfg.skip_blocks * length)
        row, start = ok.nonzero(as_tuple=True)  # only the increments that count
        stop = end[row, start]
        pred = quat_mul(quat_conj(att[row, start]), att[row, stop])
        truth = quat_mul(quat_conj(gt[row, start]), gt[row, stop])
        residual = _in_world(quat_log(quat_mul(quat_conj(pred), truth)), gt[row, stop], cfg)
        total = total + weight * _huber(residual[None], ok.new_ones(1, len(row)), cfg,
                                        reduce_count)
    return total


def pose_increments(pose_at: torch.Tensor, gt_valid: torch.Tensor, length: int,
                    first: int = 0) -> tuple[torch.Tensor, torch.Tensor]:
    """
    Return the end of the increment between poses from each stamp, and whether it counts.

    pose_at and gt_valid (B, T + 1); both results (B, T + 1 - length): the first pose
    stamp at least ``length`` samples later (clamped to T), and whether the start is a
    pose stamp from ``first`` on whose increment spans at most MAX_STRETCH times
    ``length`` with the poses trusted throughout: per window, on the device, the
    increments :func:`~denoise_imu_ros.core.metrics.increments` finds in a recording.
    """
    t = pose_at.shape[1] - 1
    index = torch.arange(t + 1, device=pose_at.device)
    # the next pose on or after each stamp (t + 1: none), and untrusted stamps up to each
    later = torch.where(pose_at, index, t + 1).flip(-1).cummin(-1).values.flip(-1)
    untrusted = torch.cumsum(~gt_valid, -1)
    n = max(0, t + 1 - length)  # a window shorter than the length holds none
    start, end = index[:n], later[:, length:length + n]
    end_at = end.clamp(max=t)
    ok = (pose_at[:, :n] & (end <= t) & (end - start <= MAX_STRETCH * length)
          & (start >= first) & gt_valid[:, :n]
          & (untrusted.gather(1, end_at) == untrusted[:, :n]))
    return end_at, ok
