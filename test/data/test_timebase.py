# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Poses onto the IMU's stamps: too sparse a stream refused, the IMU before them kept."""

import dataclasses

from denoise_imu_ros.core.errors import DatasetError
from denoise_imu_ros.core.records import Recording
from denoise_imu_ros.data.load import load_sequence
from helpers import write_asl
import numpy as np
import pytest


def test_two_poses_45_s_apart_are_refused_and_one_a_second_is_taken(tmp_path):
    sparse = write_asl(tmp_path / 'sparse', n_imu=20000, gt_rate=1 / 45)
    with pytest.raises(DatasetError, match=r'sparse: its poses come every 45\.0 s \(median\): '
                                           'too sparse'):
        load_sequence(sparse)
    seq = load_sequence(write_asl(tmp_path / 'slow', n_imu=2000, gt_rate=1.0))
    assert seq.gt_valid.all()


def test_the_imu_samples_before_the_poses_start_lead_into_the_sequence(tmp_path):
    """A trajectory that starts late: the stream a node saw is kept, the scored part apart."""
    from denoise_imu_ros.data.load import load_imu
    from helpers import write_late_trajectory
    asl = write_asl(tmp_path / 'rec', n_imu=2000, still_s=3.0)
    late = load_sequence(asl, poses=write_late_trajectory(tmp_path / 'vio', asl, 4.0))
    whole = load_imu(asl).imu
    assert len(late.lead_in) == 800 and len(late) == 1200
    assert np.array_equal(late.stream, whole) and np.array_equal(late.on_poses(whole), late.imu)
    assert np.array_equal(late.stream_stamp_ns, load_imu(asl).imu_stamp_ns)
    tail = late.tail(100, 50)  # what comes before a tail leads into it too
    assert np.array_equal(tail.stream, whole[:950]) and np.array_equal(tail.imu, whole[900:950])
    assert np.array_equal(tail.stream_stamp_ns, late.stream_stamp_ns[:950])
    own = load_sequence(asl)  # its own poses, from the first sample: nothing before
    assert len(own.lead_in) == 0 and own.stream is own.imu


def test_a_hole_in_the_imu_before_the_poses_ends_the_lead_in_there(tmp_path):
    """The node restarts at a hole: only what follows the last one leads in."""
    from helpers import write_late_trajectory
    asl = write_asl(tmp_path / 'rec', n_imu=2000, still_s=3.0)
    csv = asl / 'mav0' / 'imu0' / 'data.csv'
    lines = csv.read_text().splitlines(keepends=True)
    csv.write_text(''.join(lines[:301] + lines[501:]))  # samples 300-499 lost: a 1 s hole
    late = load_sequence(asl, poses=write_late_trajectory(tmp_path / 'vio', asl, 4.0))
    assert len(late.lead_in) == 300  # samples 500-799
    assert np.all(np.diff(late.stream_stamp_ns) == 5_000_000)
    with pytest.raises(ValueError, match='not one per sample of the stream'):
        late.on_poses(late.imu)  # an array of the poses' span alone: refused, not cut


def test_each_pose_marks_the_imu_sample_nearest_its_stamp_within_half_a_period(
        tmp_path):
    from denoise_imu_ros.data.timebase import nearest_samples
    imu = np.arange(0, 100_000_000, 5_000_000)  # 200 Hz
    poses = np.array([-4_000_000, 0, 7_400_000, 7_600_000, 52_000_000, 94_900_000,
                      97_600_000])
    at = nearest_samples(imu, poses)
    assert np.flatnonzero(at).tolist() == [0, 1, 2, 10, 19]  # 97.6 ms: 2.6 ms from the last
    seq = load_sequence(write_asl(tmp_path / 'r', n_imu=2000, gt_rate=20.0))
    assert 0.09 < seq.pose_at.mean() < 0.11  # a pose every 10th sample
    assert np.array_equal(seq.tail(100).pose_at, seq.pose_at[100:])


def test_poses_at_fits_each_stretch_once_and_serves_only_the_same_poses(monkeypatch):
    """The splines kept by content never serve other poses, and serve the same ones alike."""
    from denoise_imu_ros.data import timebase
    from scipy.spatial.transform import Rotation, RotationSpline
    fits = []

    class Counted(RotationSpline):

        def __init__(self, *args):
            fits.append(len(args[0]))
            super().__init__(*args)
    monkeypatch.setattr(timebase, 'RotationSpline', Counted)
    t = np.arange(0, 3_000_000_000, 10_000_000)  # 100 Hz poses with two holes: 3 stretches
    t = np.delete(t, np.r_[90:110, 190:210])
    stamps = np.arange(0, 2_990_000_000, 2_500_000)
    quat = Rotation.from_rotvec(np.outer(np.sin(t * 1e-9), [0.3, -0.2, 0.9])).as_quat()
    rec = Recording('r', 'r', stamps, np.zeros((len(stamps), 6)), t, quat, np.zeros((len(t), 3)))
    first = timebase.poses_at(rec, stamps)[0]
    assert len(fits) == 3
    np.testing.assert_array_equal(timebase.poses_at(rec, stamps[::3])[0], first[::3])
    assert len(fits) == 3  # nothing fitted again
    inside = (t >= 1.1e9) & (t < 1.9e9)
    fresh = RotationSpline(t[inside] * 1e-9 - t[0] * 1e-9, Rotation.from_quat(quat[inside]))
    middle = (stamps >= 1.1e9) & (stamps <= t[inside][-1])
    np.testing.assert_allclose(first[middle], fresh(stamps[middle] * 1e-9).as_quat(), atol=1e-12)
    other = dataclasses.replace(rec, gt_quat=quat[::-1].copy())  # same stamps, other poses
    assert not np.allclose(timebase.poses_at(other, stamps)[0], first)
    assert len(fits) == 6


def test_a_long_stretch_fitted_in_pieces_is_one_spline_over_it(monkeypatch):
    """Pieces of a few hundred knots give what one spline over 2000 knots gives, to rounding."""
    from denoise_imu_ros.data import timebase
    from scipy.spatial.transform import Rotation, RotationSpline
    t = np.arange(0, 20_000_000_000, 10_000_000)  # 2000 poses at 100 Hz, no hole
    quat = Rotation.from_rotvec(np.stack([np.sin(t * 1.3e-9), np.cos(t * 0.7e-9),
                                          np.sin(t * 2.9e-9) ** 2], axis=1)).as_quat()
    stamps = np.arange(0, t[-1] + 1, 2_500_000)  # both ends and every knot among them
    rec = Recording('r', 'r', stamps, np.zeros((len(stamps), 6)), t, quat, np.zeros((len(t), 3)))
    monkeypatch.setattr(timebase, 'SPLINE_KNOTS', 300)
    pieces = timebase.poses_at(rec, stamps)[0]
    whole = RotationSpline(t * 1e-9, Rotation.from_quat(quat))(stamps * 1e-9).as_quat()
    np.testing.assert_allclose(np.abs((pieces * whole).sum(1)), 1.0, atol=1e-13)
    np.testing.assert_allclose(pieces * np.sign((pieces * whole).sum(1))[:, None], whole,
                               atol=1e-12)
    assert len(timebase._pieces(0, 2000)) == 7


@pytest.mark.parametrize('count', [2, 3, 500])
def test_a_spline_evaluated_by_numpys_products_is_scipys_to_rounding(count):
    from denoise_imu_ros.data.timebase import spline_at
    from scipy.spatial.transform import Rotation, RotationSpline
    rng = np.random.default_rng(3)
    knots = np.cumsum(rng.uniform(0.004, 0.006, count))
    spline = RotationSpline(knots, Rotation.from_rotvec(np.cumsum(
        rng.normal(0.0, 0.3, (count, 3)), axis=0)))
    t = np.r_[knots[0] - 0.01, knots, np.sort(rng.uniform(knots[0], knots[-1], 2000)),
              knots[-1] + 0.01]  # the knots themselves, between them and beyond both ends
    np.testing.assert_allclose(spline_at(spline, t), spline(t).as_quat(), rtol=0, atol=1e-14)
