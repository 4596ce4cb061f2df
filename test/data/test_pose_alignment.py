# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Poses onto the IMU's clock and frame: offsets and frames found, robust fits, scale judged."""

import dataclasses
import math

from denoise_imu_ros.data.asl import read_asl
from denoise_imu_ros.data.check import check
from denoise_imu_ros.data.pose_alignment import estimate_pose_alignment
from helpers import write_asl
import numpy as np
import pytest
from scipy.spatial.transform import Rotation


@pytest.mark.parametrize('offset_ms, rotvec_deg', [
    (37.3, (30.0, -20.0, 45.0)), (-12.6, (0.0, 90.0, 0.0)), (81.0, (-170.0, 5.0, 10.0))])
def test_a_shifted_clock_and_a_rotated_pose_frame_are_recovered(euroc, offset_ms, rotvec_deg):
    rec = read_asl(euroc / 'V1_03_difficult')
    # poses of a marker body (rotated, 12 cm lever arm) on a clock offset_ms late
    marker = Rotation.from_rotvec(rotvec_deg, degrees=True)  # imu_from_pose
    body = Rotation.from_quat(rec.gt_quat)
    moved = dataclasses.replace(
        rec, gt_stamp_ns=rec.gt_stamp_ns - int(offset_ms * 1e6),
        gt_quat=(body * marker).as_quat(), gt_pos=rec.gt_pos + body.apply([0.12, 0.0, 0.05]))
    base = estimate_pose_alignment(rec)
    found = estimate_pose_alignment(moved)
    assert abs(found['time_offset_s'] - base['time_offset_s'] - offset_ms * 1e-3) < 1e-3
    rot = Rotation.from_quat(found['imu_from_pose_rotation_xyzw'])
    assert math.degrees((rot * marker.inv()).magnitude()) < 0.2
    assert found['time_offset_std_s'] < 1e-3 and found['imu_from_pose_rotation_std_deg'] < 0.2
    assert check(moved)['usable'] == 'after alignment'


def test_an_axis_that_only_vibrates_has_no_interpolation_scale_to_judge(tmp_path):
    from denoise_imu_ros.data.pose_alignment import interpolation_scale_error
    rec = read_asl(write_asl(tmp_path / 's', n_imu=12000, gt_rate=10.0, gt_dir='mocap0'))
    # a yawing robot whose body shakes by 4 deg/s at 8 Hz about x and y
    t = (rec.imu_stamp_ns - rec.imu_stamp_ns[0]) * 1e-9
    shaken = rec.imu.copy()
    shaken[:, 0] += np.radians(4.0) * np.sin(2 * np.pi * 8.0 * t)
    shaken[:, 1] += np.radians(4.0) * np.cos(2 * np.pi * 8.0 * t)
    found = interpolation_scale_error(dataclasses.replace(rec, imu=shaken))
    assert found[:2] == [None, None] and abs(found[2]) < 0.5


@pytest.mark.parametrize('n', [1, 2, 5, 100, 1001])
def test_the_offset_searchs_median_is_numpys(n):
    from denoise_imu_ros.data.pose_alignment import _median
    values = np.random.default_rng(n).exponential(size=n)
    assert _median(values) == float(np.median(values))


@pytest.mark.parametrize('noise', [0.0, 0.01, 1.0])
def test_the_frame_fit_is_scipys_on_the_centred_rates(noise):
    """The fit from the rates' sums and products: scipy's rotation, the bias, the residual."""
    from denoise_imu_ros.data.pose_alignment import fit_frame
    rng = np.random.default_rng(7)
    for seed in range(10):
        frame = Rotation.random(random_state=seed)
        pose = rng.normal(size=(1000, 3)) * [1.0, 0.3, 0.05] + [0.5, -1.0, 2.0]
        imu = frame.apply(pose) + [0.01, -0.02, 0.03] + noise * rng.normal(size=pose.shape)
        rot, bias, rms = fit_frame(imu, pose)
        centred = imu - imu.mean(0), pose - pose.mean(0)
        ref, rssd = Rotation.align_vectors(*centred)
        assert (rot * ref.inv()).magnitude() < 1e-9
        np.testing.assert_allclose(bias, imu.mean(0) - rot.apply(pose.mean(0)), atol=1e-12)
        # scipy's cost comes from an expanded sum: near 0 it is off by ~sqrt(eps) of |a|
        scale = np.sqrt(np.sum(centred[0] ** 2))
        assert abs(rms * np.sqrt(imu.size) - rssd) <= 1e-9 * rssd + 1e-7 * scale


def test_the_frame_fit_leaves_out_a_few_windows_it_cannot_explain_not_many():
    from denoise_imu_ros.data.pose_alignment import fit_frame, robust_fit
    rng = np.random.default_rng(8)
    frame = Rotation.from_rotvec([0.1, -0.4, 1.5])
    pose = rng.normal(0, 0.5, (2000, 3))
    imu = frame.apply(pose) + [0.01, -0.02, 0.03] + rng.normal(0, 1e-3, (2000, 3))
    for wrong, left_out in ((0.1, True), (0.3, False)):  # windows whose poses jumped
        spoilt = pose.copy()
        spoilt[:int(wrong * len(pose))] = rng.normal(0, 2.0, (int(wrong * len(pose)), 3))
        rot, bias, rms, out = robust_fit(imu, spoilt)
        if left_out:  # the frame and bias as if those windows were not there
            assert out.sum() == int(wrong * len(pose))
            assert math.degrees((rot * frame.inv()).magnitude()) < 0.01 and rms < 2e-3
            np.testing.assert_allclose(bias, [0.01, -0.02, 0.03], atol=1e-3)
        else:  # more than a fifth: the poses do not follow, and the residual says so
            assert not out.any() and rms == fit_frame(imu, spoilt)[2] and rms > 0.1


@pytest.mark.parametrize('n', [1, 2, 100, 1001, 4096])
def test_the_rate_norms_lag_is_scipys_full_correlation(n):
    from denoise_imu_ros.data.pose_alignment import best_lag
    from scipy.signal import correlate
    rng = np.random.default_rng(n)
    a = rng.normal(size=n)
    b = np.roll(a, min(37, n // 3)) + 0.1 * rng.normal(size=n)
    assert best_lag(a, b) == int(np.argmax(correlate(a, b, mode='full'))) - n + 1


def test_an_estimate_kept_is_the_one_computed_and_a_callers_change_stays_its_own(euroc):
    from denoise_imu_ros.data.timebase import crop
    rec = crop(read_asl(euroc / 'MH_01_easy'), 0.0, 40.0)
    found = estimate_pose_alignment(rec)
    found['time_offset_quarters_s'].append(1.0)
    assert estimate_pose_alignment(rec) != found  # the caller's copy, not the one kept
    found['time_offset_quarters_s'].pop()
    assert estimate_pose_alignment(rec) == found
    # other poses: estimated afresh
    moved = dataclasses.replace(rec, gt_stamp_ns=rec.gt_stamp_ns + 5_000_000)
    wide = estimate_pose_alignment(moved)
    assert wide['time_offset_s'] == pytest.approx(found['time_offset_s'] - 5e-3, abs=2e-4)
    turn = Rotation.from_rotvec([0.0, 0.0, 0.1])
    turned = dataclasses.replace(rec, gt_quat=(Rotation.from_quat(rec.gt_quat) * turn).as_quat())
    assert estimate_pose_alignment(turned)['imu_from_pose_rotation_deg'] == pytest.approx(
        math.degrees(0.1), abs=0.1)
