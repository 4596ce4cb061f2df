# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What the package's readers produce: recordings as read, sequences on the IMU time base.

A :class:`Recording` is what a file holds (IMU and pose streams on their own clocks),
checked by :func:`check_recording` whichever reader made it (ASL folders or bags, in
:mod:`denoise_imu_ros.data`); a :class:`Sequence` is the same data on the IMU's time
base, which every consumer (training, evaluation, correction) uses.

Conventions: stamps are int64 nanoseconds; gyro rad/s, accel m/s^2; quaternions are
scalar-last ``(x, y, z, w)`` and rotate body (IMU) vectors into the world frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import DatasetError
from .limits import describe, in_range, MAX_POSITION_M, MAX_RATE_HZ, stream_rate_hz


@dataclass(frozen=True)
class Recording:
    """IMU and pose streams as read from a file, each on its own stamps."""

    name: str
    source: str                 # file or folder it came from, for error messages
    imu_stamp_ns: np.ndarray    # (N,) int64, strictly increasing
    imu: np.ndarray             # (N, 6) float64: gyro xyz rad/s, accel xyz m/s^2
    gt_stamp_ns: np.ndarray     # (M,) int64, strictly increasing
    gt_quat: np.ndarray         # (M, 4) float64 xyzw, body to world
    gt_pos: np.ndarray          # (M, 3) float64, m


@dataclass(frozen=True)
class Sequence:
    """
    A recording on the IMU time base, cropped to where ground truth exists.

    The IMU samples before that are its ``lead_in``: what a node has run on before.
    """

    name: str
    stamp_ns: np.ndarray        # (N,) int64
    imu: np.ndarray             # (N, 6) float64
    gt_quat: np.ndarray         # (N, 4) float64 xyzw, slerped to the IMU stamps
    gt_pos: np.ndarray          # (N, 3) float64, linearly interpolated
    gt_valid: np.ndarray        # (N,) bool: False inside ground-truth holes
    pose_alignment: dict | None = None  # clock offset and frame rotation applied to poses
    # (M, 6) and (M,): the recording's IMU samples before the first here (before its poses)
    lead_in: np.ndarray = field(default_factory=lambda: np.empty((0, 6)))
    lead_in_stamp_ns: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    # (N,) bool: the IMU samples nearest a pose's stamp (within half an IMU period); None:
    # not known (the loss between poses needs it)
    pose_at: np.ndarray | None = None

    def __len__(self) -> int:
        """Return the number of IMU samples with poses (the lead-in not counted)."""
        return len(self.stamp_ns)

    @property
    def stream(self) -> np.ndarray:
        """
        Return every IMU sample (M + N, 6) from the recording's first: what a node has seen.

        A VIO's or a SLAM's trajectory starts after its initialisation, often after the
        stillness a run starts with: the turn-on bias, and everything after it that holds
        a state, must run from the stream's start, as online (:meth:`on_poses` keeps the
        samples scored).
        """
        return np.vstack([self.lead_in, self.imu]) if len(self.lead_in) else self.imu

    @property
    def stream_stamp_ns(self) -> np.ndarray:
        """Return the stamps (M + N,) of :attr:`stream`."""
        return np.concatenate([self.lead_in_stamp_ns, self.stamp_ns])

    def on_poses(self, values: np.ndarray) -> np.ndarray:
        """Return the rows of ``values`` (one per sample of :attr:`stream`) that are these."""
        if len(values) != len(self.lead_in) + len(self):
            raise ValueError(f'{len(values)} rows, not one per sample of the stream '
                             f'({len(self.lead_in)} + {len(self)})')
        return values[len(self.lead_in):]

    @property
    def dt(self) -> np.ndarray:
        """(N - 1,) s: sample k drives the attitude from stamp k to stamp k + 1."""
        return np.diff(self.stamp_ns).astype(np.float64) * 1e-9

    def tail(self, start: int, length: int | None = None) -> Sequence:
        """Return the samples from ``start`` on (``length`` of them when given), led in."""
        part = slice(start, None if length is None else start + length)
        return Sequence(self.name, self.stamp_ns[part], self.imu[part], self.gt_quat[part],
                        self.gt_pos[part], self.gt_valid[part], self.pose_alignment,
                        np.vstack([self.lead_in, self.imu[:start]]),
                        np.concatenate([self.lead_in_stamp_ns, self.stamp_ns[:start]]),
                        None if self.pose_at is None else self.pose_at[part])

    @property
    def rate_hz(self) -> float:
        """IMU sample rate, from the median stamp interval (the one rate policy)."""
        return stream_rate_hz(self.stamp_ns)


def check_recording(rec: Recording, imu_file: object = None, gt_file: object = None) -> None:
    """Reject what would corrupt training or evaluation: NaN, absurd values, bad stamps."""
    for what, stamps, values, where in (
            ('IMU', rec.imu_stamp_ns, rec.imu, imu_file or rec.source),
            ('ground truth', rec.gt_stamp_ns, np.hstack([rec.gt_quat, rec.gt_pos]),
             gt_file or rec.source)):
        bad = np.flatnonzero(~np.isfinite(values).all(axis=1))
        if len(bad):
            raise DatasetError(f'{where}: non-finite {what} values in sample {bad[0]} '
                               f'({len(bad)} such samples)')
        back = np.flatnonzero(np.diff(stamps) <= 0)
        if len(back):
            i = back[0]
            kind = 'duplicate' if stamps[i + 1] == stamps[i] else 'non-monotonic'
            raise DatasetError(f'{where}: {kind} {what} stamp at sample {i + 1} '
                               f'({stamps[i]} then {stamps[i + 1]} ns)')
        rate = stream_rate_hz(stamps)
        if rate > MAX_RATE_HZ:
            step = float(np.median(np.diff(stamps)))
            raise DatasetError(f'{where}: {what} stamps {step:g} apart, {rate:.3g} Hz if they '
                               'are nanoseconds: stamps in microseconds or milliseconds? '
                               '(nanoseconds expected)')
    far = np.flatnonzero(np.abs(rec.gt_pos).max(axis=1, initial=0.0) > MAX_POSITION_M)
    if len(far):
        raise DatasetError(f'{gt_file or rec.source}: ground-truth position beyond '
                           f'{MAX_POSITION_M:g} m in sample {far[0]}: '
                           f'{rec.gt_pos[far[0]].tolist()} ({len(far)} such samples)')
    bad = np.flatnonzero(~in_range(rec.imu[:, :3], rec.imu[:, 3:]))
    if len(bad):
        raise DatasetError(f'{imu_file or rec.source}: IMU values out of the physical range '
                           f'({describe()}) in sample {bad[0]}: {rec.imu[bad[0]].tolist()} '
                           f'({len(bad)} such samples)')
    norms = np.linalg.norm(rec.gt_quat, axis=1)
    if np.any(norms < 0.5) or np.any(norms > 1.5):
        raise DatasetError(f'{gt_file or rec.source}: ground-truth quaternions are not unit '
                           f'quaternions (norm {norms.min():.3g}..{norms.max():.3g})')
