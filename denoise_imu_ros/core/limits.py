# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Input policies shared by the node and every offline tool: value range and sample rate.

Rate: the network is trained at one IMU rate; its increments, receptive field and
normalisation are in samples. A stream whose rate (median stamp interval) is more than
RATE_TOLERANCE off the model's is refused by every offline tool (``correct``, ``eval``,
``process-bag``: a one-line error); the node, which cannot refuse a stream, reports an
ERROR in diagnostics, warns, and does not publish the attitude.

Range:
Values beyond it are not motion but corruption (a bit flip, a wrong unit, an
uninitialised field): the float32 network would overflow on them (~3e38) or turn them
into an attitude ruined for good. The limits sit well above every MEMS IMU's range
(gyros saturate at 2,000-4,000 deg/s, accelerometers at 16-200 g).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .errors import DatasetError, DataWarning
from .rotation import relative_arrays

RATE_TOLERANCE = 0.05     # relative rate mismatch refused offline, an ERROR online
MAX_GYRO_RAD_S = 100.0    # ~5,700 deg/s
MAX_ACCEL_M_S2 = 2000.0   # ~200 g
MOUNTING_TOLERANCE_DEG = 45.0  # gravity this far from the model's training IMU's: warned
MAX_RATE_HZ = 100e3       # above, stamps are not nanoseconds (microseconds give 200 kHz)
MAX_POSITION_M = 1e7      # a coordinate beyond 10,000 km is no robot's (ECEF included)


def in_range(gyro: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """Whether each sample (last axis xyz) is finite and within the physical range."""
    return (np.abs(gyro) <= MAX_GYRO_RAD_S).all(-1) & (np.abs(accel) <= MAX_ACCEL_M_S2).all(-1)


def describe() -> str:
    """Describe the limits, for error messages."""
    return f'|gyro| <= {MAX_GYRO_RAD_S:g} rad/s, |accel| <= {MAX_ACCEL_M_S2:g} m/s^2'


def stream_rate_hz(stamps_ns: np.ndarray) -> float:
    """Rate from the median stamp interval (gaps and dropped samples do not bias it)."""
    steps = np.diff(np.asarray(stamps_ns, dtype=np.int64))
    return 1e9 / float(np.median(steps)) if len(steps) and np.median(steps) > 0 else 0.0


def common_rate(rates_hz: dict[str, float], where: object) -> float:
    """
    Return the one rate of recordings trained together (their median), or raise.

    A model is for one rate: its window, increments and receptive field are in samples;
    rates further apart than RATE_TOLERANCE raise a DatasetError naming each one.
    """
    rates = list(rates_hz.values())
    if max(rates) / min(rates) - 1 > RATE_TOLERANCE:
        raise DatasetError(f'{where}: the IMU rates of the recordings differ ('
                           + ', '.join(f'{n} {r:.1f} Hz' for n, r in rates_hz.items())
                           + '): one model is for one rate (its window and increments are '
                           'in samples)')
    return float(np.median(rates))


MAX_GAP_FACTOR = 3.0  # an IMU interval above this many periods is a hole (node and tools)


def imu_holes(stamps_ns: np.ndarray, rate_hz: float | None = None,
              factor: float = MAX_GAP_FACTOR) -> np.ndarray:
    """Return the indices i of the intervals i -> i + 1 longer than ``factor`` periods."""
    rate = rate_hz or stream_rate_hz(stamps_ns)
    return np.flatnonzero(np.diff(np.asarray(stamps_ns, np.int64)) * 1e-9 > factor / rate)


def check_gaps(stamps_ns: np.ndarray, rate_hz: float | None, source: object) -> None:
    """
    Refuse an IMU recording with a hole: the node restarts its network at one.

    Offline tools would otherwise integrate across it as one step, or run the network
    across it, and disagree with the node; split the recording at the hole instead.
    """
    holes = imu_holes(stamps_ns, rate_hz)
    if len(holes):
        i = int(holes[0])
        span = (stamps_ns[i + 1] - stamps_ns[i]) * 1e-9
        raise DatasetError(f'{source}: IMU hole of {span:.3g} s after sample {i} ({len(holes)} '
                           f'longer than {MAX_GAP_FACTOR:g} periods): the node restarts there; '
                           'split the recording at its holes')


GRAVITY_M_S2 = 9.80665
ACCEL_NORM_RANGE = (3.0, 30.0)   # mean |accel| of any recording not in free fall, m/s^2
GYRO_SCALE_LIMIT = 20.0         # gyro spread this many times the model's: not rad/s
DEG_S_HINT = 'gyro in deg/s? (rad/s expected)'  # every unit check says it alike


def accel_units(norm_m_s2: float) -> str | None:
    """Return what a mean accelerometer norm says of its units (None: m/s^2, as expected)."""
    if ACCEL_NORM_RANGE[0] <= norm_m_s2 <= ACCEL_NORM_RANGE[1]:
        return None
    hint = 'accelerometer in g?' if 0.3 <= norm_m_s2 <= 3.0 else 'accelerometer not in m/s^2?'
    return f'mean accelerometer norm {norm_m_s2:.3g} m/s^2, gravity is 9.81: {hint}'


def check_units(imu: np.ndarray, source: object, model_input_std: np.ndarray | None = None,
                model_input_mean: np.ndarray | None = None) -> None:
    """
    Refuse IMU data in the wrong units, naming the likely cause; warn of another mounting.

    The mean accelerometer norm is gravity's, ~9.81 m/s^2, on any recording that is not
    in free fall: ~1 says g. A gyro whose spread is GYRO_SCALE_LIMIT times the model's
    training data (57 times: deg/s) is not in rad/s. Gravity far from where the model's
    training IMU had it (:func:`mounting`) is said as a DataWarning.
    """
    if model_input_mean is not None:
        moved = mounting(imu, model_input_mean)
        if moved:
            warnings.warn(f'{source}: {moved}', DataWarning, stacklevel=2)
    problem = accel_units(float(np.mean(np.linalg.norm(imu[:, 3:], axis=1))))
    if problem:
        raise DatasetError(f'{source}: {problem}')
    if model_input_std is not None:
        ratio = float(np.max(np.std(imu[:, :3], axis=0) / model_input_std[:3]))
        if ratio > GYRO_SCALE_LIMIT:
            raise DatasetError(f'{source}: the gyro varies {ratio:.0f} times as much as the '
                               f"model's training data: {DEG_S_HINT}")


def mounting(imu: np.ndarray, model_input_mean: np.ndarray) -> str | None:
    """
    Say whether gravity lies far from where the model's training IMU had it, or None.

    The model's input normalisation holds its training data's mean accelerometer: for
    a robot, gravity in its IMU's frame. More than MOUNTING_TOLERANCE_DEG away, this IMU
    is mounted otherwise (or the robot hangs upside down): the model corrects axes that
    are not this IMU's.
    """
    here, there = imu[:, 3:].mean(axis=0), np.asarray(model_input_mean[3:6], dtype=float)
    if min(np.linalg.norm(here), np.linalg.norm(there)) < 1.0:  # no gravity in a mean
        return None
    cos = float(here @ there / (np.linalg.norm(here) * np.linalg.norm(there)))
    angle = math.degrees(math.acos(min(1.0, max(-1.0, cos))))
    if angle <= MOUNTING_TOLERANCE_DEG:
        return None
    return (f"gravity is {angle:.0f} deg from where the model's training IMU had it (mean "
            f'accelerometer {np.round(here, 2).tolist()} against {np.round(there, 2).tolist()} '
            "m/s^2): mounted differently? The model corrects its own IMU's axes: rotate "
            "this IMU's data into them, or train on this IMU")


def check_gyro_against_poses(gyro: np.ndarray, gt_quat: np.ndarray, gt_valid: np.ndarray,
                             dt: np.ndarray, source: object) -> None:
    """
    Refuse a gyro that turns GYRO_SCALE_LIMIT times faster than its poses (deg/s: 57).

    Before a training, with no model to compare with: the RMS angular rate of the gyro
    against the poses' own, over trusted samples (the norm: any frame, any clock offset;
    the poses' noise only raises theirs).
    """
    from scipy.spatial.transform import Rotation  # offline only: the node imports limits
    ok = gt_valid[:-1] & gt_valid[1:]
    if ok.sum() < 2:
        return
    step = relative_arrays(gt_quat[:-1], gt_quat[1:])[ok]
    angle = Rotation.from_quat(step).magnitude()
    pose_rms = float(np.sqrt(np.mean((angle / dt[ok]) ** 2)))
    gyro_rms = float(np.sqrt(np.mean(np.sum(gyro[:-1][ok] ** 2, axis=1))))
    if pose_rms > 0 and gyro_rms / pose_rms > GYRO_SCALE_LIMIT:
        raise DatasetError(f'{source}: the gyro turns {gyro_rms / pose_rms:.0f} times as fast '
                           f'as the poses: {DEG_S_HINT}')


def check_rate(stamps_ns: np.ndarray, model_rate_hz: float, source: object) -> None:
    """Refuse a recording whose IMU rate is more than RATE_TOLERANCE off the model's."""
    rate = stream_rate_hz(stamps_ns)
    if abs(rate / model_rate_hz - 1) > RATE_TOLERANCE:
        raise DatasetError(f'{source}: IMU rate {rate:.1f} Hz, the model was trained at '
                           f'{model_rate_hz:.1f} Hz (more than {100 * RATE_TOLERANCE:g} % '
                           'off: retrain at this rate or resample)')
