# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
IMU increments pre-integrated over windows against the ground truth's, as a VIO weighs them.

A VIO back-end (OpenVINS, VINS-Fusion, a GTSAM smoother) does not integrate the gyro
from the start: between two keyframes i and j it pre-integrates the gyro and the
accelerometer into a rotation, velocity and position increment (Forster et al., "On-
Manifold Preintegration", T-RO 2017) and weighs them by their propagated covariance:

    dR_ij = prod_k Exp(w_k dt_k)
    dv_ij = sum_k dR_ik a_k dt_k
    dp_ij = sum_k (dv_ik dt_k + dR_ik a_k dt_k^2 / 2)

The ground truth's own increments, from its state at i and j in a world whose z points
up (gravity g = (0, 0, -GRAVITY)):

    dR_ij = R_i^T R_j
    dv_ij = R_i^T (v_j - v_i - g dt_ij)
    dp_ij = R_i^T (p_j - p_i - v_i dt_ij - g dt_ij^2 / 2)

The error of an IMU's increments is what a VIO is fed wrong: rotation (the angle of
dR_gt^T dR_imu), velocity and position (norms). With a covariance per sample (the
variance of each measurement, as sensor_msgs/Imu's covariance fields give it) the
increments' covariance is propagated as the paper's equations (the right Jacobian of a
sample's rotation taken as the identity, as it is to 1e-4 at these rates), and the
normalised squared error (NEES) of each increment says whether the covariance describes
the error: chi-square with 3 degrees of freedom if it does (mean 3, 73.9 % below 4, the
2-sigma ellipsoid). bench/preintegration.py checks it against GTSAM's
PreintegratedImuMeasurements.

Where the ground truth has positions only, its velocity is their derivative, by a local
quadratic fit (Savitzky-Golay) over VELOCITY_SPAN_S.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ..core.errors import DatasetError
from ..core.limits import GRAVITY_M_S2
from ..data.asl import read_csv

__all__ = ['GRAVITY', 'VELOCITY_SPAN_S', 'Increments', 'errors', 'ground_truth_velocity',
           'preintegrate', 'reference', 'velocity_from_positions', 'window_starts']

GRAVITY = GRAVITY_M_S2   # m/s^2, standard gravity, the poses' world's
VELOCITY_SPAN_S = 0.1    # s, the fit of the positions that gives a velocity


@dataclass(frozen=True)
class Increments:
    """Increments of W windows: rotation (W, 3, 3), velocity and position (W, 3)."""

    rotation: np.ndarray
    velocity: np.ndarray
    position: np.ndarray
    # (W, 9, 9) in the order rotation (rad), velocity, position; None: not propagated
    covariance: np.ndarray | None = None


def window_starts(valid: np.ndarray, length: int, stride: int | None = None) -> np.ndarray:
    """Return the starts of ``length``-sample windows whose ground truth is trusted throughout."""
    stride = length if stride is None else stride
    n = len(valid) - length - 1  # a window's poses: its first sample's and the one after
    if n < 0:
        return np.zeros(0, np.int64)
    bad = np.concatenate([[0], np.cumsum(~np.asarray(valid, bool))])
    starts = np.arange(0, n + 1, stride)
    return starts[bad[starts + length + 1] - bad[starts] == 0]


def velocity_from_positions(position: np.ndarray, stamp_s: np.ndarray,
                            span_s: float = VELOCITY_SPAN_S) -> np.ndarray:
    """Return the velocity (N, 3) of positions at regular stamps by a local quadratic fit."""
    from scipy.signal import savgol_filter  # importing scipy.signal costs more than a fit
    dt = float(np.median(np.diff(stamp_s)))
    window = max(5, int(round(span_s / dt)) | 1)  # odd, and more samples than the order
    return savgol_filter(position, window, 2, deriv=1, delta=dt, axis=0)


def ground_truth_velocity(folder: Path, stamp_ns: np.ndarray, position: np.ndarray,
                          stamp_s: np.ndarray) -> tuple[np.ndarray, str]:
    """
    Return the velocity (N, 3) at the IMU stamps, and where it came from.

    An ASL folder's state estimate (EuRoC's) where it has one, else the positions'
    derivative (:func:`velocity_from_positions`).
    """
    try:  # t, p xyz, q wxyz, v xyz (EuRoC's has biases after them)
        stamps, rows = read_csv(folder / 'mav0' / 'state_groundtruth_estimate0' / 'data.csv', 11)
    except DatasetError:  # no such file, or poses without velocities
        return velocity_from_positions(position, stamp_s), 'positions'
    return np.stack([np.interp(stamp_ns, stamps, rows[:, c]) for c in (7, 8, 9)],
                    axis=1), 'state estimate'


def _skew(v: np.ndarray) -> np.ndarray:
    """Return the cross-product matrices (W, 3, 3) of vectors (W, 3)."""
    s = np.zeros(v.shape[:-1] + (3, 3))
    s[..., 0, 1], s[..., 0, 2], s[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    return s - np.swapaxes(s, -1, -2)


def preintegrate(gyro: np.ndarray, accel: np.ndarray, stamp_s: np.ndarray,
                 starts: np.ndarray, length: int, gyro_var: np.ndarray | None = None,
                 accel_var: np.ndarray | None = None) -> Increments:
    """
    Pre-integrate samples ``[s, s + length)`` of every start ``s``, each over its interval.

    Sample k holds from ``stamp_s[k]`` to ``stamp_s[k + 1]``, so the last one integrated
    needs the stamp after it (:func:`window_starts` leaves room). ``gyro_var`` and
    ``accel_var`` (N, 3): each sample's measurement variance per axis
    ((rad/s)^2, (m/s^2)^2); given both, the increments' covariance is propagated too.
    """
    w, dt = len(starts), np.diff(stamp_s)
    rot = np.broadcast_to(np.eye(3), (w, 3, 3)).copy()
    vel, pos = np.zeros((w, 3)), np.zeros((w, 3))
    propagate = gyro_var is not None and accel_var is not None
    cov = np.zeros((w, 9, 9)) if propagate else None
    for k in range(length):
        idx = starts + k
        h = dt[idx][:, None]
        a_world = np.einsum('wij,wj->wi', rot, accel[idx])  # in the window's first frame
        step = Rotation.from_rotvec(gyro[idx] * h).as_matrix()
        if propagate:
            ra = rot @ _skew(accel[idx])
            a = np.broadcast_to(np.eye(9), (w, 9, 9)).copy()
            a[:, :3, :3] = np.swapaxes(step, 1, 2)
            a[:, 3:6, :3] = -ra * h[:, :, None]
            a[:, 6:, :3] = -0.5 * ra * h[:, :, None] ** 2
            a[:, 6:, 3:6] = np.eye(3) * h[:, :, None]
            b = np.zeros((w, 9, 6))
            b[:, :3, :3] = np.eye(3) * h[:, :, None]
            b[:, 3:6, 3:] = rot * h[:, :, None]
            b[:, 6:, 3:] = 0.5 * rot * h[:, :, None] ** 2
            noise = np.concatenate([gyro_var[idx], accel_var[idx]], axis=1)
            cov = a @ cov @ np.swapaxes(a, 1, 2) + (b * noise[:, None, :]) @ np.swapaxes(b, 1, 2)
        pos += vel * h + 0.5 * a_world * h ** 2
        vel += a_world * h
        rot = rot @ step
    return Increments(rot, vel, pos, cov)


def reference(gt_quat: np.ndarray, gt_pos: np.ndarray, gt_vel: np.ndarray,
              stamp_s: np.ndarray, starts: np.ndarray, length: int,
              gravity: float = GRAVITY) -> Increments:
    """Return the ground truth's increments over the same windows as :func:`preintegrate`."""
    ends = starts + length
    r_i = Rotation.from_quat(gt_quat[starts]).as_matrix()
    r_j = Rotation.from_quat(gt_quat[ends]).as_matrix()
    span = (stamp_s[ends] - stamp_s[starts])[:, None]
    g = np.array([0.0, 0.0, -gravity])
    to_body = np.swapaxes(r_i, 1, 2)
    dv = gt_vel[ends] - gt_vel[starts] - g * span
    dp = gt_pos[ends] - gt_pos[starts] - gt_vel[starts] * span - 0.5 * g * span ** 2
    return Increments(to_body @ r_j, np.einsum('wij,wj->wi', to_body, dv),
                      np.einsum('wij,wj->wi', to_body, dp))


def errors(est: Increments, ref: Increments) -> dict[str, np.ndarray]:
    """
    Return each window's errors: rotation (deg), velocity (m/s), position (m).

    With ``est``'s covariance, also the NEES of the rotation, velocity and position
    increments (each chi-square with 3 degrees of freedom when the covariance is right).
    """
    rot_err = Rotation.from_matrix(np.swapaxes(ref.rotation, 1, 2) @ est.rotation).as_rotvec()
    out = {'rotation_deg': np.degrees(np.linalg.norm(rot_err, axis=1)),
           'velocity_m_s': np.linalg.norm(est.velocity - ref.velocity, axis=1),
           'position_m': np.linalg.norm(est.position - ref.position, axis=1)}
    if est.covariance is not None:
        for name, err, block in (('rotation', rot_err, slice(0, 3)),
                                 ('velocity', est.velocity - ref.velocity, slice(3, 6)),
                                 ('position', est.position - ref.position, slice(6, 9))):
            p = est.covariance[:, block, block]
            solved = np.linalg.solve(p, err[..., None])[..., 0]
            out[f'nees_{name}'] = np.einsum('wi,wi->w', err, solved)
    return out
