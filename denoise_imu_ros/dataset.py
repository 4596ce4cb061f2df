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
IMU + ground-truth recordings: reading ASL folders and aligning ground truth.

Recordings and sequences are defined in :mod:`denoise_imu_ros.records`; bags are read
by :mod:`denoise_imu_ros.bags`.

Conventions: stamps are int64 nanoseconds; gyro rad/s, accel m/s^2; quaternions are
scalar-last ``(x, y, z, w)`` and rotate body (IMU) vectors into the world frame.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, RotationSpline, Slerp

from .errors import DatasetError
from .records import check_recording, Recording, Sequence

# Ground truth at an IMU instant is trusted only if the ground-truth samples around it
# are at most this many of the ground truth's own (median) periods apart: 20.8 ms for
# TUM-VI's 120 Hz mocap (holes of up to 3 s), 125 ms for V1_01's corrected 20 Hz poses,
# 250 ms for a 10 Hz VIO trajectory. Interpolating across a hole would invent ground truth.
GT_GAP_FACTOR = 2.5


def read_csv(path: Path, ncols: int) -> tuple[np.ndarray, np.ndarray]:
    """
    Read an ASL CSV: int64 ns stamps (column 0) and float64 columns 1..ncols-1.

    Parsed by hand because the stamps (~1.4e18 ns) do not survive a float64 parse, and
    so that every error names the file and line.
    """
    if not path.is_file():
        raise DatasetError(f'{path}: file not found')
    stamps: list[int] = []
    rows: list[list[float]] = []
    with path.open(encoding='utf-8', errors='strict') as f:
        lines = _lines(f, path)
        for lineno, line in enumerate(lines, 1):
            if line.startswith('#') or not line.strip():
                continue
            parts = line.split(',')
            if len(parts) < ncols:
                raise DatasetError(
                    f'{path}:{lineno}: expected {ncols} columns, found {len(parts)}')
            try:
                stamps.append(int(parts[0]))
                rows.append([float(x) for x in parts[1:ncols]])
            except ValueError:
                raise DatasetError(
                    f'{path}:{lineno}: unparsable row {line.strip()[:60]!r}') from None
    if not stamps:
        raise DatasetError(f'{path}: no data rows')
    return np.array(stamps, dtype=np.int64), np.array(rows, dtype=np.float64)


def _lines(f: object, path: Path) -> list[str]:
    """All lines of a text file; a binary or non-UTF-8 one is a one-line error."""
    try:
        return f.readlines()
    except UnicodeDecodeError as err:
        raise DatasetError(f'{path}: not a text CSV file (byte {err.start} is not UTF-8)'
                           ) from err


def read_asl(path: str | Path, with_gt: bool = True) -> Recording:
    """
    Read an ASL folder: EuRoC (imu0 + state_groundtruth_estimate0) or TUM-VI (mocap0).

    With ``with_gt=False`` only the IMU is read (the ground-truth arrays are empty).
    """
    root = Path(path)
    mav = root / 'mav0'
    if not mav.is_dir():
        raise DatasetError(f'{root}: not an ASL sequence folder (no mav0/ inside)')
    imu_stamp, imu = read_csv(mav / 'imu0' / 'data.csv', 7)
    if not with_gt:
        rec = Recording(root.name, str(root), imu_stamp, imu, np.zeros(0, np.int64),
                        np.zeros((0, 4)), np.zeros((0, 3)))
        check_recording(rec, imu_file=mav / 'imu0' / 'data.csv')
        return rec
    for gt_dir in ('state_groundtruth_estimate0', 'mocap0'):
        if (mav / gt_dir).is_dir():
            break
    else:
        raise DatasetError(f'{mav}: no ground truth (state_groundtruth_estimate0/ or mocap0/)')
    gt_stamp, gt = read_csv(mav / gt_dir / 'data.csv', 8)  # t, p xyz, q wxyz
    rec = Recording(name=root.name, source=str(root), imu_stamp_ns=imu_stamp, imu=imu,
                    gt_stamp_ns=gt_stamp, gt_quat=gt[:, [4, 5, 6, 3]], gt_pos=gt[:, :3])
    check_recording(rec, imu_file=mav / 'imu0' / 'data.csv', gt_file=mav / gt_dir / 'data.csv')
    return rec


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


def gt_gap_limit(gt_stamp_ns: np.ndarray, max_gt_gap_s: float | None = None) -> float:
    """Spacing (s) above which two ground-truth samples bracket a hole, not a step."""
    if max_gt_gap_s is not None:
        return max_gt_gap_s
    return GT_GAP_FACTOR * float(np.median(np.diff(gt_stamp_ns))) * 1e-9


def align(rec: Recording, max_gt_gap_s: float | None = None,
          min_samples: int = 1) -> Sequence:
    """
    Crop to the IMU/ground-truth overlap and interpolate ground truth to IMU stamps.

    IMU instants whose bracketing ground-truth samples are further apart than
    :func:`gt_gap_limit` (by default relative to the ground truth's own rate) are marked
    invalid; their values are filled by slerp and never trusted. Between trusted samples
    orientation follows a cubic rotation spline fitted to each hole-free stretch
    (measured on EuRoC poses thinned to 10-30 Hz: 10-25 % smaller increment error than
    slerp; identical at the ground-truth stamps), position is linear.
    """
    t_imu, t_gt = rec.imu_stamp_ns, rec.gt_stamp_ns
    if len(t_gt) < 2:
        raise DatasetError(f'{rec.source}: {len(t_gt)} ground-truth samples, need at least 2')
    start, end = max(t_imu[0], t_gt[0]), min(t_imu[-1], t_gt[-1])
    if start >= end:
        raise DatasetError(f'{rec.source}: IMU and ground truth do not overlap in time')
    keep = (t_imu >= start) & (t_imu <= end)
    if keep.sum() < max(min_samples, 2):
        raise DatasetError(f'{rec.source}: {keep.sum()} IMU samples overlap the ground '
                           f'truth, need at least {max(min_samples, 2)}')
    t = t_imu[keep]
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
    for lo, hi in zip(np.r_[0, breaks], np.r_[breaks, len(t_gt)]):
        inside = valid & (rel >= rel_gt[lo]) & (rel <= rel_gt[hi - 1])
        if hi - lo >= 3 and inside.any():
            spline = RotationSpline(rel_gt[lo:hi], rot_gt[lo:hi])
            quat[inside] = spline(rel[inside]).as_quat()
            splined |= inside
    if not splined.all():  # holes (never trusted) and stretches too short for a spline
        quat[~splined] = Slerp(rel_gt, rot_gt)(rel[~splined]).as_quat()
    return Sequence(name=rec.name, stamp_ns=t, imu=rec.imu[keep], gt_quat=quat,
                    gt_pos=pos, gt_valid=valid)


def is_bag(path: str | Path) -> bool:
    """ROS 1 .bag, ROS 2 .mcap/.db3 file, or a ROS 2 bag folder (metadata.yaml)."""
    p = Path(path)
    return p.suffix in ('.bag', '.mcap', '.db3') or (p / 'metadata.yaml').is_file()


def load_imu(path: str | Path, imu_topic: str | None = None) -> Recording:
    """IMU stream only (no ground truth needed) from an ASL folder or a bag."""
    if is_bag(path):
        from .bags import read_bag
        return read_bag(path, imu_topic=imu_topic, with_pose=False)
    if not Path(path).exists():
        raise DatasetError(f'{path}: no such sequence folder or bag')
    return read_asl(path, with_gt=False)


def load_recording(path: str | Path, imu_topic: str | None = None,
                   pose_topic: str | None = None) -> Recording:
    """Read an ASL folder or a bag (IMU and poses); topics are auto-detected when None."""
    if is_bag(path):
        from .bags import read_bag  # bags builds on this module's records
        return read_bag(path, imu_topic=imu_topic, pose_topic=pose_topic)
    if not Path(path).exists():
        raise DatasetError(f'{path}: no such sequence folder or bag')
    return read_asl(path)


def apply_alignment(rec: Recording, time_offset_s: float,
                    imu_from_pose_rotation_xyzw: list[float]) -> Recording:
    """
    Poses moved onto the IMU clock and into the IMU frame.

    ``t_imu = t_pose + time_offset_s`` and ``omega_imu = R omega_pose_body``, so the IMU's
    attitude is the pose's times R^-1 (positions are left as they are: only their
    distances are used, for ROE).
    """
    rot = Rotation.from_quat(imu_from_pose_rotation_xyzw)
    return Recording(rec.name, rec.source, rec.imu_stamp_ns, rec.imu,
                     rec.gt_stamp_ns + int(round(time_offset_s * 1e9)),
                     (Rotation.from_quat(rec.gt_quat) * rot.inv()).as_quat(), rec.gt_pos)


def load_sequence(path: str | Path, imu_topic: str | None = None,
                  pose_topic: str | None = None,
                  max_gt_gap_s: float | None = None,
                  min_samples: int = 1, align_poses: str | dict = 'none') -> Sequence:
    """
    Read an ASL folder or a bag and align it; topics are auto-detected when None.

    ``align_poses``: ``none``, ``auto`` (clock offset and frame rotation estimated as
    ``check-data`` does) or ``{time_offset_s, imu_from_pose_rotation_xyzw}``; what was
    applied is kept in :attr:`Sequence.alignment`.
    """
    rec = load_recording(path, imu_topic, pose_topic)
    used = None
    if align_poses == 'auto':
        from .quality import alignment  # quality builds on this module
        found = alignment(rec)
        used = {k: found[k] for k in ('time_offset_s', 'time_offset_std_s',
                                      'imu_from_pose_rotation_xyzw',
                                      'imu_from_pose_rotation_std_deg')}
    elif isinstance(align_poses, dict):
        used = dict(align_poses)
    elif align_poses != 'none':
        raise DatasetError(f'align must be none, auto or a mapping, not {align_poses!r}')
    if used is not None:
        rec = apply_alignment(rec, used['time_offset_s'], used['imu_from_pose_rotation_xyzw'])
    seq = align(rec, max_gt_gap_s=max_gt_gap_s, min_samples=min_samples)
    return dataclasses.replace(seq, alignment=used)
