# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Jumps in a trajectory: pose increments the gyro cannot explain, found and masked.

A VIO re-initialising, a SLAM relocalising or a placeholder pose written before tracking
starts moves the poses by tens of degrees between two stamps while the gyro turns by a
fraction of one. Over blocks of JUMP_WINDOW_S the angle between the poses' increment and
the gyro's is small where the poses track (motion capture ~0.01 deg, a VIO 0.1-0.3 deg);
a block beyond JUMP_MIN_DEG, JUMP_FACTOR times the median and JUMP_MOTION_FRACTION of
the gyro's own turn over it is a jump (a jump while turning fast is missed), and its samples
lose their trusted poses (the loss drops every increment across it). Blocks across an
IMU hole are not judged (the gyro does not cover it). Poses on another
clock or in another frame disagree everywhere: beyond JUMP_MAX_FRACTION of the blocks
nothing is masked (alignment, not masking, is what they need). A VIO re-initialising
after it lost track leaves a gap in its poses, which no block spans: across each gap
the gyro less its constant bias carries the pose before it to the pose after it, and a
pose after it beyond the blocks' limit plus GAP_DRIFT_DEG_S a second of the gap (the
bias's error, and the poses' own drift, that the gyro carries over the gap) is a jump
over the gap's span: said, and not rejoined. The poses after it may be in a new world (a
VIO re-initialising), or back in the world of before, where a SLAM relocalised in its
map after its poses had drifted before it lost track (ORB-SLAM2 on EuRoC's V2_03, as its
motion capture shows): moved into the world of the poses before the gap, those are
further from the truth, not nearer. Figures between poses (training's loss, check-data's
label noise) never span a gap; attitude errors from the first pose carry such a jump.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from ..core.metrics import fit_constant_bias, increment_residuals, integrate, trusted_blocks
from ..core.records import Sequence

JUMP_WINDOW_S = 0.2
JUMP_MIN_DEG = 5.0         # motion capture's glitches (TUM-VI's: 2-3 deg) stay below
JUMP_FACTOR = 10.0
JUMP_MAX_FRACTION = 0.2
JUMP_MOTION_FRACTION = 0.5  # and more than this part of the gyro's own turn over the block
HOLE_FACTOR = 1.5          # a block lasting longer than this times its length holds a hole
# what the gyro less its fitted bias may drift a second across a gap in the poses: twice
# VINS-Mono's largest heading drift on EuRoC (0.23 deg/s), which a bias fit on it takes in
GAP_DRIFT_DEG_S = 0.5


class Jump(NamedTuple):
    """A span of the recording whose poses jumped, from its first sample (s)."""

    start_s: float
    end_s: float
    angle_deg: float      # the largest block error in it, or the pose's after a gap
    over_gap: bool = False  # a gap in the poses, not a block of them


def _block(seq: Sequence) -> int:
    """Return JUMP_WINDOW_S in samples (two at least)."""
    return max(2, round(JUMP_WINDOW_S * seq.rate_hz))


def find_jumps(seq: Sequence) -> list[Jump]:
    """Spans whose pose increments the gyro cannot explain (merged where they touch), and gaps."""
    n = _block(seq)
    starts = trusted_blocks(seq.gt_valid, n)
    if len(starts) < 2:
        return []
    res, duration = increment_residuals(seq.gt_quat, seq.gt_valid, seq.imu[:, :3], seq.dt, n)
    angle = np.degrees(np.linalg.norm(res, axis=1))
    covered = duration <= HOLE_FACTOR * n * float(np.median(seq.dt))
    # the gyro's own turn over each block: a clock offset of a few ms makes errors that
    # scale with it (BROAD's fast trial: 14 deg in 0.2 s at 250 deg/s), a jump does not
    steps = np.concatenate([np.zeros((1, 3)), np.cumsum(seq.imu[:-1, :3] * seq.dt[:, None], 0)])
    turn = np.degrees(np.linalg.norm(steps[starts + n] - steps[starts], axis=1))
    limit = max(JUMP_MIN_DEG, JUMP_FACTOR * float(np.median(angle)))
    bad = covered & (angle > limit) & (angle > JUMP_MOTION_FRACTION * turn)
    if bad.mean() > JUMP_MAX_FRACTION:
        return []
    t = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
    jumps: list[Jump] = []
    for k in np.flatnonzero(bad):
        start, end = float(t[starts[k]]), float(t[starts[k] + n])
        if jumps and start <= jumps[-1].end_s:
            jumps[-1] = Jump(jumps[-1].start_s, end, max(jumps[-1].angle_deg, angle[k]))
        else:
            jumps.append(Jump(start, end, float(angle[k])))
    return sorted(jumps + _over_gaps(seq, limit, t, jumps))


def _over_gaps(seq: Sequence, limit_deg: float, t: np.ndarray,
               jumps: list[Jump]) -> list[Jump]:
    """Gaps in the poses across which the gyro cannot carry the pose before to the one after."""
    valid = seq.gt_valid
    edges = np.flatnonzero(np.diff(valid.astype(np.int8)))
    # a gap: the poses trusted before it (at i) and after it (at j), none between
    gaps = [(i, j) for i, j in zip(edges, edges[1:] + 1) if valid[i]]
    if not gaps:
        return []
    fitted = valid.copy()  # the bias fitted without the jumps already found
    for jump in jumps:
        fitted[(t >= jump.start_s) & (t <= jump.end_s)] = False
    gyro = seq.imu[:, :3] - _bias(seq, fitted)
    hole = HOLE_FACTOR * float(np.median(seq.dt))
    found = []
    for i, j in gaps:
        if (seq.dt[i:j] > hole).any():
            continue  # the gyro does not cover an IMU hole
        bridged = integrate(seq.gt_quat[i], gyro[i:j], seq.dt[i:j])[-1]
        angle = math.degrees((bridged.inv() * Rotation.from_quat(seq.gt_quat[j])).magnitude())
        if angle > limit_deg + GAP_DRIFT_DEG_S * (t[j] - t[i]):
            found.append(Jump(float(t[i + 1]), float(t[j - 1]), angle, over_gap=True))
    return found


def mask_jumps(seq: Sequence, jumps: list[Jump]) -> Sequence:
    """
    ``seq`` with its poses untrusted over every jump's span, and rejoined after it.

    After a jump mid-run the poses are in another world (a VIO re-initialised): every pose
    after the span is moved back into the world before it, bridged by the gyro less its
    constant bias fitted on the poses (the span lasts a fraction of a second), so that an
    attitude error from the first pose measures the gyro, not the jump. A jump at the
    start (a placeholder pose) has no world before it: nothing is moved; nor after a jump
    over a gap (module docstring).
    """
    if not jumps:
        return seq
    t = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
    valid = seq.gt_valid.copy()
    for jump in jumps:
        valid[(t >= jump.start_s) & (t <= jump.end_s)] = False
    quat, pos = seq.gt_quat.copy(), seq.gt_pos.copy()
    gyro = seq.imu[:, :3] - _bias(seq, valid)
    for jump in (j for j in jumps if not j.over_gap):
        before = np.flatnonzero(valid & (t < jump.start_s))
        after = np.flatnonzero(valid & (t > jump.end_s))
        if not len(before) or not len(after):
            continue
        i, j = before[-1], after[0]
        if not seq.gt_valid[i:j + 1][(t[i:j + 1] < jump.start_s) | (t[i:j + 1] > jump.end_s)
                                     ].all():
            continue  # a gap beside the jump: as over a gap, not moved
        bridged = integrate(quat[i], gyro[i:j], seq.dt[i:j])[-1]
        turn = bridged * Rotation.from_quat(quat[j]).inv()  # the world change at the jump
        quat[j:] = (turn * Rotation.from_quat(quat[j:])).as_quat()
        pos[j:] = turn.apply(pos[j:] - pos[j]) + pos[i]
    return dataclasses.replace(seq, gt_valid=valid, gt_quat=quat, gt_pos=pos)


def _bias(seq: Sequence, valid: np.ndarray) -> np.ndarray:
    """Return the gyro's constant bias against the trusted poses (0 where none fits)."""
    bias = fit_constant_bias(seq.gt_quat, valid, seq.imu[:, :3], seq.dt, _block(seq))
    return np.zeros(3) if bias is None else bias


def describe(jumps: list[Jump], most: int = 3) -> str:
    """Return the jumps in words: how many, and the first few spans."""
    spans = ', '.join(f'{j.start_s:.1f}-{j.end_s:.1f} s ({j.angle_deg:.0f} deg'
                      + (', over a gap)' if j.over_gap else ')') for j in jumps[:most])
    more = f' and {len(jumps) - most} more' if len(jumps) > most else ''
    gaps = sum(j.over_gap for j in jumps)
    causes = ['a VIO re-initialising', 'a placeholder pose'] + (
        ['a SLAM relocalising', 'motion capture at a hole'] if gaps else [])
    return (f'{len(jumps)} pose jump{"s" if len(jumps) > 1 else ""} the gyro cannot explain '
            f'({", ".join(causes)}?), {"found" if gaps == len(jumps) else "masked"}: '
            f'{spans}{more}; {math.fsum(j.end_s - j.start_s for j in jumps):.1f} s in all'
            + ('; those over a gap in the poses are not rejoined: the poses after each are in '
               'a new world (a VIO re-initialising) or back in the one before (a SLAM '
               'relocalising), and attitude errors from the first pose carry them'
               if gaps else ''))
