# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The IMU time base: crop a recording, and put its ground truth onto the IMU stamps.

A :class:`~denoise_imu_ros.core.records.Recording` holds two streams on their own stamps;
every consumer (training, evaluation, check-data) works on a
:class:`~denoise_imu_ros.core.records.Sequence`, the ground truth interpolated to each IMU
stamp and marked invalid inside its holes.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation, RotationSpline, Slerp

from ..core.errors import DatasetError
from ..core.limits import imu_holes, stream_rate_hz
from ..core.memo import content_key, Kept
from ..core.records import Recording, Sequence
from ..core.rotation import multiply_arrays

# Ground truth at an IMU instant is trusted only if the ground-truth samples around it
# are at most this many of the ground truth's own (median) periods apart: 20.8 ms for
# TUM-VI's 120 Hz mocap (holes of up to 3 s), 125 ms for V1_01's corrected 20 Hz poses,
# 250 ms for a 10 Hz VIO trajectory. Interpolating across a hole would invent ground truth.
GT_GAP_FACTOR = 2.5
MAX_POSE_PERIOD_S = 1.0  # sparser poses cannot score an attitude between them (two, 45 s apart)
MS_HINT_S = 10.0  # poses this far apart (median) are more likely stamped in ms than seconds
# The splines of the last few recordings' poses, by their content, one per hole-free
# stretch: checking a recording interpolates the same poses at several sets of stamps, and
# a spline over 10^5-10^6 poses costs far more to fit than its knots cost to hash
SPLINES_KEPT = 3  # recordings: check() interleaves its poses with two of its own
_SPLINES: Kept[dict[tuple[int, int], RotationSpline]] = Kept(SPLINES_KEPT)
# A long stretch is fitted in pieces of this many knots, each fitted SPLINE_OVERLAP knots
# beyond its ends: a cubic spline's knots sway it less by 2 - sqrt(3) per knot away, so
# the pieces equal one spline over the whole stretch to rounding, and the fit's memory
# stays that of one piece (one spline over 10^6 poses: over a gigabyte)
SPLINE_KNOTS = 20_000
SPLINE_OVERLAP = 64


def _between(rec: Recording, t0: int, t1: int) -> Recording:
    """Return the samples of both streams with t0 <= stamp <= t1 (ns)."""
    imu = (rec.imu_stamp_ns >= t0) & (rec.imu_stamp_ns <= t1)
    gt = (rec.gt_stamp_ns >= t0) & (rec.gt_stamp_ns <= t1)
    if not imu.any():
        raise DatasetError(f'{rec.source}: no IMU samples in the requested time range')
    return Recording(rec.name, rec.source, rec.imu_stamp_ns[imu], rec.imu[imu],
                     rec.gt_stamp_ns[gt], rec.gt_quat[gt], rec.gt_pos[gt])


def crop(rec: Recording, start_s: float = 0.0, duration_s: float | None = None) -> Recording:
    """Cut a recording to ``duration_s`` from ``start_s`` after its first IMU stamp."""
    t0 = rec.imu_stamp_ns[0] + int(start_s * 1e9)
    t1 = np.iinfo(np.int64).max if duration_s is None else t0 + int(duration_s * 1e9) - 1
    return _between(rec, t0, t1)


def overlap(rec: Recording) -> Recording:
    """Keep only the time span both the IMU and the ground truth cover."""
    return _between(rec, max(rec.imu_stamp_ns[0], rec.gt_stamp_ns[0]),
                    min(rec.imu_stamp_ns[-1], rec.gt_stamp_ns[-1]))


def spans(rec: Recording) -> str:
    """Say the time spans of the IMU's stamps and of the poses' (s), for an error."""
    return ', '.join(f'{what} {t[0] * 1e-9:.3f} to {t[-1] * 1e-9:.3f} s'
                     for what, t in (('IMU', rec.imu_stamp_ns), ('poses', rec.gt_stamp_ns)))


def gt_gap_limit(gt_stamp_ns: np.ndarray, max_gt_gap_s: float | None = None) -> float:
    """Spacing (s) above which two ground-truth samples bracket a hole, not a step."""
    if max_gt_gap_s is not None:
        return max_gt_gap_s
    return GT_GAP_FACTOR * float(np.median(np.diff(gt_stamp_ns))) * 1e-9


def poses_at(rec: Recording, stamps_ns: np.ndarray,
             max_gt_gap_s: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Ground truth at increasing stamps inside its span: xyzw (N, 4), position (N, 3), valid.

    Stamps whose bracketing ground-truth samples are further apart than
    :func:`gt_gap_limit` (by default relative to the ground truth's own rate) are marked
    invalid; their values are filled by slerp and never trusted. Between trusted samples
    orientation follows a cubic rotation spline fitted to each hole-free stretch
    (measured on EuRoC poses thinned to 10-30 Hz: 10-25 % smaller increment error than
    slerp; identical at the ground-truth stamps), position is linear.
    """
    t, t_gt = stamps_ns, rec.gt_stamp_ns
    limit = gt_gap_limit(t_gt, max_gt_gap_s)
    # Relative float seconds: exact enough (ns resolution for 100 days), unlike raw ns.
    rel = (t - t_gt[0]) * 1e-9
    rel_gt = (t_gt - t_gt[0]) * 1e-9
    rot_gt = Rotation.from_quat(rec.gt_quat)
    quat = np.empty((len(t), 4))
    splined = np.zeros(len(t), bool)
    pos = np.stack([np.interp(rel, rel_gt, rec.gt_pos[:, i]) for i in range(3)], axis=1)
    after = np.clip(np.searchsorted(t_gt, t, side='left'), 1, len(t_gt) - 1)
    gap = (t_gt[after] - t_gt[after - 1]) * 1e-9
    exact = t_gt[after - 1] == t  # sitting on a ground-truth sample needs no neighbour
    valid = (gap <= limit) | exact | (t_gt[after] == t)
    if not valid.any():
        raise DatasetError(
            f'{rec.source}: ground truth is never trusted at an IMU stamp (its samples are '
            f'{np.median(np.diff(t_gt)) * 1e-6:.1f} ms apart, the hole limit is '
            f'{limit * 1e3:.1f} ms)')
    # One spline per hole-free stretch of ground truth, so that no hole bends it.
    breaks = np.flatnonzero(np.diff(t_gt) * 1e-9 > limit) + 1
    fitted = _splines(rel_gt, rec.gt_quat)
    for lo, hi in zip(np.r_[0, breaks], np.r_[breaks, len(t_gt)]):
        if hi - lo < 3:
            continue
        for a, b in _pieces(lo, hi):  # each piece scores the stamps from knot a to knot b
            first, last = np.searchsorted(rel, rel_gt[[a, b - 1]],
                                          side='left').tolist()
            if b == hi:  # the stretch's last knot is its own
                last = int(np.searchsorted(rel, rel_gt[b - 1], side='right'))
            inside = np.flatnonzero(valid[first:last]) + first
            if not len(inside):
                continue
            fit = (max(lo, a - SPLINE_OVERLAP), min(hi, b + SPLINE_OVERLAP))
            if fit not in fitted:
                fitted[fit] = RotationSpline(rel_gt[slice(*fit)], rot_gt[slice(*fit)])
            quat[inside] = spline_at(fitted[fit], rel[inside])
            splined[inside] = True
    if not splined.all():  # holes (never trusted) and stretches too short for a spline
        quat[~splined] = Slerp(rel_gt, rot_gt)(rel[~splined]).as_quat()
    return quat, pos, valid


def spline_at(spline: RotationSpline, t: np.ndarray) -> np.ndarray:
    """
    Return ``spline(t).as_quat()``, its rotations composed by numpy's products.

    Scipy's evaluation: the knot before each time, times the rotation vector the cubic
    gives there; scipy's composition of the two arrays costs most of that
    (:mod:`~denoise_imu_ros.core.rotation`). It reads the spline's ``times``,
    ``rotations`` and ``interpolator``, attributes scipy does not document (scipy is
    pinned; a test compares the two evaluations).
    """
    index = np.clip(np.searchsorted(spline.times, t, side='right') - 1, 0,
                    len(spline.times) - 2)
    step = Rotation.from_rotvec(spline.interpolator(t)).as_quat()
    return multiply_arrays(spline.rotations.as_quat()[index], step)


def _pieces(lo: int, hi: int) -> list[tuple[int, int]]:
    """Split the knots lo..hi - 1 into runs of at most SPLINE_KNOTS, sharing their ends."""
    count = max(1, math.ceil((hi - 1 - lo) / SPLINE_KNOTS))
    ends = np.linspace(lo, hi - 1, count + 1).round().astype(int).tolist()
    return [(a, b + 1) for a, b in zip(ends[:-1], ends[1:])]


def _splines(t: np.ndarray, quat: np.ndarray) -> dict[tuple[int, int], RotationSpline]:
    """Return the splines fitted so far to these poses' stretches (by their knots' indices)."""
    return _SPLINES.get(content_key(t, quat), dict)


def onto_imu_stamps(rec: Recording, max_gt_gap_s: float | None = None,
                    min_samples: int = 1) -> Sequence:
    """
    Crop to the IMU/ground-truth overlap and put the ground truth onto the IMU stamps.

    The IMU samples before the poses start are kept as the sequence's ``lead_in``, from
    the last hole in the IMU stream before them on (the node restarts at a hole; a hole
    after they start is the recording's, refused where it is checked).
    """
    t_imu, t_gt = rec.imu_stamp_ns, rec.gt_stamp_ns
    if len(t_gt) < 2:
        raise DatasetError(f'{rec.source}: {len(t_gt)} ground-truth samples, need at least 2')
    period = float(np.median(np.diff(t_gt))) * 1e-9
    if period > MAX_POSE_PERIOD_S:
        raise DatasetError(f'{rec.source}: its poses come every {period:.1f} s (median): too '
                           'sparse to take an attitude between them from (one a second at '
                           'least)' + ('; stamps in milliseconds?' if period >= MS_HINT_S
                                       else ''))
    start, end = max(t_imu[0], t_gt[0]), min(t_imu[-1], t_gt[-1])
    if start >= end:
        raise DatasetError(f'{rec.source}: IMU and ground truth do not overlap in time '
                           f'({spans(rec)}; align auto finds poses on another clock)')
    keep = (t_imu >= start) & (t_imu <= end)
    if keep.sum() < max(min_samples, 2):
        raise DatasetError(f'{rec.source}: {keep.sum()} IMU samples overlap the ground '
                           f'truth, need at least {max(min_samples, 2)}')
    quat, pos, valid = poses_at(rec, t_imu[keep], max_gt_gap_s)
    first = int(np.argmax(keep))
    holes = imu_holes(t_imu[:first + 1], stream_rate_hz(t_imu)) if first else []
    lead = slice(int(holes[-1]) + 1 if len(holes) else 0, first)
    return Sequence(name=rec.name, stamp_ns=t_imu[keep], imu=rec.imu[keep], gt_quat=quat,
                    gt_pos=pos, gt_valid=valid, lead_in=rec.imu[lead],
                    lead_in_stamp_ns=t_imu[lead], pose_at=nearest_samples(t_imu[keep], t_gt))


def nearest_samples(stamps_ns: np.ndarray, pose_stamps_ns: np.ndarray) -> np.ndarray:
    """
    Return (N,) bool: the stamps nearest a pose stamp, within half their median period.

    There the poses' attitude is known up to half an IMU sample's motion, whatever
    happens between poses (what the loss between poses compares).
    """
    at = np.zeros(len(stamps_ns), bool)
    if len(stamps_ns) < 2:
        return at
    half = 0.5 * float(np.median(np.diff(stamps_ns)))
    after = np.clip(np.searchsorted(stamps_ns, pose_stamps_ns), 1, len(stamps_ns) - 1)
    nearer = np.where(pose_stamps_ns - stamps_ns[after - 1] <= stamps_ns[after] - pose_stamps_ns,
                      after - 1, after)
    at[nearer[np.abs(stamps_ns[nearer] - pose_stamps_ns) <= half]] = True
    return at
