# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Poses onto the IMU's stamps: too sparse a pose stream is refused, not interpolated."""

from denoise_imu_ros.core.errors import DatasetError
from denoise_imu_ros.data.load import load_sequence
from helpers import write_asl
import pytest


def test_two_poses_45_s_apart_are_refused_and_one_a_second_is_taken(tmp_path):
    sparse = write_asl(tmp_path / 'sparse', n_imu=20000, gt_rate=1 / 45)
    with pytest.raises(DatasetError, match=r'sparse: its poses come every 45\.0 s \(median\): '
                                           'too sparse'):
        load_sequence(sparse)
    seq = load_sequence(write_asl(tmp_path / 'slow', n_imu=2000, gt_rate=1.0))
    assert seq.gt_valid.all()
