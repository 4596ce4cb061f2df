# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Quaternion arithmetic where scipy's rotations cost more than the work; tested against it.

The robot path composes one unit quaternion (xyzw, body to world) with one small
rotation per sample, on plain floats: ``scipy.spatial.transform`` costs more to import
(about half the node's start-up) and to call than this work. Offline, integrating a
recording composes every step with the next (metrics.integrate): scipy's composition of
two arrays of rotations costs about 15 times numpy's products here, and the clock-offset
search fits a frame to a few thousand rate pairs some 1500 times a recording, where
scipy's align_vectors costs several times the SVD it wraps (:func:`kabsch`), and scipy's
rotation vectors of an array cost about 4 times :func:`log_arrays`. Everything else
offline (constructors, splines' fits, Euler angles) uses scipy.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

Quat = tuple[float, float, float, float]  # x, y, z, w

_SMALL_ANGLE = 1e-8  # rad: below it sin(a/2)/a is its Taylor series


def exp(rx: float, ry: float, rz: float) -> Quat:
    """Return the unit quaternion of a rotation vector (rad)."""
    angle = math.sqrt(rx * rx + ry * ry + rz * rz)
    if angle < _SMALL_ANGLE:
        k = 0.5 - angle * angle / 48.0
    else:
        k = math.sin(0.5 * angle) / angle
    return rx * k, ry * k, rz * k, math.cos(0.5 * angle)


def hamilton(p: Any, q: Any) -> tuple[Any, Any, Any, Any]:
    """
    Return the Hamilton product's components, of floats or of arrays alike.

    Not renormalised: the same operations on floats (online) and on arrays (a batch)
    give the same numbers bit for bit.
    """
    px, py, pz, pw = p
    qx, qy, qz, qw = q
    return (pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
            pw * qw - px * qx - py * qy - pz * qz)


def multiply(p: Quat, q: Quat) -> Quat:
    """Hamilton product p q (rotation q, then p), renormalised against drift."""
    x, y, z, w = hamilton(p, q)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    return x / n, y / n, z / n, w / n


def yaw_turn(q: Quat) -> Quat:
    """
    Return the turn about z by ``q``'s yaw (the first angle of its Z-Y-X decomposition).

    From the rotation matrix's first column by square roots alone, no trigonometry: the
    same floats online and in a batch. Half the yaw's (sin, cos) is along (b, r + a) and
    along (r - a, b), a and b its cosine and sine times r: the one without cancellation is
    taken (its sign is the quaternion's, the same turn). An undefined yaw (the x axis
    vertical) is none.
    """
    x, y, z, w = q
    a = 1.0 - 2.0 * (y * y + z * z)
    b = 2.0 * (w * z + x * y)
    r = math.sqrt(a * a + b * b)
    if r < _SMALL_ANGLE:
        return 0.0, 0.0, 0.0, 1.0
    s, c = (b, r + a) if a >= 0.0 else (r - a, b)
    n = math.sqrt(s * s + c * c)
    return 0.0, 0.0, s / n, c / n


def with_tilt_of(heading: Quat, tilt: Quat) -> Quat:
    """Return the orientation with ``heading``'s yaw and ``tilt``'s roll and pitch (xyzw)."""
    _, _, hz, hw = yaw_turn(heading)
    _, _, tz, tw = yaw_turn(tilt)
    return multiply((0.0, 0.0, hz * tw - hw * tz, hw * tw + hz * tz), tilt)  # Rz(h) Rz(t)^-1


def conjugate_arrays(q: np.ndarray) -> np.ndarray:
    """Inverses of (..., 4) xyzw unit quaternions."""
    return q * [-1.0, -1.0, -1.0, 1.0]


def multiply_arrays(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Products p q of (..., 4) xyzw quaternion arrays (broadcast), renormalised."""
    out = np.stack(hamilton(np.moveaxis(p, -1, 0), np.moveaxis(q, -1, 0)), axis=-1)
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def relative_arrays(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Rotations p^-1 q of (..., 4) xyzw unit quaternion arrays: from each p to its q."""
    return multiply_arrays(conjugate_arrays(p), q)


def log_arrays(q: np.ndarray) -> np.ndarray:
    """
    Rotation vectors (..., 3) of (..., 4) xyzw unit quaternions, angles within [0, pi].

    scipy's formula (``Rotation.as_rotvec``): the quaternion's sign scipy's (w > 0, or at
    a half turn the first non-zero of x, y, z), the angle from atan2, its Taylor series
    below 1e-3 rad. Not normalised first, unlike scipy: for quaternions of unit norm, as
    :func:`multiply_arrays` returns them.
    """
    x, y, z, w = np.moveaxis(q, -1, 0)
    flip = (w < 0) | ((w == 0) & ((x < 0) | ((x == 0) & ((y < 0) | ((y == 0) & (z < 0))))))
    q = np.where(flip[..., None], -q, q)
    angle = 2.0 * np.arctan2(np.linalg.norm(q[..., :3], axis=-1), q[..., 3])
    small = angle <= 1e-3
    square = angle * angle
    scale = np.where(small, 2.0 + square / 12.0 + 7.0 * square * square / 2880.0,
                     angle / (np.sin(0.5 * angle) + small))
    return scale[..., None] * q[..., :3]


def from_gravity(ax: float, ay: float, az: float) -> Quat:
    """Return roll and pitch from a (static) accelerometer reading, yaw 0 (z up)."""
    roll = math.atan2(ay, az)
    pitch = math.atan2(-ax, math.hypot(ay, az))
    cr, sr = math.cos(0.5 * roll), math.sin(0.5 * roll)
    cp, sp = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    return sr * cp, cr * sp, -sr * sp, cr * cp  # Rz(0) Ry(pitch) Rx(roll)


def level_heading(q: Any) -> Quat:
    """
    Return the turn about z that gives the xyzw ``q`` yaw 0, as :func:`from_gravity`'s.

    Its product with ``q`` has q's tilt and the ZYX yaw 0 (pitch within +-90 deg): the
    inverse of :func:`yaw_turn`.
    """
    _, _, s, c = yaw_turn(tuple(float(v) for v in q))
    return 0.0, 0.0, -s, c


def kabsch(h: np.ndarray) -> np.ndarray:
    """
    Return the rotation R maximising trace(R h), h the 3x3 sum of b_i a_i^T.

    The SVD of h, its smallest singular direction flipped where the best orthogonal
    matrix is a reflection.
    """
    u, _, vt = np.linalg.svd(h)
    flip = np.ones(3)
    flip[2] = np.sign(np.linalg.det(u @ vt))  # +-1: u and vt are orthogonal
    return (vt.T * flip) @ u.T
