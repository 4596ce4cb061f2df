# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Pose alignment: the clock offset and frame rotation between the poses and the IMU.

Estimated from the data, then applied to the poses before training or evaluation
(``align: auto`` in a recipe, ``--align auto`` in ``eval``); ``check-data`` reports it.

Method: the mean angular rate over short windows (50 ms, or two pose periods) of the
gyro and of the poses are compared; for each candidate clock offset the rotation from
the pose body frame to the IMU frame and the gyro bias follow in closed form (Kabsch
with centring), and the offset minimising the residual is refined to a fraction of a
millisecond by a parabola. Every fit leaves out the windows it cannot explain (a VIO
initialising, a relocalisation: :func:`robust_fit`) and is made again. Confidence
figures are the spread of the same estimates on four consecutive quarters of the
recording (standard error of their mean). Excitation is the gyro's over the windows
compared, less its bias: what the poses could see turn, without their own noise. A
clock further off than the search is found where the rates' norms (free of any frame)
match best over the recording; poses that follow the gyro only inverted or with w first
are read so (:func:`other_convention`).
"""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.spatial.transform import Rotation, Slerp

from .timebase import poses_at, spans
from ..core.errors import DatasetError
from ..core.memo import content_key, Kept
from ..core.metrics import integrate
from ..core.records import Recording, Sequence
from ..core.rotation import kabsch, log_arrays, relative_arrays

RATE_WINDOW_S = 0.05       # window of the mean rates compared (at least two pose periods)
GRID_S = 1e-3              # pose-rate grid
MAX_OFFSET_S = 0.5         # default clock-offset search range (+-)
QUARTERS = 4
COARSE_WINDOWS = 2000      # rate windows the coarse offset search scores
COARSE_STEP_S = 4e-3       # its step: the 50 ms rate windows make minima wider
OFFSET_XTOL_S = 1e-5       # precision of the final offset search
TIE_RAD_S = 1e-9           # offsets whose rate residuals differ by less than this tie
LEVEL_TOLERANCE_DEG = 5.0  # a world whose up is further from its z than this is levelled
JUMP_RATE_FACTOR = 2.0     # pose rates beyond this times the gyro's fastest, plus
JUMP_RATE_MARGIN_RAD_S = 0.2  # this, are jumps: left out of the comparison
OFFSET_TOLERANCE_S = 1e-3  # above, and SIGNIFICANCE standard errors: apply the offset
ROTATION_TOLERANCE_DEG = 0.2  # above, and SIGNIFICANCE standard errors: apply the rotation
SIGNIFICANCE = 2.0
OUTLIER_FACTOR = 6.0       # a window whose residual is beyond this times the median
OUTLIER_MAX_FRACTION = 0.2  # more than this part of them: the poses do not follow
MIN_EXCITATION_DEG_S = 2.0  # RMS rate about an axis below which it is not observed
NORM_GRID_S = 0.01         # grid of the rate norms' cross-correlation (a coarse offset)
NORM_DETREND_S = 2.0       # the norms less their moving mean over this: changes matched
FAR_MARGIN = 0.5           # an offset beyond the search wins only below this times its residual
OTHER_CLOCK_S = 10.0       # offsets said in s from this on (a clock since the poses' start)
# The estimates of the last recordings read, by their content (core.memo): an alignment
# and a scale error each, of the poses as written and as check-data reads them otherwise
ESTIMATES_KEPT = 32
_ALIGNMENTS: Kept[dict[str, Any]] = Kept(ESTIMATES_KEPT)
_SCALE_ERRORS: Kept[list[float | None]] = Kept(ESTIMATES_KEPT)


class Rates:
    """Mean angular rates of the gyro and of the poses over matching windows."""

    def __init__(self, rec: Recording, window_s: float) -> None:
        t0 = rec.gt_stamp_ns[0]
        # poses on a fine uniform grid of their own clock (holes marked)
        grid_ns = t0 + np.arange(0, rec.gt_stamp_ns[-1] - t0, int(GRID_S * 1e9))
        quat, _, valid = poses_at(rec, grid_ns)
        w = max(1, int(round(window_s / GRID_S)))
        if len(grid_ns) <= w + 1:
            raise DatasetError(f'{rec.source}: the poses span {len(grid_ns) * GRID_S:.2f} s, '
                               f'not more than the {window_s:.2f} s over which their rate is '
                               'compared with the gyro (two pose periods at least)')
        self.pose_t = (grid_ns[:-w] - t0) * 1e-9                 # window starts, pose clock
        # q_n^-1 q_n+w and its rotation vector by numpy: scipy's cost many times more
        self.pose = log_arrays(relative_arrays(quat[:-w], quat[w:])) / (w * GRID_S)
        self.pose_ok = valid[:-w] & valid[w:]
        self._pose_rows = np.ascontiguousarray(self.pose.T)
        # gyro mean rates over windows of the same length, every sample; a sample is the
        # rate at its stamp, so n samples cover from half a period before the first
        t = (rec.imu_stamp_ns - t0) * 1e-9
        n = max(1, int(round(window_s / np.median(np.diff(t)))))
        steps = rec.imu[:-1, :3] * np.diff(t)[:, None]
        cs = np.concatenate([np.zeros((1, 3)), np.cumsum(steps, axis=0)])
        self.imu_t = t[:-n] - 0.5 * np.diff(t)[:len(t) - n]
        self.imu = (cs[n:] - cs[:-n]) / (t[n:] - t[:-n])[:, None]
        self.window_s = n * float(np.median(np.diff(t)))
        self._imu_rows = np.ascontiguousarray(self.imu.T)
        # a pose jump (a VIO re-initialising, a placeholder pose) turns faster than the
        # gyro ever does: those windows are not compared (norms: any frame, any clock)
        fastest = float(np.linalg.norm(self.imu, axis=1).max())
        self.pose_ok &= np.linalg.norm(self.pose, axis=1) <= JUMP_RATE_FACTOR * fastest + \
            JUMP_RATE_MARGIN_RAD_S

    def pairs(self, offset_s: float, part: slice = slice(None)) -> np.ndarray:
        """
        Return the gyro's and the poses' rates (6, n) where trusted poses cover, at an offset.

        Each axis a contiguous row: numpy's products and sums over 3 columns of n rows
        cost several times those over 3 rows of n columns.
        """
        tau = self.imu_t[part] - offset_s  # t_pose = t_imu - offset; increasing
        lo = int(np.searchsorted(tau, self.pose_t[0], side='left'))
        hi = int(np.searchsorted(tau, self.pose_t[-1], side='right'))
        tau = tau[lo:hi]
        k = np.clip(np.round((tau - self.pose_t[0]) / GRID_S).astype(int), 0,
                    len(self.pose_t) - 1)
        ok = self.pose_ok[k]
        imu = self._imu_rows[:, part][:, lo:hi]
        if not ok.all():
            tau, imu = tau[ok], imu[:, ok]
        # linear interpolation on the uniform grid: np.interp without its binary search
        x = (tau - self.pose_t[0]) / GRID_S
        i = np.clip(np.floor(x).astype(int), 0, len(self.pose_t) - 2)
        f = x - i
        pairs = np.empty((6, len(x)))
        pairs[:3] = imu
        np.multiply(self._pose_rows[:, i], 1 - f, out=pairs[3:])
        pairs[3:] += self._pose_rows[:, i + 1] * f
        return pairs


def fit_frame(imu: np.ndarray, pose: np.ndarray) -> tuple[Rotation, np.ndarray, float]:
    """Rotation R and bias b with imu = R pose + b (least squares); RMS residual."""
    r, bias, rms, _ = _fit(np.vstack([imu.T, pose.T]))
    return Rotation.from_matrix(r), bias, rms


def _fit(pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """
    Return :func:`fit_frame`'s fit of :meth:`Rates.pairs`, R as a matrix; residual norms.

    The offset search's inner loop: Kabsch with centring, the centred cross-covariance
    from the rows' sums and one product.
    """
    n = pairs.shape[1]
    mean = pairs.sum(1) / n
    mi, mp = mean[:3], mean[3:]
    r = kabsch(np.dot(pairs[3:], pairs[:3].T) - n * np.outer(mp, mi))
    bias = mi - r @ mp
    error = pairs[:3] - np.dot(r, pairs[3:]) - bias[:, None]
    squared = np.einsum('ij,ij->j', error, error)
    return r, bias, math.sqrt(squared.sum() / (3 * n)), np.sqrt(squared)


def robust_fit(imu: np.ndarray,
               pose: np.ndarray) -> tuple[Rotation, np.ndarray, float, np.ndarray]:
    """
    Fit the frame again without the windows it cannot explain; also say which those are.

    A window beyond OUTLIER_FACTOR times the median residual is left out (a VIO
    initialising, a relocalisation), unless more than OUTLIER_MAX_FRACTION are: then the
    poses do not follow the gyro, and the residual of them all says so.
    """
    r, bias, rms, out = _robust_fit(np.vstack([imu.T, pose.T]))
    return Rotation.from_matrix(r), bias, rms, out


def _robust_fit(pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """Return :func:`robust_fit`'s fit of :meth:`Rates.pairs`, R as a matrix."""
    r, bias, rms, residual = _fit(pairs)
    out = residual > OUTLIER_FACTOR * _median(residual)
    if not out.any() or out.mean() > OUTLIER_MAX_FRACTION:
        return r, bias, rms, np.zeros(pairs.shape[1], dtype=bool)
    return (*_fit(pairs[:, ~out])[:3], out)


def _median(values: np.ndarray) -> float:
    """Return ``np.median`` of finite values, by one partition (its checks cost more)."""
    n = len(values)
    middle = np.partition(values, [(n - 1) // 2, n // 2])
    return float((middle[(n - 1) // 2] + middle[n // 2]) / 2)


def _scale_error(imu: np.ndarray, pose: np.ndarray) -> list[float | None]:
    """Return the gyro's scale error (%) per axis against pose rates in its frame, bias-free."""
    power = (pose ** 2).sum(0)
    observed = power > 1e-12 * len(pose)  # an axis without rotation has no scale
    scale = (imu * pose).sum(0) / np.where(observed, power, 1.0)
    return [float(100 * (v - 1)) if ok else None for v, ok in zip(scale, observed)]


def interpolation_scale_error(rec: Recording) -> list[float | None]:
    """
    Return the scale error (%) per axis that interpolating between the pose stamps makes.

    The gyro's integrated attitude stands for poses without error: its rates over the
    alignment's windows (:class:`Rates`), from its values at the pose stamps interpolated
    as poses are, are compared with the same from every IMU sample; what differs is the
    interpolation's alone, whatever the poses' errors and the gyro's own scale. Poses a
    few times a second (a SLAM's keyframes) miss what turns faster; a model trained on
    them learns the difference as the gyro's scale. An axis that turns less than
    MIN_EXCITATION_DEG_S over those windows (vibration) has no scale to judge: None.
    """
    key = content_key(rec.imu_stamp_ns, rec.imu[:, :3], rec.gt_stamp_ns)
    return list(_SCALE_ERRORS.get(key, lambda: _interpolation_scale_error(rec)))


def _interpolation_scale_error(rec: Recording) -> list[float | None]:
    """Return :func:`interpolation_scale_error`'s figures, computed."""
    t = rec.imu_stamp_ns
    stamps = rec.gt_stamp_ns[(rec.gt_stamp_ns >= t[0]) & (rec.gt_stamp_ns <= t[-1])]
    if len(stamps) < 3:
        return [None, None, None]
    integrated = integrate(np.array([0.0, 0.0, 0.0, 1.0]), rec.imu[:-1, :3], np.diff(t) * 1e-9)
    attitude = Slerp((t - t[0]) * 1e-9, integrated)
    window_s = max(RATE_WINDOW_S, 2 * float(np.median(np.diff(stamps))) * 1e-9)

    def seen_at(known: np.ndarray) -> Rates:  # the attitude known only at these stamps
        return Rates(Recording(rec.name, rec.source, t, rec.imu, known,
                               attitude((known - t[0]) * 1e-9).as_quat(),
                               np.zeros((len(known), 3))), window_s)

    # the same span, so the same grid: every IMU stamp inside it, and its ends
    sparse = seen_at(stamps)
    dense = seen_at(np.union1d(stamps[[0, -1]], t[(t > stamps[0]) & (t < stamps[-1])]))
    ok = sparse.pose_ok & dense.pose_ok
    truth = dense.pose[ok]
    turns = np.degrees(np.sqrt(np.mean(truth ** 2, axis=0))) >= MIN_EXCITATION_DEG_S
    return [v if on else None for v, on in zip(_scale_error(truth, sparse.pose[ok]), turns)]


def _residual(rates: Rates, offset_s: float, windows: slice = slice(None)) -> float:
    """Return the frame-fitted rate residual (rad/s) of some windows at a clock offset."""
    pairs = rates.pairs(offset_s, windows)
    return _robust_fit(pairs)[2] if pairs.shape[1] > 100 else math.inf


def _best_offset(rates: Rates, max_offset_s: float, part: slice = slice(None),
                 center: float = 0.0) -> float:
    """
    Clock offset (s) minimising the frame-fitted residual: coarse grid, fine grid, Brent.

    The coarse grid scores about COARSE_WINDOWS windows spread over the part (adjacent
    rather than overlapping windows: the same motion, a tenth of the work on EuRoC); the
    fine grid around its best offset, and the bounded Brent search between the fine
    grid's neighbours of its best point, score every window.
    """
    n = len(rates.imu_t[part])
    coarse = slice(part.start, part.stop, max(1, n // COARSE_WINDOWS))
    best = center
    for span, step, windows in ((max_offset_s, COARSE_STEP_S, coarse), (4e-3, 5e-4, part)):
        grid = best + np.arange(-span, span + step / 2, step)
        costs = np.array([_residual(rates, d, windows) for d in grid])
        # ties (motion that cannot tell offsets apart) go to the offset nearest the centre
        tied = np.flatnonzero(costs <= costs.min() + TIE_RAD_S)
        best = float(grid[tied[np.argmin(np.abs(grid[tied] - center))]])
    if not np.isfinite(costs.min()):
        return best
    found = minimize_scalar(lambda d: _residual(rates, d, part), bounds=(best - step, best + step),
                            method='bounded', options={'xatol': OFFSET_XTOL_S})
    return float(found.x) if found.fun < costs.min() - TIE_RAD_S else best


def _norm_lag(rates: Rates) -> float:
    """
    Return the clock offset (s) at which the poses' rate norms best match the gyro's.

    Norms do not depend on the frames, so one cross-correlation over the whole recording
    (on a NORM_GRID_S grid) places a clock however far off, where the offset search
    (max_offset_s) does not reach: a coarse start for it.
    """
    start = min(rates.imu_t[0], rates.pose_t[0])
    grid = np.arange(start, max(rates.imu_t[-1], rates.pose_t[-1]), NORM_GRID_S)
    pose = np.where(rates.pose_ok, np.linalg.norm(rates.pose, axis=1), np.nan)
    series = [np.interp(grid, t, v, left=np.nan, right=np.nan) for t, v in (
        (rates.imu_t, np.linalg.norm(rates.imu, axis=1)), (rates.pose_t, pose))]
    if not all(np.isfinite(v).any() for v in series):
        return 0.0  # no pose rate to match (the search then finds nothing either)
    gyro, poses = (_detrended(v, round(NORM_DETREND_S / NORM_GRID_S)) for v in series)
    return best_lag(gyro, poses) * NORM_GRID_S


def _detrended(values: np.ndarray, n: int) -> np.ndarray:
    """
    Return the values less their moving mean over n points, 0 where they are NaN.

    The gyro's norm holds its bias (still: its norm, where the poses' is 0): only what
    changes within a few seconds is matched.
    """
    known = np.isfinite(values)
    window = np.ones(min(n, len(values)))  # 'same' keeps the longer of the two
    total = np.convolve(np.where(known, values, 0.0), window, 'same')
    count = np.convolve(known.astype(float), window, 'same')
    return np.where(known, values - total / np.maximum(count, 1.0), 0.0)


def best_lag(a: np.ndarray, b: np.ndarray) -> int:
    """
    Return the lag k maximising sum over t of a[t + k] b[t], for series of one length.

    scipy.signal.correlate's ``full`` correlation by numpy's FFT: that module's import
    alone would cost every command that reads poses a third of a second.
    """
    n = len(a)
    size = 1 << (2 * n - 2).bit_length()
    match = np.fft.irfft(np.fft.rfft(a, size) * np.conj(np.fft.rfft(b, size)), size)
    lags = np.r_[np.arange(n), np.arange(size - n, size) - size]
    return int(lags[np.argmax(match[lags])])


def not_following(found: dict[str, Any], max_offset_s: float = MAX_OFFSET_S) -> str | None:
    """
    Why the poses of an estimate do not follow the gyro at any offset searched, or None.

    Then the estimate is no alignment: the offset lies beyond the search range, or the
    poses are not of this IMU.
    """
    motion = float(np.sqrt(np.mean(np.square(found['excitation_rms_deg_s']))))
    if found['time_offset_at_search_limit'] or found['rate_residual_rms_deg_s'] > 0.5 * motion:
        return (f'the poses do not follow the gyro at any clock offset searched (within '
                f'+-{max_offset_s:g} s, and of where their rate norms match best; rate residual '
                f'{found["rate_residual_rms_deg_s"]:.1f} deg/s RMS against {motion:.1f} deg/s of '
                'motion): the poses are not of this IMU, or their clock is not steady')
    return None


def describe(found: dict[str, Any]) -> str:
    """Return the clock offset and frame rotation of an estimate, in words."""
    return (f'poses {offset_text(found["time_offset_s"])} off the IMU clock and in a frame '
            f'{found["imu_from_pose_rotation_deg"]:.2f} deg from the IMU\'s')


def offset_text(offset_s: float, decimals: int = 1) -> str:
    """Say a clock offset in ms, or in s where it is one of another clock (10 s or more)."""
    if abs(offset_s) >= OTHER_CLOCK_S:
        return f'{offset_s:+.{decimals + 3}f} s'
    return f'{1e3 * offset_s:+.{decimals}f} ms'


def needs_alignment(report: dict[str, Any]) -> bool:
    """Whether the clock offset or the frame rotation found is beyond tolerance and noise."""
    return _significant(report['time_offset_s'], report['time_offset_std_s'],
                        OFFSET_TOLERANCE_S) or _significant(
        report['imu_from_pose_rotation_deg'], report['imu_from_pose_rotation_std_deg'],
        ROTATION_TOLERANCE_DEG)


def _significant(value: float, std: float | None, tolerance: float) -> bool:
    """
    Whether an estimate is both beyond the tolerance and clear of its own noise.

    An estimate whose noise was not measured (None) is not: seconds of poses.
    """
    return std is not None and abs(value) > tolerance and abs(value) > SIGNIFICANCE * std


def estimate_pose_alignment(rec: Recording,
                            max_offset_s: float = MAX_OFFSET_S) -> dict[str, Any]:
    """
    Clock offset and frame rotation between the poses and the IMU, with confidences.

    ``time_offset_s``: t_imu = t_pose + offset. ``imu_from_pose_rotation_xyzw``:
    omega_imu = R omega_pose_body. Also the gyro bias, per-axis scale and excitation, and
    the fraction of rate windows the fit left out (``rate_windows_left_out``).
    """
    key = content_key(rec.imu_stamp_ns, rec.imu[:, :3], rec.gt_stamp_ns, rec.gt_quat,
                      rec.gt_pos, salt=repr(max_offset_s))
    found = _ALIGNMENTS.get(key, lambda: _estimate_pose_alignment(rec, max_offset_s))
    return copy.deepcopy(found)  # a caller's changes stay its own


def _estimate_pose_alignment(rec: Recording, max_offset_s: float) -> dict[str, Any]:
    """Return :func:`estimate_pose_alignment`'s estimate, computed."""
    period = float(np.median(np.diff(rec.gt_stamp_ns))) * 1e-9
    rates = Rates(rec, max(RATE_WINDOW_S, 2 * period))
    offset, center = _best_offset(rates, max_offset_s), 0.0
    lag = _norm_lag(rates)
    if abs(lag) > max_offset_s:  # a clock further off than the search: searched there too
        far = _best_offset(rates, max_offset_s, center=lag)
        if _residual(rates, far) < FAR_MARGIN * _residual(rates, offset):
            offset, center = far, lag
    pairs = rates.pairs(offset)
    if pairs.shape[1] < 3:
        raise DatasetError(f'{rec.source}: no pose rate to compare with the gyro: the poses '
                           'turn faster than the gyro ever does, or overlap it nowhere')
    r, bias, rms, out = _robust_fit(pairs)
    rot = Rotation.from_matrix(r)
    imu, pose = pairs[:3, ~out].T, pairs[3:, ~out].T
    aligned = rot.apply(pose)
    # what the poses can see turn: the gyro over the windows compared, less its bias
    excitation = np.sqrt(np.mean((imu - bias) ** 2, axis=0))
    # confidence: the same estimates on four quarters of the recording
    n = len(rates.imu_t)
    offsets, angles = [], []
    for q in range(QUARTERS):
        part = slice(q * n // QUARTERS, (q + 1) * n // QUARTERS)
        offsets.append(_best_offset(rates, 4e-3, part, center=offset))
        quarter = rates.pairs(offset, part)
        if quarter.shape[1] > 100:
            turn = Rotation.from_matrix(_robust_fit(quarter)[0]) * rot.inv()
            angles.append(math.degrees(turn.magnitude()))
    return {
        'time_offset_s': offset,
        # the standard error of their mean: the sample std (ddof 1; of four, ddof 0 is 13 % low)
        'time_offset_std_s': float(np.std(offsets, ddof=1) / math.sqrt(len(offsets))),
        'time_offset_quarters_s': offsets,
        'time_offset_at_search_limit': bool(abs(offset - center) > max_offset_s - 2e-3),
        'imu_from_pose_rotation_xyzw': rot.as_quat().tolist(),
        'imu_from_pose_rotation_deg': math.degrees(rot.magnitude()),
        # None where no quarter is long enough to judge (seconds of poses): not measured
        'imu_from_pose_rotation_std_deg': float(np.sqrt(np.mean(np.square(angles)))
                                                / math.sqrt(len(angles))) if angles else None,
        'gyro_bias_vs_pose_deg_s': np.degrees(bias).tolist(),
        'gyro_scale_error_percent': _scale_error(imu - bias, aligned),
        'excitation_rms_deg_s': np.degrees(excitation).tolist(),
        'rate_residual_rms_deg_s': math.degrees(rms),
        'rate_window_s': rates.window_s,
        'rate_windows_left_out': float(out.mean()),
    }


def level(seq: Sequence) -> tuple[Sequence, float]:
    """
    Turn the poses into a world whose z is up; return them and how far up was from z.

    A SLAM's world is often its first camera frame: relative rotations (training, the
    attitude error from a first pose) do not care, a gravity-aided filter's tilt and an
    accelerometer-bias fit do. Up in the poses' world is the mean of the accelerometer
    turned into it (its motion averages out over a recording); a world more than
    LEVEL_TOLERANCE_DEG from it is turned level. Poses that do not turn the accelerometer
    into a steady up (another frame, no alignment) are left as they are.
    """
    valid = seq.gt_valid
    if valid.sum() < 2:
        return seq, 0.0
    up = Rotation.from_quat(seq.gt_quat[valid]).apply(seq.imu[valid, 3:]).mean(axis=0)
    size = float(np.linalg.norm(up))
    if size < 0.5 * float(np.linalg.norm(seq.imu[valid, 3:], axis=1).mean()):
        return seq, 0.0
    tilt = math.degrees(math.acos(min(1.0, max(-1.0, up[2] / size))))
    if tilt <= LEVEL_TOLERANCE_DEG:
        return seq, tilt
    turn = Rotation.align_vectors([[0.0, 0.0, 1.0]], [up / size])[0]
    return dataclasses.replace(seq, gt_quat=(turn * Rotation.from_quat(seq.gt_quat)).as_quat(),
                               gt_pos=turn.apply(seq.gt_pos)), tilt


def apply_pose_alignment(rec: Recording, time_offset_s: float,
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


def _inverted(rec: Recording) -> Recording:
    """Return the poses inverted: a file of world-in-body poses read as body-in-world."""
    inv = Rotation.from_quat(rec.gt_quat).inv()
    return dataclasses.replace(rec, gt_quat=inv.as_quat(), gt_pos=-inv.apply(rec.gt_pos))


def _w_first(rec: Recording) -> Recording:
    """Return the quaternions of a file that wrote w first, read as x, y, z, w."""
    quat = rec.gt_quat[:, [1, 2, 3, 0]]
    return dataclasses.replace(rec, gt_quat=quat / np.linalg.norm(quat, axis=1, keepdims=True))


def other_convention(rec: Recording, max_offset_s: float = MAX_OFFSET_S
                     ) -> tuple[Recording, dict[str, Any], str] | None:
    """
    Return the poses read another common way where they follow the gyro, its estimate, how.

    For poses that follow the gyro at no offset as read (:func:`not_following`): a file
    of world-in-camera poses (T_cw where TUM files hold T_wc), or of quaternions written
    w first. To a gyro the two look alike (an odd permutation of a quaternion's components
    is its inverse between two fixed rotations, which the frame rotation and the world
    absorb); the positions tell them apart: read the right way they trace the shorter
    path. None when neither way follows.
    """
    inverted = _inverted(rec)
    found = estimate_pose_alignment(inverted, max_offset_s)
    if not_following(found, max_offset_s):
        return None
    length, as_written = _path_length(inverted), _path_length(rec)
    if length < as_written:
        return inverted, found, 'inverted (world-in-camera poses, T_cw; TUM files hold T_wc)'
    if length == as_written:  # no positions to tell (orientation only): both read alike
        return inverted, found, 'inverted or with w first (the positions do not tell which)'
    reordered = _w_first(rec)
    found = estimate_pose_alignment(reordered, max_offset_s)
    if not_following(found, max_offset_s):
        return None
    return reordered, found, 'with w first (qw qx qy qz; TUM files hold qx qy qz qw)'


def read_and_align(rec: Recording, max_offset_s: float = MAX_OFFSET_S
                   ) -> tuple[Recording, dict[str, Any], str | None]:
    """
    Return the poses as every command reads them, their alignment estimate, and how read.

    As written (how: None) unless only another common way follows the gyro
    (:func:`other_convention`): check-data and every alignment read them alike. Poses on
    a clock the IMU's overlaps nowhere are searched for from the IMU's start
    (:func:`on_imu_clock`); the offset found is from their stamps as written.
    """
    placed, shift_ns = on_imu_clock(rec)
    found = estimate_pose_alignment(placed, max_offset_s)
    other = None
    if not_following(found, max_offset_s):
        other = other_convention(placed, max_offset_s)
    read, how = (placed, None) if other is None else (other[0], other[2])
    found = found if other is None else other[1]
    if not shift_ns:
        return read, found, how
    if not_following(found, max_offset_s):
        raise DatasetError(f"{rec.source}: the poses are on another clock than the IMU's "
                           f'({spans(rec)}) and do not follow the gyro at any clock offset over '
                           "the whole recording: another recording's trajectory?")
    moved = {**found, 'time_offset_s': found['time_offset_s'] + shift_ns * 1e-9,
             'time_offset_quarters_s': [q + shift_ns * 1e-9
                                        for q in found['time_offset_quarters_s']]}
    return dataclasses.replace(read, gt_stamp_ns=rec.gt_stamp_ns), moved, how


def on_imu_clock(rec: Recording) -> tuple[Recording, int]:
    """
    Return the poses, moved to start with the IMU where it overlaps them nowhere; the shift.

    A trajectory stamped in time since its own start, or by the clock of the computer that
    replayed the recording, overlaps the IMU's stamps nowhere. Placed start to start, the
    rates' norms (:func:`_norm_lag`) find where it lies in the recording. Poses that
    overlap the IMU's stamps are returned as they are, shift 0 (ns).
    """
    t_imu, t_gt = rec.imu_stamp_ns, rec.gt_stamp_ns
    if len(t_gt) < 2 or len(t_imu) < 2 or (t_gt[0] < t_imu[-1] and t_gt[-1] > t_imu[0]):
        return rec, 0
    shift_ns = int(t_imu[0]) - int(t_gt[0])
    return dataclasses.replace(rec, gt_stamp_ns=t_gt + shift_ns), shift_ns


def _path_length(rec: Recording) -> float:
    """Return the length of the path the positions trace (m)."""
    return float(np.linalg.norm(np.diff(rec.gt_pos, axis=0), axis=1).sum())
