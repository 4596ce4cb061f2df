# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Poses from an estimator: jumps found, said and masked; a world off level turned level."""

import dataclasses
import re

from denoise_imu_ros.core.errors import DataWarning
from denoise_imu_ros.data.asl import read_asl
from denoise_imu_ros.data.bags import write_bag
from denoise_imu_ros.data.check import check
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.data.pose_jumps import describe, find_jumps, mask_jumps
from denoise_imu_ros.data.timebase import crop, onto_imu_stamps
import numpy as np
import pytest
from scipy.spatial.transform import Rotation


def _reinitialised(rec, at_s=30.0):
    """Turn the world of ``rec``'s poses 40 deg and move it 3 m from ``at_s`` on."""
    after = (rec.gt_stamp_ns - rec.gt_stamp_ns[0]) * 1e-9 >= at_s
    world = Rotation.from_rotvec([0.0, 0.0, 40.0], degrees=True)
    quat, pos = rec.gt_quat.copy(), rec.gt_pos.copy()
    quat[after] = (world * Rotation.from_quat(quat[after])).as_quat()
    pos[after] = world.apply(pos[after]) + [3.0, 0.0, 0.0]
    return dataclasses.replace(rec, gt_quat=quat, gt_pos=pos)


def test_motion_capture_has_no_jumps_and_a_reinitialisation_is_one(euroc):
    rec = read_asl(euroc / 'MH_04_difficult')
    assert find_jumps(onto_imu_stamps(rec)) == []
    seq = onto_imu_stamps(_reinitialised(rec))
    jumps = find_jumps(seq)
    assert len(jumps) == 1
    t0 = (rec.gt_stamp_ns[0] - seq.stamp_ns[0]) * 1e-9
    assert jumps[0].start_s <= 30.0 - t0 <= jumps[0].end_s <= jumps[0].start_s + 0.5
    assert 35 < jumps[0].angle_deg < 45
    masked = mask_jumps(seq, jumps)
    assert 0 < (seq.gt_valid & ~masked.gt_valid).sum() <= 0.5 * seq.rate_hz
    # after the span the poses are back in the world before it (bridged by the gyro): an
    # attitude error from the first pose measures the gyro, not the 40 deg jump
    truth = onto_imu_stamps(rec)
    after = masked.gt_valid & (np.arange(len(seq)) > np.flatnonzero(~masked.gt_valid)[-1])
    moved = Rotation.from_quat(masked.gt_quat[after]) * Rotation.from_quat(
        truth.gt_quat[after]).inv()
    assert np.degrees(moved.magnitude()).max() < 0.5
    assert np.abs(masked.gt_pos[after] - truth.gt_pos[after]).max() < 0.3  # its span: unbridged


def test_a_reinitialisation_after_a_gap_in_the_poses_is_one_and_a_gap_alone_none(euroc):
    """A VIO that lost track for 3 s and started again in a new world."""
    rec = read_asl(euroc / 'MH_04_difficult')
    t = (rec.gt_stamp_ns - rec.gt_stamp_ns[0]) * 1e-9
    kept = (t < 28.0) | (t >= 31.0)

    def gap(r):
        return dataclasses.replace(r, gt_stamp_ns=r.gt_stamp_ns[kept], gt_quat=r.gt_quat[kept],
                                   gt_pos=r.gt_pos[kept])
    assert find_jumps(onto_imu_stamps(gap(rec))) == []  # a hole in the poses: no jump
    seq = onto_imu_stamps(gap(_reinitialised(rec)))
    jumps = find_jumps(seq)
    t0 = (rec.gt_stamp_ns[0] - seq.stamp_ns[0]) * 1e-9
    assert len(jumps) == 1 and 35 < jumps[0].angle_deg < 45
    assert jumps[0].start_s == pytest.approx(28.0 - t0, abs=0.01)
    assert jumps[0].end_s == pytest.approx(31.0 - t0, abs=0.01)
    assert jumps[0].over_gap and re.search(
        r'\(a VIO re-initialising, a placeholder pose, a SLAM relocalising, motion capture at a '
        r'hole\?\), found: \d+\.\d-\d+\.\d s \(40 deg, over a gap\); 3\.0 s in all; those '
        r'over a gap in the poses are not rejoined: the poses after each are in a new world \(a '
        r'VIO re-initialising\) or back in the one before \(a SLAM relocalising\), and attitude '
        r'errors from the first pose carry them$', describe(jumps))
    # which of the two the gyro cannot tell (a SLAM's drift before it lost track looks
    # like a new world after): said, and the poses left as written
    masked = mask_jumps(seq, jumps)
    assert np.array_equal(masked.gt_valid, seq.gt_valid)
    assert np.array_equal(masked.gt_quat, seq.gt_quat)
    # a jump between blocks before a 15 s gap, the world the same across it: the gyro's
    # bias is fitted without that jump, and the gap is no jump
    kept = (t < 10.0) | ((t >= 25.0) & (t < 30.0))
    seq = onto_imu_stamps(gap(_reinitialised(rec, at_s=5.0)))
    assert [j.over_gap for j in find_jumps(seq)] == [False]


def test_a_placeholder_first_pose_and_a_jump_are_said_masked_and_judged_without(
        euroc, tmp_path):
    rec = _reinitialised(read_asl(euroc / 'MH_04_difficult'))
    quat = rec.gt_quat.copy()
    quat[0] = [0.0, 0.0, 0.0, 1.0]  # identity written before tracking started
    rec = dataclasses.replace(rec, gt_quat=quat)
    write_bag(rec, tmp_path / 'vio')
    with pytest.warns(DataWarning, match=r'2 pose jumps the gyro cannot explain .*masked: '
                                         r'0\.0-0\.2 s \(\d+ deg\), 2\d\.\d-\d\d\.\d s'):
        seq = load_sequence(tmp_path / 'vio')
    assert not seq.gt_valid[:5].any() and seq.gt_valid[100:1000].all()
    report = check(rec)
    assert len(report['pose_jumps']) == 2 and report['usable'] != 'no'
    assert report['supervision']['helps']


@pytest.mark.parametrize('rotvec_deg, said', [
    ([100.0, 0.0, 20.0], r'(99|10\d)'),  # a first camera frame
    ([0.0, 20.0, 0.0], r'(19|20|21)'),   # a world 20 deg from gravity
])
def test_a_world_far_from_level_is_turned_level_and_said(euroc, tmp_path, rotvec_deg, said):
    from denoise_imu_ros.data.pose_alignment import level
    rec = crop(read_asl(euroc / 'MH_01_easy'), 0.0, 90.0)
    original = onto_imu_stamps(rec)
    assert level(original)[1] < 1.0  # motion capture's world is level
    world = Rotation.from_rotvec(rotvec_deg, degrees=True)
    write_bag(dataclasses.replace(
        rec, gt_quat=(world * Rotation.from_quat(rec.gt_quat)).as_quat(),
        gt_pos=world.apply(rec.gt_pos)), tmp_path / 'slam')
    with pytest.warns(DataWarning, match=rf"the poses' world has its z {said} deg from up"):
        seq = load_sequence(tmp_path / 'slam')
    tilt = Rotation.from_quat(seq.gt_quat).apply([0.0, 0.0, 1.0], inverse=True)
    true = Rotation.from_quat(original.gt_quat).apply([0.0, 0.0, 1.0], inverse=True)
    n = min(len(tilt), len(true))  # up in the body frame: as the motion capture's, to 1 deg
    angle = np.degrees(np.arccos(np.clip(np.sum(tilt[:n] * true[:n], axis=1), -1, 1)))
    assert angle.max() < 1.0
