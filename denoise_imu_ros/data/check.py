# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Data quality before training (``denoise-imu check-data``): clocks, frames, label noise.

The loss compares gyro increments with ground-truth increments over j samples. If the
ground truth jitters (mocap) or is interpolated between sparse poses (VIO at 10-20 Hz),
the short increments measure that noise rather than the gyro's error. The label-noise
profile integrates the gyro with one constant bias removed (fitted to the ground truth)
and reports the RMS increment residual per length j; divided by the increment's
duration it is the gyro error (deg/s) the noise alone would stand for. Above
NOISE_RATE_LIMIT_DEG_S, more than the corrections the method makes (at most ~1 deg/s,
the paper), an increment length is noise-dominated. The residual is also split, in the
poses' world turned level, into its heading (about the vertical) and its tilt: a VIO's
heading, which gravity does not hold, is noisier than its tilt.

Supervision: noise that averages out is not the only way poses mislead the loss. A
constant bias fitted on the poses' own increments (the paper's lengths and ~1 s) is
removed and the whole recording integrated: if that never lowers the recording's own
attitude error, the increments' disagreement with the gyro is the poses' error, and a
network trained to remove it will not beat plain integration.

Clock offset and frame rotation: :mod:`denoise_imu_ros.data.pose_alignment`. Where they
are significant, the label noise and the supervision are judged on the poses moved onto
the IMU clock and into its frame, as training with ``align: auto`` uses them.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from .pose_alignment import (apply_pose_alignment, describe, interpolation_scale_error, level,
                             MAX_OFFSET_S, MIN_EXCITATION_DEG_S, needs_alignment,
                             not_following, offset_text, on_imu_clock, read_and_align)
from .pose_jumps import describe as describe_jumps, find_jumps, Jump, mask_jumps
from .timebase import onto_imu_stamps
from ..core.architecture import ModelConfig
from ..core.limits import accel_units, DEG_S_HINT, imu_holes, MAX_GAP_FACTOR
from ..core.metrics import (attitude_errors, fit_constant_bias, increment_residuals, increments,
                            integrate, integrate_from_trusted, sequence_errors)
from ..core.records import Recording, Sequence

LENGTHS = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512)  # increment lengths profiled (samples)
# a trajectory's heading drift grows over these, its noise does not: heading and tilt
# are compared there too (init-recipe's heading_weight)
DRIFT_HORIZONS_S = (5.0, 10.0, 20.0)
# the scale error interpolating between the pose stamps makes beyond this (%): poses too
# sparse for the motion (EuRoC, at VINS-Mono's aligned stamps: 10 Hz 0.4 at most, 5 Hz
# 0.5 but 1.05 on V2_03, a pose every 0.2-1.0 s 1.6-12 and 43 on V2_03; motion capture
# 0.01 at most, BROAD's and TUM-VI's too)
INTERPOLATION_LIMIT_PERCENT = 1.0
# between pose stamps, a length counts only where its increments span this much of the
# recording (keyframes 0.2-1.0 s apart: 32 samples span almost nothing, 128 most of it)
MIN_POSE_COVERAGE = 0.5
LEFT_OUT_SAID = 0.01       # a fraction of rate windows left out of the alignment said from
BIAS_FIT_LENGTH = 64      # increments the constant bias is fitted on (samples)
NOISE_RATE_LIMIT_DEG_S = 1.0
MIN_DURATION_S = 30.0      # shorter recordings cannot train (window, tail, warm-up)
OFFSET_SPREAD_S = 4e-3     # quarters spread wider (clean ones: 3.2 ms at most): drift
PAPER_INCREMENT_S = 0.08  # the paper's 16 samples at 200 Hz (and twice it, 32)
DEG_PER_RAD_LOW = 20.0    # a gyro scale above this against the poses: degrees, not radians
SUPERVISION_LONG_S = 1.0  # the longest increment the supervision check also fits on
CLIPPED_MIN_FRACTION = 1e-3  # samples pinned at an axis's extreme beyond this: saturation
CLIPPED_MIN_SAMPLES = 10


# what check() estimates beyond rates and holes (None for a recording too short for it)
ESTIMATES = ('gyro_bias_deg_s', 'increments', 'noise_dominated_increments', 'time_offset_s',
             'time_offset_std_s', 'time_offset_quarters_s', 'time_offset_at_search_limit',
             'imu_from_pose_rotation_xyzw', 'imu_from_pose_rotation_deg',
             'imu_from_pose_rotation_std_deg', 'gyro_bias_vs_pose_deg_s',
             'gyro_scale_error_percent', 'excitation_rms_deg_s', 'rate_residual_rms_deg_s',
             'rate_window_s', 'rate_windows_left_out', 'judged_after_alignment', 'pose_jumps',
             'drift_increments', 'interpolation_scale_error_percent', 'too_sparse',
             'read_as', 'paper_increments', 'shortest_clean_increment', 'label_noise',
             'supervision')


def paper_increments(rate_hz: float) -> tuple[int, int]:
    """
    Return the paper's increments at this rate: the power of two nearest 0.08 s, and twice it.

    16/32 samples at 200 Hz, 8/16 at 100 Hz, 64/128 at 1 kHz (0.064 s: the loss needs
    powers of two).
    """
    first = 2 ** max(0, round(math.log2(PAPER_INCREMENT_S * rate_hz)))
    return first, 2 * first


def label_noise(seq: Sequence, horizons_s: tuple[float, ...] = (),
                between_poses: bool = False) -> dict[str, Any]:
    """
    Constant gyro bias against the ground truth, and the increment residual per length.

    Also the heading and tilt residuals over ``horizons_s`` (``drift_increments``). With
    ``between_poses`` every increment runs between pose stamps, as the loss then compares
    them (:func:`~denoise_imu_ros.core.metrics.increments`): what is left is the poses'
    own noise, not what interpolating between them misses.
    """
    gyro = seq.imu[:, :3]
    dt = float(np.mean(seq.dt))
    pose_at = seq.pose_at if between_poses else None
    bias = fit_constant_bias(seq.gt_quat, seq.gt_valid, gyro, seq.dt, BIAS_FIT_LENGTH,
                             pose_at=pose_at)
    if bias is None:  # no trusted block that long: the profile shows the raw residual
        bias = np.zeros(3)
    est = integrate(seq.gt_quat[0], gyro[:-1] - bias, seq.dt)  # one for every length
    world = level(seq)[0].gt_quat  # the same increments, the vertical along z

    def split(j: int) -> dict[str, float] | None:
        if (len(seq) - 1) // j < 2:
            return None
        starts, ends = increments(seq.gt_valid, j, pose_at)
        if pose_at is not None and _covered(starts, ends, len(seq)) < MIN_POSE_COVERAGE:
            return None  # too few poses that far apart: the loss would see little of it
        res, _ = increment_residuals(seq.gt_quat, seq.gt_valid, gyro - bias, seq.dt, j, est,
                                     pose_at)
        if len(res) == 0:
            return None
        # each residual is in the body frame at its increment's end
        turned = Rotation.from_quat(world[ends]).apply(res)
        return {'residual_mrad': 1e3 * float(np.sqrt(np.mean(res ** 2))),  # per axis
                'heading_mrad': 1e3 * float(np.sqrt(np.mean(turned[:, 2] ** 2))),
                'tilt_mrad': 1e3 * float(np.sqrt(np.mean(turned[:, :2] ** 2))),
                'blocks': len(res)}

    profile = {}
    for j in LENGTHS:
        found = split(j)
        if found:
            profile[j] = {**found, 'noise_rate_deg_s': math.degrees(
                found['residual_mrad'] * 1e-3 / (j * dt))}
    drift = {}
    for horizon in horizons_s:
        j = int(round(horizon / dt))
        found = split(j)
        if found:
            drift[j] = found
    noisy = [j for j, p in profile.items() if p['noise_rate_deg_s'] > NOISE_RATE_LIMIT_DEG_S]
    return {'gyro_bias_deg_s': np.degrees(bias).tolist(), 'increments': profile,
            'noise_dominated_increments': noisy, 'drift_increments': drift}


def _covered(starts: np.ndarray, ends: np.ndarray, n: int) -> float:
    """Return the fraction of n stamps that some increment [start, end] spans."""
    steps = np.zeros(n + 1, int)
    np.add.at(steps, starts, 1)
    np.add.at(steps, ends + 1, -1)
    return float(np.mean(np.cumsum(steps)[:n] > 0))


def supervision(seq: Sequence, lengths: tuple[int, ...],
                between_poses: bool = False) -> dict[str, Any]:
    """
    Whether the poses can supervise a correction of this gyro, at each increment length.

    The smallest correction there is: one constant bias, fitted on the recording's own
    j-sample increments (as the loss sees them). If removing it does not lower the
    recording's own attitude error (AOE over the whole recording, from the first pose),
    what the increments say about the gyro is the poses' error, not the gyro's; a
    network trained on them has nothing right to learn, on this recording or another.
    ``between_poses`` as for :func:`label_noise`.
    """
    gyro = seq.imu[:, :3]
    pose_at = seq.pose_at if between_poses else None

    def aoe(g: np.ndarray) -> float:
        return sequence_errors(seq, g, distances=())[1].aoe

    est = integrate_from_trusted(seq.gt_quat, seq.gt_valid, gyro, seq.dt)  # shared
    plain = attitude_errors(est, Rotation.from_quat(seq.gt_quat), seq.gt_pos, seq.gt_valid,
                            distances=()).aoe
    fits = {}
    for j in lengths:
        bias = fit_constant_bias(seq.gt_quat, seq.gt_valid, gyro, seq.dt, j, est, pose_at)
        if bias is not None:
            fits[j] = {'bias_deg_s': np.degrees(bias).tolist(), 'aoe_deg': aoe(gyro - bias)}
    best = min(fits, key=lambda j: fits[j]['aoe_deg'], default=None)
    helps = best is not None and fits[best]['aoe_deg'] < plain
    after = '/'.join(f'{f["aoe_deg"]:.2f}' for f in fits.values())
    tried = ', '.join(map(str, fits))
    if not fits:
        summary = (f'no increment of {", ".join(map(str, lengths))} samples has trusted poses '
                   'at every stamp: nothing supervises a correction')
    elif helps:
        summary = (f"a constant gyro bias fitted on the poses' own {best}-sample increments "
                   f"lowers this recording's attitude error from {plain:.2f} to "
                   f'{fits[best]["aoe_deg"]:.2f} deg (lengths {tried}: {after})')
    else:
        summary = ("a constant gyro bias fitted on the poses' own increments does not lower "
                   f"this recording's attitude error at any length tried ({tried} samples: "
                   f'{plain:.2f} -> {after} deg): what the increments say about the gyro is '
                   "the poses' error, so a network trained on them is not expected to beat "
                   'plain integration')
    return {'aoe_plain_deg': plain, 'fits': fits, 'helps': helps, 'summary': summary}


def check(rec: Recording, max_offset_s: float = MAX_OFFSET_S) -> dict[str, Any]:
    """
    Everything check-data reports on one recording, with a verdict and its reasons.

    ``usable`` is ``yes``, ``after alignment`` (the clock offset or the frame rotation
    are significant: :func:`~denoise_imu_ros.data.pose_alignment.needs_alignment`)
    or ``no``; a clock offset that is not constant along the recording is a reason too.
    """
    placed, shift_ns = on_imu_clock(rec)  # poses on another clock: where they overlap most
    seq = onto_imu_stamps(placed)
    report = _streams(rec, seq)
    if len(seq) < ModelConfig().receptive_field:
        return _too_short(report, seq)
    rec, found, report['read_as'] = read_and_align(rec, max_offset_s)  # as every command
    report.update(found)
    # the poses as training would use them: on the IMU clock and in its frame, when the
    # estimate says they are not and is itself trustworthy (the poses follow the gyro,
    # and rotation about every axis makes the frame observable)
    report['judged_after_alignment'] = (
        needs_alignment(report) and not not_following(report, max_offset_s)
        and min(report['excitation_rms_deg_s']) >= MIN_EXCITATION_DEG_S)
    if report['judged_after_alignment']:
        rec = apply_pose_alignment(rec, report['time_offset_s'],
                                   report['imu_from_pose_rotation_xyzw'])
    elif shift_ns:  # a frame too little turned to trust: on the clock found, at least
        rec = apply_pose_alignment(rec, report['time_offset_s'], [0.0, 0.0, 0.0, 1.0])
    seq = onto_imu_stamps(rec)
    if shift_ns:  # the streams where the poses lie, not where they were placed
        report.update(_streams(rec, seq))
        if len(seq) < ModelConfig().receptive_field:
            return _too_short(report, seq)
    jumps = find_jumps(seq)
    seq = mask_jumps(seq, jumps)
    report['pose_jumps'] = [j._asdict() for j in jumps]
    report['interpolation_scale_error_percent'] = interpolation_scale_error(rec)
    report['too_sparse'] = _too_sparse(report)
    # poses too sparse to interpolate are judged between their stamps, as training uses them
    between = report['too_sparse'] is not None
    report.update(label_noise(seq, DRIFT_HORIZONS_S, between))
    report.update(_increments(report, seq.rate_hz))
    long = 2 ** round(math.log2(SUPERVISION_LONG_S * seq.rate_hz))
    report['supervision'] = supervision(seq, (*report['paper_increments'], long), between)
    units = _units(report)  # wrong units explain every other symptom: say only that
    report['usable'], report['reasons'] = ('no', units) if units else _usable(report,
                                                                              max_offset_s)
    quarters = report['time_offset_quarters_s']
    spread_limit = max(OFFSET_SPREAD_S, 0.1 / report['pose_rate_hz'])  # 10 Hz poses: 10 ms
    if not units and max(quarters) - min(quarters) > spread_limit:
        report['reasons'].append(
            'the clock offset is not constant: '
            f'{", ".join(offset_text(q) for q in quarters)} on the four quarters of the '
            'recording (pose latency varies, or a clock drifts): alignment applies one '
            'offset, their mean, and increments not much longer than the spread are '
            'blurred by it')
    if not units and not report['supervision']['helps']:
        report['reasons'].append(report['supervision']['summary'])
    report['verdict'] = {'yes': 'usable for training', 'after alignment':
                         'usable for training with alignment applied',
                         'no': 'not usable for training'}[report['usable']]
    return report


def _too_short(report: dict[str, Any], seq: Sequence) -> dict[str, Any]:
    """Return the report of a recording too short for any estimate, and for the network."""
    field = ModelConfig().receptive_field
    report.update(dict.fromkeys(ESTIMATES), usable='no',
                  verdict='not usable for training', reasons=[
                      f'too short: {len(seq)} IMU samples with poses '
                      f'({report["duration_s"]:.2f} s), fewer than the network\'s '
                      f'receptive field ({field} samples): nothing to estimate or train'])
    return report


def _streams(rec: Recording, seq: Sequence) -> dict[str, Any]:
    """Return the rates, stamp jitter, pose holes and duration of a recording."""
    imu_dt = np.diff(seq.stamp_ns) * 1e-9
    gaps = imu_holes(seq.stamp_ns)
    holes = ~seq.gt_valid
    starts = np.flatnonzero(np.diff(np.r_[0, holes.astype(np.int8)]) == 1)
    ends = np.flatnonzero(np.diff(np.r_[holes.astype(np.int8), 0]) == -1)
    longest = float(max(((seq.stamp_ns[e] - seq.stamp_ns[max(s - 1, 0)]) * 1e-9
                         for s, e in zip(starts, ends)), default=0.0))
    return {'name': seq.name, 'imu_rate_hz': seq.rate_hz,
            'imu_stamp_jitter_ms': 1e3 * float(imu_dt.std()),
            'pose_rate_hz': 1.0 / float(np.median(np.diff(rec.gt_stamp_ns) * 1e-9)),
            'pose_holes': len(starts), 'pose_longest_hole_s': longest,
            'pose_hole_fraction': float(holes.mean()), 'duration_s': float(imu_dt.sum()),
            'accel_norm_mean_m_s2': float(np.mean(np.linalg.norm(seq.imu[:, 3:], axis=1))),
            'imu_holes': len(gaps), 'imu_longest_hole_s': float(imu_dt[gaps].max(initial=0.0)),
            'gyro_clipped': clipped(seq.imu[:, :3]), 'accel_clipped': clipped(seq.imu[:, 3:])}


def clipped(values: np.ndarray) -> dict[str, Any] | None:
    """
    Find samples pinned at an axis's largest magnitude (a saturated sensor), or None.

    A real signal reaches its extreme once or a few times; a saturated one sits on it. An
    axis that never varies (a constant signal) is not saturated.
    """
    worst = None
    for axis in range(values.shape[1]):
        v = np.abs(values[:, axis])
        top = float(v.max())
        pinned = int(np.count_nonzero(v == top))
        if (top > 0 and CLIPPED_MIN_SAMPLES <= pinned < len(v) / 2
                and pinned >= CLIPPED_MIN_FRACTION * len(v)
                and (worst is None or pinned > worst['samples'])):
            worst = {'axis': 'xyz'[axis], 'limit': top, 'samples': pinned,
                     'fraction': pinned / len(v)}
    return worst


def _increments(report: dict[str, Any], rate_hz: float) -> dict[str, Any]:
    """Return the paper's increments at this rate, the shortest clean one, the noise line."""
    noisy = report['noise_dominated_increments']
    paper = paper_increments(rate_hz)
    clean = [j for j in report['increments'] if j >= paper[0] and j not in noisy]
    short = [j for j in paper if j in noisy]
    absent = [j for j in paper if j not in report['increments']]
    if not short and not absent:
        line = (f"the paper's {paper[0]}- and {paper[1]}-sample increments (0.08/0.16 s at "
                f'{rate_hz:.0f} Hz) are not dominated by ground-truth noise')
    else:
        line = '; '.join(
            ([f'increments of {" and ".join(map(str, short))} samples are dominated by '
              'ground-truth noise'] if short else [])
            + ([f'{" and ".join(map(str, absent))} samples apart, too few poses (or too '
                'short a recording) to compare'] if absent else [])) + (
            f'; from {clean[0]} samples on they are not' if clean and short else
            f'; from {clean[0]} samples on they are clean' if clean else
            '; no clean length up to 512 samples')
    return {'paper_increments': list(paper),
            'shortest_clean_increment': clean[0] if clean else None, 'label_noise': line}


def _usable(report: dict[str, Any], max_offset_s: float) -> tuple[str, list[str]]:
    """Return ``yes``, ``after alignment`` or ``no``, and the reasons for it."""
    reasons = []
    if report['duration_s'] < MIN_DURATION_S:
        reasons.append(f'too short: {report["duration_s"]:.1f} s of IMU with poses, training '
                       f'needs {MIN_DURATION_S:g} s')
    not_aligned = not_following(report, max_offset_s)
    if not_aligned:
        reasons.append(not_aligned)
    for sensor, unit, scale in (('gyro', 'deg/s', math.degrees(1.0)), ('accel', 'm/s^2', 1.0)):
        c = report[f'{sensor}_clipped']
        if c:  # it misleads every estimate below (a frame rotation, a bias) before training
            reasons.append(f'{sensor} saturated: {c["samples"]} samples '
                           f'({100 * c["fraction"]:.1f} %) pinned at +-{scale * c["limit"]:.4g} '
                           f'{unit} on its {c["axis"]} axis; record within its range, or '
                           'leave the saturated motion out')
    if report['imu_holes']:
        reasons.append(f'{report["imu_holes"]} IMU holes longer than {MAX_GAP_FACTOR:g} periods '
                       f'(longest {report["imu_longest_hole_s"]:.3g} s): split the recording '
                       'at its holes')
    for axis, rms in zip('xyz', report['excitation_rms_deg_s']):
        if rms < MIN_EXCITATION_DEG_S:
            reasons.append(f'no rotation about the IMU {axis} axis ({rms:.2f} deg/s RMS)')
    if reasons:
        return 'no', reasons
    notes = [report['too_sparse']] if report['too_sparse'] else []
    if report['read_as']:
        notes.insert(0, f'the poses follow the gyro only read {report["read_as"]}: every '
                        'command reads them so')
    if needs_alignment(report):
        return 'after alignment', [f'{describe(report)}: apply both before training'] + notes
    return 'yes', notes


def interpolation_worst(report: dict[str, Any]) -> tuple[float, str] | None:
    """Return the interpolation's largest scale error (%) and its axis, or None."""
    found = report['interpolation_scale_error_percent'] or ()
    errors = [(v, axis) for v, axis in zip(found, 'xyz') if v is not None]
    return max(errors, key=lambda e: abs(e[0]), default=None)


def _too_sparse(report: dict[str, Any]) -> str | None:
    """Why the poses are too sparse for the motion to be interpolated, or None."""
    worst = interpolation_worst(report)
    if worst is None or abs(worst[0]) <= INTERPOLATION_LIMIT_PERCENT:
        return None
    return (f'poses too sparse for the motion ({report["pose_rate_hz"]:.1f} Hz): the '
            "gyro's own attitude, known only at their stamps and interpolated between them, "
            f"is off the gyro's scale by {worst[0]:+.1f} % about the IMU {worst[1]} axis "
            f'(limit {INTERPOLATION_LIMIT_PERCENT:g} %), which a model would learn as the '
            "gyro's from increments of fixed length: train on increments between the pose "
            'stamps (increments_between_poses, which init-recipe sets), or write every '
            "frame's pose (e.g. ORB-SLAM's CameraTrajectory, not its KeyFrameTrajectory)")


def _units(report: dict[str, Any]) -> list[str]:
    """Return what the accelerometer's norm and the gyro's scale say of the units."""
    reasons = []
    accel = accel_units(report['accel_norm_mean_m_s2'])
    if accel:
        reasons.append(accel)
    scale = [1 + v / 100 for v in report['gyro_scale_error_percent'] if v is not None]
    if scale and min(scale) > DEG_PER_RAD_LOW:
        reasons.append(f"the gyro reads {np.median(scale):.1f} times the poses' rate "
                       f'(57.3 for degrees): {DEG_S_HINT}')
    return reasons


def markdown(report: dict[str, Any]) -> str:
    """Human-readable report of :func:`check`."""
    r = report
    lines = [f'{r["name"]}: {r["duration_s"]:.1f} s',
             f'  IMU {r["imu_rate_hz"]:.2f} Hz, stamp jitter {r["imu_stamp_jitter_ms"]:.3f} ms, '
             f'{r["imu_holes"]} holes (longest {r["imu_longest_hole_s"]:.3f} s)',
             f'  poses {r["pose_rate_hz"]:.1f} Hz, {r["pose_holes"]} holes (longest '
             f'{r["pose_longest_hole_s"]:.2f} s, {100 * r["pose_hole_fraction"]:.1f} % of '
             'IMU stamps)']
    if r['time_offset_s'] is None:  # too short for any estimate
        lines.append(f'  verdict: {r["verdict"]}: ' + '; '.join(r['reasons']))
        return '\n'.join(lines) + '\n'
    rot = Rotation.from_quat(r['imu_from_pose_rotation_xyzw']).as_rotvec(degrees=True)
    lines += [f'  clock offset (t_imu = t_pose + offset): {offset_text(r["time_offset_s"], 2)} '
              f'+- {1e3 * r["time_offset_std_s"]:.2f} ms',
              f'  rotation pose body -> IMU: {r["imu_from_pose_rotation_deg"]:.3f} '
              + ('deg, its spread not measured (too few poses)' if r[
                  'imu_from_pose_rotation_std_deg'] is None else
                 f'+- {r["imu_from_pose_rotation_std_deg"]:.3f} deg')
              + ' (rotation vector ' + ', '.join(f'{v:+.3f}' for v in rot) + ' deg)',
              '  gyro bias against the poses (deg/s): '
              + ', '.join(f'{b:+.3f}' for b in r['gyro_bias_vs_pose_deg_s']),
              '  gyro scale error (%): '
              + ', '.join('-' if v is None else f'{v:+.3f}'
                          for v in r['gyro_scale_error_percent']),
              '  of which interpolating between the pose stamps makes (%): '
              + ', '.join('-' if v is None else f'{v:+.3f}'
                          for v in r['interpolation_scale_error_percent']),
              '  excitation, RMS rate per IMU axis (deg/s): '
              + ', '.join(f'{v:.1f}' for v in r['excitation_rms_deg_s']),
              *([f'  left out of the alignment: {100 * r["rate_windows_left_out"]:.1f} % of '
                 'its rate windows, which no frame and offset explain (poses that jump or '
                 'glitch)'] if r['rate_windows_left_out'] >= LEFT_OUT_SAID else []),
              ('  with the clock offset and frame rotation applied: increment residual'
               if r['judged_after_alignment'] else '  increment residual')
              + ' after a constant bias (samples: mrad per axis, as deg/s'
              + (', each between pose stamps):' if r['too_sparse'] else '):')]
    lines += [f'    {j:4d}: {p["residual_mrad"]:7.3f}  {p["noise_rate_deg_s"]:7.3f}'
              for j, p in r['increments'].items()]
    if r['pose_jumps']:
        lines.append(f'  {describe_jumps([Jump(**j) for j in r["pose_jumps"]])}')
    lines.append(f'  label noise: {r["label_noise"]}')
    lines.append(f'  supervision: {r["supervision"]["summary"]}')
    lines.append(f'  verdict: {r["verdict"]}' + (': ' + '; '.join(r['reasons'])
                                                 if r['reasons'] else ''))
    return '\n'.join(lines) + '\n'
