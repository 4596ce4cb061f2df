# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Open-loop attitude integration and the paper's error metrics (numpy + scipy).

One index convention everywhere: gyro sample k drives the attitude from stamp k to
stamp k + 1 (R_{k+1} = R_k Exp(omega_k dt_k)), starting from the ground-truth attitude
at the first stamp. The training loss uses the same convention.
"""

from __future__ import annotations

from typing import NamedTuple, TYPE_CHECKING

import numpy as np
from scipy.spatial.transform import Rotation

from .rotation import conjugate_arrays, log_arrays, multiply_arrays, relative_arrays

if TYPE_CHECKING:
    from .records import Sequence

ROE_DISTANCES_M = (7.0, 21.0, 35.0)
SCAN_BLOCK = 16  # steps composed per block by integrate (4x faster than one scan)
RESIDUAL_BLOCK = 16  # samples per increment of the gyro residual estimate (training, noise)
ALIGN_AT_S = 1.5  # a fused orientation's arbitrary yaw is aligned to the ground truth here
MAX_STRETCH = 2  # an increment between poses spans at most this many times its length


def _prefix_products(q: np.ndarray) -> np.ndarray:
    """Inclusive ordered products q_0 ... q_k of (M, 4) xyzw quaternions, in place."""
    shift = 1
    while shift < len(q):
        q[shift:] = multiply_arrays(q[:-shift], q[shift:])
        shift *= 2
    return q


def integrate(q0: np.ndarray, gyro: np.ndarray, dt: np.ndarray) -> Rotation:
    """
    Attitudes at N stamps from an xyzw start ``q0``, (N-1, 3) rad/s and (N-1,) s.

    The ordered products Exp(w_0 dt_0) ... Exp(w_k dt_k) are formed by vectorised
    compositions rather than a Python loop: prefix products within blocks of
    SCAN_BLOCK steps (log2 of it compositions of every step), a prefix scan over the
    blocks' totals, then one composition of each step with all the blocks before it.
    The compositions are numpy's (core.rotation), scipy's cost about 15 times more.
    """
    n = len(gyro)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (-(-n // SCAN_BLOCK) * SCAN_BLOCK, 1))
    q[:n] = Rotation.from_rotvec(gyro * dt[:, None]).as_quat()
    q = q.reshape(-1, SCAN_BLOCK, 4)                                # (blocks, SCAN_BLOCK, 4)
    shift = 1
    while shift < SCAN_BLOCK:
        q[:, shift:] = multiply_arrays(q[:, :-shift], q[:, shift:])
        shift *= 2
    totals = _prefix_products(q[:, -1].copy())                      # (blocks, 4)
    start = Rotation.from_quat(q0).as_quat()  # normalised
    before = multiply_arrays(start, np.concatenate([[[0.0, 0.0, 0.0, 1.0]], totals[:-1]]))
    steps = multiply_arrays(np.repeat(before, SCAN_BLOCK, axis=0)[:n], q.reshape(-1, 4)[:n])
    return Rotation.from_quat(np.concatenate([start[None], steps]))


def trusted_blocks(gt_valid: np.ndarray, length: int) -> np.ndarray:
    """Return the starts of the non-overlapping ``length``-sample blocks trusted throughout."""
    m = (len(gt_valid) - 1) // length
    if m == 0:
        return np.zeros(0, dtype=int)
    ok = gt_valid[:m * length].reshape(m, length).all(1) & gt_valid[length:m * length + 1:length]
    return np.arange(m)[ok] * length


def increments(gt_valid: np.ndarray, length: int,
               pose_at: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the starts and ends of the ``length``-sample increments compared with poses.

    Without ``pose_at``: the non-overlapping blocks trusted throughout
    (:func:`trusted_blocks`). With it (the stamps nearest a pose's, as the loss between
    poses compares them): from each pose's stamp to the first pose's at least ``length``
    samples later, if at most MAX_STRETCH times ``length`` away and trusted throughout.
    """
    if pose_at is None:
        starts = trusted_blocks(gt_valid, length)
        return starts, starts + length
    poses = np.flatnonzero(pose_at)
    later = np.searchsorted(poses, poses + length)
    starts, ends = poses[later < len(poses)], poses[later[later < len(poses)]]
    untrusted = np.cumsum(~gt_valid)
    ok = ((ends - starts <= MAX_STRETCH * length) & gt_valid[starts]
          & (untrusted[ends] == untrusted[starts]))
    return starts[ok], ends[ok]


def block_errors(gt_quat: np.ndarray, starts: np.ndarray, ends: np.ndarray,
                 est: Rotation) -> np.ndarray:
    """
    Return the errors (rotation vectors) of the given increments of a trajectory.

    R_gt_inc^T R_est_inc of each increment from ``starts`` to ``ends``, ``est`` the
    integrated gyro at every stamp.
    """
    gt, q = Rotation.from_quat(gt_quat).as_quat(), est.as_quat()  # normalised
    err = relative_arrays(relative_arrays(gt[starts], gt[ends]),
                          relative_arrays(q[starts], q[ends]))
    return log_arrays(err).reshape(-1, 3)


def increment_residuals(gt_quat: np.ndarray, gt_valid: np.ndarray, gyro: np.ndarray,
                        dt: np.ndarray, length: int, est: Rotation | None = None,
                        pose_at: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """
    Errors of the gyro's rotation increments over ``length`` samples (:func:`increments`).

    Non-overlapping blocks with trusted ground truth at every stamp they span, or with
    ``pose_at`` the increments between poses; returns the rotation vectors (M, 3) rad of
    R_gt_inc^T R_gyro_inc and the increments' durations (M,) s. ``gyro`` holds one
    sample per stamp (the last drives nothing); ``est``, when given, is its integration
    from ``gt_quat[0]`` (callers share one between lengths).
    """
    i, e = increments(gt_valid, length, pose_at)
    if len(i) == 0:
        return np.zeros((0, 3)), np.zeros(0)
    est = integrate(gt_quat[0], gyro[:len(dt)], dt) if est is None else est
    res = block_errors(gt_quat, i, e, est)
    t = np.concatenate([[0.0], np.cumsum(dt)])
    return res, t[e] - t[i]


def fit_constant_bias(gt_quat: np.ndarray, gt_valid: np.ndarray, gyro: np.ndarray,
                      dt: np.ndarray, length: int, est: Rotation | None = None,
                      pose_at: np.ndarray | None = None) -> np.ndarray | None:
    """
    Return the least-squares constant gyro bias (3,) rad/s from ``length``-sample increments.

    To first order a bias b gives an increment the error sum_k Q_k^T b dt_k, Q_k the
    rotation from sample k + 1 to the increment's end: the bias as seen from a turning
    frame. Dividing the error by the duration instead is right only while the body
    barely turns within an increment. None when no increment has trusted ground truth.
    ``est`` and ``pose_at`` as in :func:`increment_residuals`.
    """
    i, e = increments(gt_valid, length, pose_at)
    if len(i) == 0:
        return None
    est = integrate(gt_quat[0], gyro[:len(dt)], dt) if est is None else est
    res = block_errors(gt_quat, i, e, est)
    # sum_k Q_k^T dt_k = R_e^T sum_k R_{k+1} dt_k: one cumulative sum serves every increment
    rot = est.as_matrix()
    after = np.concatenate([np.zeros((1, 3, 3)),
                            np.cumsum(rot[1:len(dt) + 1] * dt[:, None, None], axis=0)])
    jac = np.swapaxes(rot[e], 1, 2) @ (after[e] - after[i])
    normal = np.einsum('mji,mjk->ik', jac, jac)
    return np.linalg.solve(normal, np.einsum('mji,mj->i', jac, res))


class AttitudeErrors(NamedTuple):
    """Errors of one estimated trajectory against ground truth, degrees."""

    aoe: float                 # RMS of the 3-D orientation error angle
    aoe_yaw: float             # RMS of the yaw error (about world z)
    tilt: float                # RMS of the tilt error (how far the vertical is off)
    roe: dict[float, np.ndarray]  # relative orientation errors per distance (m)
    error_deg: np.ndarray      # (N,) 3-D error angle at each stamp (NaN in GT holes)

    def roe_median(self) -> dict[float, float]:
        """Median ROE per distance (the paper's figure); NaN if never travelled."""
        return {d: float(np.median(e)) if len(e) else float('nan')
                for d, e in self.roe.items()}


def world_error(est: Rotation, gt: Rotation) -> np.ndarray:
    """Return the world-frame errors E = R_est R_gt^T as (N, 4) xyzw quaternions."""
    return multiply_arrays(est.as_quat(), conjugate_arrays(gt.as_quat()))


def error_components(est: Rotation, gt: Rotation) -> tuple[np.ndarray, ...]:
    """
    Angle, tilt and yaw (deg, each (N,)) of the world-frame error E (:func:`world_error`).

    The angle is that of E; the tilt is how far E moves the vertical (what gravity can
    correct); the yaw is the first angle of E's intrinsic Z-Y-X decomposition, its
    rotation about the world z axis, in [-180, 180).
    """
    err = Rotation.from_quat(world_error(est, gt))
    tilt = np.degrees(np.arccos(np.clip(err.as_matrix()[:, 2, 2], -1.0, 1.0)))
    return np.degrees(err.magnitude()), tilt, np.degrees(err.as_euler('ZYX')[:, 0])


def attitude_errors(est: Rotation, gt: Rotation, gt_pos: np.ndarray, valid: np.ndarray,
                    distances: tuple[float, ...] = ROE_DISTANCES_M) -> AttitudeErrors:
    """
    AOE (3-D, yaw and tilt) and ROE, skipping stamps where ground truth is not valid.

    Yaw error is the first angle of the intrinsic Z-Y-X decomposition of the world-frame
    error R_est R_gt^T, i.e. its rotation about the world z axis.
    """
    angle, tilt, yaw = error_components(est, gt)
    est_q, gt_q = est.as_quat(), gt.as_quat()
    roe = {}
    travelled = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(gt_pos, axis=0),
                                                                axis=1))])
    for d in distances:
        i = np.arange(len(travelled))
        j = np.searchsorted(travelled, travelled + d)
        ok = j < len(travelled)
        i, j = i[ok], j[ok]
        ok = valid[i] & valid[j]
        i, j = i[ok], j[ok]
        if len(i) == 0:
            roe[d] = np.zeros(0)
            continue
        rel = relative_arrays(relative_arrays(gt_q[i], gt_q[j]),
                              relative_arrays(est_q[i], est_q[j]))
        roe[d] = np.degrees(Rotation.from_quat(rel).magnitude())
    return AttitudeErrors(
        aoe=float(np.sqrt(np.mean(angle[valid] ** 2))),
        aoe_yaw=float(np.sqrt(np.mean(yaw[valid] ** 2))),
        tilt=float(np.sqrt(np.mean(tilt[valid] ** 2))),
        roe=roe,
        error_deg=np.where(valid, angle, np.nan))


def integrate_from_trusted(gt_quat: np.ndarray, gt_valid: np.ndarray, gyro: np.ndarray,
                           dt: np.ndarray) -> Rotation:
    """
    Integrate a gyro (one sample per stamp) from the first stamp with a trusted pose.

    A pose interpolated across a mocap hole is not a start: from one, every error after
    it carries the interpolation's. The stamps before keep their ground truth, which no
    error counts (they are not trusted either).
    """
    k = int(np.argmax(gt_valid)) if gt_valid.any() else 0
    est = integrate(gt_quat[k], gyro[k:len(dt)], dt[k:])
    return est if k == 0 else Rotation.concatenate([Rotation.from_quat(gt_quat[:k]), est])


def sequence_errors(seq: Sequence, gyro: np.ndarray,
                    distances: tuple[float, ...] = ROE_DISTANCES_M
                    ) -> tuple[Rotation, AttitudeErrors]:
    """Integrate a gyro (N, 3) over a sequence from its first trusted pose; its errors."""
    est = integrate_from_trusted(seq.gt_quat, seq.gt_valid, gyro, seq.dt)
    return est, attitude_errors(est, Rotation.from_quat(seq.gt_quat), seq.gt_pos,
                                seq.gt_valid, distances)


def score(seq: Sequence, gyro: np.ndarray) -> dict[str, float]:
    """AOE 3-D, yaw and tilt (deg) of one method's gyro integrated over a whole sequence."""
    err = sequence_errors(seq, gyro, distances=())[1]
    return {'aoe_deg': err.aoe, 'aoe_yaw_deg': err.aoe_yaw, 'tilt_deg': err.tilt}


def tilt_growth_deg_min(t_s: np.ndarray, tilt_deg: np.ndarray, valid: np.ndarray) -> float:
    """Slope (deg/min) of a least-squares line through the tilt error against time."""
    if valid.sum() < 2:
        return float('nan')
    return float(np.polyfit(t_s[valid] / 60.0, tilt_deg[valid], 1)[0])


class FusedErrors(NamedTuple):
    """Errors of a gravity-aided orientation, degrees, from its yaw-alignment instant on."""

    aoe: float                # RMS of the 3-D error angle
    tilt: float               # RMS of the tilt error (what gravity can correct)
    aoe_yaw: float            # RMS of the yaw error
    tilt_growth_deg_min: float
    std_rad: np.ndarray       # (3,) RMS of the world-frame error's rotation-vector components
    start: int                # index of the alignment instant


def align_yaw(est: Rotation, gt: Rotation, k: int) -> Rotation:
    """Return ``est`` with its world-frame yaw error at stamp k removed (tilt untouched)."""
    yaw = error_components(est[k:k + 1], gt[k:k + 1])[2][0]
    turn = Rotation.from_rotvec([0.0, 0.0, -np.radians(yaw)]).as_quat()
    return Rotation.from_quat(multiply_arrays(turn, est.as_quat()))


def fused_errors(est: Rotation, gt: Rotation, valid: np.ndarray, t_s: np.ndarray,
                 align_at_s: float = ALIGN_AT_S) -> FusedErrors:
    """
    Errors of an orientation whose yaw is arbitrary (a 6-D filter's) but whose tilt is not.

    Its yaw is aligned to the ground truth once, at the first trusted stamp ``align_at_s``
    after the start (the world-frame error's yaw removed there); its tilt never is.
    Scored from that stamp on, ground-truth holes skipped.
    """
    later = np.flatnonzero((t_s - t_s[0] >= align_at_s) & valid)
    trusted = np.flatnonzero(valid)
    k = int(later[0]) if len(later) else int(trusted[0]) if len(trusted) else 0
    aligned = align_yaw(est[k:], gt[k:], 0)
    angle, tilt, yaw = error_components(aligned, gt[k:])
    ok = valid[k:]
    if not ok.any():
        nan = float('nan')
        return FusedErrors(nan, nan, nan, nan, np.full(3, nan), k)

    def rms(e: np.ndarray) -> float:
        return float(np.sqrt(np.mean(e[ok] ** 2)))

    vec = log_arrays(world_error(aligned, gt[k:]))[ok]
    return FusedErrors(rms(angle), rms(tilt), rms(yaw),
                       tilt_growth_deg_min(t_s[k:] - t_s[k], tilt, ok),
                       np.sqrt(np.mean(vec ** 2, axis=0)), k)
