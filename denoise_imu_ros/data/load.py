# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Read a recording from an ASL folder or a bag, and put it on the IMU time base.

Every command takes either source; the reader is chosen by the path
(:func:`is_bag`), the topics are auto-detected when they are the only ones of their kind.
"""

from __future__ import annotations

import dataclasses
import glob
from pathlib import Path
import warnings

from .asl import read_asl
from .pose_alignment import (apply_pose_alignment, describe, level, LEVEL_TOLERANCE_DEG,
                             needs_alignment, not_following, on_imu_clock, read_and_align)
from .pose_jumps import describe as describe_jumps, find_jumps, mask_jumps
from .timebase import onto_imu_stamps
from .trajectory import read_tum, trajectory_file, with_trajectory
from ..core.errors import DataNote, DatasetError, DataWarning
from ..core.limits import check_gyro_against_poses, check_rate
from ..core.records import check_recording, Recording, Sequence


def is_bag(path: str | Path) -> bool:
    """ROS 1 .bag, ROS 2 .mcap/.db3 file, or a ROS 2 bag folder (metadata.yaml)."""
    p = Path(path)
    return p.suffix in ('.bag', '.mcap', '.db3') or (p / 'metadata.yaml').is_file()


def no_such(path: str | Path) -> DatasetError:
    """Return the error for a recording not there, naming a bag file of that name."""
    path = Path(path)
    bags = sorted(p.name for p in path.parent.glob(f'{glob.escape(path.name)}.*')
                  if is_bag(p)) if path.parent.is_dir() else []
    return DatasetError(f'{path}: no such sequence folder or bag'
                        + (f' (there is {", ".join(bags)}: name it with its suffix)'
                           if bags else ''))


def load_imu(path: str | Path, imu_topic: str | None = None) -> Recording:
    """IMU stream only (no ground truth needed) from an ASL folder or a bag."""
    if is_bag(path):
        from .bags import read_bag  # rosbags: a quarter second of import, for bags only
        return read_bag(path, imu_topic=imu_topic, with_pose=False)
    if not Path(path).exists():
        raise no_such(path)
    return read_asl(path, with_gt=False)


def load_recording(path: str | Path, imu_topic: str | None = None,
                   pose_topic: str | None = None, poses: str | Path | None = None) -> Recording:
    """
    Read an ASL folder or a bag (IMU and poses); topics are auto-detected when None.

    ``poses``: a trajectory file (TUM format, as VIO and SLAM tools write them), or a
    folder of ``<recording>.txt``, whose poses replace the recording's own.
    """
    if poses is not None:
        rec = load_imu(path, imu_topic)
        trajectory = read_tum(trajectory_file(poses, Path(path).name))
        if trajectory.summary():
            warnings.warn(trajectory.summary(), DataWarning if trajectory.dropped else DataNote,
                          stacklevel=2)
        rec = with_trajectory(rec, trajectory)
        check_recording(rec, gt_file=trajectory.path)
        return rec
    if is_bag(path):
        from .bags import read_bag  # rosbags: a quarter second of import, for bags only
        return read_bag(path, imu_topic=imu_topic, pose_topic=pose_topic)
    if not Path(path).exists():
        raise no_such(path)
    return read_asl(path)


def load_sequence(path: str | Path, imu_topic: str | None = None,
                  pose_topic: str | None = None,
                  max_gt_gap_s: float | None = None,
                  min_samples: int = 1, align_poses: str | dict = 'none',
                  poses: str | Path | None = None, rate_hz: float | None = None) -> Sequence:
    """
    Read an ASL folder or a bag and align it; topics are auto-detected when None.

    ``align_poses``: ``none``, ``auto`` (clock offset and frame rotation estimated as
    ``check-data`` does) or ``{time_offset_s, imu_from_pose_rotation_xyzw}``; what was
    applied is kept in :attr:`Sequence.pose_alignment`. ``check``: none, but poses found
    off the IMU's clock or frame are an error (figures against them would be wrong).
    ``poses``: as for :func:`load_recording`. Poses that follow the gyro only read
    inverted or with w first are read so where they are aligned or checked
    (:func:`~denoise_imu_ros.data.pose_alignment.read_and_align`). Pose jumps the gyro
    cannot explain are masked and said (:mod:`~denoise_imu_ros.data.pose_jumps`); a
    world whose z is not up is turned level
    (:func:`~denoise_imu_ros.data.pose_alignment.level`). ``rate_hz``: a model's rate,
    which the IMU stream must have before anything is judged against its poses.
    """
    rec = load_recording(path, imu_topic, pose_topic, poses)
    if rate_hz is not None:
        check_rate(rec.imu_stamp_ns, rate_hz, path)
    # a gyro in deg/s follows no poses at any clock or frame: said before any alignment
    raw = onto_imu_stamps(on_imu_clock(rec)[0] if align_poses in ('check', 'auto') else rec,
                          max_gt_gap_s=max_gt_gap_s)
    check_gyro_against_poses(raw.imu[:, :3], raw.gt_quat, raw.gt_valid, raw.dt, path)
    rec, used = _alignment(rec, align_poses, path)
    if used is not None:
        rec = apply_pose_alignment(rec, used['time_offset_s'], used['imu_from_pose_rotation_xyzw'])
    seq = onto_imu_stamps(rec, max_gt_gap_s=max_gt_gap_s, min_samples=min_samples)
    jumps = find_jumps(seq)
    if jumps:
        warnings.warn(f'{path}: {describe_jumps(jumps)}', DataWarning, stacklevel=2)
    seq, tilt = level(mask_jumps(seq, jumps))
    if tilt > LEVEL_TOLERANCE_DEG:
        warnings.warn(f"{path}: the poses' world has its z {tilt:.0f} deg from up (the "
                      'accelerometer says; a SLAM starting in its first camera frame?): '
                      'turned level for the gravity-aided filters; relative rotations, and so '
                      'training, are unchanged', DataWarning, stacklevel=2)
    return dataclasses.replace(seq, pose_alignment=used)


def _alignment(rec: Recording, align_poses: str | dict,
               path: str | Path) -> tuple[Recording, dict | None]:
    """
    Return the poses and the clock offset and frame rotation to apply to them (None: none).

    Poses that follow the gyro only read another common way (inverted, w first:
    :func:`~denoise_imu_ros.data.pose_alignment.read_and_align`) are read so, and said.
    """
    if align_poses in ('check', 'auto'):
        rec, found, way = read_and_align(rec)
        if way:
            warnings.warn(f'{path}: the poses follow the gyro only read {way}: read so',
                          DataWarning, stacklevel=3)
    if align_poses == 'check':
        why = not_following(found)
        if why:
            raise DatasetError(f'{path}: {why} (nor read inverted or with w first: another '
                               "recording's poses?): figures against them would be wrong; "
                               '--align none scores them as they are')
        if needs_alignment(found):
            raise DatasetError(f'{path}: {describe(found)}: figures against them as they are '
                               'would be wrong; give --align auto to move them first (or '
                               '--align none to score them as they are)')
        return rec, None
    if align_poses == 'auto':
        why = not_following(found)
        if why:  # no estimate to apply: say so rather than shift the poses by it
            raise DatasetError(f'{path}: align auto: {why}')
        return rec, {k: found[k] for k in ('time_offset_s', 'time_offset_std_s',
                                           'imu_from_pose_rotation_xyzw',
                                           'imu_from_pose_rotation_std_deg')}
    if isinstance(align_poses, dict):
        return rec, dict(align_poses)
    if align_poses != 'none':
        raise DatasetError('align must be none, check, auto or a mapping, not '
                           f'{align_poses!r}')
    return rec, None
