# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Unit quaternions in torch for the training path (one place, float64-friendly).

Quaternions are stored scalar-last, ``(x, y, z, w)``, as in ROS messages and
``scipy.spatial.transform``; the ASL readers convert the files' ``w, x, y, z``.
Quaternion products are used instead of 3x3 matrix products because a Hamilton
product is 16 element-wise multiplications over long tensors, which the CPU does far
faster than millions of tiny batched matmuls. Numpy code uses scipy instead.
"""

from __future__ import annotations

import torch

# Below this squared angle (rad^2) the Taylor series replaces sin/atan, which keeps both
# the value and the gradient finite at zero rotation.
_SMALL_ANGLE2 = 1e-10


def quat_mul(p: torch.Tensor, q: torch.Tensor) -> torch.Tensor:
    """Hamilton product ``p * q`` of (..., 4) xyzw quaternions: rotation q, then p."""
    px, py, pz, pw = p.unbind(-1)
    qx, qy, qz, qw = q.unbind(-1)
    return torch.stack((
        pw * qx + px * qw + py * qz - pz * qy,
        pw * qy - px * qz + py * qw + pz * qx,
        pw * qz + px * qy - py * qx + pz * qw,
        pw * qw - px * qx - py * qy - pz * qz,
    ), dim=-1)


def quat_conj(q: torch.Tensor) -> torch.Tensor:
    """Invert a unit quaternion."""
    return q * q.new_tensor([-1.0, -1.0, -1.0, 1.0])


def quat_exp(rotvec: torch.Tensor) -> torch.Tensor:
    """Map a rotation vector (..., 3) in rad to a unit quaternion (..., 4)."""
    theta2 = (rotvec * rotvec).sum(-1, keepdim=True)
    small = theta2 < _SMALL_ANGLE2
    theta = torch.sqrt(torch.where(small, torch.ones_like(theta2), theta2))
    half = 0.5 * theta
    k = torch.where(small, 0.5 - theta2 / 48.0, torch.sin(half) / theta)  # sin(t/2)/t
    w = torch.where(small, 1.0 - theta2 / 8.0, torch.cos(half))
    return torch.cat((k * rotvec, w), dim=-1)


def quat_log(q: torch.Tensor) -> torch.Tensor:
    """Map a unit quaternion (..., 4) to its rotation vector (..., 3), angle in [0, pi]."""
    q = torch.where(q[..., 3:] < 0, -q, q)  # q and -q are one rotation: take w >= 0
    v, w = q[..., :3], q[..., 3:]
    n2 = (v * v).sum(-1, keepdim=True)
    small = n2 < _SMALL_ANGLE2
    n = torch.sqrt(torch.where(small, torch.ones_like(n2), n2))
    k = torch.where(small, 2.0 / w * (1.0 - n2 / (3.0 * w * w)),
                    2.0 * torch.atan2(n, w) / n)  # angle / |v|
    return k * v


def quat_rotate(q: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """Rotate vectors (..., 3) by unit quaternions (..., 4): q v q^-1."""
    u, w = q[..., :3], q[..., 3:]
    t = 2.0 * torch.linalg.cross(u, v, dim=-1)
    return v + w * t + torch.linalg.cross(u, t, dim=-1)


def tree_product(q: torch.Tensor, levels: int) -> torch.Tensor:
    """
    Ordered products of 2**levels consecutive quaternions along dim -2.

    (..., M * 2**levels, 4) -> (..., M, 4), element m being q[s] * q[s+1] * ... with
    s = m * 2**levels; ``levels`` batched products instead of a sequential loop.
    """
    for _ in range(levels):
        q = quat_mul(q[..., 0::2, :], q[..., 1::2, :])
    return q


def prefix_product(q: torch.Tensor) -> torch.Tensor:
    """
    Return the attitudes of ordered products of quaternions along dim -2, identity first.

    (..., T, 4) -> (..., T + 1, 4), element k being q[0] * q[1] * ... * q[k - 1]: the
    attitude at stamp k relative to stamp 0. A work-efficient parallel scan: pairs are
    multiplied (as in :func:`tree_product`), their prefix found recursively, and each
    even element from the prefix before it; about 2T batched products in all.
    """
    identity = q.new_zeros(q.shape[:-2] + (1, 4))
    identity[..., 3] = 1.0
    return torch.cat((identity, _inclusive(q, identity)), -2)


def _inclusive(q: torch.Tensor, identity: torch.Tensor) -> torch.Tensor:
    """Return (..., T, 4): element k the ordered product q[0] * ... * q[k]."""
    n = q.shape[-2]
    if n <= 1:
        return q
    if n % 2:  # an identity at the end pairs the last element, and is dropped after
        return _inclusive(torch.cat((q, identity), -2), identity)[..., :n, :]
    odd = _inclusive(quat_mul(q[..., 0::2, :], q[..., 1::2, :]), identity)  # q[0] ... q[2i+1]
    even = torch.cat((q[..., :1, :], quat_mul(odd[..., :-1, :], q[..., 2::2, :])), -2)
    return torch.stack((even, odd), -2).reshape(q.shape)
