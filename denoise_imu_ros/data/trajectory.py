# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Trajectory files as VIO and SLAM tools write them (TUM format), as a recording's poses.

One pose a line, ``t x y z qx qy qz qw``: the body-to-world pose of whatever the tool
tracked (often a camera: ``align: auto`` finds its frame and clock). Lines starting with
``#`` are comments. As tools write it: t in seconds, or in nanoseconds (ORB-SLAM3's
EuRoC files, a ROS stamp's integer) where every stamp is at least NANOSECOND_STAMPS,
which no clock in seconds reaches, or where consecutive poses are NANOSECOND_SPACING
apart or more (median), which no trajectory in seconds is (nanoseconds since the tool's
start); commas between values; the same 8 followed by more columns that are not used
(COLUMNS: ASL's state CSV as EuRoC, OKVIS and Kimera write it, velocity and biases;
OpenVINS's covariance); a header line (the last comment before the first pose, or a
first line holding no number) whose names put the quaternion's w first (ASL's
``q_RS_w``, Kimera's ``qw``): read so; where no header names them, 11 or 17 columns are
read w first (W_FIRST_COLUMNS: VINS-Mono's and VINS-Fusion's CSV). Each is said. Tools
write duplicate stamps (a pose written twice), stamps that step back (a
re-initialisation rewriting its past) and rows that are not poses (NaN, a zero
quaternion): those rows are dropped and counted, and a file with nothing left is an
error.
"""

from __future__ import annotations

from array import array
import dataclasses
from dataclasses import dataclass
from decimal import Decimal, ROUND_HALF_EVEN
from pathlib import Path
import re

import numpy as np

from ..core.atomic import atomic_output
from ..core.errors import DatasetError
from ..core.limits import MAX_POSITION_M
from ..core.records import Recording

SUFFIXES = ('.txt', '.tum', '.csv')  # a folder of trajectories holds <recording><suffix>
MAX_NAMED = 6                 # trajectory files an error names, where none is a recording's
UNIT_TOLERANCE = 1e-2         # a quaternion's norm off 1 by more is no pose
NANOSECOND_STAMPS = 1e11      # a stamp this large is no clock in seconds (the year 5138)
NANOSECOND_SPACING = 1e3      # nor poses this far apart (median): 17 min in seconds
COLUMNS = (8, 11, 17, 20)  # TUM's 8, then ASL's velocity and biases, OpenVINS's covariance
# widths every tool writes w first (ASL's state CSV; VINS-Mono's and VINS-Fusion's CSV,
# t x y z qw qx qy qz vx vy vz): read so where no header names the quaternion's columns
W_FIRST_COLUMNS = (11, 17)


@dataclass(frozen=True)
class Trajectory:
    """The poses of one trajectory file, and what was dropped from it."""

    path: Path
    stamp_ns: np.ndarray        # (M,) int64, strictly increasing
    quat: np.ndarray            # (M, 4) float64 xyzw, unit, body to world
    pos: np.ndarray             # (M, 3) float64
    dropped: dict[str, int]     # rows left out, by reason
    read_as: tuple[str, ...] = ()  # how the file was read where it is not plain TUM

    def summary(self) -> str:
        """One line: how it was read and what was dropped, for the commands to say."""
        if not self.dropped and not self.read_as:
            return ''
        said = [f'{len(self.stamp_ns)} poses kept', *self.read_as]
        if self.dropped:
            said.append(dropped_text(self.dropped))
        return f'{self.path}: ' + '; '.join(said)


def read_tum(path: str | Path) -> Trajectory:
    """Read a TUM trajectory file; a file that is not one is a one-line error."""
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f'{path}: no such trajectory file or folder')
    header, values, texts = _read_poses(path)
    width = len(values) // len(texts)
    rows = np.frombuffer(values, dtype=np.float64).reshape(-1, width)
    read_as = [f'the first 8 of its {width} columns read (t x y z and a quaternion), the '
               'rest unused'] if width > 8 else []
    rows = rows[:, :8]
    named = _quaternion_named(header)
    w_first = ('as its header names them' if named == 'wxyz' else
               f"as every tool writing {width} columns writes them (ASL's state CSV, "
               "VINS-Mono's and VINS-Fusion's)" if named is None and width in W_FIRST_COLUMNS
               else None)
    if w_first:
        rows = rows[:, [0, 1, 2, 3, 5, 6, 7, 4]]
        read_as.append(f'quaternions read w first, {w_first}')
    dropped: dict[str, int] = {}
    rows, kept = drop_rows(not_poses(rows, rows[:, 4:8], rows[:, 1:4]), dropped, rows,
                           np.arange(len(rows)))
    if len(rows) < 2:
        raise DatasetError(f'{path}: fewer than two usable poses')
    large = np.abs(rows[:, 0]) >= NANOSECOND_STAMPS
    nano = large.all() or float(np.median(np.abs(np.diff(rows[:, 0])))) >= NANOSECOND_SPACING
    if large.any() and not nano:
        raise DatasetError(f'{path}: stamps from {rows[:, 0].min():.6g} to '
                           f'{rows[:, 0].max():.6g}: neither all in seconds nor all in '
                           f'nanoseconds (a clock in seconds stays below {NANOSECOND_STAMPS:g})')
    if nano:
        read_as.append('stamps read as nanoseconds')
    scale = 1 if nano else 1_000_000_000
    try:  # exact from the text: a float64 of seconds misses nanoseconds
        stamp_ns = np.fromiter(
            (int((Decimal(texts[i]) * scale).to_integral_value(ROUND_HALF_EVEN))
             for i in kept), np.int64, len(kept))
    except OverflowError:
        raise DatasetError(f'{path}: stamps up to {np.abs(rows[:, 0]).max():.6g}: no clock '
                           'in nanoseconds') from None
    rows, stamp_ns = drop_rows(out_of_order(stamp_ns), dropped, rows, stamp_ns)
    if len(rows) < 2:
        raise DatasetError(f'{path}: fewer than two usable poses')
    quat = rows[:, 4:] / np.linalg.norm(rows[:, 4:], axis=1, keepdims=True)
    return Trajectory(path, stamp_ns, quat, rows[:, 1:4], dropped, tuple(read_as))


def not_poses(rows: np.ndarray, quat: np.ndarray, pos: np.ndarray,
              tolerance: float = UNIT_TOLERANCE) -> dict[str, np.ndarray]:
    """
    Return the rows that are no pose, by reason.

    Non-finite, ``pos`` beyond MAX_POSITION_M on an axis (the first such row named,
    counted from 1), or ``quat`` off unit beyond ``tolerance``.
    """
    finite = np.isfinite(rows).all(axis=1)
    unit = np.abs(np.linalg.norm(np.where(finite[:, None], quat, 1.0), axis=1) - 1)
    far = finite & (np.abs(np.where(finite[:, None], pos, 0.0)).max(axis=1) > MAX_POSITION_M)
    first = f' (the first: pose {np.flatnonzero(far)[0] + 1})' if far.any() else ''
    return {'non-finite rows': ~finite,
            f'rows whose position is beyond {MAX_POSITION_M:g} m{first}': far,
            'rows whose quaternion is not a unit one': finite & ~far & (unit > tolerance)}


def out_of_order(stamp_ns: np.ndarray) -> dict[str, np.ndarray]:
    """
    Stamps not above every earlier kept one, by reason: a duplicate, or a step back.

    Tools write a pose twice, and a re-initialisation rewrites its past: the first
    written is kept.
    """
    later = np.ones(len(stamp_ns), dtype=bool)
    later[1:] = stamp_ns[1:] > np.maximum.accumulate(stamp_ns)[:-1]
    duplicate = ~later & np.isin(stamp_ns, stamp_ns[later])
    return {'duplicate stamps': duplicate,
            'stamps earlier than a previous one': ~later & ~duplicate}


def drop_rows(bad: dict[str, np.ndarray], dropped: dict[str, int],
              *arrays: np.ndarray) -> list[np.ndarray]:
    """Return ``arrays`` less the rows ``bad`` marks, counting them by reason in ``dropped``."""
    drop = np.zeros(len(arrays[0]), dtype=bool)
    for why, rows in bad.items():
        if rows.any():
            dropped[why] = int(rows.sum())
            drop |= rows
    return [a[~drop] for a in arrays]


def dropped_text(dropped: dict[str, int]) -> str:
    """Say the rows :func:`drop_rows` counted."""
    return 'dropped ' + ', '.join(f'{n} {why}' for why, n in dropped.items())


def _read_poses(path: Path) -> tuple[list[str], array, list[str]]:
    """
    Read a file's header's column names, its poses' values (row-major) and stamps' text.

    One line at a time: a file of millions of poses is held as its numbers only. The
    header is the last comment before the first pose, or a first line none of whose values
    is a number (OKVIS writes its names so).
    """
    header: list[str] = []
    comment = None
    values, stamps = array('d'), []
    width, offset = 0, 0
    with path.open('rb') as f:
        for raw in f:
            try:
                line = raw.decode('utf-8').strip()
            except UnicodeDecodeError as err:
                raise DatasetError(f'{path}: not a text file (byte {offset + err.start} is '
                                   'not UTF-8)') from err
            if not offset:
                line = line.removeprefix('\ufeff')
            offset += len(raw)
            if not line:
                continue
            if line.startswith('#'):
                comment = comment if stamps else line
                continue
            parts = line.replace(',', ' ').split()
            if not stamps and not header and comment is None and not any(
                    map(_is_number, parts)):
                header, comment = _names(line), ''
                continue
            if not width:
                width = len(parts)
                if width not in COLUMNS:
                    raise DatasetError(
                        f'{path}: line "{line[:60]}" has {width} values, not the 8 of a TUM '
                        "pose (t x y z qx qy qz qw), nor 11, 17 or 20 (those 8, then ASL's "
                        "velocity and biases or OpenVINS's covariance)")
                if not header and comment:
                    header = _names(comment.lstrip('#'))
            if len(parts) != width:
                raise DatasetError(f'{path}: line "{line[:60]}" has {len(parts)} values '
                                   f'where the first pose has {width}')
            try:
                values.extend(map(float, parts))
            except ValueError:
                raise DatasetError(f'{path}: unparsable line "{line[:60]}"') from None
            stamps.append(parts[0])
    if not stamps:
        raise DatasetError(f'{path}: no poses')
    return header, values, stamps


def _names(text: str) -> list[str]:
    """Return a header's column names, their units (``[m]``, ``(s)``) left out."""
    names = text.split(',') if ',' in text else text.split()
    names = [re.sub(r'\[.*?\]|\(.*?\)', '', n).strip() for n in names]
    return [n for n in names if n]  # units written apart (t [s]), a trailing comma


def _is_number(text: str) -> bool:
    """Whether a value reads as a number."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def _quaternion_named(header: list[str]) -> str | None:
    """
    Return the order a header names the quaternion's columns in (``wxyz``, ``xyzw``), or None.

    The 5th to 8th names, the first 8 being t, x, y, z and the quaternion's (more may follow).
    """
    order = ''.join(n[-1:].lower() for n in header[4:8])
    return order if len(header) >= 8 and order in ('wxyz', 'xyzw') else None


def write_tum(path: str | Path, stamp_ns: np.ndarray, pos: np.ndarray,
              quat: np.ndarray) -> Path:
    """
    Write poses as a TUM file, :func:`read_tum`'s inverse (stamps exact to the ns).

    ``quat`` (M, 4) xyzw, body to world; replaces ``path``, whole or not at all.
    """
    stamp_ns = np.asarray(stamp_ns, dtype=np.int64)
    lines = [f'{t // 1_000_000_000}.{t % 1_000_000_000:09d} '
             + ' '.join(f'{v:.12g}' for v in (*p, *q)) + '\n'
             for t, p, q in zip(stamp_ns.tolist(), np.asarray(pos).tolist(),
                                np.asarray(quat).tolist())]
    with atomic_output(path, overwrite=True) as partial:
        partial.write_text('# timestamp tx ty tz qx qy qz qw\n' + ''.join(lines))
    return Path(path)


def trajectory_file(poses: str | Path, recording: str) -> Path:
    """
    Find the trajectory of ``recording``: ``poses`` itself, or <recording>.txt in it.

    Or <recording>.tum, <recording>.csv (SUFFIXES): two of them are an error. Where none
    has the recording's name, one differing only in case is taken if it is the only one;
    where none is the recording's, the error names the files the folder holds.
    """
    poses = Path(poses)
    if not poses.is_dir():
        return poses
    files = sorted(p for p in poses.iterdir() if p.suffix.lower() in SUFFIXES and p.is_file())
    named = [p for p in files if p.stem == recording]
    alike = named or [p for p in files if p.stem.lower() == recording.lower()]  # MH_01_EASY
    if len(alike) == 1:
        return alike[0]
    if alike:  # a stale file beside the right one: which is meant is the user's to say
        raise DatasetError(f'{poses}: {len(alike)} trajectories of {recording} '
                           f'({", ".join(p.name for p in alike)}): keep one')
    held = ', '.join(p.name for p in files[:MAX_NAMED]) + (', ...' if len(files) > MAX_NAMED
                                                           else '')
    raise DatasetError(f'{poses}: no trajectory of {recording} '
                       f'({" or ".join(recording + s for s in SUFFIXES)}'
                       f'{"; it holds " + held if files else "; it holds none"})')


def with_trajectory(rec: Recording, trajectory: Trajectory) -> Recording:
    """``rec`` with the trajectory's poses in place of its own (it may have none)."""
    return dataclasses.replace(rec, gt_stamp_ns=trajectory.stamp_ns, gt_quat=trajectory.quat,
                               gt_pos=trajectory.pos)
