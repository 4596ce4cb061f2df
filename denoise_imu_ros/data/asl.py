# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
ASL folders (EuRoC, TUM-VI): the IMU CSV and the ground-truth CSV of one recording.

Conventions: stamps are int64 nanoseconds; gyro rad/s, accel m/s^2; quaternions are
scalar-last ``(x, y, z, w)`` and rotate body (IMU) vectors into the world frame.
"""

from __future__ import annotations

from pathlib import Path
import warnings

import numpy as np

from ..core.errors import DatasetError
from ..core.memo import files_key, Kept
from ..core.records import check_recording, Recording

# The CSVs of the last recordings read, by their files (core.memo): crossval, eval and the
# trainings of one process read each recording several times, its text parse the costly part
ROWS_KEPT = 2_000_000  # rows of up to 8 numbers: 128 MB at most; all of EuRoC is 0.5 M
_READ: Kept[tuple[np.ndarray, np.ndarray]] = Kept(ROWS_KEPT, lambda read: len(read[0]))


def read_csv(path: Path, ncols: int) -> tuple[np.ndarray, np.ndarray]:
    """
    Read an ASL CSV: int64 ns stamps (column 0) and float64 columns 1..ncols-1.

    The stamps (~1.4e18 ns) do not survive a float64 parse: they are read as integers,
    by numpy's parser; a file it refuses is parsed again line by line, so that the error
    names the file and the line. A file read before and unchanged since is not parsed
    again; the arrays returned are the caller's own.
    """
    if not path.is_file():
        raise DatasetError(f'{path}: file not found')
    files = files_key(path)
    stamps, values = _READ.get(None if files is None else (files, ncols),
                               lambda: _read_csv(path, ncols))
    return stamps.copy(), values.copy()


def _read_csv(path: Path, ncols: int) -> tuple[np.ndarray, np.ndarray]:
    """Return :func:`read_csv`'s arrays, parsed."""
    with path.open(encoding='utf-8-sig', errors='strict') as f:  # a BOM is no data
        lines = text_lines(f, path)
    try:
        with warnings.catch_warnings():  # a file without data rows: said below
            warnings.simplefilter('ignore', UserWarning)
            stamps = np.loadtxt(lines, delimiter=',', comments='#', dtype=np.int64,
                                usecols=0, ndmin=1)
            values = np.loadtxt(lines, delimiter=',', comments='#', dtype=np.float64,
                                usecols=range(1, ncols), ndmin=2)
    except (ValueError, OverflowError):  # OverflowError: a stamp beyond int64
        return _parse_lines(lines, path, ncols)
    if not len(stamps):
        raise DatasetError(f'{path}: no data rows')
    return stamps, values


def _parse_lines(lines: list[str], path: Path, ncols: int) -> tuple[np.ndarray, np.ndarray]:
    """Parse line by line: the first row numpy refused is an error naming its line."""
    stamps: list[int] = []
    rows: list[list[float]] = []
    for lineno, line in enumerate(lines, 1):
        if line.startswith('#') or not line.strip():
            continue
        parts = line.split(',')
        if len(parts) < ncols:
            raise DatasetError(f'{path}:{lineno}: expected {ncols} columns, found {len(parts)}')
        try:
            stamps.append(int(parts[0]))
            rows.append([float(x) for x in parts[1:ncols]])
        except ValueError:
            raise DatasetError(
                f'{path}:{lineno}: unparsable row {line.strip()[:60]!r}') from None
        if not -2 ** 63 <= stamps[-1] < 2 ** 63:
            raise DatasetError(f'{path}:{lineno}: stamp {parts[0].strip()[:30]} does not fit '
                               'in 64-bit nanoseconds')
    if not stamps:
        raise DatasetError(f'{path}: no data rows')
    return np.array(stamps, dtype=np.int64), np.array(rows, dtype=np.float64)


def text_lines(f: object, path: Path) -> list[str]:
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
        hint = f'; give its parent, {root.parent}' if root.name == 'mav0' else ''
        raise DatasetError(f'{root}: not an ASL sequence folder (no mav0/ inside{hint})')
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
